"""A sphere riding a moving plane (layer 5; compiled kernels of the event loop, used by
:mod:`hsgran._flight` and :mod:`hsgran._loop`; docs/walls.md, "Riding a moving plane").

A plane with a prescribed motion p(t) = p₀ + d s(t) (:mod:`hsgran.wallspec`) holds spheres as a
fixed plane does [OURS]. In the frame moving with the plane a sphere feels the effective
gravity g − d s̈(t), so its normal load per unit mass is

    λ(t) = −g·n + (d·n) s̈(t)

(:func:`ride_load`). While λ > 0 it rests, rolls or slides on the plane (MODEL §5.3 through
:func:`hsgran.onplane.plane_segment`, in the plane's frame); where λ falls to zero it takes off:
on a plate vibrating along its normal, at the phase where the plate's downward acceleration
reaches gravity's normal component, Γ = A ω² |d·n| / (−g·n) = 1 (:func:`takeoff_delay`, in
closed form).

The loop moves every sphere on a parabola, so a rider moves in *segments* of constant
acceleration. A segment on an oscillating plane lasts at most :data:`RIDE_STEP` of a radian of
the oscillation. Its accelerations are:

- in the plane, the relative acceleration of ``plane_segment`` under the effective gravity at
  the segment's middle, plus the plane's mean acceleration over the segment along d's
  in-plane part (so the frame's in-plane velocity is exact at the segment's end);
- along n, the largest (d·n) s̈ over the segment, so the sphere's parabola never dips below
  the plane: it hovers at most ½ |d·n| A RIDE_STEP³ above it.

At the segment's end the sphere is put back on the plane with the plane's normal velocity,
and the next segment starts. A piston's acceleration is zero while it moves, so a segment on a
piston is exact; it ends where the piston starts or stops (``END_TAKEOFF``): the sphere then
flies, and a piston that starts into it hits it at once (the contact search of
:mod:`hsgran.wallmotion`).

A sphere at rest relative to the plane is in the rolling state, as one carried round by a
turning cylinder: it moves, so the rules for spheres at rest (sleepers, hsgran._settling) do
not apply to it.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit
from hsgran._state import F_CHI, S_R, S_V
from hsgran.materials import P_MU_R, P_MU_S, SOLID_SPHERE_INERTIA
from hsgran.motion import NEVER, plane_gap
from hsgran.onplane import END_NONE, END_SLIP, MS_REST, MS_ROLLING, plane_segment
from hsgran.wallmotion import wall_shift, wall_speed
from hsgran.wallspec import (
    M_AMP,
    M_DIR,
    M_KIND,
    M_OMEGA,
    M_PHASE,
    M_TRAVEL,
    MOT_OSCILLATION,
    MOT_VELOCITY,
)

#: Longest segment on an oscillating plane, as a phase of the oscillation [rad]. Within it the
#: plane's acceleration changes by at most A ω² RIDE_STEP, so the sphere, whose normal
#: acceleration is the segment's largest, hovers at most ½ |d·n| A RIDE_STEP³ = 5e-7 A above
#: the plane (0.4 nm on a plate vibrating at A = 0.8 mm) and its normal speed differs from
#: the plane's by at most A ω RIDE_STEP² = 1e-4 A ω before the segment's end puts it back;
#: the load on the friction, taken at the segment's middle, errs by O(RIDE_STEP²) = 1e-4 of
#: A ω² |d·n|. 628 segments per period: 12,600 segment ends per second on a plate at 20 Hz.
RIDE_STEP = 1e-2
#: Relative margin on the segment's normal acceleration beyond the plane's largest [-]: the
#: rounding of the sine and of the products (~1e-16) is covered ten thousand times, and the
#: sphere then hovers at most 1e-12 of A ω² τ²/2 more.
RIDE_MARGIN = 1e-12
#: The segment ended after RIDE_STEP: the sphere is put back on the plane and goes on (an
#: ``END_*`` code of hsgran.onplane's family, handled here).
END_RIDE = 6
#: The load reached zero, or a piston started or stopped: the sphere flies from here.
END_TAKEOFF = 7


@njit(inline="always")
def _motion_along_normal(walls, w):
    """d·n of moving plane w: the share of its motion along its normal [-]."""
    mot, n = walls.planes_mot, walls.planes_n
    return mot[w, M_DIR] * n[w, 0] + mot[w, M_DIR + 1] * n[w, 1] + mot[w, M_DIR + 2] * n[w, 2]


@njit(inline="always")
def moving_gap(x, y, z, r, walls, w, t):
    """Gap [m] between a sphere of radius r [m] at (x, y, z) [m] and moving plane w at time t
    [s], and d·n, the share of the plane's motion along its normal."""
    cn = _motion_along_normal(walls, w)
    return (plane_gap(x, y, z, r, walls.planes_p, walls.planes_n, w)
            - cn * wall_shift(walls.planes_mot, w, t)), cn


