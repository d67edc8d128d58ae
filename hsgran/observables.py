"""Stress, pressure, wall forces and collision rates of every frame interval, from the sums the
event loop wrote (layer 6; ``hsgran observables``; docs/observables.md).

A scene with ``[output] observables = true`` has, for the interval that each frame closes, the
moment Σ b ⊗ J of every contact impulse, the impulse each plane took and the number of
collisions (:mod:`hsgran._observe`: exact, no sampling). This module divides them by the
interval and the volume:

- collisional stress σ_c = −Σ b ⊗ J / (V τ) [Pa];
- kinetic stress σ_k = −Σ m (v − ū) ⊗ (v − ū) / V [Pa], with ū the mean (mass-weighted)
  velocity, the mean of its values at the interval's two frames (exact when the velocities
  change only at collisions and the kinetic energy is conserved, as in an elastic gas;
  otherwise a trapezoid rule over the frames);
- stress σ = σ_k + σ_c, pressure p = −tr σ / 3 [Pa]; tensile stress is positive, as in
  :mod:`hsgran.fields` (Allen & Tildesley, *Computer Simulation of Liquids*, 2nd ed., §2.4);
- the force on each plane, its impulse over τ [N], and the collision rates [1/s].
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass

import numpy as np

from hsgran.errors import InputError


@dataclass(frozen=True)
class IntervalObservables:
    """The observables of K frame intervals (interval k ends at frame k + 1).

    Attributes:
        start, end: Interval bounds [s], shape (K,).
        volume: The volume the stress refers to [m³], or ``None`` when the trajectory has no
            box and none was given (then the stresses and pressure are ``None``).
        stress_kinetic, stress_collisional, stress: [Pa], shape (K, 3, 3), or ``None``.
        pressure: −tr(stress) / 3 [Pa], shape (K,), or ``None``.
        wall_force: Time-average force on each plane [N], shape (K, W, 3).
        wall_keys: The scene key of each plane (``walls[0].lower_z`` …).
        wall_normals: Each plane's unit normal, towards the spheres, shape (W, 3).
        unresolved_force: Support force on spheres not traced to a plane [N], shape (K, 3).
        pair_rate, wall_rate: Pair and plane collisions per second [1/s], shape (K,).
    """

    start: np.ndarray
    end: np.ndarray
    volume: float | None
    stress_kinetic: np.ndarray | None
    stress_collisional: np.ndarray | None
    stress: np.ndarray | None
    pressure: np.ndarray | None
    wall_force: np.ndarray
    wall_keys: list[str]
    wall_normals: np.ndarray
    unresolved_force: np.ndarray
    pair_rate: np.ndarray
    wall_rate: np.ndarray


def box_volume(traj) -> float | None:
    """The volume of the trajectory's box [m³], or ``None`` without a box."""
    if traj.box_lower is None:
        return None
    return float(np.prod(np.asarray(traj.box_upper) - np.asarray(traj.box_lower)))


def kinetic_stress(mass, velocity, volume: float) -> np.ndarray:
    """−Σ m (v − ū) ⊗ (v − ū) / V [Pa] of each frame.

    Args:
        mass: [kg], shape (N,).
        velocity: [m/s], shape (F, N, 3).
        volume: [m³].

    Returns:
        Shape (F, 3, 3).
    """
    mass = np.asarray(mass, dtype=float)
    mean = np.einsum("n,fnk->fk", mass, velocity) / mass.sum()
    dv = velocity - mean[:, None, :]
    return -np.einsum("n,fnk,fnl->fkl", mass, dv, dv) / volume


