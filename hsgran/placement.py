"""Sphere placement: random non-overlapping spheres for a scene's [[fill]] blocks (layer 4).

A fill places its spheres by random sequential addition, largest first: each sphere takes
uniform candidate centres in the fill's region until one clears the planes and every sphere
placed so far (explicit particles, earlier fills, its own fill). Neighbours are found in the
cell grid of :mod:`hsgran.events.grid` (the engine's grid: :func:`plan_grid`, hashed list
slots, doubly linked lists) with cells at least one largest diameter wide, so a candidate is
compared with the spheres of 27 cells only (~10⁵ spheres at packing fraction 0.2 in about a
second).

Reproducibility: the caller's ``numpy.random.Generator`` draws, per fill, the radii
(polydisperse only), then candidate centres in blocks, then the velocity directions. The
compiled kernel consumes the candidates in order, so the spheres depend on the seed alone
(compiled or not, ``NUMBA_DISABLE_JIT=1`` included) and not on the grid's layout: the grid only
decides which spheres are compared, and every sphere within reach is.

This module also holds the overlap check of a whole set of spheres
(:func:`overlapping_pairs`, a :class:`scipy.spatial.cKDTree` with periodic images), which the
scene runs on explicit particles and, as a guard, on everything after placement.

Layer 4: imports ``errors``, ``_jit``, ``wallspec`` and ``events.grid``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from hsgran._jit import njit
from hsgran.errors import InputError
from hsgran.events.grid import (
    axis_coordinate,
    axis_neighbours,
    cell_coordinates,
    insert,
    insert_all,
    plan_grid,
    slot_of,
)
from hsgran.facets import face_coordinates, on_face
from hsgran.shapes import PartTables, tables
from hsgran.wallspec import (
    BL_RADIUS,
    CY_AXIS,
    CY_HALF,
    CY_RADIUS,
    CY_SIDE,
    CY_SIZE,
    WK_BALL,
    WK_FACE,
)

#: Relative tolerance of the overlap and wall-penetration checks. Spheres written by hand as
#: touching (centre distance = R1 + R2 in decimal) differ from exact contact by a few ulp after
#: parsing and subtraction; 1e-12 accepts those and nothing a simulation could notice.
CONTACT_TOLERANCE = 1e-12

#: A fill gives up after this many candidate positions per requested sphere (plus
#: :data:`FILL_MIN_ATTEMPTS`). Random sequential addition of equal spheres jams at a packing
#: fraction of ≈ 0.38; up to ≈ 0.3 it needs a few tens of candidates per sphere at the end, so
#: this budget only runs out for requests that cannot be met, and bounds the time they waste.
FILL_ATTEMPTS_PER_SPHERE = 300
#: Minimum candidate budget of a fill (small fills in awkward regions deserve a fair try).
FILL_MIN_ATTEMPTS = 100_000
#: Packing fraction above which a fill is refused without trying (random close packing of equal
#: spheres is 0.64, and random sequential addition stays far below it).
FILL_PACKING_LIMIT = 0.64
#: Fewest candidate centres drawn in one block (more: twice the spheres still to place). The
#: candidates a fill leaves unused are discarded, so this number is part of the random sequence:
#: changing it changes every scene with a fill after the first.
FILL_MIN_BLOCK = 4096
#: Random sequential addition jamming fraction of equal spheres, quoted in messages.
RSA_JAMMING_FRACTION = 0.38


@dataclass(frozen=True, eq=False)
class Fill:
    """A checked [[fill]] block: what to place, before placement.

    Attributes:
        key: Key path for messages (``fill[0]``).
        count: Number of spheres.
        material: Material name.
        radius: (min, max) radius [m]; equal for a monodisperse fill.
        lower, upper: Corners of the region [m], shape (3,); every sphere lies wholly inside.
        speed: Speed of every sphere [m/s], in a random direction.
        angular_velocity: Angular velocity of every sphere [rad/s], shape (3,).
    """

    key: str
    count: int
    material: str
    radius: tuple[float, float]
    lower: np.ndarray
    upper: np.ndarray
    speed: float
    angular_velocity: np.ndarray


@dataclass(frozen=True, eq=False)
class Space:
    """Where spheres may lie: the side of every plane its normal points to, and the periodic
    box, if any.

    Attributes:
        plane_point: A point of each plane [m], shape (P, 3).
        plane_normal: Unit normal of each plane [-], shape (P, 3).
        origin: Lower corner of the box [m], shape (3,) (any value without periodic axes).
        period: Length of the box along each periodic axis, 0 along the others [m], shape (3,).
        cyl_center: The middle of each cylinder's axis [m], shape (C, 3).
        cyl_row: Each cylinder's hsgran.wallspec ``CY_*`` row, shape (C, CY_SIZE).
        parts: The faces, edges and corners of finite walls and the fixed spheres
            (hsgran.shapes.tables).
    """

    plane_point: np.ndarray
    plane_normal: np.ndarray
    origin: np.ndarray
    period: np.ndarray
    cyl_center: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    cyl_row: np.ndarray = field(default_factory=lambda: np.zeros((0, CY_SIZE)))
    parts: PartTables = field(default_factory=lambda: tables(()))

    @property
    def periodic(self) -> np.ndarray:
        """Periodic flag per axis, shape (3,)."""
        return self.period > 0.0


def fill_spheres(rng: np.random.Generator, fill: Fill, placed_position: np.ndarray,
                 placed_radius: np.ndarray, space: Space):
    """Draw the radii, positions and velocities of one fill (see the module docstring).

    Args:
        rng: The scene's generator, consumed in the documented order.
        fill: The fill.
        placed_position, placed_radius: Spheres already in the scene [m], (m, 3) and (m,).
        space: Planes and periodic box.

    Returns:
        (position [m] (n, 3), velocity [m/s] (n, 3), radius [m] (n,)), in the order of the
        radius draw.

    Raises:
        InputError: ``fill[k].count``: the spheres would fill more than
            :data:`FILL_PACKING_LIMIT` of the region, or not all of them could be placed within
            the candidate budget.
    """
    r_min, r_max = fill.radius
    if r_min == r_max:
        radii = np.full(fill.count, r_min)
    else:
        radii = rng.uniform(r_min, r_max, fill.count)
    volume = float(np.prod(fill.upper - fill.lower))
    fraction = float(np.sum(4.0 / 3.0 * math.pi * radii**3)) / volume
    if fraction > FILL_PACKING_LIMIT:
        raise InputError(
            f"{fill.count} spheres would fill {fraction:.2f} of the region's volume, more than "
            f"random placement can reach (~{RSA_JAMMING_FRACTION} for equal spheres): lower "
            "count or radius, or enlarge the region", f"{fill.key}.count")
    budget = max(FILL_MIN_ATTEMPTS, FILL_ATTEMPTS_PER_SPHERE * fill.count)
    positions, attempts = random_sequential_addition(
        rng, radii, fill.lower, fill.upper, placed_position, placed_radius, space, budget)
    n_placed = int(np.sum(~np.isnan(positions[:, 0])))
    if n_placed < fill.count:
        raise InputError(
            f"placed only {n_placed} of {fill.count} spheres after {attempts} random attempts "
            f"(the spheres would fill {fraction:.2f} of the region; random sequential "
            f"placement of equal spheres jams near {RSA_JAMMING_FRACTION}): lower count or "
            "radius, or enlarge the region", f"{fill.key}.count")
    direction = rng.standard_normal((fill.count, 3))
    norm = np.linalg.norm(direction, axis=1, keepdims=True)
    norm[norm == 0.0] = 1.0  # probability zero; keeps the arithmetic finite
    velocity = fill.speed * direction / norm
    return positions, velocity, radii


def random_sequential_addition(rng, radii, lower, upper, placed_position, placed_radius,
                               space: Space, budget: int):
    """Place spheres of the given radii at random without overlaps, largest first.

    Args:
        rng: Random generator; draws uniform candidate centres in blocks.
        radii: Radii [m], shape (n,).
        lower, upper: Region corners [m], shape (3,); every sphere lies wholly inside (inside
            the periodic box along periodic axes).
        placed_position, placed_radius: Spheres already in the scene [m], (m, 3) and (m,)
            (inside the periodic box along periodic axes).
        space: Planes every sphere must clear and the periodic box.
        budget: Most candidate centres to draw.

    Returns:
        (positions (n, 3) with NaN rows for spheres not placed, candidates drawn).

    Raises:
        ValueError: a periodic axis shorter than two largest diameters (a sphere could then
            meet two images of another; scenes ask for three, see hsgran.scene).
    """
    n = radii.shape[0]
    order = np.argsort(-radii, kind="stable")
    r_all_max = float(max(radii.max(), placed_radius.max() if placed_radius.size else 0.0))
    reach = 2.0 * r_all_max  # farthest centre distance at which two spheres can overlap
    period = np.asarray(space.period, dtype=np.float64)
    periodic = space.periodic
    if np.any(periodic & (period < 2.0 * reach)):
        raise ValueError(f"periodic box {period} shorter than two diameters ({2.0 * reach})")

    # the grid covers the whole box along periodic axes, the region plus `reach` along the
    # others; spheres beyond that are farther than `reach` from every candidate
    grid_lower = np.where(periodic, space.origin, lower - reach)
    grid_upper = np.where(periodic, space.origin + period, upper + reach)
    keep = np.all(periodic | ((placed_position >= grid_lower) & (placed_position < grid_upper)),
                  axis=1)
    old_position, old_radius = placed_position[keep], placed_radius[keep]
    n_old = old_radius.shape[0]
    cap = n_old + n
    origin, size, ncell = plan_grid(grid_lower, grid_upper, periodic, reach, cap)

    grid_position = np.empty((cap, 3))
    grid_radius = np.empty(cap)
    grid_position[:n_old] = old_position
    grid_radius[:n_old] = old_radius
    # int32 lists, as the engine's grid (MAX_PARTICLES is far below 2³¹)
    head = np.full(int(np.prod(ncell)), -1, dtype=np.int32)
    nxt = np.full(cap, -1, dtype=np.int32)
    prv = np.full(cap, -1, dtype=np.int32)
    insert_all(cell_coordinates(old_position, origin, size, ncell, periodic), head, nxt, prv,
               ncell)

    positions = np.full((n, 3), np.nan)
    state = np.array([0, n_old], dtype=np.int64)  # next sphere in `order`, spheres in the grid
    scratch = np.empty(3)
    near = np.empty((3, 3), dtype=np.int64)
    attempts = 0
    while state[0] < n and attempts < budget:
        block = int(min(budget - attempts, max(FILL_MIN_BLOCK, 2 * (n - state[0]))))
        u = rng.random((block, 3))
        pt = space.parts
        attempts += _rsa_kernel(u, order, radii, lower, upper, space.plane_point,
                                space.plane_normal, space.cyl_center, space.cyl_row,
                                pt.kind, pt.point, pt.normal, pt.geo, pt.cyl, pt.lines,
                                grid_position, grid_radius, head, nxt, prv, origin, size, ncell,
                                period, positions, state, scratch, near)
    return positions, attempts


def overlapping_pairs(position: np.ndarray, radius: np.ndarray, space: Space):
    """Pairs of overlapping spheres (minimum image along periodic axes).

    Args:
        position: Centres [m], shape (N, 3).
        radius: Radii [m], shape (N,).
        space: Gives the periodic box (its planes are not used).

    Returns:
        (pairs (K, 2) with i < j in each row, centre distances [m] (K,)); a pair overlaps when
        its centre distance is below the sum of radii by more than :data:`CONTACT_TOLERANCE`.
    """
    if len(radius) < 2:
        return np.empty((0, 2), dtype=np.intp), np.empty(0)
    tree = _tree(position, space)
    pairs = tree.query_pairs(2.0 * float(radius.max()), output_type="ndarray")
    if pairs.shape[0] == 0:
        return pairs, np.empty(0)
    dist = _pair_distance(position[pairs[:, 0]] - position[pairs[:, 1]], space)
    overlap = dist < (radius[pairs[:, 0]] + radius[pairs[:, 1]]) * (1.0 - CONTACT_TOLERANCE)
    return pairs[overlap], dist[overlap]


def _tree(position: np.ndarray, space: Space) -> cKDTree:
    """cKDTree of points, periodic along the space's periodic axes."""
    periodic = space.periodic
    if not np.any(periodic):
        return cKDTree(position)
    size = space.period
    x = position - space.origin
    wrapped = np.mod(x[:, periodic], size[periodic])
    # np.mod can round a tiny negative up to exactly the box size
    wrapped[wrapped >= size[periodic]] = 0.0
    x[:, periodic] = wrapped
    return cKDTree(x, boxsize=size)


