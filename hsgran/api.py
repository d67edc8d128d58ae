"""Python API mirroring the command line (layer 6).

>>> from hsgran.api import run_scene, resume_run
>>> summary = run_scene("scenarios/steel_ball_on_glass.toml", "ball.h5")   # doctest: +SKIP
>>> summary = resume_run("ball.h5", until=2.0)    # continue (or extend) it   # doctest: +SKIP
>>> from hsgran.io.h5md import read_trajectory
>>> traj = read_trajectory("ball.h5")                                     # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from hsgran import __version__, materials
from hsgran.engine import SOLVER_COUNTS, Checkpoint, RunSummary, Simulation, SimulationError
from hsgran.errors import InputError
from hsgran.io.h5md import StoredCheckpoint, TrajectoryWriter, Walls, copy_frames, read_checkpoint
from hsgran.scene import Scene, load_scene, override_note, parse_scene

#: Wall time between two checkpoints of a run that writes a file [s], unless told otherwise: a
#: hard kill loses at most this much work, and a checkpoint costs little against it (the
#: 2000-sphere pour: ~10 ms, two syncs to disk included).
CHECKPOINT_WALL = 60.0
#: Suffix of the file a resume writes before it replaces the original.
RESUME_SUFFIX = ".resume-tmp"


class TrajectoryObserver:
    """Engine observer that appends every frame block and event block to an H5MD file and
    stores every checkpoint in it.

    Args:
        writer: The open trajectory writer.
        t_end: End time of the run [s], stored with each checkpoint so that a resume ends
            where the run would have ended.
    """

    def __init__(self, writer: TrajectoryWriter, t_end: float = float("nan")):
        self.writer = writer
        self.t_end = float(t_end)

    def on_frames(self, block) -> None:
        """Append a block of frames."""
        self.writer.append_frames(block)

    def on_events(self, block) -> None:
        """Append a block of the event log."""
        self.writer.append_events(block)

    def on_checkpoint(self, ck: Checkpoint) -> None:
        """Store a restart state."""
        self.writer.write_checkpoint(ck.arrays, ck.time, ck.frames, ck.events, ck.version,
                                     t_end=self.t_end)

    def on_finish(self, summary: RunSummary) -> None:
        """Store the run summary in the file."""
        self.writer.set_summary({"events": summary.events,
                                 "simulated_time": summary.simulated_time,
                                 "wall_time": summary.wall_time,
                                 "events_per_second": summary.events_per_second,
                                 "interrupted": summary.interrupted,
                                 **{k: getattr(summary, k) for k in SOLVER_COUNTS}})


def open_writer(path, scene: Scene, sim: Simulation, *, log_events: bool,
                creator_args: str = "") -> TrajectoryWriter:
    """A trajectory writer for ``sim``'s run of ``scene`` (with checkpoint slots).

    Raises:
        InputError: the file cannot be created.
    """
    return TrajectoryWriter(
        path, radius=scene.radius, mass=scene.mass(), material=scene.material,
        material_names=list(scene.material_names), box_lower=scene.box_lower,
        box_upper=scene.box_upper, periodic=tuple(scene.periodic),
        angular_velocity=bool(scene.effects.rotation), scene_text=scene.text,
        effects=list(scene.effects.enabled()), seed=int(scene.seed), version=__version__,
        log_events=log_events, creator_args=creator_args, motion_state=True,
        observables=scene.observables, open_system=scene.open_system,
        checkpoint_layout=sim.checkpoint_layout(), overrides=scene.overrides,
        walls=Walls.of(scene.walls), scene_name=scene.name, pair_table=sim.pair_table)


def _run_into(sim: Simulation, writer: TrajectoryWriter, t_end: float, *, progress: bool,
              checkpoint_every, checkpoint_wall, stop, remove_if_empty: bool) -> RunSummary:
    """Run ``sim`` to ``t_end`` with ``writer`` observing; close the file in every case."""
    try:
        summary = sim.run(t_end, observers=[TrajectoryObserver(writer, t_end)],
                          progress=progress, checkpoint_every=checkpoint_every,
                          checkpoint_wall=checkpoint_wall, stop=stop)
    except BaseException:
        writer.close(complete=False)
        if remove_if_empty and writer.n_frames == 0:
            Path(writer.path).unlink(missing_ok=True)  # failed before its first frame
        raise
    writer.close(complete=not summary.interrupted)
    return summary


def _end_time(until, scene: Scene) -> float:
    return scene.duration if until is None else float(until)


def run_scene(scene: Scene | str | os.PathLike, output: str | os.PathLike | None = None, *,
              until: float | None = None, log_events: bool = False, progress: bool = False,
              force: bool = False, creator_args: str = "", overrides=None,
              checkpoint_every: float | None = None,
              checkpoint_wall: float | None = CHECKPOINT_WALL,
              stop: Callable[[], bool] | None = None) -> RunSummary:
    """Load (if given a path) and run a scene, writing its trajectory.

    Args:
        scene: A :class:`~hsgran.scene.Scene` or the path of a scene file.
        output: HDF5 trajectory to write, or ``None`` to run without output.
        until: End time [s] (default: the scene's duration).
        log_events: Record every collision in the file.
        progress: Show a progress bar.
        force: Overwrite an existing output file.
        creator_args: Command line recorded in the file.
        overrides: Key path → value changes applied to the scene file before validation
            (``{"contacts[0].sliding_friction": 0.2}``; see :mod:`hsgran.overrides`); only
            when ``scene`` is a path.
        checkpoint_every: Store a checkpoint at every multiple of this simulated time [s].
        checkpoint_wall: ... and after this much wall time [s] since the last (``None``:
            never by wall time). One is always stored at the end and on an interrupt.
        stop: Polled between batches of events; True ends the run early with a checkpoint
            (``RunSummary.interrupted``), for Ctrl-C and SIGTERM.

    Returns:
        The run's :class:`~hsgran.engine.RunSummary`.

    Raises:
        InputError: bad scene, or an existing output without ``force``.
        hsgran.engine.SimulationError: the run could not continue.
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene, overrides=overrides)
    elif overrides:
        raise InputError("overrides apply to a scene file: pass its path, not a Scene",
                         "overrides")
    sim = Simulation(scene, log_events=log_events)
    t_end = _end_time(until, scene)
    if output is None:
        return sim.run(t_end, progress=progress, stop=stop)
    out = Path(output)
    if out.exists() and not force:
        raise InputError(f"{out} exists: pass --force to overwrite it", "output")
    writer = open_writer(out, scene, sim, log_events=log_events, creator_args=creator_args)
    return _run_into(sim, writer, t_end, progress=progress, checkpoint_every=checkpoint_every,
                     checkpoint_wall=checkpoint_wall, stop=stop, remove_if_empty=True)


