"""One sphere's flight and motion state, and the checks of one contact (layer 5; the compiled
event loop's kernels, used by :mod:`hsgran._predict`, :mod:`hsgran._settling` and
:mod:`hsgran._loop`).

- where a sphere is at a time (its stored state plus its constant acceleration) and moving its
  stored state there (delayed states, DynamO);
- the gap to a plane, and the on-plane motion states (MODEL §5.3 through
  :func:`hsgran.onplane.plane_segment`): entering, leaving and stopping on a plane;
- the clock's rounding: what counts as no progress in time (the collapse guard's count);
- the re-check of a popped collision (still approaching?) and the TC model's elastic row.
"""

from __future__ import annotations

import numpy as np

from hsgran._cylinder import (
    carry_round,
    cylinder_gap,
    cylinder_load,
    cylinder_normal,
    enter_cylinder,
    set_cylinder_contact,
)
from hsgran._jit import njit
from hsgran._riding import (
    carry_along,
    enter_ride,
    relative_normal_speed,
    ride_load,
    takeoff_delay,
)
from hsgran._state import F_CHI, F_LANDING_SPEED, F_TC_TIME, S_R, S_T, S_V
from hsgran.facets import (
    END_OFF,
    FACE_BEHIND_REL,
    face_coordinates,
    face_leave_time,
    on_face,
)
from hsgran.materials import P_E_FIXED, P_MU_R, P_MU_S, SOLID_SPHERE_INERTIA
from hsgran.motion import NEVER, approach_noise, flight_position, plane_gap
from hsgran.onplane import END_NONE, MS_FLIGHT, MS_REST, plane_segment
from hsgran.wallmotion import wall_speed
from hsgran.wallspec import (
    BL_RADIUS,
    CY_AXIS,
    CY_FINITE,
    CY_HALF,
    CY_OMEGA,
    M_DIR,
    WK_BALL,
    WK_CYLINDER,
    WK_FACE,
    WK_MOVING,
    WK_PLANE,
)

#: A sphere whose gap to a plane is within this fraction of its radius counts as touching it
#: [-]: a gap of 1e-10 R is far above the rounding of a position dotted with a normal (~1e-16 of
#: the coordinates, ~1e-14 R for millimetre spheres in a 0.1 m box) and far below the 1e-9 R
#: overlap a run must stay under. The same value as motion.TOUCHING_REL, which is a fraction of
#: σ² for pairs; this one is a fraction of the radius for planes.
PLANE_TOUCHING_REL = 1e-10

#: Two bodies of a cluster of contacts (hsgran._cluster) touch when their gap is at most this
#: fraction of their contact distance σ (of the radius, for a wall) [-]: far above the rounding
#: of positions (1e-14 σ), far below any gap that matters. (A step of constrained motion also
#: takes every contact within its reach, touching or not.)
TOUCH_REL = 1e-6

#: A sphere whose event happens less than NO_PROGRESS_REL × max(1 s, t) after its previous one
#: made no progress in time (collapse guard, jams, wedges). In a cage of touching bodies the
#: time between collisions is the round-off of the predictions, a few ulps of the clock and
#: not always zero: a sphere sliding at 1 mm/s in a pocket of three resting spheres met them
#: 4.4e-16 s apart at t = 0.28 s (8 ulps), and with a bound of 4e-16 its run went on without
#: end. 1e-13 is ~450 ulps at t = 1 s and 1e7 times shorter than the contact duration of
#: millimetre spheres (1e4 times for micron spheres): no two real collisions are that close.
NO_PROGRESS_REL = 1e-13
#: The retry limit of pop–re-check–execute: consecutive events of one sphere that do not advance
#: its clock (re-check failures, collisions) after which the run stops with an error instead of
#: looping forever (inelastic collapse or a rounding loop). Legitimate simultaneous events (a
#: Newton's cradle, a symmetric three-body hit) involve a sphere a handful of times.
MAX_ZERO_TIME_EVENTS = 1000
#: A sphere whose gap to a plane is within this fraction of its radius at t = 0 starts on the
#: plane: the scene check accepts touching spheres written in decimal to 1e-12 (hsgran.scene
#: CONTACT_TOLERANCE), so the same bound.
START_GAP_REL = 1e-12


