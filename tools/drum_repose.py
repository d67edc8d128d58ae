"""The dynamic angle of repose of a rotating drum against its Froude number.

Runs scenarios/rotating_drum.toml (or ``--scene``) at several angular velocities and prints,
for each, the Froude number Fr = Ω² R / g, the bed's angle θ, the events and the wall time.

The angle: a bed with a flat free surface fills a circular segment of the drum's cross-section.
That segment is symmetric about the radius perpendicular to the surface, so the direction from
the axis to the bed's centre of mass is that radius. θ is that direction's angle from straight
down, positive towards the side the wall carries the beads up. It is averaged over the frames
after ``--settle`` seconds, with the error of the mean from 8 blocks.

Usage:
    .venv/bin/python tools/drum_repose.py [--omega 0.5,1,2,4] [--duration 6] [--settle 2]
        [--scene scenarios/rotating_drum.toml] [--jobs 2]

A run that stops at the collapse guard is reported as such, with the time it reached.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

#: Blocks of the error of the mean angle (frames within a block are correlated; blocks of
#: ≥ 0.5 s of a 4 s window are about independent at these speeds).
BLOCKS = 8


class _Angles:
    """Observer: the bed's angle in every frame."""

    def __init__(self, cyl):
        self.cyl = cyl
        self.t = []
        self.theta = []

    def on_frames(self, block):
        a = self.cyl.axis
        d = block.position - self.cyl.center  # (F, N, 3)
        q = d - np.einsum("fnk,k->fn", d, a)[..., None] * a
        cm = q.mean(axis=1)  # the bed's centre of mass across the axis (equal beads)
        down = np.array([0.0, 0.0, -1.0])
        down = down - (down @ a) * a
        down /= np.linalg.norm(down)
        side = np.cross(a, down)  # where Ω a carries the lowest point: Ω a × down
        sign = math.copysign(1.0, self.cyl.angular_velocity) if self.cyl.angular_velocity else 1
        self.t.extend(block.time)
        self.theta.extend(np.arctan2(sign * (cm @ side), cm @ down))


def run_one(scene_path: str, omega: float, duration: float, settle: float) -> dict:
    """One run at Ω = omega [rad/s]: its angle statistics and costs."""
    from hsgran.engine import Simulation, SimulationError
    from hsgran.scene import load_scene

    scene = load_scene(scene_path, overrides={"scene.duration": duration,
                                              "walls[0].angular_velocity": omega})
    cyl = scene.cylinders[0]
    sim = Simulation(scene)
    obs = _Angles(cyl)
    start = time.perf_counter()
    reached, guard = duration, ""
    try:
        summary = sim.run(observers=[obs])
        events = sum(summary.events.values())
    except SimulationError as exc:
        reached, guard = sim.time, str(exc)
        events = int(sim.isc[0]) if hasattr(sim, "isc") else 0
    wall = time.perf_counter() - start
    t, theta = np.array(obs.t), np.array(obs.theta)
    keep = t >= settle
    mean = err = math.nan
    if np.count_nonzero(keep) >= BLOCKS:
        blocks = np.array_split(theta[keep], BLOCKS)
        means = np.array([b.mean() for b in blocks])
        mean, err = means.mean(), means.std(ddof=1) / math.sqrt(BLOCKS)
    g = float(np.linalg.norm(scene.gravity))
    return dict(omega=omega, froude=omega**2 * cyl.radius / g, theta=math.degrees(mean),
                err=math.degrees(err), events=events, wall=wall, reached=reached, guard=guard,
                n=scene.n)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(ROOT / "scenarios" / "rotating_drum.toml"))
    ap.add_argument("--omega", default="0.5,1,2,4", help="angular velocities [rad/s]")
    ap.add_argument("--duration", type=float, default=6.0, help="simulated time [s]")
    ap.add_argument("--settle", type=float, default=2.0, help="angles from this time on [s]")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    omegas = [float(w) for w in args.omega.split(",")]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = list(pool.map(run_one, [args.scene] * len(omegas), omegas,
                             [args.duration] * len(omegas), [args.settle] * len(omegas)))
    print(f"{'Omega [rad/s]':>13} {'Fr':>8} {'theta [deg]':>12} {'+-':>6} {'events':>10} "
          f"{'wall [s]':>9} {'events/s':>9}  note")
    for r in rows:
        note = f"collapse guard at t = {r['reached']:.4f} s" if r["guard"] else ""
        print(f"{r['omega']:13.3g} {r['froude']:8.4f} {r['theta']:12.2f} {r['err']:6.2f} "
              f"{r['events']:10d} {r['wall']:9.1f} {r['events'] / r['wall']:9.3g}  {note}")
    return 1 if any(r["guard"] for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
