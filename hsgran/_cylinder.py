"""A sphere and a cylinder wall: the geometry of their contact, and the sphere's motion on the
cylinder (layer 5; compiled kernels of the event loop, used by :mod:`hsgran._flight`,
:mod:`hsgran._predict` and :mod:`hsgran._loop`; docs/walls.md, "Cylinders").

A cylinder is a wall row (``Walls.planes_kind`` = ``WK_CYLINDER``) whose ``planes_p`` is the
middle of its axis and whose ``planes_cyl`` holds the ``CY_*`` columns of
:mod:`hsgran.wallspec`. Its ``planes_n``, ``planes_vel`` and ``planes_omg`` describe one contact
at a time (:func:`set_cylinder_contact`): the normal at the contact point, the surface
velocity there and the wall's angular velocity, which is what the collision model and the
on-plane segments read of a wall.

**On a cylinder** [OURS]. A sphere resting, rolling or sliding on a cylinder moves in
*segments*, as on a plane (MODEL §5.3, hsgran.onplane), whose constant accelerations are those
of its start: the tangent plane's (its pull, friction and rolling resistance, through
:func:`hsgran.onplane.plane_segment`, in the frame turning with the wall) plus the centripetal
acceleration c²/ρ towards the axis (c the speed along the track, across the axis; ρ the
centre's distance from the axis), which also presses the sphere onto the surface inside a
drum and lifts it off outside. A segment ends at the transition it finds (slip or speed
spent) or when it has turned by :data:`CURVE_STEP` about the axis (``END_CURVE``). Then the
sphere is put back on the surface, its speed along the track is the segment's start speed plus
its tangential acceleration times the duration, and the change of that acceleration is added
over half the segment (a velocity-Verlet step), so no energy drifts from segment to segment. A
sphere the surface no longer presses (load ≤ 0 at a segment's start) flies.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit
from hsgran._state import F_CHI, S_R, S_T
from hsgran.facets import END_OFF
from hsgran.materials import P_MU_R, P_MU_S, SOLID_SPHERE_INERTIA
from hsgran.motion import NEVER, face_exit_time
from hsgran.onplane import END_NONE, END_SLIP, MS_REST, MS_ROLLING, plane_segment
from hsgran.wallspec import (
    CY_AXIS,
    CY_FINITE,
    CY_HALF,
    CY_OMEGA,
    CY_RADIUS,
    CY_SIDE,
    WK_CYLINDER,
)

#: A segment on a cylinder turns at most this angle about the axis [rad], and lasts at most
#: this share of √(ρ/|g|). Its accelerations are those of its start, so it errs by
#: O(CURVE_STEP²) of the speed within it, which the velocity-Verlet end removes but for a
#: phase error: a rolling pendulum's period comes out within 1.3e-7 at 0.3 rad
#: (tests/test_cylinders.py), at ~9 segments per degree turned and ≥ 3000 per period.
CURVE_STEP = 2e-3
#: Relative margin of a segment's acceleration towards the axis beyond the bound that keeps
#: its parabola off the wall (_normal_acceleration): rounding of the bound's terms, ~1e-16, is
#: covered a thousand times; the segment then leaves a gap of ~1e-13 ρ at most.
NORMAL_MARGIN = 1e-13
#: A sphere not moving along the track whose track acceleration is below this share of the
#: load |g − centripetal| [-] stays still: the terms that balance there (gravity's pull and the
#: rolling resistance at a turning drum's steady angle) are of size |g| and cancel to ~10 ulp,
#: far below this; any pull that matters is far above it.
STILL_ACC_REL = 1e-12
#: Velocities and spins relative to a turning wall below this share of the lab-frame speeds
#: are rounding [-]: the subtraction of the wall's motion (~1e-16 of it) leaves ~10 ulp, the
#: same margin as hsgran.onplane.ROLL_SLIP_REL's.
CARRY_ROUND_REL = 1e-12
#: The segment ended because it had turned CURVE_STEP (an ``END_*`` code of hsgran.onplane's
#: family, handled here).
END_CURVE = 5


@njit(inline="always")
def concave(walls, w):
    """Whether wall row w is a cylinder holding spheres inside it (the only concave wall)."""
    return walls.planes_kind[w] == WK_CYLINDER and walls.planes_cyl[w, CY_SIDE] > 0.0


@njit(inline="always")
def axis_offset(x, y, z, walls, w):
    """A point's offset [m] from cylinder w's axis, perpendicular to it, (qx, qy, qz)."""
    cyl, p = walls.planes_cyl, walls.planes_p
    dx = x - p[w, 0]
    dy = y - p[w, 1]
    dz = z - p[w, 2]
    ax, ay, az = cyl[w, CY_AXIS], cyl[w, CY_AXIS + 1], cyl[w, CY_AXIS + 2]
    s = dx * ax + dy * ay + dz * az
    return dx - s * ax, dy - s * ay, dz - s * az


@njit(inline="always")
def across_axis(vx, vy, vz, walls, w):
    """The part (vx, vy, vz) of a vector perpendicular to cylinder w's axis."""
    cyl = walls.planes_cyl
    ax, ay, az = cyl[w, CY_AXIS], cyl[w, CY_AXIS + 1], cyl[w, CY_AXIS + 2]
    s = vx * ax + vy * ay + vz * az
    return vx - s * ax, vy - s * ay, vz - s * az


