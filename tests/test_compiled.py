"""The compiled kernels: ahead-of-time and JIT give the same env, a stale extension is refused, a missing one
said aloud, the signatures come from the kernels' annotations, and the layouts' flood fill agrees with scipy's
connected components."""

import ast
import importlib
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from ekfslam_gym import compiled
from ekfslam_gym.kernel_types import numba_signature, numba_type

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_every_kernel_resolves_to_a_callable_of_its_source():
    for name, module in compiled.KERNELS.items():
        kernel = getattr(compiled, name)
        assert callable(kernel), name
        source = __import__(module, fromlist=[name])
        assert hasattr(source, name), f"{module}.{name} (the source of {name}) is missing"


def test_every_kernel_signature_comes_from_its_annotations():
    from numba.core import sigutils

    for name, module in compiled.KERNELS.items():
        kernel = getattr(importlib.import_module(module), name)
        arguments, _ = sigutils.normalize_signature(numba_signature(kernel))
        assert len(arguments) == kernel.py_func.__code__.co_argcount, name


def test_the_filter_kernels_take_their_arrays_and_options_bundled():
    from numba.core import sigutils, types

    from ekfslam_gym.filter import kernels

    (arrays, options, *rest), _ = sigutils.normalize_signature(numba_signature(kernels.predict_correct))
    assert isinstance(arrays, types.BaseTuple) and len(arrays) == 10 and len(options) == 8
    assert len(rest) == 5  # control, its covariance, ids, readings, Q


def test_signature_types_are_spelt_as_numba_reads_them():
    assert numba_type("tuple[float, int, F8Array2]") == "Tuple((f8, i8, f8[:, ::1]))"
    assert numba_type("tuple[bool]") == "Tuple((b1,))"
    assert numba_type("Pair", aliases={"Pair": "tuple[I8Array1, BoolArray1]"}) == "Tuple((i8[::1], b1[::1]))"

    # as a kernel module reads them (from __future__ import annotations): strings
    def unannotated(a: "float", b) -> "None":
        pass

    def unknown(a: "np.ndarray") -> "None":
        pass

    def no_return(a: "float"):
        pass

    def evaluated(a: float) -> None:
        pass

    with pytest.raises(TypeError, match="parameter 'b' has no annotation"):
        numba_signature(unannotated)
    with pytest.raises(TypeError, match=r"unknown\(a\): 'np.ndarray' is not a kernel type"):
        numba_signature(unknown)
    with pytest.raises(TypeError, match="return type has no annotation"):
        numba_signature(no_return)
    with pytest.raises(TypeError, match="from __future__ import annotations"):
        numba_signature(evaluated)


