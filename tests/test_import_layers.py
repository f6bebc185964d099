"""The import contract: no import cycle anywhere in ``ekfslam_gym`` (the repository's ``agents/`` folder included,
installed as ``ekfslam_gym.agents``), and layers that import only the layers below them, lowest first:

    angles | compiled | kernel_types | ellipses | seeds | packaged | artefacts (the shipped files, found by
        importlib.resources; the names of a training run's files and its record's parser)
    sim | filter | graph
    envs | data
    evaluation
    agents | replay (the recorded drives replayed through the filter)
    training (itself ordered: settings, demonstrations, artefacts, cloning, keep_cloning, pretraining,
        trained_agent, run, sweep) | multi
    benchmark | pretrained (the protocol; the shipped policies with their envs)
    cli (the command lines, each also ``python -m ekfslam_gym.cli.<name>``)

Packages on one line are independent of each other. Inside ``agents``, the planners' shared pieces
(``agents.navigation``: the grid, walls, paths, frontiers, the veto) import no agent, so another env's planners
reuse them alone. Every ``import`` statement counts, those inside functions
(lazy imports) too. The graph is read from the sources with ``ast``, so nothing is imported to check it.

One name per module: the checkout's top-level ``agents/``, ``configs/`` and ``models/`` folders are the packages
``ekfslam_gym.agents``, ``.configs`` and ``.models``; their own names are refused (a second name would be a second
copy of every class), and a source tree imported without that mapping says so.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = {"ekfslam_gym": ROOT / "ekfslam_gym", "ekfslam_gym.agents": ROOT / "agents"}
MAPPED_FOLDERS = ("agents", "configs", "models")  # top-level folders installed inside the package (setup.py)

LAYERS: tuple[tuple[str, ...], ...] = (
    ("angles", "compiled", "ellipses", "seeds", "packaged", "artefacts", "kernel_types"),
    ("sim", "filter", "graph"),
    ("envs", "data"),
    ("evaluation",),
    ("agents", "replay"),
    ("training", "multi"),
    ("benchmark", "pretrained"),
    ("cli",),
)
TRAINING_ORDER = (
    "settings",
    "demonstrations",
    "artefacts",
    "cloning",
    "keep_cloning",
    "pretraining",
    "trained_agent",
    "run",
    "sweep",
)


def modules() -> dict[str, Path]:
    """Every module of the package by dotted name."""
    found = {}
    for package, folder in SOURCES.items():
        for path in folder.rglob("*.py"):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            found[".".join([package, *parts])] = path
    return found


def imports(known: Mapping[str, Path]) -> dict[str, set[str]]:
    """module -> the package modules it imports (anywhere in its source): ``from x import y`` is x.y when that is a
    module, else x; a name outside the package's modules resolves to its longest known prefix, if any."""
    graph: dict[str, set[str]] = {}
    for name, path in known.items():
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(package[: len(package) - node.level + 1] + ([base] if base else []))
                targets.update(
                    f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names
                )
        resolved = set()
        for target in targets:
            while target and target not in known:
                target = target.rpartition(".")[0]
            if target and target != name:
                resolved.add(target)
        graph[name] = resolved
    return graph


def place(module: str) -> tuple[int, str]:
    """(layer, group) of a module: its layer's index and the package on that line it belongs to."""
    rest = module.split(".", 1)[1] if "." in module else ""
    if not rest:
        return 2, "envs"  # the package's __init__ registers the env ids
    top = rest.split(".")[0]
    for index, line in enumerate(LAYERS):
        if top in line:
            return index, top
    raise AssertionError(f"{module} is in no layer: add its package to LAYERS")


def layer_violations(graph: Mapping[str, Iterable[str]]) -> list[str]:
    """Every import of a module in the same layer's other package or in a layer above."""
    found = []
    for module, targets in graph.items():
        layer, group = place(module)
        for target in targets:
            other, other_group = place(target)
            if other > layer or (other == layer and other_group != group):
                found.append(f"{module} imports {target} ({LAYERS[other]} is not below {LAYERS[layer]})")
    return sorted(found)


def training_violations(graph: Mapping[str, Iterable[str]]) -> list[str]:
    """Every import inside ``ekfslam_gym.training`` that goes against ``TRAINING_ORDER``."""
    prefix = "ekfslam_gym.training."
    rank = {f"{prefix}{name}": i for i, name in enumerate(TRAINING_ORDER)}
    found = []
    for module, targets in graph.items():
        for target in targets:
            if module in rank and target in rank and rank[target] >= rank[module]:
                found.append(f"{module} imports {target}, later in the training order")
    return sorted(found)


def navigation_violations(graph: Mapping[str, Iterable[str]]) -> list[str]:
    """Every import of an agents module outside ``agents.navigation`` (and the angles it reads) from inside it."""
    prefix = "ekfslam_gym.agents.navigation"
    found = []
    for module, targets in graph.items():
        if module == prefix or module.startswith(prefix + "."):
            for target in targets:
                inside = target == prefix or target.startswith(prefix + ".")
                if target.startswith("ekfslam_gym.agents") and not inside:
                    found.append(f"{module} imports {target}")
    return sorted(found)


