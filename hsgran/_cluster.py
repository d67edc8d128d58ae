"""Touching spheres and walls solved together: the cluster treatment of dense scenes (layer 5;
compiled kernels used by :mod:`hsgran._loop`, with gravity and ``[enduring_contact] treatment =
"clusters"``). What it does and what it costs is in docs/enduring-contact.md ("Clusters of
contacts").

A collision under gravity whose spheres touch nothing else, in flight, is the paper's binary
collision (the caller's). Otherwise the event's spheres and every body touching them are a
cluster (:func:`gather`), and at the event's instant:

1. **impulses** (Moreau 1988; Jean 1999): all contacts of the cluster at once, each with
   Newton's restitution (the pair's e_n from the collision model, MODEL §3, for an approach
   faster than the landing speed; 0 for a slower one: the contact persists) and a Coulomb cone
   (MODEL §4's μ_s; rolling couples with μ_r, MODEL §5.1), by
   :func:`hsgran.contact.cluster.solve`. Afterwards no contact of the cluster approaches;
2. **one step of contact dynamics** over the next segment, of length h (:func:`_segment_time`):
   the contacts that persist (no longer separating) take the impulses of one Moreau–Jean step
   under gravity, with the same cones, so that none approaches at the step's end; the
   velocity change over h gives each body constant accelerations for the segment (the
   piecewise-constant accelerations of Baraff's event-driven resting contact, found at the
   velocity level, where the solver converges also where sliding contacts would make the
   force-level problem diverge);
3. **motion states**: a sphere slower than the landing speed that its supports hold still at
   the step's end comes to rest; one whose only persisting contact is a plane takes the
   paper's motion on a plate (MODEL §5.3), or flies if the plane overhangs it
   (:func:`hsgran._flight.enter_plane`); one without persisting contacts flies; any other
   moves with the step's accelerations (``MS_SUPPORTED``) until its segment ends, when its
   cluster is solved again. A sphere at rest set moving wakes the resting spheres it
   touches, which are solved again at once.

Over a segment, the normal velocity of a persisting contact moves linearly from its value now
(≥ 0, up to the solver's tolerance) to its value at the step's end (≥ 0), so the contact never
closes: the prediction skips
a touching pair with a supported sphere whose normal velocity stays above −``Space.slack``
(the solver's tolerance) until the segment ends (:func:`hsgran._predict.held_apart`). No
zero-time sequence follows a solve.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._cylinder import concave
from hsgran._flight import (
    TOUCH_REL,
    advance,
    ball,
    curved,
    enter_plane,
    flat_fixed,
    halt,
    leave_plane,
    min_image,
    moving,
    set_wall_velocity,
    state_at,
    wall_gap,
)
from hsgran._jit import njit
from hsgran._predict import cell_heads, near_wall, near_walls, reschedule_fn
from hsgran._riding import moving_gap
from hsgran._settling import (
    WEDGE_EVENTS,
    rests_on_plane_and_sphere,
    rests_on_two_planes,
)
from hsgran._state import (
    F_CLUSTER_LOSS,
    F_LANDING_SPEED,
    FL_ADHESION,
    FL_CLUSTERS,
    FL_FRICTION,
    FL_PLASTICITY,
    FL_ROLLING,
    FL_ROTATION,
    FL_VISCOUS,
    I_FROZEN,
    I_SHORT,
    I_STEP_SWEEPS,
    I_SWEEPS,
    I_UNSOLVED,
    I_VISITS,
    S_R,
    S_T,
    WARM_EMPTY,
    WARM_SLOTS,
)
from hsgran.contact.cluster import cap, solve_polished, start
from hsgran.contact.model import (
    REC_CAPTURED,
    REC_E_N,
    REC_ENERGY_LOST,
    REC_J_N,
    REC_J_T,
    REC_REGIME,
    REC_STAGE,
    resolve,
)
from hsgran.materials import P_E_FIXED, P_MU_R, P_MU_S
from hsgran.motion import NEVER
from hsgran.onplane import END_NONE, END_RESOLVE, MS_FLIGHT, MS_REST, MS_SUPPORTED
from hsgran.wallspec import BL_RADIUS, CY_RADIUS

#: A segment of constant accelerations lasts until a contact between spheres has moved
#: tangentially by this fraction of σ [-]: the contact normal then turns by 1e-4 rad and the
#: spheres, which move along the tangent, lift off each other by 5e-9 σ; the cluster is then
#: solved again from the new normals.
CURVATURE_REL = 1e-4
#: Inside a cylinder a sphere moving along the tangent of its contact sinks into the wall,
#: by d²/2(ρ − r) after a distance d: a segment there lasts until it could have sunk by this
#: fraction of its radius [-], what the prediction takes as touching (hsgran._flight
#: PLANE_TOUCHING_REL), and the next solve puts it back on the surface (:func:`gather`).
CONCAVE_SINK_REL = 1e-10
#: A sphere whose collisions have not advanced the clock this many times in a row
#: (``zstreak``) is in a zero-time sequence the pairwise rules (``treatment = "pairwise"``)
#: have not ended: its next collision is solved as a cluster, and so is every collision of a
#: sphere in constrained motion after it (:func:`hands_over`). Twice the streak at which the
#: last pairwise rule acts (the wedge stop, hsgran._settling.WEDGE_EVENTS, after the jam rule's
#: JAM_EVENTS), so that every rule has had its turn; a quarter of the collapse guard's count
#: (hsgran._flight.MAX_ZERO_TIME_EVENTS). (At 100, before the wedge stop, small pours that
#: the wedge stop settles in seconds were handed over and ran for minutes.)
HAND_OVER_STREAK = 2 * WEDGE_EVENTS
#: In a cluster the pairwise rules hand over, spheres in flight or on a plane join it up to
#: this many contacts from the event's spheres; those further away are its boundary, moving
#: as before under gravity or on their plane (as are those beyond the scratch arrays' room).
#: A boundary sphere that then closes on a body meets it: that collision is solved as a
#: cluster with it. Spheres in constrained motion always join (their accelerations hang on
#: the bodies'; tried as a boundary moving with the accelerations of their own last solve,
#: which made a 14° chute's solves five times cheaper, its bed gained energy: beads were
#: thrown out at 3 m/s at 0.15 s, not yet traced). One contact: the spheres of a
#: zero-time sequence and those touching them, not the whole moving bed of a dense flow
#: (with all, a chute's bed of 355 spheres was solved again and again: 23,000 cluster
#: events took 317 s).
HAND_OVER_REACH = 1
#: Longest segment [s]: even a cluster whose contacts do not slide is solved again this often,
#: which bounds what the solver's tolerance can add up to (slack × MAX_SEGMENT = 1e-13 m of
#: overlap with the default landing speed).
MAX_SEGMENT = 1e-3
#: Shortest segment, relative to max(1 s, t) [-]: 1e4 times the collapse guard's "one instant"
#: (hsgran._flight.NO_PROGRESS_REL), so that every solve of a segment's end advances the clock.
MIN_SEGMENT_REL = 1e-9
#: Slack of the prediction for supported spheres, relative to the landing speed [-] (1e-10 m/s
#: with the default): above what the solver leaves (SOLVE_TOL_REL of it), below anything that
#: moves a sphere measurably within MAX_SEGMENT (1e-13 m).
SLACK_V_REL = 1e-7
#: The solves converge to this fraction of the slack (each contact's velocity, or acceleration,
#: within it of its target, and no impulse changing by more than that in a sweep) [-]: what
#: is left over is then below what the prediction forgives.
SOLVE_TOL_REL = 0.01
#: A contact slips when its slip speed exceeds this fraction of the landing speed [-] (below:
#: static friction); the same for rolling (R* times the rolling angular velocity). 1e-7 m/s
#: with the default landing speed: slower slips stop within a segment.
SLIP_REL = 1e-4
#: A sphere comes to rest when, besides being slower than the landing speed, its acceleration
#: and R times its angular acceleration are below this fraction of |g| [-]: far above the
#: residual of a converged force solve (~1e-12 |g|).
REST_ACC_REL = 1e-6
#: An impact (faster than the landing speed) moves the resting spheres up to this many contacts
#: away from the event's spheres (a row of five, Newton's cradle, in full); resting spheres
#: further away are immovable. A slower meeting moves none: a pile at rest carries it
#: (docs/enduring-contact.md). With the cluster treatment moving spheres are always part of
#: the cluster: held as a boundary moving as before, they could squeeze a body between them
#: and a wall (see HAND_OVER_REACH for the pairwise rules' clusters).
REST_DEPTH = 4
#: Target of a contact left out of the force solve (it separates): no force can act.
NO_CONTACT = -1e300

CL_ISOLATED = 0  #: the event's spheres touch nothing else in flight: a binary collision
CL_SOLVED = 1  #: the cluster was solved
#: Stage code of a collision solved in a cluster (event log; the normal model's are ≥ 0).
STAGE_CLUSTER = -2


@njit
def _add_body(q, depth, t, flight, dyn, clus, nb, rotation):
    """Make sphere q (advanced to t) the cluster's body nb."""
    st, omg = flight.st, dyn.omg
    advance(st, flight.acc, omg, dyn.alpha, q, t, True, rotation)
    clus.cl_loc[q] = nb
    clus.cl_body[nb] = q
    clus.cl_was[nb] = flight.mstate[q]
    clus.cl_depth[nb] = depth
    clus.cl_inv_m[nb] = dyn.inv_m[q]
    clus.cl_inv_i[nb] = dyn.inv_i[q]
    clus.cl_rad[nb] = st[q, S_R]
    for k in range(3):
        clus.cl_v[nb, k] = st[q, 3 + k]
        clus.cl_w[nb, k] = omg[q, k] if rotation else 0.0
    return nb + 1


