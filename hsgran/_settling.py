"""Enduring contact under gravity: the rules that end zero-time sequences of collisions in
rest (layer 5; compiled kernels used by :mod:`hsgran._loop`). All of them are hsgran's own
choices [OURS]; what each costs in accuracy is in docs/enduring-contact.md.

The event loop reaches them through four entry points, with gravity only (the loop compiled
without gravity runs none of the rules):

- :func:`settle` — a slow meeting of two spheres ends in rest instead of a collision: a sphere
  lands on a plane it lies on, falls asleep on a sphere at rest, or two slow spheres on their
  supports both stop;
- :func:`collide_pair` — a sphere–sphere collision with supports: backing by a plane or by the
  sphere a sleeper rests on, hops of pressed pairs, resting spheres held where they are, waking
  the sleepers of a sphere set moving, and stopping a sphere wedged between immovable bodies;
- :func:`lands_before_wall` — a sphere meeting a plane too slowly to bounce stays on it;
- :func:`collide_wall` — a sphere–plane collision with backing by another plane, landing after
  a slow rebound and the wedge stop.

The next step for dense scenes (a multi-contact treatment in place of these pairwise rules)
replaces this module behind the same entry points.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._flight import (
    PLANE_TOUCHING_REL,
    advance,
    approaching,
    ball,
    curved,
    enter_plane,
    flat_fixed,
    halt,
    holds_now,
    immovable,
    leave_plane,
    min_image,
    moving,
    pressed,
    rest_on,
    stop_on_plane,
    tc_row,
    wall_curvature,
    wall_gap,
    wall_normal,
)
from hsgran._jit import njit
from hsgran._observe import book_support, observing
from hsgran._predict import axis_cells, near_wall, near_walls, reschedule_fn
from hsgran._state import (
    F_LANDING_SPEED,
    F_TC_TIME,
    FL_ADHESION,
    FL_COMPLIANCE,
    FL_FRICTION,
    FL_GRAVITY,
    FL_PLASTICITY,
    FL_ROLLING,
    FL_ROTATION,
    FL_VISCOUS,
    S_R,
    S_V,
)
from hsgran.contact.model import (
    REC_ENERGY_LOST,
    REC_J_N,
    REC_J_T,
    REC_REGIME,
    REC_STAGE,
    resolve,
)
from hsgran.contact.tangential import tangential_impulse
from hsgran.events.kinds import EV_HOP
from hsgran.materials import P_MU_R, P_MU_S
from hsgran.motion import NEVER
from hsgran.onplane import (
    END_NONE,
    MS_FLIGHT,
    MS_REST,
    MS_ROLLING,
    MS_SLIDING,
    holds_still,
    load_and_pull,
)

#: Events of one sphere in succession, each less than the TC time after the previous one (or
#: at the same instant), after which it counts as jammed: in an enduring contact with several
#: bodies at once (see _falls_asleep). Far above the handful of collisions of a legitimate
#: simultaneous hit, far below the collapse guard.
JAM_EVENTS = 64
#: Events of one sphere in succession without its clock advancing (NO_PROGRESS_REL) after which
#: a collision with an immovable body (a plane, or a sphere the collision leaves at rest) stops
#: it: see _wedge_stop. Above JAM_EVENTS, so that a jammed sphere that can fall
#: asleep on an upward contact does so first; far below the collapse guard
#: (MAX_ZERO_TIME_EVENTS).
WEDGE_EVENTS = 128
#: A jammed sphere may fall asleep on a resting sphere it meets if the contact normal points
#: upwards at all, so that gravity presses it onto that sphere: cos ≥ 1e-10 to the vertical,
#: far above the rounding of the direction [-] (the centres' offset over σ: ~1e-16 of the
#: coordinates over σ, 5e-15 for millimetre spheres 0.1 m from the origin). (1e-3 left a
#: sphere 0.05° above the equator of a sleeper, wedged between it and a side wall, hopping
#: off it into the wall for ever; 1e-6 left a bead in a pocket of three resting beads on a
#: silo's floor, 67 pm above the floor and 3.4e-8 above their equators, hopping among them at
#: one instant until the collapse guard stopped the run.)
JAM_SUPPORT_COS = 1e-10
#: A sphere can fall asleep on another only if the contact normal is within 60° of the upward
#: vertical (cos 60° = 0.5): it then lies on top of it, as in a pile, where a sphere in the
#: pocket of three others touches each at ~35° from the vertical; a sideways touch is a
#: collision like any other.
SUPPORT_COS = 0.5


@njit(inline="always")
def _can_support(p, st, mstate, mplane, v_sleep):
    """Sphere p can carry a sleeper: at rest (on a plane or asleep itself), or on a plane and
    slower than ``v_sleep`` (it is then brought to rest first)."""
    if mstate[p] == MS_REST:
        return True
    if mstate[p] == MS_FLIGHT or mplane[p] < 0:
        return False
    return st[p, 3] ** 2 + st[p, 4] ** 2 + st[p, 5] ** 2 <= v_sleep * v_sleep


@njit
def _falls_asleep(i, j, nx, ny, nz, st, mstate, mplane, gravity, v_sleep, jam_i, jam_j):
    """Which of i, j (n = unit vector from j to i) falls asleep on the other, or −1.

    A sphere falls asleep when it meets from above a sphere that is at rest (on a plane or
    itself asleep), or on a plane and slower than ``v_sleep`` (the landing speed), with a
    relative speed at most ``v_sleep``: what a collision would have done is a rebound slower
    than that. This is hsgran's remedy for sphere–sphere inelastic collapse in piles [OURS,
    after DynamO's sleeping particles]; it gives up at most ½ m v_sleep² per sphere stopped,
    and the support is not pushed.

    "From above" is within 60° of the vertical (SUPPORT_COS), or, for a jammed sphere
    (``jam_i``/``jam_j``: JAM_EVENTS rapid events in succession), any upward direction: a
    sphere wedged between a wall and a sphere it leans on, or in a pocket of spheres on a
    plate, rests against several bodies at once, which the hard-sphere loop can only see as an
    endless buzz of (TC-elastic) collisions [OURS]."""
    g = math.sqrt(gravity[0] ** 2 + gravity[1] ** 2 + gravity[2] ** 2)
    if g == 0.0:
        return -1
    up = -(nx * gravity[0] + ny * gravity[1] + nz * gravity[2]) / g  # cos(angle(n, up))
    dvx = st[i, 3] - st[j, 3]
    dvy = st[i, 4] - st[j, 4]
    dvz = st[i, 5] - st[j, 5]
    if dvx * dvx + dvy * dvy + dvz * dvz > v_sleep * v_sleep:
        return -1
    if (mstate[i] != MS_REST and up >= (JAM_SUPPORT_COS if jam_i else SUPPORT_COS)
            and _can_support(j, st, mstate, mplane, v_sleep)):
        return i
    if (mstate[j] != MS_REST and -up >= (JAM_SUPPORT_COS if jam_j else SUPPORT_COS)
            and _can_support(i, st, mstate, mplane, v_sleep)):
        return j
    return -1


@njit(inline="always")
def _jammed(p, dyn):
    """Whether sphere p is jammed: more than JAM_EVENTS rapid events (note_rapid) or events
    without its clock advancing in succession."""
    return dyn.rapid[p] > JAM_EVENTS or dyn.zstreak[p] > JAM_EVENTS


@njit(inline="always")
def note_rapid(p, t, t_last, rapid, tc):
    """Count sphere p's collisions in succession that come less than the TC time ``tc`` [s]
    after its previous one (jam detection, JAM_EVENTS)."""
    if t - t_last[p] < tc:
        rapid[p] += 1
    else:
        rapid[p] = 0


@njit(inline="always")
def _holds(p, v0x, v0y, v0z, mstate, zstreak):
    """Whether sphere p, which met a collision with velocity v0, is immovable for the wedge
    rule (_wedge_stop): at rest after it, or stopped by the rule at this instant."""
    return mstate[p] == MS_REST or (zstreak[p] >= WEDGE_EVENTS and v0x == 0.0 and v0y == 0.0
                                    and v0z == 0.0)


@njit
def _wedge_stop(p, t, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling,
                rotation):
    """Stop sphere p, which has just collided with an immovable body after at least
    WEDGE_EVENTS events in succession at one instant (NO_PROGRESS_REL), if it moves (in
    flight, or sliding or rolling on a plane); returns whether it was stopped. Immovable: a
    plane (planes never move), a sphere the collision leaves at rest, or a sphere stopped
    here at this instant (it met the collision at standstill); the caller decides (_holds).

    Such a sequence is a sphere wedged between immovable bodies: between a side wall and a
    sleeper leaning over it, on the floor in a pocket of a wall and resting spheres, or in a
    chain of spheres between a wall and a sleeper (seen in a 400-sphere pour at e = 0.8: the
    spheres at its ends stop against the wall and the sleeper, the ones between against
    them). The TC model makes its collisions elastic, so the bodies send it back and forth at
    the same instant without end: with sticking friction the impulses shrink geometrically
    (by ~0.9 a collision, seen in 200-sphere pours), without friction they need not shrink at
    all. A sphere held by bodies at rest comes to rest relative to them (e = 0, the limit of
    an enduring contact), so it is stopped at once [OURS]: in flight, velocity and spin zero,
    and gravity then decides what comes next (it falls out of a wedge that opens downwards,
    or, pressed into an upward contact, falls asleep there, _falls_asleep); on a plane, at
    rest there (stop_on_plane; on a slope too steep for rest it slides on from standstill).
    What is given up is the kinetic energy it had left, which ``dissipated_energy`` counts;
    the run summary's "wedge" count says how often, and the event log has an entry for each
    stop (EV_WEDGE). A zero-time loop that meets no immovable body is left to the collapse
    guard."""
    st, omg, mstate = flight.st, dyn.omg, flight.mstate
    if dyn.zstreak[p] < WEDGE_EVENTS or mstate[p] == MS_REST or (
            st[p, 3] == 0.0 and st[p, 4] == 0.0 and st[p, 5] == 0.0
            and (not rotation or (omg[p, 0] == 0.0 and omg[p, 1] == 0.0 and omg[p, 2] == 0.0))):
        return False  # nothing to stop
    if mstate[p] == MS_FLIGHT:
        halt(p, st, omg, rotation)
    else:
        stop_on_plane(p, t, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling,
                       rotation)
    return True


@njit(inline="always")
def _can_rest(p, flight, dyn, walls, gravity, pair_table, friction, rolling):
    """Whether sphere p, on a support, can rest there: asleep or at rest already, or on a
    plane whose slope its friction and rolling resistance hold (hsgran.onplane.holds_still,
    the rest test of the on-plane model)."""
    w = flight.mplane[p]
    if flight.mstate[p] == MS_REST or w < 0:
        return True
    nx, ny, nz = wall_normal(walls, w, flight.st[p, 0], flight.st[p, 1], flight.st[p, 2])
    gn, gtx, gty, gtz = load_and_pull(nx, ny, nz, gravity)
    row = pair_table[dyn.mat[p], walls.planes_mat[w]]
    return holds_still(math.sqrt(gtx * gtx + gty * gty + gtz * gtz), gn,
                       row[P_MU_S] if friction else 0.0, row[P_MU_R] if rolling else 0.0)


@njit
def _both_slow_on_supports(i, j, flight, dyn, walls, gravity, pair_table, friction, rolling,
                           v_land):
    """Whether spheres i and j are both on a support (a plane, or asleep on a sphere), both
    slower than the landing speed ``v_land`` [m/s], and both can rest there (_can_rest).
    When such spheres meet they both stop where they are [OURS]: the sphere-against-sphere
    counterpart of landing, at a cost of at most ½ m v_land² per sphere stopped. As a
    collision, a slow sphere sliding into a resting one that had just taken a sleeper made a
    zero-time chain: the collision moved the support, the sleeper stopped it again, and the
    slider met it again, ever slower. Stopped where it cannot rest (a slope too steep), a
    sphere moves on from standstill at once: a bead rolling down a chute's floor into one at
    rest on the rough base was stopped and set rolling again 1000 times at one instant, its
    hop off the base undone each time; they collide instead."""
    if flight.mstate[i] == MS_FLIGHT or flight.mstate[j] == MS_FLIGHT:
        return False
    # Not on a cylinder: stopped at two places of a curved wall, the spheres are pulled
    # together at once (their accelerations differ), met again at the same instant and were
    # stopped again, for ever (seen in drums of 48 and 62 beads); there they collide. Not on a
    # moving plane either: its spheres move with it, and their lab speeds say nothing of
    # their motion relative to it.
    for p in (i, j):
        w = flight.mplane[p]
        if w >= 0 and (curved(walls, w) or moving(walls, w)):
            return False
    st = flight.st
    vi2 = st[i, 3] * st[i, 3] + st[i, 4] * st[i, 4] + st[i, 5] * st[i, 5]
    vj2 = st[j, 3] * st[j, 3] + st[j, 4] * st[j, 4] + st[j, 5] * st[j, 5]
    return (vi2 <= v_land * v_land and vj2 <= v_land * v_land
            and _can_rest(i, flight, dyn, walls, gravity, pair_table, friction, rolling)
            and _can_rest(j, flight, dyn, walls, gravity, pair_table, friction, rolling))


@njit
def _fall_asleep(a, b, flight, dyn, rotation):
    """Sphere a rests on sphere b from now on: zero velocity, spin and acceleration."""
    rest_on(a, -2 - b, flight, dyn, rotation)  # the support code of sphere b


@njit
def wake_sleepers(s, t, flight, dyn, walls, space, grid, sched, isc, grav_on, rotation):
    """Sphere s was at rest and has been hit: every sphere asleep on it, and on those, falls."""
    if observing(dyn):
        # their supports so far, booked down the chains through s while those still stand
        _visit_sleepers(s, t, False, flight, dyn, walls, space, grid, sched, isc, grav_on,
                        rotation)
    _visit_sleepers(s, t, True, flight, dyn, walls, space, grid, sched, isc, grav_on, rotation)


@njit
def _visit_sleepers(s, t, wake, flight, dyn, walls, space, grid, sched, isc, grav_on, rotation):
    """Every sphere asleep on sphere s, and on those: wake each (``wake``), or book its
    supports (hsgran._observe.book_support)."""
    st, counter, acc = flight.st, flight.counter, flight.acc
    mstate, mplane = flight.mstate, flight.mplane
    omg, alpha = dyn.omg, dyn.alpha
    gravity, box_len, periodic = space.gravity, space.box_len, space.periodic
    ncell, cell, head, nxt, ac, ah, stack = grid.ncell, grid.cell, grid.head, grid.nxt, grid.ac, \
        grid.ah, grid.stack
    top = 0
    stack[top] = s
    top += 1
    while top > 0:
        top -= 1
        b = stack[top]
        mx = axis_cells(cell[b, 0], ncell[0], box_len[0], periodic[0], 0, ac, ah)
        my = axis_cells(cell[b, 1], ncell[1], box_len[1], periodic[1], 1, ac, ah)
        mz = axis_cells(cell[b, 2], ncell[2], box_len[2], periodic[2], 2, ac, ah)
        for x in range(mx):
            for y in range(my):
                for z in range(mz):
                    q = np.int64(head[(ac[0, x] * ncell[1] + ac[1, y]) * ncell[2] + ac[2, z]])
                    while q >= 0:
                        if mstate[q] == MS_REST and mplane[q] == -2 - b:
                            if wake:
                                advance(st, acc, omg, alpha, q, t, grav_on, rotation)
                                leave_plane(q, flight, dyn, gravity, rotation)
                                mplane[q] = -1
                                counter[q] += 1
                                reschedule_fn(q, t, flight, walls, space, grid, sched, isc,
                                               grav_on)
                            else:
                                book_support(q, t, flight, dyn, walls, space)
                            stack[top] = q
                            top += 1
                        q = np.int64(nxt[q])


#: Two spheres pressed into planes with support cosines c_i, c_j both ~1 (c_i² + c_j² ≥ 2 − this)
#: would have no mobility along the contact normal: then neither is treated as backed.
SUPPORT_EPS = 1e-9


@njit(inline="always")
def _support_normal(p, st, mstate, mplane, walls, box_len, periodic):
    """Unit normal N [-] of what backs sphere p: its wall's normal (a cylinder's where p
    touches it), or, for a sphere asleep on sphere b, the direction from b to p; (0, 0, 0) for
    a sphere in flight."""
    if mstate[p] == MS_FLIGHT:
        return 0.0, 0.0, 0.0
    w = mplane[p]
    if w >= 0:
        return wall_normal(walls, w, st[p, 0], st[p, 1], st[p, 2])
    b = -2 - w
    if b < 0:
        return 0.0, 0.0, 0.0
    dx = min_image(st[p, 0] - st[b, 0], 0, box_len, periodic)
    dy = min_image(st[p, 1] - st[b, 1], 1, box_len, periodic)
    dz = min_image(st[p, 2] - st[b, 2], 2, box_len, periodic)
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    return dx / d, dy / d, dz / d


@njit(inline="always")
def _support_cos(sx, sy, sz, bx, by, bz):
    """How much an impulse along the unit vector s presses a sphere into what backs it (unit
    normal N = b): c = −s·N if c > 0, else 0.

    A sphere on a plane, or asleep on another sphere, that is hit towards its support is
    backed by it [OURS, rigid-support limit]: the support takes the part of the impulse along
    N, so along the contact normal the sphere has the inverse mass (1 − c²)/m. Without this
    the hit would push it into the support, it would land again at once and be hit again: an
    endless zero-time cascade."""
    c = -(sx * bx + sy * by + sz * bz)
    return c if c > 0.0 else 0.0


@njit(inline="always")
def _off_support(x, y, z, bx, by, bz):
    """What a backed sphere keeps of an impulse (x, y, z) [N s]: all but its part along its
    support's unit normal b, which the support takes."""
    xb = x * bx + y * by + z * bz
    return x - xb * bx, y - xb * by, z - xb * bz