def _pair_column_names() -> dict[int, str]:
    """Column of a pair row → the name of its ``hsgran.materials.P_*`` constant."""
    return {value: name for name, value in vars(materials).items()
            if name.startswith("P_") and isinstance(value, int)}


def _check_pair_table(path, stored: StoredCheckpoint, table, material_names) -> None:
    """Refuse a resume whose contact laws would not be bit for bit those that built the
    checkpoint (the same version can still differ, e.g. through a changed material file).

    Raises:
        InputError: naming the first pair and parameter that differ.
    """
    old = stored.pair_table
    if old is None:  # written before the table was stored: the version check is all there is
        return
    if old.shape != table.shape:
        raise InputError(f"{path}: the checkpoint's pair table has shape {old.shape}, this "
                         f"scene's {table.shape}: resume with the hsgran that wrote it or "
                         "start again")
    if old.tobytes() == table.tobytes():  # bits, so NaNs (no contact law) compare equal
        return
    a, b, k = (int(x) for x in np.argwhere(old.view(np.uint64) != table.view(np.uint64))[0])
    column = _pair_column_names().get(k, f"column {k}")
    raise InputError(f"{path}: the contact law {material_names[a]}-{material_names[b]} differs "
                     f"from the checkpoint's ({column}: {old[a, b, k]!r} stored, "
                     f"{table[a, b, k]!r} now): resume with the hsgran that wrote it or start "
                     "again")


def resume_run(path: str | os.PathLike, *, until: float | None = None, progress: bool = False,
               checkpoint_every: float | None = None,
               checkpoint_wall: float | None = CHECKPOINT_WALL,
               stop: Callable[[], bool] | None = None) -> RunSummary:
    """Continue the run of a trajectory file from its last checkpoint.

    The file is written anew up to the checkpoint (frames and events written after it are
    dropped: the resumed run writes them again, bit for bit the same), then the run goes on.
    A complete file can be extended by giving a later ``until``.

    Args:
        path: Trajectory file of ``hsgran run`` (interrupted, killed, or complete).
        until: End time [s] (default: the end time of the original run).
        progress, checkpoint_every, checkpoint_wall, stop: As in :func:`run_scene`.

    Returns:
        The :class:`~hsgran.engine.RunSummary` of the resumed part.

    Raises:
        InputError: no usable checkpoint, nothing left to run, ``until`` before it, or the
            checkpoint was written by another hsgran version or with other contact laws (a
            resume would not continue the run bit for bit).
        hsgran.engine.SimulationError: the run could not continue.
    """
    path = Path(path)
    stored = read_checkpoint(path)
    if stored.hsgran_version != __version__:
        raise InputError(f"{path}: checkpoint written by hsgran {stored.hsgran_version}, this "
                         f"is {__version__}: resume with that version or start again")
    text, note = stored.scene_text, override_note(stored.overrides)
    if stored.overrides and text.endswith(note):
        text = text[:-len(note)]
    scene = parse_scene(text, source=str(path), overrides=stored.overrides or None)
    if until is not None:
        t_end = float(until)
    elif stored.t_end == stored.t_end:  # not NaN
        t_end = stored.t_end
    else:
        t_end = scene.duration
    if t_end < stored.time:
        raise InputError(f"must not be before the checkpoint at t = {stored.time:.9g} s, "
                         f"got {t_end:.9g}", "--until")
    if stored.complete and t_end <= stored.time:
        raise InputError(f"{path} is complete (t = {stored.time:.9g} s): give a later --until "
                         "to extend it")
    sim = Simulation(scene, log_events=stored.log_events)
    _check_pair_table(path, stored, sim.pair_table, scene.material_names)
    try:
        sim.restore(Checkpoint(stored.arrays, stored.time, stored.frames, stored.events,
                               stored.version))
    except SimulationError as exc:
        raise InputError(f"{path}: {exc}") from None
    tmp = path.with_name(path.name + RESUME_SUFFIX)
    writer = open_writer(tmp, scene, sim, log_events=stored.log_events,
                         creator_args=stored.creator_args)
    try:
        copy_frames(path, writer, stored.frames, stored.events)
        ck = sim.checkpoint()
        writer.write_checkpoint(ck.arrays, ck.time, ck.frames, ck.events, ck.version,
                                t_end=t_end)
        os.replace(tmp, path)  # the open file keeps being written under its new name
    except BaseException:
        writer.close(complete=False)
        tmp.unlink(missing_ok=True)
        raise
    writer.path = os.fspath(path)
    return _run_into(sim, writer, t_end, progress=progress, checkpoint_every=checkpoint_every,
                     checkpoint_wall=checkpoint_wall, stop=stop, remove_if_empty=False)