def _pair_distance(delta: np.ndarray, space: Space) -> np.ndarray:
    """Lengths of centre differences (K, 3), minimum image along periodic axes."""
    periodic = space.periodic
    if np.any(periodic):
        size = space.period
        d = delta[:, periodic]
        delta[:, periodic] = d - size[periodic] * np.round(d / size[periodic])
    return np.sqrt(np.einsum("ij,ij->i", delta, delta))


# ---- the compiled kernel -----------------------------------------------------------------

@njit
def _rsa_kernel(u, order, radii, lower, upper, plane_point, plane_normal, cyl_center, cyl_row,
                part_kind, part_point, part_normal, part_geo, part_cyl, part_lines,
                grid_position, grid_radius, head, nxt, prv, origin, size, ncell, period,
                positions, state, x, near):
    """Consume uniform triples ``u`` as candidate centres; returns how many were used.

    ``state`` = [next index into ``order``, number of spheres in the grid], updated in place;
    ``x`` (3,) and ``near`` (3, 3) are scratch.
    """
    k = state[0]
    filled = state[1]
    n = order.shape[0]
    used = 0
    while k < n and used < u.shape[0]:
        s = order[k]
        r = radii[s]
        for a in range(3):
            x[a] = lower[a] + r + u[used, a] * (upper[a] - lower[a] - 2.0 * r)
        used += 1
        if not _clear_of_planes(x, r, plane_point, plane_normal):
            continue
        if not _clear_of_cylinders(x, r, cyl_center, cyl_row):
            continue
        if not _clear_of_parts(x, r, part_kind, part_point, part_normal, part_geo, part_cyl,
                               part_lines):
            continue
        if not _clear_of_spheres(x, r, grid_position, grid_radius, head, nxt, origin, size,
                                 ncell, period, near):
            continue
        for a in range(3):
            grid_position[filled, a] = x[a]
            positions[s, a] = x[a]
        grid_radius[filled] = r
        insert(filled, slot_of(near[0, 0], near[1, 0], near[2, 0], ncell), head, nxt, prv)
        filled += 1
        k += 1
    state[0] = k
    state[1] = filled
    return used


