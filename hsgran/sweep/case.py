"""One case of a sweep: a scene plus overrides, run, summarised (what a Dask task executes).

:func:`run_case` is the public entry point for users driving sweeps from their own code::

    from dask.distributed import Client
    from hsgran.sweep import run_case
    client = Client()
    futures = [client.submit(run_case, "scene.toml", {"contacts[0].sliding_friction": mu},
                             ["e_n", "rebound_angle"], pure=False) for mu in (0.1, 0.2, 0.3)]
    rows = client.gather(futures)          # [{"e_n": ..., "rebound_angle": ...}, ...]

:func:`execute_case` is what ``hsgran sweep`` submits: it never raises for a failing case but
returns (and writes) a row with ``status = "error"`` and the one-line error, so one broken case
does not stop a sweep.
"""

from __future__ import annotations

import math
import os
import socket
import time
import traceback
from pathlib import Path

import numpy as np

from hsgran.api import TrajectoryObserver, open_writer
from hsgran.engine import SOLVER_COUNTS, EventBlock, RunSummary, Simulation
from hsgran.errors import HsgranError, InputError
from hsgran.events.kinds import EV_PAIR, EV_WALL
from hsgran.onplane import MS_ASLEEP, MS_REST
from hsgran.scene import Scene, load_scene, parse_scene
from hsgran.sweep import store
from hsgran.sweep.summaries import FirstCollision, RunRecord, evaluate


class _Log:
    """Engine observer that keeps the event log and, optionally, feeds a trajectory file."""

    def __init__(self, trajectory: TrajectoryObserver | None):
        self.blocks = []
        self.trajectory = trajectory

    def on_frames(self, block) -> None:
        if self.trajectory is not None:
            self.trajectory.on_frames(block)

    def on_events(self, block) -> None:
        self.blocks.append(block)
        if self.trajectory is not None:
            self.trajectory.on_events(block)

    def arrays(self) -> dict:
        """The event log so far, field name → array."""
        return vars(EventBlock.concatenate(self.blocks))


def _scene(scene, overrides, source: str) -> Scene:
    if isinstance(scene, Scene):
        if overrides:
            raise InputError("overrides apply to a scene file or text, not to a Scene",
                             "overrides")
        return scene
    text = str(scene)
    if "\n" not in text and text.endswith(".toml"):
        return load_scene(text, overrides=overrides)
    return parse_scene(text, source=source, overrides=overrides)


def _first_collision(sim: Simulation, scene: Scene, log: dict) -> FirstCollision | None:
    hits = np.flatnonzero((log["kind"] == EV_PAIR) | (log["kind"] == EV_WALL))
    if len(hits) == 0:
        return None
    k = int(hits[0])
    t, i, j = float(log["time"][k]), int(log["i"][k]), int(log["j"][k])
    pos, vel = sim.state_at(t)
    g = scene.gravity
    before = scene.velocity[i] + g * t
    after = vel[i].copy()
    if j >= 0:
        n = pos[i] - pos[j]
        n = n / np.linalg.norm(n)
        before = before - (scene.velocity[j] + g * t)
        after = after - vel[j]
    else:
        n = np.asarray(scene.planes[-1 - j].normal, dtype=float)
    omega = sim.omg[i].copy() if sim.rotation else np.zeros(3)
    return FirstCollision(t, i, j, float(log["e_n"][k]), n, before, after, omega)


def _add(a: dict, b: dict) -> dict:
    return {k: a.get(k, 0) + b.get(k, 0) for k in {**a, **b}}


