"""Prediction of a sphere's next event (layer 5; the compiled event loop's hot path, used by
:mod:`hsgran._settling` and :mod:`hsgran._loop`).

One pending event per sphere (Smallenburg 2022): the earliest of its cell exit, its contact with
a plane, its contact with a neighbour in the cells around it, and (with gravity) the end of its
on-plane motion segment. A sphere's event stores its partner's event counter, so that a popped
pair event whose partner has moved on since is known to be stale (lazy invalidation).
"""

from __future__ import annotations

from hsgran._cylinder import across_axis, axis_offset
from hsgran._flight import (
    PLANE_TOUCHING_REL,
    min_image,
    moving,
    state_at,
    wall_gap,
)
from hsgran._jit import njit, prefetch
from hsgran._riding import moving_gap
from hsgran._state import I_PEND_A, I_PEND_B, I_SEQ, S_R, S_T
from hsgran.events.calendar import calendar_update, has_buckets
from hsgran.events.grid import slot_of
from hsgran.events.kinds import EV_CELL, EV_EXIT, EV_NONE, EV_PAIR, EV_STATE, EV_WALL
from hsgran.facets import (
    FACE_BEHIND_REL,
    ball_contact_time,
    edge_contact_time,
    face_coordinates,
    face_leave_time,
    on_face,
)
from hsgran.motion import (
    NEVER,
    cylinder_contact_time,
    face_exit_time,
    pair_contact_accelerated,
    pair_contact_before,
    plane_contact_time,
    plane_gap,
)
from hsgran.onplane import MS_FLIGHT, MS_REST, MS_SUPPORTED
from hsgran.outlets import outlet_entry_time
from hsgran.wallmotion import moving_plane_contact_time
from hsgran.wallspec import (
    BL_RADIUS,
    CY_AXIS,
    CY_FINITE,
    CY_HALF,
    CY_RADIUS,
    CY_SIDE,
    WK_BALL,
    WK_FACE,
    WK_PLANE,
)

#: Cells a crossed axis needs for the crossing to look only at the new layer of neighbouring
#: cells (see predict): with 1 or 2 the lists of that axis are not neighbour layers.
LAYER_MIN_CELLS = 3


@njit(inline="always")
def prefetch_cells(i, cell, ncell, head):
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
def axis_cells(c, n, length, periodic, k, ac, ah):
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
def held_pair(i, j, flight, space):
    """Whether the pair of spheres i and j is held apart by a step of constrained motion
    (hsgran._cluster): one of them in constrained motion, the other in the same step (the same
    start and end) or at rest since before it began, and their gap at the step's start within
    the step's reach (``seg_reach``). The step's solve kept that gap from closing over the
    whole step, so no contact of theirs falls within it."""
    mstate, st, seg_end, reach = flight.mstate, flight.st, flight.seg_end, flight.seg_reach
    if mstate[i] == MS_SUPPORTED:
        s, o = i, j
    elif mstate[j] == MS_SUPPORTED:
        s, o = j, i
    else:
        return False
    held = reach[s]
    if mstate[o] == MS_SUPPORTED:
        if st[o, S_T] != st[s, S_T] or seg_end[o] != seg_end[s]:
            return False
        held = min(held, reach[o])
    elif mstate[o] != MS_REST or st[o, S_T] > st[s, S_T]:
        return False
    dx = min_image(st[s, 0] - st[o, 0], 0, space.box_len, space.periodic)
    dy = min_image(st[s, 1] - st[o, 1], 1, space.box_len, space.periodic)
    dz = min_image(st[s, 2] - st[o, 2], 2, space.box_len, space.periodic)
    return (dx * dx + dy * dy + dz * dz) ** 0.5 - st[s, S_R] - st[o, S_R] <= held


@njit(inline="always")
def held_wall(i, w, flight, walls):
    """Whether sphere i, in constrained motion, is held off wall w by its step: a fixed wall
    whose gap at the step's start is within the step's reach (see :func:`held_pair`)."""
    return (flight.mstate[i] == MS_SUPPORTED and not moving(walls, w)
            and wall_gap(i, w, flight.st, walls) <= flight.seg_reach[i])


@njit(inline="always")
def cell_heads(s, grid, space):
    """Write the list heads of the cells around sphere s's (those that are not empty) into
    ``grid.heads`` and return how many (for cold callers that walk its neighbours; positions
    are compared by nearest image, so the shifts are not needed)."""
    ncell, cell, head, ac, ah, heads = grid.ncell, grid.cell, grid.head, grid.ac, grid.ah, \
        grid.heads
    mx = axis_cells(cell[s, 0], ncell[0], space.box_len[0], space.periodic[0], 0, ac, ah)
    my = axis_cells(cell[s, 1], ncell[1], space.box_len[1], space.periodic[1], 1, ac, ah)
    mz = axis_cells(cell[s, 2], ncell[2], space.box_len[2], space.periodic[2], 2, ac, ah)
    m = 0
    for x in range(mx):
        for y in range(my):
            for z in range(mz):
                q = head[(ac[0, x] * ncell[1] + ac[1, y]) * ncell[2] + ac[2, z]]
                if q >= 0:
                    heads[m] = q
                    m += 1
    return m