@njit
def _clear_of_planes(x, r, plane_point, plane_normal):
    """Whether a sphere (centre ``x``, radius ``r``) lies wholly on every plane's side."""
    for q in range(plane_point.shape[0]):
        d = 0.0
        for a in range(3):
            d += (x[a] - plane_point[q, a]) * plane_normal[q, a]
        if d < r:
            return False
    return True


@njit
def _clear_of_cylinders(x, r, cyl_center, cyl_row):
    """Whether a sphere (centre ``x``, radius ``r``) lies wholly on every cylinder's side."""
    for q in range(cyl_center.shape[0]):
        s = 0.0
        for a in range(3):
            s += (x[a] - cyl_center[q, a]) * cyl_row[q, CY_AXIS + a]
        d2 = 0.0
        for a in range(3):
            c = x[a] - cyl_center[q, a] - s * cyl_row[q, CY_AXIS + a]
            d2 += c * c
        gap = cyl_row[q, CY_SIDE] * (cyl_row[q, CY_RADIUS] - math.sqrt(d2))
        if gap < r:
            return False
    return True


@njit
def _clear_of_parts(x, r, kind, point, normal, geo, cyl, lines):
    """Whether a sphere (centre ``x``, radius ``r``) is clear of every part of the finite walls
    and every fixed sphere: its distance from a fixed sphere's centre at least r + R, from an
    edge's segment at least r, and from a face's plane at least r where its foot is on the
    face (hsgran.shapes.Part.distance)."""
    for q in range(kind.shape[0]):
        d0 = x[0] - point[q, 0]
        d1 = x[1] - point[q, 1]
        d2 = x[2] - point[q, 2]
        if kind[q] == WK_BALL:
            if d0 * d0 + d1 * d1 + d2 * d2 < (r + geo[q, BL_RADIUS]) ** 2:
                return False
        elif kind[q] == WK_FACE:
            height = d0 * normal[q, 0] + d1 * normal[q, 1] + d2 * normal[q, 2]
            if abs(height) < r:
                u, v = face_coordinates(x[0], x[1], x[2], point, geo, q)
                if on_face(u, v, point, geo, lines, q):
                    return False
        else:  # an edge
            s = min(max(d0 * cyl[q, CY_AXIS] + d1 * cyl[q, CY_AXIS + 1]
                        + d2 * cyl[q, CY_AXIS + 2], -cyl[q, CY_HALF]), cyl[q, CY_HALF])
            e0 = d0 - s * cyl[q, CY_AXIS]
            e1 = d1 - s * cyl[q, CY_AXIS + 1]
            e2 = d2 - s * cyl[q, CY_AXIS + 2]
            if e0 * e0 + e1 * e1 + e2 * e2 < r * r:
                return False
    return True


