"""Layout families and their difficulty tiers: the ``world`` section of an env config for each family at each
tier, as data in one table.

A family is a layout generator (its name is the ``world.layout``); a tier fixes its size, its landmark count
and how much its walls hide. From ``easy`` to ``hard`` the worlds grow (about 15-20 m across, then 20-30 m,
then 30-40 m), the landmarks thin out (about 0.08 a square metre of the world, then 0.06-0.075, then
0.05-0.06) and the occluding structure grows (more pillars, rooms, shelf rows or maze cells). ``medium`` of ``arena`` and
``loop`` are EKFSLAM-v0's and EKFSLAM-Loop-v0's worlds. Which families are for training and which are held
out is ``ekfslam_gym.seeds``' business (``TRAINING_FAMILIES``, ``HELDOUT_FAMILIES``).
"""

from __future__ import annotations

from typing import Any

TIERS: tuple[str, ...] = ("easy", "medium", "hard")

# family -> tier -> (n_landmarks, layout_kwargs); every kwarg not given keeps the generator's default
_TABLE: dict[str, dict[str, tuple[int, dict[str, Any]]]] = {
    "arena": {
        "easy": (20, {"width": 15.0, "height": 15.0}),
        "medium": (30, {"width": 20.0, "height": 20.0}),
        "hard": (45, {"width": 30.0, "height": 30.0}),
    },
    "pillars": {
        "easy": (20, {"width": 16.0, "height": 16.0, "n_pillars": 6}),
        "medium": (30, {"width": 22.0, "height": 22.0, "n_pillars": 14}),
        "hard": (45, {"width": 30.0, "height": 30.0, "n_pillars": 30}),
    },
    "rooms": {
        "easy": (20, {"width": 16.0, "height": 16.0, "n_rooms_x": 2, "n_rooms_y": 2}),
        "medium": (30, {"width": 20.0, "height": 20.0, "n_rooms_x": 3, "n_rooms_y": 3}),
        "hard": (50, {"width": 32.0, "height": 32.0, "n_rooms_x": 4, "n_rooms_y": 4}),
    },
    "loop": {
        "easy": (20, {"width": 16.0, "height": 16.0}),
        "medium": (30, {"width": 20.0, "height": 20.0}),
        "hard": (50, {"width": 32.0, "height": 32.0}),
    },
    "figure_eight": {
        "easy": (20, {"width": 22.0, "height": 12.0}),
        "medium": (30, {"width": 30.0, "height": 16.0}),
        "hard": (45, {"width": 40.0, "height": 20.0}),
    },
    "office": {
        "easy": (20, {"width": 20.0, "height": 14.0, "rooms_per_side": 3}),
        "medium": (30, {"width": 28.0, "height": 18.0, "rooms_per_side": 4}),
        "hard": (50, {"width": 36.0, "height": 24.0, "rooms_per_side": 6}),
    },
    "warehouse": {
        "easy": (20, {"width": 18.0, "height": 14.0, "n_rows": 3, "n_cross": 0}),
        "medium": (30, {"width": 24.0, "height": 20.0, "n_rows": 5, "n_cross": 1}),
        "hard": (50, {"width": 34.0, "height": 28.0, "n_rows": 7, "n_cross": 2}),
    },
    "maze": {
        "easy": (20, {"width": 15.0, "height": 15.0, "cell": 3.0}),
        "medium": (30, {"width": 20.0, "height": 20.0, "cell": 2.5}),
        "hard": (50, {"width": 30.0, "height": 30.0, "cell": 2.5}),
    },
}

FAMILIES: tuple[str, ...] = tuple(_TABLE)
"""Every layout family's name, each a layout name usable as ``world.layout``."""


def world_section(family: str, tier: str) -> dict[str, Any]:
    """The env config's ``world`` section for ``family`` at ``tier``: ``{"layout", "n_landmarks",
    "layout_kwargs"}``, a fresh dict (change it freely). ValueError naming the valid values otherwise."""
    if family not in _TABLE:
        raise ValueError(f"unknown layout family {family!r}; choose one of {', '.join(FAMILIES)}")
    if tier not in TIERS:
        raise ValueError(f"unknown tier {tier!r}; choose one of {', '.join(TIERS)}")
    n_landmarks, kwargs = _TABLE[family][tier]
    return {"layout": family, "n_landmarks": n_landmarks, "layout_kwargs": dict(kwargs)}
