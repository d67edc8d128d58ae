"""The compiled event loop (layer 5; used only by :mod:`hsgran.engine`).

One pending event per sphere (Smallenburg 2022), kept in an event calendar
(:mod:`hsgran.events.calendar`) together with one extra entry, the frame tick (index N). Each
sphere's event stores the event counter of its partner at prediction time; a popped pair event
whose partner has had an event since is stale and only makes the owner re-predict (lazy
invalidation). Spheres are advanced only when they take part in an event (delayed states,
DynamO); frames evaluate every sphere's parabola at the frame time without touching the stored
states, so the output interval never changes the trajectory.

Event kinds: ``EV_PAIR`` (sphere–sphere), ``EV_WALL`` (sphere–plane), ``EV_CELL`` (a sphere
leaves its cell; periodic wrap), and the frame tick. Pop, re-check, execute: a popped collision
is executed only if its partner is unchanged (else the owner re-predicts: "stale") and the bodies
still approach at the contact point (else both re-predict: "miss", a grazing contact that
round-off turned around). The collision itself is the kernel of
:mod:`hsgran.contact.model`, inlined with the scene's effect flags as constants.

Everything here is array-in, array-out; the scalar state lives in ``fsc`` (floats) and ``isc``
(ints) at the ``F_*``/``I_*`` indices so a run can stop (buffer full, event budget) and continue.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit, prefetch
from hsgran.contact.model import (
    REC_E_N,
    REC_ENERGY_LOST,
    REC_J_N,
    REC_J_T,
    REC_REGIME,
    REC_STAGE,
    resolve,
)
from hsgran.events.calendar import (
    Q_SIZE,
    calendar_build,
    calendar_prefetch,
    calendar_top,
    calendar_update,
    has_buckets,
)
from hsgran.events.grid import insert, remove, slot_of
from hsgran.events.kinds import (
    EV_CELL,
    EV_FRAME,
    EV_HOP,
    EV_LAND,
    EV_MISS,
    EV_NONE,
    EV_PAIR,
    EV_STALE,
    EV_STATE,
    EV_TC,
    EV_WALL,
    EV_WEDGE,
)
from hsgran.events.kinds import EVENT_NAMES as EVENT_NAMES  # re-exported for hsgran.engine
from hsgran.events.queue import ARITY
from hsgran.materials import P_E_FIXED, P_MU_R, P_MU_S, SOLID_SPHERE_INERTIA
from hsgran.motion import (
    NEVER,
    TOUCHING_REL,
    approach_noise,
    face_exit_time,
    flight_position,
    pair_contact_accelerated,
    pair_contact_before,
    plane_contact_time,
)
from hsgran.onplane import END_NONE, MS_ASLEEP, MS_FLIGHT, MS_REST, plane_segment

# float scalars
F_T_CUR = 0  #: time of the last popped event [s]
F_T_END = 1  #: stop before events later than this [s]
F_FRAME_DT = 2  #: frame interval [s]
F_DISSIPATED = 3  #: energy the collision model took so far (hops: negative) [J]
F_LANDING_SPEED = 4  #: rebound speed below which a sphere stays on a plane [m/s]
F_CHI = 5  #: rolling-torque convention while sliding (hsgran.onplane CONVENTION_A/_B)
#: TC model (Luding & McNamara 1998) [s]: a collision of a sphere less than this after its
#: previous collision is elastic (e_n = 1; friction still acts), which ends the infinite
#: sequences of ever-smaller collisions of inelastic collapse in clusters; 0 turns it off
F_TC_TIME = 6
F_SIZE = 7
# int scalars
I_SEQ = 0  #: next sequence number (tie-break)
I_N_FRAMES = 1  #: frames in the buffer
I_N_LOG = 2  #: event-log entries in the buffer
I_FRAME_INDEX = 3  #: index of the next frame (its time is index × frame_dt)
I_N_EVENTS = 4  #: events executed in total
I_COLLAPSED = 5  #: sphere that triggered the collapse guard, or −1
I_PEND_A = 6  #: a sphere whose next event must be predicted before the next pop, or −1
I_PEND_B = 7  #: a second one, or −1
I_PEND_LAYER = 8  #: the cell face that the sphere in I_PEND_A just crossed (EV_CELL), or −1
I_SIZE = 9

#: Cells a crossed axis needs for the crossing to look only at the new layer of neighbouring
#: cells (see _predict): with 1 or 2 the lists of that axis are not neighbour layers.
LAYER_MIN_CELLS = 3

# effect and engine switches: the ``flags`` argument, a bool array of FL_SIZE entries. They are
# run-time values, so one compiled loop serves every scene with gravity and one every scene
# without (a cold compile costs tens of seconds; gravity alone is a compile-time constant, see
# run_loop); a disabled effect is skipped by one predictable branch and its code never runs.
FL_PLASTICITY = 0  #: staged normal model (MODEL §3); else elastic Hertz
FL_FRICTION = 1  #: tangential impulse (MODEL §4)
FL_ROLLING = 2  #: rolling resistance (MODEL §5)
FL_ADHESION = 3  #: adhesion in recovery (MODEL §3.8)
FL_ROTATION = 4  #: spins are tracked
FL_GRAVITY = 5  #: parabolic flight, on-plane motion states
FL_LOG = 6  #: record every event in the log buffer
FL_SIZE = 7

#: Event-log entries one event can write: a collision, and a landing or the wedge stops of
#: both spheres. The log buffer is flushed while it still has room for that many, so no entry
#: of an event is ever dropped (the buffer must hold at least this many).
LOG_ENTRIES_PER_EVENT = 3

STATUS_DONE = 0  #: reached t_end
STATUS_FRAMES_FULL = 1  #: the frame buffer is full: flush and call again
STATUS_LOG_FULL = 2  #: the event-log buffer is full: flush and call again
STATUS_BUDGET = 3  #: executed the requested number of events (progress report)
STATUS_COLLAPSE = 4  #: a sphere had too many events without time advancing

#: Two instants closer than ZERO_TIME_REL × max(1 s, t) are the same up to double round-off of
#: the clock (a frame due at t_end may round that far above it).
ZERO_TIME_REL = 4e-16
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
#: upwards at all, so that gravity presses it onto that sphere: cos ≥ 1e-6 to the vertical,
#: far above the rounding of the direction [-]. (1e-3 left a sphere 0.05° above the equator of
#: a sleeper, wedged between it and a side wall, hopping off it into the wall for ever.)
JAM_SUPPORT_COS = 1e-6
#: A sphere whose gap to a plane is within this fraction of its radius at t = 0 starts on the
#: plane: the scene check accepts touching spheres written in decimal to 1e-12 (hsgran.scene
#: CONTACT_TOLERANCE), so the same bound.
START_GAP_REL = 1e-12


# What a prediction reads of a neighbour sits in one 64-byte row (one cache line) of ``st``:
S_X = 0  #: position x, y, z at the sphere's local time [m] (columns 0–2)
S_V = 3  #: velocity at the local time [m/s] (columns 3–5)
S_T = 6  #: local time: the stored state is valid at this instant [s]
S_R = 7  #: radius [m]
S_WIDTH = 8

# The arrays travel in seven tuples, unpacked where they are used:
#   flight = (st, counter, acc, mstate, mplane, seg_end, seg_code, pc_t, pc_partner, pc_count)
#            what a prediction needs of every sphere: the 64-byte rows, the event counters and,
#            with gravity, each sphere's acceleration [m/s²], motion state (hsgran.onplane MS_*),
#            plane, and the end time [s] and kind (END_*) of its on-plane motion segment;
#            without gravity, each sphere's earliest pair contact among its neighbours at its
#            last prediction (time [s], partner or −1, the partner's counter then), which lets a
#            cell crossing look at the new layer of cells only (see _predict)
#   dyn    = (omg, inv_m, inv_i, mat, zstreak, alpha, seg_dir, t_last, row_tc, rapid)
#            what a collision needs in addition; alpha [rad/s²] and seg_dir (the direction the
#            segment's end refers to) only with gravity; t_last: time of each sphere's last
#            collision [s] (TC model); row_tc: scratch pair row for an elastic TC collision
# Without gravity acc, mstate, mplane, seg_end, seg_code, alpha and seg_dir are 1-row dummies,
# with gravity pc_t, pc_partner and pc_count.
#   walls  = (planes_p, planes_n, planes_mat, planes_vel, planes_omg)
#   space  = (gravity, box_len, periodic)
#   grid   = (origin, csize, ncell, cell, head, nxt, prv, heads, shifts, ac, ah, stack)   the last
#            five are scratch space: 27 list heads, their image shifts (27, 3), the per-axis list
#            coordinates and shifts (3, 3) of _predict, and a stack (N,) for waking sleepers
#   sched  = (ev_t, ev_seq, ev_kind, ev_partner, ev_pcount, cal)   cal: the event calendar's
#            arrays (hsgran.events.calendar), whose keys are ev_t and ev_seq
#   out    = (fr_time, fr_pos, fr_vel, fr_omg, log_f, log_i, fr_ms)


@njit(inline="always")
def _state_at(st, acc, j, t, grav_on):
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
def _advance(st, acc, omg, alpha, j, t, grav_on, rotation):
    """Move sphere j's stored state (and its spin, which changes only on a plane) to time t."""
    if grav_on and rotation:
        dt = t - st[j, S_T]
        omg[j, 0] += alpha[j, 0] * dt
        omg[j, 1] += alpha[j, 1] * dt
        omg[j, 2] += alpha[j, 2] * dt
    x, y, z, u, v, w = _state_at(st, acc, j, t, grav_on)
    st[j, 0] = x
    st[j, 1] = y
    st[j, 2] = z
    st[j, 3] = u
    st[j, 4] = v
    st[j, 5] = w
    st[j, S_T] = t


