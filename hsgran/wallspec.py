"""The walls' kinds, the prescribed motions of planes and the cylinders' geometry, as numbers
(layer 1; no numba: files and drawings read them too). :mod:`hsgran.wallmotion` compiles these
functions for the event loop and adds the contact time with a moving plane (docs/walls.md).

The engine keeps one row per wall (``Walls.planes_*``): the planes first, then the cylinders,
then the parts of the finite walls (faces, their edges and corners) and the fixed spheres;
``Walls.planes_kind`` says which (``WK_*``; docs/walls.md, "Finite walls").

A moving plane keeps its normal and translates along a unit direction d: p(t) = p₀ + d s(t),
s(0) = 0. Each plane's motion is one row of ``M_*`` values (``Walls.planes_mot``); a fixed
plane has kind ``MOT_FIXED``.
"""

from __future__ import annotations

import math

WK_PLANE = 0  #: a fixed plane
WK_MOVING = 1  #: a plane with a prescribed motion (``planes_mot``)
#: a cylinder (``planes_cyl``; its row's ``planes_p`` is the centre of its axis, and its
#: ``planes_n``, ``planes_vel``, ``planes_omg`` describe its last contact: the normal there, the
#: surface velocity, the wall's angular velocity)
WK_CYLINDER = 2

CY_AXIS = 0  #: unit axis a, columns 0–2
CY_RADIUS = 3  #: radius R [m]
CY_SIDE = 4  #: +1: the spheres are inside; −1: outside
CY_OMEGA = 5  #: angular velocity Ω about a [rad/s] (right-handed)
CY_HALF = 6  #: half its length [m] (for drawings; its ends are closed by planes)
#: 1 for the edge of a finite wall: a cylinder of radius 0 whose contacts count only between
#: its ends (|s| ≤ CY_HALF along the axis from its middle); 0 for a cylinder wall
CY_FINITE = 7
CY_SIZE = 8

#: a face of a finite wall: a one-sided plane (``planes_p``, ``planes_n``) whose contacts
#: count only where the centre's foot lies on the face (``planes_geo``: the ``FC_*`` columns)
WK_FACE = 3
#: a fixed sphere, or the corner of a finite wall (radius 0): centre ``planes_p``, radius
#: ``planes_geo[w, BL_RADIUS]``; its row's ``planes_n`` is the normal at its last contact
WK_BALL = 4

FC_E1 = 0  #: unit in-plane axis e₁ of the face's coordinates (u, v), columns 0–2
FC_E2 = 3  #: unit in-plane axis e₂ = n × e₁, columns 3–5
#: first row and number of rows in ``face_lines`` of the half-planes a u + b v ≤ c whose
#: intersection is the face's outline (none: the face is unbounded, a plane with a hole)
FC_LINES = 6
FC_NLINES = 7
#: first row and number of rows of the hole, the region where a u + b v < c for all of them
#: (none: no hole)
FC_HOLE = 8
FC_NHOLE = 9
BL_RADIUS = 0  #: a fixed sphere's radius [m] (0 for a corner)
GEO_SIZE = 10

MOT_FIXED = 0  #: the plane does not move
MOT_OSCILLATION = 1  #: s(t) = A [sin(ω t + φ) − sin φ]
MOT_VELOCITY = 2  #: s(t) = V clamp(t − t₀, 0, L/V)

M_KIND = 0  #: MOT_* code (stored as a float)
M_DIR = 1  #: unit direction d of the motion, columns 1–3
M_AMP = 4  #: amplitude A [m] (oscillation) or speed V [m/s] (velocity)
M_OMEGA = 5  #: angular frequency ω [rad/s] (oscillation)
M_PHASE = 6  #: phase φ [rad] (oscillation) or start time t₀ [s] (velocity)
M_TRAVEL = 7  #: travel L [m] (velocity)
M_SIZE = 8


def wall_shift(mot, w, t):
    """s(t) [m]: how far plane w has moved along its direction at time t [s]."""
    kind = mot[w, M_KIND]
    if kind == MOT_OSCILLATION:
        return mot[w, M_AMP] * (math.sin(mot[w, M_OMEGA] * t + mot[w, M_PHASE])
                                - math.sin(mot[w, M_PHASE]))
    if kind == MOT_VELOCITY:
        speed = mot[w, M_AMP]
        return speed * min(max(t - mot[w, M_PHASE], 0.0), mot[w, M_TRAVEL] / speed)
    return 0.0


def wall_speed(mot, w, t):
    """ṡ(t) [m/s] of plane w at time t [s] (a piston at its start or end: the speed after)."""
    kind = mot[w, M_KIND]
    if kind == MOT_OSCILLATION:
        return mot[w, M_AMP] * mot[w, M_OMEGA] * math.cos(mot[w, M_OMEGA] * t + mot[w, M_PHASE])
    if kind == MOT_VELOCITY:
        speed = mot[w, M_AMP]
        t0 = mot[w, M_PHASE]
        return speed if t0 <= t < t0 + mot[w, M_TRAVEL] / speed else 0.0
    return 0.0



def cylinder_bounds(center, row):
    """Lower and upper corners [m] of the box around a cylinder (centre ``center`` [m], its
    ``CY_*`` row), each a (3,) tuple."""
    lower, upper = [], []
    for k in range(3):
        a = row[CY_AXIS + k]
        reach = row[CY_RADIUS] * math.sqrt(max(1.0 - a * a, 0.0)) + row[CY_HALF] * abs(a)
        lower.append(center[k] - reach)
        upper.append(center[k] + reach)
    return tuple(lower), tuple(upper)