@njit(inline="always")
def near_walls(i, walls, grid):
    """(how many walls sphere i looks at, where its cell's parts start in ``part_items``):
    the walls every prediction looks at (the first ``Walls.n_global``), then the parts of finite
    walls listed in its cell (events.grid.part_lists); walk them with :func:`near_wall`."""
    n_global = walls.n_global[0]
    if grid.part_items.shape[0] == 0:
        return n_global, 0
    s = slot_of(grid.cell[i, 0], grid.cell[i, 1], grid.cell[i, 2], grid.ncell)
    a = grid.part_start[s]
    return n_global + grid.part_start[s + 1] - a, a


@njit(inline="always")
def near_wall(k, walls, grid, a):
    """The k-th wall of :func:`near_walls` (``a``: its second value)."""
    n_global = walls.n_global[0]
    if k < n_global:
        return k
    return grid.part_items[a + k - n_global]


@njit
def other_wall_time(x, y, z, u, v, w_, gx, gy, gz, r, walls, w, t_now, horizon):
    """Delay [s] until a sphere of radius r [m] at (x, y, z) [m] with velocity (u, v, w_) [m/s]
    and acceleration (gx, gy, gz) [m/s²] at t_now [s] meets wall w, a moving plane, a
    cylinder, an edge or a fixed sphere; ``inf`` if not within ``horizon`` [s]."""
    if moving(walls, w):
        n = walls.planes_n
        gap, cn = moving_gap(x, y, z, r, walls, w, t_now)
        return moving_plane_contact_time(
            gap, u * n[w, 0] + v * n[w, 1] + w_ * n[w, 2], gx * n[w, 0] + gy * n[w, 1]
            + gz * n[w, 2], walls.planes_mot, w, cn, t_now, r, horizon)
    v_sum = abs(u) + abs(v) + abs(w_)
    x_sum = abs(x) + abs(y) + abs(z)
    p = walls.planes_p
    if walls.planes_kind[w] == WK_BALL:
        # a fixed sphere or a corner (hsgran.facets)
        return ball_contact_time(x - p[w, 0], y - p[w, 1], z - p[w, 2], u, v, w_, gx, gy, gz,
                                 r + walls.planes_geo[w, BL_RADIUS], horizon, v_sum, x_sum)
    cyl = walls.planes_cyl
    side = cyl[w, CY_SIDE]
    qx, qy, qz = axis_offset(x, y, z, walls, w)
    ux, uy, uz = across_axis(u, v, w_, walls, w)
    ax, ay, az = across_axis(gx, gy, gz, walls, w)
    if cyl[w, CY_FINITE] != 0.0:
        # an edge of a finite wall: its contacts count between its ends (hsgran.facets)
        a0, a1, a2 = cyl[w, CY_AXIS], cyl[w, CY_AXIS + 1], cyl[w, CY_AXIS + 2]
        return edge_contact_time(qx, qy, qz, ux, uy, uz, ax, ay, az,
                                 (x - p[w, 0]) * a0 + (y - p[w, 1]) * a1 + (z - p[w, 2]) * a2,
                                 u * a0 + v * a1 + w_ * a2, gx * a0 + gy * a1 + gz * a2, r,
                                 cyl[w, CY_HALF], horizon, v_sum, x_sum)
    return cylinder_contact_time(qx, qy, qz, ux, uy, uz, ax, ay, az,
                                 cyl[w, CY_RADIUS] - side * r, side, horizon, v_sum, x_sum)