@njit(inline="always")
def state_at(st, acc, j, t, grav_on):
    """Position and velocity of sphere j at time t (its stored state is at ``st[j, S_T]``).

    With gravity every sphere moves with its own constant acceleration ``acc[j]``: gravity in
    flight, the on-plane value while sliding or rolling (hsgran.onplane), zero at rest."""
    dt = t - st[j, S_T]
    if grav_on:
        return (flight_position(st[j, 0], st[j, 3], acc[j, 0], dt),
                flight_position(st[j, 1], st[j, 4], acc[j, 1], dt),
                flight_position(st[j, 2], st[j, 5], acc[j, 2], dt),
                st[j, 3] + acc[j, 0] * dt, st[j, 4] + acc[j, 1] * dt,
                st[j, 5] + acc[j, 2] * dt)
    return (st[j, 0] + st[j, 3] * dt, st[j, 1] + st[j, 4] * dt, st[j, 2] + st[j, 5] * dt,
            st[j, 3], st[j, 4], st[j, 5])


@njit(inline="always")
def advance(st, acc, omg, alpha, j, t, grav_on, rotation):
    """Move sphere j's stored state (and its spin, which changes only on a plane) to time t."""
    if grav_on and rotation:
        dt = t - st[j, S_T]
        omg[j, 0] += alpha[j, 0] * dt
        omg[j, 1] += alpha[j, 1] * dt
        omg[j, 2] += alpha[j, 2] * dt
    x, y, z, u, v, w = state_at(st, acc, j, t, grav_on)
    st[j, 0] = x
    st[j, 1] = y
    st[j, 2] = z
    st[j, 3] = u
    st[j, 4] = v
    st[j, 5] = w
    st[j, S_T] = t


@njit(inline="always")
def min_image(d, k, box_len, periodic):
    """Nearest periodic image of a separation along axis k. Stored positions stay within one
    box length of the box (wrapped at every cell exit), so one shift is always enough."""
    if periodic[k]:
        half = 0.5 * box_len[k]
        if d > half:
            return d - box_len[k]
        if d < -half:
            return d + box_len[k]
    return d


@njit(inline="always")
def note_progress(p, t, st, zstreak):
    """Count consecutive events of sphere p that do not advance its clock (collapse guard)."""
    if t - st[p, S_T] <= NO_PROGRESS_REL * max(1.0, t):
        zstreak[p] += 1
    else:
        zstreak[p] = 0


@njit(inline="always")
def pressed(i, w, t, st, walls, gravity):
    """(normal load per unit mass g_n = −g·n [m/s²], normal velocity v·n [m/s]) of sphere i
    against wall w at time t [s]; against a moving plane, the load in its frame and the
    velocity relative to it (hsgran._riding)."""
    planes_n = walls.planes_n
    if moving(walls, w):
        return (ride_load(gravity, walls, w, t),
                relative_normal_speed(st[i, 3], st[i, 4], st[i, 5], walls, w, t))
    vn = st[i, 3] * planes_n[w, 0] + st[i, 4] * planes_n[w, 1] + st[i, 5] * planes_n[w, 2]
    if curved(walls, w):  # its row describes the contact with sphere i (wall_gap)
        return cylinder_load(st[i, 0], st[i, 1], st[i, 2], st[i, 3], st[i, 4], st[i, 5],
                             gravity, walls, w), vn
    gn = -(gravity[0] * planes_n[w, 0] + gravity[1] * planes_n[w, 1]
           + gravity[2] * planes_n[w, 2])
    return gn, vn


@njit(inline="always")
def halt(p, st, omg, rotation):
    """Sphere p stops: zero velocity and spin."""
    for k in range(3):
        st[p, S_V + k] = 0.0
        if rotation:
            omg[p, k] = 0.0


@njit
def leave_plane(i, flight, dyn, gravity, rotation):
    """Sphere i flies again (a collision moved it): acceleration g, constant spin."""
    acc, mstate, seg_end, seg_code = flight.acc, flight.mstate, flight.seg_end, flight.seg_code
    alpha = dyn.alpha
    mstate[i] = MS_FLIGHT
    seg_end[i] = NEVER
    seg_code[i] = END_NONE
    for k in range(3):
        acc[i, k] = gravity[k]
        if rotation:
            alpha[i, k] = 0.0


@njit
def rest_on(i, w, flight, dyn, rotation):
    """Sphere i rests on fixed sphere (or corner) w from now on: zero velocity, spin and
    acceleration, motion state rest, no segment end (as a sleeper on a sphere, [OURS])."""
    halt(i, flight.st, dyn.omg, rotation)
    for k in range(3):
        flight.acc[i, k] = 0.0
        if rotation:
            dyn.alpha[i, k] = 0.0
    flight.mstate[i] = MS_REST
    flight.mplane[i] = w
    flight.seg_end[i] = NEVER
    flight.seg_code[i] = END_NONE


