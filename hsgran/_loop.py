"""The compiled event loop (layer 5; used only by :mod:`hsgran.engine`): pop, re-check, dispatch.

One pending event per sphere (Smallenburg 2022; predicted by :mod:`hsgran._predict`), kept in an
event calendar (:mod:`hsgran.events.calendar`) together with one extra entry, the frame tick
(index N). Spheres are advanced only when they take part in an event (delayed states, DynamO);
frames evaluate every sphere's flight at the frame time without touching the stored states, so
the output interval never changes the trajectory.

Each turn of the loop (two of them, with gravity and without: :func:`_loop_of`):

1. predict the spheres the last event changed (at most two, queued in ``isc[I_PEND_*]``) and
   move their calendar entries;
2. pop the earliest entry; stop if it is later than the end time;
3. re-check: a pair event whose partner has had an event since it was predicted is stale, and
   only makes its owner re-predict;
4. dispatch to the handler of the event's kind (hsgran.events.kinds): :func:`_on_frame`,
   ``on_pair`` and ``on_wall`` (:func:`_pair_handler`, :func:`_wall_handler`), :func:`_on_state`,
   :func:`_on_cell`. A collision whose
   bodies no longer approach at the contact point (a grazing contact that round-off turned
   around) is a "miss": both re-predict. Every executed collision ends in
   :func:`_finish_collision` (counts, dissipated energy, collapse guard, event log).

The collision itself is the kernel of :mod:`hsgran.contact.model`, inlined with the scene's effect
flags; with gravity, the enduring-contact rules of :mod:`hsgran._settling` wrap it. The arrays
travel in the named groups of :mod:`hsgran._state`; the scalar state lives in ``fsc`` (floats)
and ``isc`` (ints) at the ``F_*``/``I_*`` indices, so a run can stop (buffer full, budget) and
continue.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._cluster import (
    CL_SOLVED,
    cluster_collision,
    cluster_resolve,
    hands_over_pair,
    hands_over_wall,
)
from hsgran._cylinder import enter_cylinder, set_cylinder_contact, track_before
from hsgran._exchange import absent, remove_sphere
from hsgran._flight import (
    MAX_ZERO_TIME_EVENTS,
    PLANE_TOUCHING_REL,
    START_GAP_REL,
    advance,
    approaching,
    ball,
    curved,
    enter_plane,
    leave_plane,
    min_image,
    moving,
    note_progress,
    pressed,
    set_ball_contact,
    set_wall_velocity,
    state_at,
    tc_row,
    wall_curvature,
    wall_gap,
)
from hsgran._jit import njit, prefetch
from hsgran._observe import (
    before_pair,
    before_wall,
    book_pair,
    book_wall,
    close_interval,
    observing,
)
from hsgran._predict import (
    near_wall,
    near_walls,
    predict,
    predict_fn,
    prefetch_cells,
    repredict_later,
)
from hsgran._riding import END_TAKEOFF, leave_ride, moving_gap
from hsgran._settling import (
    SETTLE_NONE,
    SETTLE_SLEEP,
    SETTLE_STOP,
    STAGE_HOP,
    collide_pair,
    collide_wall,
    lands_before_wall,
    note_rapid,
    settle,
)
from hsgran._state import (
    F_DISSIPATED,
    F_ENTERED,
    F_EXITED,
    F_FRAME_DT,
    F_LANDING_SPEED,
    F_T_CUR,
    F_T_END,
    F_TC_TIME,
    F_UNWRAPPED,
    FL_ADHESION,
    FL_COMPLIANCE,
    FL_FRICTION,
    FL_GRAVITY,
    FL_LOG,
    FL_PLASTICITY,
    FL_ROLLING,
    FL_ROTATION,
    FL_VISCOUS,
    I_COLLAPSED,
    I_FRAME_INDEX,
    I_N_EVENTS,
    I_N_FRAMES,
    I_N_LOG,
    I_PEND_A,
    I_PEND_B,
    I_PEND_LAYER,
    I_SEQ,
    I_VISITS,
    S_R,
    S_T,
    S_V,
)
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
    calendar_build,
    calendar_prefetch,
    calendar_runner_up,
    calendar_top,
    calendar_update,
    has_buckets,
)
from hsgran.events.grid import insert, remove, slot_of
from hsgran.events.kinds import (
    EV_CELL,
    EV_CLUSTER,
    EV_EXIT,
    EV_FRAME,
    EV_HOP,
    EV_LAND,
    EV_MISS,
    EV_PAIR,
    EV_STALE,
    EV_STATE,
    EV_TC,
    EV_WALL,
    EV_WEDGE,
)
from hsgran.events.kinds import EVENT_NAMES as EVENT_NAMES  # re-exported for hsgran.engine
from hsgran.facets import END_OFF
from hsgran.motion import NEVER
from hsgran.onplane import END_NONE, END_RESOLVE, MS_ABSENT, MS_ASLEEP, MS_FLIGHT, MS_REST

#: Event-log entries one event can write: a collision, and a landing or the wedge stops of
#: both spheres (or the two spheres of a mutual stop). The log buffer is flushed while it still
#: has room for that many, so no entry of an event is ever dropped (the buffer must hold at
#: least this many).
LOG_ENTRIES_PER_EVENT = 3

STATUS_DONE = 0  #: reached t_end
STATUS_FRAMES_FULL = 1  #: the frame buffer is full: flush and call again
STATUS_LOG_FULL = 2  #: the event-log buffer is full: flush and call again
STATUS_BUDGET = 3  #: executed the requested number of collisions or events (progress report)
STATUS_COLLAPSE = 4  #: a sphere had too many events without time advancing

# What a handler tells the loop (besides a STATUS_* code, which ends the call):
GO_ON = -1  #: the event is done; no collision was executed
EXECUTED = -2  #: a collision was executed (counts against the collision budget)

#: Two instants closer than ZERO_TIME_REL × max(1 s, t) are the same up to double round-off of
#: the clock (a frame due at t_end may round that far above it).
ZERO_TIME_REL = 4e-16


@njit(inline="always")
def _log(out, st, isc, t, jn, jt, en, kind, i, other, stage, regime):
    """Append one entry to the event log; True when the buffer can no longer take all the
    entries of one event (LOG_ENTRIES_PER_EVENT): flush it before the next event. Every entry
    holds sphere i's velocity as it stands after the event (``st``, advanced to t) [m/s].

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
    log_f[m, 4] = st[i, S_V]
    log_f[m, 5] = st[i, S_V + 1]
    log_f[m, 6] = st[i, S_V + 2]
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
    if grav_on:
        # spheres that start on a wall (touching it, not moving away faster than the
        # landing speed, pressed on by gravity) start in an on-wall state (a moving plane is
        # where it is at t = 0: s(0) = 0)
        for i in range(st.shape[0]):
            if absent(flight, i):
                continue
            n_near, first_part = near_walls(i, walls, grid)
            for k in range(n_near):
                w = near_wall(k, walls, grid, first_part)
                if ball(walls, w):
                    continue  # (no motion state on a fixed sphere)
                gap = wall_gap(i, w, st, walls)
                gn, vn = pressed(i, w, 0.0, st, walls, space.gravity)
                if (abs(gap) <= START_GAP_REL * st[i, S_R] and gn > 0.0
                        and vn <= fsc[F_LANDING_SPEED] and flight.mstate[i] == MS_FLIGHT):
                    enter_plane(i, w, 0.0, no_end, flight, dyn, walls, space.gravity,
                                 pair_table, fsc, friction, rolling, rotation)
    for i in range(st.shape[0]):
        if not absent(flight, i):  # (an inflow's spheres wait for it, out of the calendar)
            predict_fn(i, 0.0, flight, walls, space, grid, sched, isc, grav_on)
    calendar_build(sched.cal, sched.ev_t, sched.ev_seq, 0.0)