@njit(inline="always")
def cylinder_gap(x, y, z, r, walls, w):
    """Gap [m] between a sphere of radius r [m] at (x, y, z) [m] and cylinder w (negative:
    overlap)."""
    qx, qy, qz = axis_offset(x, y, z, walls, w)
    d = math.sqrt(qx * qx + qy * qy + qz * qz)
    return walls.planes_cyl[w, CY_SIDE] * (walls.planes_cyl[w, CY_RADIUS] - d) - r


@njit(inline="always")
def _frame(x, y, z, walls, w):
    """At a centre (x, y, z) [m]: its distance from cylinder w's axis d [m], the unit radial
    direction û, the unit track direction e = a × û and the normal n towards the sphere."""
    cyl = walls.planes_cyl
    qx, qy, qz = axis_offset(x, y, z, walls, w)
    d = math.sqrt(qx * qx + qy * qy + qz * qz)
    if d == 0.0:  # on the axis (no contact possible): any direction across it
        qx, qy, qz = across_axis(1.0, 0.0, 0.0, walls, w)
        if qx * qx + qy * qy + qz * qz < 0.5:
            qx, qy, qz = across_axis(0.0, 1.0, 0.0, walls, w)
        dq = math.sqrt(qx * qx + qy * qy + qz * qz)
        qx, qy, qz = qx / dq, qy / dq, qz / dq
    else:
        qx, qy, qz = qx / d, qy / d, qz / d
    ax, ay, az = cyl[w, CY_AXIS], cyl[w, CY_AXIS + 1], cyl[w, CY_AXIS + 2]
    ex, ey, ez = ay * qz - az * qy, az * qx - ax * qz, ax * qy - ay * qx
    side = cyl[w, CY_SIDE]  # inside, the normal points to the axis
    return d, (qx, qy, qz), (ex, ey, ez), (-side * qx, -side * qy, -side * qz)


@njit(inline="always")
def cylinder_normal(x, y, z, walls, w):
    """Unit normal of cylinder w at the contact with a sphere centred at (x, y, z) [m],
    pointing to the sphere."""
    _, _, _, n = _frame(x, y, z, walls, w)
    return n