@njit(inline="always")
def wall_acceleration(mot, w, t):
    """s̈(t) [m/s²] of moving plane w at time t [s] (a piston: zero; its starts and stops end
    segments instead)."""
    if mot[w, M_KIND] == MOT_OSCILLATION:
        om = mot[w, M_OMEGA]
        return -mot[w, M_AMP] * om * om * math.sin(om * t + mot[w, M_PHASE])
    return 0.0


@njit(inline="always")
def ride_load(gravity, walls, w, t):
    """Normal load per unit mass λ(t) = −g·n + (d·n) s̈(t) [m/s²] of a sphere on moving plane w
    at time t [s]; it rides while λ > 0."""
    n = walls.planes_n
    gn = -(gravity[0] * n[w, 0] + gravity[1] * n[w, 1] + gravity[2] * n[w, 2])
    return gn + _motion_along_normal(walls, w) * wall_acceleration(walls.planes_mot, w, t)


@njit(inline="always")
def relative_normal_speed(vx, vy, vz, walls, w, t):
    """Normal speed [m/s] of a sphere moving at (vx, vy, vz) [m/s] relative to moving plane w
    at time t [s] (positive: moving off it)."""
    n = walls.planes_n
    vn = vx * n[w, 0] + vy * n[w, 1] + vz * n[w, 2]
    return vn - _motion_along_normal(walls, w) * wall_speed(walls.planes_mot, w, t)


@njit
def takeoff_delay(gravity, walls, w, t):
    """Delay [s] from t [s] until a sphere riding moving plane w takes off: 0 if the load
    λ(t) is not positive now, ``inf`` if it never fails.

    On an oscillating plane λ(θ) = G − (d·n) A ω² sin θ with θ = ω t + φ and G = −g·n. With
    σ = sign(d·n) and ψ = θ (σ > 0) or θ + π, λ ≤ 0 where sin ψ ≥ κ = G/(|d·n| A ω²): on
    [asin κ, π − asin κ] modulo 2π. A piston's load is G until it starts or stops."""
    n, mot = walls.planes_n, walls.planes_mot
    big_g = -(gravity[0] * n[w, 0] + gravity[1] * n[w, 1] + gravity[2] * n[w, 2])
    if big_g <= 0.0:
        return 0.0
    if mot[w, M_KIND] == MOT_VELOCITY:
        start = mot[w, M_PHASE]
        end = start + mot[w, M_TRAVEL] / mot[w, M_AMP]
        if t < start:
            return start - t
        if t < end:
            return end - t
        return NEVER
    cn = _motion_along_normal(walls, w)
    om = mot[w, M_OMEGA]
    reach = abs(cn) * mot[w, M_AMP] * om * om
    if big_g >= reach:
        return NEVER  # Γ ≤ 1: the plane never pulls away faster than gravity
    kappa = big_g / reach
    rise = math.asin(kappa)
    psi = om * t + mot[w, M_PHASE] + (0.0 if cn > 0.0 else math.pi)
    m = (psi - rise) % (2.0 * math.pi)
    if m <= math.pi - 2.0 * rise:
        return 0.0  # in the window where the plane pulls away
    return (2.0 * math.pi - m) / om


@njit(inline="always")
def _max_sin(a, b):
    """The largest sin θ on [a, b] [rad]."""
    top = math.ceil((a - 0.5 * math.pi) / (2.0 * math.pi)) * 2.0 * math.pi + 0.5 * math.pi
    if top <= b:
        return 1.0
    return max(math.sin(a), math.sin(b))


@njit(inline="always")
def _normal_acceleration(walls, w, cn, t, h):
    """The largest (d·n) s̈ [m/s²] of oscillating plane w over [t, t + h] [s], with its margin."""
    mot = walls.planes_mot
    om = mot[w, M_OMEGA]
    reach = abs(cn) * mot[w, M_AMP] * om * om
    # (d·n) s̈ = −(d·n) A ω² sin θ: its largest is |d·n| A ω² times the largest of −σ sin θ
    shift = math.pi if cn > 0.0 else 0.0
    theta = om * t + mot[w, M_PHASE] + shift
    return reach * (_max_sin(theta, theta + om * h) + RIDE_MARGIN)


@njit(inline="always")
def snap_to_plane(i, w, t, st, walls, with_speed=True):
    """Put sphere i on moving plane w at time t [s]: no gap, and (``with_speed``) the plane's
    normal speed."""
    n = walls.planes_n
    gap, _ = moving_gap(st[i, 0], st[i, 1], st[i, 2], st[i, S_R], walls, w, t)
    vn = relative_normal_speed(st[i, 3], st[i, 4], st[i, 5], walls, w, t) if with_speed else 0.0
    for k in range(3):
        st[i, k] -= gap * n[w, k]
        st[i, S_V + k] -= vn * n[w, k]


