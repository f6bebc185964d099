"""The compiled kernels of the env's hot path, from the ahead-of-time module when the install built it.

Why: numba compiles on first use (about 40 s after a fresh install) and, even from its on-disk cache, costs
~0.4 s to import and ~0.4 s more to load the first kernel, in every new process: every subprocess vector-env
worker and every command line. So ``pip install`` compiles the kernels listed in ``KERNELS`` ahead of time
with ``numba.pycc`` into the extension ``ekfslam_gym._aot`` (see ``setup.py``), from the very same Python
sources, and this module hands those out. Where that extension is absent (a build without numba's AOT
compiler, or ``EKFSLAM_GYM_JIT=1`` in the environment) it hands out the numba JIT functions instead: same
sources, same results, slower start.

The AOT functions do not check their arguments: callers pass exactly the dtypes and C-contiguous layouts of
the kernels' annotations (the Python wrappers around them convert). Use: ``from ekfslam_gym import compiled``,
then ``compiled.predict(...)``; the first access of a name resolves it.
"""

from __future__ import annotations

import hashlib
import importlib
import os
import sys
import warnings
from pathlib import Path

# name -> the module whose function of that name is the kernel. Each kernel's signature, the specialisation the
# build exports, is written as its annotations (``ekfslam_gym.kernel_types``).
KERNELS: dict[str, str] = {
    "predict": "ekfslam_gym.filter.kernels",
    "correct": "ekfslam_gym.filter.kernels",
    "predict_correct": "ekfslam_gym.filter.kernels",
    "associate": "ekfslam_gym.filter.association_kernels",
    "correct_unknown": "ekfslam_gym.filter.association_kernels",
    "min_wall_distance": "ekfslam_gym.sim.geometry",
    "visible_landmarks": "ekfslam_gym.sim.geometry",
    "add_reading_noise": "ekfslam_gym.sim.geometry",
    "cast_rays": "ekfslam_gym.sim.geometry",
    "accept_spaced": "ekfslam_gym.sim.geometry",
    "connected_component": "ekfslam_gym.sim.geometry",
    "free_cells": "ekfslam_gym.sim.geometry",
    "odometry_reading": "ekfslam_gym.sim.odometry_kernels",
    "velocity_reading": "ekfslam_gym.sim.odometry_kernels",
    "wheel_reading": "ekfslam_gym.sim.odometry_kernels",
    "measure_step": "ekfslam_gym.sim.measurement_kernels",
    "tally_associations": "ekfslam_gym.envs.association_truth",
    "travel_distance": "ekfslam_gym.envs.clearance_kernels",
    "scan_clearances": "ekfslam_gym.envs.clearance_kernels",
    "mark_coverage": "ekfslam_gym.envs.kernels",
    "fill_observation": "ekfslam_gym.envs.kernels",
    "mark_walls": "ekfslam_gym.envs.kernels",
    "fill_belief_image": "ekfslam_gym.envs.kernels",
    "step_metrics": "ekfslam_gym.envs.kernels",
}

# Every file the kernels' machine code and signatures depend on, relative to the package: the build compiles
# their digest into the extension (``aot_digest()``), and an extension built from other sources (an editable
# install whose kernels were edited since) is not used. The Makefile reads this list (``python compiled.py``);
# a test holds it to the kernel modules and what they import from the package.
SOURCES: tuple[str, ...] = (
    "kernel_types.py",
    "angles.py",
    "filter/codes.py",
    "filter/models.py",
    "filter/kernels.py",
    "filter/association_kernels.py",
    "sim/geometry.py",
    "sim/odometry_kernels.py",
    "sim/measurement_kernels.py",
    "envs/kernels.py",
    "envs/clearance_kernels.py",
    "envs/observation_codes.py",
    "envs/association_truth.py",
)
AOT_MODULE = "ekfslam_gym._aot"
# Set (to anything but 0) where a missing ahead-of-time build is an error, not a fallback: CI, release builds.
REQUIRE_AOT = "EKFSLAM_GYM_REQUIRE_AOT"


def sources_digest() -> tuple[int, ...]:
    """SHA-256 over the kernel table and the kernel sources, as four int64 (what the build compiles in)."""
    package = Path(__file__).resolve().parent
    digest = hashlib.sha256(repr(sorted(KERNELS.items())).encode())
    for relative in SOURCES:
        digest.update((package / relative).read_bytes())
    raw = digest.digest()
    return tuple(int.from_bytes(raw[i : i + 8], "little", signed=True) for i in range(0, 32, 8))


def digest_kernel(parts: tuple[int, ...]):
    """A function returning ``parts``, for the build to compile into the extension as ``aot_digest``."""
    a, b, c, d = parts

    def aot_digest():
        return a, b, c, d

    return aot_digest


def build_failed(error: Exception) -> None:
    """What the install does when the ahead-of-time build fails (``setup.py``): raise where ``REQUIRE_AOT`` is
    set, else say so on stderr and go on (the package then uses numba's JIT, and warns when it first does)."""
    if os.environ.get(REQUIRE_AOT, "") not in ("", "0"):
        raise RuntimeError(
            f"the ahead-of-time kernels were not built, and {REQUIRE_AOT} is set: {error!r}"
        ) from error
    rule = "!" * 100
    message = f"warning: ahead-of-time kernels not built ({error!r}); numba's JIT will be used ({REQUIRE_AOT}=1: fail)"
    print(f"{rule}\n{message}\n{rule}", file=sys.stderr)


def _load_aot():
    if os.environ.get("EKFSLAM_GYM_JIT", "") not in ("", "0"):
        return None
    try:
        module = importlib.import_module(AOT_MODULE)
    except ImportError:
        warnings.warn(
            "ekfslam_gym: the ahead-of-time kernels were not built at install; numba's JIT compiles them on first "
            f"use instead (about 40 s once, then cached). Reinstall with {REQUIRE_AOT}=1 to see why the build "
            "failed, or set EKFSLAM_GYM_JIT=1 to choose the JIT and silence this",
            RuntimeWarning,
            stacklevel=2,
        )
        return None
    if tuple(module.aot_digest()) != sources_digest():
        warnings.warn(
            "ekfslam_gym: the ahead-of-time kernels were built from other sources than these; using numba's "
            "JIT instead (reinstall the package to rebuild them)",
            RuntimeWarning,
            stacklevel=2,
        )
        return None
    return module


_aot = None if __name__ == "__main__" else _load_aot()  # run as a script it only lists the sources


def backend() -> str:
    """``"aot"`` when the kernels come from the extension built at install, else ``"jit"`` (numba)."""
    return "aot" if _aot is not None else "jit"


def __getattr__(name: str):
    try:
        module = KERNELS[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    kernel = getattr(_aot, name, None) if _aot is not None else None
    if kernel is None:
        kernel = getattr(importlib.import_module(module), name)
    globals()[name] = kernel
    return kernel


if __name__ == "__main__":  # the Makefile's list of kernel sources, without importing the package
    print(" ".join(f"ekfslam_gym/{source}" for source in SOURCES))
