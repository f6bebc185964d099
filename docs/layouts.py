"""Draw a thumbnail of every layout family at every tier, and the table of them on docs/layouts.md.

    python docs/layouts.py          # rewrite docs/images/layouts/<family>_<tier>.png and the page's table
    python docs/layouts.py --check  # exit 1 if the page's table is stale (the PNGs are not compared)

Each thumbnail is the world ``reset(seed=0)`` builds for ``world_section(family, tier)``, drawn at one scale
for all (8 pixels a metre), so the tiers' sizes compare at a glance: walls in black, landmarks as orange dots,
the start as a blue arrow. The table sits between the page's markers; the rest of the page is written by hand.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

DOCS = Path(__file__).resolve().parent
IMAGES = DOCS / "images" / "layouts"
PAGE = DOCS / "layouts.md"
START, END = "<!-- thumbnails:start -->", "<!-- thumbnails:end -->"
PIXELS_PER_METRE = 8
SEED = 0


def thumbnail_path(family: str, tier: str) -> Path:
    return IMAGES / f"{family}_{tier}.png"


def draw(family: str, tier: str, path: Path) -> None:
    """One family at one tier, seed 0, to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from ekfslam_gym.sim import make_layout, world_section

    world = world_section(family, tier)
    layout = make_layout(
        world["layout"], np.random.default_rng(SEED), world["n_landmarks"], **world["layout_kwargs"]
    )
    xmin, ymin, xmax, ymax = layout.bounds
    dpi = 100
    figure = plt.figure(
        figsize=((xmax - xmin) * PIXELS_PER_METRE / dpi, (ymax - ymin) * PIXELS_PER_METRE / dpi)
    )
    axes = figure.add_axes((0, 0, 1, 1))
    axes.set_xlim(xmin - 0.3, xmax + 0.3)
    axes.set_ylim(ymin - 0.3, ymax + 0.3)
    axes.set_aspect("equal")
    axes.axis("off")
    segments = layout.walls.reshape(-1, 2, 2)
    axes.add_collection(LineCollection(segments, colors="black", linewidths=1.2, capstyle="round"))
    axes.scatter(*layout.landmarks.T, s=6, color="tab:orange", zorder=3)
    x, y, theta = layout.start
    axes.arrow(x, y, 1.2 * np.cos(theta), 1.2 * np.sin(theta), width=0.25, head_width=0.9, head_length=0.7,
               color="tab:blue", length_includes_head=True, zorder=4)  # fmt: skip
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=dpi, metadata={"Software": None})
    plt.close(figure)


def table() -> str:
    """The page's table: a row per family, a column per tier, each cell a thumbnail and its size."""
    from ekfslam_gym.seeds import HELDOUT_FAMILIES
    from ekfslam_gym.sim import FAMILIES, LAYOUTS, TIERS, world_section

    lines = ["| family | " + " | ".join(TIERS) + " |", "|---|" + "---|" * len(TIERS)]
    for family in FAMILIES:
        summary = " ".join(LAYOUTS[family].__doc__.strip().split("\n\n")[0].split())
        name = f"`{family}`" + (" (held out)" if family in HELDOUT_FAMILIES else "") + f"<br>{summary}"
        cells = []
        for tier in TIERS:
            world = world_section(family, tier)
            kwargs = world["layout_kwargs"]
            size = f"{kwargs['width']:g} × {kwargs['height']:g} m, {world['n_landmarks']} landmarks"
            image = thumbnail_path(family, tier).relative_to(DOCS)
            cells.append(f"![{family}, {tier}]({image})<br>{size}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def render_page(text: str) -> str:
    head, _, rest = text.partition(START)
    _, _, tail = rest.partition(END)
    return head + START + "\n" + table() + "\n" + END + tail


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--check", action="store_true", help="fail if the page's table is out of date")
    args = parser.parse_args(argv)
    text = PAGE.read_text()
    if START not in text or END not in text:
        print(f"{PAGE} lacks the markers {START} and {END}", file=sys.stderr)
        return 1
    page = render_page(text)
    if args.check:
        if page != text:
            print(f"out of date: {PAGE.name}: run python docs/layouts.py", file=sys.stderr)
            return 1
        return 0
    from ekfslam_gym.sim import FAMILIES, TIERS

    for family in FAMILIES:
        for tier in TIERS:
            draw(family, tier, thumbnail_path(family, tier))
    PAGE.write_text(page)
    print(
        f"wrote {len(FAMILIES) * len(TIERS)} thumbnails under {IMAGES.relative_to(DOCS.parent)} and {PAGE.name}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
