"""The Brazil-nut effect: the height of a large sphere in a vibrated bed of small ones against
time, at several accelerations Γ of the plate.

Runs scenarios/vibrated_bed.toml (or ``--scene``) with the box's vibrating floor
(``walls[0].motion.lower_z``) at each Γ = A ω²/g (its amplitude changed, its frequency kept)
and prints, for each, the large sphere's height above the floor's rest position and the
height of the bed's surface (the 90th percentile of the small spheres' heights) at every
``--every`` seconds, averaged over the frames of one plate period around that time (the
bed breathes within a period), then the time at which the large sphere's centre first comes
within one small diameter of the surface (its rise time), the mean vertical speed of the small
spheres in the middle third of the box's width and in the outer thirds after ``--settle``
seconds, from their net rise over one plate period (convection: up in the middle, down at the
walls), the events and the wall time.

Usage:
    .venv/bin/python tools/brazil_nut.py [--gamma 1.5,2.5,3.5] [--duration 10] [--every 1]
        [--settle 1] [--scene scenarios/vibrated_bed.toml] [--jobs 2] [--wall-limit 3600]

A run that stops at the collapse guard or at the wall-time limit is reported as such, with
the time it reached.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections import deque
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

#: The bed's surface: this percentile of the small spheres' heights [%] (the few spheres
#: thrown highest above a vibrated bed are not its surface).
SURFACE_PERCENTILE = 90.0
#: The vibrating floor: the scene's wall key of the face whose amplitude each run sets.
FLOOR = "walls[0].lower_z"
#: ... and the scene-file path of its amplitude (an override, hsgran.overrides).
FLOOR_AMPLITUDE = "walls[0].motion.lower_z.amplitude"
#: The large sphere has risen when its centre is within this many small diameters of the
#: surface [-].
RISEN_DIAMETERS = 1.0


class _Heights:
    """Observer: the large sphere's height and the bed's surface in every frame, and the small
    spheres' net vertical motion over one plate period, in the middle third of the box's
    width and in the outer thirds (by where they were a period before), summed over the frames
    after ``settle`` [s]: convection, free of the bed's breathing within a period."""

    def __init__(self, big: int, small: np.ndarray, settle: float, lag: int):
        self.big = big
        self.small = small
        self.settle = settle
        self.lag = lag  # frames per plate period
        self.t, self.z_big, self.z_bed = [], [], []
        self.past = deque(maxlen=lag + 1)  # the small spheres' (x, z) of the last frames
        self.dz_sum = np.zeros(2)  # Σ Δz over a period [m]: middle, outer
        self.dz_n = np.zeros(2)

    def on_frames(self, block):
        z = block.position[:, :, 2]
        self.t.extend(block.time)
        self.z_big.extend(z[:, self.big])
        self.z_bed.extend(np.percentile(z[:, self.small], SURFACE_PERCENTILE, axis=1))
        for f in range(block.time.shape[0]):
            self.past.append(block.position[f, self.small][:, [0, 2]])
            if len(self.past) <= self.lag or block.time[f] < self.settle:
                continue
            x0, z0 = self.past[0][:, 0], self.past[0][:, 1]
            lo, hi = x0.min(), x0.max()
            middle = np.abs(x0 - 0.5 * (lo + hi)) <= (hi - lo) / 6
            dz = self.past[-1][:, 1] - z0
            self.dz_sum += (dz[middle].sum(), dz[~middle].sum())
            self.dz_n += (middle.sum(), (~middle).sum())