@njit
def enter_plane(i, w, t, snap, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling,
                 rotation):
    """Put sphere i on plane w at time t (or start its next segment there; ``snap`` is the
    transition that ended the last one): MODEL §5.3 through hsgran.onplane.plane_segment. On a
    cylinder (hsgran._cylinder) or a moving plane (hsgran._riding), a sphere the surface does
    not press flies instead."""
    if moving(walls, w):
        if not enter_ride(i, w, t, snap, flight, dyn, walls, gravity, pair_table, fsc, friction,
                          rolling, rotation):
            leave_plane(i, flight, dyn, gravity, rotation)
        return
    if curved(walls, w):
        if not enter_cylinder(i, w, t, snap, (0.0, 0.0, 0.0, 0.0), flight, dyn, walls, gravity,
                              pair_table, fsc, friction, rolling, rotation):
            leave_plane(i, flight, dyn, gravity, rotation)
        return
    if ball(walls, w):
        # a fixed sphere has no motion on it: a sphere asleep there stays if slower than the
        # landing speed (at rest), else flies (hsgran._settling._sleeps_on_ball)
        st = flight.st
        if st[i, 3] ** 2 + st[i, 4] ** 2 + st[i, 5] ** 2 <= fsc[F_LANDING_SPEED] ** 2:
            rest_on(i, w, flight, dyn, rotation)
        else:
            leave_plane(i, flight, dyn, gravity, rotation)
        return
    st, acc, mstate = flight.st, flight.acc, flight.mstate
    mplane, seg_end, seg_code = flight.mplane, flight.seg_end, flight.seg_code
    omg, mat, alpha, seg_dir = dyn.omg, dyn.mat, dyn.alpha, dyn.seg_dir
    planes_p, planes_n, planes_mat = walls.planes_p, walls.planes_n, walls.planes_mat
    nx = planes_n[w, 0]
    ny = planes_n[w, 1]
    nz = planes_n[w, 2]
    if gravity[0] * nx + gravity[1] * ny + gravity[2] * nz > 0.0:
        # an overhanging plane (−g·n < 0) does not carry the sphere: gravity takes it away,
        # and on-plane motion there would slide it along the plane with a negative load, its
        # friction pushing instead of resisting (MODEL §5.3 assumes g_n > 0). A cluster solve
        # that leaves the sphere one touching contact, with that plane, sends it here
        leave_plane(i, flight, dyn, gravity, rotation)
        return
    gap = plane_gap(st[i, 0], st[i, 1], st[i, 2], st[i, S_R], planes_p, planes_n, w)
    if gap > PLANE_TOUCHING_REL * st[i, S_R]:
        # not on the plane: a sphere a cluster solve leaves on (or at rest on) a plane it
        # touches to within its TOUCH_REL, up to 1e-6 σ away. Moved down onto the plane, it
        # would be moved by up to that into the neighbours it touches: a sphere at rest in a
        # corpus V groove, 4.3 nm above its plane, went 2.2e-7 σ into a neighbour when a
        # collision put it back on the plane. It flies, and lands there (slower than the
        # landing speed: it falls 1e-6 R at most) [OURS]
        leave_plane(i, flight, dyn, gravity, rotation)
        return
    # exactly on the plane, moving along it: the normal gap and speed left are round-off or
    # (on landing) the rebound given up, bounded by the landing speed
    vn = st[i, 3] * nx + st[i, 4] * ny + st[i, 5] * nz
    st[i, 0] -= gap * nx
    st[i, 1] -= gap * ny
    st[i, 2] -= gap * nz
    st[i, 3] -= vn * nx
    st[i, 4] -= vn * ny
    st[i, 5] -= vn * nz
    row = pair_table[mat[i], planes_mat[w]]
    mu_s = row[P_MU_S] if friction else 0.0
    mu_r = row[P_MU_R] if rolling else 0.0
    wv = omg[i] if rotation else omg[0]
    state, ax, ay, az, alx, aly, alz, dur, code = plane_segment(
        st[i, S_V:S_V + 3], wv, planes_n[w], gravity, st[i, S_R], SOLID_SPHERE_INERTIA, mu_s,
        mu_r, fsc[F_CHI], snap, seg_dir[i])
    mstate[i] = state
    mplane[i] = w
    acc[i, 0] = ax
    acc[i, 1] = ay
    acc[i, 2] = az
    if rotation:
        alpha[i, 0] = alx
        alpha[i, 1] = aly
        alpha[i, 2] = alz
    if face(walls, w):
        off = face_leave_time(st[i, 0], st[i, 1], st[i, 2], st[i, 3], st[i, 4], st[i, 5], ax, ay,
                              az, planes_p, walls.planes_geo, walls.face_lines, w)
        if off < dur:
            dur = off
            code = END_OFF
    seg_end[i] = t + dur
    seg_code[i] = code


