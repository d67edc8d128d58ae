"""Outlets: regions of space where spheres leave the system (layer 2: kinematics only;
docs/open-systems.md).

An outlet is a region; a sphere leaves when its centre enters it. Two kinds:

- ``OUT_BELOW``: the half-space behind a plane, {x : (x − p)·n < 0}, with n the plane's unit
  normal pointing away from the outlet (towards the spheres that stay);
- ``OUT_BOX``: an axis-aligned box, {x : lo ≤ x ≤ hi}.

Each outlet is one row of ``OL_*`` values (``Walls.outlets`` of the engine). The time at which a
sphere in free flight (a parabola) enters one is exact: a root of a quadratic per plane or
face (:func:`hsgran.motion.upward_root`), never a sampled test.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit
from hsgran.motion import NEVER, upward_root

OUT_BELOW = 0  #: the half-space behind a plane
OUT_BOX = 1  #: an axis-aligned box

OL_KIND = 0  #: OUT_* code (stored as a float)
#: columns 1–3: a point of the plane (OUT_BELOW) or the box's lower corner (OUT_BOX) [m]
OL_A = 1
#: columns 4–6: the plane's unit normal, pointing away from the outlet (OUT_BELOW), or the box's
#: upper corner (OUT_BOX) [m]
OL_B = 4
OL_SIZE = 7

#: A point closer to a box face than this fraction of the box's size (plus its coordinates'
#: size) counts as on the face when a sphere's entry through another face is checked: a sphere
#: that enters through an edge or a corner reaches two or three faces at one instant, and the
#: two roots agree only to rounding (~1e-16 relative).
BOX_EDGE_REL = 1e-12


@njit(inline="always")
def _inside_slab(x, lo, hi, slack):
    return lo - slack <= x <= hi + slack


@njit
def outlet_entry_time(x, y, z, u, v, w, gx, gy, gz, outlets, o):
    """Delay τ ≥ 0 [s] until the centre of a sphere in free flight enters outlet o, or ``inf``.

    The centre moves on x(τ) = x + u τ + ½ g τ² (positions [m], velocities [m/s],
    accelerations [m/s²]). A centre already inside enters now (τ = 0).

    Args:
        x, y, z, u, v, w, gx, gy, gz: The centre's position, velocity and acceleration.
        outlets: The outlet rows, shape (O, OL_SIZE).
        o: Which row.
    """
    a0, a1, a2 = outlets[o, OL_A], outlets[o, OL_A + 1], outlets[o, OL_A + 2]
    b0, b1, b2 = outlets[o, OL_B], outlets[o, OL_B + 1], outlets[o, OL_B + 2]
    if outlets[o, OL_KIND] == OUT_BELOW:
        d = (x - a0) * b0 + (y - a1) * b1 + (z - a2) * b2
        if d <= 0.0:
            return 0.0
        # the signed distance d + vn τ + ½ gn τ² falls through zero: −d rises through it
        return upward_root(-d, -(u * b0 + v * b1 + w * b2), -(gx * b0 + gy * b1 + gz * b2))
    xs = (x, y, z)
    us = (u, v, w)
    gs = (gx, gy, gz)
    los = (a0, a1, a2)
    his = (b0, b1, b2)
    if (_inside_slab(x, a0, b0, 0.0) and _inside_slab(y, a1, b1, 0.0)
            and _inside_slab(z, a2, b2, 0.0)):
        return 0.0
    best = NEVER
    # Each coordinate is a quadratic in τ: it enters its slab rising through lo or falling
    # through hi, at most twice in all. The box is entered at the first such instant at which
    # the other two coordinates are inside their slabs.
    for k in range(3):
        for side in range(2):
            level = los[k] if side == 0 else his[k]
            sign = 1.0 if side == 0 else -1.0  # the slope of an entry: rising through lo
            for r in range(2):
                tau = _root(xs[k] - level, us[k], gs[k], r)
                if not (0.0 <= tau < best) or sign * (us[k] + gs[k] * tau) <= 0.0:
                    continue
                inside = True
                for m in range(3):
                    if m != k:
                        xm = xs[m] + tau * (us[m] + 0.5 * gs[m] * tau)
                        slack = BOX_EDGE_REL * (his[m] - los[m] + abs(los[m]) + abs(his[m]))
                        if not _inside_slab(xm, los[m], his[m], slack):
                            inside = False
                if inside:
                    best = tau
    return best


@njit(inline="always")
def _root(c, b, a, r):
    """Root r (0 or 1) of c + b τ + ½ a τ² = 0 [s], or NaN (no real root, or no second one);
    evaluated without cancellation."""
    if a == 0.0:
        if r == 0 and b != 0.0:
            return -c / b
        return math.nan
    disc = b * b - 2.0 * a * c
    if disc < 0.0:
        return math.nan
    q = -(b + math.sqrt(disc)) if b >= 0.0 else -(b - math.sqrt(disc))
    if q == 0.0:
        return 0.0 if r == 0 else np.nan  # c = b = 0
    return q / a if r == 0 else 2.0 * c / q


def inside_outlet(row: np.ndarray, position: np.ndarray) -> np.ndarray:
    """Whether points (..., 3) [m] are inside the outlet of one row (``OL_*`` values)."""
    position = np.asarray(position, dtype=np.float64)
    a = row[OL_A:OL_A + 3]
    b = row[OL_B:OL_B + 3]
    if int(row[OL_KIND]) == OUT_BELOW:
        return (position - a) @ b <= 0.0
    return np.all((position >= a) & (position <= b), axis=-1)
