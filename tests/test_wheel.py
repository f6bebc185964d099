"""The wheel works outside a checkout: built from a copy of the sources, installed into a fresh venv, and run
from an empty folder, where no ``agents``, ``configs`` or ``models`` folder can help.

The fresh venv reuses this environment's installed dependencies (torch above all) through a ``.pth`` line naming
this venv's site-packages, read after the fresh venv's own: the wheel's ``ekfslam_gym`` is the one imported, and
nothing is downloaded. Each step's time is printed (``pytest -s``).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import time
import zipfile
from pathlib import Path

import gymnasium as gym
import pytest

from ekfslam_gym import compiled

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent
IGNORE = shutil.ignore_patterns(
    ".git", ".venv*", "build", "dist", "runs", "out", "__pycache__", "*.egg-info", "_aot*.so", ".*_cache"
)
REGISTERED = sorted(i for i in gym.registry if i.startswith("EKFSLAM"))
SHIPPED = sorted(i for i in REGISTERED if i.endswith("-v0"))  # the ids with a shipped policy
SMOKE_TRAINING = ["--timesteps", "64", "--n-envs", "1", "--hyperparams", "n_steps=64", "batch_size=32"]

MAKE_EVERY_ID = """
import importlib.util, json, gymnasium as gym, ekfslam_gym
from ekfslam_gym import compiled
ids = sorted(i for i in gym.registry if i.startswith("EKFSLAM"))
for env_id in ids:
    env = gym.make(env_id)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()
print(json.dumps({"ids": ids, "file": ekfslam_gym.__file__, "version": ekfslam_gym.__version__,
                  "backend": compiled.backend(), "agents": importlib.util.find_spec("agents") is not None}))
"""


def test_the_wheel_installs_and_runs_outside_a_checkout(tmp_path):
    timings: dict[str, float] = {}

    def step(name: str, command: list[str], **kwargs) -> str:
        started = time.perf_counter()
        done = subprocess.run(command, capture_output=True, text=True, **kwargs)
        timings[name] = time.perf_counter() - started
        assert done.returncode == 0, (
            f"{name}: {' '.join(command)}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
        )
        return done.stdout

    source, wheels, venv, work = (tmp_path / n for n in ("src", "wheels", "venv", "work"))
    shutil.copytree(ROOT, source, ignore=IGNORE)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check"]
    step(
        "build the wheel",
        [*pip, "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(wheels), str(source)],
    )
    (wheel,) = wheels.glob("ekfslam_gym-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names} == {
        "ekfslam_gym",
        wheel.name.split("-")[0] + "-" + wheel.name.split("-")[1] + ".dist-info",
    }
    assert not any(n.startswith("agents/") for n in names)
    for env_id in SHIPPED:
        assert f"ekfslam_gym/models/ppo_{env_id}.zip" in names
    assert "ekfslam_gym/configs/ppo.yaml" in names and "ekfslam_gym/benchmark/reference.json" in names

    step("make the venv", [sys.executable, "-m", "venv", "--without-pip", str(venv)])
    python = venv / "bin" / "python"
    step(
        "install the wheel",
        [*pip, "--python", str(python), "install", "-q", "--no-deps", "--no-index", str(wheel)],
    )
    purelib = Path(
        subprocess.check_output(
            [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], text=True
        ).strip()
    )
    (purelib / "reuse_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")

    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env.update(OPENBLAS_NUM_THREADS="1", PATH=f"{venv / 'bin'}{os.pathsep}{env['PATH']}")
    run = {"cwd": work, "env": env}
    found = json.loads(step("make every registered id", [str(python), "-c", MAKE_EVERY_ID], **run))
    assert found["ids"] == REGISTERED and not found["agents"]
    assert Path(found["file"]).is_relative_to(venv) and found["backend"] == compiled.backend()

    scripts = venv / "bin"
    for env_id in SHIPPED:
        out = step(f"evaluate the shipped {env_id} policy, one episode",
                   [str(scripts / "ekfslam-evaluate"), "--agent", "ppo", "--env-id", env_id, "--seeds", "20000",
                    "--json", "--no-progress"], **run)  # fmt: skip
        assert json.loads(out)["episodes"] == 1
    step("ekfslam-train at smoke size", [str(scripts / "ekfslam-train"), "--config", "ppo", "--out", "run",
                                         "--no-progress", *SMOKE_TRAINING], **run)  # fmt: skip
    out = step("evaluate the trained model on its own env",
               [str(scripts / "ekfslam-evaluate"), "--agent", "ppo", "--model", "run/model.zip", "--seeds", "20000",
                "--max-episode-steps", "5", "--json", "--no-progress"], **run)  # fmt: skip
    assert json.loads(out)["episodes"] == 1
    out = step("ekfslam-benchmark --quick on EKFSLAM-v0",
               [str(scripts / "ekfslam-benchmark"), "--agent", "frontier", "--env-ids", "EKFSLAM-v0", "--quick",
                "--json", "--no-progress"], **run)  # fmt: skip
    assert json.loads(out)["results"]["EKFSLAM-v0"]["summary"]["episodes"] == 5
    step("pip check", [*pip, "--python", str(python), "check"], **run)

    print(f"\nwheel {wheel.name}: {wheel.stat().st_size / 2**20:.1f} MiB")
    for name, seconds in timings.items():
        print(f"  {name}: {seconds:.1f} s")