@njit
def stop_on_plane(p, t, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling,
                   rotation):
    """Sphere p, on its plane, stops there: at rest, or, on a slope too steep for rest, starting
    a new segment from standstill. On a turning cylinder or a moving plane it stops relative
    to the wall: it moves with it, as one body."""
    w = flight.mplane[p]
    if turning(walls, w):
        carry_round(p, flight.st, dyn.omg, walls, w, rotation)
    elif moving(walls, w):
        carry_along(p, t, flight.st, dyn.omg, walls, w, rotation)
    else:
        halt(p, flight.st, dyn.omg, rotation)
    enter_plane(p, np.int64(flight.mplane[p]), t, np.int64(END_NONE), flight, dyn, walls, gravity,
                 pair_table, fsc, friction, rolling, rotation)
    flight.counter[p] += 1


@njit(inline="always")
def moving(walls, w):
    """Whether wall w is a plane with a prescribed motion (hsgran.wallmotion)."""
    return walls.planes_kind[w] == WK_MOVING


@njit(inline="always")
def holds_now(walls, w, t, gravity):
    """Whether wall w can hold a sphere that lands on it at time t [s]: any wall but a moving
    plane that pulls away from its spheres then (hsgran._riding) and a fixed sphere or corner
    (a sphere has no motion on it: it falls asleep there or bounces,
    hsgran._settling._sleeps_on_ball; the cluster treatment refuses them)."""
    if ball(walls, w):
        return False
    return not moving(walls, w) or takeoff_delay(gravity, walls, w, t) > 0.0


@njit(inline="always")
def immovable(walls, w):
    """Whether wall w neither moves nor turns: a fixed plane, a part of a finite wall, a fixed
    sphere, or a cylinder at rest (a sphere wedged against it may be stopped,
    hsgran._settling)."""
    return flat_fixed(walls, w) or walls.planes_kind[w] == WK_BALL or (
        curved(walls, w) and not turning(walls, w))


@njit(inline="always")
def flat_fixed(walls, w):
    """Whether wall w is a fixed plane or the face of a fixed finite wall (flat, at rest)."""
    kind = walls.planes_kind[w]
    return kind == WK_PLANE or kind == WK_FACE


@njit(inline="always")
def ball(walls, w):
    """Whether wall w is a fixed sphere or a corner of a finite wall."""
    return walls.planes_kind[w] == WK_BALL


@njit(inline="always")
def face(walls, w):
    """Whether wall w is a face of a finite wall."""
    return walls.planes_kind[w] == WK_FACE


@njit(inline="always")
def ball_normal(walls, w, x, y, z):
    """Unit normal of fixed sphere (or corner) w at its contact with a sphere centred at
    (x, y, z) [m], pointing to the sphere (any direction from its very centre)."""
    dx = x - walls.planes_p[w, 0]
    dy = y - walls.planes_p[w, 1]
    dz = z - walls.planes_p[w, 2]
    d = (dx * dx + dy * dy + dz * dz) ** 0.5
    if d == 0.0:
        return 0.0, 0.0, 1.0
    return dx / d, dy / d, dz / d


@njit(inline="always")
def set_ball_contact(walls, w, x, y, z):
    """Store fixed sphere w's normal at its contact with the sphere at (x, y, z) [m] in
    ``planes_n[w]`` (what the collision model reads of a wall; it neither moves nor turns)."""
    nx, ny, nz = ball_normal(walls, w, x, y, z)
    walls.planes_n[w, 0] = nx
    walls.planes_n[w, 1] = ny
    walls.planes_n[w, 2] = nz


@njit(inline="always")
def wall_curvature(walls, w, r):
    """1/R* of a sphere of radius r [m] against wall w [1/m]: 1/r + 1/R against a fixed sphere
    of radius R, 1/r against a flat wall, an edge or a corner (MODEL §2; an edge or a corner
    is taken as flat in the collision model, docs/walls.md, "Finite walls")."""
    if ball(walls, w) and walls.planes_geo[w, BL_RADIUS] > 0.0:
        return 1.0 / r + 1.0 / walls.planes_geo[w, BL_RADIUS]
    return 1.0 / r


@njit(inline="always")
def beyond_ends(walls, w, x, y, z):
    """Whether the point (x, y, z) [m] lies beyond the ends of edge w (a finite cylinder),
    measured along its axis; never for a cylinder wall."""
    if walls.planes_cyl[w, CY_FINITE] == 0.0:
        return False
    s = ((x - walls.planes_p[w, 0]) * walls.planes_cyl[w, CY_AXIS]
         + (y - walls.planes_p[w, 1]) * walls.planes_cyl[w, CY_AXIS + 1]
         + (z - walls.planes_p[w, 2]) * walls.planes_cyl[w, CY_AXIS + 2])
    return abs(s) > walls.planes_cyl[w, CY_HALF]


