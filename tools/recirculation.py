"""Flat events and memory while spheres leave and re-enter (docs/open-systems.md).

A steady rain: N steel spheres fall under gravity in a tall box, leave through an outlet below
(a "below" plane above the floor) and a recirculating inflow puts them back at the top. After
the first fall the number in the system, the events per simulated second and the process's
memory should stay level. Prints one row per window of simulated time: spheres present, events
of each main kind in the window per simulated second, exits, and the resident memory.

Usage:
    .venv/bin/python tools/recirculation.py [--spheres 400] [--seconds 3] [--window 0.25]
"""

from __future__ import annotations

import argparse
import resource
import time

import numpy as np

from hsgran.engine import Simulation
from hsgran.scene import parse_scene

SCENE = """
[scene]
name = "steady rain through an outlet"
duration = {seconds}
effects = ["gravity"]
seed = 7
[output]
frame_interval = {window}
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.05, 0.05, 0.3]
material = "steel"
[[fill]]
count = {spheres}
material = "steel"
radius = 0.001
region = {{ lower = [0.0, 0.0, 0.1], upper = [0.05, 0.05, 0.3] }}
speed = 0.1
[[outlets]]
kind = "below"
point = [0.0, 0.0, 0.02]
normal = [0.0, 0.0, 1.0]
[[inflow]]
recirculate = true
region = {{ lower = [0.0, 0.0, 0.27], upper = [0.05, 0.05, 0.3] }}
rate = 5000.0
interval = 0.005
"""


def rss_mb() -> float:
    """Resident memory of this process now [MB] (Linux /proc)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spheres", type=int, default=400)
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--window", type=float, default=0.25)
    args = ap.parse_args(argv)
    scene = parse_scene(SCENE.format(spheres=args.spheres, seconds=args.seconds,
                                     window=args.window))
    sim = Simulation(scene)
    print(f"{args.spheres} spheres, windows of {args.window} s; events per simulated second")
    print(f"{'t [s]':>6} {'present':>7} {'pair/s':>9} {'wall/s':>9} {'cell/s':>9} "
          f"{'exits/s':>8} {'wall time':>9} {'RSS [MB]':>8}")
    t = 0.0
    while t < args.seconds - 1e-12:
        t = min(args.seconds, t + args.window)
        w0 = time.perf_counter()
        s = sim.run(until=t)
        e = s.events
        rate = 1.0 / args.window
        print(f"{t:6.2f} {int(np.sum(sim.present)):7d} {e['pair'] * rate:9.0f} "
              f"{e['wall'] * rate:9.0f} {e['cell'] * rate:9.0f} {e['exit'] * rate:8.0f} "
              f"{time.perf_counter() - w0:8.2f}s {rss_mb():8.1f}")
    print(f"energy: entered {sim.entered_energy:.4g} J, exited {sim.exited_energy:.4g} J, "
          f"dissipated {sim.dissipated_energy():.3g} J")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