@njit(inline="always")
def _collapsed(isc, zstreak, i, j):
    """The collapse guard, the last line of defence against a zero-time loop: whether sphere i,
    or sphere j ≥ 0, has had more than MAX_ZERO_TIME_EVENTS events in succession without its
    clock advancing (inelastic collapse, or a rounding loop). If so, ``isc[I_COLLAPSED]`` names
    sphere i and the run stops with STATUS_COLLAPSE."""
    if zstreak[i] > MAX_ZERO_TIME_EVENTS or (j >= 0 and zstreak[j] > MAX_ZERO_TIME_EVENTS):
        isc[I_COLLAPSED] = i
        return True
    return False


@njit(inline="always")
def _prefetch_next(cal, ev_t, st, cell, n):
    """Ask for the records of the sphere that is likely to have the event after the one at the
    top of the calendar, so that they are in the cache when its turn comes (a hint: nothing
    changes if the guess is wrong)."""
    e = calendar_runner_up(cal)
    if e < 0 or e >= n:
        return -1
    prefetch(ev_t, e)
    prefetch(st, e)
    prefetch(cell, e)
    return e


@njit
def _absent_row(f, j, out, grav_on, rotation):
    """Frame f's row of sphere j, which is not in the system (it left, or has not entered
    yet): NaN position, velocity and spin, motion state MS_ABSENT (docs/open-systems.md)."""
    for k in range(3):
        out.fr_pos[f, j, k] = math.nan
        out.fr_vel[f, j, k] = math.nan
        if rotation:
            out.fr_omg[f, j, k] = math.nan
    out.fr_ms[f, j] = MS_ABSENT