def _package_imports(path: Path) -> set[Path]:
    """The package files ``path`` imports by relative import, and theirs, transitively."""
    found: set[Path] = set()
    todo = [path]
    while todo:
        current = todo.pop()
        for node in ast.walk(ast.parse(current.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                base = current.parent
                for _ in range(node.level - 1):
                    base = base.parent
                target = base.joinpath(*(node.module or "").split("."))
                candidates = [target.with_suffix(".py")] + [target / f"{a.name}.py" for a in node.names]
                for candidate in candidates:
                    if candidate.is_file() and candidate not in found:
                        found.add(candidate)
                        todo.append(candidate)
    return found


def test_the_digest_covers_every_kernel_module_and_what_it_imports():
    package = Path(compiled.__file__).parent
    modules = {package.joinpath(*m.split(".")[1:]).with_suffix(".py") for m in compiled.KERNELS.values()}
    needed = modules | {p for m in modules for p in _package_imports(m)}
    listed = {package / source for source in compiled.SOURCES}
    missing = sorted(str(p.relative_to(package)) for p in needed - listed)
    assert not missing, f"add to compiled.SOURCES: {missing}"


def test_unknown_kernel_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no_such_kernel"):
        compiled.no_such_kernel  # noqa: B018


@pytest.mark.skipif(compiled.backend() != "aot", reason="the ahead-of-time extension is not built here")
def test_jit_backend_reproduces_the_golden_rollouts():
    """The AOT extension is what the tests above ran; the JIT fallback, from the same sources, must agree."""
    env = {**os.environ, "EKFSLAM_GYM_JIT": "1"}
    code = "from ekfslam_gym import compiled; assert compiled.backend() == 'jit'"
    subprocess.run([sys.executable, "-c", code], env=env, check=True, cwd=REPO)
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests/envs/test_golden_rollouts.py"],
        env=env, cwd=REPO, capture_output=True, text=True,
    )  # fmt: skip
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    from tests.golden.record import ENV_IDS, SETTINGS

    assert f"{len(ENV_IDS) * len(SETTINGS)} passed" in result.stdout


@pytest.mark.skipif(compiled.backend() != "aot", reason="the ahead-of-time extension is not built here")
def test_an_extension_built_from_other_sources_is_refused(monkeypatch):
    monkeypatch.setattr(compiled, "sources_digest", lambda: (0, 0, 0, 0))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert compiled._load_aot() is None
    assert any("other sources" in str(w.message) for w in caught)


def test_digest_changes_with_the_sources(monkeypatch):
    before = compiled.sources_digest()
    monkeypatch.setitem(compiled.KERNELS, "predict", "some.other.module")
    assert compiled.sources_digest() != before
    assert compiled.digest_kernel(before)() == before


@pytest.mark.parametrize("seed", range(5))
def test_connected_component_matches_scipy_label(seed):
    ndimage = pytest.importorskip("scipy.ndimage")
    rng = np.random.default_rng(seed)
    free = rng.random((37, 23)) < 0.6
    row, col = np.argwhere(free)[rng.integers(free.sum())]
    labels, _ = ndimage.label(free)  # default structure: 4-connectivity, as the flood fill
    expected = labels == labels[row, col]
    np.testing.assert_array_equal(compiled.connected_component(free, int(row), int(col)), expected)


def test_the_makefile_rebuilds_the_extension_when_any_kernel_source_changes():
    """The Makefile's ``KERNEL_SOURCES`` are ``compiled.SOURCES``, printed by ``compiled.py`` run as a plain
    script (no package import, so any Python will do), so ``make install`` rebuilds the extension whenever a
    file of its digest changes rather than leave a stale build to be refused."""
    makefile = Path(REPO, "Makefile").read_text(encoding="utf-8")
    assert (
        "KERNEL_SOURCES := setup.py ekfslam_gym/compiled.py $(shell $(PYTHON) ekfslam_gym/compiled.py)"
        in makefile
    )
    printed = subprocess.run(
        [sys.executable, "-I", "ekfslam_gym/compiled.py"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=True,
    )
    assert printed.stdout.split() == [f"ekfslam_gym/{source}" for source in compiled.SOURCES]
    assert printed.stderr == ""
    assert all(Path(REPO, path).is_file() for path in printed.stdout.split())


def test_a_missing_extension_is_said_aloud_unless_the_jit_is_chosen(monkeypatch):
    def no_extension(name):
        raise ImportError(name)

    monkeypatch.setattr(compiled.importlib, "import_module", no_extension)
    monkeypatch.delenv("EKFSLAM_GYM_JIT", raising=False)
    with pytest.warns(RuntimeWarning, match="EKFSLAM_GYM_REQUIRE_AOT=1"):
        assert compiled._load_aot() is None
    monkeypatch.setenv("EKFSLAM_GYM_JIT", "1")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert compiled._load_aot() is None


def test_a_failed_build_fails_the_install_only_when_asked_to(monkeypatch, capsys):
    error = OSError("no C compiler")
    monkeypatch.setenv(compiled.REQUIRE_AOT, "1")
    with pytest.raises(RuntimeError, match="EKFSLAM_GYM_REQUIRE_AOT is set: OSError"):
        compiled.build_failed(error)
    monkeypatch.setenv(compiled.REQUIRE_AOT, "0")
    compiled.build_failed(error)
    assert "ahead-of-time kernels not built (OSError('no C compiler'))" in capsys.readouterr().err