@njit(inline="always")
def turning(walls, w):
    """Whether wall w is a cylinder turning about its axis."""
    return walls.planes_kind[w] == WK_CYLINDER and walls.planes_cyl[w, CY_OMEGA] != 0.0


@njit(inline="always")
def curved(walls, w):
    """Whether wall w is a cylinder."""
    return walls.planes_kind[w] == WK_CYLINDER


@njit(inline="always")
def wall_normal(walls, w, x, y, z):
    """Unit normal of wall w at its contact with a sphere centred at (x, y, z) [m], pointing
    to the sphere: a plane's (or a face's) normal, or a cylinder's or a fixed sphere's
    there."""
    if curved(walls, w):
        return cylinder_normal(x, y, z, walls, w)
    if ball(walls, w):
        return ball_normal(walls, w, x, y, z)
    return walls.planes_n[w, 0], walls.planes_n[w, 1], walls.planes_n[w, 2]


@njit(inline="always")
def wall_gap(i, w, st, walls):
    """Gap [m] of sphere i to wall w, a fixed plane, a cylinder or a fixed sphere (whose row
    then describes its contact with sphere i, for :func:`pressed`), or a face or an edge of
    a finite wall (``inf`` where the sphere is off it: its foot off the face, behind it, or
    beyond the edge's ends)."""
    x, y, z, r = st[i, 0], st[i, 1], st[i, 2], st[i, S_R]
    if curved(walls, w):
        if beyond_ends(walls, w, x, y, z):
            return NEVER
        set_cylinder_contact(walls, w, x, y, z)
        return cylinder_gap(x, y, z, r, walls, w)
    if ball(walls, w):
        set_ball_contact(walls, w, x, y, z)
        p = walls.planes_p
        return (((x - p[w, 0]) ** 2 + (y - p[w, 1]) ** 2 + (z - p[w, 2]) ** 2) ** 0.5 - r
                - walls.planes_geo[w, BL_RADIUS])
    gap = plane_gap(x, y, z, r, walls.planes_p, walls.planes_n, w)
    if face(walls, w):
        u, v = face_coordinates(x, y, z, walls.planes_p, walls.planes_geo, w)
        if gap < -FACE_BEHIND_REL * r or not on_face(u, v, walls.planes_p, walls.planes_geo,
                                                     walls.face_lines, w):
            return NEVER
    return gap


@njit(inline="always")
def set_wall_velocity(walls, w, t):
    """Store moving plane w's velocity at time t [s] in ``planes_vel[w]`` [m/s] (what the
    collision model reads as the wall's velocity)."""
    speed = wall_speed(walls.planes_mot, w, t)
    for k in range(3):
        walls.planes_vel[w, k] = speed * walls.planes_mot[w, M_DIR + k]


#: Restitution of a collision the TC model makes elastic.
TC_RESTITUTION = 1.0


@njit(inline="always")
def tc_row(row, t, t1, t2, fsc, row_tc):
    """(pair row, made elastic) for a collision at t of bodies last hit at t1, t2 [s]: ``row``
    itself, or, when one of them collided less than the TC time ago, a copy with a fixed
    restitution of 1 in ``row_tc`` (TC model, Luding & McNamara 1998, through MODEL §3.9's
    fixed-restitution bypass; the tangential model is unchanged)."""
    tc = fsc[F_TC_TIME]
    if tc > 0.0 and (t - t1 < tc or t - t2 < tc):
        for k in range(row.shape[0]):  # (a slice copy would need numba's allocator)
            row_tc[k] = row[k]
        row_tc[P_E_FIXED] = TC_RESTITUTION
        return row_tc, True
    return row, False


@njit(inline="always")
def approaching(i, j, dx, dy, dz, sigma, st):
    """Whether touching spheres i, j (r = x_i − x_j = (dx, dy, dz) [m]) approach by more than
    rounding: the re-check matching predict's test (motion.approach_noise)."""
    rw = 0.0
    v_sum = 0.0
    x_sum = 0.0
    for k, rk in enumerate((dx, dy, dz)):
        rw += rk * (st[i, S_V + k] - st[j, S_V + k])
        v_sum += abs(st[i, S_V + k]) + abs(st[j, S_V + k])
        x_sum += abs(st[i, k]) + abs(st[j, k])
    return -rw > approach_noise(sigma, v_sum, x_sum)