@njit(inline="always")
def _add_contact(clus, nc, a, b, q, mat, nx, ny, nz, rb):
    """Contact nc between body a and body b (−1: immovable, partner q; −1 − w for plane w)."""
    clus.ck_a[nc] = a
    clus.ck_b[nc] = b
    clus.ck_q[nc] = q
    clus.ck_mat[nc] = mat
    clus.ck_n[nc, 0] = nx
    clus.ck_n[nc, 1] = ny
    clus.ck_n[nc, 2] = nz
    clus.ck_rb[nc] = rb
    for k in range(3):
        clus.ck_vb[nc, k] = 0.0
        clus.ck_ab[nc, k] = 0.0
    return nc + 1


@njit
def _boundary_motion(q, c, nx, ny, nz, t, flight, dyn, clus, rotation):
    """Velocity and acceleration of the contact point of immovable sphere q (n from q to the
    body) into contact c: a sphere at rest has none; a moving sphere beyond the cluster keeps
    its own (centripetal terms left out)."""
    st, acc = flight.st, flight.acc
    if flight.mstate[q] == MS_REST:
        return
    _, _, _, u, v, w = state_at(st, acc, q, t, True)
    rq = st[q, S_R]
    clus.ck_vb[c, 0], clus.ck_vb[c, 1], clus.ck_vb[c, 2] = u, v, w
    for k in range(3):
        clus.ck_ab[c, k] = acc[q, k]
    if rotation:
        om = dyn.omg[q]
        al = dyn.alpha[q]
        dt = t - st[q, S_T]
        ox, oy, oz = om[0] + al[0] * dt, om[1] + al[1] * dt, om[2] + al[2] * dt
        clus.ck_vb[c, 0] += rq * (oy * nz - oz * ny)
        clus.ck_vb[c, 1] += rq * (oz * nx - ox * nz)
        clus.ck_vb[c, 2] += rq * (ox * ny - oy * nx)
        clus.ck_ab[c, 0] += rq * (al[1] * nz - al[2] * ny)
        clus.ck_ab[c, 1] += rq * (al[2] * nx - al[0] * nz)
        clus.ck_ab[c, 2] += rq * (al[0] * ny - al[1] * nx)


