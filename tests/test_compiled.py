"""The compiled kernels: ahead-of-time and JIT give the same env, a stale extension is refused, and the
layouts' flood fill agrees with scipy's connected components."""

import fnmatch
import os
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest

from ekfslam_gym import compiled

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_every_kernel_resolves_to_a_callable_of_its_source():
    for name, (module, function, _) in compiled.KERNELS.items():
        kernel = getattr(compiled, name)
        assert callable(kernel), name
        source = __import__(module, fromlist=[function])
        assert hasattr(source, function), f"{module}.{function} (the source of {name}) is missing"


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
    monkeypatch.setitem(compiled.KERNELS, "predict", ("m", "f", "void()"))
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
    """Every file the extension's digest covers (``compiled.SOURCES``) is among the Makefile's
    ``KERNEL_SOURCES``, so ``make install`` rebuilds it rather than leave a stale build to be refused."""
    with open(os.path.join(REPO, "Makefile"), encoding="utf-8") as file:
        makefile = file.read()
    listed = re.search(r"^KERNEL_SOURCES := (.*?)(?<!\\)$", makefile, re.M | re.S).group(1)
    patterns = re.findall(r"ekfslam_gym/[\w/*.]+\.py", listed)
    missing = [
        source
        for source in compiled.SOURCES
        if not any(fnmatch.fnmatch(f"ekfslam_gym/{source}", pattern) for pattern in patterns)
    ]
    assert patterns and not missing, f"add to the Makefile's KERNEL_SOURCES: {missing}"
