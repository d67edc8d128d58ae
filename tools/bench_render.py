"""Drawing speed of ``hsgran render``: milliseconds per frame against the number of spheres.

Usage:
    .venv/bin/python tools/bench_render.py [--sizes 10,1000,10000] [--frames 20]
        [--size 1280x720] [--spheres auto] [--color-by speed]

Prints figures only (no pass/fail), with the target next to them (issue 5: at most 100 ms per
frame for 1000 spheres at 1280×720).

Each size is a synthetic trajectory in memory (no file, no engine): N steel spheres of equal
radius on a jittered cubic lattice filling the lower half of a closed glass box (a settling pile,
the common case), at packing fraction ~0.3 within that half, moving with random velocities and
spins. The iso camera frames the whole box, so the pile covers a similar share of the picture at
every N and the spheres get smaller as N grows. A frame is timed from the playback of its time
(interpolation, spin integration, colours) through VTK's render to the screenshot in memory;
encoding a movie is excluded (imageio-ffmpeg runs in its own process, in parallel). The first
frame (shader compilation, texture upload) is drawn before timing.

Rendering uses Mesa's software rasteriser when there is no GPU, which shares the machine's cores:
figures taken while the machine is busy are noisy.
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time

import numpy as np

from hsgran.errors import InputError
from hsgran.io.h5md import Trajectory
from hsgran.render import Renderer, missing_system_libraries

#: Sizes (numbers of spheres) of the issue's benchmark.
DEFAULT_SIZES = (10, 1000, 10000)
#: Timed frames per size (after one untimed frame).
DEFAULT_FRAMES = 20
#: Target of issue 5 [ms/frame] at TARGET_N spheres and 1280×720.
TARGET_MS, TARGET_N = 100.0, 1000
#: Sphere radius [m] and packing fraction of the pile [-]; only ratios matter for the picture.
RADIUS = 0.001
PACKING = 0.3
#: rms speed [m/s] and spin [rad/s] of the spheres, and the frame interval [s]: slow enough that
#: the pile stays a pile over the frames drawn.
SPEED, SPIN, FRAME_INTERVAL = 0.05, 50.0, 0.002
SEED = 1


def pile(n: int, frames: int) -> Trajectory:
    """A synthetic trajectory of ``n`` spheres piled in the lower half of a box."""
    rng = np.random.default_rng(SEED)
    volume = n * (4.0 / 3.0) * math.pi * RADIUS**3 / PACKING
    side = (volume / 0.5) ** (1.0 / 3.0)          # the pile fills half the box's height
    per_row = max(1, math.ceil((n / 0.5) ** (1.0 / 3.0)))
    spacing = side / per_row
    cells = np.array([[i, j, k] for k in range(per_row) for j in range(per_row)
                      for i in range(per_row)][:n], dtype=float)
    jitter = max(0.0, 0.5 * spacing - RADIUS) * rng.uniform(-1.0, 1.0, (n, 3))
    start = (cells + 0.5) * spacing + jitter
    velocity = rng.normal(0.0, SPEED / math.sqrt(3.0), (n, 3))
    spin = rng.normal(0.0, SPIN / math.sqrt(3.0), (n, 3))
    time_ = FRAME_INTERVAL * np.arange(frames)
    position = start[None] + velocity[None] * time_[:, None, None]
    upper = np.array([side, side, side])
    scene = f"""
[scene]
name = "bench_render: {n} spheres"
duration = {FRAME_INTERVAL * frames}
[output]
frame_interval = {FRAME_INTERVAL}
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [{side}, {side}, {side}]
material = "glass"
[[particles]]
material = "steel"
radius = {RADIUS}
position = [{side / 2}, {side / 2}, {side / 2}]
"""
    zeros = np.zeros(frames)
    return Trajectory(
        time=time_, step=np.arange(frames), position=position,
        velocity=np.broadcast_to(velocity, (frames, n, 3)).copy(),
        angular_velocity=np.broadcast_to(spin, (frames, n, 3)).copy(),
        radius=np.full(n, RADIUS), mass=np.full(n, 1e-5), material=np.zeros(n, dtype=np.int32),
        material_names=["steel", "glass"], box_lower=np.zeros(3), box_upper=upper,
        periodic=(False, False, False),
        energies={"kinetic_energy_translational": zeros, "potential_energy": zeros,
                  "dissipated_energy": zeros},
        events=None, scene_text=scene, effects=["rotation"], seed=SEED, version="bench",
        summary={})


def measure(n: int, frames: int, size: tuple[int, int], spheres: str,
            color_by: str) -> tuple[float, str]:
    """Mean drawing time of one frame [s] and the sphere style used."""
    traj = pile(n, frames + 1)
    renderer = Renderer(traj, size=size, camera="iso", color_by=color_by, spheres=spheres)
    try:
        renderer.draw(renderer.playback.frame(float(traj.time[0])))
        t0 = time.perf_counter()
        for t in traj.time[1:]:
            renderer.draw(renderer.playback.frame(float(t)))
        elapsed = time.perf_counter() - t0
    finally:
        renderer.close()
    return elapsed / frames, "mesh" if renderer.mesh_mode else "points"


def _sizes(text: str) -> list[int]:
    try:
        sizes = [int(float(s)) for s in text.split(",") if s.strip()]
    except ValueError:
        sizes = []
    if not sizes or min(sizes) < 1:
        raise SystemExit(f"bench_render: --sizes: expected positive integers, got {text!r}")
    return sizes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default=",".join(str(n) for n in DEFAULT_SIZES),
                        help="numbers of spheres, comma-separated (default 10,1000,10000)")
    parser.add_argument("--frames", type=int, default=DEFAULT_FRAMES,
                        help=f"timed frames per size (default {DEFAULT_FRAMES})")
    parser.add_argument("--size", default="1280x720", help="picture size WxH (default 1280x720)")
    parser.add_argument("--spheres", default="auto", help="auto, mesh or points")
    parser.add_argument("--color-by", default="speed", help="speed, state or material")
    args = parser.parse_args(argv)
    sizes = _sizes(args.sizes)
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        raise SystemExit(f"bench_render: --size: expected WxH, got {args.size!r}") from None
    if args.frames < 1:
        raise SystemExit("bench_render: --frames: must be >= 1")
    problem = missing_system_libraries()
    if problem:
        raise SystemExit(f"bench_render: {problem}")

    print(f"# hsgran render: {width}x{height}, {args.frames} timed frames per size, "
          f"--color-by {args.color_by}, {platform.processor() or platform.machine()}")
    print(f"{'spheres':>8}  {'style':>6}  {'ms/frame':>9}")
    results = {}
    for n in sizes:
        try:
            seconds, style = measure(n, args.frames, (width, height), args.spheres,
                                     args.color_by)
        except InputError as exc:
            raise SystemExit(f"bench_render: {exc}") from None
        results[n] = seconds
        print(f"{n:>8,}  {style:>6}  {1e3 * seconds:>9.1f}", flush=True)
    if TARGET_N in results and (width, height) == (1280, 720):
        ms = 1e3 * results[TARGET_N]
        verdict = "met" if ms <= TARGET_MS else "missed"
        print(f"targets: <= {TARGET_MS:.0f} ms/frame at {TARGET_N:,} spheres, 1280x720: "
              f"{ms:.1f} ({verdict})")
    else:
        print(f"targets: <= {TARGET_MS:.0f} ms/frame at {TARGET_N:,} spheres, 1280x720 "
              "(not measured in this run)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