def simulate(scene: Scene, trajectory: str | os.PathLike | None = None,
             creator_args: str = "") -> RunRecord:
    """Run a scene to its duration and keep what the summaries need.

    The run stops once right after its first collision to record the state there (the engine
    updates a sphere only at its own events, so this is the exact post-collision state), then
    continues; the two calls give the same run as one call.

    Args:
        scene: The scene.
        trajectory: HDF5 file to write (overwritten), or ``None``.
        creator_args: Recorded in the trajectory file.

    Raises:
        hsgran.engine.SimulationError: the run could not continue.
    """
    sim = Simulation(scene, log_events=True)
    writer = None
    if trajectory is not None:
        writer = open_writer(Path(trajectory), scene, sim, log_events=True,
                             creator_args=creator_args)
    log = _Log(TrajectoryObserver(writer) if writer is not None else None)
    try:
        part1 = sim.run(max_collisions=1, observers=[log])
        first = _first_collision(sim, scene, log.arrays())
        part2 = sim.run(observers=[log]) if first is not None else RunSummary()
        counts = _add(part1.events, part2.events)
        if log.trajectory is not None:
            wall = part1.wall_time + part2.wall_time
            executed = sum(counts.get(k, 0) for k in ("pair", "wall", "cell"))
            log.trajectory.on_finish(RunSummary(
                events=counts, simulated_time=scene.duration, wall_time=wall,
                events_per_second=executed / wall if wall > 0 else math.inf,
                **{k: getattr(part1, k) + getattr(part2, k) for k in SOLVER_COUNTS}))
    finally:
        if writer is not None:
            writer.close()
    t_end = scene.duration
    pos, vel = sim.state_at(t_end)
    kin_t, kin_r, _ = sim.energies_at(t_end)
    kinetic = kin_t + (kin_r or 0.0)
    at_rest = bool(scene.effects.gravity) and bool(np.all(np.isin(sim.mstate,
                                                                  (MS_REST, MS_ASLEEP))))
    return RunRecord(events=log.arrays(), counts=counts, first=first, t_end=t_end,
                     position=pos, velocity=vel, at_rest=at_rest, kinetic_energy=kinetic,
                     dissipated_energy=sim.dissipated_energy(t_end))


def run_case(scene, overrides: dict | None = None, summaries=("collisions",), *,
             source: str = "<sweep>", trajectory: str | os.PathLike | None = None
             ) -> dict[str, float]:
    """Run a scene with overrides and return its summary quantities.

    Args:
        scene: Path of a scene file (``*.toml``), the text of one, or a
            :class:`~hsgran.scene.Scene` (then without overrides).
        overrides: Key path → value (``{"contacts[0].sliding_friction": 0.2}``), see
            :mod:`hsgran.overrides`.
        summaries: Names from :data:`hsgran.sweep.summaries.SUMMARIES`.
        source: Name of the scene text in error messages.
        trajectory: HDF5 trajectory to write, or ``None``.

    Returns:
        Summary name → value (SI units, angles in degrees; NaN where undefined).

    Raises:
        InputError: bad scene, bad override or unknown summary name.
        hsgran.engine.SimulationError: the run could not continue.
    """
    from hsgran.errors import did_you_mean
    from hsgran.sweep.summaries import SUMMARIES

    for name in summaries:
        if name not in SUMMARIES:
            raise InputError(f"unknown summary '{name}'{did_you_mean(name, SUMMARIES)}",
                             "summaries")
    record = simulate(_scene(scene, overrides, source), trajectory)
    return evaluate(summaries, record)


def one_line(exc: BaseException) -> str:
    """``Type: message`` of an exception on one line (the message alone for hsgran's own)."""
    text = " ".join(str(exc).split())
    if isinstance(exc, HsgranError):
        return text
    return f"{exc.__class__.__name__}: {text}" if text else exc.__class__.__name__


def execute_case(task: dict) -> dict:
    """Run one case of ``hsgran sweep`` and write its row file; never raises for the case.

    Args:
        task: ``scene_text``, ``source``, ``overrides``, ``summaries``, ``row`` (row file to
            write, or ``None``), ``trajectory`` (file or ``None``), ``retry`` (rerun a case whose
            row file records a failure) and ``row_base`` (case id, index, parameters and
            seed, copied into the row).

    Returns:
        The row: ``row_base`` plus ``status`` ("ok" or "error"), ``error`` (one line),
        ``summaries``, ``wall_time`` [s], ``host`` and ``pid``; when the row file already
        held the case (see the comment below), that row with ``reused = True``.
    """
    # Dask may run a finished task again when the worker holding its result dies before the
    # client fetched it; the row on disk then already says the case is done.
    if task.get("row"):
        done = store.read_row(task["row"])
        if store.is_done(done, task["summaries"], retry_failed=bool(task.get("retry"))):
            return {**done, **task["row_base"], "reused": True}
    t0 = time.perf_counter()
    row = dict(task["row_base"])
    try:
        scene = parse_scene(task["scene_text"], source=task["source"],
                            overrides=task["overrides"])
        record = simulate(scene, task.get("trajectory"))
        row.update(status="ok", error="", summaries=evaluate(task["summaries"], record))
    except Exception as exc:  # a failing case is a row, not a failed sweep
        row.update(status="error", error=one_line(exc), summaries={},
                   traceback="" if isinstance(exc, HsgranError) else traceback.format_exc())
    row.update(wall_time=time.perf_counter() - t0, host=socket.gethostname(), pid=os.getpid())
    if task.get("row"):
        store.write_row(task["row"], row)
    return row
