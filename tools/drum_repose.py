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
    .venv/bin/python tools/drum_repose.py --corpus 12 [--corpus-seed 0] [--duration 2]
        [--timeout 600] [--jobs 2]

A run that stops at the collapse guard is reported as such, with the time it reached.

``--corpus N`` runs N drums drawn from a seeded parameter space instead (scenes nobody tuned
for; drum ``S-I`` draws from ``numpy.random.default_rng([S, I])``): radius 20–80 mm, length
2–6 largest diameters, beads of radius 1–3 mm, equal or two sizes (ratio up to 2), glass or
steel, filling 20–50 % of the drum, restitution 0.3–0.9, sliding friction 0.1–0.6, rolling
friction 0–0.05 (or none), Froude number 1e-4–0.3 (log-uniform), either sense of rotation. It
prints each drum's outcome (completed, or the guard's time, or the timeout) and the rate of
completed runs.
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
        events = int(sim.counts.sum())  # the events of every kind up to the guard
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


def corpus_scene(seed: int, index: int, duration: float) -> str:
    """The text of drum ``seed-index`` of the corpus (see the module docstring)."""
    rng = np.random.default_rng([seed, index])
    big = rng.uniform(0.02, 0.08)
    r = rng.uniform(0.001, 0.003)
    ratio = 1.0 if rng.random() < 0.5 else rng.uniform(1.2, 2.0)
    r_max = r * ratio
    length = rng.uniform(2.0, 6.0) * 2.0 * r_max
    fill = rng.uniform(0.2, 0.5)
    packing = 0.6 * fill * math.pi * (big - r_max) ** 2 * (length - 2.0 * r_max)
    vol = 4.0 / 3.0 * math.pi * (r**3 + r_max**3) / (2.0 if ratio > 1.0 else 1.0)
    count = max(20, int(packing / vol))
    froude = math.exp(rng.uniform(math.log(1e-4), math.log(0.3)))
    omega = math.sqrt(froude * 9.81 / big) * (1.0 if rng.random() < 0.5 else -1.0)
    bead = str(rng.choice(["glass", "steel"]))
    e = rng.uniform(0.3, 0.9)
    mu = rng.uniform(0.1, 0.6)
    mu_r = rng.uniform(0.0, 0.05) if rng.random() < 0.7 else None
    effects = '"gravity", "rotation", "friction"' + (', "rolling_resistance"' if mu_r else "")
    rolling = f"rolling_friction = {mu_r!r}\n" if mu_r else ""
    half = 0.5 * length
    fills = []
    counts = [count] if ratio == 1.0 else [count // 2, count - count // 2]
    radii = [r] if ratio == 1.0 else [r, r_max]
    for n, radius in zip(counts, radii, strict=True):
        fills.append(f"""[[fill]]
count = {n}
material = "{bead}"
radius = {radius!r}
region = {{ lower = [{-big!r}, {-half!r}, {-big!r}], upper = [{big!r}, {half!r}, {big!r}] }}
""")
    pairs = [(bead, bead), (bead, "steel")] if bead != "steel" else [("steel", "steel")]
    contacts = "".join(f"""[[contacts]]
between = ["{a}", "{b}"]
restitution = {e!r}
sliding_friction = {mu!r}
{rolling}""" for a, b in pairs)
    return f"""[scene]
name = "drum {seed}-{index}"
duration = {duration!r}
effects = [{effects}]
seed = {index}
[output]
frame_interval = 0.05
{contacts}[[walls]]
kind = "cylinder"
center = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
radius = {big!r}
length = {length!r}
angular_velocity = {omega!r}
material = "steel"
{"".join(fills)}"""


def run_corpus_one(seed: int, index: int, duration: float, timeout: float) -> dict:
    """Drum ``seed-index`` in a process of its own, killed after ``timeout`` s of wall time."""
    import subprocess

    text = corpus_scene(seed, index, duration)
    code = ("import sys, time\n"
            "from hsgran.scene import parse_scene\n"
            "from hsgran.engine import Simulation, SimulationError\n"
            "scene = parse_scene(sys.stdin.read())\n"
            "sim = Simulation(scene)\n"
            "t0 = time.perf_counter()\n"
            "try:\n"
            "    s = sim.run()\n"
            "    print('completed', sim.time, sum(s.events.values()), time.perf_counter() - t0,"
            " scene.n)\n"
            "except SimulationError as exc:\n"
            "    print('guard', sim.time, 0, time.perf_counter() - t0, scene.n)\n")
    try:
        out = subprocess.run([sys.executable, "-c", code], input=text, capture_output=True,
                             text=True, timeout=timeout, cwd=ROOT)
        words = out.stdout.split()
        if len(words) < 5:
            last = (out.stderr.strip().splitlines() or ["?"])[-1]
            return dict(id=f"{seed}-{index}", outcome="error", t=math.nan, events=0,
                        wall=math.nan, n=0, note=last[:80])
        return dict(id=f"{seed}-{index}", outcome=words[0], t=float(words[1]),
                    events=int(words[2]), wall=float(words[3]), n=int(words[4]), note="")
    except subprocess.TimeoutExpired:
        return dict(id=f"{seed}-{index}", outcome="timeout", t=math.nan, events=0,
                    wall=timeout, n=0, note="")


def corpus_main(args) -> int:
    """The ``--corpus`` table and the rate of completed runs."""
    idx = list(range(args.corpus))
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = list(pool.map(run_corpus_one, [args.corpus_seed] * len(idx), idx,
                             [args.duration] * len(idx), [args.timeout] * len(idx)))
    print(f"{'drum':>6} {'N':>5} {'outcome':>9} {'t [s]':>8} {'wall [s]':>9}  note")
    for r in rows:
        print(f"{r['id']:>6} {r['n']:5d} {r['outcome']:>9} {r['t']:8.4f} {r['wall']:9.1f}  "
              f"{r['note']}")
    done = sum(r["outcome"] == "completed" for r in rows)
    print(f"completed {done} of {len(rows)} ({100.0 * done / len(rows):.0f} %) to "
          f"{args.duration} s")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(ROOT / "scenarios" / "rotating_drum.toml"))
    ap.add_argument("--omega", default="0.5,1,2,4", help="angular velocities [rad/s]")
    ap.add_argument("--duration", type=float, default=6.0, help="simulated time [s]")
    ap.add_argument("--settle", type=float, default=2.0, help="angles from this time on [s]")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--corpus", type=int, default=0, help="run this many random drums")
    ap.add_argument("--corpus-seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=600.0, help="per drum [s] (corpus)")
    args = ap.parse_args(argv)
    if args.corpus:
        return corpus_main(args)
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
