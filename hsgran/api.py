"""Python API mirroring the command line (layer 6).

>>> from hsgran.api import run_scene
>>> summary = run_scene("scenarios/steel_ball_on_glass.toml", "ball.h5")   # doctest: +SKIP
>>> from hsgran.io.h5md import read_trajectory
>>> traj = read_trajectory("ball.h5")                                     # doctest: +SKIP
"""

from __future__ import annotations

import os
from pathlib import Path

from hsgran import __version__
from hsgran.engine import RunSummary, Simulation
from hsgran.errors import InputError
from hsgran.io.h5md import TrajectoryWriter
from hsgran.scene import Scene, load_scene


class TrajectoryObserver:
    """Engine observer that appends every frame block and event block to an H5MD file."""

    def __init__(self, writer: TrajectoryWriter):
        self.writer = writer

    def on_frames(self, b) -> None:
        """Append a block of frames."""
        self.writer.append_frames(b.step, b.time, b.position, b.velocity, b.angular_velocity,
                                  b.kinetic_translational, b.kinetic_rotational, b.potential,
                                  b.dissipated, motion_state=b.motion_state)

    def on_events(self, b) -> None:
        """Append a block of the event log."""
        self.writer.append_events(b.time, b.kind, b.i, b.j, b.normal_impulse,
                                  b.tangential_impulse, b.e_n, b.stage, b.regime)

    def on_finish(self, summary: RunSummary) -> None:
        """Store the run summary in the file."""
        self.writer.set_summary({"events": summary.events,
                                 "simulated_time": summary.simulated_time,
                                 "wall_time": summary.wall_time,
                                 "events_per_second": summary.events_per_second})


def run_scene(scene: Scene | str | os.PathLike, output: str | os.PathLike | None = None, *,
              until: float | None = None, log_events: bool = False, progress: bool = False,
              force: bool = False, creator_args: str = "") -> RunSummary:
    """Load (if given a path) and run a scene, writing its trajectory.

    Args:
        scene: A :class:`~hsgran.scene.Scene` or the path of a scene file.
        output: HDF5 trajectory to write, or ``None`` to run without output.
        until: End time [s] (default: the scene's duration).
        log_events: Record every collision in the file.
        progress: Show a progress bar.
        force: Overwrite an existing output file.
        creator_args: Command line recorded in the file.

    Returns:
        The run's :class:`~hsgran.engine.RunSummary`.

    Raises:
        InputError: bad scene, or an existing output without ``force``.
        hsgran.engine.SimulationError: the run could not continue.
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    sim = Simulation(scene, log_events=log_events)
    if output is None:
        return sim.run(until, progress=progress)
    out = Path(output)
    if out.exists() and not force:
        raise InputError(f"{out} exists: pass --force to overwrite it", "output")
    writer = TrajectoryWriter(
        out, radius=scene.radius, mass=scene.mass(), material=scene.material,
        material_names=list(scene.material_names), box_lower=scene.box_lower,
        box_upper=scene.box_upper, periodic=tuple(scene.periodic),
        angular_velocity=bool(scene.effects.rotation), scene_text=scene.text,
        effects=list(scene.effects.enabled()), seed=int(scene.seed), version=__version__,
        log_events=log_events, creator_args=creator_args, motion_state=True)
    with writer:
        return sim.run(until, observers=[TrajectoryObserver(writer)], progress=progress)