def run_one(scene_path: str, gamma: float, duration: float, settle: float,
            wall_limit: float) -> dict:
    """One run at plate acceleration Γ: the heights against time and the costs."""
    from hsgran.engine import Simulation, SimulationError
    from hsgran.scene import load_scene
    from hsgran.wallspec import M_KIND, M_OMEGA, MOT_OSCILLATION

    base = load_scene(scene_path)
    # the face whose amplitude is set below: its frequency is kept
    floor = next((p for p in base.planes if p.key == FLOOR and p.motion is not None
                  and p.motion[M_KIND] == MOT_OSCILLATION), None)
    if floor is None:
        raise SystemExit(f"{scene_path}: {FLOOR} does not oscillate")
    omega = float(floor.motion[M_OMEGA])
    amplitude = gamma * abs(base.gravity[2]) / omega**2
    scene = load_scene(scene_path, overrides={
        "scene.duration": duration, FLOOR_AMPLITUDE: amplitude})
    radii = np.asarray(scene.radius)
    big = int(np.argmax(radii))
    small = np.nonzero(radii < radii[big])[0]
    sim = Simulation(scene)
    lag = max(1, round(2 * math.pi / omega / scene.frame_interval))
    obs = _Heights(big, small, settle, lag)
    start = time.perf_counter()
    status = "completed"
    try:
        summary = sim.run(observers=[obs],
                          stop=lambda: time.perf_counter() - start > wall_limit)
        if summary.interrupted:
            status = f"wall-time limit at t = {sim.time:.3f} s"
    except SimulationError:
        status = f"collapse guard at t = {sim.time:.3f} s"
    wall = time.perf_counter() - start
    return {"gamma": gamma, "omega": omega, "t": np.array(obs.t), "z_big": np.array(obs.z_big),
            "z_bed": np.array(obs.z_bed), "d_small": 2 * float(radii[small].max()),
            "w": obs.dz_sum / np.maximum(obs.dz_n, 1) / (lag * scene.frame_interval),
            "status": status,
            "events": int(sim.counts.sum()), "wall": wall, "reached": float(sim.time)}


def _at(res: dict, t: float) -> tuple[float, float]:
    """Large sphere's height and the surface's [m], averaged over one plate period at t."""
    half = math.pi / res["omega"]
    near = np.abs(res["t"] - t) <= half
    if not near.any():
        return math.nan, math.nan
    return float(res["z_big"][near].mean()), float(res["z_bed"][near].mean())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--gamma", default="1.5,2.5,3.5")
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--every", type=float, default=1.0)
    ap.add_argument("--settle", type=float, default=1.0,
                    help="convection is averaged over the frames after this time [s]")
    ap.add_argument("--scene", default=str(ROOT / "scenarios" / "vibrated_bed.toml"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--wall-limit", type=float, default=3600.0,
                    help="a run stops after this much wall time [s] and reports how far it got")
    args = ap.parse_args(argv)
    try:
        gammas = [float(g) for g in args.gamma.split(",")]
    except ValueError:
        print(f"--gamma: not a list of numbers: {args.gamma!r}", file=sys.stderr)
        return 2
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(run_one, [args.scene] * len(gammas), gammas,
                                [args.duration] * len(gammas), [args.settle] * len(gammas),
                                [args.wall_limit] * len(gammas)))
    times = np.arange(0.0, args.duration + 1e-9, args.every)
    print("height of the large sphere / of the bed's surface [mm] against time [s]")
    print("t       " + "  ".join(f"  Γ = {r['gamma']:<10.3g}" for r in results))
    for t in times:
        cells = []
        for r in results:
            zb, zs = _at(r, t)
            cells.append(f"{zb * 1e3:6.1f} / {zs * 1e3:5.1f}")
        print(f"{t:6.2f}  " + "  ".join(f"{c:>16}" for c in cells))
    print()
    for r in results:
        risen = r["z_big"] >= r["z_bed"] - RISEN_DIAMETERS * r["d_small"]
        rise = f"{r['t'][np.argmax(risen)]:.2f} s" if risen.any() else "not within the run"
        print(f"Γ = {r['gamma']:.3g}: {r['status']}; rise time {rise}; mean vertical speed of "
              f"the beads in the middle third {r['w'][0] * 1e3:+.2f} mm/s, in the outer thirds "
              f"{r['w'][1] * 1e3:+.2f} mm/s; {r['events']:,} events, {r['wall']:.0f} s wall for "
              f"{r['reached']:.2f} s simulated")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
