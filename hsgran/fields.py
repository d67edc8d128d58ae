"""Coarse-grained profiles of a trajectory along one axis (layer 6): ``hsgran fields``.

The method is binning with exact volumes: the box is cut into slabs normal to the axis, and
each sphere counts in each slab with the fraction w of its volume that lies there (the volume
of a sphere between two planes, from spherical caps), so a sphere across a slab boundary is
split, not assigned whole to the slab of its centre, and the profiles hold the exact mass. Per
slab and frame, with V_s the slab's volume, m_i the masses and v_i the velocities:

* packing fraction      φ = Σ w_i V_i / V_s;
* velocity              u = Σ w_i m_i v_i / Σ w_i m_i                          [m/s];
* granular temperature  T = Σ w_i m_i |v_i − u|² / (3 Σ w_i m_i)                [m²/s²]
  (the velocity variance per degree of freedom, mass weighted);
* kinetic stress        σ_ab = −Σ w_i m_i (v_i − u)_a (v_i − u)_b / V_s          [Pa]
  (the streaming part only: the collisional part needs the collisions' impulses, which the
  trajectory does not keep).

Each is averaged over the frames of a time window (their standard error across frames is given
too; consecutive frames are correlated, so it is a lower bound). Weinhart et al.'s kernel
coarse-graining (MercuryDPM) smooths with a width instead; slabs are its limit of a box-shaped
kernel along one axis. Periodic axes wrap: a sphere across the cell boundary counts in the slabs
at both ends.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hsgran.errors import InputError
from hsgran.io.h5md import read_trajectory

AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class Profiles:
    """Slab profiles along one axis, averaged over a time window (SI units).

    Attributes:
        axis: "x", "y" or "z".
        edges: Slab boundaries along the axis [m], shape (B + 1,).
        frames: Number of frames averaged.
        packing_fraction, temperature: shape (B,) [-], [m²/s²].
        velocity: shape (B, 3) [m/s].
        kinetic_stress: shape (B, 3, 3) [Pa].
        mass: Mass in each slab [kg], shape (B,) (Σ over slabs: the mass in the box).
        packing_fraction_error, temperature_error: Standard errors across frames.
    """

    axis: str
    edges: np.ndarray
    frames: int
    packing_fraction: np.ndarray
    velocity: np.ndarray
    temperature: np.ndarray
    kinetic_stress: np.ndarray
    mass: np.ndarray
    packing_fraction_error: np.ndarray
    temperature_error: np.ndarray

    @property
    def centres(self) -> np.ndarray:
        """Slab centres [m]."""
        return 0.5 * (self.edges[1:] + self.edges[:-1])


def volume_below(z: np.ndarray, centre: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Volume [m³] of each sphere (centre coordinate and radius along the axis) below the
    plane at ``z`` (a spherical cap: π h² (3R − h)/3 with h the height below the plane)."""
    h = np.clip(z - (centre - radius), 0.0, 2.0 * radius)
    return math.pi * h * h * (3.0 * radius - h) / 3.0


def slab_fractions(edges: np.ndarray, centre: np.ndarray, radius: np.ndarray,
                   period: float | None = None) -> np.ndarray:
    """Fraction of each sphere's volume in each slab, shape (N, B); with ``period`` [m] the
    axis is periodic with that length starting at ``edges[0]`` and spheres are wrapped."""
    vol = 4.0 / 3.0 * math.pi * radius**3
    shifts = (0.0,) if period is None else (-period, 0.0, period)
    frac = np.zeros((centre.shape[0], edges.shape[0] - 1))
    for s in shifts:
        c = centre[:, None] + s
        below = volume_below(edges[None, :], c, radius[:, None])
        frac += np.diff(below, axis=1)
    return frac / vol[:, None]


