"""Write the conical hopper of ``scenarios/hopper.toml`` as an STL file (docs/walls.md, "Finite
walls"): the side of a cone frustum, open at both ends, from radius ``--outlet`` at z = 0 to
``--top`` at z = ``--height``, cut into ``--segments`` quadrilaterals of two triangles each
around its axis, the triangles' normals pointing inwards (to the spheres). Lengths in mm, as
CAD files usually are (the scene reads it with ``scale = 0.001``).

Usage:
    .venv/bin/python tools/make_hopper.py [-o scenarios/hopper.stl] [--outlet 6] [--top 30]
        [--height 30] [--segments 48]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np


def hopper(outlet: float, top: float, height: float, segments: int):
    """(vertices (2 segments, 3), triangles (2 segments, 3)) of the frustum's side."""
    phi = 2.0 * math.pi * np.arange(segments) / segments
    ring = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(segments)])
    lower = ring * outlet
    upper = ring * top + [0.0, 0.0, height]
    vertices = np.concatenate([lower, upper])
    faces = []
    for k in range(segments):
        a, b = k, (k + 1) % segments
        # counter-clockwise seen from the axis: the normals point inwards
        faces += [(a, segments + a, b), (b, segments + a, segments + b)]
    return vertices, np.array(faces)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", type=Path, default=Path("scenarios/hopper.stl"))
    ap.add_argument("--outlet", type=float, default=6.0, help="radius at the bottom [mm]")
    ap.add_argument("--top", type=float, default=30.0, help="radius at the top [mm]")
    ap.add_argument("--height", type=float, default=30.0, help="[mm]")
    ap.add_argument("--segments", type=int, default=48)
    args = ap.parse_args(argv)
    import trimesh

    vertices, faces = hopper(args.outlet, args.top, args.height, args.segments)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    args.output.write_bytes(trimesh.exchange.stl.export_stl_ascii(mesh).encode())
    print(f"wrote {args.output}: {len(faces)} triangles")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