@njit(inline="always")
def set_cylinder_contact(walls, w, x, y, z):
    """Store cylinder w's contact with the sphere at (x, y, z) [m] in its row: the normal
    towards the sphere in ``planes_n[w]``, the surface velocity Ω a × (c − p) at the contact
    point c in ``planes_vel[w]`` [m/s], and Ω a in ``planes_omg[w]`` [rad/s] (what the
    collision model and the on-plane segments read of a wall)."""
    cyl = walls.planes_cyl
    _, _, e, n = _frame(x, y, z, walls, w)
    om = cyl[w, CY_OMEGA]
    speed = om * cyl[w, CY_RADIUS]  # the contact point is R û from the axis
    for k in range(3):
        walls.planes_n[w, k] = n[k]
        walls.planes_vel[w, k] = speed * e[k]
        walls.planes_omg[w, k] = om * cyl[w, CY_AXIS + k]


@njit(inline="always")
def carried_velocity(x, y, z, walls, w):
    """Velocity [m/s] of the point (x, y, z) [m] turning with cylinder w: Ω a × (x − p)."""
    cyl = walls.planes_cyl
    om = cyl[w, CY_OMEGA]
    qx, qy, qz = axis_offset(x, y, z, walls, w)
    ax, ay, az = cyl[w, CY_AXIS], cyl[w, CY_AXIS + 1], cyl[w, CY_AXIS + 2]
    return om * (ay * qz - az * qy), om * (az * qx - ax * qz), om * (ax * qy - ay * qx)


@njit(inline="always")
def carry_round(p, st, omg, walls, w, rotation):
    """Sphere p turns with cylinder w as one body: its velocity is the wall's motion at its
    centre and its spin (with ``rotation``) the wall's Ω a."""
    vx, vy, vz = carried_velocity(st[p, 0], st[p, 1], st[p, 2], walls, w)
    st[p, 3], st[p, 4], st[p, 5] = vx, vy, vz
    if rotation:
        for k in range(3):
            omg[p, k] = walls.planes_cyl[w, CY_OMEGA] * walls.planes_cyl[w, CY_AXIS + k]


@njit(inline="always")
def cylinder_load(x, y, z, vx, vy, vz, gravity, walls, w):
    """Normal load per unit mass [m/s²] of a sphere centred at (x, y, z) [m] moving at
    (vx, vy, vz) [m/s] on cylinder w: −g·n plus the centripetal acceleration c²/ρ inside (the
    wall turns the centre's path), minus it outside (docs/walls.md, "On a cylinder").

    Where the wall carries none of the weight (−g·n ≤ 0: a silo's upright side, a drum's
    overhang), the motion alone holds the sphere on it, and only while c²/ρ exceeds the pull
    of gravity along the axis |g·a|; a slower sphere is not held (load −g·n ≤ 0) and falls
    along the side instead of riding it [OURS]. (A bead creeping at 10⁻¹¹ m/s against a silo's
    side, on a bead below, was put on the side by a load of 10⁻¹⁹ m/s², slid down it onto
    that bead at once, and back, without end.) A drum's axis is level: unchanged there."""
    d, _, e, n = _frame(x, y, z, walls, w)
    c = vx * e[0] + vy * e[1] + vz * e[2]
    gn = -(gravity[0] * n[0] + gravity[1] * n[1] + gravity[2] * n[2])
    if d <= 0.0:
        return gn
    cyl = walls.planes_cyl
    held = cyl[w, CY_SIDE] * c * c / d
    if gn <= 0.0 < held and held <= abs(gravity[0] * cyl[w, CY_AXIS]
                                        + gravity[1] * cyl[w, CY_AXIS + 1]
                                        + gravity[2] * cyl[w, CY_AXIS + 2]):
        return gn
    return gn + held


@njit
def track_before(i, t, acc, st, walls, w):
    """What the velocity-Verlet end of sphere i's segment on cylinder w needs, read before the
    sphere is moved to t [s]: (duration h [s], speed along the track it should have at t
    [m/s], its tangential accelerations along the track and the axis [m/s²])."""
    h = t - st[i, S_T]
    _, _, e, _ = _frame(st[i, 0], st[i, 1], st[i, 2], walls, w)
    cyl = walls.planes_cyl
    ac = acc[i, 0] * e[0] + acc[i, 1] * e[1] + acc[i, 2] * e[2]
    aa = (acc[i, 0] * cyl[w, CY_AXIS] + acc[i, 1] * cyl[w, CY_AXIS + 1]
          + acc[i, 2] * cyl[w, CY_AXIS + 2])
    c = st[i, 3] * e[0] + st[i, 4] * e[1] + st[i, 5] * e[2]
    return h, c + ac * h, ac, aa


