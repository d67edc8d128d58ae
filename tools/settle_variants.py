"""Variants of a small pour: does each one settle, or does the collapse guard stop it?

Usage:
    .venv/bin/python tools/settle_variants.py [--until 0.8] [--part K/M] [--count 100,400]
        [--restitution 0.3,0.8] [--width 0.012,0.02] [--seeds 1,2]

Runs ``tools/scenes/small_pour.toml`` over the grid of restitution (both contacts), sphere
count, box width (x and y; the fill region follows) and effect set ({gravity}; {gravity,
rotation, friction}; the same with rolling resistance, rolling friction 0.01) and seeds, each
to ``--until``, and prints one line per case: how it ended (``ok``, or ``guard`` with the
collapse guard's message), the spheres at rest, the wedge stops (docs/enduring-contact.md) and
the wall time; then the number of cases that reached the guard. ``--part K/M`` runs every M-th
case from the K-th (0-based), so that M processes can share the grid. Figures only, no
pass/fail; the measured study is in docs/enduring-contact.md ("Settling scenes").
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np

from hsgran.engine import Simulation, SimulationError
from hsgran.onplane import MS_REST
from hsgran.scene import load_scene

BASE = Path(__file__).resolve().parent / "scenes" / "small_pour.toml"
#: The effect sets of the grid, by the name printed for them.
EFFECT_SETS = {
    "gravity": ["gravity"],
    "friction": ["gravity", "rotation", "friction"],
    "rolling": ["gravity", "rotation", "friction", "rolling_resistance"],
}
#: Rolling friction coefficient of both contacts in the "rolling" effect set [-].
ROLLING_FRICTION = 0.01
#: Height of the box and of the top of the fill region [m] (as in the base scene).
BOX_HEIGHT = 0.12


def overrides(e: float, count: int, effects: str, width: float, seed: int) -> dict:
    """Key-path overrides of the base scene for one case."""
    over = {"scene.seed": seed, "scene.effects": EFFECT_SETS[effects],
            "fill[0].count": count, "walls[0].upper": [width, width, BOX_HEIGHT],
            "fill[0].region.upper": [width, width, BOX_HEIGHT]}
    for k in range(2):
        over[f"contacts[{k}].restitution"] = e
        if effects == "rolling":
            over[f"contacts[{k}].rolling_friction"] = ROLLING_FRICTION
    return over


def run_case(over: dict, until: float) -> str:
    """One line: how the case ended, spheres at rest, wedge stops, wall time."""
    scene = load_scene(BASE, overrides=over)
    sim = Simulation(scene)
    t0 = time.perf_counter()
    try:
        summary = sim.run(until=until)
        end = f"ok, wedge stops {summary.events['wedge']}"
    except SimulationError as ex:
        end = f"guard: {ex}"
    rest = int(np.sum(sim.mstate == MS_REST))
    return f"{end}; at rest {rest}/{scene.n}; wall {time.perf_counter() - t0:.1f} s"


def _floats(text: str) -> list[float]:
    return [float(x) for x in text.split(",")]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--until", type=float, default=0.8, help="simulated time [s]")
    ap.add_argument("--part", default="0/1", help="K/M: every M-th case from the K-th")
    ap.add_argument("--restitution", default="0.3,0.8")
    ap.add_argument("--count", default="100,400")
    ap.add_argument("--width", default="0.012,0.02", help="box widths [m]")
    ap.add_argument("--effects", default=",".join(EFFECT_SETS))
    ap.add_argument("--seeds", default="1,2")
    args = ap.parse_args(argv)
    k, m = (int(x) for x in args.part.split("/"))
    grid = list(itertools.product(
        _floats(args.restitution), [int(x) for x in args.count.split(",")],
        args.effects.split(","), _floats(args.width), [int(x) for x in args.seeds.split(",")]))
    print(f"# {BASE.name} to t = {args.until} s: restitution, count, effects, width [m], seed")
    stopped = 0
    for case in grid[k::m]:
        line = run_case(overrides(*case), args.until)
        stopped += line.startswith("guard")
        print(" ".join(str(x) for x in case), line, flush=True)
    print(f"{stopped} of {len(grid[k::m])} cases reached the collapse guard")
    return 0


if __name__ == "__main__":
    sys.exit(main())
