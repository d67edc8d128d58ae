"""Spheres that leave the system through an outlet or enter it from an inflow (layer 5;
docs/open-systems.md).

The particle table is fixed; ``Flight.present`` says who is in the system. A sphere whose
centre enters an outlet region (hsgran.outlets, predicted as an ``EV_EXIT`` event by
hsgran._predict) is removed at that instant (:func:`remove_sphere`): what it carried out is
booked, the spheres it held up are set free, and it leaves the cell grid and the calendar; its
row stays, at rest where it left, so that no prediction or frame ever moves it. An inflow's
batch (hsgran.inflow, placed by hsgran.engine between calls of the loop) puts spheres into
the system (:func:`enter_sphere`): into the grid and the calendar, with the spheres around
them predicted again.
"""

from __future__ import annotations

from hsgran._cluster import resolve_without
from hsgran._flight import halt
from hsgran._jit import njit
from hsgran._predict import cell_heads, reschedule_fn
from hsgran._settling import wake_sleepers
from hsgran._state import F_EXITED, FL_CLUSTERS, FL_ROTATION, S_V
from hsgran.events.calendar import calendar_update
from hsgran.events.grid import axis_coordinate, insert, remove, slot_of
from hsgran.events.kinds import EV_NONE
from hsgran.motion import NEVER
from hsgran.onplane import END_NONE, MS_FLIGHT


@njit(inline="always")
def absent(flight, i):
    """Whether sphere i is out of the system (only ever in an open one)."""
    return flight.present.shape[0] > 0 and flight.present[i] == 0


@njit
def sphere_energy(i, st, omg, inv_m, inv_i, gravity, rotation):
    """Mechanical energy sphere i carries [J]: ½ m v² + ½ I ω² − m g·x (the potential of
    hsgran.engine's energies, zero at the origin), from its stored state: what it takes out
    of the system when it leaves, or brings in when it enters."""
    m = 1.0 / inv_m[i]
    e = 0.0
    for k in range(3):
        e += 0.5 * m * st[i, S_V + k] ** 2 - m * gravity[k] * st[i, k]
        if rotation:
            e += 0.5 * omg[i, k] ** 2 / inv_i[i]
    return e


@njit
def remove_sphere(i, t, flight, dyn, walls, space, grid, sched, clus, isc, fsc, flags,
                  grav_on):
    """Sphere i leaves the system at time t [s] through an outlet.

    The caller has advanced its state to t (and logged it, with its velocity). Then: the
    energy it carries out is added to ``fsc[F_EXITED]``; it leaves the cell lists and stops
    where it is; with gravity the spheres asleep on it fall (hsgran._settling.wake_sleepers)
    and the spheres moving in contact with it (and, with clusters, those resting on it) are
    solved again without it (hsgran._cluster.resolve_without); its counter moves on (every
    pair event predicted with it is stale), and it leaves the calendar, marked absent.
    """
    rotation = flags[FL_ROTATION]
    st, acc, mstate = flight.st, flight.acc, flight.mstate
    omg, alpha = dyn.omg, dyn.alpha
    fsc[F_EXITED] += sphere_energy(i, st, omg, dyn.inv_m, dyn.inv_i, space.gravity, rotation)
    # out of the grid and at rest first: the spheres set free below are predicted without it
    cell = grid.cell
    remove(i, slot_of(cell[i, 0], cell[i, 1], cell[i, 2], grid.ncell), grid.head, grid.nxt,
           grid.prv)
    halt(i, st, omg, rotation)
    if grav_on:
        for k in range(3):
            acc[i, k] = 0.0
            if rotation:
                alpha[i, k] = 0.0
        # (the walks below find its neighbours from its cell, and the touching ones from its
        # position, which stays)
        wake_sleepers(i, t, flight, dyn, walls, space, grid, sched, isc, grav_on, rotation)
        resolve_without(i, t, flight, walls, space, grid, sched, clus, isc, flags[FL_CLUSTERS])
        mstate[i] = MS_FLIGHT
        flight.mplane[i] = -1
        flight.seg_end[i] = NEVER
        flight.seg_code[i] = END_NONE
    flight.counter[i] += 1
    flight.present[i] = 0
    sched.ev_t[i] = NEVER
    sched.ev_kind[i] = EV_NONE
    sched.ev_partner[i] = -1
    calendar_update(sched.cal, sched.ev_t, sched.ev_seq, i)


@njit
def enter_sphere(i, t, flight, dyn, walls, space, grid, sched, isc, grav_on, rotation, around):
    """Sphere i enters the system at time t [s], in flight: the caller has written its
    position, velocity and local time t into ``flight.st`` and its spin into ``dyn.omg``.
    It joins its cell and the calendar with its first event predicted, and every sphere in the
    cells around it is predicted again (their events were predicted without it; farther ones
    cross into these cells, and are predicted, before they can reach it). Its counter moves
    on, so no event predicted before it left is taken for a current one. ``around``: scratch
    room for the neighbours (int64, one entry per sphere)."""
    st, cell = flight.st, grid.cell
    for k in range(3):
        cell[i, k] = axis_coordinate(st[i, k], grid.origin[k], grid.csize[k], grid.ncell[k],
                                     space.periodic[k])
    insert(i, slot_of(cell[i, 0], cell[i, 1], cell[i, 2], grid.ncell), grid.head, grid.nxt,
           grid.prv)
    flight.present[i] = 1
    flight.counter[i] += 1
    dyn.zstreak[i] = 0
    dyn.t_last[i] = -NEVER  # no collision history (a recirculated sphere's is of its last stay)
    dyn.rapid[i] = 0
    if grav_on:
        for k in range(3):
            flight.acc[i, k] = space.gravity[k]
            if rotation:
                dyn.alpha[i, k] = 0.0
        flight.mstate[i] = MS_FLIGHT
        flight.mplane[i] = -1
        flight.seg_end[i] = NEVER
        flight.seg_code[i] = END_NONE
    reschedule_fn(i, t, flight, walls, space, grid, sched, isc, grav_on)
    # the neighbours, gathered first: a prediction overwrites grid.heads
    m = 0
    heads = cell_heads(i, grid, space)
    for h in range(heads):
        q = grid.heads[h]
        seen = False  # a grid of one or two cells on a periodic axis repeats its lists
        for e in range(h):
            seen = seen or grid.heads[e] == q
        while q >= 0 and not seen:
            around[m] = q
            m += 1
            q = grid.nxt[q]
    for k in range(m):
        q = around[k]
        if q != i:
            reschedule_fn(q, t, flight, walls, space, grid, sched, isc, grav_on)