@njit(inline="always")
def _on_frame(t, flight, dyn, walls, space, sched, out, fsc, isc, counts, flags, grav_on):
    """Frame tick at time t [s]: sample every sphere's flight at t into the frame buffer, leave
    the stored states alone, and schedule the next tick. ``fr_ms`` takes every sphere's
    motion state (``MS_*``, ``MS_ASLEEP`` for a sleeper; left at flight without gravity); with
    observables on, the frame closes their interval (hsgran._observe)."""
    st, acc, mstate, mplane = flight.st, flight.acc, flight.mstate, flight.mplane
    omg, alpha = dyn.omg, dyn.alpha
    fr_time, fr_pos, fr_vel, fr_omg, fr_ms = out.fr_time, out.fr_pos, out.fr_vel, out.fr_omg, \
        out.fr_ms
    rotation = flags[FL_ROTATION]
    n = st.shape[0]
    f = isc[I_N_FRAMES]
    fr_time[f] = t
    open_system = out.fr_pres.shape[0] > 0  # spheres may have left or not yet entered
    if open_system:
        out.fr_left[f] = fsc[F_EXITED]
        out.fr_in[f] = fsc[F_ENTERED]
    if out.fr_unwrap.shape[0] > 0:  # gravity along a periodic axis
        out.fr_unwrap[f] = fsc[F_UNWRAPPED]
    for j in range(n):
        if open_system:
            out.fr_pres[f, j] = flight.present[j]
            if flight.present[j] == 0:
                _absent_row(f, j, out, grav_on, rotation)
                continue
        x, y, z, u, v, w = state_at(st, acc, j, t, grav_on)
        fr_pos[f, j, 0] = x
        fr_pos[f, j, 1] = y
        fr_pos[f, j, 2] = z
        fr_vel[f, j, 0] = u
        fr_vel[f, j, 1] = v
        fr_vel[f, j, 2] = w
        if grav_on:
            fr_ms[f, j] = MS_ASLEEP if mstate[j] == MS_REST and mplane[j] <= -2 else mstate[j]
        if rotation:
            dt = t - st[j, S_T] if grav_on else 0.0
            fr_omg[f, j, 0] = omg[j, 0] + alpha[j, 0] * dt if grav_on else omg[j, 0]
            fr_omg[f, j, 1] = omg[j, 1] + alpha[j, 1] * dt if grav_on else omg[j, 1]
            fr_omg[f, j, 2] = omg[j, 2] + alpha[j, 2] * dt if grav_on else omg[j, 2]
    if observing(dyn):
        close_interval(f, t, flight, dyn, walls, space, out, grav_on)
    isc[I_N_FRAMES] = f + 1
    isc[I_FRAME_INDEX] += 1
    sched.ev_t[n] = isc[I_FRAME_INDEX] * fsc[F_FRAME_DT]
    sched.ev_seq[n] = isc[I_SEQ]
    isc[I_SEQ] += 1
    calendar_update(sched.cal, sched.ev_t, sched.ev_seq, n)
    counts[EV_FRAME] += 1
    if f + 1 == fr_time.shape[0]:
        return STATUS_FRAMES_FULL
    return GO_ON


@njit(inline="always")
def _finish_collision(kind, i, other, t, tc_on, landed, wedged_a, wedged_b, st, mstate,
                      zstreak, out, fsc, isc, counts, rec, log_on):
    """Book an executed collision of sphere i with ``other`` (a sphere, or −1 − w for plane w):
    counts, the energy the collision model took, the collapse guard, and the event log (the
    collision, a landing after it, the spheres it stopped in a wedge). Returns EXECUTED or the
    STATUS_* code that ends the call."""
    counts[kind] += 1
    if tc_on:
        counts[EV_TC] += 1
    isc[I_N_EVENTS] += 1
    fsc[F_DISSIPATED] += rec[REC_ENERGY_LOST]
    if _collapsed(isc, zstreak, i, other):
        return STATUS_COLLAPSE
    for p in (wedged_a, wedged_b):
        if p >= 0:
            counts[EV_WEDGE] += 1
    if log_on:
        # every entry of the event is written (_log keeps room for them)
        full = _log(out, st, isc, t, rec[REC_J_N], rec[REC_J_T], rec[REC_E_N], kind, i, other,
                    int(rec[REC_STAGE]), int(rec[REC_REGIME]))
        if landed:
            # the rebound was too slow: the sphere stays on the plane from now on
            full = _log(out, st, isc, t, 0.0, 0.0, math.nan, EV_LAND, i, other, mstate[i],
                        END_NONE) or full
        for p in (wedged_a, wedged_b):
            if p >= 0:
                full = _log(out, st, isc, t, 0.0, 0.0, math.nan, EV_WEDGE, p,
                            other if p == i else i, mstate[p], END_NONE) or full
        if full:
            return STATUS_LOG_FULL
    return EXECUTED


