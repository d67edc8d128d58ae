"""Tiny scenes and sweep files shared by the sweep tests (fast also with NUMBA_DISABLE_JIT)."""

from __future__ import annotations

from pathlib import Path

#: One steel sphere thrown at a glass plate under gravity: one impact after 0.1 ms, then a
#: short flight; 4 ms of simulated time and a handful of events.
BALL = """\
[scene]
name = "ball on glass"
duration = 0.004
effects = ["gravity", "rotation", "friction", "plasticity"]
[output]
frame_interval = 0.002
[[contacts]]
between = ["steel", "glass"]
sliding_friction = 0.3
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "glass"
[[particles]]
material = "steel"
radius = 0.005
position = [0.0, 0.0, 0.0051]
velocity = [0.5, 0.0, -1.0]
"""

SUMMARIES = ["e_n", "rebound_angle", "spin_after", "collisions", "final_height"]

#: 2 frictions x 3 angles = 6 cases.
SWEEP = """\
[sweep]
scene = "ball.toml"
summaries = ["e_n", "rebound_angle", "spin_after", "collisions", "final_height"]
[vary]
"contacts[0].sliding_friction" = [0.1, 0.3]
angle = [10.0, 30.0, 50.0]
[set]
"particles[0].velocity" = ["2 * sin(radians(angle))", 0.0, "-2 * cos(radians(angle))"]
"""


def write(folder: Path, sweep: str = SWEEP, scene: str = BALL) -> Path:
    """Write ball.toml and sweep.toml into ``folder``; return the sweep file."""
    (folder / "ball.toml").write_text(scene)
    path = folder / "sweep.toml"
    path.write_text(sweep)
    return path