@njit(inline="always")
def leave_ride(i, w, t, st, walls):
    """Sphere i takes off from moving plane w at time t [s]: it is put on the plane; on an
    oscillating plane it also takes the plane's normal speed (continuous there), and from a
    piston that starts or stops it keeps the speed it rode at (the piston's before t)."""
    snap_to_plane(i, w, t, st, walls, walls.planes_mot[w, M_KIND] == MOT_OSCILLATION)


@njit
def carry_along(p, t, st, omg, walls, w, rotation):
    """Sphere p stops relative to moving plane w at time t [s]: it moves with the plane (velocity
    d ṡ(t)) and does not spin."""
    speed = wall_speed(walls.planes_mot, w, t)
    for k in range(3):
        st[p, S_V + k] = speed * walls.planes_mot[w, M_DIR + k]
        if rotation:
            omg[p, k] = 0.0


# long: one segment on a moving plane, from the checks of the load through the plane's frame
# to the three parts of the acceleration; its steps share the frame's speeds and the normal
@njit
def enter_ride(i, w, t, snap, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling,
               rotation):
    """Put sphere i on moving plane w at time t [s], or start its next segment there (see the
    module's docstring). ``snap``: the transition that ended the last segment (``END_*``).

    Returns:
        False, with nothing changed, if the plane does not press the sphere now (it must fly).
    """
    st, acc, mstate = flight.st, flight.acc, flight.mstate
    mplane, seg_end, seg_code = flight.mplane, flight.seg_end, flight.seg_code
    omg, alpha = dyn.omg, dyn.alpha
    mot, n = walls.planes_mot, walls.planes_n
    if ride_load(gravity, walls, w, t) <= 0.0:
        return False
    limit = takeoff_delay(gravity, walls, w, t)
    if limit <= 0.0:
        return False
    code_limit = END_TAKEOFF
    oscillating = mot[w, M_KIND] == MOT_OSCILLATION
    if oscillating:
        step = RIDE_STEP / mot[w, M_OMEGA]
        if step < limit:
            limit = step
            code_limit = END_RIDE
    snap_to_plane(i, w, t, st, walls)
    cn = _motion_along_normal(walls, w)
    # the plane's frame: the sphere moves there at v − d ṡ(t), under g − d s̈ at the middle
    speed = wall_speed(mot, w, t)
    mid = wall_acceleration(mot, w, t + 0.5 * limit) if limit < NEVER else 0.0
    for k in range(3):
        st[i, S_V + k] -= speed * mot[w, M_DIR + k]
    if snap == END_RIDE:  # a rolling sphere's spin follows its velocity exactly
        snap = np.int64(END_SLIP) if mstate[i] == MS_ROLLING else np.int64(END_NONE)
    row = pair_table[dyn.mat[i], walls.planes_mat[w]]
    mu_s = row[P_MU_S] if friction else 0.0
    mu_r = row[P_MU_R] if rolling else 0.0
    wv = omg[i] if rotation else omg[0]
    g_eff = (gravity[0] - mid * mot[w, M_DIR], gravity[1] - mid * mot[w, M_DIR + 1],
             gravity[2] - mid * mot[w, M_DIR + 2])
    state, ax, ay, az, alx, aly, alz, dur, code = plane_segment(
        st[i, S_V:S_V + 3], wv, n[w], g_eff, st[i, S_R], SOLID_SPHERE_INERTIA, mu_s, mu_r,
        fsc[F_CHI], snap, dyn.seg_dir[i], abs(speed))
    for k in range(3):
        st[i, S_V + k] += speed * mot[w, M_DIR + k]
    if dur >= limit:
        dur = limit
        code = code_limit
    if state == MS_REST:
        state = MS_ROLLING  # carried by the plane, which moves
    # the frame's acceleration over the segment: along n the largest, so the sphere stays on
    # the spheres' side; along d's in-plane part the mean, so that speed is exact at the end
    a_n = 0.0
    a_mean = 0.0
    if oscillating and dur < NEVER:
        a_n = _normal_acceleration(walls, w, cn, t, dur)
        a_mean = (wall_speed(mot, w, t + dur) - speed) / dur if dur > 0.0 else 0.0
    acc[i, 0] = ax + a_n * n[w, 0] + a_mean * (mot[w, M_DIR] - cn * n[w, 0])
    acc[i, 1] = ay + a_n * n[w, 1] + a_mean * (mot[w, M_DIR + 1] - cn * n[w, 1])
    acc[i, 2] = az + a_n * n[w, 2] + a_mean * (mot[w, M_DIR + 2] - cn * n[w, 2])
    if rotation:
        alpha[i, 0] = alx
        alpha[i, 1] = aly
        alpha[i, 2] = alz
    mstate[i] = state
    mplane[i] = w
    seg_end[i] = t + dur
    seg_code[i] = code
    return True
