"""The site as a reader meets it: it builds strictly, its code runs where a reader runs it, its words are theirs.

- ``mkdocs build --strict`` passes with every warning shown, and fails on a broken link injected into a copy;
- every ``python`` block of every page runs, page by page in one process (as a reader pastes them), from an
  empty folder outside the checkout against the installed package; a block whose first line says what it
  ``# needs`` (a data set to download) or how long it ``# takes`` is skipped, and says so on the page;
- no page names a file that exists only in a checkout, or a data set, without saying where to get it;
- no page, plot title or printed string uses the project's working words;
- every env page has its header table, its default configuration, its legend and its version history.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PAGES = sorted(DOCS.rglob("*.md"))
SKIP_MARK = re.compile(r"^# (needs|takes) ")


def _env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env.update(OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1", MPLBACKEND="Agg", NO_MKDOCS_2_WARNING="1")
    return env


def _build(config: Path, site: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config), "-d", str(site)],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=900,
    )


# ------------------------------------------------------------------------------------ the strict build
@pytest.mark.slow
def test_site_builds_strictly_without_a_warning(tmp_path) -> None:
    pytest.importorskip("mkdocstrings", reason="the docs extra builds the site")
    result = _build(ROOT / "mkdocs.yml", tmp_path / "site")
    assert result.returncode == 0, result.stderr[-3000:]
    assert "WARNING" not in result.stderr, result.stderr[-3000:]
    assert (tmp_path / "site" / "api" / "index.html").is_file()


@pytest.mark.slow
def test_a_broken_link_fails_the_build(tmp_path) -> None:
    """The same site with one link to a page that does not exist: the build stops and names it."""
    pytest.importorskip("mkdocstrings", reason="the docs extra builds the site")
    shutil.copytree(DOCS, tmp_path / "docs", ignore=shutil.ignore_patterns("*.gif"))
    shutil.copy(ROOT / "mkdocs.yml", tmp_path / "mkdocs.yml")
    index = tmp_path / "docs" / "index.md"
    index.write_text(index.read_text() + "\nSee [the missing page](no-such-page.md).\n")
    result = _build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert result.returncode != 0
    assert "no-such-page.md" in result.stderr


# ------------------------------------------------------------------------------------ code that runs
FILE_MARK = re.compile(r"^# (\w+\.py)\n")


def python_blocks(page: Path) -> tuple[list[str], list[str]]:
    """(blocks to run, reasons of the blocks skipped) of a page's ``python`` blocks; a block whose first line
    names a file (``# myagents.py``) is that file's content, saved rather than run (``saved_files``)."""
    blocks = re.findall(r"^```python\n(.*?)^```", page.read_text(), re.S | re.M)
    run = [b for b in blocks if not SKIP_MARK.match(b) and not FILE_MARK.match(b)]
    skipped = [b.split("\n", 1)[0] for b in blocks if SKIP_MARK.match(b)]
    return run, skipped


def shown_outputs(page: Path) -> list[str]:
    """The lines of every ``text`` block a page introduces with "Output:"."""
    blocks = re.findall(r"^Output:\n\n```text\n(.*?)^```", page.read_text(), re.S | re.M)
    return [line for block in blocks for line in block.splitlines() if line.strip()]


def saved_files(page: Path) -> dict[str, str]:
    """{file name: content} of the blocks a page asks the reader to save."""
    blocks = re.findall(r"^```python\n(.*?)^```", page.read_text(), re.S | re.M)
    return {m.group(1): b for b in blocks if (m := FILE_MARK.match(b))}


PYTHON_PAGES = [p for p in PAGES if "```python\n" in p.read_text()]


@pytest.mark.slow
@pytest.mark.parametrize("page", PYTHON_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_python_blocks_run_from_an_empty_folder_outside_the_checkout(page: Path, tmp_path) -> None:
    run, skipped = python_blocks(page)
    for reason in skipped:  # a skipped block says why, in words a reader can act on
        assert len(reason) > 20, f"{page.name}: a skipped block needs its reason: {reason!r}"
    if not run:
        pytest.skip(f"every block of {page.name} is marked: {skipped}")
    folder = tmp_path / "reader"
    folder.mkdir()
    for name, content in saved_files(page).items():  # what the page asks the reader to save, saved
        (folder / name).write_text(content)
    script = folder / "page_blocks.py"  # run as a reader runs a script: from the folder that holds it
    script.write_text("\n\n".join(run))
    result = subprocess.run(
        [sys.executable, str(script)], cwd=folder, capture_output=True, text=True, env=_env(), timeout=900
    )
    assert result.returncode == 0, f"{page.name}:\n{result.stderr[-3000:]}"
    assert not ROOT.is_relative_to(folder) and not folder.is_relative_to(ROOT)
    printed = result.stdout.splitlines()
    for shown in shown_outputs(page):  # what the page says the blocks print, they print
        assert shown in printed, f"{page.name} shows {shown!r}; the blocks printed {printed}"


def test_marked_blocks_are_skipped_and_the_rest_kept(tmp_path) -> None:
    page = tmp_path / "page.md"
    page.write_text(
        "```python\nprint(1)\n```\n\n```python\n# needs the Victoria Park files (see Real data)\nload()\n```\n"
    )
    run, skipped = python_blocks(page)
    assert run == ["print(1)\n"] and skipped == ["# needs the Victoria Park files (see Real data)"]
    page.write_text("```python\nprint(2)\n```\n\nOutput:\n\n```text\n2\n```\n")
    assert shown_outputs(page) == ["2"]
    page.write_text("```python\n# mine.py\nX = 1\n```\n\n```python\nfrom mine import X\n```\n")
    assert python_blocks(page) == (["from mine import X\n"], []) and saved_files(page) == {
        "mine.py": "# mine.py\nX = 1\n"
    }


# ------------------------------------------------------------------------------------ paths a reader has
CHECKOUT_ONLY = (
    "configs/",
    "models/",
    "tests/",
    "bench/",
    "docs/",
    ".ci/",
    "train.py",
    "demo.py",
    "Makefile",
)
WHERE = re.compile(r"checkout|repository|git clone", re.I)


def unexplained_paths(text: str) -> list[str]:
    """What a page names that a reader may not have, unless the page says where to get it: a repository path
    needs the page to say it is the repository's; a data path must be ``DATA/...`` with a link to the page on
    data sets; a path into the development machine's own data folder is never right."""
    found = [m.group(0) for m in re.finditer(r"(?:\.\./)?shared/data\S*", text)]
    if "DATA/" in text and "data-sets.md" not in text and not text.startswith("# Data sets"):
        found.append("DATA/ without a link to data-sets.md")
    if not WHERE.search(text):
        code = re.findall(r"`([^`\n]+)`", text) + re.findall(r"^```[^\n]*\n(.*?)^```", text, re.S | re.M)
        for token in (t for c in code for t in re.split(r"[\s,;()\[\]'\"=]+", c)):
            if token.startswith(CHECKOUT_ONLY):
                found.append(token)
    return found


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_pages_say_where_their_files_come_from(page: Path) -> None:
    missing = unexplained_paths(page.read_text())
    assert not missing, f"{page.name} names files a reader may not have, without saying where: {missing}"


def test_the_path_check_finds_what_it_is_for() -> None:
    assert unexplained_paths("Load `models/ppo_EKFSLAM-v0.zip`.") == ["models/ppo_EKFSLAM-v0.zip"]
    assert unexplained_paths("In a checkout, `configs/ppo.yaml` has it.") == []
    assert unexplained_paths("Read `../shared/data/mrclam`.") == ["../shared/data/mrclam`."]
    assert unexplained_paths("`--data DATA/mrclam`") == ["DATA/ without a link to data-sets.md"]
    assert unexplained_paths("`--data DATA/mrclam` ([Data sets](data-sets.md))") == []


# ------------------------------------------------------------------------------------ the reader's words
WORKING_WORDS = re.compile(
    r"(?<!progress )(?<!error )\b(?:bars?(?!-Shalom)|issue's|issues?|maintainers?|yardsticks?|the lead)\b",
    re.I,
)
STRING_SOURCES = [
    *sorted((ROOT / "ekfslam_gym").rglob("*.py")),
    *sorted((ROOT / "agents").rglob("*.py")),
    *sorted(DOCS.glob("*.py")),
    ROOT / "train.py",
    ROOT / "demo.py",
]


def working_words(text: str) -> list[str]:
    return [m.group(0) for m in WORKING_WORDS.finditer(text)]


@pytest.mark.parametrize("page", [*PAGES, ROOT / "README.md"], ids=lambda p: str(p.relative_to(ROOT)))
def test_pages_use_the_readers_words(page: Path) -> None:
    assert not working_words(page.read_text()), f"{page.name}: {working_words(page.read_text())}"


def test_plot_titles_help_and_printed_strings_use_the_readers_words() -> None:
    """Every string of the package, the agents and the docs' scripts: plot titles, --help, printed lines."""
    found = []
    for path in STRING_SOURCES:
        with path.open("rb") as handle:
            for token in tokenize.tokenize(handle.readline):
                if token.type == tokenize.STRING and working_words(token.string):
                    found.append(f"{path.relative_to(ROOT)}:{token.start[0]} {working_words(token.string)}")
    assert not found, found


def test_the_word_check_finds_what_it_is_for() -> None:
    assert working_words("the bar asks for 0.05 m; the issue's yardstick") == ["bar", "issue's", "yardstick"]
    assert working_words("no progress bars, error bars (Bar-Shalom)") == []


# ------------------------------------------------------------------------------------ env pages
def test_every_registered_id_has_a_complete_page() -> None:
    from gymnasium.envs.registration import registry

    import ekfslam_gym  # noqa: F401

    ids = [i for i, s in registry.items() if str(s.entry_point).startswith("ekfslam_gym.")]
    assert ids
    for env_id in ids:
        text = (DOCS / "envs" / f"{env_id}.md").read_text()
        for row in ("| Action space |", "| Observation space |", "| Reward range |", "| Episode length |"):
            assert row in text, (env_id, row)
        assert f'gymnasium.make("{env_id}")' in text
        assert "## Configuration" in text and "\nmax_episode_steps: " in text and "\nsensor:\n" in text
        assert "legend" in text and f"../images/{env_id}.png" in text
        assert "## Version history" in text and f"**{env_id}**" in text


@pytest.mark.slow
def test_the_readmes_python_blocks_run_in_the_checkout(tmp_path) -> None:
    """The README is read in the repository, so its blocks run from the checkout's root."""
    run, _ = python_blocks(ROOT / "README.md")
    assert run
    script = tmp_path / "readme_blocks.py"
    script.write_text("\n\n".join(run))
    result = subprocess.run(
        [sys.executable, str(script)], cwd=ROOT, capture_output=True, text=True, env=_env(), timeout=900
    )
    assert result.returncode == 0, result.stderr[-3000:]