# long: one breadth-first walk over the touching bodies; its cell scan, plane scan and the
# three kinds of partner (a body, a new body, the boundary) share the walk's state
@njit
def gather(s1, s2, t, fast, reach, flight, dyn, walls, space, grid, clus, rotation):
    """The cluster of sphere s1 (and s2, or −1): every body touching them, and every sphere in
    constrained motion touching those, and every other moving one up to ``reach`` contacts
    away, breadth first; in an impact
    (``fast``: faster than the landing speed) also the resting spheres up to REST_DEPTH
    contacts away, through which its impulse travels. Other spheres at rest are immovable
    partners, moving spheres beyond ``reach`` or the room of the scratch arrays the
    cluster's boundary. Walls are immovable partners
    moving as they do at t (a moving plane at its velocity then, a turning cylinder's surface
    with it). Returns (bodies, contacts, whether a moving plane is among the partners,
    whether a moving sphere is); the bodies are advanced to t."""
    st, acc, mstate, mat = flight.st, flight.acc, flight.mstate, dyn.mat
    planes_n, planes_mat = walls.planes_n, walls.planes_mat
    box_len, periodic, nxt = space.box_len, space.periodic, grid.nxt
    loc = clus.cl_loc
    max_b = clus.cl_body.shape[0]
    max_c = clus.ck_a.shape[0]
    nb = _add_body(s1, 0, t, flight, dyn, clus, 0, rotation)
    if s2 >= 0:
        nb = _add_body(s2, 0, t, flight, dyn, clus, nb, rotation)
    nc = 0
    driven = False
    left = False
    p = 0
    while p < nb:
        s = clus.cl_body[p]
        rs = st[s, S_R]
        n_near, first_part = near_walls(s, walls, grid)
        for k in range(n_near):
            w = near_wall(k, walls, grid, first_part)
            if moving(walls, w):
                gap, _ = moving_gap(st[s, 0], st[s, 1], st[s, 2], rs, walls, w, t)
                set_wall_velocity(walls, w, t)
            else:  # (its row's normal and velocity then those at its contact with s)
                gap = wall_gap(s, w, st, walls)
            if gap <= TOUCH_REL * rs and nc < max_c:
                driven = driven or moving(walls, w)
                if gap < 0.0 and concave(walls, w):
                    _to_surface(s, w, gap, st, walls)
                nc = _add_contact(clus, nc, p, -1, -1 - w, planes_mat[w], planes_n[w, 0],
                                  planes_n[w, 1], planes_n[w, 2],
                                  walls.planes_geo[w, BL_RADIUS]
                                  if ball(walls, w) else 0.0)
                for k in range(3):
                    clus.ck_vb[nc - 1, k] = walls.planes_vel[w, k]
        for h in range(cell_heads(s, grid, space)):
            q = np.int64(grid.heads[h])
            while q >= 0:
                lq = loc[q]
                if q != s and (lq < 0 or lq > p):
                    xq, yq, zq, _, _, _ = state_at(st, acc, q, t, True)
                    dx = min_image(st[s, 0] - xq, 0, box_len, periodic)
                    dy = min_image(st[s, 1] - yq, 1, box_len, periodic)
                    dz = min_image(st[s, 2] - zq, 2, box_len, periodic)
                    sigma = rs + st[q, S_R]
                    d = math.sqrt(dx * dx + dy * dy + dz * dz)
                    if d - sigma <= TOUCH_REL * sigma and nc < max_c:
                        nx, ny, nz = dx / d, dy / d, dz / d
                        if (lq < 0 and nb < max_b and (
                                mstate[q] == MS_SUPPORTED
                                or (mstate[q] != MS_REST and clus.cl_depth[p] < reach)
                                or (fast and clus.cl_depth[p] < REST_DEPTH))):
                            lq = nb
                            nb = _add_body(q, clus.cl_depth[p] + 1, t, flight, dyn,
                                           clus, nb, rotation)
                        if lq >= 0:
                            nc = _add_contact(clus, nc, p, lq, q, mat[q], nx, ny, nz,
                                              st[q, S_R])
                        else:
                            nc = _add_contact(clus, nc, p, -1, q, mat[q], nx, ny, nz,
                                              st[q, S_R])
                            _boundary_motion(q, nc - 1, nx, ny, nz, t, flight, dyn,
                                             clus, rotation)
                            left = left or mstate[q] != MS_REST
                q = np.int64(nxt[q])
        p += 1
    return nb, nc, driven, left


@njit(inline="always")
def _to_surface(s, w, gap, st, walls):
    """Put sphere s, sunk into concave wall w by −gap [m] (at most CONCAVE_SINK_REL of its
    radius over a segment, and a rounding), back on its surface, along the normal in its
    row."""
    for k in range(3):
        st[s, k] -= gap * walls.planes_n[w, k]


@njit
def release(nb, clus):
    """Forget the cluster's bodies (the sphere-to-body map back to −1)."""
    for b in range(nb):
        clus.cl_loc[clus.cl_body[b]] = -1


@njit
def _kinetic(nb, clus, rotation):
    """Kinetic energy of the cluster's bodies [J]."""
    e = 0.0
    for b in range(nb):
        v2 = clus.cl_v[b, 0] ** 2 + clus.cl_v[b, 1] ** 2 + clus.cl_v[b, 2] ** 2
        e += 0.5 * v2 / clus.cl_inv_m[b]
        if rotation:
            w2 = clus.cl_w[b, 0] ** 2 + clus.cl_w[b, 1] ** 2 + clus.cl_w[b, 2] ** 2
            e += 0.5 * w2 / clus.cl_inv_i[b]
    return e


@njit(inline="always")
def _normal_velocity(c, clus):
    """Relative normal velocity of contact c [m/s] (spins do not enter: the contact points lie
    on the normal)."""
    a = clus.ck_a[c]
    b = clus.ck_b[c]
    u = 0.0
    for k in range(3):
        vb = clus.cl_v[b, k] if b >= 0 else clus.ck_vb[c, k]
        u += (clus.cl_v[a, k] - vb) * clus.ck_n[c, k]
    return u


@njit
def _restitution(c, clus, row, rec, flags):
    """Normal restitution of contact c as a binary collision of its two bodies (MODEL §3, the
    pair's row; an immovable partner as a wall of infinite mass) [-]."""
    if row[P_E_FIXED] >= 0.0:
        return row[P_E_FIXED]
    a = clus.ck_a[c]
    b = clus.ck_b[c]
    v1, w1, v2, w2 = clus.ck_slip[c], clus.ck_rslip[c], clus.ck_pt[c], clus.ck_hr[c]
    for k in range(3):
        v1[k] = clus.cl_v[a, k]
        w1[k] = 0.0
        v2[k] = clus.cl_v[b, k] if b >= 0 else clus.ck_vb[c, k]
        w2[k] = 0.0
    r1 = clus.cl_rad[a]
    r2 = clus.ck_rb[c]
    curv = 1.0 / r1 + (1.0 / r2 if r2 > 0.0 else 0.0)
    resolve(v1, w1, v2, w2, clus.ck_n[c, 0], clus.ck_n[c, 1], clus.ck_n[c, 2],
            clus.cl_inv_m[a], clus.cl_inv_m[b] if b >= 0 else 0.0, 0.0, 0.0, r1, r2, curv, row,
            rec, flags[FL_PLASTICITY], False, False, flags[FL_ADHESION], False, False, False,
            flags[FL_VISCOUS])
    if rec[REC_CAPTURED] > 0.0:
        return 0.0
    return rec[REC_E_N]


@njit(inline="always")
def _cold(c, clus):
    """Contact c starts a solve from no impulse, with static friction and rolling (no kinetic
    directions)."""
    clus.ck_pn[c] = 0.0
    for k in range(3):
        clus.ck_pt[c, k] = 0.0
        clus.ck_hr[c, k] = 0.0
        clus.ck_slip[c, k] = 0.0
        clus.ck_rslip[c, k] = 0.0


