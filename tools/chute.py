"""Flow down a chute over a rough base of fixed beads (docs/open-systems.md, "Chute flow").

The scene is scenarios/chute.toml's: 400 glass beads (d = 2 mm, e = 0.5, μ = 0.3) in a box
periodic along the flow (x, 30 mm) and across it (y, 10 mm), over a base of 40 fixed glass
beads on the floor, under gravity tilted by θ from the vertical towards +x. For each
inclination the tool prints the beads' mean velocity along the slope in windows of
simulated time, how many are at rest at the end, and what the run did (events, wall time, or
the collapse guard); and, for one inclination (``--profile``), the velocity profile: the mean
v_x of the beads in slabs of one bead diameter, averaged over the frames of the last half.

A flow is called **stopped** when the mean velocity of its last window is below 1 mm/s,
**steady** when the mean velocity's rate of change over the last half of the windows (a
least-squares slope, printed as a fraction of g sin θ) is within ``--steady`` (1 %) of
g sin θ, and **accelerating** or **slowing** otherwise; the range of inclinations with a
steady flow is read off the table (the thresholds are this tool's, not a law's).

Usage:
    .venv/bin/python tools/chute.py [--angles 14,18,22,26,30] [--seconds 1.5] [--windows 6]
        [--profile 24] [--jobs 2] [--timeout 600]
"""

from __future__ import annotations

import argparse
import itertools
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

SCENE = Path(__file__).resolve().parents[1] / "scenarios" / "chute.toml"
D = 0.002  #: bead diameter [m]
STOPPED = 1e-3  #: a mean speed below this is a stopped flow [m/s]
#: A flow is steady where its mean velocity changes over the last half of the run by less than
#: this fraction of g sin θ [-] (a bead sliding freely gains g sin θ): at 1 % a window of
#: 0.25 s may gain ~1 % of g sin θ × 0.25 s, 9–12 mm/s at 22–30°, about the window-to-window
#: scatter of the mean of 400 beads measured there (±0.006–0.018 m/s).
STEADY = 0.01


def chute_scene(angle: float, duration: float):
    """scenarios/chute.toml's scene with gravity (9.81 m/s²) tilted by ``angle`` degrees from the
    vertical towards +x, run for ``duration`` seconds."""
    from hsgran.scene import load_scene

    th = math.radians(angle)
    return load_scene(SCENE, overrides={
        "scene.gravity": [9.81 * math.sin(th), 0.0, -9.81 * math.cos(th)],
        "scene.duration": duration})


def run_one(args) -> dict:
    """Run the chute at ``angle`` degrees for ``seconds`` of simulated time, or until
    ``timeout`` seconds of wall time (None: no limit); return its frames' figures and where
    it stopped early (the collapse guard, or the timeout)."""
    from hsgran.engine import Simulation, SimulationError

    angle, seconds, timeout = args
    sim = Simulation(chute_scene(angle, seconds))
    frames = {"t": [], "vx": [], "z": [], "rest": []}

    class Keep:
        def on_frames(self, b):
            for f in range(len(b.time)):
                frames["t"].append(b.time[f])
                frames["vx"].append(b.velocity[f, :, 0].copy())
                frames["z"].append(b.position[f, :, 2].copy())
                frames["rest"].append(int(np.sum(b.motion_state[f] == 3)))

    wall = time.perf_counter()
    guard = None
    timed_out = None
    events = {}

    def out_of_time() -> bool:
        return timeout is not None and time.perf_counter() - wall > timeout

    try:
        summary = sim.run(observers=[Keep()], stop=out_of_time)
        events = summary.events
        if summary.interrupted:
            timed_out = sim.time
    except SimulationError as err:  # the collapse guard: reported, not hidden
        guard = (sim.time, str(err))
    return {"angle": angle, "wall": time.perf_counter() - wall, "guard": guard,
            "timed_out": timed_out, "events": events,
            **{k: np.array(v) for k, v in frames.items()}}