# long: the hot path of every scene, inlined into the loop at one call site; its steps (cell
# exit, planes, the neighbours' lists) share the sphere's state at t_now and the best event so
# far, which split functions would pass back and forth as tuples
@njit(inline="always")
def predict(i, t_now, flight, walls, space, grid, sched, isc, grav_on, layer):
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
    xi, yi, zi, ui, vi, wi = state_at(st, acc, i, t_now, grav_on)
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
    supported = grav_on and mstate[i] == MS_SUPPORTED
    for k in range(3):
        lo = origin[k] + cell[i, k] * csize[k]
        tau, side = face_exit_time(xs[k], us[k], gi[k], lo, lo + csize[k])
        if tau < best:
            best = tau
            kind = EV_CELL
            partner = 2 * k + (1 if side > 0 else 0)
    n_near, first_part = near_walls(i, walls, grid)
    for k in range(n_near):
        w = near_wall(k, walls, grid, first_part)
        if w == on_plane:
            continue
        nx = planes_n[w, 0]
        ny = planes_n[w, 1]
        nz = planes_n[w, 2]
        wkind = walls.planes_kind[w]
        if supported and held_wall(i, w, flight, walls):
            continue  # held off the wall by its step: no contact within it
        if wkind != WK_PLANE and wkind != WK_FACE:
            tau = other_wall_time(xi, yi, zi, ui, vi, wi, gi[0], gi[1], gi[2], ri, walls, w,
                                  t_now, best)
            if tau < best:
                best = tau
                kind = EV_WALL
                partner = w
            continue
        gap = plane_gap(xi, yi, zi, ri, planes_p, planes_n, w)
        if wkind == WK_FACE and gap < -FACE_BEHIND_REL * ri:
            continue  # behind a face (hsgran.facets)
        if gap <= PLANE_TOUCHING_REL * ri:
            # touching within rounding: a contact now if approaching beyond rounding or
            # pressed (a gap of 1e-19 m closing at 1e-5 m/s would otherwise come 1e-14 s later,
            # after every zero-time pair event of a sphere wedged between neighbours on this
            # plane)
            gap = 0.0
        gn = gi[0] * nx + gi[1] * ny + gi[2] * nz
        vn = ui * nx + vi * ny + wi * nz
        tau = plane_contact_time(gap, vn, gn, abs(ui) + abs(vi) + abs(wi))
        if wkind == WK_FACE and tau < best:
            # a face's plane met off the face is no contact (hsgran.facets)
            fu, fv = face_coordinates(xi + tau * (ui + 0.5 * gi[0] * tau),
                                      yi + tau * (vi + 0.5 * gi[1] * tau),
                                      zi + tau * (wi + 0.5 * gi[2] * tau), planes_p,
                                      walls.planes_geo, w)
            if not on_face(fu, fv, planes_p, walls.planes_geo, walls.face_lines, w):
                tau = NEVER
            elif gap == 0.0 and face_leave_time(xi, yi, zi, ui, vi, wi, gi[0], gi[1], gi[2],
                                                planes_p, walls.planes_geo, walls.face_lines,
                                                w) == 0.0:
                # touching it at its outline and leaving it (the sphere's foot left it now,
                # END_OFF): no contact, whether the plane's time came out 0 or a rounding
                # later; the next part takes the sphere
                tau = NEVER
        if tau < best:
            best = tau
            kind = EV_WALL
            partner = w
    outlets = walls.outlets
    for o in range(outlets.shape[0]):
        tau = outlet_entry_time(xi, yi, zi, ui, vi, wi, gi[0], gi[1], gi[2], outlets, o)
        if tau < best:
            best = tau
            kind = EV_EXIT
            partner = o
    # The neighbouring lists and, on periodic axes, which image of their spheres can touch
    # sphere i: the one in the cell next to i's (the nearest image at prediction time is not
    # always the one that touches later). First gather the heads of the lists, then walk them:
    # the head loads do not depend on each other, so their cache misses overlap where the grid
    # does not fit the cache (docs/performance.md).
    # i's share of the rounding scales of an approach (motion.approach_noise)
    vs_i = abs(ui) + abs(vi) + abs(wi)
    xs_i = abs(xi) + abs(yi) + abs(zi)
    heads, shifts, ac, ah = grid.heads, grid.shifts, grid.ac, grid.ah
    mx = axis_cells(cell[i, 0], ncell[0], box_len[0], periodic[0], 0, ac, ah)
    my = axis_cells(cell[i, 1], ncell[1], box_len[1], periodic[1], 1, ac, ah)
    mz = axis_cells(cell[i, 2], ncell[2], box_len[2], periodic[2], 2, ac, ah)
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
                xj, yj, zj, uj, vj, wj = state_at(st, acc, j, t_now, grav_on)
                horizon = min(best, pbest) if grav_on else pbest
                if grav_on and (supported or mstate[j] == MS_SUPPORTED) and held_pair(
                        i, j, flight, space):
                    tau = NEVER
                elif grav_on and (acc[j, 0] != gi[0] or acc[j, 1] != gi[1] or acc[j, 2] != gi[2]):
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
def predict_fn(i, t_now, flight, walls, space, grid, sched, isc, grav_on):
    """:func:`predict` as a compiled function (for cold callers; all neighbours)."""
    predict(i, t_now, flight, walls, space, grid, sched, isc, grav_on, -1)


@njit
def reschedule_fn(i, t_now, flight, walls, space, grid, sched, isc, grav_on):
    """Predict sphere i's next event (all neighbours) and move its calendar entry accordingly
    (for cold callers)."""
    predict_fn(i, t_now, flight, walls, space, grid, sched, isc, grav_on)
    calendar_update(sched.cal, sched.ev_t, sched.ev_seq, i)


@njit(inline="always")
def repredict_later(isc, p):
    """Queue sphere p for re-prediction at the top of the next loop iteration (at most two)."""
    if isc[I_PEND_A] < 0:
        isc[I_PEND_A] = p
    else:
        isc[I_PEND_B] = p
