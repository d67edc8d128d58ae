"""What a triangle mesh costs the event loop (docs/walls.md, "Finite walls").

An elastic gas of N spheres without gravity in a box, three ways: the box alone; with a ball of
T triangles (a subdivided icosahedron written to an STL file) fixed in its middle; and with the
box's floor replaced by a flat mesh of T triangles. The cell grid lists each part of a mesh in
the cells it reaches, so a prediction looks only at the parts near the sphere: events per
second of wall time should stay near the plain box's, whatever T. Prints, per variant, the
walls (engine rows), the events, the wall time and events per second, best of ``--repeat``
runs (the machines are shared and noisy).

Usage:
    .venv/bin/python tools/bench_mesh.py [--spheres 1000] [--triangles 20480] [--seconds 0.2]
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from hsgran.engine import Simulation
from hsgran.scene import parse_scene

HEAD = """
[scene]
name = "gas with a mesh"
duration = {seconds}
effects = []
seed = 3
[output]
frame_interval = {seconds}
[[contacts]]
between = ["steel", "steel"]
restitution = 1.0
[[fill]]
count = {spheres}
material = "steel"
radius = 0.001
region = {{ lower = [0.0, 0.0, 0.001], upper = [0.06, 0.06, 0.019] }}
speed = 0.5
"""
BOX = """
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.06, 0.06, 0.06]
material = "steel"
"""
OPEN_FLOOR = """
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.06]
normal = [0.0, 0.0, -1.0]
material = "steel"
""" + "".join(f"""
[[walls]]
kind = "plane"
point = [{p}]
normal = [{n}]
material = "steel"
""" for p, n in (("0.0, 0.0, 0.0", "1.0, 0.0, 0.0"), ("0.06, 0.0, 0.0", "-1.0, 0.0, 0.0"),
                 ("0.0, 0.0, 0.0", "0.0, 1.0, 0.0"), ("0.0, 0.06, 0.0", "0.0, -1.0, 0.0")))


def icosphere(level: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (unit sphere) and triangles of an icosahedron subdivided ``level`` times
    (20 · 4^level triangles, counter-clockwise seen from outside)."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    vertices = [np.array(p, float) / np.linalg.norm(p) for p in v]

    def mid(a, b, middle):
        key = (min(a, b), max(a, b))
        if key not in middle:
            p = vertices[a] + vertices[b]
            vertices.append(p / np.linalg.norm(p))
            middle[key] = len(vertices) - 1
        return middle[key]

    for _ in range(level):
        middle: dict = {}
        faces = []
        for a, b, c in f:
            ab, bc, ca = mid(a, b, middle), mid(b, c, middle), mid(c, a, middle)
            faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = faces
    return np.array(vertices), np.array(f)


def flat_grid(n: int, size: float) -> tuple[np.ndarray, np.ndarray]:
    """A square z = 0 of side ``size`` cut into n × n squares of two triangles, facing up."""
    x = np.linspace(0.0, size, n + 1)
    xx, yy = np.meshgrid(x, x, indexing="ij")
    vertices = np.column_stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)])
    faces = []
    for i in range(n):
        for j in range(n):
            a, b = i * (n + 1) + j, (i + 1) * (n + 1) + j
            faces += [(a, b, b + 1), (a, b + 1, a + 1)]
    return vertices, np.array(faces)


def write_stl(path: Path, vertices, faces) -> Path:
    import trimesh

    trimesh.Trimesh(vertices, faces, process=False).export(str(path))
    return path


def run(text: str, repeat: int) -> tuple[int, int, float]:
    """(walls, events, best wall time [s]) of a scene text."""
    best = math.inf
    for _ in range(repeat):
        scene = parse_scene(text)
        sim = Simulation(scene)
        w0 = time.perf_counter()
        summary = sim.run()
        best = min(best, time.perf_counter() - w0)
        events = sum(summary.events.values())
    return len(scene.walls), events, best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spheres", type=int, default=1000)
    ap.add_argument("--triangles", type=int, default=20480,
                    help="triangles of the ball (rounded to 20·4^k) and of the floor (2n²)")
    ap.add_argument("--seconds", type=float, default=0.2)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    level = max(0, round(math.log(args.triangles / 20.0, 4)))
    n_floor = max(1, round(math.sqrt(args.triangles / 2.0)))
    head = HEAD.format(seconds=args.seconds, spheres=args.spheres)
    with tempfile.TemporaryDirectory() as tmp:
        v, f = icosphere(level)
        ball = write_stl(Path(tmp) / "ball.stl", v, f)
        floor = write_stl(Path(tmp) / "floor.stl", *flat_grid(n_floor, 0.06))
        # the ball: radius 1 cm in the middle, above the fill
        variants = {
            "box": head + BOX,
            f"box + ball of {len(f)} triangles": head + BOX + (
                f"[[walls]]\nkind = \"mesh\"\nfile = \"{ball}\"\nscale = 0.01\n"
                "offset = [0.03, 0.03, 0.03]\nmaterial = \"steel\"\nfaces = \"front\"\n"),
            f"floor of {2 * n_floor * n_floor} triangles": head + OPEN_FLOOR + (
                f"[[walls]]\nkind = \"mesh\"\nfile = \"{floor}\"\nmaterial = \"steel\"\n"
                "faces = \"front\"\n"),
        }
        print(f"{args.spheres} spheres, elastic, no gravity, {args.seconds} s simulated; best "
              f"of {args.repeat}")
        print(f"{'variant':32} {'walls':>7} {'events':>9} {'wall [s]':>9} {'events/s':>10}")
        for name, text in variants.items():
            walls, events, wall = run(text, args.repeat)
            print(f"{name:32} {walls:7d} {events:9d} {wall:9.3f} {events / wall:10.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
