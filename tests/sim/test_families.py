"""Layout families and tiers, registry-wide: exact landmark counts, every landmark reachable from the start and
clear of walls (checked on an independent grid: brute-force distances and scipy's labelling), determinism per
seed; the fast free-space grid against brute force; the keyword registry and its check at config build."""

from __future__ import annotations

import inspect
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from scipy import ndimage

import ekfslam_gym  # noqa: F401  (registers the ids)
from ekfslam_gym.envs import EnvConfig
from ekfslam_gym.seeds import HELDOUT_FAMILIES, TRAINING_FAMILIES, check_training_family, family_seeds
from ekfslam_gym.sim import FAMILIES, LAYOUTS, TIERS, World, layout_keywords, make_layout, world_section
from ekfslam_gym.sim.geometry import free_cells, min_wall_distance

ROOT = Path(__file__).resolve().parents[2]
CASES = [(family, tier) for family in FAMILIES for tier in TIERS]


def _layout(family: str, tier: str, seed: int):
    world = world_section(family, tier)
    return make_layout(
        world["layout"], np.random.default_rng(seed), world["n_landmarks"], **world["layout_kwargs"]
    )


def _reachable_from_start(layout, clearance: float, cell: float = 0.1) -> np.ndarray:
    """For each landmark, whether a disc of radius ``clearance`` can move from the start to it: an independent
    grid of brute-force distances (cells whose centres are clearance + cell / sqrt(2) clear), labelled by scipy."""
    xmin, ymin, xmax, ymax = layout.bounds
    nx, ny = int(math.ceil((xmax - xmin) / cell)), int(math.ceil((ymax - ymin) / cell))
    xs, ys = xmin + (np.arange(nx) + 0.5) * cell, ymin + (np.arange(ny) + 0.5) * cell
    centres = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    free = (min_wall_distance(centres, layout.walls) >= clearance + cell / math.sqrt(2.0)).reshape(ny, nx)
    labels, _ = ndimage.label(free)

    def label(points: np.ndarray) -> np.ndarray:
        cols = ((points[:, 0] - xmin) // cell).astype(int)
        rows = ((points[:, 1] - ymin) // cell).astype(int)
        return labels[rows, cols]

    start = label(layout.start[None, :2])[0]
    assert start > 0, "the start's own cell is not free"
    return label(layout.landmarks) == start


def test_at_least_six_families_with_three_tiers_each() -> None:
    assert len(FAMILIES) >= 6 and TIERS == ("easy", "medium", "hard")
    assert {"arena", "rooms", "loop"} <= set(FAMILIES) <= set(LAYOUTS)


@pytest.mark.parametrize(("family", "tier"), CASES)
def test_every_family_and_tier_generates_a_valid_world(family: str, tier: str) -> None:
    n = world_section(family, tier)["n_landmarks"]
    for seed in range(3):
        layout = _layout(family, tier, seed)
        assert layout.name == family and layout.landmarks.shape == (n, 2)
        xmin, ymin, xmax, ymax = layout.bounds
        walls = layout.walls
        assert np.all((walls[:, [0, 2]] >= xmin) & (walls[:, [0, 2]] <= xmax))
        assert np.all((walls[:, [1, 3]] >= ymin) & (walls[:, [1, 3]] <= ymax))
        assert min_wall_distance(layout.landmarks, walls).min() >= 0.5  # the default landmark_clearance
        assert min_wall_distance(layout.start[None, :2], walls)[0] >= 1.0  # the default start_clearance
        gaps = np.hypot(*(layout.landmarks[:, None] - layout.landmarks[None]).transpose(2, 0, 1))
        assert gaps[~np.eye(n, dtype=bool)].min() >= 1.0  # the default min_spacing
        assert np.all(_reachable_from_start(layout, 0.2 + 0.05)), "a landmark the robot cannot reach"
        World(layout)  # pymunk accepts it: the robot does not overlap a wall at the start


@pytest.mark.parametrize("family", FAMILIES)
def test_families_are_deterministic_per_seed_and_differ_between_seeds(family: str) -> None:
    for tier in TIERS:
        a, b, c = _layout(family, tier, 11), _layout(family, tier, 11), _layout(family, tier, 12)
        for field in ("walls", "landmarks", "start", "bounds"):
            assert np.array_equal(getattr(a, field), getattr(b, field))
        assert not np.array_equal(a.landmarks, c.landmarks)
        assert not np.array_equal(a.start, c.start)


@pytest.mark.parametrize("family", sorted(set(FAMILIES) - {"arena", "loop", "figure_eight"}))
def test_structured_families_draw_their_walls(family: str) -> None:
    walls = {_layout(family, "medium", seed).walls.tobytes() for seed in range(4)}
    assert len(walls) == 4


def test_tiers_grow_thin_out_and_occlude_more() -> None:
    for family in FAMILIES:
        areas, walls, density = [], [], []
        for tier in TIERS:
            layout = _layout(family, tier, 0)
            xmin, ymin, xmax, ymax = layout.bounds
            areas.append((xmax - xmin) * (ymax - ymin))
            walls.append(len(layout.walls))
            density.append(layout.n_landmarks / areas[-1])
        assert areas[0] < areas[1] < areas[2], family
        assert walls[0] <= walls[1] <= walls[2], family
        assert density[0] > density[1] > density[2], family


def test_maze_is_a_tree_of_corridors() -> None:
    """With braid 0 the maze's cells form a spanning tree: cells - 1 openings, every cell reachable."""
    from ekfslam_gym.sim.procedural import _spanning_tree

    rows, cols = 7, 9
    closed = _spanning_tree(np.random.default_rng(3), rows, cols, braid=0.0)
    openings = (~closed[0, 1:rows, :cols]).sum() + (~closed[1, :rows, 1:cols]).sum()
    assert openings == rows * cols - 1
    assert closed[0, 0, :cols].all() and closed[0, rows, :cols].all()
    assert closed[1, :rows, 0].all() and closed[1, :rows, cols].all()
    braided = _spanning_tree(np.random.default_rng(3), rows, cols, braid=0.5)
    assert (~braided[0, 1:rows, :cols]).sum() + (~braided[1, :rows, 1:cols]).sum() > openings


def test_world_section_is_a_fresh_config_and_names_valid_values() -> None:
    section = world_section("maze", "hard")
    section["layout_kwargs"]["cell"] = 99.0
    assert world_section("maze", "hard")["layout_kwargs"]["cell"] == 2.5
    EnvConfig.from_overrides(world=world_section("office", "easy"))
    with pytest.raises(ValueError, match="arena.*rooms"):
        world_section("castle", "easy")
    with pytest.raises(ValueError, match="easy, medium, hard"):
        world_section("maze", "extreme")


def test_medium_arena_and_loop_are_the_v0_worlds() -> None:
    v0 = gym.make("EKFSLAM-v0").unwrapped.config.world
    loop = gym.make("EKFSLAM-Loop-v0").unwrapped.config.world
    for family, world in (("arena", v0), ("loop", loop)):
        section = world_section(family, "medium")
        assert section["layout"] == world.layout and section["n_landmarks"] == world.n_landmarks
        a = make_layout(world.layout, np.random.default_rng(5), world.n_landmarks, **world.layout_kwargs)
        b = make_layout(family, np.random.default_rng(5), section["n_landmarks"], **section["layout_kwargs"])
        assert np.array_equal(a.walls, b.walls) and np.array_equal(a.landmarks, b.landmarks)


@pytest.mark.parametrize("family", FAMILIES)
def test_an_episode_runs_on_the_hard_tier(family: str) -> None:
    env = gym.make("EKFSLAM-v0", world=world_section(family, "hard"), max_episode_steps=30)
    obs, _ = env.reset(seed=3)
    assert env.observation_space.contains(obs)
    env.action_space.seed(0)
    for _ in range(30):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert np.isfinite(reward)
        if terminated or truncated:
            break
    assert truncated or terminated
    env.close()


@pytest.mark.parametrize(
    ("name", "kwargs", "message"),
    [
        ("pillars", {"pillar_size": 2.5}, "pillar_size must be in"),
        ("pillars", {"gap": 0.4}, "gap .* too narrow"),
        ("pillars", {"n_pillars": 400}, "could place only"),
        ("figure_eight", {"corridor": 1.5}, "too narrow"),
        ("figure_eight", {"width": 12.0}, "leaves no blocks"),
        ("office", {"rooms_per_side": 20}, "no room for 20 rooms"),
        ("office", {"door_width": 0.5}, "door_width .* too narrow"),
        ("office", {"jitter": 0.5}, "jitter must be in"),
        ("warehouse", {"n_rows": 14}, "aisle between rows"),
        ("warehouse", {"shelf_depth": 3.0}, "shelf_depth must be in"),
        ("warehouse", {"n_cross": 8}, "shelves under 1 m"),
        ("warehouse", {"end_aisle": 1.0}, "end_aisle"),
        ("maze", {"cell": 1.5}, "cell must be >= 2"),
        ("maze", {"cell": 12.0}, "at least 2 x 2 cells"),
        ("maze", {"braid": 1.0}, "braid must be in"),
        ("maze", {"width": float("nan")}, "width and height must be finite"),
    ],
)
def test_bad_family_keywords_raise_before_anything_is_drawn(name: str, kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make_layout(name, np.random.default_rng(0), 10, **kwargs)


# ---------------------------------------------------------------------------------------- the free grid
def test_free_cells_equals_brute_force_distances() -> None:
    rng = np.random.default_rng(0)
    for trial in range(20):
        walls = rng.uniform(-1.0, 11.0, (int(rng.integers(0, 12)), 4))
        if trial % 2:  # axis-aligned ones too, whose bounding boxes are thin
            walls[:, 3] = walls[:, 1]
        x0, y0, cell = rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(0.05, 0.4)
        rows, cols, clearance = int(rng.integers(1, 60)), int(rng.integers(1, 60)), rng.uniform(0.0, 1.5)
        xs, ys = x0 + (np.arange(cols) + 0.5) * cell, y0 + (np.arange(rows) + 0.5) * cell
        centres = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
        expected = (min_wall_distance(centres, walls) >= clearance).reshape(rows, cols)
        assert np.array_equal(free_cells(walls, x0, y0, cell, rows, cols, clearance), expected)


# ---------------------------------------------------------------------------------------- the keywords
@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_every_keyword_of_every_layout_is_documented(name: str) -> None:
    keywords = layout_keywords(name)
    parameters = inspect.signature(LAYOUTS[name]).parameters
    assert list(keywords) == [p for p, v in parameters.items() if v.kind is inspect.Parameter.KEYWORD_ONLY]
    assert all(meaning for _, meaning in keywords.values())


def test_configuration_page_lists_every_layouts_keywords() -> None:
    page = (ROOT / "docs" / "configuration.md").read_text()
    for name in LAYOUTS:
        assert f"### `{name}`" in page
        for key, (_, meaning) in layout_keywords(name).items():
            assert f"| `{key}` |" in page and meaning.replace("|", r"\|") in page, (name, key)


def test_an_unknown_layout_keyword_fails_when_the_config_is_built() -> None:
    with pytest.raises(
        ValueError, match=r"world\.layout_kwargs\.widht .*valid keys: width, height, n_rooms_x"
    ):
        EnvConfig.from_overrides(world={"layout": "rooms", "layout_kwargs": {"widht": 30.0}})
    with pytest.raises(ValueError, match=r"world\.layout_kwargs\.cell"):
        gym.make("EKFSLAM-v0", world={"layout": "arena", "layout_kwargs": {"cell": 2.0}})


def test_a_layout_keyword_of_the_wrong_kind_fails_when_the_config_is_built() -> None:
    with pytest.raises(ValueError, match=r"world\.layout_kwargs\.n_rooms_x must be an integer"):
        EnvConfig.from_overrides(world={"layout": "rooms", "layout_kwargs": {"n_rooms_x": 2.5}})
    with pytest.raises(ValueError, match=r"world\.layout_kwargs\.width must be a number"):
        EnvConfig.from_overrides(world={"layout": "maze", "layout_kwargs": {"width": "wide"}})
    with pytest.raises(ValueError, match=r"world\.layout_kwargs\.yaml must be a string"):
        EnvConfig.from_overrides(world={"layout": "map_server", "layout_kwargs": {"yaml": Path("map.yaml")}})
    # an int where a number is due, numpy scalars and arrays: held as plain Python values (YAML-safe)
    config = EnvConfig.from_overrides(
        world={"layout": "maze", "layout_kwargs": {"width": 24, "cell": np.float64(3)}}
    )
    assert config.world.layout_kwargs == {"width": 24.0, "cell": 3.0}
    assert (
        type(config.world.layout_kwargs["width"]) is float
        and type(config.world.layout_kwargs["cell"]) is float
    )
    surveyed = {
        "layout": "surveyed",
        "n_landmarks": 2,
        "layout_kwargs": {"landmarks": np.array([[1.0, 1.0], [3.0, 2.0]])},
    }
    assert EnvConfig.from_overrides(world=surveyed).world.layout_kwargs["landmarks"] == [
        [1.0, 1.0],
        [3.0, 2.0],
    ]


def test_a_value_the_generator_refuses_fails_when_the_config_is_built() -> None:
    with pytest.raises(ValueError, match=r"world \(layout 'rooms'\): jitter must be in \[0, 0.5\)"):
        EnvConfig.from_overrides(world={"layout": "rooms", "layout_kwargs": {"jitter": 0.7}})
    with pytest.raises(ValueError, match="could place only"):
        EnvConfig.from_overrides(world={"layout": "maze", "n_landmarks": 400})
    with pytest.raises(ValueError, match=r"map YAML .*nowhere\.yaml does not exist"):
        gym.make("EKFSLAM-v0", world={"layout": "map_server", "layout_kwargs": {"yaml": "nowhere.yaml"}})
    with pytest.raises(ValueError, match=r"world\.layout_kwargs\.yaml is required"):
        EnvConfig.from_overrides(world={"layout": "map_server"})


# ---------------------------------------------------------------------------------------------- the split
def test_the_split_is_fixed_disjoint_and_covers_every_family() -> None:
    assert set(TRAINING_FAMILIES) | set(HELDOUT_FAMILIES) == set(FAMILIES)
    assert not set(TRAINING_FAMILIES) & set(HELDOUT_FAMILIES)
    assert len(HELDOUT_FAMILIES) >= 2 and "maze" in HELDOUT_FAMILIES
    for family in TRAINING_FAMILIES:
        seeds = family_seeds(family)
        assert not set(seeds.training) & set(seeds.heldout) and not set(seeds.evaluation) & set(seeds.heldout)
        assert check_training_family(family, "training envs") == family
    for family in HELDOUT_FAMILIES:
        seeds = family_seeds(family)
        assert len(seeds.training) == 0 and seeds.evaluation == () and len(seeds.heldout) > 0
        with pytest.raises(ValueError, match=f"held-out layout family '{family}'"):
            check_training_family(family, "training envs")
    with pytest.raises(ValueError, match="unknown layout family"):
        family_seeds("castle")


def test_a_training_run_refuses_a_held_out_family() -> None:
    from ekfslam_gym.training.settings import SettingsError, validate_entry

    entry = {"n_timesteps": 10, "env_kwargs": {"world": world_section("maze", "easy")}}
    with pytest.raises(SettingsError, match="held-out layout family 'maze'"):
        validate_entry(entry, env_id="EKFSLAM-v0")
    validate_entry({**entry, "env_kwargs": {"world": world_section("office", "easy")}}, env_id="EKFSLAM-v0")


def test_layouts_page_shows_every_family_at_every_tier() -> None:
    """docs/layouts.md's table is what docs/layouts.py writes, and every thumbnail it shows exists."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("docs_layouts", ROOT / "docs" / "layouts.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.main(["--check"]) == 0
    for family, tier in CASES:
        assert module.thumbnail_path(family, tier).is_file(), (family, tier)