def profiles(trajectory, axis: str = "z", bins: int = 20, *, start: float | None = None,
             end: float | None = None) -> Profiles:
    """Slab profiles of a trajectory (see the module).

    Args:
        trajectory: A path or a :class:`hsgran.io.h5md.Trajectory` (with a box).
        axis: "x", "y" or "z".
        bins: Number of slabs over the box.
        start, end: Time window [s] (default: every frame).

    Raises:
        InputError: no box, unknown axis, bad bin count or an empty window.
    """
    traj = read_trajectory(trajectory) if not hasattr(trajectory, "position") else trajectory
    if axis not in AXES:
        raise InputError(f"must be one of x, y, z, got {axis!r}", "--axis")
    if not isinstance(bins, int) or bins < 1:
        raise InputError(f"must be a whole number >= 1, got {bins!r}", "--bins")
    if traj.box_lower is None:
        raise InputError("the trajectory has no box: the slabs need its cross-section",
                         "trajectory")
    k = AXES[axis]
    t0 = traj.time[0] if start is None else start
    t1 = traj.time[-1] if end is None else end
    sel = np.flatnonzero((traj.time >= t0) & (traj.time <= t1))
    if sel.size == 0:
        raise InputError(f"no frame between {t0:g} and {t1:g} s", "--from/--to")
    lo, hi = np.asarray(traj.box_lower, float), np.asarray(traj.box_upper, float)
    edges = np.linspace(lo[k], hi[k], bins + 1)
    area = float(np.prod(np.delete(hi - lo, k)))
    slab_v = area * np.diff(edges)
    period = float(hi[k] - lo[k]) if traj.periodic[k] else None
    r, m = traj.radius, traj.mass
    vol = 4.0 / 3.0 * math.pi * r**3
    per = {name: [] for name in ("phi", "u", "T", "sigma", "mass")}
    # (a stand-in without the attribute holds only particles in the system)
    present = getattr(traj, "present", np.ones(traj.position.shape[:2], dtype=bool))
    for f in sel:
        # a sphere that has left the system (NaN, docs/open-systems.md) weighs nothing
        here = present[f]
        w = slab_fractions(edges, np.where(here, traj.position[f, :, k], lo[k]), r, period)
        w[~here] = 0.0
        wm = w * m[:, None]
        mass = wm.sum(axis=0)
        safe = np.where(mass > 0.0, mass, 1.0)
        v = np.where(here[:, None], traj.velocity[f], 0.0)
        u = (wm.T @ v) / safe[:, None]
        dv = v[:, None, :] - u[None, :, :]  # (N, B, 3)
        sig = -np.einsum("nb,nbi,nbj->bij", wm, dv, dv) / slab_v[:, None, None]
        temp = np.einsum("nb,nbi,nbi->b", wm, dv, dv) / (3.0 * safe)
        per["phi"].append((w * vol[:, None]).sum(axis=0) / slab_v)
        per["u"].append(np.where(mass[:, None] > 0.0, u, np.nan))
        per["T"].append(np.where(mass > 0.0, temp, np.nan))
        per["sigma"].append(sig)
        per["mass"].append(mass)
    arr = {name: np.array(vals) for name, vals in per.items()}
    n = sel.size

    def err(a):
        return a.std(axis=0, ddof=1) / math.sqrt(n) if n > 1 else np.full(a.shape[1:], np.nan)

    return Profiles(axis, edges, n, arr["phi"].mean(axis=0), np.nanmean(arr["u"], axis=0),
                    np.nanmean(arr["T"], axis=0), arr["sigma"].mean(axis=0),
                    arr["mass"].mean(axis=0), err(arr["phi"]), err(arr["T"]))


def table(p: Profiles) -> str:
    """The profiles as a text table (one row per slab)."""
    k = AXES[p.axis]
    lines = [f"# {p.frames} frames; slabs along {p.axis}; T = velocity variance per degree of "
             "freedom; sigma = kinetic stress (streaming part)",
             f"{p.axis + ' [m]':>12} {'phi':>10} {'+-':>9} {'u_' + p.axis + ' [m/s]':>12} "
             f"{'T [m2/s2]':>11} {'+-':>9} {'sigma_' + p.axis * 2 + ' [Pa]':>14}"]
    for b in range(p.centres.shape[0]):
        lines.append(f"{p.centres[b]:12.6g} {p.packing_fraction[b]:10.5f} "
                     f"{p.packing_fraction_error[b]:9.2g} {p.velocity[b, k]:12.5g} "
                     f"{p.temperature[b]:11.5g} {p.temperature_error[b]:9.2g} "
                     f"{p.kinetic_stress[b, k, k]:14.6g}")
    return "\n".join(lines)


def write_csv(p: Profiles, path) -> None:
    """The profiles as CSV: slab centre and edges [m], every field (SI units)."""
    import csv

    with open(path, "w", newline="", encoding="utf-8") as f:
        out = csv.writer(f)
        out.writerow(["centre_m", "lower_m", "upper_m", "packing_fraction",
                      "packing_fraction_error", "u_x_m_s", "u_y_m_s", "u_z_m_s",
                      "temperature_m2_s2", "temperature_error",
                      *[f"sigma_{a}{b}_Pa" for a in "xyz" for b in "xyz"], "mass_kg"])
        for b in range(p.centres.shape[0]):
            out.writerow([repr(float(x)) for x in (
                p.centres[b], p.edges[b], p.edges[b + 1], p.packing_fraction[b],
                p.packing_fraction_error[b], *p.velocity[b], p.temperature[b],
                p.temperature_error[b], *p.kinetic_stress[b].ravel(), p.mass[b])])