def _pair_handler(grav_on):
    """The pair-collision handler of the loop with gravity or without (``grav_on``, a constant
    of the closure: numba drops the other branch of every ``if grav_on`` before it inlines
    anything, so neither loop compiles the other's collision)."""

    @njit(inline="always")
    def on_pair(i, j, t, flight, dyn, walls, space, grid, sched, clus, out, pair_table, fsc, isc,
                counts, rec, flags):
        """Collision of spheres i and j at time t [s] (their pair event is not stale)."""
        friction, rolling = flags[FL_FRICTION], flags[FL_ROLLING]
        rotation, log_on = flags[FL_ROTATION], flags[FL_LOG]
        st, counter, acc, mstate = flight.st, flight.counter, flight.acc, flight.mstate
        omg, zstreak, alpha, t_last, rapid = dyn.omg, dyn.zstreak, dyn.alpha, dyn.t_last, dyn.rapid
        box_len, periodic = space.box_len, space.periodic
        note_progress(i, t, st, zstreak)
        note_progress(j, t, st, zstreak)
        advance(st, acc, omg, alpha, i, t, grav_on, rotation)
        advance(st, acc, omg, alpha, j, t, grav_on, rotation)
        dx = min_image(st[i, 0] - st[j, 0], 0, box_len, periodic)
        dy = min_image(st[i, 1] - st[j, 1], 1, box_len, periodic)
        dz = min_image(st[i, 2] - st[j, 2], 2, box_len, periodic)
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
        nx, ny, nz = dx / dist, dy / dist, dz / dist
        obs_on = observing(dyn)
        if obs_on:
            p_i, p_j, w_i = before_pair(i, j, t, flight, dyn, walls, space, grav_on)
        else:
            p_i = p_j = (0.0, 0.0, 0.0)
            w_i = 0.5
        if grav_on and hands_over_pair(i, j, flight, dyn, walls, space, pair_table, fsc,
                                       flags) and cluster_collision(
                i, j, -1, t, flight, dyn, walls, space, grid, sched, clus, isc, pair_table, fsc,
                rec, flags) == CL_SOLVED:
            # touching other bodies: solved with them (it re-predicted them all)
            counts[EV_CLUSTER] += 1
            return _finish_collision(EV_PAIR, i, j, t, False, False, -1, -1, st, mstate, zstreak,
                                     out, fsc, isc, counts, rec, log_on)
        if grav_on:
            # a slow meeting that ends in rest instead of a collision (see _settling.settle)
            rule, who, what = settle(i, j, nx, ny, nz, t, flight, dyn, walls, grid, space.gravity,
                                     pair_table, fsc, friction, rolling, rotation)
            if rule != SETTLE_NONE:
                # re-predictions in a fixed order (it sets the sequence numbers that break ties
                # between simultaneous events): a sleeper first, else i
                first = who if rule == SETTLE_SLEEP else i
                repredict_later(isc, first)
                repredict_later(isc, j if first == i else i)
                counts[EV_LAND] += 1
                if rule != SETTLE_SLEEP and _collapsed(isc, zstreak, i, j):
                    return STATUS_COLLAPSE
                if log_on:
                    full = _log(out, st, isc, t, 0.0, 0.0, math.nan, EV_LAND, who, what,
                                mstate[who], END_NONE)
                    if rule == SETTLE_STOP:  # both spheres stopped: an entry for each
                        full = _log(out, st, isc, t, 0.0, 0.0, math.nan, EV_LAND, what, who,
                                    mstate[what], END_NONE) or full
                    if full:
                        return STATUS_LOG_FULL
                return GO_ON
            hit, tc_on, wedged_a, wedged_b = collide_pair(i, j, t, nx, ny, nz, dx, dy, dz, flight,
                                                          dyn, walls, space, grid, sched, isc,
                                                          pair_table, fsc, rec, counts, flags)
        else:
            wedged_a = wedged_b = -1
            ri = st[i, S_R]
            rj = st[j, S_R]
            row, tc_on = tc_row(pair_table[dyn.mat[i], dyn.mat[j]], t, t_last[i], t_last[j], fsc,
                                dyn.row_tc)
            hit = False
            if approaching(i, j, dx, dy, dz, ri + rj, st):
                hit = resolve(st[i, S_V:S_V + 3], omg[i] if rotation else omg[0],
                              st[j, S_V:S_V + 3], omg[j] if rotation else omg[0], nx, ny, nz,
                              dyn.inv_m[i], dyn.inv_m[j], dyn.inv_i[i], dyn.inv_i[j], ri, rj,
                              1.0 / ri + 1.0 / rj, row, rec, flags[FL_PLASTICITY], friction,
                              rolling, flags[FL_ADHESION], rotation, False, flags[FL_COMPLIANCE],
                              flags[FL_VISCOUS])
        if not hit:
            # re-check failed: a grazing contact that round-off turned into "separating" (or into
            # an approach below rounding, which the prediction ignores as well). Nothing changed,
            # so no counter moves; both re-predict from the exact contact state, which no longer
            # approaches. A loop of such retries is caught by the collapse guard.
            repredict_later(isc, i)
            repredict_later(isc, j)
            counts[EV_MISS] += 1
            if _collapsed(isc, zstreak, i, j):
                return STATUS_COLLAPSE
            return GO_ON
        if obs_on:
            book_pair(i, j, p_i, p_j, w_i, dx, dy, dz, flight, dyn, grav_on)
        counter[i] += 1
        counter[j] += 1
        note_rapid(i, t, t_last, rapid, fsc[F_TC_TIME])
        note_rapid(j, t, t_last, rapid, fsc[F_TC_TIME])
        t_last[i] = t_last[j] = t
        repredict_later(isc, i)
        repredict_later(isc, j)
        return _finish_collision(EV_PAIR, i, j, t, tc_on, False, wedged_a, wedged_b, st, mstate,
                                 zstreak, out, fsc, isc, counts, rec, log_on)

    return on_pair