@njit
def _impact_setup(nc, clus, pair_table, mat, rec, fsc, flags):
    """Targets, friction and rolling coefficients of the impulse solve (MODEL §3, §4, §5.1):
    an approach faster than the landing speed rebounds with the pair's e_n, a slower one not
    at all."""
    v_land = fsc[F_LANDING_SPEED]
    for c in range(nc):
        a = clus.ck_a[c]
        row = pair_table[mat[clus.cl_body[a]], clus.ck_mat[c]]
        un = _normal_velocity(c, clus)
        e = 0.0
        if un < -v_land:
            e = _restitution(c, clus, row, rec, flags)
        clus.ck_tgt[c] = -e * un if un < 0.0 else 0.0
        clus.ck_mu[c] = row[P_MU_S]
        clus.ck_mur[c] = row[P_MU_R]
        r1 = clus.cl_rad[a]
        r2 = clus.ck_rb[c]
        clus.ck_reff[c] = r1 * r2 / (r1 + r2) if r2 > 0.0 else r1
        _cold(c, clus)


@njit(inline="always")
def _room_time(room, v, a):
    """Time [s] in which a relative motion of speed v [m/s] and acceleration a [m/s²] covers
    the distance room [m] (v τ + a τ²/2 = room; inf if neither moves)."""
    if v <= 0.0 and a <= 0.0:
        return math.inf
    return 2.0 * room / (v + math.sqrt(v * v + 2.0 * a * room))


@njit(inline="always")
def _room(c, clus, walls):
    """How far contact c may move along its tangent before its cluster is solved again [m]:
    CURVATURE_REL × the sum of its radii of curvature (a sphere, a fixed sphere, a corner, an
    edge, a cylinder from outside), the distance that sinks a sphere by CONCAVE_SINK_REL of
    its radius inside a cylinder, and no limit on a flat wall (inf)."""
    r = clus.cl_rad[clus.ck_a[c]]
    q = clus.ck_q[c]
    w = -1 - q
    if clus.ck_b[c] >= 0 or q >= 0 or ball(walls, w):
        return CURVATURE_REL * (r + clus.ck_rb[c])  # (ck_rb: the partner's radius)
    if not curved(walls, w):
        return math.inf
    rho = walls.planes_cyl[w, CY_RADIUS]
    if concave(walls, w):
        return math.sqrt(2.0 * max(rho - r, 0.0) * CONCAVE_SINK_REL * r)
    return CURVATURE_REL * (r + rho)


@njit
def _segment_time(nc, clus, h, solved, t, walls):
    """Length of a segment of constant accelerations [s]: until a contact could have moved
    along its tangent by its :func:`_room` (between spheres CURVATURE_REL σ: the normal then
    turns by 1e-4 rad, and the spheres, which move along the tangent, lift off each other by
    5e-9 σ), at most
    ``h`` (MAX_SEGMENT for the step), at least MIN_SEGMENT_REL × max(1 s, t). Before the
    step's solve (``solved`` False) from the relative velocities only: the step's length h;
    after it, with the relative accelerations the solve gave too: the segment's length, at
    most h (the accelerations keep every persisting contact from closing over the whole
    step, so over any part of it too)."""
    tau = h
    for c in range(nc):
        if clus.ck_tgt[c] == NO_CONTACT:
            continue  # separating
        room = _room(c, clus, walls)
        if room == math.inf:
            continue  # flat
        a = clus.ck_a[c]
        b = clus.ck_b[c]
        v2 = a2 = 0.0
        for k in range(3):
            v2 += (clus.cl_v[a, k] - (clus.cl_v[b, k] if b >= 0 else clus.ck_vb[c, k])) ** 2
            if solved:  # a boundary's ck_ab holds its velocity at the step's end
                a2 += (clus.cl_a[a, k] - (clus.cl_a[b, k] if b >= 0 else
                                          (clus.ck_ab[c, k] - clus.ck_vb[c, k]) / h)) ** 2
        tau = min(tau, _room_time(room, math.sqrt(v2), math.sqrt(a2)))
    return max(tau, MIN_SEGMENT_REL * max(1.0, t))


@njit(inline="always")
def _warm_key(c, clus):
    """Where contact c's force is kept (:func:`_warm_load`): (owner sphere, partner code,
    sign): the pair's lower sphere keeps it (a sphere its planes' too); sign −1 when the owner
    is b (the force on a is then minus the kept one)."""
    sa = np.int64(clus.cl_body[clus.ck_a[c]])
    q = clus.ck_q[c]
    if q < 0 or sa < q:
        return sa, q, 1.0
    return q, sa, -1.0


@njit(inline="always")
def _warm_slot(clus, owner, partner, free):
    """Slot of ``owner``'s kept forces for ``partner``; if it has none, the first empty slot
    when ``free``, else −1."""
    empty = -1
    for k in range(WARM_SLOTS):
        q = clus.wm_q[owner, k]
        if q == partner:
            return k
        if q == WARM_EMPTY and empty < 0:
            empty = k
    return empty if free else -1


@njit
def _warm_load(c, h, clus, friction, rolling):
    """Contact c of the step starts from its force in the last solve, if kept, times the step
    h [s]: the normal part at least 0, the tangential part within the cone (μ_s, MODEL §4),
    the rolling couple within μ_r R* P_n (MODEL §5.1); the caller applies them
    (:func:`hsgran.contact.cluster.start`)."""
    owner, partner, sign = _warm_key(c, clus)
    k = _warm_slot(clus, owner, partner, False)
    if k < 0:
        return
    f = clus.wm_f[owner, k]
    n = clus.ck_n[c]
    fn = sign * h * (f[0] * n[0] + f[1] * n[1] + f[2] * n[2])
    pn = max(fn, 0.0)
    clus.ck_pn[c] = pn
    if friction:
        for j in range(3):
            clus.ck_pt[c, j] = sign * h * f[j] - fn * n[j]
        clus.ck_pt[c, 0], clus.ck_pt[c, 1], clus.ck_pt[c, 2] = cap(
            clus.ck_pt[c, 0], clus.ck_pt[c, 1], clus.ck_pt[c, 2], clus.ck_mu[c] * pn)
    if rolling:
        hn = sign * h * (f[3] * n[0] + f[4] * n[1] + f[5] * n[2])
        for j in range(3):
            clus.ck_hr[c, j] = sign * h * f[3 + j] - hn * n[j]
        clus.ck_hr[c, 0], clus.ck_hr[c, 1], clus.ck_hr[c, 2] = cap(
            clus.ck_hr[c, 0], clus.ck_hr[c, 1], clus.ck_hr[c, 2],
            clus.ck_mur[c] * clus.ck_reff[c] * pn)


