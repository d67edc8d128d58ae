"""Finite walls: when a sphere meets a face, an edge or a corner, and when a sphere moving on a
face reaches its outline (layer 2: kinematics only; docs/walls.md, "Finite walls").

A finite wall (a convex polygon, a disk, a plane with a hole, a triangle of a mesh) is split
into parts that are contact geometry each, and a sphere meets the wall where it first meets
one of them:

- a **face** (``WK_FACE``): a one-sided plane whose contacts count only where the centre's
  foot lies on the face (:func:`on_face`); a two-sided plate is two faces;
- an **edge**: a cylinder of radius 0 whose contacts count only between its ends
  (``CY_FINITE``; :func:`edge_contact_time`);
- a **corner** (``WK_BALL`` of radius 0, as a fixed sphere): no restriction.

That the first of these contacts is the sphere's first contact with the wall: at that instant
the point of the wall nearest the centre lies inside a face, on an edge or at a corner, and
that part's distance reaches the radius then; before, no part's distance was below it, since
each part's distance is at least the wall's. A face's plane can be met first outside the face
(the foot off the face: the sphere passes beside it; it cannot slide onto the face within the
radius without meeting an edge first), and an edge's line outside the edge, after which the
sphere may leave the line's cylinder and meet the line again between the ends (a sphere thrown
up beside the end of a horizontal edge): :func:`edge_contact_time` looks for that second entry.

A face's outline and hole are convex polygons in its coordinates (u, v) = ((x − p)·e₁,
(x − p)·e₂), each the intersection of half-planes a u + b v ≤ c (rows of ``face_lines``).
"""

from __future__ import annotations

from hsgran._jit import njit
from hsgran.motion import (
    NEVER,
    _first_fall,
    cylinder_contact_time,
    gap_at_start,
    pair_contact_accelerated,
    pair_contact_before,
    root_horizon,
    upward_root,
)
from hsgran.wallspec import FC_E1, FC_E2, FC_HOLE, FC_LINES, FC_NHOLE, FC_NLINES

#: A sphere's segment on a face ended where its centre's foot left the face (an ``END_*``
#: code of hsgran.onplane's family, after hsgran._riding's): it flies from there, and meets
#: the edge it passed over at once if gravity presses it on (docs/walls.md, "Finite walls").
END_OFF = 8

#: A face is met only by a sphere whose centre lies in front of it by more than this share
#: of its radius less one radius (a gap above −FACE_BEHIND_REL r) [-]: a sphere that touches
#: a face overlaps it by rounding only; one whose centre came through a one-sided face from
#: behind (the other side of a plane with a hole, of a "front" polygon) is not held or hit
#: by it until its centre is half a radius in front.
FACE_BEHIND_REL = 0.5

#: A foot within this share of the size of the terms of a side's equation a u + b v − c (the
#: rounding of a position projected on the face, ~1e-16 of them) counts as on the side [-]:
#: a sphere whose foot left its face where the face meets another in the same plane is then
#: on both, leaves the one at once and lands on the other (without it, rounding could put the
#: foot a hair inside the face it leaves, or outside both). Far below any distance that
#: matters (1e-12 of the face's coordinates).
OUTLINE_ROUND_REL = 1e-12


@njit(inline="always")
def _side(a, b, c, u, v, far):
    """a u + b v − c, and its rounding scale: OUTLINE_ROUND_REL of its terms and of ``far``
    (|p|₁ of the face's origin p [m]: (u, v) come from x − p, rounded to ~1e-16 of |x|)."""
    return a * u + b * v - c, OUTLINE_ROUND_REL * (abs(a * u) + abs(b * v) + abs(c) + far)


@njit(inline="always")
def _far(p, w):
    """|p|₁ of face w's origin [m] (the scale of the rounding of its coordinates)."""
    return abs(p[w, 0]) + abs(p[w, 1]) + abs(p[w, 2])


@njit(inline="always")
def face_coordinates(x, y, z, p, geo, w):
    """The in-plane coordinates (u, v) [m] of the foot of (x, y, z) [m] on face w."""
    dx, dy, dz = x - p[w, 0], y - p[w, 1], z - p[w, 2]
    return (dx * geo[w, FC_E1] + dy * geo[w, FC_E1 + 1] + dz * geo[w, FC_E1 + 2],
            dx * geo[w, FC_E2] + dy * geo[w, FC_E2 + 1] + dz * geo[w, FC_E2 + 2])


@njit(inline="always")
def on_face(u, v, p, geo, lines, w):
    """Whether the in-plane point (u, v) [m] lies on face w (origins ``p``): inside its outline
    and not inside its hole, the sides included (to their rounding, OUTLINE_ROUND_REL)."""
    far = _far(p, w)
    start = int(geo[w, FC_LINES])
    for k in range(start, start + int(geo[w, FC_NLINES])):
        g, eps = _side(lines[k, 0], lines[k, 1], lines[k, 2], u, v, far)
        if g > eps:
            return False
    n_hole = int(geo[w, FC_NHOLE])
    if n_hole == 0:
        return True
    start = int(geo[w, FC_HOLE])
    for k in range(start, start + n_hole):
        g, eps = _side(lines[k, 0], lines[k, 1], lines[k, 2], u, v, far)
        if g >= -eps:
            return True
    return False


@njit(inline="always")
def _down_crossing(g0, g1, g2):
    """First τ ≥ 0 where g = g0 + g1 τ + ½ g2 τ² falls through zero (``inf`` if never): at
    once from g0 ≥ 0 (motion.upward_root of −g), or, from g0 < 0, after it has risen above
    zero (a concave g: its later root)."""
    if g0 >= 0.0:
        return upward_root(-g0, -g1, -g2)
    if g2 >= 0.0:
        return NEVER
    s2 = g1 * g1 - 2.0 * g2 * g0
    if s2 <= 0.0:
        return NEVER
    top = g1 + s2 ** 0.5
    return top / -g2 if top > 0.0 else NEVER