@njit(inline="always")
def _backed_velocity(p, v0x, v0y, v0z, jx, jy, jz, bx, by, bz, st, inv_m):
    """Velocity of a backed sphere p after the impulse J [N s] on it: its support (unit normal
    b) takes J·b."""
    kx, ky, kz = _off_support(jx, jy, jz, bx, by, bz)
    st[p, 3] = v0x + inv_m[p] * kx
    st[p, 4] = v0y + inv_m[p] * ky
    st[p, 5] = v0z + inv_m[p] * kz


@njit(inline="always")
def _friction_push(tx, ty, tz, c, b, inv_m_full, inv_m_used):
    """Velocity change [m/s] that the tangential impulse t [N s] made on a sphere in a pair
    collision: backed by its support (c > 0, unit normal b), its support takes t·b
    (_backed_velocity); else as the collision applied it (``inv_m_used``, 0 if held)."""
    if c > 0.0:
        kx, ky, kz = _off_support(tx, ty, tz, b[0], b[1], b[2])
        return inv_m_full * kx, inv_m_full * ky, inv_m_full * kz
    return inv_m_used * tx, inv_m_used * ty, inv_m_used * tz


@njit
def _support_friction(p, press, bx, by, bz, flight, dyn, walls, pair_table, w, rotation):
    """Coulomb friction of sphere p's support for the normal impulse ``press`` [N s] that the
    support took from a backed collision (unit normal b from the support to p) [OURS,
    docs/enduring-contact.md, "Backing"]: :func:`foot_friction` with μ the sliding friction
    of p and its support (model.md §4). It acts where the support is at rest: a fixed wall (a
    plane, a face, a fixed sphere, a cylinder at rest), or the sphere p sleeps on; a moving
    plane or a turning cylinder gives none here. Without it, a bed on a slope held only its
    bottom spheres' own weight by friction and slid down as a block (corpus 0-69, against
    LAMMPS: docs/enduring-contact.md, "A bed on a slope, beside soft-sphere DEM")."""
    mplane, mat = flight.mplane, dyn.mat
    sup = mplane[p]
    if sup >= 0:
        if not immovable(walls, sup):
            return
        mu = pair_table[mat[p], walls.planes_mat[sup]][P_MU_S]
    elif sup <= -2:
        mu = pair_table[mat[p], mat[-2 - sup]][P_MU_S]
    else:
        return
    foot_friction(p, press, mu, bx, by, bz, flight.st, dyn, w, rotation)