_on_pair_gravity = _pair_handler(True)
_on_pair_free = _pair_handler(False)


def _wall_handler(grav_on):
    """The wall-collision handler of the loop with gravity or without (see _pair_handler)."""

    @njit(inline="always")
    def on_wall(i, t, flight, dyn, walls, space, grid, sched, clus, out, pair_table, fsc, isc,
                counts, rec, flags, ev_partner):
        """Collision of sphere i with its event's plane at time t [s]."""
        rotation, log_on = flags[FL_ROTATION], flags[FL_LOG]
        st, counter, acc, mstate = flight.st, flight.counter, flight.acc, flight.mstate
        omg, zstreak, alpha, t_last = dyn.omg, dyn.zstreak, dyn.alpha, dyn.t_last
        w = np.int64(ev_partner[i])
        note_progress(i, t, st, zstreak)
        advance(st, acc, omg, alpha, i, t, grav_on, rotation)
        if moving(walls, w):
            gap, _ = moving_gap(st[i, 0], st[i, 1], st[i, 2], st[i, S_R], walls, w, t)
            if gap > PLANE_TOUCHING_REL * st[i, S_R]:
                # the search for the contact stopped short of it (hsgran.wallmotion
                # MAX_ADVANCE_STEPS): no contact yet, predicted again from here
                repredict_later(isc, i)
                counts[EV_MISS] += 1
                if _collapsed(isc, zstreak, i, -1):
                    return STATUS_COLLAPSE
                return GO_ON
            set_wall_velocity(walls, w, t)
        elif curved(walls, w):
            set_cylinder_contact(walls, w, st[i, 0], st[i, 1], st[i, 2])
        elif ball(walls, w):
            set_ball_contact(walls, w, st[i, 0], st[i, 1], st[i, 2])
        obs_on = observing(dyn)
        p_i = before_wall(i, t, flight, dyn, walls, space, grav_on) if obs_on else (0.0, 0.0, 0.0)
        if grav_on and hands_over_wall(i, w, t, flight, dyn, walls, space, pair_table, fsc,
                                       flags) \
                and cluster_collision(i, -1, w, t, flight, dyn, walls, space, grid, sched, clus,
                                      isc, pair_table, fsc, rec, flags) == CL_SOLVED:
            counts[EV_CLUSTER] += 1
            return _finish_collision(EV_WALL, i, -1 - w, t, False, False, -1, -1, st, mstate,
                                     zstreak, out, fsc, isc, counts, rec, log_on)
        if grav_on and lands_before_wall(i, w, t, flight, dyn, walls, grid, space.gravity,
                                         pair_table, fsc, flags):
            counter[i] += 1
            repredict_later(isc, i)
            counts[EV_LAND] += 1
            if _collapsed(isc, zstreak, i, -1):
                return STATUS_COLLAPSE
            if log_on and _log(out, st, isc, t, 0.0, 0.0, math.nan, EV_LAND, i, -1 - w, mstate[i],
                               END_NONE):
                return STATUS_LOG_FULL
            return GO_ON
        landed = wedged = False
        if grav_on:
            hit, tc_on, landed, wedged = collide_wall(i, w, t, flight, dyn, walls, space.gravity,
                                                      pair_table, fsc, rec, flags)
        else:
            ri = st[i, S_R]
            planes_n = walls.planes_n
            row, tc_on = tc_row(pair_table[dyn.mat[i], walls.planes_mat[w]], t, t_last[i], -NEVER,
                                fsc, dyn.row_tc)
            hit = resolve(st[i, S_V:S_V + 3], omg[i] if rotation else omg[0], walls.planes_vel[w],
                          walls.planes_omg[w], planes_n[w, 0], planes_n[w, 1], planes_n[w, 2],
                          dyn.inv_m[i], 0.0, dyn.inv_i[i], 0.0, ri, 0.0,
                          wall_curvature(walls, w, ri), row, rec,
                          flags[FL_PLASTICITY], flags[FL_FRICTION], flags[FL_ROLLING],
                          flags[FL_ADHESION], rotation, False, flags[FL_COMPLIANCE],
                          flags[FL_VISCOUS])
        if not hit:
            # re-check failed (see on_pair)
            repredict_later(isc, i)
            counts[EV_MISS] += 1
            if _collapsed(isc, zstreak, i, -1):
                return STATUS_COLLAPSE
            return GO_ON
        if obs_on:
            book_wall(i, w, p_i, flight, dyn, walls, grav_on)
        if rec[REC_STAGE] == STAGE_HOP:
            counts[EV_HOP] += 1  # a sphere on a wall sent off another (_settling._wall_hop)
        if landed:
            counts[EV_LAND] += 1
        counter[i] += 1
        note_rapid(i, t, t_last, dyn.rapid, fsc[F_TC_TIME])
        t_last[i] = t
        repredict_later(isc, i)
        return _finish_collision(EV_WALL, i, -1 - w, t, tc_on, landed, i if wedged else -1, -1,
                                 st, mstate, zstreak, out, fsc, isc, counts, rec, log_on)

    return on_wall