@njit(inline="always")
def _min_image(d, k, box_len, periodic):
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
def _note_progress(p, t, st, zstreak):
    """Count consecutive events of sphere p that do not advance its clock (collapse guard)."""
    if t - st[p, S_T] <= NO_PROGRESS_REL * max(1.0, t):
        zstreak[p] += 1
    else:
        zstreak[p] = 0


@njit(inline="always")
def _prefetch_cells(i, cell, ncell, head):
    """Ask for the list heads of the cells around sphere i's, ahead of its prediction (a hint
    only; the z-neighbours of a cell share its cache line mostly)."""
    nx = ncell[0]
    ny = ncell[1]
    nz = ncell[2]
    # (a coordinate is out of range only on a non-periodic axis, which is hashed)
    cx = cell[i, 0]
    cy = cell[i, 1]
    cz = cell[i, 2]
    if not (0 <= cx < nx and 0 <= cy < ny and 0 <= cz < nz):
        cx %= nx
        cy %= ny
        cz %= nz
    for a in range(3):
        x = cx + a - 1
        x = nx - 1 if x < 0 else (0 if x >= nx else x)
        for b in range(3):
            y = cy + b - 1
            y = ny - 1 if y < 0 else (0 if y >= ny else y)
            prefetch(head, (x * ny + y) * nz + cz)


@njit(inline="always")
def _axis_cells(c, n, length, periodic, k, ac, ah):
    """Write the neighbouring list coordinates along axis k and the image shift of each.

    Args:
        c: Sphere's cell coordinate (in [0, n) on a periodic axis, any integer otherwise).
        n: Cells on the axis; ≥ 3 on a periodic axis, except 1 for the all-pairs mode.
        length: Period [m] (periodic axes).
        periodic: Whether the axis is periodic.
        k: Axis.
        ac, ah: (3, 3) scratch: row k receives the coordinates and the shifts [m]; a sphere
            stored in list coordinate ``ac[k, a]`` is met at its stored position + ``ah[k, a]``.

    Returns:
        The number of entries written. One modulo, then ±1 offsets wrap by comparison (integer
        division costs tens of cycles, and this runs at every prediction).
    """
    if n == 1:
        ac[k, 0] = 0
        ah[k, 0] = 0.0
        if periodic:  # all-pairs mode: every sphere, in each of its three images
            ac[k, 1] = 0
            ac[k, 2] = 0
            ah[k, 1] = -length
            ah[k, 2] = length
            return 3
        return 1
    if n == 2:  # a non-periodic hashed axis: both lists, no images
        ac[k, 0] = 0
        ac[k, 1] = 1
        ah[k, 0] = 0.0
        ah[k, 1] = 0.0
        return 2
    b = c % n
    ac[k, 0] = b - 1
    ac[k, 1] = b
    ac[k, 2] = b + 1
    ah[k, 0] = 0.0
    ah[k, 1] = 0.0
    ah[k, 2] = 0.0
    if b == 0:
        ac[k, 0] = n - 1
        if periodic:
            ah[k, 0] = -length
    if b == n - 1:
        ac[k, 2] = 0
        if periodic:
            ah[k, 2] = length
    return 3


