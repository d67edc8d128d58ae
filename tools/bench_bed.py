"""What the cluster solver costs in a jamming bed (docs/enduring-contact.md, "Anderson
acceleration").

The scene is scenarios/chute.toml's (400 glass beads over a rough base of fixed beads) with
gravity tilted by ``--angle`` degrees (14 by default: below the inclinations with a steady
flow, so the bed slows and comes into constrained motion). The tool runs it to ``--start``
seconds (not timed), then times ``--span`` seconds of simulated time in windows and prints,
per window and in total: CPU time, Gauss–Seidel sweeps and contact visits of the cluster
solves, cluster events, and how many beads are in constrained motion. To compare two
versions of the solver, run this in each, alternating, on one machine, from one checkpoint
(``--checkpoint``: written by the first run, read by the others; the versions' trajectories
part at the first cluster solve that ends otherwise, so each must start from the same state).

Usage:
    .venv/bin/python tools/bench_bed.py [--angle 14] [--start 0.163] [--span 0.005]
        [--windows 5] [--checkpoint bed.pkl]
"""

from __future__ import annotations

import argparse
import pickle
import sys
import time
from pathlib import Path

from chute import chute_scene


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--angle", type=float, default=14.0, help="inclination [deg]")
    p.add_argument("--start", type=float, default=0.163,
                   help="simulated time run before the timing starts [s]")
    p.add_argument("--span", type=float, default=0.005, help="simulated time timed [s]")
    p.add_argument("--windows", type=int, default=5)
    p.add_argument("--checkpoint", type=Path, default=None,
                   help="state at --start: read if it exists, else written")
    a = p.parse_args(argv)

    from hsgran._state import I_SWEEPS, I_VISITS
    from hsgran.engine import Simulation, SimulationError
    from hsgran.onplane import MS_SUPPORTED

    sim = Simulation(chute_scene(a.angle, a.start + a.span))
    wall = time.perf_counter()
    if a.checkpoint is not None and a.checkpoint.exists():
        try:
            state = pickle.loads(a.checkpoint.read_bytes())
        except Exception as err:  # (any byte string may fail to unpickle in its own way)
            print(f"bench_bed: --checkpoint {a.checkpoint}: not a checkpoint ({err})",
                  file=sys.stderr)
            return 2
        try:
            sim.restore(state)
        except (SimulationError, AttributeError, TypeError) as err:  # (not a Checkpoint)
            print(f"bench_bed: --checkpoint {a.checkpoint}: {err}", file=sys.stderr)
            return 2
    else:
        sim.run(until=a.start)
        if a.checkpoint is not None:
            a.checkpoint.write_bytes(pickle.dumps(sim.checkpoint()))
    print(f"to t = {a.start} s: {time.perf_counter() - wall:.1f} s of wall time "
          f"(not timed; {int((sim.mstate == MS_SUPPORTED).sum())} beads in constrained motion)")
    print(f"{'t [s]':>8} {'CPU [s]':>8} {'sweeps':>10} {'visits':>10} {'clusters':>8} "
          f"{'supported':>9}")
    sweeps0, visits0, cpu0 = int(sim.isc[I_SWEEPS]), int(sim.isc[I_VISITS]), time.process_time()
    clusters = 0
    for k in range(1, a.windows + 1):
        t = a.start + a.span * k / a.windows
        s = sim.run(until=t)
        clusters += s.events["cluster"]
        print(f"{t:8.4f} {time.process_time() - cpu0:8.1f} "
              f"{int(sim.isc[I_SWEEPS]) - sweeps0:10.3g} {int(sim.isc[I_VISITS]) - visits0:10.3g} "
              f"{clusters:8d} {int((sim.mstate == MS_SUPPORTED).sum()):9d}")
    print(f"total: {time.process_time() - cpu0:.1f} s of CPU for {a.span} s of simulated time")
    return 0


if __name__ == "__main__":
    sys.exit(main())
