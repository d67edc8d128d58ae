"""What checkpoints cost: time to store one, its size on disk, and time to resume from it.

    .venv/bin/python tools/bench_checkpoint.py [--sizes 2e3,1e5]

For each size, a granular gas (every mechanical effect on, gravity, a closed box) is built and
run for a few frames into a trajectory file; then a checkpoint is stored repeatedly (the median
time is printed, two syncs to disk included), the file's growth per checkpoint slot is measured,
and a resume (read the checkpoint, rebuild the run from the scene, restore, rebuild the event
calendar) is timed without running further.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

from hsgran.api import TrajectoryObserver, open_writer
from hsgran.engine import Checkpoint, Simulation
from hsgran.io.h5md import read_checkpoint
from hsgran.scene import parse_scene

#: Checkpoints stored per size; the median is printed.
REPEATS = 5


def scene_text(n: int) -> str:
    """A box of ``n`` steel spheres of 1 mm at ~10 % volume fraction, all effects on."""
    side = (n * 4.19e-9 / 0.1) ** (1 / 3)
    return f"""
[scene]
name = "checkpoint bench"
duration = 1.0
gravity = [0.0, 0.0, -9.81]
effects = ["gravity", "rotation", "friction", "plasticity"]
seed = 1
[output]
frame_interval = 0.001
[[contacts]]
between = ["steel", "steel"]
sliding_friction = 0.3
[[contacts]]
between = ["steel", "glass"]
sliding_friction = 0.3
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [{side}, {side}, {side}]
material = "glass"
[[fill]]
count = {n}
material = "steel"
radius = 0.001
region = {{ lower = [0.0, 0.0, 0.0], upper = [{side}, {side}, {side}] }}
speed = 0.5
"""


def measure(n: int, folder: Path) -> dict:
    """Store/resume figures of an ``n``-sphere run."""
    scene = parse_scene(scene_text(n))
    sim = Simulation(scene)
    path = folder / f"bench{n}.h5"
    writer = open_writer(path, scene, sim, log_events=False)
    empty = path.stat().st_size
    observer = TrajectoryObserver(writer, scene.duration)
    sim.run(0.003, observers=[observer])
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        observer.on_checkpoint(sim.checkpoint())
        times.append(time.perf_counter() - t0)
    writer.close()
    layout_bytes = sum(a.nbytes for a in sim.checkpoint().arrays.values())
    t0 = time.perf_counter()
    stored = read_checkpoint(path)
    again = Simulation(parse_scene(stored.scene_text))
    again.restore(Checkpoint(stored.arrays, stored.time, stored.frames, stored.events,
                             stored.version))
    resume = time.perf_counter() - t0
    return {"n": n, "store_ms": 1e3 * statistics.median(times),
            "bytes_per_sphere": layout_bytes / n, "file_empty_MB": empty / 2**20,
            "resume_s": resume}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="2e3,1e5", help="sphere counts, comma-separated")
    args = parser.parse_args(argv)
    sizes = [int(float(x)) for x in args.sizes.split(",")]
    print(f"{'spheres':>9} {'store [ms]':>11} {'state [B/sphere]':>17} "
          f"{'new file [MB]':>14} {'resume [s]':>11}")
    with tempfile.TemporaryDirectory() as d:
        for n in sizes:
            r = measure(n, Path(d))
            print(f"{r['n']:>9,} {r['store_ms']:>11.1f} {r['bytes_per_sphere']:>17.0f} "
                  f"{r['file_empty_MB']:>14.1f} {r['resume_s']:>11.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