@njit(inline="always")
def _predict(i, t_now, flight, walls, space, grid, sched, isc, grav_on, layer):
    """Find sphere i's next event after t_now and store it (the caller moves its calendar entry).

    ``layer`` ≥ 0 (without gravity only): i has just crossed that cell face (EV_CELL code) and
    its trajectory is unchanged since its last prediction. Then only the spheres in the new layer
    of neighbouring cells are looked at, against the earliest pair contact of the last
    prediction (``pc_*``) if its partner has had no event since. That is exact: a neighbour that
    has not changed its flight meets i no earlier than that contact, one that has changed was
    predicted against i then, and the spheres of the layer left behind are out of reach until
    one of the two crosses again (Rapaport's treatment of cell crossings). Otherwise, or if the
    partner has moved on, all neighbouring cells are looked at.
    """
    st, counter, acc, mstate = flight.st, flight.counter, flight.acc, flight.mstate
    mplane, seg_end, seg_code = flight.mplane, flight.seg_end, flight.seg_code
    pc_t, pc_partner, pc_count = flight.pc_t, flight.pc_partner, flight.pc_count
    planes_p, planes_n = walls.planes_p, walls.planes_n
    box_len, periodic = space.box_len, space.periodic
    origin, csize, ncell = grid.origin, grid.csize, grid.ncell
    cell, head, nxt = grid.cell, grid.head, grid.nxt
    ev_t, ev_seq, ev_kind = sched.ev_t, sched.ev_seq, sched.ev_kind
    ev_partner, ev_pcount = sched.ev_partner, sched.ev_pcount
    xi, yi, zi, ui, vi, wi = _state_at(st, acc, i, t_now, grav_on)
    ri = st[i, S_R]
    best = NEVER
    kind = EV_NONE
    partner = -1
    on_plane = -1
    if grav_on:
        gi = (acc[i, 0], acc[i, 1], acc[i, 2])
        if mstate[i] != MS_FLIGHT:
            on_plane = mplane[i]
            if seg_end[i] < NEVER:
                best = max(0.0, seg_end[i] - t_now)
                kind = EV_STATE
                partner = seg_code[i]
    else:
        gi = (0.0, 0.0, 0.0)
    xs = (xi, yi, zi)
    us = (ui, vi, wi)
    for k in range(3):
        lo = origin[k] + cell[i, k] * csize[k]
        tau, side = face_exit_time(xs[k], us[k], gi[k], lo, lo + csize[k])
        if tau < best:
            best = tau
            kind = EV_CELL
            partner = 2 * k + (1 if side > 0 else 0)
    for w in range(planes_p.shape[0]):
        if w == on_plane:
            continue
        nx = planes_n[w, 0]
        ny = planes_n[w, 1]
        nz = planes_n[w, 2]
        gap = ((xi - planes_p[w, 0]) * nx + (yi - planes_p[w, 1]) * ny
               + (zi - planes_p[w, 2]) * nz - ri)
        if gap <= TOUCHING_REL * ri:
            # touching within rounding: a contact now if approaching or pressed (a gap of
            # 1e-19 m closing at 1e-5 m/s would otherwise come 1e-14 s later, after every
            # zero-time pair event of a sphere wedged between neighbours on this plane)
            gap = 0.0
        gn = gi[0] * nx + gi[1] * ny + gi[2] * nz
        tau = plane_contact_time(gap, ui * nx + vi * ny + wi * nz, gn)
        if tau < best:
            best = tau
            kind = EV_WALL
            partner = w
    # The neighbouring lists and, on periodic axes, which image of their spheres can touch
    # sphere i: the one in the cell next to i's (the nearest image at prediction time is not
    # always the one that touches later). First gather the heads of the lists, then walk them:
    # the head loads do not depend on each other, so their cache misses overlap (measured 1.2x
    # faster predictions at N = 1e6, where the grid does not fit the cache; same at N = 1e3).
    # i's share of the rounding scales of an approach (motion.approach_noise)
    vs_i = abs(ui) + abs(vi) + abs(wi)
    xs_i = abs(xi) + abs(yi) + abs(zi)
    heads, shifts, ac, ah = grid.heads, grid.shifts, grid.ac, grid.ah
    mx = _axis_cells(cell[i, 0], ncell[0], box_len[0], periodic[0], 0, ac, ah)
    my = _axis_cells(cell[i, 1], ncell[1], box_len[1], periodic[1], 1, ac, ah)
    mz = _axis_cells(cell[i, 2], ncell[2], box_len[2], periodic[2], 2, ac, ah)
    # the earliest pair contact so far [s from t_now] and its partner; with gravity the search
    # stops at the best event of any kind, without it the pair contact is found in full (the
    # next crossing reuses it)
    pbest = NEVER
    ppartner = -1
    kept = False
    if not grav_on and layer >= 0:
        kl = layer // 2
        q = pc_partner[i]
        if ncell[kl] >= LAYER_MIN_CELLS and (q < 0 or counter[q] == pc_count[i]):
            # look at the new layer only: row kl of (ac, ah) keeps the entry ahead of i
            e = 2 if layer % 2 == 1 else 0
            ac[kl, 0] = ac[kl, e]
            ah[kl, 0] = ah[kl, e]
            if kl == 0:
                mx = 1
            elif kl == 1:
                my = 1
            else:
                mz = 1
            pbest = pc_t[i] - t_now
            ppartner = q
            kept = True
    m = 0
    for a in range(mx):
        sx = ac[0, a] * ncell[1]
        for b in range(my):
            sxy = (sx + ac[1, b]) * ncell[2]
            for c in range(mz):
                j = head[sxy + ac[2, c]]
                if j >= 0:
                    heads[m] = j
                    shifts[m, 0] = ah[0, a]
                    shifts[m, 1] = ah[1, b]
                    shifts[m, 2] = ah[2, c]
                    m += 1
    if has_buckets(sched.cal):  # a large system: its rows are likely not in the cache
        for q in range(m):
            prefetch(st, heads[q])
            prefetch(nxt, heads[q])
    for q in range(m):
        j = heads[q]
        ox = xi - shifts[q, 0]
        oy = yi - shifts[q, 1]
        oz = zi - shifts[q, 2]
        while j >= 0:
            if j != i:
                xj, yj, zj, uj, vj, wj = _state_at(st, acc, j, t_now, grav_on)
                horizon = min(best, pbest) if grav_on else pbest
                if grav_on and (acc[j, 0] != gi[0] or acc[j, 1] != gi[1] or acc[j, 2] != gi[2]):
                    # different accelerations (one of them on a plane): a quartic, wanted only
                    # up to the end of j's current motion segment (j's transition re-predicts)
                    tau = pair_contact_accelerated(
                        ox - xj, oy - yj, oz - zj, ui - uj, vi - vj, wi - wj, gi[0] - acc[j, 0],
                        gi[1] - acc[j, 1], gi[2] - acc[j, 2], ri + st[j, S_R],
                        min(horizon, seg_end[j] - t_now), vs_i + abs(uj) + abs(vj) + abs(wj),
                        xs_i + abs(xj) + abs(yj) + abs(zj))
                else:
                    tau = pair_contact_before(ox - xj, oy - yj, oz - zj, ui - uj, vi - vj,
                                              wi - wj, ri + st[j, S_R], horizon,
                                              vs_i + abs(uj) + abs(vj) + abs(wj),
                                              xs_i + abs(xj) + abs(yj) + abs(zj))
                if tau < pbest:
                    pbest = tau
                    ppartner = j
                    kept = False
            j = nxt[j]
    if not grav_on and not kept:
        pc_t[i] = t_now + pbest
        pc_partner[i] = ppartner
        pc_count[i] = counter[ppartner] if ppartner >= 0 else 0
    if pbest < best:
        best = pbest
        kind = EV_PAIR
        partner = ppartner
    # a kept contact keeps its time to the bit (t_now + (t − t_now) need not be t)
    ev_t[i] = pc_t[i] if kind == EV_PAIR and kept else t_now + best
    ev_kind[i] = kind
    ev_partner[i] = partner
    ev_pcount[i] = counter[partner] if kind == EV_PAIR else 0
    ev_seq[i] = isc[I_SEQ]
    isc[I_SEQ] += 1


# The prediction is the hot path: run_loop inlines it at one place only (the re-predictions an
# event asks for wait in isc[I_PEND_*] until the top of the next iteration), and every other
# caller goes through these compiled functions. Inlining it at each call site made the loop
# take minutes to compile.
@njit
def _predict_fn(i, t_now, flight, walls, space, grid, sched, isc, grav_on):
    """:func:`_predict` as a compiled function (for cold callers; all neighbours)."""
    _predict(i, t_now, flight, walls, space, grid, sched, isc, grav_on, -1)


@njit
def _reschedule_fn(i, t_now, flight, walls, space, grid, sched, isc, grav_on):
    """Predict sphere i's next event (all neighbours) and move its calendar entry accordingly
    (for cold callers)."""
    _predict_fn(i, t_now, flight, walls, space, grid, sched, isc, grav_on)
    calendar_update(sched.cal, sched.ev_t, sched.ev_seq, i)


@njit(inline="always")
def _repredict_later(isc, p):
    """Queue sphere p for re-prediction at the top of the next loop iteration (at most two)."""
    if isc[I_PEND_A] < 0:
        isc[I_PEND_A] = p
    else:
        isc[I_PEND_B] = p


@njit
def _leave_plane(i, flight, dyn, gravity, rotation):
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


@njit(inline="always")
def _halt(p, st, omg, rotation):
    """Sphere p stops: zero velocity and spin."""
    for k in range(3):
        st[p, S_V + k] = 0.0
        if rotation:
            omg[p, k] = 0.0


@njit
def _stop_on_plane(p, t, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling,
                   rotation):
    """Sphere p, on its plane, stops there: at rest, or, on a slope too steep for rest, starting
    a new segment from standstill."""
    _halt(p, flight.st, dyn.omg, rotation)
    _enter_plane(p, np.int64(flight.mplane[p]), t, np.int64(END_NONE), flight, dyn, walls, gravity,
                 pair_table, fsc, friction, rolling, rotation)
    flight.counter[p] += 1


@njit
def _enter_plane(i, w, t, snap, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling,
                 rotation):
    """Put sphere i on plane w at time t (or start its next segment there; ``snap`` is the
    transition that ended the last one): MODEL §5.3 through hsgran.onplane.plane_segment."""
    st, acc, mstate = flight.st, flight.acc, flight.mstate
    mplane, seg_end, seg_code = flight.mplane, flight.seg_end, flight.seg_code
    omg, mat, alpha, seg_dir = dyn.omg, dyn.mat, dyn.alpha, dyn.seg_dir
    planes_p, planes_n, planes_mat = walls.planes_p, walls.planes_n, walls.planes_mat
    nx = planes_n[w, 0]
    ny = planes_n[w, 1]
    nz = planes_n[w, 2]
    # exactly on the plane, moving along it: the normal gap and speed left are round-off or
    # (on landing) the rebound given up, bounded by the landing speed
    gap = ((st[i, 0] - planes_p[w, 0]) * nx + (st[i, 1] - planes_p[w, 1]) * ny
           + (st[i, 2] - planes_p[w, 2]) * nz - st[i, S_R])
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
    seg_end[i] = t + dur
    seg_code[i] = code


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
def _note_rapid(p, t, t_last, rapid, tc):
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
    rest there (_stop_on_plane; on a slope too steep for rest it slides on from standstill).
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
        _halt(p, st, omg, rotation)
    else:
        _stop_on_plane(p, t, flight, dyn, walls, gravity, pair_table, fsc, friction, rolling,
                       rotation)
    return True