@njit
def _warm_store(nb, nc, h, clus):
    """Keep the step's contact forces (its impulses over h [s]) for the next solve's warm
    start: the bodies' own entries are replaced by their contacts now (a pair no longer
    touching is forgotten); a contact without a free slot is not kept."""
    for b in range(nb):
        for k in range(WARM_SLOTS):
            clus.wm_q[clus.cl_body[b], k] = WARM_EMPTY
    for c in range(nc):
        if clus.ck_tgt[c] == NO_CONTACT or clus.ck_pn[c] == 0.0:
            continue
        owner, partner, sign = _warm_key(c, clus)
        k = _warm_slot(clus, owner, partner, True)
        if k < 0:
            continue
        clus.wm_q[owner, k] = partner
        s = sign / h
        for j in range(3):
            clus.wm_f[owner, k, j] = s * (clus.ck_pn[c] * clus.ck_n[c, j] + clus.ck_pt[c, j])
            clus.wm_f[owner, k, 3 + j] = s * clus.ck_hr[c, j]


@njit
def _step_setup(nb, nc, h, clus, gravity, v_persist, rotation, friction, rolling):
    """The step problem of the contacts that persist (Moreau–Jean over one segment of length h
    [s]): each body's velocity at the segment's end without contacts (v + h g, in ``cl_a``;
    spin in ``cl_al``); a persisting contact (separating after the impulses slower than
    ``v_persist`` [m/s], the landing speed: gravity would bring it back at once) must not
    approach at the end (target 0; its normal velocity then stays ≥ 0 over the segment, so
    it never closes) and starts from its force in the last solve (warm); a contact
    separating faster takes nothing. Returns the number of persisting contacts."""
    persist = 0
    for b in range(nb):
        for k in range(3):
            clus.cl_a[b, k] = clus.cl_v[b, k] + h * gravity[k]
            clus.cl_al[b, k] = clus.cl_w[b, k] if rotation else 0.0
    for c in range(nc):
        un = _normal_velocity(c, clus)
        _cold(c, clus)
        for k in range(3):
            # an immovable partner's velocity at the segment's end
            clus.ck_ab[c, k] = clus.ck_vb[c, k] + h * clus.ck_ab[c, k]
        if un > v_persist:
            clus.ck_tgt[c] = NO_CONTACT
        else:
            persist += 1
            clus.ck_tgt[c] = 0.0
            _warm_load(c, h, clus, friction, rolling and rotation)
    start(nc, clus.ck_a, clus.ck_b, clus.ck_n, clus.ck_rb, clus.cl_inv_m, clus.cl_inv_i,
          clus.cl_rad, clus.cl_a, clus.cl_al, clus.ck_pn, clus.ck_pt, clus.ck_hr, rotation)
    return persist


@njit
def _solve_cluster(nc, clus, v, w, vb, rotation, friction, rolling, tol, grow):
    """:func:`hsgran.contact.cluster.solve_polished` on the cluster's contacts, with the
    bodies' velocities (or the step's end velocities) ``v``, ``w`` and the immovable partners'
    ``vb``; with ``grow``, a solve that stalls stops short; returns (sweeps, worst,
    stalled, frozen)."""
    return solve_polished(nc, clus.ck_a, clus.ck_b, clus.ck_n, clus.ck_rb, vb, clus.ck_tgt,
                          clus.ck_mu, clus.ck_slip, clus.ck_mur, clus.ck_reff, clus.ck_rslip,
                          clus.cl_inv_m, clus.cl_inv_i, clus.cl_rad, v, w, clus.ck_pn,
                          clus.ck_pt, clus.ck_hr, rotation, friction, rolling, tol,
                          grow=grow)


@njit(inline="always")
def _count(isc, sweeps, nc, step, frozen):
    """Book a solve's work: its sweeps (a step's force solve: also I_STEP_SWEEPS), the
    contacts they visited, and whether its friction was frozen unconverged (I_FROZEN)."""
    isc[I_SWEEPS] += sweeps
    if step:
        isc[I_STEP_SWEEPS] += sweeps
    isc[I_VISITS] += sweeps * nc
    if frozen:
        isc[I_FROZEN] += 1


@njit
def _unsolved_step(nb, nc, h, clus, isc, space, rotation):
    """The step's solve with friction did not converge (Gauss–Seidel with Coulomb cones need
    not): solve it again without friction and rolling couples, a convex problem on which
    Gauss–Seidel converges; if that too stops short, the bodies keep their velocities over
    the segment (no acceleration: gravity is left out for at most one segment). Either way no
    contact closes within the segment, which a contact left approaching would (a zero-time
    sequence). Counted in ``isc[I_UNSOLVED]``."""
    for b in range(nb):
        held = clus.cl_depth[b] < 0  # held at rest (_hold_rests)
        for k in range(3):
            clus.cl_a[b, k] = 0.0 if held else clus.cl_v[b, k] + h * space.gravity[k]
            clus.cl_al[b, k] = clus.cl_w[b, k] if rotation and not held else 0.0
    for c in range(nc):
        _cold(c, clus)
    sweeps, worst, _, _ = _solve_cluster(nc, clus, clus.cl_a, clus.cl_al, clus.ck_ab, rotation,
                                         False, False, SOLVE_TOL_REL * space.slack[0], False)
    _count(isc, sweeps, nc, True, False)
    if worst > space.slack[0]:
        for b in range(nb):
            if clus.cl_depth[b] >= 0:
                for k in range(3):
                    clus.cl_a[b, k] = clus.cl_v[b, k]
                    clus.cl_al[b, k] = clus.cl_w[b, k]


@njit
def _solve_step(nb, nc, h, clus, isc, space, rotation, friction, rolling, grow):
    """The step's force solve, on from the impulses it has; if it stops short of the slack,
    the fallback :func:`_unsolved_step` (counted in ``isc[I_UNSOLVED]``). Returns whether it
    was solved; with ``grow``, False at once where the solve stalls (the caller solves a
    larger cluster)."""
    sweeps, worst, stalled, frozen = _solve_cluster(nc, clus, clus.cl_a, clus.cl_al, clus.ck_ab,
                                                    rotation, friction, rolling,
                                                    SOLVE_TOL_REL * space.slack[0], grow)
    _count(isc, sweeps, nc, True, frozen)
    if stalled:
        return False
    if worst > space.slack[0]:
        isc[I_UNSOLVED] += 1
        _unsolved_step(nb, nc, h, clus, isc, space, rotation)
        return False
    return True


@njit
def _accelerations(nb, h, clus):
    """Turn the step's end velocities (``cl_a``, ``cl_al``) into the segment's constant
    accelerations [m/s², rad/s²]."""
    for b in range(nb):
        for k in range(3):
            clus.cl_a[b, k] = (clus.cl_a[b, k] - clus.cl_v[b, k]) / h
            clus.cl_al[b, k] = (clus.cl_al[b, k] - clus.cl_w[b, k]) / h