@njit
def foot_friction(p, press, mu, bx, by, bz, st, dyn, w, rotation):
    """The friction impulse of a body at rest that takes the normal impulse ``press`` [N s]
    from sphere p (unit normal b from the body to p) [OURS, docs/enduring-contact.md,
    "Backing" and "From bouncing to contact"]: model.md §4.2's impulse against a body at rest
    (:func:`hsgran.contact.tangential.tangential_impulse`, with m_t = 1/(1/m + R²/I)), on p
    at its contact point −R b against the point's slip u_t: the impulse that stops the slip,
    or μ press where that exceeds the cone (μ [-]: the pair's sliding friction). A stopped
    slip or one reduced along itself only takes energy away. ``w``: p's spin [rad/s],
    updated."""
    if press <= 0.0 or mu <= 0.0:
        return
    r = st[p, S_R]
    inv_m, inv_i = dyn.inv_m[p], dyn.inv_i[p]
    # velocity of p's material point at −R b (the support's point is at rest)
    ux, uy, uz = st[p, 3], st[p, 4], st[p, 5]
    if rotation:
        ux -= r * (w[1] * bz - w[2] * by)
        uy -= r * (w[2] * bx - w[0] * bz)
        uz -= r * (w[0] * by - w[1] * bx)
    un = ux * bx + uy * by + uz * bz
    ux -= un * bx
    uy -= un * by
    uz -= un * bz
    slip = math.sqrt(ux * ux + uy * uy + uz * uz)
    if slip == 0.0:
        return
    j_t, _ = tangential_impulse(slip, 1.0 / (inv_m + (r * r * inv_i if rotation else 0.0)), mu,
                                press)
    fx, fy, fz = -j_t * ux / slip, -j_t * uy / slip, -j_t * uz / slip
    st[p, 3] += inv_m * fx
    st[p, 4] += inv_m * fy
    st[p, 5] += inv_m * fz
    if rotation:  # the torque (−R b) × F
        k = -r * inv_i
        w[0] += k * (by * fz - bz * fy)
        w[1] += k * (bz * fx - bx * fz)
        w[2] += k * (bx * fy - by * fx)


@njit
def _landing_friction(i, w, vn, flight, dyn, walls, pair_table, flags):
    """Sphere i lands on wall w with normal velocity ``vn`` [m/s] (its approach, or the rebound
    given up): a landing is a perfectly plastic impact, in which the wall takes the normal
    impulse m |v_n| that stops the sphere and gives its Coulomb friction for it
    (:func:`foot_friction`, μ the pair's sliding friction, model.md §4) [OURS,
    docs/enduring-contact.md, "From bouncing to contact"]. On a fixed flat wall; a moving
    plane, a cylinder or a fixed sphere gives none here. Without it, the load that a rattling
    bed passes to its floor through landings (each at most the landing speed) took no
    friction: a bed on a 7° slope with μ = 0.08 slid at 0.45–0.52 m/s² where its weight's
    friction allows 0.36 (corpus 0-69's variant against LAMMPS)."""
    if not flags[FL_FRICTION] or moving(walls, w) or not flat_fixed(walls, w):
        return
    rotation = flags[FL_ROTATION]
    mu = pair_table[dyn.mat[i], walls.planes_mat[w]][P_MU_S]
    foot_friction(i, abs(vn) / dyn.inv_m[i], mu, walls.planes_n[w, 0], walls.planes_n[w, 1],
                  walls.planes_n[w, 2], flight.st, dyn, dyn.omg[i] if rotation else dyn.omg[0],
                  rotation)