@njit
def _clear_of_spheres(x, r, grid_position, grid_radius, head, nxt, origin, size, ncell, period,
                      near):
    """Whether a sphere (centre ``x``, radius ``r``) overlaps none of the grid's spheres.

    Leaves the cell coordinates of ``x`` in ``near[:, 0]`` (its own cell comes first: that is
    where a rejected candidate usually finds its overlap).
    """
    mx = axis_neighbours(axis_coordinate(x[0], origin[0], size[0], ncell[0], period[0] > 0.0),
                         ncell[0], near[0])
    my = axis_neighbours(axis_coordinate(x[1], origin[1], size[1], ncell[1], period[1] > 0.0),
                         ncell[1], near[1])
    mz = axis_neighbours(axis_coordinate(x[2], origin[2], size[2], ncell[2], period[2] > 0.0),
                         ncell[2], near[2])
    for ix in range(mx):
        for iy in range(my):
            for iz in range(mz):
                p = head[slot_of(near[0, ix], near[1, iy], near[2, iz], ncell)]
                while p >= 0:
                    d2 = 0.0
                    for a in range(3):
                        e = x[a] - grid_position[p, a]
                        if period[a] > 0.0:  # minimum image
                            if e > 0.5 * period[a]:
                                e -= period[a]
                            elif e < -0.5 * period[a]:
                                e += period[a]
                        d2 += e * e
                    reach = r + grid_radius[p]
                    if d2 < reach * reach:
                        return False
                    p = nxt[p]
    return True