@njit(inline="always")
def _both_slow_on_supports(i, j, st, mstate, v_land):
    """Whether spheres i and j are both on a support (a plane, or asleep on a sphere) and both
    slower than the landing speed ``v_land`` [m/s]. When such spheres meet they both stop
    where they are (on a steep incline the plane then sets them moving again) [OURS]: the
    sphere-against-sphere counterpart of landing, at a cost of at most ½ m v_land² per sphere
    stopped. As a collision, a slow sphere sliding into a resting one that had just taken a
    sleeper made a zero-time chain: the collision moved the support, the sleeper stopped it
    again, and the slider met it again, ever slower."""
    if mstate[i] == MS_FLIGHT or mstate[j] == MS_FLIGHT:
        return False
    vi2 = st[i, 3] * st[i, 3] + st[i, 4] * st[i, 4] + st[i, 5] * st[i, 5]
    vj2 = st[j, 3] * st[j, 3] + st[j, 4] * st[j, 4] + st[j, 5] * st[j, 5]
    return vi2 <= v_land * v_land and vj2 <= v_land * v_land


@njit
def _fall_asleep(a, b, flight, dyn, rotation):
    """Sphere a rests on sphere b from now on: zero velocity, spin and acceleration."""
    st, acc, mstate = flight.st, flight.acc, flight.mstate
    mplane, seg_end = flight.mplane, flight.seg_end
    _halt(a, st, dyn.omg, rotation)
    for k in range(3):
        acc[a, k] = 0.0
        if rotation:
            dyn.alpha[a, k] = 0.0
    mstate[a] = MS_REST
    mplane[a] = -2 - b  # the support: sphere b
    seg_end[a] = NEVER


@njit
def _wake_sleepers(s, t, flight, dyn, walls, space, grid, sched, isc, grav_on, rotation):
    """Sphere s was at rest and has been hit: every sphere asleep on it, and on those, falls."""
    st, counter, acc = flight.st, flight.counter, flight.acc
    mstate, mplane = flight.mstate, flight.mplane
    omg, alpha = dyn.omg, dyn.alpha
    gravity, box_len, periodic = space
    ncell, cell, head, nxt, ac, ah, stack = grid.ncell, grid.cell, grid.head, grid.nxt, grid.ac, \
        grid.ah, grid.stack
    top = 0
    stack[top] = s
    top += 1
    while top > 0:
        top -= 1
        b = stack[top]
        mx = _axis_cells(cell[b, 0], ncell[0], box_len[0], periodic[0], 0, ac, ah)
        my = _axis_cells(cell[b, 1], ncell[1], box_len[1], periodic[1], 1, ac, ah)
        mz = _axis_cells(cell[b, 2], ncell[2], box_len[2], periodic[2], 2, ac, ah)
        for x in range(mx):
            for y in range(my):
                for z in range(mz):
                    q = np.int64(head[(ac[0, x] * ncell[1] + ac[1, y]) * ncell[2] + ac[2, z]])
                    while q >= 0:
                        if mstate[q] == MS_REST and mplane[q] == -2 - b:
                            _advance(st, acc, omg, alpha, q, t, grav_on, rotation)
                            _leave_plane(q, flight, dyn, gravity, rotation)
                            mplane[q] = -1
                            counter[q] += 1
                            _reschedule_fn(q, t, flight, walls, space, grid, sched, isc,
                                           grav_on)
                            stack[top] = q
                            top += 1
                        q = np.int64(nxt[q])


#: Two spheres pressed into planes with support cosines c_i, c_j both ~1 (c_i² + c_j² ≥ 2 − this)
#: would have no mobility along the contact normal: then neither is treated as backed.
SUPPORT_EPS = 1e-9


@njit(inline="always")
def _support_normal(p, st, mstate, mplane, planes_n, box_len, periodic):
    """Unit normal N [-] of what backs sphere p: its plane's normal, or, for a sphere asleep on
    sphere b, the direction from b to p; (0, 0, 0) for a sphere in flight."""
    if mstate[p] == MS_FLIGHT:
        return 0.0, 0.0, 0.0
    w = mplane[p]
    if w >= 0:
        return planes_n[w, 0], planes_n[w, 1], planes_n[w, 2]
    b = -2 - w
    if b < 0:
        return 0.0, 0.0, 0.0
    dx = _min_image(st[p, 0] - st[b, 0], 0, box_len, periodic)
    dy = _min_image(st[p, 1] - st[b, 1], 1, box_len, periodic)
    dz = _min_image(st[p, 2] - st[b, 2], 2, box_len, periodic)
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
def _backed_velocity(p, v0x, v0y, v0z, jx, jy, jz, bx, by, bz, st, inv_m):
    """Velocity of a backed sphere p after the impulse J [N s] on it: its support (unit normal
    b) takes J·b."""
    jn = jx * bx + jy * by + jz * bz
    st[p, 3] = v0x + inv_m[p] * (jx - jn * bx)
    st[p, 4] = v0y + inv_m[p] * (jy - jn * by)
    st[p, 5] = v0z + inv_m[p] * (jz - jn * bz)


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
        _enter_plane(p, np.int64(mplane[p]), t, no_end, flight, dyn, walls, gravity, pair_table,
                     fsc, friction, rolling, rotation)
        return
    if _stays_asleep(p, c, st, mstate, mplane, fsc[F_LANDING_SPEED]):
        _halt(p, st, dyn.omg, rotation)
        return
    _leave_plane(p, flight, dyn, gravity, rotation)
    if mplane[p] < -1:
        mplane[p] = -1  # no longer asleep on a sphere


#: Code stored as the normal-model stage of a hop in the event log.
STAGE_HOP = -1


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
    for k in range(rec.shape[0]):
        rec[k] = math.nan
    rec[REC_J_N] = jn
    rec[REC_J_T] = 0.0
    rec[REC_E_N] = math.nan
    rec[REC_STAGE] = STAGE_HOP
    rec[REC_REGIME] = 0
    rec[REC_ENERGY_LOST] = -0.5 * m_eff * (v_hop * v_hop - vn * vn)
    return True


#: Restitution of a collision the TC model makes elastic.
TC_RESTITUTION = 1.0


@njit(inline="always")
def _tc_row(row, t, t1, t2, fsc, row_tc):
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
def _pressed(i, w, st, walls, gravity):
    """(normal load per unit mass g_n = −g·n [m/s²], normal velocity v·n [m/s]) of sphere i
    against plane w."""
    planes_n = walls.planes_n
    gn = -(gravity[0] * planes_n[w, 0] + gravity[1] * planes_n[w, 1]
           + gravity[2] * planes_n[w, 2])
    vn = st[i, 3] * planes_n[w, 0] + st[i, 4] * planes_n[w, 1] + st[i, 5] * planes_n[w, 2]
    return gn, vn


@njit
def _resting_plane(i, st, walls, gravity, v_land):
    """A plane that sphere i (in flight) touches within rounding while gravity presses it onto
    it and it moves off or onto it slower than the landing speed ``v_land`` [m/s], or −1. Such
    a sphere lands there at once: the rebound it would make is a landing's (the normal speed
    given up is at most v_land) [OURS]. A sphere wedged between neighbours on a plane and
    hopped off them, slightly upwards, would otherwise meet them again and again before it
    ever came back to the plane."""
    planes_p, planes_n = walls.planes_p, walls.planes_n
    for w in range(planes_p.shape[0]):
        gap = ((st[i, 0] - planes_p[w, 0]) * planes_n[w, 0]
               + (st[i, 1] - planes_p[w, 1]) * planes_n[w, 1]
               + (st[i, 2] - planes_p[w, 2]) * planes_n[w, 2] - st[i, S_R])
        if gap <= TOUCHING_REL * st[i, S_R]:
            gn, vn = _pressed(i, w, st, walls, gravity)
            if gn > 0.0 and abs(vn) <= v_land:
                return w
    return -1