def late_acceleration(means: list[float], window: float) -> float:
    """The mean velocity's rate of change over the last half of the windows [m/s²]: the
    least-squares slope of the window means (of length ``window`` s) against their times; NaN
    where fewer than two windows hold frames."""
    late = np.asarray(means[len(means) // 2:], dtype=float)
    t = window * np.arange(len(late))
    ok = np.isfinite(late)
    if ok.sum() < 2:
        return math.nan
    return float(np.polyfit(t[ok], late[ok], 1)[0])


def classify(means: list[float], guard: float | None, timed_out: float | None,
             steady: float, window: float, g_slope: float) -> str:
    """What a run's flow did, from its mean velocities per window (each ``window`` s long)
    [m/s]: where it stopped early (the collapse guard at ``guard`` s, or the wall-time limit
    at ``timed_out`` s of simulated time: its last windows are then empty and say nothing),
    else stopped (the last window below STOPPED), steady (the mean velocity's rate of change
    over the last half of the windows, :func:`late_acceleration`, within ``steady`` times
    g sin θ = ``g_slope`` [m/s²], the acceleration of a bead sliding freely down the slope),
    accelerating or slowing. (Until 2026-11-28 a flow was called steady where the last two
    windows' means were within 10 % of each other: a flow gaining 0.16 m/s a window at
    1.6 m/s passed that test.)"""
    if guard is not None:
        return f"guard at {guard:.4f} s"
    if timed_out is not None:
        return f"timed out at {timed_out:.4f} s"
    if not means[-1] > STOPPED:
        return "stopped"
    rate = late_acceleration(means, window)
    if abs(rate) <= steady * g_slope:
        return "steady"
    return "accelerating" if rate > 0.0 else "slowing"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--angles", default="14,18,22,26,30", help="inclinations [deg]")
    ap.add_argument("--seconds", type=float, default=1.5, help="simulated time per run [s]")
    ap.add_argument("--windows", type=int, default=6)
    ap.add_argument("--steady", type=float, default=STEADY,
                    help="largest rate of change of the mean velocity over the last half of "
                         "the windows of a steady flow, as a fraction of g sin(theta) "
                         f"(default {STEADY})")
    ap.add_argument("--profile", type=float, default=None,
                    help="print the velocity profile of this inclination (one of --angles)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=None,
                    help="wall time [s] after which a run stops and is reported as timed out "
                         "(default: none)")
    a = ap.parse_args()
    angles = [float(s) for s in a.angles.split(",")]
    with ProcessPoolExecutor(max_workers=a.jobs) as pool:
        results = list(pool.map(run_one, [(th, a.seconds, a.timeout) for th in angles]))
    edges = np.linspace(0.0, a.seconds, a.windows + 1)
    window = a.seconds / a.windows
    print("theta  mean v_x of the beads per window [m/s]" + " " * 13
          + "at rest  late dv/dt / g sin(theta)  flow          wall [s]  events")
    for r in results:
        means = []
        for lo, hi in itertools.pairwise(edges):
            sel = (r["t"] > lo) & (r["t"] <= hi + 1e-12)
            means.append(r["vx"][sel].mean() if sel.any() else math.nan)
        g_slope = 9.81 * math.sin(math.radians(r["angle"]))
        flow = classify(means, r["guard"][0] if r["guard"] else None, r["timed_out"],
                        a.steady, window, g_slope)
        late = late_acceleration(means, window) / g_slope
        n_events = sum(v for k, v in r["events"].items() if k in ("pair", "wall"))
        rest = r["rest"][-1] if len(r["rest"]) else 0
        print(f"{r['angle']:5.1f}  " + " ".join(f"{m:7.4f}" for m in means)
              + f"  {rest:7d}  {late:+27.4f}  {flow:<13} {r['wall']:8.1f}  "
              f"{n_events:,} collisions")
        if a.profile is not None and r["angle"] == a.profile:
            half = r["t"] >= 0.5 * a.seconds
            if not half.any():
                print(f"  profile at {a.profile:g} deg: no frames after {0.5 * a.seconds:g} s")
                continue
            z = r["z"][half].ravel()
            vx = r["vx"][half].ravel()
            slab = np.floor(z / D).astype(int)
            print(f"  profile at {a.profile:g} deg (frames from {0.5 * a.seconds:g} s):")
            for k in range(slab.max() + 1):
                s = slab == k
                if s.sum() > 0:
                    print(f"    z {k * D * 1e3:4.0f}-{(k + 1) * D * 1e3:3.0f} mm: "
                          f"v_x {vx[s].mean():7.4f} m/s  ({s.sum() / half.sum():5.1f} beads)")


if __name__ == "__main__":
    main()