# long: one segment on a cylinder, from the snap onto the surface through the frame turning
# with the wall to the Verlet correction; its steps share the frame (û, e, n) and the speeds
@njit
def enter_cylinder(i, w, t, snap, prev, flight, dyn, walls, gravity, pair_table, fsc, friction,
                   rolling, rotation):
    """Put sphere i on cylinder w at time t [s], or start its next segment there (see the
    module's docstring). ``snap``: the transition that ended the last segment (``END_*``);
    ``prev``: :func:`track_before` of a segment that ended now, or h = 0.

    Returns:
        False if the surface does not press the sphere (it must fly; nothing was changed but
        its position and velocity, put on the surface and along it).
    """
    st, mstate, mplane = flight.st, flight.mstate, flight.mplane
    cyl = walls.planes_cyl
    r = st[i, S_R]
    side = cyl[w, CY_SIDE]
    rho = cyl[w, CY_RADIUS] - side * r
    ax, ay, az = cyl[w, CY_AXIS], cyl[w, CY_AXIS + 1], cyl[w, CY_AXIS + 2]
    finite = cyl[w, CY_FINITE] != 0.0  # an edge of a finite wall (hsgran.facets)
    if finite and abs(_along(st, i, walls, w)) > cyl[w, CY_HALF]:
        return False  # past its end: nothing holds the sphere
    d, u, e, n = _frame(st[i, 0], st[i, 1], st[i, 2], walls, w)
    for k in range(3):  # on the surface exactly
        st[i, k] += (rho - d) * u[k]
    va = st[i, 3] * ax + st[i, 4] * ay + st[i, 5] * az
    c = st[i, 3] * e[0] + st[i, 4] * e[1] + st[i, 5] * e[2]
    h, c_track, ac0, aa0 = prev
    curve = snap == END_CURVE
    if h > 0.0:
        c = c_track  # the parabola's end overshoots the track speed by c (turn)²/2
    _set_velocity(st, i, va, c, ax, ay, az, e)
    set_cylinder_contact(walls, w, st[i, 0], st[i, 1], st[i, 2])
    if snap == END_CURVE:  # the spin of a rolling sphere follows its new direction exactly
        snap = np.int64(END_SLIP) if mstate[i] == MS_ROLLING else np.int64(END_NONE)
    code = _segment(i, w, t, snap, rho, c, side, e, n, flight, dyn, walls, gravity, pair_table,
                    fsc, friction, rolling, rotation)
    if code < 0:
        return False
    if h > 0.0 and curve:
        # velocity Verlet: half the change of the tangential accelerations over the segment
        acc = flight.acc
        ac1 = acc[i, 0] * e[0] + acc[i, 1] * e[1] + acc[i, 2] * e[2]
        aa1 = acc[i, 0] * ax + acc[i, 1] * ay + acc[i, 2] * az
        va = st[i, 3] * ax + st[i, 4] * ay + st[i, 5] * az + 0.5 * h * (aa1 - aa0)
        c = st[i, 3] * e[0] + st[i, 4] * e[1] + st[i, 5] * e[2] + 0.5 * h * (ac1 - ac0)
        _set_velocity(st, i, va, c, ax, ay, az, e)
        code = _segment(i, w, t, np.int64(END_SLIP) if mstate[i] == MS_ROLLING
                        else np.int64(END_NONE), rho, c, side, e, n, flight, dyn, walls,
                        gravity, pair_table, fsc, friction, rolling, rotation)
        if code < 0:
            return False
    if finite:
        # an edge's segment also ends where the sphere passes its end: it flies from there
        acc = flight.acc
        off, _ = face_exit_time(_along(st, i, walls, w), st[i, 3] * ax + st[i, 4] * ay
                                + st[i, 5] * az, acc[i, 0] * ax + acc[i, 1] * ay
                                + acc[i, 2] * az, -cyl[w, CY_HALF], cyl[w, CY_HALF])
        if t + off < flight.seg_end[i]:
            flight.seg_end[i] = t + off
            flight.seg_code[i] = END_OFF
    mplane[i] = w
    return True