@njit
def _rest_candidates(nb, nc, clus, fsc, gravity):
    """Mark in ``cl_depth`` (−1) the bodies that come to rest: slower than the landing speed
    now (what is given up), at a standstill at the step's end (its velocities in ``cl_a``,
    ``cl_al``: below SLIP_REL × the landing speed, R × spin included: their supports hold
    them), and not resting on a body that goes on moving (a persisting contact below them)."""
    v_land = fsc[F_LANDING_SPEED]
    v_still = SLIP_REL * v_land
    for b in range(nb):
        r = clus.cl_rad[b]
        v2 = clus.cl_v[b, 0] ** 2 + clus.cl_v[b, 1] ** 2 + clus.cl_v[b, 2] ** 2
        w2 = (clus.cl_w[b, 0] ** 2 + clus.cl_w[b, 1] ** 2 + clus.cl_w[b, 2] ** 2) * r * r
        e2 = e3 = 0.0  # at the step's end
        for k in range(3):
            e2 += clus.cl_a[b, k] ** 2
            e3 += clus.cl_al[b, k] ** 2 * r * r
        if v2 <= v_land * v_land and w2 <= v_land * v_land and e2 <= v_still * v_still \
                and e3 <= v_still * v_still:
            clus.cl_depth[b] = -1
    # a body rests only on supports that rest too: a persisting contact from below (its normal
    # towards the body points up) with a body that moves, or a moving boundary, keeps it going;
    # and only where nothing that goes on moving approaches it now (halted, it would be met at
    # once: the same solve again, and again)
    slack = SLACK_V_REL * v_land
    changed = True
    while changed:
        changed = False
        for c in range(nc):
            if clus.ck_tgt[c] == NO_CONTACT:
                continue
            a = clus.ck_a[c]
            b = clus.ck_b[c]
            up = -(clus.ck_n[c, 0] * gravity[0] + clus.ck_n[c, 1] * gravity[1]
                   + clus.ck_n[c, 2] * gravity[2])  # > 0: b is below a
            moving_b = (clus.cl_depth[b] >= 0) if b >= 0 else (
                clus.ck_vb[c, 0] != 0.0 or clus.ck_vb[c, 1] != 0.0 or clus.ck_vb[c, 2] != 0.0
                or clus.ck_ab[c, 0] != 0.0 or clus.ck_ab[c, 1] != 0.0
                or clus.ck_ab[c, 2] != 0.0)
            if clus.cl_depth[a] < 0 and moving_b and (up > 0.0 or _pressed(c, b, clus, slack)):
                clus.cl_depth[a] = 0
                changed = True
            if b >= 0 and clus.cl_depth[b] < 0 and clus.cl_depth[a] >= 0 and (
                    up < 0.0 or _pressed(c, a, clus, slack)):
                clus.cl_depth[b] = 0
                changed = True


@njit(inline="always")
def _pressed(c, m, clus, slack):
    """Whether body m (or contact c's moving boundary, m = −1), going on moving, approaches the
    other side of contact c faster than ``slack`` [m/s] once that side is halted."""
    u = 0.0
    for k in range(3):
        vm = clus.cl_v[m, k] if m >= 0 else clus.ck_vb[c, k]
        u += vm * clus.ck_n[c, k]
    # the normal points from b to a: a moving b approaches a halted a along +n, a moving a
    # approaches a halted b along −n
    return (u > slack) if m == clus.ck_b[c] else (u < -slack)


@njit
def _hold_rests(nb, nc, clus):
    """If a body that comes to rest (:func:`_rest_candidates`) shares a persisting contact with
    one that goes on moving, the moving one was solved as if its partner went on with the
    partner's (slight) motion: hold every resting body still (immovable, at rest at the step's
    end) so that the step can be solved again, from the forces it has; returns whether it
    must be. (Halted after the solve instead, a resting body would leave the moving one
    closing on it by up to its standstill speed: a contact at once, again and again.)"""
    mixed = False
    for c in range(nc):
        b = clus.ck_b[c]
        if clus.ck_tgt[c] != NO_CONTACT and b >= 0 and \
                (clus.cl_depth[clus.ck_a[c]] < 0) != (clus.cl_depth[b] < 0):
            mixed = True
            break
    if mixed:
        for b in range(nb):
            if clus.cl_depth[b] < 0:
                clus.cl_inv_m[b] = 0.0
                clus.cl_inv_i[b] = 0.0
                for k in range(3):
                    clus.cl_a[b, k] = 0.0
                    clus.cl_al[b, k] = 0.0
    return mixed


@njit
def _support(b, nc, clus):
    """The persisting contact of body b with the largest force: its plane w (as w) or sphere q
    (as −2 − q), for the motion state's ``mplane``; and how many persisting contacts b has and
    the plane of the last one (−1 if it is not a plane)."""
    best = -1.0
    code = -1
    count = 0
    plane = -1
    for c in range(nc):
        if clus.ck_tgt[c] == NO_CONTACT:
            continue
        a = clus.ck_a[c]
        bb = clus.ck_b[c]
        if a != b and bb != b:
            continue
        count += 1
        q = clus.ck_q[c] if a == b else clus.cl_body[a]
        plane = -1 - q if q < 0 else -1
        if clus.ck_pn[c] > best:
            best = clus.ck_pn[c]
            code = -1 - q if q < 0 else -2 - q
    return code, count, plane


@njit
def resolve_without(s, t, flight, walls, space, grid, sched, clus, isc, rest):
    """Sphere s leaves the system at time t [s] (hsgran._exchange): every sphere in
    constrained motion that touches it, and with ``rest`` every one at rest (the cluster
    treatment's; the pairwise rules wake theirs), is solved again at once, without it."""
    _wake(s, t, flight, walls, space, grid, sched, clus, isc, True, rest)


@njit
def _wake(s, t, flight, walls, space, grid, sched, clus, isc, supported=False, rest=True):
    """Sphere s, at rest before the solve, moves: the resting spheres it touches (outside the
    cluster) are solved again at once, since s may have carried them. With ``supported``
    (s leaves the system, hsgran._exchange) the spheres in constrained motion that touch it are
    solved again too; without ``rest`` only those."""
    st, mstate = flight.st, flight.mstate
    box_len, periodic = space.box_len, space.periodic
    woken = 0  # (re-predicted after the walk: a prediction overwrites grid.heads)
    for h in range(cell_heads(s, grid, space)):
        q = np.int64(grid.heads[h])
        while q >= 0:
            if q != s and ((rest and mstate[q] == MS_REST)
                           or (supported and mstate[q] == MS_SUPPORTED)) \
                    and clus.cl_loc[q] < 0 and flight.seg_code[q] != END_RESOLVE:
                dx = min_image(st[s, 0] - st[q, 0], 0, box_len, periodic)
                dy = min_image(st[s, 1] - st[q, 1], 1, box_len, periodic)
                dz = min_image(st[s, 2] - st[q, 2], 2, box_len, periodic)
                sigma = st[s, S_R] + st[q, S_R]
                if math.sqrt(dx * dx + dy * dy + dz * dz) - sigma <= TOUCH_REL * sigma:
                    flight.seg_end[q] = t
                    flight.seg_code[q] = END_RESOLVE
                    grid.stack[woken] = q
                    woken += 1
            q = np.int64(grid.nxt[q])
    for k in range(woken):
        reschedule_fn(np.int64(grid.stack[k]), t, flight, walls, space, grid, sched, isc, True)