@njit
def _dissipative_friction(i, j, nx, ny, nz, jx, jy, jz, bi, bj, ci, cj, inv_mi, inv_mj,
                          inv_ii, inv_ij, ri, rj, st, wi, wj, inv_m, rotation):
    """Friction that does not add energy to a backed collision [OURS]. The collision model
    finds the tangential impulse of a backed sphere with its reduced inverse mass (1 − c²)/m
    along every direction, and the support then takes the impulse's part along its normal
    from the translation but not from the spin: the contact can end slipping backwards faster
    than it slipped, and the pair gain kinetic energy (605 of 5,045 random backed collisions
    against an immovable partner did, by up to 150 %; docs/enduring-contact.md, "Backing").
    The velocities and spins after the collision are affine in a factor s on the tangential
    impulse J_t (s = 1 as the model found it, s = 0 frictionless); where s = 1 leaves more
    kinetic energy than s = 0, J_t is scaled to the s in [0, 1] that leaves the least, the
    impulse along its direction that ends the slip along it for the backed bodies. J [N s]
    is the impulse on i, n its unit normal from j to i; bi, bj the supports' unit normals
    (used where ci, cj > 0); inv_mi, inv_mj, inv_ii, inv_ij the inverse masses and moments
    the collision used (0: held)."""
    jn = jx * nx + jy * ny + jz * nz
    tx, ty, tz = jx - jn * nx, jy - jn * ny, jz - jn * nz
    dvi = _friction_push(tx, ty, tz, ci, bi, inv_m[i], inv_mi)
    dvj = _friction_push(-tx, -ty, -tz, cj, bj, inv_m[j], inv_mj)
    # both spins change by −R inv_I (n × J_t): the impulse J_t at −R_i n on i, −J_t at +R_j n
    # on j
    cx, cy, cz = ny * tz - nz * ty, nz * tx - nx * tz, nx * ty - ny * tx
    lin = quad = 0.0  # kinetic energy E(s) = E(0) + lin s + quad s²
    mi, mj = 1.0 / inv_m[i], 1.0 / inv_m[j]
    for k in range(3):
        for p, d, mass in ((i, dvi[k], mi), (j, dvj[k], mj)):
            lin += mass * (st[p, 3 + k] - d) * d
            quad += 0.5 * mass * d * d
    if rotation:
        for w, inv_rot, r in ((wi, inv_ii, ri), (wj, inv_ij, rj)):
            if inv_rot > 0.0:
                for k, ck in enumerate((cx, cy, cz)):
                    d = -r * inv_rot * ck
                    lin += (w[k] - d) * d / inv_rot
                    quad += 0.5 * d * d / inv_rot
    if not lin + quad > 0.0:
        return
    back = 1.0 - min(1.0, max(0.0, -lin / (2.0 * quad)))  # 1 − s
    for k in range(3):
        st[i, 3 + k] -= back * dvi[k]
        st[j, 3 + k] -= back * dvj[k]
    if rotation:
        for w, inv_rot, r in ((wi, inv_ii, ri), (wj, inv_ij, rj)):
            w[0] += back * r * inv_rot * cx
            w[1] += back * r * inv_rot * cy
            w[2] += back * r * inv_rot * cz


@njit(inline="always")
def _stays_asleep(p, c, st, mstate, mplane, v_sleep):
    """Whether sphere p, asleep on a sphere and pressed into it (support cosine c > 0), stays
    asleep with its present velocity: slower than ``v_sleep`` (the landing speed)."""
    return (mstate[p] == MS_REST and mplane[p] <= -2 and c > 0.0
            and st[p, 3] ** 2 + st[p, 4] ** 2 + st[p, 5] ** 2 <= v_sleep * v_sleep)


@njit(inline="always")
def _slow_touch_at_rest(p, q, nx, ny, nz, st, mstate, v_sleep):
    """Whether sphere p is at rest (on a plane or asleep on a sphere) and sphere q meets it
    (unit normal n from q to p) with a normal approach speed of at most ``v_sleep``."""
    if mstate[p] != MS_REST:
        return False
    vn = ((st[q, 3] - st[p, 3]) * nx + (st[q, 4] - st[p, 4]) * ny
          + (st[q, 5] - st[p, 5]) * nz)
    return vn <= v_sleep


@njit
def _after_backed(p, c, t, no_end, flight, dyn, walls, gravity, pair_table, fsc, friction,
                  rolling, rotation):
    """Motion state of sphere p after a pair collision (c: its support cosine). A backed sphere
    on a plane starts a new segment there; a backed sleeper stays asleep if it is left slower
    than the landing speed (giving up less than ½ m v_land²); any other flies."""
    st, mstate, mplane = flight.st, flight.mstate, flight.mplane
    if mstate[p] == MS_FLIGHT:
        return
    if c > 0.0 and mplane[p] >= 0:
        enter_plane(p, np.int64(mplane[p]), t, no_end, flight, dyn, walls, gravity, pair_table,
                     fsc, friction, rolling, rotation)
        return
    if _stays_asleep(p, c, st, mstate, mplane, fsc[F_LANDING_SPEED]):
        halt(p, st, dyn.omg, rotation)
        return
    leave_plane(p, flight, dyn, gravity, rotation)
    if mplane[p] < -1:
        mplane[p] = -1  # no longer asleep on a sphere


#: Code stored as the normal-model stage of a hop in the event log.
STAGE_HOP = -1


@njit(inline="always")
def _record_hop(rec, jn, lost):
    """The collision record of a hop (_hop, _wall_hop): normal impulse jn [N s], stage
    STAGE_HOP, and the energy ``lost`` [J] (negative: a hop adds energy)."""
    for k in range(rec.shape[0]):
        rec[k] = math.nan
    rec[REC_J_N] = jn
    rec[REC_J_T] = 0.0
    rec[REC_STAGE] = STAGE_HOP
    rec[REC_REGIME] = 0
    rec[REC_ENERGY_LOST] = lost


@njit
def _hop(i, j, nx, ny, nz, inv_mi, inv_mj, st, acc, rec, tc):
    """A hop of touching spheres i, j (unit normal n from j to i) that their accelerations
    press together and that meet slower than v_hop = a_n t_c / 2 (a_n the pressing relative
    acceleration [m/s²], t_c the TC time): an enduring sphere–sphere contact, which has no
    motion state of its own, would otherwise be a zero-time sequence of ever-smaller
    collisions (or of re-check failures) [OURS]. The normal relative velocity is set to +v_hop,
    so that they touch again a TC time later; the kinetic energy this adds, at most
    ½ m_eff v_hop² (~1e-14 J for millimetre steel spheres), is booked as negative dissipation.
    A sphere given an inverse mass of 0 (one at rest: the loop holds it) is not moved.
    Returns False (nothing done) when the pair is not pressed together or meets faster."""
    a_n = ((acc[i, 0] - acc[j, 0]) * nx + (acc[i, 1] - acc[j, 1]) * ny
           + (acc[i, 2] - acc[j, 2]) * nz)
    inv_sum = inv_mi + inv_mj
    if not a_n < 0.0 or inv_sum == 0.0 or tc <= 0.0:
        return False
    vn = ((st[i, 3] - st[j, 3]) * nx + (st[i, 4] - st[j, 4]) * ny
          + (st[i, 5] - st[j, 5]) * nz)
    v_hop = -0.5 * a_n * tc
    if vn >= v_hop or -vn > v_hop:
        return False
    dv = v_hop - vn
    m_eff = 1.0 / inv_sum
    jn = m_eff * dv
    for k, nk in enumerate((nx, ny, nz)):
        st[i, S_V + k] += inv_mi * jn * nk
        st[j, S_V + k] -= inv_mj * jn * nk
    _record_hop(rec, jn, -0.5 * m_eff * (v_hop * v_hop - vn * vn))
    return True