@njit(inline="always")
def _along(st, i, walls, w):
    """Sphere i's coordinate [m] along cylinder w's axis from its middle."""
    p, cyl = walls.planes_p, walls.planes_cyl
    return ((st[i, 0] - p[w, 0]) * cyl[w, CY_AXIS] + (st[i, 1] - p[w, 1]) * cyl[w, CY_AXIS + 1]
            + (st[i, 2] - p[w, 2]) * cyl[w, CY_AXIS + 2])


@njit(inline="always")
def _set_velocity(st, i, va, c, ax, ay, az, e):
    """Sphere i's velocity: va along the axis, c along the track, none across the surface."""
    st[i, 3] = va * ax + c * e[0]
    st[i, 4] = va * ay + c * e[1]
    st[i, 5] = va * az + c * e[2]


@njit(inline="always")
def _to_turning_frame(i, st, omg, carried, om, cyl, w, e, rotation):
    """Sphere i's velocity and spin relative to the frame turning with cylinder w at Ω = om
    (``carried`` = Ω ρ [m/s] along e at its centre). What is left of them below CARRY_ROUND_REL
    of the lab-frame speeds is rounding of the subtraction (a sphere carried round without
    slip) and is set to zero, as hsgran.onplane would otherwise take it for a slip."""
    scale = abs(carried) + abs(st[i, 3]) + abs(st[i, 4]) + abs(st[i, 5])
    rel = 0.0
    for k in range(3):
        st[i, 3 + k] -= carried * e[k]
        rel += abs(st[i, 3 + k])
    if rel <= CARRY_ROUND_REL * scale:
        for k in range(3):
            st[i, 3 + k] = 0.0
    if rotation:
        r = st[i, S_R]
        scale = abs(carried) + r * (abs(om) + abs(omg[i, 0]) + abs(omg[i, 1]) + abs(omg[i, 2]))
        rel = 0.0
        for k in range(3):
            omg[i, k] -= om * cyl[w, CY_AXIS + k]
            rel += r * abs(omg[i, k])
        if rel <= CARRY_ROUND_REL * scale:
            for k in range(3):
                omg[i, k] = 0.0