@njit(inline="always")
def _approaching(i, j, dx, dy, dz, sigma, st):
    """Whether touching spheres i, j (r = x_i − x_j = (dx, dy, dz) [m]) approach by more than
    rounding: the re-check matching _predict's test (motion.approach_noise)."""
    rw = 0.0
    v_sum = 0.0
    x_sum = 0.0
    for k, rk in enumerate((dx, dy, dz)):
        rw += rk * (st[i, S_V + k] - st[j, S_V + k])
        v_sum += abs(st[i, S_V + k]) + abs(st[j, S_V + k])
        x_sum += abs(st[i, k]) + abs(st[j, k])
    return -rw > approach_noise(sigma, v_sum, x_sum)


SETTLE_NONE = 0  #: the pair collides
SETTLE_PLANE = 1  #: a sphere lying on a plane landed there
SETTLE_SLEEP = 2  #: a sphere fell asleep on the other (progress: it cannot repeat until the
#: support moves, so the collapse guard does not count it)
SETTLE_STOP = 3  #: both stopped on their supports


@njit
def _settle(i, j, nx, ny, nz, t, flight, dyn, walls, gravity, pair_table, fsc, friction,
            rolling, rotation):
    """The rules that end a slow meeting of spheres i, j (unit normal n from j to i) in rest
    instead of a collision, in this order [OURS]:

    1. one of them, in flight, lies on a plane it meets slower than the landing speed
       (_resting_plane): it lands there first;
    2. one falls asleep on the other (_falls_asleep; a slow support on a plane is brought to
       rest first, and if it cannot rest there, a steep incline, they collide);
    3. both are on supports and slow (_both_slow_on_supports): both stop.

    Returns (rule, sphere, partner): the rule that applied (SETTLE_*, SETTLE_NONE when the
    pair collides), and the sphere and partner of the event log's landing entry (partner
    −1 − w for plane w).
    """
    st, counter, mstate, mplane = flight.st, flight.counter, flight.mstate, flight.mplane
    v_land = fsc[F_LANDING_SPEED]
    no_end = np.int64(END_NONE)
    for p in (i, j):
        if mstate[p] == MS_FLIGHT:
            w = _resting_plane(p, st, walls, gravity, v_land)
            if w >= 0:
                _enter_plane(p, w, t, no_end, flight, dyn, walls, gravity, pair_table, fsc,
                             friction, rolling, rotation)
                counter[p] += 1
                return SETTLE_PLANE, p, -1 - w
    rapid, zstreak = dyn.rapid, dyn.zstreak
    sleeper = _falls_asleep(i, j, nx, ny, nz, st, mstate, mplane, gravity, v_land,
                            rapid[i] > JAM_EVENTS or zstreak[i] > JAM_EVENTS,
                            rapid[j] > JAM_EVENTS or zstreak[j] > JAM_EVENTS)
    if sleeper >= 0:
        other = j if sleeper == i else i
        if mstate[other] != MS_REST:
            # giving up less than ½ m v_land²
            _stop_on_plane(other, t, flight, dyn, walls, gravity, pair_table, fsc, friction,
                           rolling, rotation)
        if mstate[other] == MS_REST:
            # the sphere stays on its support, which is not moved
            _fall_asleep(sleeper, other, flight, dyn, rotation)
            counter[sleeper] += 1
            return SETTLE_SLEEP, sleeper, other
    if _both_slow_on_supports(i, j, st, mstate, v_land):
        for p in (i, j):
            if mstate[p] != MS_REST:
                _stop_on_plane(p, t, flight, dyn, walls, gravity, pair_table, fsc, friction,
                               rolling, rotation)
        return SETTLE_STOP, i, j
    return SETTLE_NONE, -1, 0


@njit(inline="always")
def _log(out, isc, t, jn, jt, en, kind, i, other, stage, regime):
    """Append one entry to the event log; True when the buffer can no longer take all the
    entries of one event (LOG_ENTRIES_PER_EVENT): flush it before the next event.

    Collisions log (J_n, J_t, e_n, stage, regime); motion-state changes (``EV_STATE``,
    ``EV_LAND``, ``EV_WEDGE``) log zero impulses, e_n = NaN, the new motion state
    (hsgran.onplane ``MS_*``) as the stage and the transition that ended the last segment
    (``END_*``) as the regime."""
    log_f, log_i = out.log_f, out.log_i
    m = isc[I_N_LOG]
    log_f[m, 0] = t
    log_f[m, 1] = jn
    log_f[m, 2] = jt
    log_f[m, 3] = en
    log_i[m, 0] = kind
    log_i[m, 1] = i
    log_i[m, 2] = other
    log_i[m, 3] = stage
    log_i[m, 4] = regime
    isc[I_N_LOG] = m + 1
    return log_f.shape[0] - (m + 1) < LOG_ENTRIES_PER_EVENT


@njit
def init(flight, dyn, walls, space, grid, sched, pair_table, fsc, isc, flags):
    """Predict every sphere's first event and build the calendar (``flags``: see ``FL_*``)."""
    friction, rolling, rotation = flags[FL_FRICTION], flags[FL_ROLLING], flags[FL_ROTATION]
    grav_on = flags[FL_GRAVITY]
    no_end = np.int64(END_NONE)
    st = flight.st
    planes_p, planes_n = walls.planes_p, walls.planes_n
    if grav_on:
        # spheres that start on a plane (touching it, not moving away faster than the
        # landing speed, pressed on by gravity) start in an on-plane state
        for i in range(st.shape[0]):
            for w in range(planes_p.shape[0]):
                gap = ((st[i, 0] - planes_p[w, 0]) * planes_n[w, 0]
                       + (st[i, 1] - planes_p[w, 1]) * planes_n[w, 1]
                       + (st[i, 2] - planes_p[w, 2]) * planes_n[w, 2] - st[i, S_R])
                gn, vn = _pressed(i, w, st, walls, space.gravity)
                if (abs(gap) <= START_GAP_REL * st[i, S_R] and gn > 0.0
                        and vn <= fsc[F_LANDING_SPEED] and flight.mstate[i] == MS_FLIGHT):
                    _enter_plane(i, w, 0.0, no_end, flight, dyn, walls, space.gravity,
                                 pair_table, fsc, friction, rolling, rotation)
    for i in range(st.shape[0]):
        _predict_fn(i, 0.0, flight, walls, space, grid, sched, isc, grav_on)
    calendar_build(sched.cal, sched.ev_t, sched.ev_seq, 0.0)


@njit(inline="always")
def _prefetch_next(cal, ev_t, st, cell, n):
    """Ask for the records of the sphere that is likely to have the event after the one at the
    top of the calendar (the earliest of the top's children in its heap), so that they are in
    the cache when its turn comes (a hint: nothing changes if the guess is wrong)."""
    heap, key_t = cal[0], cal[2]
    last = min(ARITY, cal[7][Q_SIZE] - 1)
    if last < 1:
        return -1
    best = 1
    for c in range(2, last + 1):
        if key_t[c] < key_t[best]:
            best = c
    e = heap[best]
    if e >= n:
        return -1
    prefetch(ev_t, e)
    prefetch(st, e)
    prefetch(cell, e)
    return e