# long: the motion state of each body after a solve (rest, flight, the paper's plate, or
# supported) writes the same dozen arrays in four ways; split, each would take them all
@njit
def _apply_states(nb, nc, t, tau, flight, dyn, walls, space, grid, sched, clus, isc,
                  pair_table, fsc, flags):
    """Write the solve's velocities and motion states back to the spheres, re-predict them and
    wake what they carried; returns the kinetic energy given up by the spheres put to rest
    [J]."""
    rotation, friction, rolling = flags[FL_ROTATION], flags[FL_FRICTION], flags[FL_ROLLING]
    st, acc, mstate, mplane = flight.st, flight.acc, flight.mstate, flight.mplane
    omg, alpha = dyn.omg, dyn.alpha
    gravity = space.gravity
    given_up = 0.0
    for b in range(nb):
        s = clus.cl_body[b]
        for k in range(3):
            st[s, 3 + k] = clus.cl_v[b, k]
            if rotation:
                omg[s, k] = clus.cl_w[b, k]
        code, count, plane = _support(b, nc, clus)
        if clus.cl_depth[b] < 0:  # at rest on its supports (_rest_candidates)
            given_up += 0.5 * (st[s, 3] ** 2 + st[s, 4] ** 2 + st[s, 5] ** 2) / dyn.inv_m[s]
            if rotation:
                given_up += 0.5 * (omg[s, 0] ** 2 + omg[s, 1] ** 2 + omg[s, 2] ** 2) \
                    / dyn.inv_i[s]
            halt(s, st, omg, rotation)
            for k in range(3):
                acc[s, k] = 0.0
                if rotation:
                    alpha[s, k] = 0.0
            mstate[s] = MS_REST
            mplane[s] = code
            flight.seg_end[s] = NEVER
            flight.seg_code[s] = END_NONE
        elif count == 1 and plane >= 0 and flat_fixed(walls, plane):
            # on one plane (or face) only: the paper's plate (MODEL §5.3)
            leave_plane(s, flight, dyn, gravity, rotation)
            enter_plane(s, np.int64(plane), t, np.int64(END_NONE), flight, dyn, walls, gravity,
                        pair_table, fsc, friction, rolling, rotation)
        elif count == 0:
            leave_plane(s, flight, dyn, gravity, rotation)
            mplane[s] = -1
        else:
            mstate[s] = MS_SUPPORTED
            mplane[s] = -1
            for k in range(3):
                acc[s, k] = clus.cl_a[b, k]
                if rotation:
                    alpha[s, k] = clus.cl_al[b, k]
            flight.seg_end[s] = t + tau
            flight.seg_code[s] = END_RESOLVE
        flight.counter[s] += 1
    for b in range(nb):
        reschedule_fn(clus.cl_body[b], t, flight, walls, space, grid, sched, isc, True)
    for b in range(nb):
        s = clus.cl_body[b]
        if clus.cl_was[b] == MS_REST and mstate[s] != MS_REST:
            _wake(s, t, flight, walls, space, grid, sched, clus, isc)
    return given_up


@njit
def _solve(nb, nc, seed, t, flight, dyn, walls, space, grid, sched, clus, isc, pair_table, fsc,
           rec, flags, final):
    """Impulses, forces and motion states of a gathered cluster (see the module); the impulse
    of contact ``seed`` (or −1) goes to ``rec`` for the event log. Returns the energy the
    cluster took [J] (the impulses' loss and what the spheres put to rest gave up); unless
    ``final``, NaN, with nothing written back, where the impulses or the step stop short of
    the slack or their solve stalls (the caller grows the cluster: see :func:`_grown`)."""
    rotation, friction, rolling = flags[FL_ROTATION], flags[FL_FRICTION], flags[FL_ROLLING]
    e0 = _kinetic(nb, clus, rotation)
    _impact_setup(nc, clus, pair_table, dyn.mat, rec, fsc, flags)
    sweeps, worst, stalled, frozen = _solve_cluster(nc, clus, clus.cl_v, clus.cl_w, clus.ck_vb,
                                                    rotation, friction, rolling,
                                                    SOLVE_TOL_REL * space.slack[0], not final)
    _count(isc, sweeps, nc, False, frozen)
    if stalled:
        return math.nan
    for k in range(rec.shape[0]):
        rec[k] = math.nan
    rec[REC_J_N] = clus.ck_pn[seed] if seed >= 0 else 0.0
    rec[REC_J_T] = math.sqrt(clus.ck_pt[seed, 0] ** 2 + clus.ck_pt[seed, 1] ** 2
                             + clus.ck_pt[seed, 2] ** 2) if seed >= 0 else 0.0
    rec[REC_STAGE] = STAGE_CLUSTER
    rec[REC_REGIME] = nb
    loss = e0 - _kinetic(nb, clus, rotation)
    h = _segment_time(nc, clus, MAX_SEGMENT, False, t, walls)
    _step_setup(nb, nc, h, clus, space.gravity, fsc[F_LANDING_SPEED], rotation, friction,
                rolling)
    solved = _solve_step(nb, nc, h, clus, isc, space, rotation, friction, rolling, not final)
    _rest_candidates(nb, nc, clus, fsc, space.gravity)
    if solved and _hold_rests(nb, nc, clus):
        solved = _solve_step(nb, nc, h, clus, isc, space, rotation, friction, rolling,
                             not final)
    if not final and (not solved or worst > space.slack[0]):
        return math.nan
    if solved:
        _warm_store(nb, nc, h, clus)
    _accelerations(nb, h, clus)
    tau = _segment_time(nc, clus, h, True, t, walls)
    if tau <= MIN_SEGMENT_REL * max(1.0, t):
        isc[I_SHORT] += 1
    loss += _apply_states(nb, nc, t, tau, flight, dyn, walls, space, grid, sched, clus, isc,
                          pair_table, fsc, flags)
    fsc[F_CLUSTER_LOSS] += loss
    rec[REC_ENERGY_LOST] = loss
    return loss


@njit(inline="always")
def _seed_contact(nc, clus, j, w):
    """The contact of the event: with body 1 (sphere j ≥ 0) or with plane w."""
    for c in range(nc):
        if clus.ck_a[c] == 0 and ((j >= 0 and clus.ck_b[c] == 1) or (j < 0 and
                                                                      clus.ck_q[c] == -1 - w)):
            return c
    return -1