def interval_observables(traj, volume: float | None = None) -> IntervalObservables:
    """The observables of every frame interval of a trajectory (see the module's docstring).

    Args:
        traj: A :class:`hsgran.io.h5md.Trajectory` of a run with ``[output] observables``.
        volume: The volume the stress refers to [m³]; default the box's.

    Raises:
        InputError: The run did not sum the observables, it has fewer than two frames, or
            ``volume`` is not positive.
    """
    if not traj.sums:
        raise InputError("the trajectory has no observables: run the scene with "
                         "'[output] observables = true'", "output.observables")
    if traj.n_frames < 2:
        raise InputError(f"the trajectory has {traj.n_frames} frame(s); the observables "
                         "need at least two")
    if volume is None:
        volume = box_volume(traj)
    elif not (np.isfinite(volume) and volume > 0):
        raise InputError(f"must be a positive volume in m³, got {volume}", "volume")
    t = np.asarray(traj.time, dtype=float)
    tau = np.diff(t)
    sums = {name: np.asarray(values)[1:] for name, values in traj.sums.items()}
    stress_k = stress_c = stress = pressure = None
    if volume is not None:
        frames = kinetic_stress(traj.mass, traj.velocity, volume)
        stress_k = 0.5 * (frames[:-1] + frames[1:])
        stress_c = -sums["impulse_moment"] / (volume * tau[:, None, None])
        stress = stress_k + stress_c
        pressure = -np.trace(stress, axis1=1, axis2=2) / 3.0
    keys = list(traj.walls.key) if traj.walls is not None else []
    normals = (np.asarray(traj.walls.normal, dtype=float) if traj.walls is not None
               else np.zeros((0, 3)))
    counts = sums["collisions"]
    return IntervalObservables(
        start=t[:-1], end=t[1:], volume=volume, stress_kinetic=stress_k,
        stress_collisional=stress_c, stress=stress, pressure=pressure,
        wall_force=sums["wall_impulse"] / tau[:, None, None], wall_keys=keys, wall_normals=normals,
        unresolved_force=sums["unresolved_support_impulse"] / tau[:, None],
        pair_rate=counts[:, 0] / tau, wall_rate=counts[:, 1] / tau)


def mean_and_error(values, blocks: int = 10) -> tuple[float, float]:
    """Mean of a time series and its standard error from ``blocks`` block averages (Flyvbjerg
    & Petersen, J. Chem. Phys. 91, 461 (1989)): correlated successive values make the naive
    error too small, block means far apart in time are nearly independent.

    Args:
        values: Shape (K,), K ≥ blocks.
        blocks: Number of blocks (≥ 2).
    """
    values = np.asarray(values, dtype=float)
    blocks = min(blocks, values.shape[0])
    if blocks < 2:
        return float(values.mean()), float("nan")
    means = np.array([b.mean() for b in np.array_split(values, blocks)])
    return float(values.mean()), float(means.std(ddof=1) / np.sqrt(blocks))


#: Columns of the table ``hsgran observables`` prints, per interval.
COLUMNS = ("start_s", "end_s", "pressure_Pa", "pressure_kinetic_Pa", "pressure_collisional_Pa",
           "pair_collisions_per_s", "wall_collisions_per_s")


def table_rows(obs: IntervalObservables) -> list[list]:
    """One row per interval: :data:`COLUMNS`, then each plane's force x, y, z [N] and the
    unresolved support force."""
    rows = []
    for k in range(obs.start.shape[0]):
        if obs.pressure is None:
            p = [float("nan")] * 3
        else:
            p = [obs.pressure[k], -np.trace(obs.stress_kinetic[k]) / 3,
                 -np.trace(obs.stress_collisional[k]) / 3]
        rows.append([obs.start[k], obs.end[k], *p, obs.pair_rate[k], obs.wall_rate[k],
                     *obs.wall_force[k].ravel(), *obs.unresolved_force[k]])
    return rows


def header(obs: IntervalObservables) -> list[str]:
    """Column names of :func:`table_rows`."""
    walls = [f"{key}_F{axis}_N" for key in obs.wall_keys for axis in "xyz"]
    return [*COLUMNS, *walls, "unresolved_Fx_N", "unresolved_Fy_N", "unresolved_Fz_N"]


def write_csv(obs: IntervalObservables, path) -> None:
    """Every interval as a CSV row (:func:`header`), written whole or not at all."""
    tmp = f"{path}.part"
    with open(tmp, "w", newline="", encoding="utf-8") as out:
        writer = csv.writer(out)
        writer.writerow(header(obs))
        writer.writerows([[f"{v:.10g}" for v in row] for row in table_rows(obs)])
    os.replace(tmp, path)


def summary(obs: IntervalObservables, start: float = 0.0) -> str:
    """Each quantity's mean over the intervals that start at or after ``start`` [s], with its
    standard error (:func:`mean_and_error`), as text."""
    keep = [row for row in table_rows(obs) if row[0] >= start]
    if not keep:
        raise InputError(f"no interval starts at or after {start} s", "--from")
    data = np.array(keep)
    volume = f"volume {obs.volume:.6g} m³" if obs.volume else "no volume (no stress)"
    lines = [f"{len(keep)} intervals from {data[0, 0]:.6g} s to {data[-1, 1]:.6g} s, {volume}"]
    for k, name in enumerate(header(obs)[2:], start=2):
        mean, err = mean_and_error(data[:, k])
        lines.append(f"  {name:<34s} {mean:14.6g} ± {err:.2g}")
    return "\n".join(lines)