@njit(inline="always")
def _hop_speed(i, w, t, flight, walls, tc):
    """(v·n_w [m/s], v_hop = a_n t_c / 2 [m/s]) of sphere i against wall w at time t [s],
    a_n being what its own motion presses it into w with (its acceleration there, plus c²/ρ
    along a cylinder's inside); v_hop is 0 where w does not press it or the TC model is off."""
    a_n, vn = pressed(i, w, t, flight.st, walls, flight.acc[i])
    if not a_n > 0.0 or tc <= 0.0:
        return vn, 0.0
    return vn, 0.5 * a_n * tc


@njit(inline="always")
def _needs_two_supports(p, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling):
    """Whether sphere p slides or rolls slower than the landing speed on a fixed flat wall
    whose slope it cannot rest on alone (_can_rest)."""
    m = flight.mstate[p]
    w = flight.mplane[p]
    if (m != MS_SLIDING and m != MS_ROLLING) or w < 0 or not flat_fixed(walls, w):
        return False
    st = flight.st
    v_land = fsc[F_LANDING_SPEED]
    return (st[p, 3] ** 2 + st[p, 4] ** 2 + st[p, 5] ** 2 <= v_land * v_land
            and not _can_rest(p, flight, dyn, walls, gravity, pair_table, friction, rolling))


@njit
def rests_on_two_planes(i, w, t, flight, dyn, walls, gravity, pair_table, fsc, friction,
                        rolling):
    """Whether sphere i, sliding or rolling slower than the landing speed on a fixed flat wall
    whose slope it cannot rest on alone, meets the fixed flat wall w pressed into it and
    slower than a hop (:func:`_wall_hop`) [OURS]: a contact with two walls at once that may
    hold it, which the cluster solve takes as a support by both (rest in the corner where
    friction holds it there, else constrained motion along it) instead of a hop. Hops there
    fed a limit cycle: a sphere rolled down an incline into a wall, hopped off it, rolled up,
    stopped, rolled back and hopped again, and never came to rest
    (docs/enduring-contact.md, "Two supports")."""
    if w == flight.mplane[i] or not flat_fixed(walls, w) or not _needs_two_supports(
            i, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling):
        return False
    vn, v_hop = _hop_speed(i, w, t, flight, walls, fsc[F_TC_TIME])
    return v_hop > 0.0 and vn < v_hop and -vn <= v_hop


@njit
def rests_on_plane_and_sphere(p, q, flight, dyn, walls, gravity, pair_table, fsc, friction,
                              rolling):
    """Whether sphere p, sliding or rolling slower than the landing speed on a fixed flat wall
    whose slope it cannot rest on alone, meets sphere q at rest [OURS]: the plane and q may
    hold it together, which the cluster solve decides (as :func:`rests_on_two_planes`). As a
    collision (elastic where the staged model is, at such speeds) a sphere on a 19° incline
    in a pocket of resting spheres bounced between them at 0.2 mm/s for ever."""
    return flight.mstate[q] == MS_REST and _needs_two_supports(
        p, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling)


@njit
def _wall_hop(i, w, t, ax, ay, az, ci, inv_mi, flight, walls, rec, tc):
    """A hop of sphere i, on a wall of normal a = (ax, ay, az), off a fixed wall w that its
    motion on its wall presses it into (a_n > 0: its acceleration there towards w, plus c²/ρ
    along a cylinder's inside) and that it meets slower than v_hop = a_n t_c / 2 [OURS; the
    wall form of _hop, whose reasons it shares]. ``ci`` = −n_w·a is the cosine between the two
    normals (< 1), ``inv_mi`` the sphere's inverse mass backed by its wall, (1 − ci²)/m.

    A sphere in flight (a = 0, ci = 0) hops off a fixed sphere that gravity presses it onto
    in the same way (collide_wall): a bead knocked off its rest on a chute's fixed bead, along
    the fixed bead's surface, met it again at once, found it not approaching (its normal
    speed 3e-19 m/s) and again, 1000 times, until the collapse guard stopped the run.

    A sphere sliding on a silo's floor along its cylindrical side keeps meeting the side: its
    straight path on the floor turns into the side at c²/ρ. Left to collisions, their normal
    speeds shrank to nothing and the sphere met the side 10¹⁰ times a second. The hop sets the
    normal speed off w to +v_hop within the sphere's wall (the change is along n_w − (n_w·a) a,
    so it stays on its wall), and the sphere meets w again a TC time later: it follows the
    side in chords of c t_c. The kinetic energy it adds is booked as negative dissipation.
    Returns False (nothing done) where w does not press the sphere or it meets faster."""
    st = flight.st
    vn, v_hop = _hop_speed(i, w, t, flight, walls, tc)
    if not v_hop > 0.0 or vn >= v_hop or -vn > v_hop:
        return False
    nx, ny, nz = walls.planes_n[w, 0], walls.planes_n[w, 1], walls.planes_n[w, 2]
    scale = (v_hop - vn) / (1.0 - ci * ci)
    ke0 = st[i, 3] ** 2 + st[i, 4] ** 2 + st[i, 5] ** 2
    st[i, 3] += scale * (nx + ci * ax)
    st[i, 4] += scale * (ny + ci * ay)
    st[i, 5] += scale * (nz + ci * az)
    ke1 = st[i, 3] ** 2 + st[i, 4] ** 2 + st[i, 5] ** 2
    _record_hop(rec, (v_hop - vn) / inv_mi, -0.5 * (ke1 - ke0) * (1.0 - ci * ci) / inv_mi)
    return True


@njit
def _resting_plane(i, st, walls, grid, gravity, v_land):
    """A plane that sphere i (in flight) touches within rounding while gravity presses it onto
    it and it moves off or onto it slower than the landing speed ``v_land`` [m/s], or −1. Such
    a sphere lands there at once: the rebound it would make is a landing's (the normal speed
    given up is at most v_land) [OURS]. A sphere wedged between neighbours on a plane and
    hopped off them, slightly upwards, would otherwise meet them again and again before it
    ever came back to the plane. Of several such planes, the one that carries the most of its
    weight (the largest load g_n): a sphere standing still in the corner of a silo's floor and
    its cylindrical side touches both, and the side's load, the centripetal c²/ρ of a creeping
    sphere, is next to nothing (on the side, gravity pulls it back onto the floor at once)."""
    n_near, first_part = near_walls(i, walls, grid)
    best = -1
    best_gn = 0.0
    for k in range(n_near):
        w = near_wall(k, walls, grid, first_part)
        if moving(walls, w) or not holds_now(walls, w, 0.0, gravity):
            continue  # a moving plane meets the sphere at its contact time instead; a fixed
            # sphere holds none
        gap = wall_gap(i, w, st, walls)
        if gap <= PLANE_TOUCHING_REL * st[i, S_R]:
            gn, vn = pressed(i, w, 0.0, st, walls, gravity)
            if gn > best_gn and abs(vn) <= v_land:
                best = w
                best_gn = gn
    return best


SETTLE_NONE = 0  #: the pair collides
SETTLE_PLANE = 1  #: a sphere lying on a plane landed there
SETTLE_SLEEP = 2  #: a sphere fell asleep on the other (progress: it cannot repeat until the
#: support moves, so the collapse guard does not count it)
SETTLE_STOP = 3  #: both stopped on their supports