@njit
def _run_loop(flight, dyn, walls, space, grid, sched, out, pair_table, fsc, isc, counts,
              max_events, rec, flags, grav_on):
    """Run events until t_end, a full buffer, or ``max_events``; returns a ``STATUS_*`` code.

    ``grav_on`` (= ``flags[FL_GRAVITY]``) is a compile-time constant: see :func:`run_loop`.

    The array groups are listed at the top of this module. ``omg`` is (N, 3) with rotation
    and (1, 3) otherwise (never read then); likewise ``fr_omg``. ``log_f`` (L, 4) holds
    (time, J_n, J_t, e_n) and ``log_i`` (L, 5) holds (kind, i, j, stage, regime) of each
    executed collision; j = −1 − w for a collision with plane w. ``fr_ms`` (F, N) int8 takes
    every sphere's motion state at each frame (``MS_*``, ``MS_ASLEEP`` for a sleeper; left at
    flight without gravity, where there are no motion states).
    """
    plasticity, friction, rolling = flags[FL_PLASTICITY], flags[FL_FRICTION], flags[FL_ROLLING]
    adhesion, rotation = flags[FL_ADHESION], flags[FL_ROTATION]
    log_on = flags[FL_LOG]
    no_end = np.int64(END_NONE)  # a typed value, not a literal: one compiled _enter_plane
    st, counter, acc = flight.st, flight.counter, flight.acc
    mstate, mplane = flight.mstate, flight.mplane
    omg, inv_m, inv_i = dyn.omg, dyn.inv_m, dyn.inv_i
    mat, zstreak, alpha = dyn.mat, dyn.zstreak, dyn.alpha
    t_last, row_tc, rapid = dyn.t_last, dyn.row_tc, dyn.rapid
    planes_n, planes_mat = walls.planes_n, walls.planes_mat
    planes_vel, planes_omg = walls.planes_vel, walls.planes_omg
    gravity, box_len, periodic = space
    ncell, cell, head, nxt, prv = grid.ncell, grid.cell, grid.head, grid.nxt, grid.prv
    ev_t, ev_seq, ev_kind, ev_partner, ev_pcount, cal = sched
    fr_time, fr_pos, fr_vel = out.fr_time, out.fr_pos, out.fr_vel
    fr_omg, fr_ms = out.fr_omg, out.fr_ms
    n = st.shape[0]
    t_end = fsc[F_T_END]
    executed = 0
    guess = -1  # the sphere likely to have the next event (_prefetch_next)
    # Prefetch hints only for large systems, whose data do not fit the cache. The calendar
    # has buckets exactly for them, and has_buckets is a constant of its type: for small
    # systems the hints are not even compiled in.
    large = has_buckets(cal)
    while True:
        if large and guess >= 0 and ev_kind[guess] == EV_PAIR:
            # its record has arrived meanwhile: ask for its partner's too
            prefetch(st, ev_partner[guess])
            prefetch(ev_t, ev_partner[guess])
        # predict both spheres first, then move their calendar entries: the places in the
        # calendar that the moves touch are asked for (prefetched) meanwhile
        pa = isc[I_PEND_A]
        pb = isc[I_PEND_B]
        for slot in range(I_PEND_A, I_PEND_B + 1):
            p = isc[slot]
            if p >= 0:
                isc[slot] = -1
                layer = isc[I_PEND_LAYER] if slot == I_PEND_A else -1
                isc[I_PEND_LAYER] = -1
                _predict(p, fsc[F_T_CUR], flight, walls, space, grid, sched, isc, grav_on, layer)
                if large:
                    calendar_prefetch(cal, ev_t, p)
        if pa >= 0:
            calendar_update(cal, ev_t, ev_seq, pa)
        if pb >= 0:
            calendar_update(cal, ev_t, ev_seq, pb)
        e, t = calendar_top(cal, ev_t, ev_seq)
        if large:
            guess = _prefetch_next(cal, ev_t, st, cell, n)
        if t > t_end or t == NEVER:
            # a frame due at t_end whose time k × frame_dt rounded above it is still taken
            # (0.3 s is not 6 × 0.05 s in floating point)
            if not (e == n and t - t_end <= ZERO_TIME_REL * max(1.0, t_end)):
                return STATUS_DONE
        fsc[F_T_CUR] = t
        if e == n:
            # frame tick: sample every sphere's flight at t, leave the stored states alone
            f = isc[I_N_FRAMES]
            fr_time[f] = t
            for j in range(n):
                x, y, z, u, v, w = _state_at(st, acc, j, t, grav_on)
                fr_pos[f, j, 0] = x
                fr_pos[f, j, 1] = y
                fr_pos[f, j, 2] = z
                fr_vel[f, j, 0] = u
                fr_vel[f, j, 1] = v
                fr_vel[f, j, 2] = w
                if grav_on:
                    fr_ms[f, j] = (MS_ASLEEP if mstate[j] == MS_REST and mplane[j] <= -2
                                   else mstate[j])
                if rotation:
                    dt = t - st[j, S_T] if grav_on else 0.0
                    fr_omg[f, j, 0] = omg[j, 0] + alpha[j, 0] * dt if grav_on else omg[j, 0]
                    fr_omg[f, j, 1] = omg[j, 1] + alpha[j, 1] * dt if grav_on else omg[j, 1]
                    fr_omg[f, j, 2] = omg[j, 2] + alpha[j, 2] * dt if grav_on else omg[j, 2]
            isc[I_N_FRAMES] = f + 1
            isc[I_FRAME_INDEX] += 1
            ev_t[n] = isc[I_FRAME_INDEX] * fsc[F_FRAME_DT]
            ev_seq[n] = isc[I_SEQ]
            isc[I_SEQ] += 1
            calendar_update(cal, ev_t, ev_seq, n)
            counts[EV_FRAME] += 1
            if f + 1 == fr_time.shape[0]:
                return STATUS_FRAMES_FULL
            continue

        i = e
        kind = ev_kind[i]
        landed = False
        wedged_a = wedged_b = -1  # spheres this collision stops in a wedge (_wedge_stop)
        tc_on = False
        if kind == EV_PAIR:
            j = np.int64(ev_partner[i])  # one integer type for sphere indices: one compile
            if large:
                _prefetch_cells(i, cell, ncell, head)
            if counter[j] != ev_pcount[i]:
                # stale: the partner moved on since this was predicted; re-predict the owner
                _repredict_later(isc, i)
                counts[EV_STALE] += 1
                continue
            if large:
                _prefetch_cells(j, cell, ncell, head)
            _note_progress(i, t, st, zstreak)
            _note_progress(j, t, st, zstreak)
            _advance(st, acc, omg, alpha, i, t, grav_on, rotation)
            _advance(st, acc, omg, alpha, j, t, grav_on, rotation)
            dx = _min_image(st[i, 0] - st[j, 0], 0, box_len, periodic)
            dy = _min_image(st[i, 1] - st[j, 1], 1, box_len, periodic)
            dz = _min_image(st[i, 2] - st[j, 2], 2, box_len, periodic)
            dist = math.sqrt(dx * dx + dy * dy + dz * dz)
            nx, ny, nz = dx / dist, dy / dist, dz / dist
            if grav_on:
                # a slow meeting that ends in rest instead of a collision (see _settle)
                rule, who, what = _settle(i, j, nx, ny, nz, t, flight, dyn, walls, gravity,
                                          pair_table, fsc, friction, rolling, rotation)
                if rule != SETTLE_NONE:
                    # re-predictions in a fixed order (it sets the sequence numbers that break
                    # ties between simultaneous events): a sleeper first, else i
                    first = who if rule == SETTLE_SLEEP else i
                    _repredict_later(isc, first)
                    _repredict_later(isc, j if first == i else i)
                    counts[EV_LAND] += 1
                    if rule != SETTLE_SLEEP and (zstreak[i] > MAX_ZERO_TIME_EVENTS
                                                 or zstreak[j] > MAX_ZERO_TIME_EVENTS):
                        isc[I_COLLAPSED] = i
                        return STATUS_COLLAPSE
                    if log_on and _log(out, isc, t, 0.0, 0.0, math.nan, EV_LAND, who, what,
                                       mstate[who], END_NONE):
                        return STATUS_LOG_FULL
                    continue
                rest_i = mstate[i] == MS_REST
                rest_j = mstate[j] == MS_REST
            wi = omg[i] if rotation else omg[0]
            wj = omg[j] if rotation else omg[0]
            ri = st[i, S_R]
            rj = st[j, S_R]
            ci = cj = 0.0
            if grav_on:
                # a sphere on a plane that the impulse presses into the plane is backed by it
                bix, biy, biz = _support_normal(i, st, mstate, mplane, planes_n, box_len,
                                                periodic)
                bjx, bjy, bjz = _support_normal(j, st, mstate, mplane, planes_n, box_len,
                                                periodic)
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
            row, tc_on = _tc_row(pair_table[mat[i], mat[j]], t, t_last[i], t_last[j], fsc, row_tc)
            hit = False
            held_i = held_j = False
            if grav_on:
                # pressed together by their accelerations and meeting slower than a hop: a hop
                # instead of a collision (see _hop); a sphere at rest is held where it is
                held_i = mstate[i] == MS_REST
                held_j = mstate[j] == MS_REST
                hit = _hop(i, j, nx, ny, nz, 0.0 if held_i else inv_mi,
                           0.0 if held_j else inv_mj, st, acc, rec, fsc[F_TC_TIME])
                if hit:
                    counts[EV_HOP] += 1
                    tc_on = False
                    if held_i:
                        ci = inv_mi = 0.0
                    if held_j:
                        cj = inv_mj = 0.0
                else:
                    held_i = held_j = False
            hopped = hit
            inv_ii, inv_ij = inv_i[i], inv_i[j]
            if grav_on and not hit:
                # a sphere at rest met slower than the landing speed is held where it is: such
                # a touch cannot move it in a pile [OURS]; knocked off, it would stop again at
                # once and be knocked off again (a zero-time sequence)
                held_i = _slow_touch_at_rest(i, j, nx, ny, nz, st, mstate,
                                             fsc[F_LANDING_SPEED])
                held_j = _slow_touch_at_rest(j, i, -nx, -ny, -nz, st, mstate,
                                             fsc[F_LANDING_SPEED])
                if held_i and held_j:
                    held_i = held_j = False  # two resting spheres never approach each other
                if held_i:
                    ci = inv_mi = inv_ii = 0.0
                if held_j:
                    cj = inv_mj = inv_ij = 0.0
            for attempt in range(2):
                if not hit and _approaching(i, j, dx, dy, dz, ri + rj, st):
                    hit = resolve(st[i, S_V:S_V + 3], wi, st[j, S_V:S_V + 3], wj, nx, ny, nz,
                                  inv_mi, inv_mj, inv_ii, inv_ij, ri, rj, 1.0 / ri + 1.0 / rj,
                                  row, rec, plasticity, friction, rolling, adhesion, rotation,
                                  False)
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
                        _backed_velocity(i, vi0x, vi0y, vi0z, jx, jy, jz, bix, biy, biz, st,
                                         inv_m)
                    if cj > 0.0:
                        _backed_velocity(j, vj0x, vj0y, vj0z, -jx, -jy, -jz, bjx, bjy, bjz, st,
                                         inv_m)
                if not grav_on or not hit or hopped or held_i or held_j or attempt > 0:
                    break
                # A sleeper that the collision leaves asleep (see _after_backed) has not
                # moved: the collision was with an immovable body, so it is redone as one
                # [OURS]. Otherwise a heavier sphere meeting a lighter sleeper would keep
                # approaching it after each collision (the sleeper's share of the momentum
                # vanishing as it is stopped): a zero-time sequence of collisions with
                # impulses shrinking geometrically.
                held_i = _stays_asleep(i, ci, st, mstate, mplane, fsc[F_LANDING_SPEED])
                held_j = _stays_asleep(j, cj, st, mstate, mplane, fsc[F_LANDING_SPEED])
                if held_i == held_j:
                    held_i = held_j = False  # (both: two sleepers never approach each other)
                    break
                st[i, 3], st[i, 4], st[i, 5] = vi0x, vi0y, vi0z
                st[j, 3], st[j, 4], st[j, 5] = vj0x, vj0y, vj0z
                wi[0], wi[1], wi[2] = wi0x, wi0y, wi0z
                wj[0], wj[1], wj[2] = wj0x, wj0y, wj0z
                if held_i:
                    ci = inv_mi = inv_ii = 0.0
                if held_j:
                    cj = inv_mj = inv_ij = 0.0
                hit = False
            if not hit:
                # re-check failed: a grazing contact that round-off turned into "separating"
                # (or into an approach below rounding, which _predict ignores as well).
                # Nothing changed, so no counter moves; both re-predict from the exact contact
                # state, which no longer approaches. A loop of such retries is caught by the
                # collapse guard (MAX_ZERO_TIME_EVENTS).
                _repredict_later(isc, i)
                _repredict_later(isc, j)
                counts[EV_MISS] += 1
                if zstreak[i] > MAX_ZERO_TIME_EVENTS or zstreak[j] > MAX_ZERO_TIME_EVENTS:
                    isc[I_COLLAPSED] = i
                    return STATUS_COLLAPSE
                continue
            if grav_on:
                # a backed sphere stays on its plane (a new segment from its new velocity and
                # spin); one pulled off it, or asleep on a sphere, flies
                if not held_i:
                    _after_backed(i, ci, t, no_end, flight, dyn, walls, gravity, pair_table,
                                  fsc, friction, rolling, rotation)
                if not held_j:
                    _after_backed(j, cj, t, no_end, flight, dyn, walls, gravity, pair_table,
                                  fsc, friction, rolling, rotation)
                # spheres asleep on a sphere that was at rest and now moves fall again
                if rest_i and mstate[i] != MS_REST:
                    _wake_sleepers(i, t, flight, dyn, walls, space, grid, sched, isc,
                                   flags[FL_GRAVITY], rotation)
                if rest_j and mstate[j] != MS_REST:
                    _wake_sleepers(j, t, flight, dyn, walls, space, grid, sched, isc,
                                   flags[FL_GRAVITY], rotation)
                # a zero-time sequence against a sphere the collision left at rest, or
                # against one stopped in such a sequence at this instant (met at standstill:
                # a chain between immovable ends, see _wedge_stop); not after a hop, whose
                # separation is what ends its zero-time meetings
                i_holds = _holds(i, vi0x, vi0y, vi0z, mstate, zstreak)
                j_holds = _holds(j, vj0x, vj0y, vj0z, mstate, zstreak)
                if not hopped and j_holds and _wedge_stop(i, t, flight, dyn, walls, gravity,
                                                          pair_table, fsc, friction, rolling,
                                                          rotation):
                    wedged_a = i
                if not hopped and i_holds and _wedge_stop(j, t, flight, dyn, walls, gravity,
                                                          pair_table, fsc, friction, rolling,
                                                          rotation):
                    wedged_b = j
            counter[i] += 1
            counter[j] += 1
            _note_rapid(i, t, t_last, rapid, fsc[F_TC_TIME])
            _note_rapid(j, t, t_last, rapid, fsc[F_TC_TIME])
            t_last[i] = t_last[j] = t
            _repredict_later(isc, i)
            _repredict_later(isc, j)
            other = j
        elif kind == EV_WALL:
            w = np.int64(ev_partner[i])
            _note_progress(i, t, st, zstreak)
            _advance(st, acc, omg, alpha, i, t, grav_on, rotation)
            if grav_on:
                gn, vn = _pressed(i, w, st, walls, gravity)
                if gn > 0.0 and -vn <= fsc[F_LANDING_SPEED]:
                    # too slow to bounce: it stays on the plane (MODEL §5.3; what is given
                    # up is the rebound, at most ½ m v_land², see hsgran.scene)
                    if mstate[i] != MS_FLIGHT:
                        _leave_plane(i, flight, dyn, gravity, rotation)
                    _enter_plane(i, w, t, no_end, flight, dyn, walls, gravity, pair_table,
                                 fsc, friction, rolling, rotation)
                    counter[i] += 1
                    _repredict_later(isc, i)
                    counts[EV_LAND] += 1
                    if zstreak[i] > MAX_ZERO_TIME_EVENTS:
                        isc[I_COLLAPSED] = i
                        return STATUS_COLLAPSE
                    if log_on and _log(out, isc, t, 0.0, 0.0, math.nan, EV_LAND, i, -1 - w,
                                       mstate[i], END_NONE):
                        return STATUS_LOG_FULL
                    continue
            wi = omg[i] if rotation else omg[0]
            ri = st[i, S_R]
            ci = -1.0
            if grav_on and mstate[i] != MS_FLIGHT and mplane[i] >= 0:
                # on another plane (a sphere sliding into a side wall): backed by that plane
                # as in the pair case, unless the wall pulls it off (or squeezes it head-on)
                pw = mplane[i]
                ci = -(planes_n[w, 0] * planes_n[pw, 0] + planes_n[w, 1] * planes_n[pw, 1]
                       + planes_n[w, 2] * planes_n[pw, 2])
                if ci < 0.0 or ci * ci >= 1.0 - SUPPORT_EPS:
                    ci = -1.0
            vi0x, vi0y, vi0z = st[i, 3], st[i, 4], st[i, 5]
            inv_mi = inv_m[i] * (1.0 - ci * ci) if ci >= 0.0 else inv_m[i]
            row, tc_on = _tc_row(pair_table[mat[i], planes_mat[w]], t, t_last[i], -NEVER, fsc,
                                 row_tc)
            hit = resolve(st[i, S_V:S_V + 3], wi, planes_vel[w], planes_omg[w],
                          planes_n[w, 0], planes_n[w, 1], planes_n[w, 2], inv_mi, 0.0,
                          inv_i[i], 0.0, ri, 0.0, 1.0 / ri, row, rec, plasticity, friction,
                          rolling, adhesion, rotation, False)
            if hit and ci >= 0.0:
                _backed_velocity(i, vi0x, vi0y, vi0z, (st[i, 3] - vi0x) / inv_mi,
                                 (st[i, 4] - vi0y) / inv_mi, (st[i, 5] - vi0z) / inv_mi,
                                 planes_n[pw, 0], planes_n[pw, 1], planes_n[pw, 2], st, inv_m)
            if not hit:
                # re-check failed (see the pair case)
                _repredict_later(isc, i)
                counts[EV_MISS] += 1
                if zstreak[i] > MAX_ZERO_TIME_EVENTS:
                    isc[I_COLLAPSED] = i
                    return STATUS_COLLAPSE
                continue
            if grav_on and ci >= 0.0:
                _enter_plane(i, np.int64(mplane[i]), t, no_end, flight, dyn, walls, gravity,
                             pair_table, fsc, friction, rolling, rotation)
            elif grav_on:
                if mstate[i] != MS_FLIGHT:
                    _leave_plane(i, flight, dyn, gravity, rotation)  # knocked off its plane
                gn, vn = _pressed(i, w, st, walls, gravity)
                if gn > 0.0 and vn <= fsc[F_LANDING_SPEED]:
                    _enter_plane(i, w, t, no_end, flight, dyn, walls, gravity, pair_table,
                                 fsc, friction, rolling, rotation)
                    counts[EV_LAND] += 1
                    landed = True
            # a zero-time sequence against this plane (planes never move: immovable)
            if grav_on and not landed and _wedge_stop(i, t, flight, dyn, walls, gravity,
                                                      pair_table, fsc, friction, rolling,
                                                      rotation):
                wedged_a = i
            counter[i] += 1
            _note_rapid(i, t, t_last, rapid, fsc[F_TC_TIME])
            t_last[i] = t
            _repredict_later(isc, i)
            other = -1 - w
        elif grav_on and kind == EV_STATE:
            # the on-plane motion segment ends: slide → roll, roll → rest, spin reversal
            _note_progress(i, t, st, zstreak)
            _advance(st, acc, omg, alpha, i, t, grav_on, rotation)
            ended = ev_partner[i]
            _enter_plane(i, np.int64(mplane[i]), t, np.int64(ended), flight, dyn, walls, gravity,
                         pair_table, fsc, friction, rolling, rotation)
            counter[i] += 1
            _repredict_later(isc, i)
            counts[EV_STATE] += 1
            if zstreak[i] > MAX_ZERO_TIME_EVENTS:
                isc[I_COLLAPSED] = i
                return STATUS_COLLAPSE
            if log_on and _log(out, isc, t, 0.0, 0.0, math.nan, EV_STATE, i, -1 - mplane[i],
                               mstate[i], ended):
                return STATUS_LOG_FULL
            continue
        else:
            # EV_CELL (EV_NONE has time NEVER and is never popped): move to the neighbouring
            # cell; on a periodic axis wrap the stored state by one box length
            code = ev_partner[i]
            k = code // 2
            step = 1 if code % 2 == 1 else -1
            old = slot_of(cell[i, 0], cell[i, 1], cell[i, 2], ncell)
            c = cell[i, k] + step
            if periodic[k]:
                if c >= ncell[k]:
                    c = 0
                    st[i, k] -= box_len[k]
                elif c < 0:
                    c = ncell[k] - 1
                    st[i, k] += box_len[k]
            cell[i, k] = c
            remove(i, old, head, nxt, prv)
            insert(i, slot_of(cell[i, 0], cell[i, 1], cell[i, 2], ncell), head, nxt, prv)
            if large:
                _prefetch_cells(i, cell, ncell, head)
            _repredict_later(isc, i)  # into I_PEND_A: the top of the loop emptied both slots
            isc[I_PEND_LAYER] = code  # look at the new layer of neighbours only
            counts[EV_CELL] += 1
            continue

        # a collision was executed (pair or wall)
        counts[kind] += 1
        if tc_on:
            counts[EV_TC] += 1
        isc[I_N_EVENTS] += 1
        executed += 1
        fsc[F_DISSIPATED] += rec[REC_ENERGY_LOST]
        if zstreak[i] > MAX_ZERO_TIME_EVENTS or (
                other >= 0 and zstreak[other] > MAX_ZERO_TIME_EVENTS):
            isc[I_COLLAPSED] = i
            return STATUS_COLLAPSE
        for p in (wedged_a, wedged_b):
            if p >= 0:
                counts[EV_WEDGE] += 1
        if log_on:
            # every entry of the event is written (_log keeps room for them)
            full = _log(out, isc, t, rec[REC_J_N], rec[REC_J_T], rec[REC_E_N], kind, i,
                        other, int(rec[REC_STAGE]), int(rec[REC_REGIME]))
            if landed:
                # the rebound was too slow: the sphere stays on the plane from now on
                full = _log(out, isc, t, 0.0, 0.0, math.nan, EV_LAND, i, other, mstate[i],
                            END_NONE) or full
            for p in (wedged_a, wedged_b):
                if p >= 0:
                    full = _log(out, isc, t, 0.0, 0.0, math.nan, EV_WEDGE, p,
                                other if p == i else i, mstate[p], END_NONE) or full
            if full:
                return STATUS_LOG_FULL
        if executed >= max_events:
            return STATUS_BUDGET



