"""The compiled kernels of the env's hot path, from the ahead-of-time module when the install built it.

Why: numba compiles on first use (about 40 s after a fresh install) and, even from its on-disk cache, costs
~0.4 s to import and ~0.4 s more to load the first kernel, in every new process: every subprocess vector-env
worker and every command line. So ``pip install`` compiles the kernels listed in ``KERNELS`` ahead of time
with ``numba.pycc`` into the extension ``ekfslam_gym._aot`` (see ``setup.py``), from the very same Python
sources, and this module hands those out. Where that extension is absent (a build without numba's AOT
compiler, or ``EKFSLAM_GYM_JIT=1`` in the environment) it hands out the numba JIT functions instead: same
sources, same results, slower start.

The AOT functions do not check their arguments: callers pass exactly the dtypes and C-contiguous layouts in
the signatures below (the Python wrappers around them convert). Use: ``from ekfslam_gym import compiled``,
then ``compiled.predict(...)``; the first access of a name resolves it.
"""

from __future__ import annotations

import hashlib
import importlib
import os
import warnings
from pathlib import Path

_F8_1 = "f8[::1]"
_F8_2 = "f8[:, ::1]"

# name -> (source module, function, numba signature of the exported specialisation)
KERNELS: dict[str, tuple[str, str, str]] = {
    "predict": (
        "ekfslam_gym.filter.kernels",
        "predict",
        f"Tuple((f8, i8))({_F8_1}, {_F8_2}, {_F8_2}, i8, {_F8_1}, f8, f8, {_F8_2}, b1, b1, {_F8_1}, b1, {_F8_2})",
    ),
    "correct": (
        "ekfslam_gym.filter.kernels",
        "correct",
        f"Tuple((f8, i8, i8))({_F8_1}, {_F8_2}, {_F8_2}, b1[::1], i8[::1], {_F8_2}, {_F8_2}, f8, b1, b1, b1, "
        f"i8, i8, {_F8_1}, {_F8_2}, f8[:, :, ::1], i8[::1])",
    ),
    "associate": (
        "ekfslam_gym.filter.association_kernels",
        "associate",
        f"i8({_F8_1}, {_F8_2}, b1[::1], {_F8_2}, {_F8_2}, f8, i8, {_F8_1}, i8, i8[::1], {_F8_1})",
    ),
    "correct_unknown": (
        "ekfslam_gym.filter.association_kernels",
        "correct_unknown",
        f"Tuple((f8, i8, i8, i8))({_F8_1}, {_F8_2}, {_F8_2}, b1[::1], {_F8_2}, {_F8_2}, f8, b1, b1, b1, i8, i8, "
        f"{_F8_1}, {_F8_2}, f8[:, :, ::1], i8[::1], i8, {_F8_1}, f8, i8, i8, i8[::1], i8[::1], b1[::1], i8[::1])",
    ),
    "predict_correct": (
        "ekfslam_gym.filter.kernels",
        "predict_correct",
        f"Tuple((f8, i8, f8, i8, i8))({_F8_1}, {_F8_2}, {_F8_2}, b1[::1], i8, {_F8_1}, f8, f8, {_F8_2}, b1, "
        f"{_F8_1}, b1, {_F8_2}, i8[::1], {_F8_2}, {_F8_2}, f8, b1, b1, i8, i8, {_F8_2}, f8[:, :, ::1], i8[::1])",
    ),
    "min_wall_distance": ("ekfslam_gym.sim.geometry", "min_wall_distance", f"{_F8_1}({_F8_2}, {_F8_2})"),
    "visible_landmarks": (
        "ekfslam_gym.sim.geometry",
        "visible_landmarks",
        f"i8(f8, f8, f8, {_F8_2}, {_F8_2}, f8, f8, f8, f8, i8[::1], {_F8_2})",
    ),
    "add_reading_noise": ("ekfslam_gym.sim.geometry", "add_reading_noise", f"void({_F8_2}, {_F8_2}, f8, f8)"),
    "cast_rays": (
        "ekfslam_gym.sim.geometry",
        "cast_rays",
        f"void(f8, f8, f8, {_F8_1}, {_F8_2}, f8, f8, {_F8_1})",
    ),
    "accept_spaced": ("ekfslam_gym.sim.geometry", "accept_spaced", f"i8({_F8_2}, {_F8_2}, i8, f8)"),
    "connected_component": (
        "ekfslam_gym.sim.geometry",
        "connected_component",
        "b1[:, ::1](b1[:, ::1], i8, i8)",
    ),
    "free_cells": ("ekfslam_gym.sim.geometry", "free_cells", f"b1[:, ::1]({_F8_2}, f8, f8, f8, i8, i8, f8)"),
    "odometry_reading": (
        "ekfslam_gym.sim.odometry_kernels",
        "odometry_reading",
        f"void(f8, f8, f8, f8, f8, f8, {_F8_1}, {_F8_1}, {_F8_1}, {_F8_2}, {_F8_1})",
    ),
    "velocity_reading": (
        "ekfslam_gym.sim.odometry_kernels",
        "velocity_reading",
        f"void(f8, f8, f8, f8, f8, f8, f8, {_F8_1}, {_F8_1}, {_F8_1}, {_F8_2}, {_F8_1})",
    ),
    "tally_associations": (
        "ekfslam_gym.envs.association_truth",
        "tally_associations",
        f"Tuple((i8, i8, i8[::1], {_F8_2}))(i8[::1], {_F8_2}, i8[::1], b1[::1], i8[::1], b1[::1], i8[::1], {_F8_2}, "
        f"{_F8_2}, b1[::1])",
    ),
    "travel_distance": (
        "ekfslam_gym.envs.clearance_kernels",
        "travel_distance",
        f"f8({_F8_1}, {_F8_1}, b1[::1], f8, f8)",
    ),
    "scan_clearances": (
        "ekfslam_gym.envs.clearance_kernels",
        "scan_clearances",
        f"UniTuple(f8, 3)({_F8_1}, {_F8_1}, {_F8_1}, f8, f8, f8, b1)",
    ),
    "mark_coverage": (
        "ekfslam_gym.envs.kernels",
        "mark_coverage",
        f"i8({_F8_2}, {_F8_1}, {_F8_1}, f8, f8, f8)",
    ),
    "fill_observation": (
        "ekfslam_gym.envs.kernels",
        "fill_observation",
        f"void(f4[::1], i8[::1], {_F8_1}, {_F8_1}, {_F8_2}, b1[::1], f8, {_F8_2}, {_F8_1}, {_F8_2}, {_F8_1}, f8)",
    ),
    "mark_walls": (
        "ekfslam_gym.envs.kernels",
        "mark_walls",
        f"i8({_F8_2}, {_F8_1}, {_F8_1}, f8, {_F8_1}, {_F8_1}, f8)",
    ),
    "fill_belief_image": (
        "ekfslam_gym.envs.kernels",
        "fill_belief_image",
        f"void(f4[::1], i8, {_F8_2}, {_F8_2}, {_F8_1}, {_F8_1}, {_F8_2}, b1[::1], f8, f8)",
    ),
    "step_metrics": (
        "ekfslam_gym.envs.kernels",
        "step_metrics",
        f"Tuple((f8, f8, i8, f8, i8, f8, f8))({_F8_1}, {_F8_2}, b1[::1], UniTuple(f8, 3), {_F8_2}, i8[::1], "
        f"i8[::1], {_F8_1}, {_F8_1}, i8, i8)",
    ),
    "wheel_reading": (
        "ekfslam_gym.sim.odometry_kernels",
        "wheel_reading",
        f"void({_F8_2}, f8, f8, {_F8_1}, {_F8_1}, {_F8_1}, {_F8_2}, {_F8_1})",
    ),
    "measure_step": (
        "ekfslam_gym.sim.measurement_kernels",
        "measure_step",
        f"void(f8, f8, f8, f8, f8, f8, f8, f8, {_F8_1}, {_F8_1}, {_F8_1}, {_F8_2}, {_F8_1}, {_F8_2}, f8, f8)",
    ),
}

# Every file the kernels' machine code depends on, relative to the package: the build compiles their digest
# into the extension (``aot_digest()``), and an extension built from other sources (an editable install whose
# kernels were edited since) is not used.
SOURCES: tuple[str, ...] = (
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


def sources_digest() -> tuple[int, ...]:
    """SHA-256 over the kernel sources and the signature table, as four int64 (what the build compiles in)."""
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


def _load_aot():
    if os.environ.get("EKFSLAM_GYM_JIT", "") not in ("", "0"):
        return None
    try:
        module = importlib.import_module(AOT_MODULE)
    except ImportError:
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


_aot = _load_aot()


def backend() -> str:
    """``"aot"`` when the kernels come from the extension built at install, else ``"jit"`` (numba)."""
    return "aot" if _aot is not None else "jit"


def __getattr__(name: str):
    try:
        module, function, _ = KERNELS[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    kernel = getattr(_aot, name, None) if _aot is not None else None
    if kernel is None:
        kernel = getattr(importlib.import_module(module), function)
    globals()[name] = kernel
    return kernel