_on_wall_gravity = _wall_handler(True)
_on_wall_free = _wall_handler(False)


@njit(inline="always")
def _on_state(i, t, flight, dyn, walls, space, grid, sched, clus, out, pair_table, fsc, isc,
              counts, rec, flags, grav_on, ev_partner):
    """Sphere i's on-plane motion segment ends at time t [s]: slide → roll, roll → rest, spin
    reversal; the next segment starts (MODEL §5.3)."""
    friction, rolling, rotation = flags[FL_FRICTION], flags[FL_ROLLING], flags[FL_ROTATION]
    st, mstate, mplane, zstreak = flight.st, flight.mstate, flight.mplane, dyn.zstreak
    note_progress(i, t, st, zstreak)
    ended = ev_partner[i]
    if ended == END_RESOLVE:
        # a segment of constrained motion ends, or a support moved: solve the cluster again
        fsc[F_DISSIPATED] += cluster_resolve(i, t, flight, dyn, walls, space, grid, sched, clus,
                                             isc, pair_table, fsc, rec, flags)
        counts[EV_CLUSTER] += 1
        counts[EV_STATE] += 1
        if _collapsed(isc, zstreak, i, -1):
            return STATUS_COLLAPSE
        if flags[FL_LOG] and _log(out, st, isc, t, 0.0, 0.0, math.nan, EV_STATE, i, -1, mstate[i],
                                  ended):
            return STATUS_LOG_FULL
        return GO_ON
    w = np.int64(mplane[i])
    if ended == END_TAKEOFF or ended == END_OFF:
        # the plane pulls away faster than gravity, or a piston starts or stops
        # (hsgran._riding), or the sphere's foot leaves its face (hsgran.facets): the sphere
        # flies from there (at the plane's speed)
        advance(st, flight.acc, dyn.omg, dyn.alpha, i, t, grav_on, rotation)
        if ended == END_TAKEOFF:
            leave_ride(i, w, t, st, walls)
        leave_plane(i, flight, dyn, space.gravity, rotation)
    elif curved(walls, w):
        # a segment on a cylinder ends (hsgran._cylinder): on the surface again, with the
        # speed along the track its accelerations gave; flies if no longer pressed on
        prev = track_before(i, t, flight.acc, st, walls, w)
        advance(st, flight.acc, dyn.omg, dyn.alpha, i, t, grav_on, rotation)
        if not enter_cylinder(i, w, t, np.int64(ended), prev, flight, dyn, walls, space.gravity,
                              pair_table, fsc, friction, rolling, rotation):
            leave_plane(i, flight, dyn, space.gravity, rotation)
    else:
        advance(st, flight.acc, dyn.omg, dyn.alpha, i, t, grav_on, rotation)
        enter_plane(i, w, t, np.int64(ended), flight, dyn, walls, space.gravity, pair_table,
                    fsc, friction, rolling, rotation)
    flight.counter[i] += 1
    repredict_later(isc, i)
    counts[EV_STATE] += 1
    if _collapsed(isc, zstreak, i, -1):
        return STATUS_COLLAPSE
    if flags[FL_LOG] and _log(out, st, isc, t, 0.0, 0.0, math.nan, EV_STATE, i, -1 - w,
                              mstate[i], ended):
        return STATUS_LOG_FULL
    return GO_ON