# Gravity is a compile-time constant of the loop: one compiled loop with it and one without, and
# the second has no parabolas, motion states or resting rules in it (LLVM drops them), measured
# 8-15 % more events/s for the elastic gas than with a run-time switch. The other effects are
# run-time switches, so every scene uses one of these two compiled loops.
@njit
def run_loop_gravity(flight, dyn, walls, space, grid, sched, out, pair_table, fsc, isc, counts,
                     max_events, rec, flags):
    """:func:`_run_loop` with gravity (``flags[FL_GRAVITY]`` set)."""
    return _run_loop(flight, dyn, walls, space, grid, sched, out, pair_table, fsc, isc, counts,
                     max_events, rec, flags, True)


@njit
def run_loop_free(flight, dyn, walls, space, grid, sched, out, pair_table, fsc, isc, counts,
                  max_events, rec, flags):
    """:func:`_run_loop` without gravity: straight flights, no motion states."""
    return _run_loop(flight, dyn, walls, space, grid, sched, out, pair_table, fsc, isc, counts,
                     max_events, rec, flags, False)


def run_loop(flight, dyn, walls, space, grid, sched, out, pair_table, fsc, isc, counts,
             max_events, rec, flags):
    """Run events until t_end, a full buffer, or ``max_events``; returns a ``STATUS_*`` code
    (the compiled loop for the scene's gravity switch, ``flags[FL_GRAVITY]``)."""
    loop = run_loop_gravity if flags[FL_GRAVITY] else run_loop_free
    return loop(flight, dyn, walls, space, grid, sched, out, pair_table, fsc, isc, counts,
                max_events, rec, flags)
