"""Build hook: compile the env's hot-path numba kernels ahead of time into ``ekfslam_gym._aot``.

Everything else about the package is in ``pyproject.toml``. ``ekfslam_gym/compiled.py`` lists the kernels and
explains why, each kernel's annotations give its signature (``ekfslam_gym/kernel_types.py``); this only runs
``numba.pycc`` over them at install time. If that fails (no compiler, a numba without ``pycc``), the install
raises where ``EKFSLAM_GYM_REQUIRE_AOT=1`` is set (CI), and otherwise goes on with a warning, the package then
using numba's JIT (and saying so when it first loads a kernel).
"""

from __future__ import annotations

import importlib
import os
import sys
import types
from pathlib import Path

from setuptools import Extension, find_packages, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
PACKAGE = ROOT / "ekfslam_gym"
AOT = "ekfslam_gym._aot"


def _kernel_table():
    """``ekfslam_gym.compiled`` imported without running the package ``__init__`` files (gymnasium, pymunk
    and SB3 are not build dependencies; only numpy and numba are)."""
    os.environ["EKFSLAM_GYM_JIT"] = "1"  # do not load a stale extension while building a new one
    for name in ("ekfslam_gym", "ekfslam_gym.sim", "ekfslam_gym.filter", "ekfslam_gym.envs"):
        stub = types.ModuleType(name)
        stub.__path__ = [str(PACKAGE.joinpath(*name.split(".")[1:]))]
        sys.modules[name] = stub
    return importlib.import_module("ekfslam_gym.compiled")


class BuildKernels(build_ext):
    def build_extension(self, ext: Extension) -> None:
        if ext.name != AOT:
            super().build_extension(ext)
            return
        target = Path(self.get_ext_fullpath(ext.name))
        compiled = _kernel_table()
        try:
            from numba.pycc import CC

            kernel_types = importlib.import_module("ekfslam_gym.kernel_types")
            cc = CC(target.name.split(".")[0], "ekfslam_gym.compiled")
            cc.output_dir = str(target.parent)
            cc.output_file = target.name
            for name, module in compiled.KERNELS.items():
                kernel = getattr(importlib.import_module(module), name)
                cc.export(name, kernel_types.numba_signature(kernel))(kernel.py_func)
            cc.export("aot_digest", "UniTuple(i8, 4)()")(compiled.digest_kernel(compiled.sources_digest()))
            cc.compile()
        except Exception as error:
            # raises under EKFSLAM_GYM_REQUIRE_AOT, else warns: numba's JIT takes over
            compiled.build_failed(error)


# The repository's top-level folders that install inside the package (the project's layout keeps them at the top):
# the agents, the shipped policies and the training recipes with the env presets. configs/experiments/ stays out
# (its recipes are the record of past experiments, not the package's); the data files themselves are listed as
# package data in pyproject.toml and read through importlib.resources (ekfslam_gym.packaged).
MAPPED = {
    "ekfslam_gym.agents": "agents",
    "ekfslam_gym.models": "models",
    "ekfslam_gym.configs": "configs",
    "ekfslam_gym.configs.env": "configs/env",
}


def _packages() -> tuple[list[str], dict[str, str]]:
    """The packages and their folders. The agents install as ``ekfslam_gym.agents``, so a user's own ``agents``
    module never clashes; ``models/`` and ``configs/`` travel with the package as its data."""
    packages = find_packages(where=str(ROOT), include=["ekfslam_gym", "ekfslam_gym.*"])
    agents = [f"ekfslam_gym.agents.{name}" for name in find_packages(str(ROOT / "agents"))]
    return packages + list(MAPPED) + agents, dict(MAPPED)


PACKAGES, PACKAGE_DIR = _packages()

setup(
    packages=PACKAGES,
    package_dir=PACKAGE_DIR,
    ext_modules=[Extension(AOT, sources=[], optional=True)],
    cmdclass={"build_ext": BuildKernels},
)