@njit
def _on_exit(i, t, flight, dyn, walls, space, grid, sched, clus, out, fsc, isc, counts, flags,
             grav_on, ev_partner):
    """Sphere i's centre enters outlet ``ev_partner[i]`` at time t [s]: it leaves the system
    (hsgran._exchange; logged with the velocity it leaves with). Not inlined: it is rare."""
    st = flight.st
    note_progress(i, t, st, dyn.zstreak)
    advance(st, flight.acc, dyn.omg, dyn.alpha, i, t, grav_on, flags[FL_ROTATION])
    full = flags[FL_LOG] and _log(out, st, isc, t, 0.0, 0.0, math.nan, EV_EXIT, i,
                                  ev_partner[i], flight.mstate[i] if grav_on else MS_FLIGHT,
                                  END_NONE)
    remove_sphere(i, t, flight, dyn, walls, space, grid, sched, clus, isc, fsc, flags, grav_on)
    counts[EV_EXIT] += 1
    return STATUS_LOG_FULL if full else GO_ON


@njit(inline="always")
def _on_cell(i, flight, dyn, space, grid, fsc, isc, counts, ev_partner, large, grav_on):
    """Sphere i leaves its cell: move it to the neighbouring one (on a periodic axis wrap its
    stored state by one box length, and keep the potential energy that hides in
    ``F_UNWRAPPED``) and re-predict it, looking at the new layer of neighbouring cells only."""
    st, cell, ncell = flight.st, grid.cell, grid.ncell
    code = ev_partner[i]
    k = code // 2
    step = 1 if code % 2 == 1 else -1
    old = slot_of(cell[i, 0], cell[i, 1], cell[i, 2], ncell)
    c = cell[i, k] + step
    if space.periodic[k]:
        shift = 0.0
        if c >= ncell[k]:
            c = 0
            shift = -space.box_len[k]
        elif c < 0:
            c = ncell[k] - 1
            shift = space.box_len[k]
        if shift != 0.0:
            st[i, k] += shift
            # −m g·x of the stored position changes by −m g_k shift; the motion's does not
            if grav_on and space.gravity[k] != 0.0 and dyn.inv_m[i] > 0.0:
                fsc[F_UNWRAPPED] += space.gravity[k] * shift / dyn.inv_m[i]
    cell[i, k] = c
    remove(i, old, grid.head, grid.nxt, grid.prv)
    insert(i, slot_of(cell[i, 0], cell[i, 1], cell[i, 2], ncell), grid.head, grid.nxt, grid.prv)
    if large:
        prefetch_cells(i, cell, ncell, grid.head)
    repredict_later(isc, i)  # into I_PEND_A: the top of the loop emptied both slots
    isc[I_PEND_LAYER] = code  # look at the new layer of neighbours only
    counts[EV_CELL] += 1
    return GO_ON


