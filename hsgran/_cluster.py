"""Touching spheres and walls solved together: the cluster treatment of dense scenes (layer 5;
compiled kernels used by :mod:`hsgran._loop`, with gravity). What it does and what it costs is
in docs/enduring-contact.md ("Clusters of contacts", "Constrained motion in steps").

A collision under gravity whose spheres touch nothing else, in flight, is the paper's binary
collision (the caller's). Otherwise the event's spheres and every body touching them, and
every moving sphere touching those, are a cluster (:func:`gather`), and it moves on in
**steps** of the Moreau–Jean contact dynamics (Moreau 1988; Jean 1999, "The non-smooth contact
dynamics method", with θ = 1), each of length h (:func:`_step_of`):

1. **one solve per step** (:func:`hsgran.contact.cluster.solve_polished`): every contact of
   the cluster that touches or could close within the step (gap g ≤ the step's *reach*) at
   once, for the bodies' velocities at the step's end, v⁺ = v + h g + M⁻¹ Σ P. A contact
   approaching faster than the landing speed that closes within the step is an impact:
   Newton's restitution, u⁺ ≥ −e u⁻ (the pair's e_n from the collision model, MODEL §3);
   every other contact may close its gap by the step's end and no further, u⁺ ≥ −g/h (the
   gap-aware Signorini condition of the Moreau–Jean scheme: a contact that stays open takes
   no impulse; one that closes slowly does not rebound). Coulomb's cone with MODEL §4's μ_s;
   rolling couples within μ_r R* P_n (MODEL §5.1). The solve starts warm from the forces of
   the last step that had no impact;
2. **the motion over the step**: a body moves from its position with constant velocity v⁺
   (θ = 1). Spheres and planes are convex, so the gap of a contact along straight paths is
   at least g + h u⁺·... ≥ 0 at every instant of the step: no contact of the step closes
   within it, and none that the solve held needs an event (:func:`hsgran._predict.
   held_pair`). Where no body of a connected part of the cluster approaches a partner at the
   step's start, its bodies move on the parabola from v to v⁺ instead (constant
   accelerations: the piecewise-constant accelerations of Baraff's event-driven resting
   contact, Baraff 1994), which keeps every gap open as well and is exact for a motion of
   constant forces, such as a sphere rolling down a groove;
3. **motion states**: a sphere slower than the landing speed that its supports hold still at
   the step's end comes to rest; one that the solve gave no impulse flies from the step's
   start (its exact parabola); any other moves on in constrained motion (``MS_SUPPORTED``)
   until its step ends, when its cluster is solved again; a single sphere left touching only
   a fixed flat wall takes the paper's motion on a plate (MODEL §5.3). A sphere at rest set
   moving wakes the resting spheres it touches, which are solved again at once.

Collisions with spheres outside the cluster, and with spheres of the cluster that were not
within the step's reach of each other at its start, are events as any other: the cluster is
solved again at that instant, from its state then.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._cylinder import across_axis, concave
from hsgran._flight import (
    PLANE_TOUCHING_REL,
    TOUCH_REL,
    advance,
    ball,
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
from hsgran.motion import APPROACH_NOISE_ULPS, NEVER, ROUNDOFF, TOUCHING_REL
from hsgran.onplane import END_NONE, END_RESOLVE, MS_FLIGHT, MS_REST, MS_SUPPORTED
from hsgran.wallspec import BL_RADIUS, CY_RADIUS, WK_MOVING, WK_PLANE

#: Longest step of constrained motion [s] (Moreau–Jean, docs/enduring-contact.md "Constrained
#: motion in steps"). A cluster's step is also cut to STEP_TRAVEL_REL below: this bounds the
#: steps of slow clusters (a pile, a creeping bed), whose contacts form and break on its scale
#: (a step of 1e-4 s lets a sphere falling at the landing speed move 1e-7 m), and what a
#: contact's force may lag behind a change of its partners (one step).
STEP_MAX = 1e-4
#: A step lasts at most until two bodies of the cluster, or a body and an immovable partner,
#: moving apart or together at their relative speed (:func:`_step_of`; and the landing speed),
#: could have changed their distance by this fraction of the cluster's smallest radius [-]: a
#: contact's normal turns by at most ~1e-2 rad within a step, and an impact within it is taken
#: early by at most that fraction of the radius (the positions at the step's start,
#: docs/enduring-contact.md).
STEP_TRAVEL_REL = 1e-2
#: The step's reach [m], what a contact's gap may be at the step's start for the step's solve
#: to hold it, is this many times the distance the fastest relative motion of the cluster
#: (:func:`_step_of`, and the landing speed) and gravity could close within the step [-]: a
#: sphere that could meet a body of the cluster within the step joins it, so that no collision
#: of the step's own bodies falls within it (a faster one is an event as any).
REACH_SAFETY = 2.0
#: Sweeps that friction and rolling couples get in a step's solve before they are frozen and
#: the normal impulses polished with friction held in proportion to them
#: (hsgran.contact.cluster.solve_polished) [-]. The next step starts from these forces (its
#: warm start), so friction goes on converging from step to step where the contacts persist;
#: what a step leaves unconverged is counted
#: (``I_FROZEN``). On corpus scene 0-17 (188 spheres poured into a wedge, μ = 0.62,
#: μ_r = 0.02) the bed comes to rest with 100 (every sphere below 1e-9 m/s by 0.32 s), where
#: 2000 took five times the sweeps.
STEP_FRICTION_SWEEPS = 100
#: Inside a cylinder a sphere moving along the tangent of its contact sinks into the wall (by
#: d²/2(R − r) after a distance d): its contact's target holds the distance from the axis that
#: the step's straight motion reaches at its end (:func:`_sink`), which depends on the
#: tangential velocity the solve gives. So the step is solved again with the targets of its
#: end velocities, up to this many times, while one of them changes by more than the solve's
#: tolerance [-] (the change is of second order in the step: one round meets it, as a rule).
CONCAVE_ROUNDS = 4
#: A sphere whose collisions have not advanced the clock this many times in a row
#: (``zstreak``) is in a zero-time sequence the pairwise rules (``treatment = "pairwise"``)
#: have not ended: its next collision is solved as a cluster, and so is every collision of a
#: sphere in constrained motion after it (:func:`hands_over`). Twice the streak at which the
#: last pairwise rule acts (the wedge stop, hsgran._settling.WEDGE_EVENTS, after the jam rule's
#: JAM_EVENTS), so that every rule has had its turn; a quarter of the collapse guard's count
#: (hsgran._flight.MAX_ZERO_TIME_EVENTS). (At 100, before the wedge stop, small pours that
#: the wedge stop settles in seconds were handed over and ran for minutes.)
HAND_OVER_STREAK = 2 * WEDGE_EVENTS
#: A sphere whose pairwise collisions have each come within the TC time of the one before
#: this many times in a row (``rapid``, hsgran._settling.note_rapid) is in an enduring contact
#: that the TC model keeps elastic (Luding & McNamara 1998: it hides collapse, it makes no
#: resting contact) and the pairwise rules have not ended: its next collision is solved as a
#: cluster, and the streak ends there (:func:`_end_streak`). Where nothing can rest alone (a
#: bed on a tilted floor without rolling friction), no sphere ever sleeps on another and the
#: streak never ends: corpus 0-69 (218 spheres on a 7° periodic chute, μ = 0.53; LAMMPS's bed
#: stops by 0.15 s) made 6.8 million pair collisions (5.1 million TC) from 0.14 s to 0.16 s,
#: one sphere 707,232 TC collisions in a row. Where the rules do end a streak (the jam rule,
#: JAM_EVENTS, once a partner rests), it took up to 40,270 collisions in the corpus's first 40
#: scenes and 13,723 in the 2000-sphere pour (docs/enduring-contact.md, "TC streaks"): a
#: hand-over there would put a forming pile in constrained motion, whose steps cost far more
#: than the collisions they save (the pour: 92 s of CPU to 0.2 s with a limit of 256, where it
#: takes 16 s). So the limit sits over three times above the longest streak the rules ended:
#: it sets only when an unending streak is handed over, at a cost of about this many
#: collisions per buzzing sphere, never whether.
HAND_OVER_RAPID = 1 << 17
#: Moving spheres join a cluster however many contacts away from the event's spheres they are
#: (contacts within the step's reach); beyond the scratch arrays' room they are its boundary,
#: moving on as before. (Before the steps, the pairwise rules' clusters stopped one contact
#: away, since each of a dense flow's contacts that formed was a solve of its whole bed.)
ALL_CONTACTS = 1 << 30
#: Shortest step, relative to max(1 s, t) [-]: 1e4 times the collapse guard's "one instant"
#: (hsgran._flight.NO_PROGRESS_REL), so that every solve of a step's end advances the clock.
MIN_SEGMENT_REL = 1e-9
#: Slack of the step's solve, relative to the landing speed [-] (1e-10 m/s with the default):
#: a contact's normal velocity may end this far below its target, which closes its gap over
#: a step of STEP_MAX by 1e-14 m (the next step's target takes that back, so overlaps do not
#: add up); far below anything that moves a sphere measurably. Slower approaches also count
#: as none (a body is put to rest beside one that closes on it no faster,
#: :func:`_rest_candidates`; a part of the cluster moves on the parabola where no contact
#: approaches faster, :func:`_linear_parts`).
SLACK_V_REL = 1e-7
#: The solves converge to this fraction of the slack (each contact's velocity within it of its
#: target, and no impulse changing by more than that in a sweep) [-]: what is left over is
#: then below the slack (1e-12 m/s with the default landing speed).
SOLVE_TOL_REL = 0.01
#: A step's solve that meets every contact to the slack may still give its bodies more
#: kinetic energy than its targets and moving partners can supply (:func:`_creates_energy`):
#: friction frozen before it converged and then held while the normal impulses are polished
#: (hsgran.contact.cluster.solve_polished) need not oppose the slips it ends with. On corpus
#: scene 0-37 (169 spheres in a 28-sided drum, μ = 0.71) one such solve of 15 resting bodies
#: met its contacts to 4e-11 m/s with 1.4 N s between two of them and sent one off at 90 m/s.
#: What the solve may gain beyond its supply is this many times the slack's work, the slack
#: [m/s] times its impulses [N s] [-], plus ENERGY_ROUNDING_ULPS units of round-off of the
#: bodies' kinetic energies; a healthy step of a resting bed loses ½ m (h g)² a body (the
#: Moreau–Jean step is dissipative: Acary 2016, ZAMM 96, 585), far more. [OURS]
ENERGY_SLACK = 2.0
ENERGY_ROUNDING_ULPS = 64.0
#: A contact slips when its slip speed exceeds this fraction of the landing speed [-] (below:
#: static friction); the same for rolling (R* times the rolling angular velocity). 1e-7 m/s
#: with the default landing speed: slower slips stop within a step.
SLIP_REL = 1e-4
#: An impact (faster than the landing speed) moves the resting spheres up to this many contacts
#: away from the event's spheres (a row of five, Newton's cradle, in full); resting spheres
#: further away are immovable. A slower meeting moves none: a pile at rest carries it
#: (docs/enduring-contact.md).
REST_DEPTH = 4
#: The step's reach where the contacts within it do not fit the cluster's scratch arrays:
#: no contact is held, every one is an event (:func:`_stepped`).
NO_REACH = -1.0

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
def _add_contact(clus, nc, a, b, q, mat, nx, ny, nz, rb, gap):
    """Contact nc between body a and body b (−1: immovable, partner q; −1 − w for plane w), at
    ``gap`` [m]."""
    clus.ck_gap[nc] = gap
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
def gather(s1, s2, t, fast, reach, rho, flight, dyn, walls, space, grid, clus, rotation):
    """The cluster of sphere s1 (and s2, or −1): every body within ``rho`` [m] of them (or
    touching them: a gap of at most TOUCH_REL of the contact distance), and every sphere in
    constrained motion within that of those, and every other moving one up to ``reach``
    contacts away, breadth first; in an impact (``fast``: faster than the landing speed) also
    the resting spheres up to REST_DEPTH contacts away, through which its impulse travels.
    Other spheres at rest are immovable partners, moving spheres beyond ``reach`` or the room
    of the scratch arrays the cluster's boundary. Walls are immovable partners moving as they
    do at t (a moving plane at its velocity then, a turning cylinder's surface with it). Every
    pair of bodies, and every body and partner, within ``rho`` is a contact, with its gap.
    Returns (bodies, contacts, whether a moving plane is among the partners, whether a
    moving sphere is); the bodies are advanced to t."""
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
            if gap <= max(rho, TOUCH_REL * rs) and nc < max_c:
                driven = driven or moving(walls, w)
                if gap < 0.0 and concave(walls, w):
                    _to_surface(s, w, gap, st, walls)
                    gap = 0.0
                nc = _add_contact(clus, nc, p, -1, -1 - w, planes_mat[w], planes_n[w, 0],
                                  planes_n[w, 1], planes_n[w, 2],
                                  walls.planes_geo[w, BL_RADIUS]
                                  if ball(walls, w) else 0.0, gap)
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
                    if d - sigma <= max(rho, TOUCH_REL * sigma) and nc < max_c:
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
                                              st[q, S_R], d - sigma)
                        else:
                            nc = _add_contact(clus, nc, p, -1, q, mat[q], nx, ny, nz,
                                              st[q, S_R], d - sigma)
                            _boundary_motion(q, nc - 1, nx, ny, nz, t, flight, dyn,
                                             clus, rotation)
                            left = left or mstate[q] != MS_REST
                q = np.int64(nxt[q])
        p += 1
    return nb, nc, driven, left


@njit(inline="always")
def _to_surface(s, w, gap, st, walls):
    """Put sphere s, sunk into concave wall w by −gap [m] (what a step's solve left within its
    tolerance, :func:`_sink`, or a rounding), back on its surface, along the normal in its
    row."""
    for k in range(3):
        st[s, k] -= gap * walls.planes_n[w, k]


@njit
def release(nb, clus):
    """Forget the cluster's bodies (the sphere-to-body map back to −1)."""
    for b in range(nb):
        clus.cl_loc[clus.cl_body[b]] = -1


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


@njit(inline="always")
def _partner_speed(c, clus, walls):
    """Speed [m/s] at which body ``ck_a[c]`` moves against its immovable partner in contact c,
    for :func:`_step_of`: along the normal alone at an unbounded plane, fixed or moving (its
    normal does not turn, whatever the body's motion along it), the whole relative speed at any
    other partner (a sphere, a cylinder, an edge, a corner, a face whose outline the body may
    cross: there a motion along the contact turns its normal or ends it)."""
    a = clus.ck_a[c]
    ux = clus.cl_v[a, 0] - clus.ck_vb[c, 0]
    uy = clus.cl_v[a, 1] - clus.ck_vb[c, 1]
    uz = clus.cl_v[a, 2] - clus.ck_vb[c, 2]
    q = clus.ck_q[c]
    if q < 0 and (walls.planes_kind[-1 - q] == WK_PLANE
                  or walls.planes_kind[-1 - q] == WK_MOVING):
        return abs(ux * clus.ck_n[c, 0] + uy * clus.ck_n[c, 1] + uz * clus.ck_n[c, 2])
    return math.sqrt(ux * ux + uy * uy + uz * uz)


@njit
def _step_of(nb, nc, t, clus, walls, gravity, v_land):
    """Length h [s] and reach [m] of the step of a cluster gathered with its touching contacts (nb
    bodies, nc contacts): h is STEP_MAX, or shorter where two of its bodies, or a body and an
    immovable partner, could change their distance by STEP_TRAVEL_REL of the smallest radius
    within it at their relative speed v_rel (and the landing speed ``v_land`` [m/s]); at least
    MIN_SEGMENT_REL × max(1 s, t). Two bodies move against each other at most twice the largest
    speed of a body about the cluster's mean velocity (Galilean: a bed sliding as a block has
    slow relative motions), a body against an immovable partner as :func:`_partner_speed`. The
    reach is REACH_SAFETY times what v_rel and gravity close within h."""
    rmin = math.inf
    mx = my = mz = 0.0
    for b in range(nb):
        rmin = min(rmin, clus.cl_rad[b])
        mx += clus.cl_v[b, 0]
        my += clus.cl_v[b, 1]
        mz += clus.cl_v[b, 2]
    mx, my, mz = mx / nb, my / nb, mz / nb
    dev = 0.0
    for b in range(nb):
        dev = max(dev, math.sqrt((clus.cl_v[b, 0] - mx) ** 2 + (clus.cl_v[b, 1] - my) ** 2
                                 + (clus.cl_v[b, 2] - mz) ** 2))
    v_rel = 2.0 * dev
    for c in range(nc):
        if clus.ck_b[c] < 0:
            v_rel = max(v_rel, _partner_speed(c, clus, walls))
    v_rel += v_land
    h = max(min(STEP_MAX, STEP_TRAVEL_REL * rmin / v_rel), MIN_SEGMENT_REL * max(1.0, t))
    g = math.sqrt(gravity[0] ** 2 + gravity[1] ** 2 + gravity[2] ** 2)
    return h, REACH_SAFETY * (v_rel * h + g * h * h)


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


@njit(inline="always")
def _impact(nc, clus):
    """Whether a contact of the step is an impact (a rebound target, :func:`_setup`). Such a
    step's impulses are not forces that persist: kept as forces over h and reloaded by the next
    step's warm start, an impact's impulse would start the next step as if it went on, and in
    a jammed bed, whose redundant contacts meet their targets with any self-equilibrated part
    of the impulses, much of it would stay; so a step with an impact keeps the forces it
    found (:func:`_warm_store` is not called; :func:`_warm_load` reads the last persisting
    forces). On corpus scene 0-17 (188 spheres poured into a jammed wedge) the run to rest
    took 17.7 s of CPU, against 21.8 s with an impact's impulses kept as forces."""
    for c in range(nc):
        if not math.isnan(clus.ck_reb[c]):
            return True
    return False


@njit
def _warm_store(nb, nc, h, clus):
    """Keep the step's contact forces (its impulses over h [s]) for the next solve's warm
    start: the bodies' own entries are replaced by their contacts now (a pair no longer
    touching is forgotten); a contact without a free slot is not kept."""
    for b in range(nb):
        for k in range(WARM_SLOTS):
            clus.wm_q[clus.cl_body[b], k] = WARM_EMPTY
    for c in range(nc):
        if clus.ck_pn[c] == 0.0:
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


@njit(inline="always")
def _rebound(e, un, an, h):
    """Normal velocity [m/s] at the end of a step of h [s] of a contact that closes within it
    at the normal velocity un < 0 [m/s], with restitution e [-] and the relative acceleration
    an [m/s²] of gravity along its normal (:func:`_setup`): the impact, then free flight for
    the rest of the step, −e un + h an, where gravity presses the pair together (an ≤ 0; the
    gravity a body against an immovable partner would otherwise not feel in the step of its
    bounce, which kept a bead bouncing in a pocket for ever). Where gravity pulls the pair
    apart (an > 0: an immovable partner above the body's centre) the impact is taken at the
    step's end, after gravity slowed the approach for the whole step, −e (un + h an): taken
    at its start, the rebound would gain (1 + e) |un| h an a unit mass on the motion without
    contacts, which kept a sphere in a groove of two resting spheres bouncing against an
    overhanging third for ever (corpus 0-15). Either way the rebound's normal speed is at
    most that of the motion without contacts, |un + h an|, for e ≤ 1. [OURS]"""
    if an <= 0.0:
        return -e * un + h * an
    return -e * (un + h * an)


@njit(inline="always")
def _target(gap, reb, h, slack):
    """Target [m/s] of a contact's normal velocity at the step's end (:func:`_setup`): the
    rebound ``reb`` of an impact (NaN: none), never closing the gap ``gap`` [m] within the step
    h [s]; an overlap within ``slack`` × h stays as it is (0); any other gap may close, −gap/h."""
    if not math.isnan(reb):
        return max(reb, -gap / h)
    if gap < 0.0 and gap >= -slack * h:
        return 0.0
    return -gap / h


@njit(inline="always")
def _sink(c, h, v, clus, walls):
    """How far [m] the body of contact c sinks into a concave wall (the inside of a cylinder) by
    moving straight at its velocity ``v[ck_a[c]]`` [m/s] for h [s], beyond what its normal
    velocity does: with ρ = R − r the largest distance of its centre from the axis, a body at
    distance d₀ = ρ − g that moves by h u_n towards the axis and by h v_p across the axis and
    the normal ends at distance √((d₀ − h u_n)² + h² v_p²), within ρ where u_n ≥ (s − g)/h,
    s = ρ − √(ρ² − h² v_p²) (exact for the straight motion; its distance from the axis is
    convex in time, so the gap is least at the step's start or end). 0 for any other contact."""
    q = clus.ck_q[c]
    if q >= 0 or not concave(walls, -1 - q):
        return 0.0
    w = -1 - q
    a = clus.ck_a[c]
    un = v[a, 0] * clus.ck_n[c, 0] + v[a, 1] * clus.ck_n[c, 1] + v[a, 2] * clus.ck_n[c, 2]
    px, py, pz = across_axis(v[a, 0] - un * clus.ck_n[c, 0], v[a, 1] - un * clus.ck_n[c, 1],
                             v[a, 2] - un * clus.ck_n[c, 2], walls, w)
    s2 = h * h * (px * px + py * py + pz * pz)
    rho = max(walls.planes_cyl[w, CY_RADIUS] - clus.cl_rad[a], 0.0)
    root = math.sqrt(max(rho * rho - s2, 0.0))
    return s2 / (rho + root) if rho + root > 0.0 else 0.0


@njit
def _concave_retarget(nc, h, slack, clus, walls):
    """The targets of the contacts with concave walls at the velocities the step's solve gave
    (:func:`_sink`); returns the largest change of a target [m/s]."""
    change = 0.0
    for c in range(nc):
        q = clus.ck_q[c]
        if q < 0 and concave(walls, -1 - q):
            gap = clus.ck_gap[c] - _sink(c, h, clus.cl_a, clus, walls)
            tgt = _target(gap, clus.ck_reb[c], h, slack)
            change = max(change, abs(tgt - clus.ck_tgt[c]))
            clus.ck_tgt[c] = tgt
    return change


@njit
def _setup(nb, nc, h, slack, clus, walls, pair_table, mat, rec, gravity, v_land, flags):
    """The step's problem (Moreau–Jean, θ = 1, over h [s]): each body's velocity at the step's end
    without contacts, v + h g (into ``cl_a``; spin into ``cl_al``); each contact's target for its
    normal velocity at the step's end (``ck_tgt``): an approach faster than the landing speed
    ``v_land`` [m/s] that closes within the step rebounds with the pair's e_n (MODEL §3, as a binary
    collision), −e u, and then flies freely for the step (plus h times the relative acceleration of
    gravity along the normal, which against an immovable partner brings it back, or the impact
    taken at the step's end where gravity pulls the pair apart: :func:`_rebound`; at least −g/h: a
    rebound that gravity takes back within the step is no rebound at that step's resolution); every
    other contact may close its gap g by the step's end, −g/h, and one that overlaps by more than
    the solve's slack (``slack`` [m/s] over h: what a solve may leave) opens by as much (an overlap
    within it stays as it is: asking a body squeezed between two partners to leave both would ask
    what may not be possible), :func:`_target`; inside a cylinder g less what the step's straight
    motion at these velocities sinks into it (:func:`_sink`, solved again at the velocities the
    solve gives: :func:`_concave_rounds`); its friction (MODEL §4) and rolling coefficients (MODEL
    §5.1); and each contact starts from its force in the last solve, if kept (warm), applied to the
    bodies."""
    rotation, friction, rolling = flags[FL_ROTATION], flags[FL_FRICTION], flags[FL_ROLLING]
    for b in range(nb):
        for k in range(3):
            clus.cl_a[b, k] = clus.cl_v[b, k] + h * gravity[k]
            clus.cl_al[b, k] = clus.cl_w[b, k] if rotation else 0.0
    for c in range(nc):
        a = clus.ck_a[c]
        row = pair_table[mat[clus.cl_body[a]], clus.ck_mat[c]]
        un = _normal_velocity(c, clus)
        gap = clus.ck_gap[c] - _sink(c, h, clus.cl_a, clus, walls)
        clus.ck_reb[c] = math.nan
        if un < -v_land and gap + h * un < 0.0:
            # the rebound, then free flight for the rest of the step; never closing further
            an = 0.0
            for k in range(3):
                ab = gravity[k] if clus.ck_b[c] >= 0 else clus.ck_ab[c, k]
                an += (gravity[k] - ab) * clus.ck_n[c, k]
            clus.ck_reb[c] = _rebound(_restitution(c, clus, row, rec, flags), un, an, h)
        clus.ck_tgt[c] = _target(gap, clus.ck_reb[c], h, slack)
        clus.ck_mu[c] = row[P_MU_S]
        clus.ck_mur[c] = row[P_MU_R]
        r1 = clus.cl_rad[a]
        r2 = clus.ck_rb[c]
        clus.ck_reff[c] = r1 * r2 / (r1 + r2) if r2 > 0.0 else r1
        _cold(c, clus)
        for k in range(3):
            # an immovable partner's velocity over the step: at its end
            clus.ck_ab[c, k] = clus.ck_vb[c, k] + h * clus.ck_ab[c, k]
        _warm_load(c, h, clus, friction, rolling and rotation)
    start(nc, clus.ck_a, clus.ck_b, clus.ck_n, clus.ck_rb, clus.cl_inv_m, clus.cl_inv_i,
          clus.cl_rad, clus.cl_a, clus.cl_al, clus.ck_pn, clus.ck_pt, clus.ck_hr, rotation)


@njit
def _solve_cluster(nc, clus, v, w, vb, rotation, friction, rolling, tol):
    """:func:`hsgran.contact.cluster.solve_polished` on the cluster's contacts, with the
    bodies' velocities at the step's end ``v``, ``w`` and the immovable partners' ``vb``,
    friction given STEP_FRICTION_SWEEPS sweeps, every part of it stopping where it stalls
    (a problem with no solution, which Gauss–Seidel shows by not converging: a body held
    between immovable partners that the targets ask it to leave); returns (sweeps, worst,
    stalled, frozen)."""
    return solve_polished(nc, clus.ck_a, clus.ck_b, clus.ck_n, clus.ck_rb, vb, clus.ck_tgt,
                          clus.ck_mu, clus.ck_slip, clus.ck_mur, clus.ck_reff, clus.ck_rslip,
                          clus.cl_inv_m, clus.cl_inv_i, clus.cl_rad, v, w, clus.ck_pn,
                          clus.ck_pt, clus.ck_hr, rotation, friction, rolling, tol,
                          STEP_FRICTION_SWEEPS, False, True)


@njit(inline="always")
def _count(isc, sweeps, nc, step, frozen):
    """Book a solve's work: its sweeps (a step's solve: also I_STEP_SWEEPS), the contacts they
    visited, and whether its friction was frozen unconverged (I_FROZEN)."""
    isc[I_SWEEPS] += sweeps
    if step:
        isc[I_STEP_SWEEPS] += sweeps
    isc[I_VISITS] += sweeps * nc
    if frozen:
        isc[I_FROZEN] += 1


#: What :func:`_solve_step` ended with.
STEP_SOLVED = 0  #: every contact met, friction as far as its sweeps reached
STEP_PLASTIC = 1  #: met without rebounds (every target at most 0; counted)
STEP_FRICTIONLESS = 2  #: met without rebounds, friction and rolling couples (counted)
STEP_SHORT = 3  #: not even that met every contact to the slack (counted)


@njit
def _restart(nb, h, clus, nc, space, rotation):
    """Start the step's solve again from no impulse (the bodies at their velocities without
    contacts, those held at rest at none), every target at most 0: no rebound."""
    for b in range(nb):
        held = clus.cl_depth[b] < 0  # held at rest (_hold_rests)
        for k in range(3):
            clus.cl_a[b, k] = 0.0 if held else clus.cl_v[b, k] + h * space.gravity[k]
            clus.cl_al[b, k] = clus.cl_w[b, k] if rotation and not held else 0.0
    for c in range(nc):
        _cold(c, clus)
        clus.ck_tgt[c] = min(clus.ck_tgt[c], 0.0)


@njit
def _creates_energy(nb, nc, h, clus, gravity, rotation, slack):
    """Whether the step's solve gave the bodies more kinetic energy than it may [bool]: their
    energy at the step's end less that of their velocities without contacts (v + h g, the spin
    as it is), against what the contacts may supply: each its normal impulse times its target
    where that is positive (an overlap opened), an impact's rebound at most the kinetic energy
    ½ m* u⁺² of the pair's binary rebound (m* the pair's reduced mass, an immovable partner's
    infinite), and the work of its impulse at a moving partner's velocity; with Coulomb
    friction and rolling couples that oppose the slips they end with (and normal impulses only
    where a contact meets its target) the rest is lost, never gained (ENERGY_SLACK,
    ENERGY_ROUNDING_ULPS). Bodies held at rest (no mass in the solve) have no energy.

    The rebound's bound is not its impulse times its target: on corpus 0-6 (108 spheres on a
    19° incline, μ = 0.47) a solve with frozen friction met a rebound of 1.9 mm/s off a resting
    sphere with 16.5 N s, a body wedged between it and its neighbours, and gave three bodies
    2 m/s: 0.014 J, within the 0.031 J that impulse times its target allows, 10⁷ times the
    3 × 10⁻⁹ J that the rebound carries. [OURS]"""
    gain = 0.0
    scale = 0.0
    for b in range(nb):
        if clus.cl_inv_m[b] > 0.0:
            m = 1.0 / clus.cl_inv_m[b]
            for k in range(3):
                vf = clus.cl_v[b, k] + h * gravity[k]
                gain += 0.5 * m * (clus.cl_a[b, k] ** 2 - vf * vf)
                scale += 0.5 * m * (clus.cl_a[b, k] ** 2 + vf * vf)
        if rotation and clus.cl_inv_i[b] > 0.0:
            i = 1.0 / clus.cl_inv_i[b]
            for k in range(3):
                gain += 0.5 * i * (clus.cl_al[b, k] ** 2 - clus.cl_w[b, k] ** 2)
                scale += 0.5 * i * (clus.cl_al[b, k] ** 2 + clus.cl_w[b, k] ** 2)
    supply = 0.0
    impulses = 0.0
    for c in range(nc):
        pn = clus.ck_pn[c]
        reb = clus.ck_reb[c]
        if math.isnan(reb):
            supply += pn * max(clus.ck_tgt[c], 0.0)
        else:
            # an impact's rebound: at most the energy of the pair's binary rebound, whatever
            # impulse the solve put there, and the impulse's work on any opening beyond it
            reb = max(reb, 0.0)
            inv = clus.cl_inv_m[clus.ck_a[c]] + (clus.cl_inv_m[clus.ck_b[c]]
                                                 if clus.ck_b[c] >= 0 else 0.0)
            if inv > 0.0:
                supply += 0.5 * reb * reb / inv
            supply += pn * max(clus.ck_tgt[c] - reb, 0.0)
        impulses += abs(pn) + math.sqrt(clus.ck_pt[c, 0] ** 2 + clus.ck_pt[c, 1] ** 2
                                        + clus.ck_pt[c, 2] ** 2)
        if clus.ck_b[c] < 0:  # an immovable partner's velocity at the step's end (_setup)
            for k in range(3):
                supply += (pn * clus.ck_n[c, k] + clus.ck_pt[c, k]) * clus.ck_ab[c, k]
    return gain > supply + ENERGY_SLACK * slack * impulses + ENERGY_ROUNDING_ULPS * ROUNDOFF * scale


@njit
def _solve_step(nb, nc, h, clus, isc, space, flags):
    """The step's solve, on from the impulses it has (:func:`_setup`). Where it stops short of
    the slack (Gauss–Seidel with Coulomb cones need not converge, and a problem may have no
    solution: an impact's rebound off a body held between immovable partners), or where
    friction frozen unconverged gave the bodies energy (:func:`_creates_energy`), it is solved
    again from no impulse without rebounds (every target at most 0, which bodies that stop
    meet), and if that too stops short, also without friction and rolling couples: a convex
    problem (both counted in ``isc[I_UNSOLVED]``); if even that stops short, its impulses are
    kept as they are (a contact then closes by at most what they leave over the step, which
    the next step's target takes back). Returns a STEP_* code. (A solve whose friction stalls
    has it frozen, as where its sweeps run out: hsgran.contact.cluster.solve_polished.)"""
    rotation, friction, rolling = flags[FL_ROTATION], flags[FL_FRICTION], flags[FL_ROLLING]
    tol = SOLVE_TOL_REL * space.slack[0]
    slack = space.slack[0]
    sweeps, worst, _, frozen = _solve_cluster(nc, clus, clus.cl_a, clus.cl_al, clus.ck_ab,
                                              rotation, friction, rolling, tol)
    _count(isc, sweeps, nc, True, frozen)
    if worst <= slack and not (
            frozen and _creates_energy(nb, nc, h, clus, space.gravity, rotation, slack)):
        return STEP_SOLVED
    isc[I_UNSOLVED] += 1
    _restart(nb, h, clus, nc, space, rotation)
    if friction or rolling:
        sweeps, worst, _, frozen = _solve_cluster(nc, clus, clus.cl_a, clus.cl_al, clus.ck_ab,
                                                  rotation, friction, rolling, tol)
        _count(isc, sweeps, nc, True, frozen)
        if worst <= slack and not (
                frozen and _creates_energy(nb, nc, h, clus, space.gravity, rotation, slack)):
            return STEP_PLASTIC
        _restart(nb, h, clus, nc, space, rotation)
    sweeps, worst, _, _ = _solve_cluster(nc, clus, clus.cl_a, clus.cl_al, clus.ck_ab, rotation,
                                         False, False, tol)
    _count(isc, sweeps, nc, True, False)
    return STEP_FRICTIONLESS if worst <= slack else STEP_SHORT


@njit
def _concave_rounds(nb, nc, h, clus, isc, walls, space, flags):
    """:func:`_solve_step`, and where it is met and the cluster touches the inside of a cylinder,
    again with the targets of the velocities it gave (:func:`_sink`) while one changes by more
    than the solve's tolerance, at most CONCAVE_ROUNDS times. Returns a STEP_* code."""
    status = _solve_step(nb, nc, h, clus, isc, space, flags)
    tol = SOLVE_TOL_REL * space.slack[0]
    for _ in range(CONCAVE_ROUNDS):
        if status != STEP_SOLVED or _concave_retarget(nc, h, space.slack[0], clus, walls) <= tol:
            break
        status = _solve_step(nb, nc, h, clus, isc, space, flags)
    return status


@njit(inline="always")
def _root(b, clus):
    """The representative of body b's part (union-find with path halving on ``cl_root``)."""
    root = clus.cl_root
    while root[b] != b:
        root[b] = root[root[b]]
        b = root[b]
    return b


@njit
def _linear_parts(nb, nc, clus, walls, slack):
    """Which bodies move with constant velocity over the step (θ = 1) rather than on the parabola
    from their velocity now to the step's end: every body of a part of the cluster (bodies joined by
    its contacts) in which some contact approaches at the step's start (normal velocity below
    −``slack`` [m/s] before the solve: a gap closing no faster closes on the parabola by less than
    slack × h, 1e-14 m over a step of STEP_MAX with the default landing speed). Along straight paths
    a gap changes at least as the normal velocity at the step's end says, which the solve keeps from
    closing it; on the parabola it changes by the mean of that and the normal velocity now, which
    keeps it open as well only where the latter is not negative. A part touching the inside of a
    cylinder (``walls``) moves straight too: its targets hold the straight motion (:func:`_sink`),
    whose gap with the concave wall is least at the step's start or end. In ``cl_root``: a body of a
    linear part gets a negative entry (:func:`_linear`)."""
    root = clus.cl_root
    for b in range(nb):
        root[b] = b
    for c in range(nc):
        bb = clus.ck_b[c]
        if bb >= 0:
            ra = _root(clus.ck_a[c], clus)
            rb = _root(bb, clus)
            if ra != rb:
                root[max(ra, rb)] = min(ra, rb)
    for b in range(nb):
        root[b] = _root(b, clus)
    # mark the representative of every part with an approaching contact, or a contact inside
    # a cylinder (whose target holds the straight motion, :func:`_sink`): −1 − itself
    for c in range(nc):
        r = root[clus.ck_a[c]]
        q = clus.ck_q[c]
        if r >= 0 and root[r] >= 0 and (_normal_velocity(c, clus) < -slack
                                        or (q < 0 and concave(walls, -1 - q))):
            root[r] = -1 - r
    for b in range(nb):
        r = root[b]
        if r >= 0 and root[r] < 0:
            root[b] = root[r]


@njit(inline="always")
def _linear(b, clus):
    """Whether body b moves with constant velocity over the step (:func:`_linear_parts`)."""
    return clus.cl_root[b] < 0


@njit
def _rest_candidates(nb, nc, clus, fsc, gravity):
    """Mark in ``cl_depth`` (−1) the bodies that come to rest: at a standstill both now and at
    the step's end (velocities in ``cl_v``, ``cl_w`` and ``cl_a``, ``cl_al``: below SLIP_REL
    × the landing speed, R × spin included), so that their supports held them still over a
    whole step from rest, and not resting on a body that goes on moving (a contact below them
    that carries or touches). (At the step's end alone is not enough: a sphere rocking in a
    hollow, whose speed passes through zero within a step, can end the step at a standstill,
    the more easily the closer its speed was to what gravity takes from it in a step.)"""
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
        still = v_still * v_still
        if v2 <= still and w2 <= still and e2 <= still and e3 <= still:
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
            if clus.ck_pn[c] == 0.0 and clus.ck_gap[c] > TOUCH_REL * clus.cl_rad[clus.ck_a[c]]:
                continue  # neither carries nor touches
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
    """If a body that comes to rest (:func:`_rest_candidates`) shares a contact of the step
    with one that goes on moving (one that carries or one within the reach: the prediction
    then holds that pair apart), the moving one was solved as if its partner went on with the
    partner's (slight) motion: hold every resting body still (immovable, at rest at the step's
    end) so that the step can be solved again, from the forces it has; returns whether it
    must be. (Halted after the solve instead, a resting body would leave the moving one
    closing on it by up to its standstill speed: a contact at once, again and again.)"""
    mixed = False
    for c in range(nc):
        b = clus.ck_b[c]
        if b >= 0 and (clus.cl_depth[clus.ck_a[c]] < 0) != (clus.cl_depth[b] < 0):
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
    """The contact of body b with the largest impulse in the step: its plane w (as w) or
    sphere q (as −2 − q), for the motion state's ``mplane``; and how many of its contacts
    carry an impulse, and the plane of the last one (−1 if it is not a plane)."""
    best = -1.0
    code = -1
    count = 0
    plane = -1
    for c in range(nc):
        if clus.ck_pn[c] == 0.0:
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


@njit(inline="always")
def _lowest_gap(g0, rel_v, rel_a, h):
    """The least of g0 + rel_v τ + rel_a τ²/2 over 0 ≤ τ ≤ h [m]."""
    low = min(g0, g0 + rel_v * h + 0.5 * rel_a * h * h)
    if rel_a > 0.0 and 0.0 < -rel_v / rel_a < h:
        low = min(low, g0 - 0.5 * rel_v * rel_v / rel_a)
    return low


@njit
def _flies_clear(b, nc, h, clus, walls, gravity, slack):
    """Whether body b, which the step's solve gave no impulse, can fly on its exact parabola
    from now without closing a contact of the step within it [bool]. The solve kept its
    contacts open for the step's motion of it (:func:`_linear_parts`), not for its flight: a
    sphere moving slowly up into one above it, which gravity turns back within the step,
    needs no impulse by the step's end, but in flight it meets that sphere at once (a
    zero-time sequence). For each contact, the gap along the normal now, with the relative
    motion of its flight against the partner's motion in the step (at rest, or on its line or
    parabola; a partner with no impulse either may fly too, or move on its line), must stay
    above −``slack`` × h over the step; and a contact that touches now, to the prediction's
    level, must not approach beyond the rounding of b's velocity. The solve meets a contact
    to its slack, so it can leave a touching contact approaching at, say, 3e-14 m/s with no
    impulse; in flight the prediction meets that contact at once, and the solve that follows
    gives it no impulse again: a sphere of a 2000-sphere pour met its side wall a thousand
    times at one instant until the collapse guard stopped the run. Likewise a sphere touching
    the inside of a cylinder that the curvature alone presses into it: its straight motion
    over the step would sink into the side (:func:`_sink`) further than its normal velocity
    takes it away, however little (a sphere grazing at 10⁻⁵ m/s sinks by ~10⁻²⁰ m, below the
    slack and the rounding alike, but the prediction meets it at once). Such a sphere moves on
    in constrained motion instead, which holds its contacts for the step."""
    v_sum = abs(clus.cl_v[b, 0]) + abs(clus.cl_v[b, 1]) + abs(clus.cl_v[b, 2])
    noise = APPROACH_NOISE_ULPS * ROUNDOFF * v_sum  # at most the prediction's for both kinds
    for c in range(nc):
        a = clus.ck_a[c]
        p = clus.ck_b[c]
        if a != b and p != b:
            continue
        sign = 1.0 if a == b else -1.0  # the normal, from the partner to b
        o = p if a == b else a
        rel_v = rel_a = 0.0  # against the partner's motion in the step
        fly_v = 0.0  # against its flight, if it may fly (the same acceleration)
        may_fly = o >= 0 and clus.cl_depth[o] >= 0 and _unloaded(o, nc, clus)
        for k in range(3):
            n = sign * clus.ck_n[c, k]
            if o < 0:  # immovable: a wall, a sphere at rest, or the boundary
                vo = clus.ck_vb[c, k]
                ao = (clus.ck_ab[c, k] - clus.ck_vb[c, k]) / h
            elif clus.cl_depth[o] < 0:  # comes to rest
                vo = ao = 0.0
            elif _linear(o, clus):
                vo = clus.cl_a[o, k]
                ao = 0.0
            else:
                vo = clus.cl_v[o, k]
                ao = (clus.cl_a[o, k] - clus.cl_v[o, k]) / h
            rel_v += (clus.cl_v[b, k] - vo) * n
            rel_a += (gravity[k] - ao) * n
            if may_fly:
                fly_v += (clus.cl_v[b, k] - clus.cl_v[o, k]) * n
        low = _lowest_gap(clus.ck_gap[c], rel_v, rel_a, h)
        if may_fly:
            low = min(low, _lowest_gap(clus.ck_gap[c], fly_v, 0.0, h))
        if low < -slack * h:
            return False
        if _touching_now(c, b, o, clus) and (
                min(rel_v, fly_v if may_fly else rel_v) < -noise
                or (o < 0 and _presses(c, rel_v, h, clus, walls))):
            return False
    return True


@njit(inline="always")
def _presses(c, rel_v, h, clus, walls):
    """Whether the curvature of the concave wall of contact c presses its body into it over a
    step of h [s] (:func:`_sink` positive) faster than its normal velocity ``rel_v`` [m/s]
    takes it away [bool]."""
    sink = _sink(c, h, clus.cl_v, clus, walls)
    return sink > 0.0 and rel_v * h < sink


@njit(inline="always")
def _touching_now(c, b, o, clus):
    """Whether contact c of body b (partner body o ≥ 0, or immovable) touches to the prediction's
    level [bool]: a wall within its touching distance (``PLANE_TOUCHING_REL`` R, where the
    prediction takes the gap as closed), a sphere within the distance at which it tests an
    approach against rounding (``motion.TOUCHING_REL``: |r|² within that fraction of σ²)."""
    if o < 0 and clus.ck_q[c] < 0:
        return clus.ck_gap[c] <= PLANE_TOUCHING_REL * clus.cl_rad[b]
    sigma = clus.cl_rad[clus.ck_a[c]] + clus.ck_rb[c]  # (ck_rb: the radius of ck_b's sphere)
    return clus.ck_gap[c] <= 0.5 * TOUCHING_REL * sigma


@njit(inline="always")
def _unloaded(b, nc, clus):
    """Whether no contact of body b carries an impulse in the step."""
    for c in range(nc):
        if (clus.ck_a[c] == b or clus.ck_b[c] == b) and clus.ck_pn[c] != 0.0:
            return False
    return True


# long: the motion state of each body after a solve (rest, flight, or supported on a line
# or a parabola) writes the same dozen arrays in three ways; split, each would take them all
@njit
def _apply_states(nb, nc, t, h, reach, flight, dyn, walls, space, grid, sched, clus, isc,
                  flags):
    """Write the step's motion and motion states back to the spheres (the bodies' velocities
    now in ``cl_v``, ``cl_w``, at the step's end in ``cl_a``, ``cl_al``), re-predict them and
    wake what they carried. A sphere in constrained motion holds, until its step ends at
    t + h, every contact within ``reach`` [m] of its position now (``seg_reach``)."""
    rotation = flags[FL_ROTATION]
    st, acc, mstate, mplane = flight.st, flight.acc, flight.mstate, flight.mplane
    omg, alpha = dyn.omg, dyn.alpha
    gravity = space.gravity
    _linear_parts(nb, nc, clus, walls, space.slack[0])
    for b in range(nb):
        s = clus.cl_body[b]
        code, count, _ = _support(b, nc, clus)
        if clus.cl_depth[b] < 0:  # at rest on its supports (_rest_candidates)
            halt(s, st, omg, rotation)
            for k in range(3):
                acc[s, k] = 0.0
                if rotation:
                    alpha[s, k] = 0.0
            mstate[s] = MS_REST
            mplane[s] = code
            flight.seg_end[s] = NEVER
            flight.seg_code[s] = END_NONE
        elif count == 0 and _flies_clear(b, nc, h, clus, walls, gravity, space.slack[0]):
            # no impulse in the step: it flies, exactly, from now
            for k in range(3):
                st[s, 3 + k] = clus.cl_v[b, k]
                if rotation:
                    omg[s, k] = clus.cl_w[b, k]
            leave_plane(s, flight, dyn, gravity, rotation)
            mplane[s] = -1
        else:
            linear = _linear(b, clus)
            for k in range(3):
                if linear:
                    st[s, 3 + k] = clus.cl_a[b, k]
                    acc[s, k] = 0.0
                else:
                    st[s, 3 + k] = clus.cl_v[b, k]
                    acc[s, k] = (clus.cl_a[b, k] - clus.cl_v[b, k]) / h
                if rotation:
                    omg[s, k] = clus.cl_al[b, k] if linear else clus.cl_w[b, k]
                    alpha[s, k] = 0.0 if linear else (clus.cl_al[b, k] - clus.cl_w[b, k]) / h
            mstate[s] = MS_SUPPORTED
            mplane[s] = -1
            flight.seg_end[s] = t + h
            flight.seg_code[s] = END_RESOLVE
            flight.seg_reach[s] = reach
        flight.counter[s] += 1
    for b in range(nb):
        reschedule_fn(clus.cl_body[b], t, flight, walls, space, grid, sched, isc, True)
    for b in range(nb):
        s = clus.cl_body[b]
        if clus.cl_was[b] == MS_REST and mstate[s] != MS_REST:
            _wake(s, t, flight, walls, space, grid, sched, clus, isc)


@njit
def _step_loss(nb, h, clus, flight, dyn, gravity, rotation):
    """Mechanical energy the step takes from the bodies [J]: their kinetic energy now less
    that at the step's end, plus the work of gravity over the step's motion (zero for a
    sphere that flies, which keeps its energy; a resting one gives up its kinetic energy)."""
    loss = 0.0
    for b in range(nb):
        s = clus.cl_body[b]
        m = 1.0 / dyn.inv_m[s]
        e = 0.0
        for k in range(3):
            v0 = clus.cl_v[b, k]
            if flight.mstate[s] == MS_REST:
                dx = v1 = 0.0
            elif flight.mstate[s] != MS_SUPPORTED:  # flies (or on a plate): no loss booked
                v1 = v0
                dx = 0.0
            else:
                v1 = clus.cl_a[b, k]
                dx = h * v1 if _linear(b, clus) else 0.5 * h * (v0 + v1)
            e += 0.5 * m * (v0 * v0 - v1 * v1) + m * gravity[k] * dx
        if rotation and flight.mstate[s] != MS_FLIGHT:
            w2 = clus.cl_w[b, 0] ** 2 + clus.cl_w[b, 1] ** 2 + clus.cl_w[b, 2] ** 2
            w1 = 0.0
            if flight.mstate[s] == MS_SUPPORTED:
                w1 = clus.cl_al[b, 0] ** 2 + clus.cl_al[b, 1] ** 2 + clus.cl_al[b, 2] ** 2
            e += 0.5 * (w2 - w1) / dyn.inv_i[s]
        loss += e
    return loss


@njit
def _solve(nb, nc, seed, t, h, reach, flight, dyn, walls, space, grid, sched, clus, isc,
           pair_table, fsc, rec, flags):
    """One step of length h [s] and reach ``reach`` [m] of the gathered cluster (see the module):
    its solve, motion and motion states; the impulse of contact ``seed`` (or −1) goes to ``rec`` for
    the event log. Returns the energy the step took [J]."""
    rotation = flags[FL_ROTATION]
    _setup(nb, nc, h, space.slack[0], clus, walls, pair_table, dyn.mat, rec, space.gravity,
           fsc[F_LANDING_SPEED], flags)
    status = _concave_rounds(nb, nc, h, clus, isc, walls, space, flags)
    _rest_candidates(nb, nc, clus, fsc, space.gravity)
    # (a step solved again without rebounds, STEP_PLASTIC, holds its resting bodies too, and
    # its forces start the next step: else a solve whose frozen friction gave energy is
    # started from the same forces again, and gives it again, step after step)
    if status <= STEP_PLASTIC and _hold_rests(nb, nc, clus):
        status = _concave_rounds(nb, nc, h, clus, isc, walls, space, flags)
    if status <= STEP_PLASTIC and not _impact(nc, clus):  # (an impact's impulse is no force)
        _warm_store(nb, nc, h, clus)
    for k in range(rec.shape[0]):
        rec[k] = math.nan
    rec[REC_J_N] = clus.ck_pn[seed] if seed >= 0 else 0.0
    rec[REC_J_T] = math.sqrt(clus.ck_pt[seed, 0] ** 2 + clus.ck_pt[seed, 1] ** 2
                             + clus.ck_pt[seed, 2] ** 2) if seed >= 0 else 0.0
    rec[REC_STAGE] = STAGE_CLUSTER
    rec[REC_REGIME] = nb
    if h <= MIN_SEGMENT_REL * max(1.0, t):
        isc[I_SHORT] += 1
    _apply_states(nb, nc, t, h, reach, flight, dyn, walls, space, grid, sched, clus, isc, flags)
    loss = _step_loss(nb, h, clus, flight, dyn, space.gravity, rotation)
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
def hands_over(i, j, flight, dyn, flags):
    """Whether the collision of sphere i with sphere j (or a wall, j < 0) is solved as a
    cluster: always with ``treatment = "clusters"``; with the pairwise rules, where either
    sphere is in constrained motion, in a zero-time sequence of HAND_OVER_STREAK collisions
    (the last resort before the collapse guard) or in a TC streak of HAND_OVER_RAPID."""
    if flags[FL_CLUSTERS]:
        return True
    mstate = flight.mstate
    if mstate[i] == MS_SUPPORTED or _streaked(i, dyn):
        return True
    return j >= 0 and (mstate[j] == MS_SUPPORTED or _streaked(j, dyn))


@njit(inline="always")
def _streaked(p, dyn):
    """Whether sphere p is in a sequence of collisions the pairwise rules have not ended: a
    zero-time one (HAND_OVER_STREAK) or a TC streak (HAND_OVER_RAPID)."""
    return dyn.zstreak[p] >= HAND_OVER_STREAK or dyn.rapid[p] >= HAND_OVER_RAPID


@njit(inline="always")
def _end_streak(p, dyn, flags):
    """A collision of sphere p that the cluster solved ends its TC streak if the streak handed
    it over (HAND_OVER_RAPID; with the pairwise rules): back in flight, it returns to them."""
    if not flags[FL_CLUSTERS] and dyn.rapid[p] >= HAND_OVER_RAPID:
        dyn.rapid[p] = 0


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
def _stepped(i, j, w, t, fast, nb, nc, flight, dyn, walls, space, grid, sched, clus, isc,
             pair_table, fsc, rec, flags):
    """The next step of the cluster of sphere i (and sphere j ≥ 0 or wall w) from time t [s],
    gathered with its touching contacts (nb bodies, nc contacts): its length and reach from
    those (:func:`_step_of`), the cluster gathered again within that reach, and solved. Where
    the contacts within the reach do not fit the scratch arrays, those that do are solved and
    none is held (each is then an event). Returns the energy taken [J]."""
    h, reach = _step_of(nb, nc, t, clus, walls, space.gravity, fsc[F_LANDING_SPEED])
    release(nb, clus)
    nb, nc, _, _ = gather(i, j, t, fast, ALL_CONTACTS, reach, flight, dyn, walls, space, grid,
                          clus, flags[FL_ROTATION])
    if nc >= clus.ck_a.shape[0]:
        reach = NO_REACH
    seed = _seed_contact(nc, clus, j, w) if (j >= 0 or w >= 0) else -1
    loss = _solve(nb, nc, seed, t, h, reach, flight, dyn, walls, space, grid, sched, clus, isc,
                  pair_table, fsc, rec, flags)
    release(nb, clus)
    return loss


@njit
def cluster_collision(i, j, w, t, flight, dyn, walls, space, grid, sched, clus, isc, pair_table,
                      fsc, rec, flags):
    """A collision of sphere i with sphere j (j ≥ 0) or plane w at time t [s] under gravity:
    CL_ISOLATED if the two touch nothing else and fly, and neither is in a sequence of
    collisions that binary collisions have not ended (:func:`_streaked`) (the caller collides
    them as a pair; nothing has changed but the spheres' stored states, advanced to t), else the
    cluster takes a step from t (CL_SOLVED; ``rec`` holds the event's impulse and the energy
    taken)."""
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
    nb, nc, driven, _ = gather(i, j, t, fast, ALL_CONTACTS, 0.0, flight, dyn, walls, space,
                               grid, clus, flags[FL_ROTATION])
    binary = (nc == 1 and nb == (2 if j >= 0 else 1) and mstate[i] == MS_FLIGHT
              and (j < 0 or mstate[j] == MS_FLIGHT))
    if (binary and not (_streaked(i, dyn) or (j >= 0 and _streaked(j, dyn)))) or (
            driven and not flags[FL_CLUSTERS] and mstate[i] != MS_SUPPORTED
            and (j < 0 or mstate[j] != MS_SUPPORTED)):
        # a binary collision, unless it is one of a zero-time sequence that binary collisions
        # have not ended (a sphere grazing the inside of a cylinder, pressed into it by its
        # curvature at no normal speed: no impulse, met again at once); or a hand-over
        # (:func:`hands_over`) beside a moving plane, which the treatment takes only as it
        # moves now: left to the pairwise rules
        release(nb, clus)
        return CL_ISOLATED
    _stepped(i, j, w, t, fast, nb, nc, flight, dyn, walls, space, grid, sched, clus, isc,
             pair_table, fsc, rec, flags)
    _end_streak(i, dyn, flags)
    if j >= 0:
        _end_streak(j, dyn, flags)
    return CL_SOLVED


@njit
def cluster_resolve(i, t, flight, dyn, walls, space, grid, sched, clus, isc, pair_table, fsc,
                    rec, flags):
    """Sphere i's step has ended (or a support of it moved): its cluster takes its next step
    from time t [s]; a sphere that touches nothing flies on, and one that touches a fixed
    flat wall alone takes the paper's motion on it (MODEL §5.3), without a solve. Returns the
    energy taken [J]."""
    nb, nc, _, _ = gather(i, -1, t, False, ALL_CONTACTS, 0.0, flight, dyn, walls, space, grid,
                          clus, flags[FL_ROTATION])
    if nb == 1 and (nc == 0 or (nc == 1 and clus.ck_q[0] < 0
                                and flat_fixed(walls, -1 - clus.ck_q[0]))):
        release(nb, clus)
        rotation = flags[FL_ROTATION]
        leave_plane(i, flight, dyn, space.gravity, rotation)
        flight.mplane[i] = -1
        if nc == 1:
            enter_plane(i, np.int64(-1 - clus.ck_q[0]), t, np.int64(END_NONE), flight, dyn,
                        walls, space.gravity, pair_table, fsc, flags[FL_FRICTION],
                        flags[FL_ROLLING], rotation)
        flight.counter[i] += 1
        reschedule_fn(i, t, flight, walls, space, grid, sched, isc, True)
        for k in range(rec.shape[0]):
            rec[k] = math.nan
        return 0.0
    return _stepped(i, -1, -1, t, False, nb, nc, flight, dyn, walls, space, grid, sched, clus,
                    isc, pair_table, fsc, rec, flags)


def slack(landing_speed: float) -> float:
    """The prediction's slack for supported spheres (``Space.slack``) [m/s]."""
    return SLACK_V_REL * landing_speed