@njit
def _segment(i, w, t, snap, rho, c, side, e, n, flight, dyn, walls, gravity, pair_table, fsc,
             friction, rolling, rotation):
    """The segment of sphere i on cylinder w from its current state (on the surface, moving
    along it at c [m/s] along the track e): the tangent plane's segment in the frame turning
    with the wall, plus the centripetal acceleration; stored in its motion state. Returns its
    end code, or −1 if the surface does not press the sphere."""
    st, acc, mstate = flight.st, flight.acc, flight.mstate
    seg_end, seg_code = flight.seg_end, flight.seg_code
    omg, alpha = dyn.omg, dyn.alpha
    cyl = walls.planes_cyl
    k_c = c * c / rho  # the centripetal acceleration [m/s²]
    gx = gravity[0] - side * k_c * n[0]
    gy = gravity[1] - side * k_c * n[1]
    gz = gravity[2] - side * k_c * n[2]
    if -(gx * n[0] + gy * n[1] + gz * n[2]) <= 0.0:
        return -1
    # the frame turning with the wall at Ω: the centre moves there at v − Ω ρ e, the sphere
    # turns at ω − Ω a; the frame's own accelerations are normal to the surface
    om = cyl[w, CY_OMEGA]
    carried = om * rho
    if om != 0.0:
        _to_turning_frame(i, st, omg, carried, om, cyl, w, e, rotation)
    row = pair_table[dyn.mat[i], walls.planes_mat[w]]
    mu_s = row[P_MU_S] if friction else 0.0
    mu_r = row[P_MU_R] if rolling else 0.0
    wv = omg[i] if rotation else omg[0]
    state, a_x, a_y, a_z, alx, aly, alz, dur, code = plane_segment(
        st[i, 3:6], wv, walls.planes_n[w], (gx, gy, gz), st[i, S_R], SOLID_SPHERE_INERTIA,
        mu_s, mu_r, fsc[F_CHI], snap, dyn.seg_dir[i], abs(carried) + abs(om) * st[i, S_R])
    for k in range(3):
        st[i, 3 + k] += carried * e[k]
    if rotation:
        for k in range(3):
            omg[i, k] += om * cyl[w, CY_AXIS + k]
    if state == MS_REST and om != 0.0:
        state = MS_ROLLING  # carried round by the turning wall, without slip
    mstate[i] = state
    if rotation:
        alpha[i, 0] = alx
        alpha[i, 1] = aly
        alpha[i, 2] = alz
    a_c = a_x * e[0] + a_y * e[1] + a_z * e[2]
    g_scale = math.sqrt(gx * gx + gy * gy + gz * gz)
    if c == 0.0 and abs(a_c) <= STILL_ACC_REL * g_scale:
        # still on the track: the tangential terms balance to rounding (a sphere rolling in
        # place at a turning drum's steady angle), exactly still then
        a_x -= a_c * e[0]
        a_y -= a_c * e[1]
        a_z -= a_c * e[2]
        a_c = 0.0
    if c != 0.0 or a_c != 0.0:
        # the segment turns at most CURVE_STEP about the axis, and lasts at most CURVE_STEP
        # of the time scale √(ρ/|g|) of motion on the curve (a pendulum's 1/ω)
        reach = CURVE_STEP * rho
        turn = 2.0 * reach / (abs(c) + math.sqrt(c * c + 2.0 * abs(a_c) * reach))
        turn = min(turn, CURVE_STEP * math.sqrt(rho / g_scale))
        if turn < dur:
            dur = turn
            code = END_CURVE
    a_n = _normal_acceleration(c, a_c, dur, rho, side)
    acc[i, 0] = a_x + side * a_n * n[0]
    acc[i, 1] = a_y + side * a_n * n[1]
    acc[i, 2] = a_z + side * a_n * n[2]
    seg_end[i] = t + dur
    seg_code[i] = code
    return code


@njit(inline="always")
def _normal_acceleration(c, a_c, h, rho, side):
    """The acceleration towards the axis [m/s²] of a segment of h [s] that starts on the
    surface at the track speed c [m/s] with the track acceleration a_c [m/s²] (side: +1
    inside, −1 outside): near the centripetal c²/ρ, and such that the segment's parabola stays
    on the spheres' side of the surface throughout (docs/walls.md, "On a cylinder").

    Across the axis the centre is at s(τ) = c τ + ½ a_c τ² along the tangent and ½ a_n τ²
    towards the axis, so its distance d from the axis has d² − ρ² = τ² [(c + ½ a_c τ)² −
    ρ a_n + ¼ a_n² τ²]. Inside that stays ≤ 0 if ρ a_n covers the largest (c + ½ a_c τ)² on
    [0, h], at an end, and ¼ a_n² h²; outside it stays ≥ 0 if ρ a_n is at most the smallest
    (0 where c + ½ a_c τ turns round)."""
    if h == NEVER:
        return c * c / rho
    u0 = c * c
    u1 = (c + 0.5 * a_c * h) ** 2
    if side > 0.0:
        a_n = max(u0, u1) / rho
        a_n = (max(u0, u1) + 0.25 * a_n * a_n * h * h) / rho  # (a_n grows by ~CURVE_STEP²)
        return a_n * (1.0 + NORMAL_MARGIN)
    if c * (c + 0.5 * a_c * h) <= 0.0:
        return 0.0
    return min(u0, u1) / rho * (1.0 - NORMAL_MARGIN)