def _loop_of(grav_on):
    """The event loop with gravity or without (``grav_on``, a constant of the closure). Gravity is
    a compile-time constant: the loop without it has no parabolas, motion states, settling rules
    or collisions under gravity in it, and the loop with it has not the plain collisions
    (numba prunes ``if grav_on`` before it inlines; docs/performance.md). The other effects are
    run-time switches, so every scene uses one of these two compiled loops."""

    @njit
    def run_loop(flight, dyn, walls, space, grid, sched, clus, out, pair_table, fsc, isc, counts,
                 max_collisions, max_events, max_visits, rec, flags):
        """Run events until t_end, a full buffer, ``max_collisions`` collisions, ``max_events``
        events of any kind or ``max_visits`` contact visits of the cluster solves (this call);
        returns a ``STATUS_*`` code.

        The groups are those of :mod:`hsgran._state`.
        """
        st, counter, cell = flight.st, flight.counter, grid.cell
        ev_t, ev_seq, ev_kind, ev_partner, ev_pcount, cal = sched
        n = st.shape[0]
        t_end = fsc[F_T_END]
        executed = 0
        popped = 0
        visits_end = isc[I_VISITS] + max_visits
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
                    predict(p, fsc[F_T_CUR], flight, walls, space, grid, sched, isc, grav_on, layer)
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
                r = _on_frame(t, flight, dyn, walls, space, sched, out, fsc, isc, counts, flags,
                              grav_on)
            else:
                i = e
                kind = ev_kind[i]
                if kind == EV_PAIR:
                    j = np.int64(ev_partner[i])  # one integer type for sphere indices: one compile
                    if large:
                        prefetch_cells(i, cell, grid.ncell, grid.head)
                    if counter[j] != ev_pcount[i]:
                        # stale: the partner moved on since this was predicted; re-predict the owner
                        repredict_later(isc, i)
                        counts[EV_STALE] += 1
                        r = GO_ON
                    else:
                        if large:
                            prefetch_cells(j, cell, grid.ncell, grid.head)
                        if grav_on:
                            r = _on_pair_gravity(i, j, t, flight, dyn, walls, space, grid, sched,
                                                 clus, out, pair_table, fsc, isc, counts, rec,
                                                 flags)
                        else:
                            r = _on_pair_free(i, j, t, flight, dyn, walls, space, grid, sched,
                                              clus, out, pair_table, fsc, isc, counts, rec, flags)
                elif kind == EV_WALL:
                    if grav_on:
                        r = _on_wall_gravity(i, t, flight, dyn, walls, space, grid, sched, clus,
                                             out, pair_table, fsc, isc, counts, rec, flags,
                                             ev_partner)
                    else:
                        r = _on_wall_free(i, t, flight, dyn, walls, space, grid, sched, clus, out,
                                          pair_table, fsc, isc, counts, rec, flags, ev_partner)
                elif grav_on and kind == EV_STATE:
                    r = _on_state(i, t, flight, dyn, walls, space, grid, sched, clus, out,
                                  pair_table, fsc, isc, counts, rec, flags, grav_on, ev_partner)
                elif kind == EV_CELL:  # (EV_NONE has time NEVER and is never popped)
                    r = _on_cell(i, flight, dyn, space, grid, fsc, isc, counts, ev_partner,
                                 large, grav_on)
                else:  # EV_EXIT
                    r = _on_exit(i, t, flight, dyn, walls, space, grid, sched, clus, out, fsc,
                                 isc, counts, flags, grav_on, ev_partner)
            if r == EXECUTED:
                executed += 1
                if executed >= max_collisions:
                    return STATUS_BUDGET
            elif r != GO_ON:
                return r
            popped += 1
            # (cluster solves come only with gravity: the free loop has no such compare)
            if popped >= max_events or (grav_on and isc[I_VISITS] >= visits_end):
                return STATUS_BUDGET

    return run_loop


run_loop_gravity = _loop_of(True)
run_loop_free = _loop_of(False)


def run_loop(flight, dyn, walls, space, grid, sched, clus, out, pair_table, fsc, isc, counts,
             max_collisions, max_events, max_visits, rec, flags):
    """Run events until t_end, a full buffer, ``max_collisions`` collisions, ``max_events``
    events of any kind or ``max_visits`` contact visits of the cluster solves; returns a
    ``STATUS_*`` code (the compiled loop for the scene's gravity switch,
    ``flags[FL_GRAVITY]``)."""
    loop = run_loop_gravity if flags[FL_GRAVITY] else run_loop_free
    return loop(flight, dyn, walls, space, grid, sched, clus, out, pair_table, fsc, isc, counts,
                max_collisions, max_events, max_visits, rec, flags)