@njit
def settle(i, j, nx, ny, nz, t, flight, dyn, walls, grid, gravity, pair_table, fsc, friction,
           rolling, rotation):
    """The rules that end a slow meeting of spheres i, j (unit normal n from j to i) in rest
    instead of a collision, in this order [OURS]:

    1. one of them, in flight, lies on a plane it meets slower than the landing speed
       (_resting_plane): it lands there first;
    2. one falls asleep on the other (_falls_asleep; a slow support on a plane is brought to
       rest first, and if it cannot rest there, a steep incline, they collide);
    3. both are on supports, slow, and able to rest there (_both_slow_on_supports): both
       stop.

    Returns (rule, sphere, partner): the rule that applied (SETTLE_*, SETTLE_NONE when the
    pair collides), and the sphere and partner of the event log's landing entry (partner
    −1 − w for plane w).
    """
    st, counter, mstate, mplane = flight.st, flight.counter, flight.mstate, flight.mplane
    v_land = fsc[F_LANDING_SPEED]
    no_end = np.int64(END_NONE)
    for p in (i, j):
        if mstate[p] == MS_FLIGHT:
            w = _resting_plane(p, st, walls, grid, gravity, v_land)
            if w >= 0:
                enter_plane(p, w, t, no_end, flight, dyn, walls, gravity, pair_table, fsc,
                             friction, rolling, rotation)
                counter[p] += 1
                return SETTLE_PLANE, p, -1 - w
    # jammed: by its own count, or by the pair's zero-time events (the event's sphere i
    # counts them: a sphere rolling from standstill on a chute into a bead at rest on the
    # base, both stopped and it rolling again, at one instant, 1000 times)
    zstreak = dyn.zstreak
    sleeper = _falls_asleep(i, j, nx, ny, nz, st, mstate, mplane, gravity, v_land,
                            _jammed(i, dyn) or zstreak[j] > JAM_EVENTS,
                            _jammed(j, dyn) or zstreak[i] > JAM_EVENTS)
    if sleeper >= 0:
        other = j if sleeper == i else i
        if mstate[other] != MS_REST:
            # giving up less than ½ m v_land²
            stop_on_plane(other, t, flight, dyn, walls, gravity, pair_table, fsc, friction,
                           rolling, rotation)
        if mstate[other] == MS_REST:
            # the sphere stays on its support, which is not moved
            _fall_asleep(sleeper, other, flight, dyn, rotation)
            counter[sleeper] += 1
            return SETTLE_SLEEP, sleeper, other
    if _both_slow_on_supports(i, j, flight, dyn, walls, gravity, pair_table, friction, rolling,
                              v_land):
        for p in (i, j):
            if mstate[p] != MS_REST:
                stop_on_plane(p, t, flight, dyn, walls, gravity, pair_table, fsc, friction,
                               rolling, rotation)
        return SETTLE_STOP, i, j
    return SETTLE_NONE, -1, 0


# ---- the interface the event loop uses (with gravity only) ---------------------------------

@njit(inline="always")
def _hold(held, c, inv_m, inv_i):
    """(support cosine, inverse mass, inverse moment of inertia) of a sphere in a pair
    collision: its own, or zeros for a sphere held where it is (it is not moved)."""
    if held:
        return 0.0, 0.0, 0.0
    return c, inv_m, inv_i