@njit(inline="always")
def _reach(flags):
    """How many contacts away from the event's spheres moving spheres join a cluster: all
    with the cluster treatment, HAND_OVER_REACH with the pairwise rules."""
    return np.int64(1 << 30) if flags[FL_CLUSTERS] else np.int64(HAND_OVER_REACH)


@njit(inline="always")
def hands_over(i, j, flight, dyn, flags):
    """Whether the collision of sphere i with sphere j (or a wall, j < 0) is solved as a
    cluster: always with ``treatment = "clusters"``; with the pairwise rules, where either
    sphere is in constrained motion or in a zero-time sequence of HAND_OVER_STREAK
    collisions (the last resort before the collapse guard)."""
    if flags[FL_CLUSTERS]:
        return True
    mstate, zstreak = flight.mstate, dyn.zstreak
    if mstate[i] == MS_SUPPORTED or zstreak[i] >= HAND_OVER_STREAK:
        return True
    return j >= 0 and (mstate[j] == MS_SUPPORTED or zstreak[j] >= HAND_OVER_STREAK)


@njit(inline="always")
def hands_over_wall(i, w, t, flight, dyn, walls, space, pair_table, fsc, flags):
    """Whether the collision of sphere i with wall w at time t [s] is solved as a cluster: as
    :func:`hands_over`, and also where a slow sphere on one flat wall that cannot rest on it
    alone is pressed into another (hsgran._settling.rests_on_two_planes): a support by two
    walls, which the pairwise rules can only hop off."""
    return hands_over(i, -1, flight, dyn, flags) or rests_on_two_planes(
        i, w, t, flight, dyn, walls, space.gravity, pair_table, fsc, flags[FL_FRICTION],
        flags[FL_ROLLING])


@njit(inline="always")
def hands_over_pair(i, j, flight, dyn, walls, space, pair_table, fsc, flags):
    """Whether the collision of spheres i and j is solved as a cluster: as :func:`hands_over`,
    and also where one, slow on a flat wall that cannot hold it alone, meets the other at
    rest (hsgran._settling.rests_on_plane_and_sphere): a support by the wall and the sphere."""
    if hands_over(i, j, flight, dyn, flags):
        return True
    g, friction, rolling = space.gravity, flags[FL_FRICTION], flags[FL_ROLLING]
    return (rests_on_plane_and_sphere(i, j, flight, dyn, walls, g, pair_table, fsc, friction,
                                      rolling)
            or rests_on_plane_and_sphere(j, i, flight, dyn, walls, g, pair_table, fsc, friction,
                                         rolling))


@njit
def _grown(i, j, w, t, fast, nb, nc, left, flight, dyn, walls, space, grid, sched, clus, isc,
           pair_table, fsc, rec, flags):
    """Solve the cluster of sphere i (and sphere j ≥ 0 or wall w) at time t [s], gathered
    (nb bodies, nc contacts; ``left``: moving spheres were left out as its boundary); where
    the solve stops short of the slack, or stalls, while moving spheres were
    left out (HAND_OVER_REACH), gather it again reaching twice as far and solve that (a
    boundary sphere pressing a body against fixed walls can leave it no motion that
    approaches nothing, or none that its friction allows). Returns the energy taken [J]."""
    reach = _reach(flags)
    while True:
        final = not left or nb >= clus.cl_body.shape[0]
        seed = _seed_contact(nc, clus, j, w) if (j >= 0 or w >= 0) else -1
        loss = _solve(nb, nc, seed, t, flight, dyn, walls, space, grid, sched, clus, isc,
                      pair_table, fsc, rec, flags, final)
        release(nb, clus)
        if loss == loss:  # (not NaN: solved, and written back)
            return loss
        reach *= 2
        nb, nc, _, left = gather(i, j, t, fast, reach, flight, dyn, walls, space, grid, clus,
                                 flags[FL_ROTATION])


@njit
def cluster_collision(i, j, w, t, flight, dyn, walls, space, grid, sched, clus, isc, pair_table,
                      fsc, rec, flags):
    """A collision of sphere i with sphere j (j ≥ 0) or plane w at time t [s] under gravity:
    CL_ISOLATED if the two touch nothing else and fly (the caller collides them as a pair;
    nothing has changed but the spheres' stored states, advanced to t), else the cluster is
    solved (CL_SOLVED; ``rec`` holds the event's impulse and the energy taken)."""
    mstate, st, v_land = flight.mstate, flight.st, fsc[F_LANDING_SPEED]
    if j >= 0:
        un = 0.0
        d = 0.0
        for k in range(3):
            dk = min_image(st[i, k] - st[j, k], k, space.box_len, space.periodic)
            un += dk * (st[i, 3 + k] - st[j, 3 + k])
            d += dk * dk
        un /= math.sqrt(d)
    else:
        un = (st[i, 3] * walls.planes_n[w, 0] + st[i, 4] * walls.planes_n[w, 1]
              + st[i, 5] * walls.planes_n[w, 2])
    fast = un < -v_land
    nb, nc, driven, left = gather(i, j, t, fast, _reach(flags), flight, dyn, walls, space,
                                  grid, clus, flags[FL_ROTATION])
    if (nc == 1 and nb == (2 if j >= 0 else 1) and mstate[i] == MS_FLIGHT
            and (j < 0 or mstate[j] == MS_FLIGHT)) or (
            driven and not flags[FL_CLUSTERS] and mstate[i] != MS_SUPPORTED
            and (j < 0 or mstate[j] != MS_SUPPORTED)):
        # a binary collision; or a hand-over (:func:`hands_over`) beside a moving plane,
        # which the treatment takes only as it moves now: left to the pairwise rules
        release(nb, clus)
        return CL_ISOLATED
    _grown(i, j, w, t, fast, nb, nc, left, flight, dyn, walls, space, grid, sched, clus, isc,
           pair_table, fsc, rec, flags)
    return CL_SOLVED


@njit
def cluster_resolve(i, t, flight, dyn, walls, space, grid, sched, clus, isc, pair_table, fsc,
                    rec, flags):
    """Sphere i's segment has ended (or a support of it moved): solve its cluster again at
    time t [s]. Returns the energy taken [J]."""
    nb, nc, _, left = gather(i, -1, t, False, _reach(flags), flight, dyn, walls, space, grid,
                             clus, flags[FL_ROTATION])
    return _grown(i, -1, -1, t, False, nb, nc, left, flight, dyn, walls, space, grid, sched,
                  clus, isc, pair_table, fsc, rec, flags)


def slack(landing_speed: float) -> float:
    """The prediction's slack for supported spheres (``Space.slack``) [m/s]."""
    return SLACK_V_REL * landing_speed
