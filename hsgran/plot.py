"""Plots of a trajectory with matplotlib: ``hsgran plot`` (layer 6).

One figure: the energies against time (translational and rotational kinetic energy, the change
of potential energy since the start, the energy dissipated so far, with outlets the energy
carried out of the system, and their sum, which stays at the initial kinetic energy: the
dissipated energy is what the mechanical energy lost); and, for
a few particles, their height, speed and spin against time with the collisions and
motion-state changes of the event log marked on each curve. matplotlib is used through its
object interface with the Agg canvas, so nothing touches pyplot's global state or needs a
display.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import tomllib
from pathlib import Path

import numpy as np

from hsgran.errors import InputError, MissingDependency
from hsgran.events.kinds import EV_EXIT, EV_LAND, EV_PAIR, EV_STATE, EV_WALL, EV_WEDGE
from hsgran.io.h5md import read_trajectory
from hsgran.observables import interval_observables

#: Scenes with at most this many particles get the per-particle panels by default; more lines
#: than this are hard to tell apart.
FEW_PARTICLES = 10
#: Most particles ``--particles`` may pick (one line and colour each).
MAX_PARTICLES = 50
#: Most events marked on the curves: beyond this the markers merge into a smear that hides the
#: curves, and the figure says how many there were instead.
MAX_MARKED_EVENTS = 2000
#: Figure width and height of one panel [inch], and resolution of raster output [dpi].
FIGURE_WIDTH, PANEL_HEIGHT, DPI = 10.0, 2.6, 120
#: Figure formats by extension (all native to matplotlib's Agg/PDF/SVG canvases).
FORMATS = {".png": "png", ".pdf": "pdf", ".svg": "svg"}
#: Marker of each event kind: (kind, label, matplotlib marker).
EVENT_MARKERS = ((EV_PAIR, "sphere-sphere collision", "o"),
                 (EV_WALL, "wall collision", "v"),
                 (EV_STATE, "motion-state change", "d"),
                 (EV_LAND, "landing", "s"),
                 (EV_WEDGE, "stopped in a wedge", "x"),
                 (EV_EXIT, "left through an outlet", "*"))

#: Figure of a sweep's results folder when no output is given.
SWEEP_FIGURE = "summary.png"

ENERGY_CURVES = (("kinetic_energy_translational", "translational kinetic", "C0"),
                 ("kinetic_energy_rotational", "rotational kinetic", "C1"),
                 ("potential_energy", "potential (change since start)", "C2"),
                 ("dissipated_energy", "dissipated", "C3"),
                 ("exited_energy", "carried out through outlets", "C4"))


def _import_matplotlib():
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        raise MissingDependency("plotting needs matplotlib (the 'render' extra): "
                                "pip install -e '.[render]'") from None
    return Figure, FigureCanvasAgg


def select_particles(particles, n: int) -> list[int]:
    """Particles to plot against time.

    Args:
        particles: ``None`` (all when N ≤ :data:`FEW_PARTICLES`, else none), ``"all"``,
            ``"none"``, comma-separated indices, or a sequence of ints.
        n: Number of particles N.

    Returns:
        Sorted distinct indices.

    Raises:
        InputError: naming ``--particles``.
    """
    if particles is None:
        return list(range(n)) if n <= FEW_PARTICLES else []
    if isinstance(particles, str):
        text = particles.strip().lower()
        if text == "none":
            return []
        if text == "all":
            chosen = list(range(n))
        else:
            try:
                chosen = [int(p) for p in text.split(",") if p.strip()]
            except ValueError:
                raise InputError(f"expected comma-separated particle indices, 'all' or 'none', "
                                 f"got {particles!r}", "--particles") from None
    else:
        chosen = [int(p) for p in particles]
    bad = [p for p in chosen if not 0 <= p < n]
    if bad:
        raise InputError(f"particle {bad[0]} does not exist (the trajectory has {n}: 0 to "
                         f"{n - 1})", "--particles")
    chosen = sorted(set(chosen))
    if len(chosen) > MAX_PARTICLES:
        raise InputError(f"at most {MAX_PARTICLES} particles, got {len(chosen)}",
                         "--particles")
    return chosen


def _scene_name(scene_text: str) -> str:
    try:
        return str(tomllib.loads(scene_text).get("scene", {}).get("name", ""))
    except (tomllib.TOMLDecodeError, AttributeError):
        return ""


def figure(traj, particles: list[int], title: str = ""):
    """The matplotlib Figure of a trajectory.

    Args:
        traj: A :class:`hsgran.io.h5md.Trajectory`.
        particles: Particles whose height, speed and spin are drawn (may be empty).
        title: Figure title.

    Returns:
        A :class:`matplotlib.figure.Figure` (Agg canvas attached).
    """
    Figure, FigureCanvasAgg = _import_matplotlib()
    histories = []
    if particles:
        histories = [("height z [m]", traj.position[:, :, 2]),
                     ("speed [m/s]", np.linalg.norm(traj.velocity, axis=2))]
        if traj.angular_velocity is not None:
            histories.append(("spin |ω| [rad/s]", np.linalg.norm(traj.angular_velocity, axis=2)))
    observed = interval_observables(traj) if traj.sums and traj.n_frames >= 2 else None
    extra = 0 if observed is None else (1 if observed.pressure is None else 2)
    rows = 1 + extra + len(histories)
    fig = Figure(figsize=(FIGURE_WIDTH, PANEL_HEIGHT * rows + 0.8), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    t = traj.time
    _energy_panel(axes[0], traj)
    if observed is not None:
        _observables_panels(axes[1:1 + extra], observed)
        axes = np.concatenate([axes[:1], axes[1 + extra:]])
    notes = []
    events = _events_of(traj, particles) if particles else None
    if particles and traj.events is None:
        notes.append("no event log: run with 'hsgran run --events' to mark collisions")
    elif events is not None and events["time"].shape[0] > MAX_MARKED_EVENTS:
        notes.append(f"{events['time'].shape[0]:,} events of these particles: too many to mark "
                     f"(limit {MAX_MARKED_EVENTS:,})")
        events = None
    for ax, (label, values) in zip(axes[1:], histories, strict=True):
        for k, p in enumerate(particles):
            color = f"C{k % 10}"
            ax.plot(t, values[:, p], color=color, lw=1.4, label=f"particle {p}")
            if events is not None:
                _mark_events(ax, t, values[:, p], events, p, color)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    if histories:
        handles, labels = axes[1].get_legend_handles_labels()
        if events is not None:
            handles, labels = _event_legend(axes[1], events, handles, labels)
        axes[1].legend(handles, labels, fontsize="small", loc="best",
                       ncol=2 if len(labels) > 6 else 1)
    axes[-1].set_xlabel("time [s]")
    heading = title or "trajectory"
    if notes:
        heading += "\n" + "; ".join(notes)
    fig.suptitle(heading, fontsize="medium")
    return fig


def _energy_panel(ax, traj) -> None:
    energies = traj.energies
    t = traj.time
    total = np.zeros_like(t)
    for name, label, color in ENERGY_CURVES:
        if name not in energies:
            continue
        values = np.asarray(energies[name], dtype=float)
        if name == "potential_energy":
            # only changes matter; the absolute value depends on where z = 0 is
            values = values - values[0]
        total += values
        ax.plot(t, values, color=color, lw=1.5, label=label)
    ax.plot(t, total, color="black", lw=1.0, ls="--", label="sum")
    ax.set_ylabel("energy [J]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", loc="best")


def _observables_panels(axes, obs) -> None:
    """The normal force on each plane, and (with a volume) the pressure and its kinetic and
    collisional parts, as steps over the frame intervals (hsgran.observables)."""
    edges = np.append(obs.start, obs.end[-1])
    ax = axes[0]
    for w, key in enumerate(obs.wall_keys):
        push = -obs.wall_force[:, w] @ obs.wall_normals[w]
        ax.stairs(push, edges, lw=1.3, label=key, color=f"C{w % 10}")
    if np.any(obs.unresolved_force):
        ax.stairs(np.linalg.norm(obs.unresolved_force, axis=1), edges, lw=1.0, ls=":",
                  color="gray", label="support not traced to a plane (magnitude)")
    ax.set_ylabel("force on plane,\nnormal [N]")
    ax.grid(True, alpha=0.3)
    if obs.wall_keys or np.any(obs.unresolved_force):
        ax.legend(fontsize="small", loc="best", ncol=2)
    if obs.pressure is None:
        return
    ax = axes[1]
    kinetic = -np.trace(obs.stress_kinetic, axis1=1, axis2=2) / 3
    ax.stairs(kinetic, edges, color="C0", lw=1.2, label="kinetic")
    ax.stairs(obs.pressure - kinetic, edges, color="C1", lw=1.2, label="contacts")
    ax.stairs(obs.pressure, edges, color="black", lw=1.0, ls="--", label="pressure")
    ax.set_ylabel("pressure [Pa]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", loc="best")


def _events_of(traj, particles: list[int]):
    """Events involving the chosen particles (kinds of :data:`EVENT_MARKERS`), or None."""
    ev = traj.events
    if ev is None:
        return None
    kinds = [k for k, _, _ in EVENT_MARKERS]
    chosen = np.array(particles)
    keep = np.isin(ev["kind"], kinds) & (np.isin(ev["i"], chosen) | np.isin(ev["j"], chosen))
    return {name: ev[name][keep] for name in ("time", "kind", "i", "j")}


def _mark_events(ax, t, values, events, particle, color) -> None:
    mine = (events["i"] == particle) | (events["j"] == particle)
    for kind, _, marker in EVENT_MARKERS:
        at = events["time"][mine & (events["kind"] == kind)]
        if at.shape[0]:
            ax.plot(at, np.interp(at, t, values), ls="none", marker=marker, ms=5,
                    mfc="white", mec=color, mew=1.2)


def _event_legend(ax, events, handles, labels):
    from matplotlib.lines import Line2D

    for kind, label, marker in EVENT_MARKERS:
        if np.any(events["kind"] == kind):
            handles.append(Line2D([], [], ls="none", marker=marker, mfc="white", mec="black"))
            labels.append(label)
    return handles, labels


def plot(trajectory, output=None, *, particles=None, force: bool = False) -> Path:
    """Plot a trajectory file, or the results folder of a sweep, to a figure file.

    Args:
        trajectory: HDF5 trajectory written by ``hsgran run``, or a results folder of
            ``hsgran sweep`` (then each summary quantity against the swept keys; see
            :mod:`hsgran.sweep.figure`).
        output: ``.png``, ``.pdf`` or ``.svg``; default: the trajectory's name with ``.png``,
            or ``RESULTS/summary.png``.
        particles: See :func:`select_particles` (trajectories only).
        force: Overwrite an existing output.

    Returns:
        The figure's path.

    Raises:
        InputError: bad option, unreadable or non-hsgran trajectory, existing output without
            ``force``; one line.
        MissingDependency: matplotlib is not installed.
    """
    path = Path(trajectory)
    sweep = path.is_dir()
    if sweep and particles is not None:
        raise InputError("applies to a trajectory, not to a sweep's results folder",
                         "--particles")
    default = path / SWEEP_FIGURE if sweep else path.with_suffix(".png")
    target = default if output is None else Path(output)
    fmt = FORMATS.get(target.suffix.lower())
    if fmt is None:
        raise InputError(f"unknown figure type '{target.suffix or target.name}': use "
                         f"{', '.join(FORMATS)}", "-o")
    if target.is_dir():
        raise InputError(f"{target} is a folder", "-o")
    if not target.parent.is_dir():
        raise InputError(f"folder {target.parent} does not exist", "-o")
    if target.exists() and not force:
        raise InputError(f"{target} exists: pass --force to overwrite it", "-o")
    if sweep:
        from hsgran.sweep.figure import sweep_figure

        fig = sweep_figure(path, _import_matplotlib()[0])
    else:
        traj = read_trajectory(path)
        if traj.n_frames == 0:
            raise InputError(f"{path} has no frames")
        chosen = select_particles(particles, traj.n_particles)
        fig = figure(traj, chosen, title=_scene_name(traj.scene_text) or path.name)
    handle, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".part{target.suffix}",
                                    dir=target.parent)
    os.close(handle)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(name, 0o666 & ~umask)      # mkstemp's file is private; a figure is not
    try:
        fig.savefig(name, format=fmt, dpi=DPI)
        os.replace(name, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(name)
        raise
    return target