# The two collisions under gravity are compiled functions of their own, not inlined into the
# loop: numba's inliner re-processes an inlined body at every level it passes through, and
# with the contact model inside them that tripled the loop's compile time
# (docs/performance.md). A call costs the copy of its arguments, which the settling scenes do
# not measurably feel; the loop without gravity has the plain collision inlined.
@njit
def collide_pair(i, j, t, nx, ny, nz, dx, dy, dz, flight, dyn, walls, space, grid, sched, isc,
                 pair_table, fsc, rec, counts, flags):
    """Collide touching spheres i, j (unit normal n from j to i, r = x_i − x_j = (dx, dy, dz)
    [m]) under gravity, with the enduring-contact rules [OURS, docs/enduring-contact.md]: a
    sphere pressed into its support (a plane, or a sphere it sleeps on) is backed by it; a
    pair pressed together and meeting slowly hops (:func:`_hop`); a resting sphere met slowly
    is held where it is; a sleeper the collision leaves asleep is treated as immovable; after
    it, backed spheres stay on their planes, sleepers of a sphere set moving fall, and a
    sphere wedged in a zero-time sequence against an immovable body is stopped
    (:func:`_wedge_stop`).

    Returns:
        (hit, tc_on, wedged_a, wedged_b): whether the collision was executed (False: the
        re-check found the pair not approaching, nothing changed), whether the TC model made
        it elastic, and the spheres it stopped in a wedge (−1 for none).
    """
    plasticity, friction, rolling = flags[FL_PLASTICITY], flags[FL_FRICTION], flags[FL_ROLLING]
    adhesion, rotation = flags[FL_ADHESION], flags[FL_ROTATION]
    no_end = np.int64(END_NONE)
    st, mstate, mplane = flight.st, flight.mstate, flight.mplane
    omg, inv_m, inv_i, mat, zstreak = dyn.omg, dyn.inv_m, dyn.inv_i, dyn.mat, dyn.zstreak
    gravity, box_len, periodic = space.gravity, space.box_len, space.periodic
    wedged_a = wedged_b = -1
    rest_i = mstate[i] == MS_REST
    rest_j = mstate[j] == MS_REST
    wi = omg[i] if rotation else omg[0]
    wj = omg[j] if rotation else omg[0]
    ri = st[i, S_R]
    rj = st[j, S_R]
    # a sphere on a plane that the impulse presses into the plane is backed by it
    bix, biy, biz = _support_normal(i, st, mstate, mplane, walls, box_len, periodic)
    bjx, bjy, bjz = _support_normal(j, st, mstate, mplane, walls, box_len, periodic)
    ci = _support_cos(nx, ny, nz, bix, biy, biz)
    cj = _support_cos(-nx, -ny, -nz, bjx, bjy, bjz)
    if ci * ci + cj * cj >= 2.0 - SUPPORT_EPS:
        ci = cj = 0.0  # pressed into two facing planes at once: no rigid limit
    vi0x, vi0y, vi0z = st[i, 3], st[i, 4], st[i, 5]
    vj0x, vj0y, vj0z = st[j, 3], st[j, 4], st[j, 5]
    wi0x, wi0y, wi0z = wi[0], wi[1], wi[2]
    wj0x, wj0y, wj0z = wj[0], wj[1], wj[2]
    inv_mi = inv_m[i] * (1.0 - ci * ci)
    inv_mj = inv_m[j] * (1.0 - cj * cj)
    inv_ii, inv_ij = inv_i[i], inv_i[j]
    row, tc_on = tc_row(pair_table[mat[i], mat[j]], t, dyn.t_last[i], dyn.t_last[j], fsc,
                        dyn.row_tc)
    # pressed together by their accelerations and meeting slower than a hop: a hop instead of
    # a collision (see _hop); a sphere at rest is held where it is
    held_i = mstate[i] == MS_REST
    held_j = mstate[j] == MS_REST
    hit = _hop(i, j, nx, ny, nz, 0.0 if held_i else inv_mi, 0.0 if held_j else inv_mj, st,
               flight.acc, rec, fsc[F_TC_TIME])
    if hit:
        counts[EV_HOP] += 1
        tc_on = False
        ci, inv_mi, inv_ii = _hold(held_i, ci, inv_mi, inv_ii)
        cj, inv_mj, inv_ij = _hold(held_j, cj, inv_mj, inv_ij)
    else:
        # a sphere at rest met slower than the landing speed is held where it is: such a touch
        # cannot move it in a pile [OURS]; knocked off, it would stop again at once and be
        # knocked off again (a zero-time sequence)
        held_i = _slow_touch_at_rest(i, j, nx, ny, nz, st, mstate, fsc[F_LANDING_SPEED])
        held_j = _slow_touch_at_rest(j, i, -nx, -ny, -nz, st, mstate, fsc[F_LANDING_SPEED])
        if held_i and held_j:
            held_i = held_j = False  # two resting spheres never approach each other
        ci, inv_mi, inv_ii = _hold(held_i, ci, inv_mi, inv_ii)
        cj, inv_mj, inv_ij = _hold(held_j, cj, inv_mj, inv_ij)
    hopped = hit
    for attempt in range(2):
        if not hit and approaching(i, j, dx, dy, dz, ri + rj, st):
            hit = resolve(st[i, S_V:S_V + 3], wi, st[j, S_V:S_V + 3], wj, nx, ny, nz, inv_mi,
                          inv_mj, inv_ii, inv_ij, ri, rj, 1.0 / ri + 1.0 / rj, row, rec,
                          plasticity, friction, rolling, adhesion, rotation, False,
                          flags[FL_COMPLIANCE], flags[FL_VISCOUS])
        if hit and (ci > 0.0 or cj > 0.0):
            # the impulse J on i, recovered from the body that moved freely along n
            if inv_mi >= inv_mj:
                jx = (st[i, 3] - vi0x) / inv_mi
                jy = (st[i, 4] - vi0y) / inv_mi
                jz = (st[i, 5] - vi0z) / inv_mi
            else:
                jx = -(st[j, 3] - vj0x) / inv_mj
                jy = -(st[j, 4] - vj0y) / inv_mj
                jz = -(st[j, 5] - vj0z) / inv_mj
            if ci > 0.0:
                _backed_velocity(i, vi0x, vi0y, vi0z, jx, jy, jz, bix, biy, biz, st, inv_m)
            if cj > 0.0:
                _backed_velocity(j, vj0x, vj0y, vj0z, -jx, -jy, -jz, bjx, bjy, bjz, st, inv_m)
            if friction:
                _dissipative_friction(i, j, nx, ny, nz, jx, jy, jz, (bix, biy, biz),
                                      (bjx, bjy, bjz), ci, cj, inv_mi, inv_mj, inv_ii, inv_ij,
                                      ri, rj, st, wi, wj, inv_m, rotation)
                # the support's own friction for the normal impulse it took
                if ci > 0.0:
                    _support_friction(i, -(jx * bix + jy * biy + jz * biz), bix, biy, biz,
                                      flight, dyn, walls, pair_table, wi, rotation)
                if cj > 0.0:
                    _support_friction(j, jx * bjx + jy * bjy + jz * bjz, bjx, bjy, bjz,
                                      flight, dyn, walls, pair_table, wj, rotation)
        if not hit or hopped or held_i or held_j or attempt > 0:
            break
        # A sleeper that the collision leaves asleep (see _after_backed) has not moved: the
        # collision was with an immovable body, so it is redone as one [OURS]. Otherwise a
        # heavier sphere meeting a lighter sleeper would keep approaching it after each
        # collision (the sleeper's share of the momentum vanishing as it is stopped): a
        # zero-time sequence of collisions with impulses shrinking geometrically.
        held_i = _stays_asleep(i, ci, st, mstate, mplane, fsc[F_LANDING_SPEED])
        held_j = _stays_asleep(j, cj, st, mstate, mplane, fsc[F_LANDING_SPEED])
        if held_i == held_j:
            held_i = held_j = False  # (both: two sleepers never approach each other)
            break
        st[i, 3], st[i, 4], st[i, 5] = vi0x, vi0y, vi0z
        st[j, 3], st[j, 4], st[j, 5] = vj0x, vj0y, vj0z
        wi[0], wi[1], wi[2] = wi0x, wi0y, wi0z
        wj[0], wj[1], wj[2] = wj0x, wj0y, wj0z
        ci, inv_mi, inv_ii = _hold(held_i, ci, inv_mi, inv_ii)
        cj, inv_mj, inv_ij = _hold(held_j, cj, inv_mj, inv_ij)
        hit = False
    if not hit:
        return False, tc_on, wedged_a, wedged_b
    # a backed sphere stays on its plane (a new segment from its new velocity and spin); one
    # pulled off it, or asleep on a sphere, flies
    if not held_i:
        _after_backed(i, ci, t, no_end, flight, dyn, walls, gravity, pair_table, fsc, friction,
                      rolling, rotation)
    if not held_j:
        _after_backed(j, cj, t, no_end, flight, dyn, walls, gravity, pair_table, fsc, friction,
                      rolling, rotation)
    # spheres asleep on a sphere that was at rest and now moves fall again
    if rest_i and mstate[i] != MS_REST:
        wake_sleepers(i, t, flight, dyn, walls, space, grid, sched, isc, flags[FL_GRAVITY],
                      rotation)
    if rest_j and mstate[j] != MS_REST:
        wake_sleepers(j, t, flight, dyn, walls, space, grid, sched, isc, flags[FL_GRAVITY],
                      rotation)
    # a zero-time sequence against a sphere the collision left at rest, or against one stopped
    # in such a sequence at this instant (met at standstill: a chain between immovable ends,
    # see _wedge_stop); not after a hop, whose separation is what ends its zero-time meetings
    i_holds = _holds(i, vi0x, vi0y, vi0z, mstate, zstreak)
    j_holds = _holds(j, vj0x, vj0y, vj0z, mstate, zstreak)
    if not hopped and j_holds and _wedge_stop(i, t, flight, dyn, walls, gravity, pair_table,
                                              fsc, friction, rolling, rotation):
        wedged_a = i
    if not hopped and i_holds and _wedge_stop(j, t, flight, dyn, walls, gravity, pair_table,
                                              fsc, friction, rolling, rotation):
        wedged_b = j
    return True, tc_on, wedged_a, wedged_b


@njit(inline="always")
def _sleeps_on_ball(i, w, gn, flight, dyn, gravity, v_land, rotation):
    """Whether sphere i, meeting fixed sphere (or corner) w from above (load g_n = −g·n > 0
    [m/s²]), falls asleep on it, as on a resting sphere (_falls_asleep, [OURS]): slower than
    the landing speed ``v_land`` [m/s], with the contact within 60° of the upward vertical
    (SUPPORT_COS), or, jammed (JAM_EVENTS rapid events in succession), pointing upwards at all
    (JAM_SUPPORT_COS). It then rests there (hsgran._flight.rest_on) until it is hit.

    A bead falling into a chute's rough base of fixed beads lands in a pocket of two or three
    of them, which the hard-sphere loop sees as an endless buzz of collisions with each: a
    440-bead chute stopped at the collapse guard at 0.044 s, a bead sent back and forth
    between two fixed beads 1e-10 s apart."""
    st = flight.st
    if st[i, 3] ** 2 + st[i, 4] ** 2 + st[i, 5] ** 2 > v_land * v_land:
        return False
    g = math.sqrt(gravity[0] ** 2 + gravity[1] ** 2 + gravity[2] ** 2)
    if gn < (JAM_SUPPORT_COS if _jammed(i, dyn) else SUPPORT_COS) * g:
        return False
    if flight.mstate[i] != MS_FLIGHT:
        leave_plane(i, flight, dyn, gravity, rotation)
    rest_on(i, w, flight, dyn, rotation)
    return True


@njit(inline="always")
def _falls_back(i, a, w, st, walls, gravity, v_land):
    """Whether sphere i, on wall a (or touching it, gravity pressing it on) and meeting wall w,
    would close on a at once if it moved onto w [OURS]: it does not leave a (normal speed off
    it at most the landing speed ``v_land`` [m/s]) and gravity along w's surface presses it
    into a.

    A sphere sliding on a silo's floor along its cylindrical side is pressed into the side by
    its own motion (the centripetal load c²/ρ, hsgran._cylinder), but on the side gravity
    pulls it straight back onto the floor it touches: moved onto the side it landed on the
    floor again at the same instant, and back, without end (a 1200-bead silo pour stopped at
    the collapse guard at 0.058 s). Such a sphere stays on a, and the collision with w is
    backed by a (collide_wall). A sphere rolling from a floor up a slope moves away from the
    floor and does move onto the slope."""
    ax, ay, az = wall_normal(walls, a, st[i, 0], st[i, 1], st[i, 2])
    if st[i, 3] * ax + st[i, 4] * ay + st[i, 5] * az > v_land:
        return False
    nx, ny, nz = walls.planes_n[w, 0], walls.planes_n[w, 1], walls.planes_n[w, 2]
    gw = gravity[0] * nx + gravity[1] * ny + gravity[2] * nz
    # gravity along w's surface, dotted with a's normal
    return ((gravity[0] - gw * nx) * ax + (gravity[1] - gw * ny) * ay
            + (gravity[2] - gw * nz) * az) < 0.0


