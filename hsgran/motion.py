"""Free flight and every "when" question of the event loop (layer 2: kinematics only).

Between events a sphere follows an exact parabola x(τ) = x0 + v τ + ½ g τ² (a straight line
without gravity). Two spheres under the same gravity move linearly relative to each other, so
their contact time is the root of a quadratic; so are the times at which a sphere reaches a plane
or a cell face. Every such question reduces to :func:`upward_root`: the first time a quadratic
``c + b τ + ½ a τ²`` crosses zero going up.

All functions are compiled and take scalars; ``inf`` means "never".
"""

from __future__ import annotations

import math

from hsgran._jit import njit

NEVER = math.inf


@njit
def upward_root(c, b, a):
    """First τ ≥ 0 at which f(τ) = c + b τ + ½ a τ² crosses zero with f' > 0.

    A slightly positive ``c`` (round-off has already carried the point past the crossing) is
    treated as zero, so a crossing that is under way happens now (τ = 0) instead of being lost.

    Args:
        c: f(0) (should be ≤ 0).
        b: f'(0).
        a: f'' (constant).

    Returns:
        τ ≥ 0, or ``inf`` if f never crosses zero upwards.

    Notes:
        The two roots are τ± = (−b ± s)/a with s² = b² − 2 a c, and f'(τ±) = ±s, so the upward
        crossing is always τ+. For b ≥ 0 it is evaluated as −2c/(b + s) to avoid cancellation.
    """
    if c > 0.0:
        c = 0.0
    if a == 0.0:
        if b > 0.0:
            return -c / b
        return NEVER
    disc = b * b - 2.0 * a * c
    if disc < 0.0:
        return NEVER
    s = math.sqrt(disc)
    if b >= 0.0:
        den = b + s
        if den > 0.0:
            return -2.0 * c / den
        return 0.0 if a > 0.0 else NEVER  # c = b = 0: f = ½ a τ²
    if a > 0.0:
        return (s - b) / a
    return NEVER


@njit
def flight_position(x0, v0, g, dt):
    """Coordinate after a free flight of ``dt`` [s]: x0 + v0 dt + ½ g dt² [m]."""
    return x0 + dt * (v0 + 0.5 * g * dt)


@njit
def pair_contact_time(rx, ry, rz, wx, wy, wz, sigma):
    """Time until two spheres in free flight touch.

    Args:
        rx, ry, rz: Relative position x_i − x_j at a common instant [m].
        wx, wy, wz: Relative velocity v_i − v_j [m/s] (constant: gravity cancels).
        sigma: Contact distance R_i + R_j [m].

    Returns:
        Delay τ ≥ 0 [s] until |r + w τ| = σ while approaching, or ``inf``.
    """
    rr = rx * rx + ry * ry + rz * rz
    rw = rx * wx + ry * wy + rz * wz
    if rw >= 0.0:
        return NEVER  # separating or sliding past: no approach
    ww = wx * wx + wy * wy + wz * wz
    # f(τ) = σ² − |r + wτ|² crosses zero upwards at contact
    return upward_root(sigma * sigma - rr, -2.0 * rw, -2.0 * ww)


@njit
def pair_contact_before(rx, ry, rz, wx, wy, wz, sigma, horizon):
    """:func:`pair_contact_time`, but ``inf`` for any contact not before ``horizon`` [s].

    The event loop only needs a pair's contact time if it beats the best event found so far.
    The quadratic f(τ) = σ² − |r + wτ|² has its peak at τ* = −r·w/|w|²; if f(horizon) < 0 and
    the peak lies at or after the horizon, f is still below zero and rising there, so there is
    no contact before the horizon: a square root and a division are saved.
    """
    rr = rx * rx + ry * ry + rz * rz
    rw = rx * wx + ry * wy + rz * wz
    if rw >= 0.0:
        return NEVER
    ww = wx * wx + wy * wy + wz * wz
    c = sigma * sigma - rr
    if horizon < NEVER and -rw >= ww * horizon and c - horizon * (2.0 * rw + ww * horizon) < 0.0:
        return NEVER
    return upward_root(c, -2.0 * rw, -2.0 * ww)


@njit
def plane_contact_time(gap, vn, gn):
    """Time until a sphere in free flight touches a plane.

    Args:
        gap: Distance from the plane minus the radius [m] (≥ 0 when not touching).
        vn: Velocity component along the plane normal [m/s].
        gn: Gravity component along the plane normal [m/s²].

    Returns:
        Delay τ ≥ 0 [s] until the gap closes while approaching, or ``inf``.
    """
    return upward_root(-gap, -vn, -gn)


@njit
def face_exit_time(x, v, g, lo, hi):
    """Time until a coordinate in free flight leaves the interval [lo, hi], and which side.

    Args:
        x, v, g: Coordinate [m], velocity [m/s] and acceleration [m/s²] along one axis.
        lo, hi: Interval bounds [m].

    Returns:
        (τ [s], side): side = +1 through ``hi``, −1 through ``lo``; (``inf``, 0) if never.
    """
    t_hi = upward_root(x - hi, v, g)
    t_lo = upward_root(lo - x, -v, -g)
    if t_hi <= t_lo:
        if t_hi == NEVER:
            return NEVER, 0
        return t_hi, 1
    return t_lo, -1
