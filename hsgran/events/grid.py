"""Cell grid: which spheres can meet soon (layer 3).

Space is cut into cells at least one largest diameter wide, so a sphere can only touch spheres in
its own and the 26 neighbouring cells. Each sphere stores its integer cell coordinates; cells are
kept as doubly linked lists (``head``, ``nxt``, ``prv``) so moving a sphere costs O(1).

On a periodic axis the cells tile the box exactly and coordinates wrap. On any other axis the
coordinate is unbounded and the list slot is the coordinate modulo the number of cells (a hashed
grid): a sphere that leaves the initial region keeps working, it only shares its slot with far
away spheres that the distance test then rejects.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit

#: Maximum number of cells per axis and in total: the grid never costs more memory than the
#: particles themselves (a few cells per particle) and never exceeds this many slots.
MAX_CELLS_PER_PARTICLE = 4
MAX_CELLS_TOTAL = 1 << 24
#: Cells a periodic axis needs: with three or more, the cells next to a sphere's own are
#: distinct, so each neighbour is met in exactly one image (hsgran._loop._axis_cells).
MIN_PERIODIC_CELLS = 3


@njit
def slot_of(cx, cy, cz, ncell):
    """List slot of integer cell coordinates (modulo the grid size on every axis)."""
    return ((cx % ncell[0]) * ncell[1] + (cy % ncell[1])) * ncell[2] + (cz % ncell[2])


@njit
def insert(i, s, head, nxt, prv):
    """Put sphere ``i`` at the front of the list of slot ``s``."""
    first = head[s]
    nxt[i] = first
    prv[i] = -1
    if first >= 0:
        prv[first] = i
    head[s] = i


@njit
def remove(i, s, head, nxt, prv):
    """Take sphere ``i`` out of the list of slot ``s``."""
    a = prv[i]
    b = nxt[i]
    if a >= 0:
        nxt[a] = b
    else:
        head[s] = b
    if b >= 0:
        prv[b] = a


def plan_grid(lower, upper, periodic, cell_min, n_particles):
    """Choose the grid for a domain.

    Args:
        lower, upper: Extent to cover [m], (3,) (the box, or the spheres' bounding region).
        periodic: Per-axis periodic flags; on those axes the cells tile [lower, upper] exactly.
        cell_min: Smallest allowed cell width [m] (the largest contact distance).
        n_particles: Number of spheres (bounds the number of cells).

    Returns:
        (origin (3,), cell size (3,), number of cells (3,) int64).
    """
    lower = np.asarray(lower, dtype=np.float64)
    upper = np.asarray(upper, dtype=np.float64)
    extent = np.maximum(upper - lower, cell_min)
    n = np.maximum(np.floor(extent / cell_min), 1).astype(np.int64)
    budget = min(MAX_CELLS_TOTAL, max(27, MAX_CELLS_PER_PARTICLE * n_particles))
    periodic = np.asarray(periodic, dtype=bool)
    # a periodic axis keeps at least MIN_PERIODIC_CELLS cells (see there); coarsen the open
    # axes first, the largest first
    floor = np.where(periodic, np.minimum(n, MIN_PERIODIC_CELLS), 1)
    while int(np.prod(n)) > budget:
        room = np.where(n > floor, n, 0)
        open_room = np.where(periodic, 0, room)
        k = int(np.argmax(open_room)) if open_room.max() > 3 else int(np.argmax(room))
        if room[k] == 0:
            break
        n[k] = max(floor[k], n[k] // 2)
    size = extent / n
    return lower.copy(), size, n


def cell_coordinates(pos, origin, size, ncell, periodic):
    """Integer cell coordinates of positions (N, 3); wrapped into range on periodic axes."""
    c = np.floor((pos - origin) / size).astype(np.int64)
    for k in range(3):
        if periodic[k]:
            c[:, k] = np.clip(c[:, k], 0, ncell[k] - 1)
    return c


@njit
def axis_coordinate(x, origin, size, n, periodic):
    """Integer cell coordinate of one position component: :func:`cell_coordinates` for one
    point along one axis, callable from compiled kernels.

    Args:
        x: Position component [m].
        origin, size: The axis's grid origin and cell size [m] (from :func:`plan_grid`).
        n: Number of cells along the axis.
        periodic: Whether the axis is periodic (then the coordinate is clipped into [0, n)).
    """
    c = math.floor((x - origin) / size)
    if periodic:
        c = min(max(c, 0), n - 1)
    return c


@njit
def axis_neighbours(c, n, out):
    """Coordinates of the cells within one cell of coordinate ``c`` along an axis of ``n``
    cells, own cell first, each list slot once.

    With fewer than three cells the coordinates ``c - 1`` and ``c + 1`` share a slot (or share
    it with ``c``), so they are left out: a search visits every slot once.

    Args:
        c: Cell coordinate (any integer: :func:`slot_of` takes it modulo ``n``).
        n: Number of cells along the axis.
        out: (3,) int array receiving the coordinates.

    Returns:
        How many entries of ``out`` were written (1, 2 or 3).
    """
    out[0] = c
    if n == 1:
        return 1
    out[1] = c + 1
    if n == 2:
        return 2
    out[2] = c - 1
    return 3


@njit
def insert_all(cell, head, nxt, prv, ncell):
    """Put spheres ``0 .. len(cell) - 1`` into the lists of their cells, in index order.

    Args:
        cell: Integer cell coordinates (N, 3) (from :func:`cell_coordinates`).
        head, nxt, prv: Empty lists (``head`` all -1) with room for the N spheres.
        ncell: Number of cells per axis (3,).
    """
    for i in range(cell.shape[0]):
        insert(i, slot_of(cell[i, 0], cell[i, 1], cell[i, 2], ncell), head, nxt, prv)


def part_lists(lower: np.ndarray, upper: np.ndarray, origin, size, ncell, periodic):
    """The cell lists of the parts of finite walls (hsgran.shapes): part q is listed in every
    list whose cells meet its box [lower[q], upper[q]] (the part's extent grown by the largest
    sphere radius: every centre within a radius of the part lies in it), so a sphere looks
    only at the parts listed in its own cell's list, up to its cell exit.

    Args:
        lower, upper: Boxes [m], (Q, 3).
        origin, size, ncell, periodic: The grid (:func:`plan_grid`); along a periodic axis a
            box is cut to the period (parts near its ends have images of their own), along the
            others the cells are hashed, as the spheres'.

    Returns:
        (start (cells + 1,), items (M,)): list s holds items[start[s]:start[s + 1]], indices
        into the Q parts in increasing order.
    """
    ncell = np.asarray(ncell, dtype=np.int64)
    slots, owners = [], []
    for q in range(len(lower)):
        axes = []
        for k in range(3):
            lo = int(np.floor((lower[q, k] - origin[k]) / size[k]))
            hi = int(np.floor((upper[q, k] - origin[k]) / size[k]))
            if periodic[k]:
                lo, hi = max(lo, 0), min(hi, ncell[k] - 1)
            span = np.arange(lo, hi + 1) if hi - lo + 1 < ncell[k] else np.arange(ncell[k])
            axes.append(np.unique(np.mod(span, ncell[k])))
        x, y, z = np.meshgrid(*axes, indexing="ij")
        s = ((x * ncell[1] + y) * ncell[2] + z).ravel()
        slots.append(s)
        owners.append(np.full(s.shape, q, dtype=np.int64))
    cells = int(np.prod(ncell))
    slots = np.concatenate(slots) if slots else np.zeros(0, dtype=np.int64)
    owners = np.concatenate(owners) if owners else np.zeros(0, dtype=np.int64)
    order = np.lexsort((owners, slots))
    start = np.zeros(cells + 1, dtype=np.int64)
    np.add.at(start, slots + 1, 1)
    return np.cumsum(start), owners[order]