@njit(inline="always")
def lands_before_wall(i, w, t, flight, dyn, walls, grid, gravity, pair_table, fsc, flags):
    """Whether sphere i, meeting plane w at time t, is too slow to bounce and stays on it
    instead (MODEL §5.3; what is given up is the rebound, at most ½ m v_land², see
    hsgran.scene). It is then put on the plane.

    Not if on w it would fall back at once onto the wall a it is on, or, in flight, the wall
    it rests on (_resting_plane; it lands there instead): it stays on a, and the collision
    with w is backed by a (_falls_back, collide_wall)."""
    friction, rolling, rotation = flags[FL_FRICTION], flags[FL_ROLLING], flags[FL_ROTATION]
    v_land = fsc[F_LANDING_SPEED]
    gn, vn = pressed(i, w, t, flight.st, walls, gravity)
    if not (gn > 0.0 and -vn <= v_land):
        return False
    if ball(walls, w):
        return _sleeps_on_ball(i, w, gn, flight, dyn, gravity, v_land, rotation)
    if not holds_now(walls, w, t, gravity):
        return False  # a moving plane pulling away: it hits the sphere (or misses it)
    a = np.int64(flight.mplane[i])
    if flight.mstate[i] == MS_FLIGHT:
        a = _resting_plane(i, flight.st, walls, grid, gravity, v_land)
    if a >= 0 and a != w and _falls_back(i, a, w, flight.st, walls, gravity, v_land):
        if flight.mstate[i] == MS_FLIGHT:
            enter_plane(i, a, t, np.int64(END_NONE), flight, dyn, walls, gravity, pair_table,
                        fsc, friction, rolling, rotation)
        return False  # on a, backed by it against w (collide_wall)
    if flight.mstate[i] != MS_FLIGHT:
        leave_plane(i, flight, dyn, gravity, rotation)
    _landing_friction(i, w, vn, flight, dyn, walls, pair_table, flags)
    enter_plane(i, w, t, np.int64(END_NONE), flight, dyn, walls, gravity, pair_table, fsc,
                friction, rolling, rotation)
    return True


@njit
def collide_wall(i, w, t, flight, dyn, walls, gravity, pair_table, fsc, rec, flags):
    """Collide sphere i with plane w under gravity, with the enduring-contact rules [OURS]: a
    sphere on another plane is backed by it (a sphere sliding into a side wall), one knocked
    off its plane flies, one whose rebound is slower than the landing speed lands, and a
    sphere wedged in a zero-time sequence is stopped (an immovable plane). A moving plane hits
    with its velocity at t; a sphere lands on it by its speed relative to the plane and the
    load in its frame (hsgran._riding), and is never wedge-stopped against it.

    Returns:
        (hit, tc_on, landed, wedged): whether the collision was executed (False: the re-check
        found it not approaching, nothing changed), whether the TC model made it elastic,
        whether the sphere landed on the plane, and whether it was stopped in a wedge.
    """
    plasticity, friction, rolling = flags[FL_PLASTICITY], flags[FL_FRICTION], flags[FL_ROLLING]
    adhesion, rotation = flags[FL_ADHESION], flags[FL_ROTATION]
    no_end = np.int64(END_NONE)
    st, mstate, mplane, omg, inv_m = flight.st, flight.mstate, flight.mplane, dyn.omg, dyn.inv_m
    planes_n, planes_mat = walls.planes_n, walls.planes_mat
    wi = omg[i] if rotation else omg[0]
    ri = st[i, S_R]
    ci = -1.0
    pw = -1
    pnx = pny = pnz = 0.0  # the normal of the wall sphere i is on
    if mstate[i] != MS_FLIGHT and mplane[i] >= 0:
        # on another plane (a sphere sliding into a side wall): backed by that plane as in the
        # pair case, unless the wall pulls it off (or squeezes it head-on)
        pw = mplane[i]
        pnx, pny, pnz = wall_normal(walls, pw, st[i, 0], st[i, 1], st[i, 2])
        ci = -(planes_n[w, 0] * pnx + planes_n[w, 1] * pny + planes_n[w, 2] * pnz)
        if ci < 0.0 or ci * ci >= 1.0 - SUPPORT_EPS:
            ci = -1.0
    vi0x, vi0y, vi0z = st[i, 3], st[i, 4], st[i, 5]
    inv_mi = inv_m[i] * (1.0 - ci * ci) if ci >= 0.0 else inv_m[i]
    # a backed sphere that its motion on its wall presses into w and that meets w slower than
    # a hop: a hop off w instead of a collision (_wall_hop)
    driven = not immovable(walls, w)
    if ci >= 0.0 and not driven and _wall_hop(i, w, t, pnx, pny, pnz, ci, inv_mi, flight,
                                              walls, rec, fsc[F_TC_TIME]):
        enter_plane(i, np.int64(mplane[i]), t, no_end, flight, dyn, walls, gravity, pair_table,
                    fsc, friction, rolling, rotation)
        return True, False, False, False
    # a sphere in flight that gravity presses onto a fixed sphere it slides over (it has no
    # motion on one): a hop, as off a sphere (_hop)
    if (mstate[i] == MS_FLIGHT and ball(walls, w)
            and _wall_hop(i, w, t, 0.0, 0.0, 0.0, 0.0, inv_m[i], flight, walls, rec,
                          fsc[F_TC_TIME])):
        return True, False, False, False
    row, tc_on = tc_row(pair_table[dyn.mat[i], planes_mat[w]], t, dyn.t_last[i], -NEVER, fsc,
                        dyn.row_tc)
    # a moving plane's or a cylinder's velocity and normal at t are in planes_vel[w],
    # planes_n[w] (the wall handler); no sphere is wedge-stopped against a wall that moves or
    # turns
    hit = resolve(st[i, S_V:S_V + 3], wi, walls.planes_vel[w], walls.planes_omg[w],
                  planes_n[w, 0], planes_n[w, 1], planes_n[w, 2], inv_mi, 0.0, dyn.inv_i[i],
                  0.0, ri, 0.0, wall_curvature(walls, w, ri), row, rec, plasticity, friction,
                  rolling, adhesion,
                  rotation, False, flags[FL_COMPLIANCE], flags[FL_VISCOUS])
    if hit and ci >= 0.0:
        _backed_velocity(i, vi0x, vi0y, vi0z, (st[i, 3] - vi0x) / inv_mi,
                         (st[i, 4] - vi0y) / inv_mi, (st[i, 5] - vi0z) / inv_mi,
                         pnx, pny, pnz, st, inv_m)
    if not hit:
        return False, tc_on, False, False
    landed = False
    if ci >= 0.0:
        enter_plane(i, np.int64(mplane[i]), t, no_end, flight, dyn, walls, gravity, pair_table,
                    fsc, friction, rolling, rotation)
    else:
        if mstate[i] != MS_FLIGHT:
            leave_plane(i, flight, dyn, gravity, rotation)  # knocked off its plane
        gn, vn = pressed(i, w, t, st, walls, gravity)
        if gn > 0.0 and vn <= fsc[F_LANDING_SPEED] and holds_now(walls, w, t, gravity):
            _landing_friction(i, w, vn, flight, dyn, walls, pair_table, flags)
            enter_plane(i, w, t, no_end, flight, dyn, walls, gravity, pair_table, fsc, friction,
                        rolling, rotation)
            landed = True
    # a zero-time sequence against this plane (an immovable one)
    wedged = not landed and not driven and _wedge_stop(i, t, flight, dyn, walls, gravity,
                                                       pair_table, fsc, friction, rolling,
                                                       rotation)
    return True, tc_on, landed, wedged
