"""Spheres grazing the inside of a cylinder: a seeded generator of single-sphere scenes and
the share that run to their end (docs/enduring-contact.md, "A binary collision that ends
nothing").

Usage:
    .venv/bin/python tools/graze.py [--seed 2] [--count 200]

Each scene puts one sphere against the side of an upright cylinder (radius 5–100 mm), far
from its ends, moving along the side at a speed drawn log-uniformly from 10⁻⁴ to 1 m/s and
up or down at up to 5 cm/s, under gravity, for 0.03 s; restitution 0.1–0.95, sliding
friction 0, 0.3 or 0.8, either treatment. The curvature presses such a sphere into the side
at no normal speed. Prints how many ran to their end with the sphere inside the side in every
frame (its centre within ρ = R − r to 1e-9 relative), how many stopped at the collapse guard,
and the fastest grazing speed among those that did.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

DURATION = 0.03  #: simulated time of each scene [s]
INSIDE_REL = 1e-9  #: a centre beyond ρ (1 + this) + INSIDE_ABS is outside the side [-]
INSIDE_ABS = 1e-12  #: ... [m] (the touching tolerance of the contact times)


class Farthest:
    """Observer: the sphere's largest distance from the axis in any frame [m]."""

    def __init__(self):
        self.rho = 0.0

    def on_frames(self, block):
        x = block.position[:, 0]
        self.rho = max(self.rho, float(np.hypot(x[:, 0], x[:, 1]).max()))


def scene_text(rng, k: int) -> tuple[str, float, float, str]:
    """Scene k drawn from ``rng``: its TOML text, ρ [m], grazing speed [m/s], treatment."""
    radius = rng.uniform(0.005, 0.1)
    r = min(rng.uniform(0.0005, 0.003) * (radius / 0.04) ** 0.3, 0.3 * radius)
    phi, rho = rng.uniform(0.0, 2.0 * math.pi), radius - r
    vt, vz = 10.0 ** rng.uniform(-4.0, 0.0), rng.uniform(-0.05, 0.05)
    treatment = str(rng.choice(["pairwise", "clusters"]))
    mu, e = float(rng.choice([0.0, 0.3, 0.8])), rng.uniform(0.1, 0.95)
    friction = ', "friction"' if mu > 0.0 else ""
    text = f"""
[scene]
name = "graze {k}"
duration = {DURATION}
gravity = [0.0, 0.0, -9.81]
effects = ["gravity", "rotation"{friction}]
[output]
frame_interval = 0.01
[enduring_contact]
treatment = "{treatment}"
[[contacts]]
between = ["glass", "steel"]
restitution = {e!r}
sliding_friction = {mu!r}
[[walls]]
kind = "cylinder"
center = [0.0, 0.0, 0.5]
axis = [0.0, 0.0, 1.0]
radius = {radius!r}
length = 1.0
caps = false
material = "steel"
[[particles]]
material = "glass"
radius = {r!r}
position = [{rho * math.cos(phi)!r}, {rho * math.sin(phi)!r}, 0.5]
velocity = [{-vt * math.sin(phi)!r}, {vt * math.cos(phi)!r}, {vz!r}]
"""
    return text, rho, vt, treatment


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=2, help="seed of the draws (default 2)")
    ap.add_argument("--count", type=int, default=200, help="scenes (default 200)")
    args = ap.parse_args(argv)
    if args.count < 1:
        ap.error("--count must be at least 1")
    from hsgran.engine import Simulation, SimulationError
    from hsgran.scene import parse_scene

    rng = np.random.default_rng(args.seed)
    inside = outside = 0
    guarded = []
    for k in range(args.count):
        text, rho, vt, treatment = scene_text(rng, k)
        sim, farthest = Simulation(parse_scene(text)), Farthest()
        try:
            sim.run(observers=[farthest])
        except SimulationError:
            guarded.append((k, vt, treatment))
            continue
        if farthest.rho > rho * (1.0 + INSIDE_REL) + INSIDE_ABS:
            outside += 1
        else:
            inside += 1
    print(f"{inside}/{args.count} ran to their end inside the side, {len(guarded)} stopped at "
          f"the collapse guard, {outside} went outside it")
    if guarded:
        print(f"fastest grazing speed among those at the guard: "
              f"{max(v for _, v, _ in guarded):.3g} m/s")
        for k, v, treatment in guarded[:10]:
            print(f"  scene {k}: {v:.3g} m/s along the side, {treatment}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
