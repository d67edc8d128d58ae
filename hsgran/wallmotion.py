"""When a sphere in flight meets a moving plane (layer 2: kinematics only; docs/walls.md).

The planes' prescribed motions, p(t) = p₀ + d s(t), are defined in :mod:`hsgran.wallspec`
(numbers only, so that files can be read without numba); this module compiles them for the
event loop.

The contact time of a sphere on a parabola with an oscillating plane is the first root of the
gap g(τ) = g₀ + v_n τ + ½ g_n τ² − d·n [s(t₀ + τ) − s(t₀)], a transcendental function.
:func:`moving_plane_contact_time` finds it by conservative advancement (the step to the first
root of a quadratic lower bound of g, whose curvature is at least g_n − |d·n| A ω², so a step
never passes a root), then polishes it with Newton steps (Mirtich, *Impulse-based dynamic
simulation of rigid body systems*, PhD thesis, Berkeley 1996, ch. 3, for the conservative
bound). A piston's gap is a quadratic on each of its three pieces and is solved exactly.
"""

from __future__ import annotations

import math

from hsgran import wallspec
from hsgran._jit import njit
from hsgran.motion import APPROACH_NOISE_ULPS, NEVER, ROUNDOFF, plane_contact_time
from hsgran.wallspec import M_AMP, M_KIND, M_OMEGA, M_PHASE, M_TRAVEL, MOT_VELOCITY

#: Conservative advancement stops when the gap is below this fraction of the radius [-]: the
#: touching tolerance of planes (hsgran._flight.PLANE_TOUCHING_REL); Newton steps then take the
#: time to the root's rounding.
ADVANCE_STOP_REL = 1e-10
#: Newton steps after the advancement. Each squares the relative error of the contact time
#: (from ~1e-10 R / |ġ|): two reach rounding; the third is a margin.
NEWTON_STEPS = 3
#: Most advancement steps of one prediction. A step is at least √(2 g / K) (K the bound of the
#: gap's curvature), so this many steps cover thousands of oscillation periods of a sphere
#: grazing the plane at 1e-10 R. A search that runs out returns the time it reached; the wall
#: handler re-checks the gap there, finds no contact, and predicts again (hsgran._loop).
MAX_ADVANCE_STEPS = 100_000
#: Shortest advancement step, as a phase of the oscillation [rad]: a sphere touching the plane
#: with no relative normal speed at this instant would otherwise step by zero. Within 1e-9/ω
#: the gap can close by at most ½ K (1e-9/ω)² = 5e-19 A, far below any tolerance.
MIN_STEP_PHASE = 1e-9


# the motions themselves are plain Python in hsgran.wallspec (reading and drawing files must
# not import numba); compiled here for the loop
wall_shift = njit(inline="always")(wallspec.wall_shift)
wall_speed = njit(inline="always")(wallspec.wall_speed)


@njit(inline="always")
def _gap(g0, vn, gn, cn, mot, w, t0, s0, tau):
    return g0 + vn * tau + 0.5 * gn * tau * tau - cn * (wall_shift(mot, w, t0 + tau) - s0)


@njit
def _oscillation_contact(g0, vn, gn, cn, mot, w, t0, radius, horizon):
    """First root of the gap with an oscillating plane within ``horizon`` [s] (see module)."""
    s0 = wall_shift(mot, w, t0)
    om = mot[w, M_OMEGA]
    bound = abs(cn) * mot[w, M_AMP] * om * om  # |d·n s̈| ≤ this
    curv = gn - bound  # the gap's curvature is at least this
    stop = ADVANCE_STOP_REL * radius
    min_step = MIN_STEP_PHASE / om
    # an approach below the rounding of the speeds is none (motion.APPROACH_NOISE_ULPS): a
    # sphere that rode the plane leaves it at the plane's speed, and the rounding of that
    # speed must not make a contact of the same instant
    noise = APPROACH_NOISE_ULPS * ROUNDOFF * (abs(vn) + abs(cn) * mot[w, M_AMP] * om)
    tau = 0.0
    g = g0
    for _ in range(MAX_ADVANCE_STEPS):
        slope = vn + gn * tau - cn * wall_speed(mot, w, t0 + tau)
        if g <= stop and slope < -noise:
            break  # touching and approaching: the contact
        step = plane_contact_time(max(g, 0.0), slope, curv)
        if step == NEVER:
            return NEVER
        tau += max(step, min_step)
        if tau > horizon:
            return NEVER
        g = _gap(g0, vn, gn, cn, mot, w, t0, s0, tau)
    else:
        return tau  # grazing for very long: the handler re-checks and predicts again
    for _ in range(NEWTON_STEPS):
        slope = vn + gn * tau - cn * wall_speed(mot, w, t0 + tau)
        if slope >= 0.0:
            break  # at a grazing minimum: the re-check decides
        nxt = tau - g / slope
        if not nxt >= 0.0:
            break
        tau = nxt
        g = _gap(g0, vn, gn, cn, mot, w, t0, s0, tau)
    return tau


@njit
def _piston_contact(g0, vn, gn, cn, mot, w, t0):
    """First root of the gap with a piston: a quadratic on each piece of its motion."""
    speed = mot[w, M_AMP]
    start = mot[w, M_PHASE]
    end = start + mot[w, M_TRAVEL] / speed
    tau0 = 0.0
    g = g0
    v = vn
    for piece in range(3):
        if piece == 0:
            hi, ws = start, 0.0
        elif piece == 1:
            hi, ws = end, speed
        else:
            hi, ws = math.inf, 0.0
        t_now = t0 + tau0
        if t_now >= hi:
            continue
        dt = hi - t_now  # time left in this piece
        # relative to the plane: gap g, normal speed v − d·n ṡ, curvature g_n
        tau = plane_contact_time(g, v - cn * ws, gn)
        if tau <= dt:
            return tau0 + tau
        # to the piece's end
        g = g + (v - cn * ws) * dt + 0.5 * gn * dt * dt
        v = v + gn * dt
        tau0 += dt
    return NEVER


@njit
def moving_plane_contact_time(g0, vn, gn, mot, w, cn, t0, radius, horizon):
    """Time until a sphere in flight touches moving plane w [s from t0], or ``inf``.

    Args:
        g0: Gap to the plane's position at t0, minus the radius [m].
        vn: Sphere's velocity along the normal at t0 [m/s].
        gn: Its acceleration along the normal [m/s²].
        mot: The planes' motion rows (``M_*``).
        w: The plane.
        cn: d·n, the share of the motion along the normal [-].
        t0: Time of the prediction [s].
        radius: The sphere's radius [m] (scale of the stopping tolerance).
        horizon: No root is wanted after this delay [s] (an earlier event comes first).
    """
    if mot[w, M_KIND] == MOT_VELOCITY:
        return _piston_contact(g0, vn, gn, cn, mot, w, t0)
    if cn == 0.0:
        return plane_contact_time(g0, vn, gn)  # it slides along itself: the gap ignores it
    return _oscillation_contact(g0, vn, gn, cn, mot, w, t0, radius, horizon)
