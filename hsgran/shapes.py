"""Finite walls as the parts the engine meets: faces, edges and corners (layer 1: numbers; no
numba; docs/walls.md, "Finite walls").

A convex polygon becomes one face per side it is met from, one edge per side of its outline
(a cylinder of radius 0 between two corners, ``CY_FINITE``) and one corner per vertex (a
fixed sphere of radius 0, ``WK_BALL``); a plane with a hole becomes a face without outline
and the hole's edges and corners. Disks and circular holes are regular polygons with the
circle's area (``sides`` corners, 64 unless given): the engine's contact geometry is flat
faces, straight edges and corners, each met at its exact time. A fixed sphere is one ball.

Every part is one engine wall row (:class:`Part`); :mod:`hsgran.facets` says when a sphere
meets it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hsgran.wallspec import (
    BL_RADIUS,
    CY_AXIS,
    CY_FINITE,
    CY_HALF,
    CY_SIDE,
    CY_SIZE,
    FC_E1,
    FC_E2,
    FC_HOLE,
    FC_LINES,
    FC_NHOLE,
    FC_NLINES,
    GEO_SIZE,
    WK_BALL,
    WK_CYLINDER,
    WK_FACE,
)

#: Corners of a regular polygon standing for a disk or a circular hole, unless given.
DEFAULT_SIDES = 64
#: Fewest corners of such a polygon.
MIN_SIDES = 3
#: Relative tolerance of the checks of a polygon [-]: its corners lie in one plane within this
#: share of its size, and it turns one way at each corner by more than this (convex, no
#: repeated or aligned corners). Far above the rounding of coordinates written in a file
#: (1e-16), far below any polygon a scene means.
FLAT_REL = 1e-9
#: Faces that share a side and whose normals differ by less than this [rad] lie in one
#: surface (shapes.weld drops the edge between them). A mesh stored in single precision (STL)
#: has normals off by ~1e-7–1e-6 rad on a flat surface; at a fold this small a sphere of
#: radius r comes no closer than r (1 − cos(θ/2)) ≈ r θ²/8 = 1.3e-11 r to the dropped edge.
WELD_ANGLE = 1e-5


@dataclass(frozen=True, eq=False)
class Part:
    """One part of a finite wall, or a fixed sphere: one engine wall row.

    Attributes:
        kind: ``WK_FACE``, ``WK_CYLINDER`` (an edge: radius 0, ``CY_FINITE``) or ``WK_BALL``.
        point: A face's origin of (u, v), an edge's middle, a ball's centre [m], shape (3,).
        normal: A face's unit normal, to the side it is met from (zeros otherwise), shape (3,).
        geo: Its ``FC_*`` (face) or ``BL_RADIUS`` (ball) values, shape (GEO_SIZE,); a face's
            ``FC_LINES`` and ``FC_HOLE`` count rows of ``lines``.
        cyl: An edge's ``CY_*`` values, shape (CY_SIZE,) (zeros otherwise).
        lines: A face's outline then hole, rows (a, b, c) of a u + b v ≤ c, shape (L, 3).
        material: Index into the scene's material names.
        key: Key path for messages (``walls[2]``).
    """

    kind: int
    point: np.ndarray
    normal: np.ndarray
    geo: np.ndarray
    cyl: np.ndarray
    lines: np.ndarray
    material: int
    key: str
    corners: np.ndarray  #: a face's outline corners, an edge's ends, a ball's centre [m]
    motion = None  # (parts never move)

    def distance(self, position: np.ndarray) -> np.ndarray:
        """Distance [m] of points (..., 3) from the part: from a face where their foot is on
        it (``inf`` elsewhere), from an edge's segment, from a ball's surface."""
        x = np.asarray(position, dtype=float)
        d = x - self.point
        if self.kind == WK_BALL:
            return np.sqrt(np.einsum("...k,...k->...", d, d)) - self.geo[BL_RADIUS]
        if self.kind == WK_CYLINDER:
            a = self.cyl[CY_AXIS:CY_AXIS + 3]
            s = np.clip(d @ a, -self.cyl[CY_HALF], self.cyl[CY_HALF])
            q = d - np.multiply.outer(s, a)
            return np.sqrt(np.einsum("...k,...k->...", q, q))
        u = d @ self.geo[FC_E1:FC_E1 + 3]
        v = d @ self.geo[FC_E2:FC_E2 + 3]
        return np.where(self.on_face(u, v), np.abs(d @ self.normal), np.inf)

    def bounds(self):
        """The corners (lower, upper) [m] of the box around the part, or ``None`` for a face
        without outline (a plane with a hole, unbounded)."""
        if self.kind == WK_BALL:
            reach = self.geo[BL_RADIUS]
            return self.point - reach, self.point + reach
        if len(self.corners) == 0:
            return None
        return self.corners.min(axis=0), self.corners.max(axis=0)

    def on_face(self, u, v) -> np.ndarray:
        """Whether in-plane points (u, v) [m] lie on this face (as hsgran.facets.on_face,
        without its allowance for the rounding of the loop's positions)."""
        u = np.asarray(u, dtype=float)
        v = np.asarray(v, dtype=float)
        inside = np.ones(np.broadcast(u, v).shape, dtype=bool)
        s, n = int(self.geo[FC_LINES]), int(self.geo[FC_NLINES])
        for a, b, c in self.lines[s:s + n]:
            inside &= a * u + b * v <= c
        s, n = int(self.geo[FC_HOLE]), int(self.geo[FC_NHOLE])
        if n:
            hole = np.ones_like(inside)
            for a, b, c in self.lines[s:s + n]:
                hole &= a * u + b * v < c
            inside &= ~hole
        return inside

    def outline(self) -> np.ndarray:
        """A face's outline corners [m], shape (K, 3), in order (empty for a face without
        outline); use :meth:`hole` for the hole's."""
        return self._corners(int(self.geo[FC_LINES]), int(self.geo[FC_NLINES]))

    def hole(self) -> np.ndarray:
        """A face's hole corners [m], shape (K, 3), in order (empty without a hole)."""
        return self._corners(int(self.geo[FC_HOLE]), int(self.geo[FC_NHOLE]))

    def _corners(self, start: int, count: int) -> np.ndarray:
        e1, e2 = self.geo[FC_E1:FC_E1 + 3], self.geo[FC_E2:FC_E2 + 3]
        rows = self.lines[start:start + count]
        out = []
        for k in range(count):  # corner k joins side k − 1 and side k
            (a1, b1, c1), (a2, b2, c2) = rows[k - 1], rows[k]
            det = a1 * b2 - a2 * b1
            u = (c1 * b2 - c2 * b1) / det
            v = (a1 * c2 - a2 * c1) / det
            out.append(self.point + u * e1 + v * e2)
        return np.array(out).reshape(-1, 3)


def in_plane_axes(normal: np.ndarray, first=None) -> tuple[np.ndarray, np.ndarray]:
    """Unit axes e₁, e₂ = n × e₁ of a plane of unit normal n: e₁ along ``first`` projected on
    the plane, or across the coordinate axis least aligned with n."""
    n = np.asarray(normal, dtype=float)
    if first is None:
        first = np.cross(np.eye(3)[int(np.argmin(np.abs(n)))], n)
    e1 = np.asarray(first, dtype=float) - (np.dot(first, n)) * n
    e1 = e1 / math.sqrt(float(np.dot(e1, e1)))
    return e1, np.cross(n, e1)


def regular_polygon(center, normal, radius: float, sides: int, first=None) -> np.ndarray:
    """Corners [m], shape (sides, 3), of the regular polygon with the area of the circle of
    ``radius`` [m] about ``center`` in the plane of unit ``normal``, counter-clockwise seen
    from the normal's side, the first corner along e₁ (:func:`in_plane_axes`)."""
    e1, e2 = in_plane_axes(normal, first)
    # area ½ k R'² sin(2π/k) = π R²
    r = radius * math.sqrt(2.0 * math.pi / (sides * math.sin(2.0 * math.pi / sides)))
    phi = 2.0 * math.pi * np.arange(sides) / sides
    return np.asarray(center, float) + r * (np.outer(np.cos(phi), e1) + np.outer(np.sin(phi), e2))


def rectangle(center, normal, size, first=None) -> np.ndarray:
    """Corners [m], shape (4, 3), of a rectangle of ``size`` (along e₁, along e₂) [m] about
    ``center`` in the plane of unit ``normal``, counter-clockwise seen from its side."""
    e1, e2 = in_plane_axes(normal, first)
    a, b = 0.5 * size[0] * e1, 0.5 * size[1] * e2
    c = np.asarray(center, float)
    return np.array([c - a - b, c + a - b, c + a + b, c - a + b])


def polygon_normal(corners: np.ndarray) -> np.ndarray:
    """Unit normal of a polygon by the right-hand rule of its corners' order (Newell)."""
    c = np.asarray(corners, dtype=float)
    n = np.cross(c, np.roll(c, -1, axis=0)).sum(axis=0)
    length = math.sqrt(float(np.dot(n, n)))
    if length == 0.0:
        raise ValueError("its corners enclose no area")
    return n / length


def _lines(corners, origin, e1, e2, what: str) -> np.ndarray:
    """The half-planes (a, b, c) of a convex polygon, counter-clockwise about e₁ × e₂; raises
    ValueError naming ``what`` if its corners are not in the plane or not convex."""
    c = np.asarray(corners, dtype=float)
    n = np.cross(e1, e2)
    size = float(np.max(np.linalg.norm(c - c.mean(axis=0), axis=1)))
    if len(c) < MIN_SIDES or size == 0.0:
        raise ValueError(f"{what} needs at least {MIN_SIDES} distinct corners")
    if np.max(np.abs((c - origin) @ n)) > FLAT_REL * size:
        raise ValueError(f"the corners of {what} do not lie in one plane")
    uv = np.stack([(c - origin) @ e1, (c - origin) @ e2], axis=1)
    if _area(uv) < 0.0:  # clockwise: the other way round
        uv = uv[::-1]
    side = np.roll(uv, -1, axis=0) - uv  # side k from corner k to corner k + 1
    after = np.roll(side, -1, axis=0)
    turn = side[:, 0] * after[:, 1] - side[:, 1] * after[:, 0]
    # convex: it turns one way at every corner, and once round in all (a star turns one way
    # at every corner too, but twice round or more)
    total = float(np.sum(np.arctan2(turn, np.einsum("ij,ij->i", side, after))))
    if not (np.all(turn > FLAT_REL * size * size) and abs(total - 2.0 * math.pi) < 1.0):
        raise ValueError(f"{what} must be convex, without repeated or aligned corners")
    out = np.column_stack([side[:, 1], -side[:, 0]])  # outward normals (a, b)
    out /= np.linalg.norm(out, axis=1)[:, None]
    return np.column_stack([out, np.einsum("ij,ij->i", out, uv)])


def _area(uv: np.ndarray) -> float:
    """Signed area of a polygon (K, 2), positive counter-clockwise (the shoelace formula)."""
    return 0.5 * float(np.sum(uv[:, 0] * np.roll(uv[:, 1], -1) - np.roll(uv[:, 0], -1) * uv[:, 1]))


def _face(origin, normal, e1, e2, outline, hole, material, key, corners) -> Part:
    geo = np.zeros(GEO_SIZE)
    geo[FC_E1:FC_E1 + 3] = e1
    geo[FC_E2:FC_E2 + 3] = e2
    geo[FC_LINES], geo[FC_NLINES] = 0, len(outline)
    geo[FC_HOLE], geo[FC_NHOLE] = len(outline), len(hole)
    lines = np.concatenate([outline, hole]).reshape(-1, 3)
    return Part(WK_FACE, np.asarray(origin, float), np.asarray(normal, float), geo,
                np.zeros(CY_SIZE), lines, material, key, np.asarray(corners, float))


def _rim(corners, material, key) -> list[Part]:
    """The edges and corners of a closed polygon's outline."""
    parts = []
    c = np.asarray(corners, dtype=float)
    for k in range(len(c)):
        a, b = c[k], c[(k + 1) % len(c)]
        length = float(np.linalg.norm(b - a))
        cyl = np.zeros(CY_SIZE)
        cyl[CY_AXIS:CY_AXIS + 3] = (b - a) / length
        cyl[CY_SIDE] = -1.0
        cyl[CY_HALF] = 0.5 * length
        cyl[CY_FINITE] = 1.0
        parts.append(Part(WK_CYLINDER, 0.5 * (a + b), np.zeros(3), np.zeros(GEO_SIZE), cyl,
                          np.zeros((0, 3)), material, key, np.array([a, b])))
    for k in range(len(c)):
        parts.append(ball(c[k], 0.0, material, key))
    return parts


def ball(center, radius: float, material: int, key: str) -> Part:
    """A fixed sphere of ``radius`` [m] (0: a corner) about ``center`` [m]."""
    geo = np.zeros(GEO_SIZE)
    geo[BL_RADIUS] = radius
    center = np.asarray(center, dtype=float)
    return Part(WK_BALL, center, np.zeros(3), geo, np.zeros(CY_SIZE), np.zeros((0, 3)),
                material, key, center[None])


def polygon(corners, material: int, key: str, both_sides: bool = True) -> list[Part]:
    """The parts of a flat convex polygon: its face (met from the side its corners turn
    counter-clockwise about, the right-hand rule, and with ``both_sides`` from the other
    too), its edges and its corners. Raises ValueError if the corners are not coplanar and
    convex."""
    c = np.asarray(corners, dtype=float)
    if np.any(np.all(c == np.roll(c, -1, axis=0), axis=1)):
        raise ValueError("the polygon has a corner written twice in a row")
    n = polygon_normal(c)
    origin = c.mean(axis=0)
    e1, e2 = in_plane_axes(n, c[1] - c[0])
    parts = [_face(origin, n, e1, e2, _lines(c, origin, e1, e2, "the polygon"), np.zeros((0, 3)),
                   material, key, c)]
    if both_sides:
        # the back face: normal −n, axes (e₂, e₁) keep e₂ = n × e₁ for its own normal
        parts.append(_face(origin, -n, e2, e1, _lines(c, origin, e2, e1, "the polygon"),
                           np.zeros((0, 3)), material, key, c))
    return parts + _rim(c, material, key)


def plane_with_hole(point, normal, hole_corners, material: int, key: str) -> list[Part]:
    """The parts of a plane (one-sided, unit ``normal``) with a convex polygonal hole: a face
    without outline whose (u, v) origin is the hole's middle, and the hole's edges and
    corners. Raises ValueError if the hole's corners are not in the plane or not convex."""
    n = np.asarray(normal, dtype=float)
    c = np.asarray(hole_corners, dtype=float)
    if np.any(np.all(c == np.roll(c, -1, axis=0), axis=1)):
        raise ValueError("the hole has a corner written twice in a row")
    origin = c.mean(axis=0)
    if abs(float(np.dot(origin - np.asarray(point, float), n))) > FLAT_REL * float(
            np.max(np.linalg.norm(c - origin, axis=1))):
        raise ValueError("the hole does not lie in the plane")
    e1, e2 = in_plane_axes(n, c[1] - c[0])
    face = _face(origin, n, e1, e2, np.zeros((0, 3)), _lines(c, origin, e1, e2, "the hole"),
                 material, key, np.zeros((0, 3)))
    return [face, *_rim(c, material, key)]


def weld(parts: list[Part]) -> list[Part]:
    """The parts without repeats and without the edges and corners that lie inside a flat
    surface: a face written twice (the same corners and side) is kept once; an edge is
    dropped where the faces that share it (an outline side of each, the same two corners) lie
    in one plane, within WELD_ANGLE, on either side of it, two for each side the surface is
    met from (tiles of a plane, the triangles of a flat mesh: no contact geometry there, and
    a sphere rolls across as on the plane); a corner is dropped where every edge that ends at
    it was; an edge or a corner that several walls share is kept once. Corners match when
    written the same, bit for bit (as in a mesh)."""
    def point(p):
        return np.asarray(p, dtype=float).tobytes()

    def side(a, b):
        return tuple(sorted((point(a), point(b))))

    faces_seen = set()
    kept_faces = []
    sharing: dict = {}  # side → (face, the direction of its inside across the side)
    for q in parts:
        if q.kind != WK_FACE:
            continue
        key = (tuple(sorted(point(c) for c in q.corners)), q.normal.tobytes())
        if len(q.corners) and key in faces_seen:
            continue  # the same face again
        faces_seen.add(key)
        kept_faces.append(q)
        c = q.corners
        for k in range(len(c)):
            a, b = c[k], c[(k + 1) % len(c)]
            inward = np.cross(q.normal, b - a)  # (which way the face lies from the side)
            if np.dot(inward, c.mean(axis=0) - a) < 0.0:
                inward = -inward
            sharing.setdefault(side(a, b), []).append((q, inward))
    flat = set()
    cos_weld = math.cos(WELD_ANGLE)
    for key, faces in sharing.items():
        n0 = faces[0][0].normal
        groups = ([f for f in faces if np.dot(f[0].normal, n0) >= cos_weld],
                  [f for f in faces if np.dot(f[0].normal, n0) <= -cos_weld])
        if len(groups[0]) + len(groups[1]) != len(faces):
            continue  # a fold
        if all(not g or any(np.dot(f[1], h[1]) < 0.0 for f in g for h in g) for g in groups):
            flat.add(key)
    out, seen, ends = [], set(), set()
    for q in parts:
        if q.kind == WK_FACE:
            if any(q is f for f in kept_faces):
                out.append(q)
            continue
        if q.kind == WK_CYLINDER and len(q.corners) == 2:
            key = side(*q.corners)
            if key in flat or key in seen:
                continue
            seen.add(key)
            ends.update(key)
        out.append(q)
    kept, corners = [], set()
    for q in out:
        if q.kind == WK_BALL and q.geo[BL_RADIUS] == 0.0:
            key = point(q.corners[0])
            if key not in ends or key in corners:
                continue
            corners.add(key)
        kept.append(q)
    return kept


@dataclass(frozen=True)
class PartTables:
    """Parts as arrays, one row each, their faces' lines in one table (a face's ``FC_LINES``
    and ``FC_HOLE`` count rows of ``lines``): what the engine, the placement and the
    trajectory file keep."""

    kind: np.ndarray  #: WK_* codes, (Q,) int64
    point: np.ndarray  #: (Q, 3) [m]
    normal: np.ndarray  #: (Q, 3)
    geo: np.ndarray  #: (Q, GEO_SIZE)
    cyl: np.ndarray  #: (Q, CY_SIZE)
    lines: np.ndarray  #: (L, 3)


def tables(parts) -> PartTables:
    """The arrays of ``parts`` (:class:`PartTables`)."""
    parts = list(parts)
    geo = np.array([q.geo for q in parts], dtype=float).reshape(-1, GEO_SIZE)
    start = 0
    for k, q in enumerate(parts):
        if q.kind == WK_FACE:
            geo[k, FC_LINES] += start
            geo[k, FC_HOLE] += start
            start += len(q.lines)
    lines = [q.lines for q in parts if q.kind == WK_FACE]
    return PartTables(
        kind=np.array([q.kind for q in parts], dtype=np.int64),
        point=np.array([q.point for q in parts], dtype=float).reshape(-1, 3),
        normal=np.array([q.normal for q in parts], dtype=float).reshape(-1, 3),
        geo=geo,
        cyl=np.array([q.cyl for q in parts], dtype=float).reshape(-1, CY_SIZE),
        lines=np.concatenate(lines).reshape(-1, 3) if lines else np.zeros((0, 3)))


def read_mesh(path) -> np.ndarray:
    """The triangles [file units] (T, 3, 3) of a triangle mesh file (STL, or any format
    trimesh reads), in the file's corner order; triangles of no area (below FLAT_REL of the
    mesh's size squared) are left out. Raises OSError or ValueError if the file cannot be
    read as a triangle mesh."""
    import trimesh  # (imported here: only scenes with meshes need it)

    mesh = trimesh.load(str(path), force="mesh", process=False)
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ValueError("no triangles in it")
    triangles = np.asarray(mesh.vertices, dtype=float)[np.asarray(mesh.faces)]
    size = float(np.ptp(triangles.reshape(-1, 3), axis=0).max())
    area = np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0],
                                   triangles[:, 2] - triangles[:, 0]), axis=1)
    return triangles[area > FLAT_REL * size * size]