@njit
def face_leave_time(x, y, z, vx, vy, vz, ax, ay, az, p, geo, lines, w):
    """Delay [s] until the centre of a sphere moving on face w (position (x, y, z) [m],
    velocity v [m/s], constant acceleration a [m/s²] along the face) has its foot leave the
    face: across a line of the outline, or into the hole through one of the hole's lines
    (the crossing point inside the others); ``inf`` if not."""
    u0, v0 = face_coordinates(x, y, z, p, geo, w)
    u1 = vx * geo[w, FC_E1] + vy * geo[w, FC_E1 + 1] + vz * geo[w, FC_E1 + 2]
    v1 = vx * geo[w, FC_E2] + vy * geo[w, FC_E2 + 1] + vz * geo[w, FC_E2 + 2]
    u2 = ax * geo[w, FC_E1] + ay * geo[w, FC_E1 + 1] + az * geo[w, FC_E1 + 2]
    v2 = ax * geo[w, FC_E2] + ay * geo[w, FC_E2 + 1] + az * geo[w, FC_E2 + 2]
    best = NEVER
    far = _far(p, w)
    start = int(geo[w, FC_LINES])
    for k in range(start, start + int(geo[w, FC_NLINES])):
        a, b, c = lines[k, 0], lines[k, 1], lines[k, 2]
        g, eps = _side(a, b, c, u0, v0, far)
        tau = upward_root(g if g < -eps else 0.0, a * u1 + b * v1, a * u2 + b * v2)
        best = min(best, tau)
    start = int(geo[w, FC_HOLE])
    stop = start + int(geo[w, FC_NHOLE])
    for k in range(start, stop):
        a, b, c = lines[k, 0], lines[k, 1], lines[k, 2]
        # into the hole across line k: a u + b v − c falls through zero, there inside the rest
        g, eps = _side(a, b, c, u0, v0, far)
        tau = _down_crossing(g if abs(g) > eps else 0.0, a * u1 + b * v1, a * u2 + b * v2)
        if tau >= best:
            continue
        u = u0 + tau * (u1 + 0.5 * u2 * tau)
        v = v0 + tau * (v1 + 0.5 * v2 * tau)
        inside = True
        for q in range(start, stop):
            gq, eq = _side(lines[q, 0], lines[q, 1], lines[q, 2], u, v, far)
            if q != k and gq > eq:
                inside = False
                break
        if inside:
            best = tau
    return best


@njit
def edge_contact_time(qx, qy, qz, ux, uy, uz, gx, gy, gz, s0, s1, s2, r, half, horizon,
                      v_sum, x_sum):
    """Delay [s] until a sphere of radius r [m] meets an edge (a segment of length 2 half [m]):
    its centre's offset from the edge's line q [m] (perpendicular to it), velocity u [m/s] and
    acceleration g [m/s²] across the line, and its coordinate along the line from the edge's
    middle s0 [m], with its rate s1 [m/s] and acceleration s2 [m/s²]. The line's first
    contact (motion.cylinder_contact_time, radius 0 outside) counts where |s| ≤ half; met
    beyond an end, the line's next contact is looked for (a quartic has two at most)."""
    tau = cylinder_contact_time(qx, qy, qz, ux, uy, uz, gx, gy, gz, r, -1.0, horizon, v_sum,
                                x_sum)
    if tau == NEVER:
        return NEVER
    if abs(s0 + tau * (s1 + 0.5 * s2 * tau)) <= half:
        return tau
    # the next downward crossing of f = |q(τ)|² − r² after τ (the quartic's coefficients as
    # in cylinder_contact_time, outside: sgn = 1)
    c4 = 0.25 * (gx * gx + gy * gy + gz * gz)
    if c4 == 0.0:
        return NEVER  # a straight line meets a cylinder once
    c3 = ux * gx + uy * gy + uz * gz
    c2 = ux * ux + uy * uy + uz * uz + qx * gx + qy * gy + qz * gz
    c1 = 2.0 * (qx * ux + qy * uy + qz * uz)
    c0 = qx * qx + qy * qy + qz * qz - r * r
    # (met at τ = 0, touching: the next crossing lies beyond the piece it starts)
    again = _first_fall(qx, qy, qz, ux, uy, uz, gx, gy, gz, gap_at_start(qx, qy, qz, r), 1.0,
                        c4, c3, c2, c1, root_horizon(c4, c3, c2, c1, c0, horizon), tau == 0.0,
                        tau)
    if again < NEVER and abs(s0 + again * (s1 + 0.5 * s2 * again)) <= half:
        return again
    return NEVER


@njit
def ball_contact_time(dx, dy, dz, vx, vy, vz, gx, gy, gz, sigma, horizon, v_sum, x_sum):
    """Delay [s] until a sphere meets a fixed sphere or a corner: separation d = x − c [m],
    the sphere's velocity v [m/s] and acceleration g [m/s²], contact distance σ = r + R [m]
    (as two spheres, the fixed one at rest)."""
    if gx == 0.0 and gy == 0.0 and gz == 0.0:
        return pair_contact_before(dx, dy, dz, vx, vy, vz, sigma, horizon, v_sum, x_sum)
    return pair_contact_accelerated(dx, dy, dz, vx, vy, vz, gx, gy, gz, sigma, horizon, v_sum,
                                    x_sum)