def cycles(graph: Mapping[str, Iterable[str]]) -> list[list[str]]:
    """The import cycles: strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in graph.get(node, ()):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    return imports(modules())


def test_the_graph_is_read(graph):
    assert "ekfslam_gym.agents.frontier" in graph and "ekfslam_gym.training.run" in graph
    assert "ekfslam_gym.evaluation.metrics" in graph["ekfslam_gym.evaluation.rollout"] or any(
        t.startswith("ekfslam_gym.evaluation.") for t in graph["ekfslam_gym.evaluation.rollout"]
    )
    assert "ekfslam_gym.seeds" in graph["ekfslam_gym.cli.common"]  # ``from .. import seeds``


def test_no_import_cycle(graph):
    assert cycles(graph) == []


def test_layers_import_only_the_layers_below(graph):
    assert layer_violations(graph) == []


def test_training_imports_one_way(graph):
    assert training_violations(graph) == []


def test_the_planners_shared_pieces_import_no_agent(graph):
    assert "ekfslam_gym.agents.navigation.paths" in graph
    assert navigation_violations(graph) == []


def test_the_checks_catch_what_they_forbid():
    """An upward import (lazy or not), a peer import, a cycle and a training import against the order."""
    upward = {"ekfslam_gym.evaluation.rollout": {"ekfslam_gym.agents"}, "ekfslam_gym.agents": set()}
    assert layer_violations(upward) == [
        "ekfslam_gym.evaluation.rollout imports ekfslam_gym.agents (('agents', 'replay') is not below ('evaluation',))"
    ]
    assert layer_violations({"ekfslam_gym.replay.mrclam": {"ekfslam_gym.agents.base"}})  # peers, independent
    assert layer_violations({"ekfslam_gym.sim.world": {"ekfslam_gym.filter.ekf"}})  # peers are independent
    assert layer_violations({"ekfslam_gym.envs.config": {"ekfslam_gym.sim.robot"}}) == []
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert training_violations({"ekfslam_gym.training.cloning": {"ekfslam_gym.training.run"}})
    assert navigation_violations(
        {"ekfslam_gym.agents.navigation.paths": {"ekfslam_gym.agents.frontier.agent"}}
    )
    assert not navigation_violations({"ekfslam_gym.agents.frontier.agent": {"ekfslam_gym.agents.navigation"}})


def test_lazy_imports_are_read(tmp_path):
    source = tmp_path / "lazy.py"
    source.write_text("def f():\n    from .agents import make_agent\n    return make_agent\n")
    known = {"ekfslam_gym.lazy": source, "ekfslam_gym.agents": tmp_path / "agents.py"}
    (tmp_path / "agents.py").write_text("")
    assert imports(known)["ekfslam_gym.lazy"] == {"ekfslam_gym.agents"}


def _python(code: str, *options: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *options, "-c", code], cwd=cwd, capture_output=True, text=True)


@pytest.mark.parametrize(
    "name", ["agents", "agents.base", "agents.greedy.agent", "configs", "configs.env", "models"]
)
def test_the_top_level_name_is_refused_from_the_checkout(name):
    package = f"ekfslam_gym.{name.split('.')[0]}"
    done = _python(f"import {name}")
    assert done.returncode == 1
    assert f"ImportError: the checkout's {name.split('.')[0]}/ folder installs as {package}" in done.stderr


def test_the_package_name_is_the_one_module_from_the_checkout():
    """From the checkout's root the package name imports the checkout's files, and no top-level copy appears."""
    code = (
        "import sys, ekfslam_gym.agents.base as base, ekfslam_gym.configs, ekfslam_gym.models\n"
        "print(base.__file__)\n"
        f"print(sorted(m for m in sys.modules if m.split('.')[0] in {MAPPED_FOLDERS!r}))\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr
    file, others = done.stdout.splitlines()
    assert Path(file).resolve() == ROOT / "agents" / "base.py"
    assert others == "[]"


def test_a_source_tree_without_its_mapping_says_so(tmp_path):
    """The package's own folder on the path with no install's mapping (as when the checkout's root shadows a
    regular install): ``ekfslam_gym.agents`` is refused with the way out, and the env still registers."""
    (tmp_path / "ekfslam_gym").symlink_to(ROOT / "ekfslam_gym")
    site = [p for p in sys.path if p.endswith("site-packages")]
    code = (
        f"import sys; sys.path[:0] = [{str(tmp_path)!r}]; sys.path += {site!r}\n"
        "import gymnasium as gym, ekfslam_gym\n"
        "gym.make('EKFSLAM-v0').close()\n"
        "import ekfslam_gym.agents\n"
    )
    done = _python(code, "-S", cwd=tmp_path)  # -S: no site, so no .pth file installs an editable finder
    assert done.returncode == 1
    assert "ModuleNotFoundError: no module named 'ekfslam_gym.agents'" in done.stderr
    assert "is a source tree without its agents/ folder" in done.stderr
    assert "pip install -e" in done.stderr


def test_no_source_imports_a_mapped_folder_by_its_top_level_name():
    files = [
        *ROOT.glob("*.py"),
        *(p for d in ("ekfslam_gym", "agents", "tests", "bench", "docs") for p in (ROOT / d).rglob("*.py")),
    ]
    found = []
    for path in files:
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            found += [f"{path.relative_to(ROOT)}: {n}" for n in names if n.split(".")[0] in MAPPED_FOLDERS]
    assert found == []
