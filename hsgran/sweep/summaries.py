"""Summary quantities of one run, picked by name in a sweep file (``summaries = [...]``).

Each quantity is a small named function of a :class:`RunRecord` (what a run leaves behind: the
scene, its event log, the state just after the first collision, the event counts and the last
frame) returning one float in SI units (angles in degrees). :data:`SUMMARIES` maps the name to
the function, its unit and a one-line description; ``hsgran sweep --help`` and docs/sweeps.md
list them. A quantity that does not exist for a run (no collision, never at rest) is NaN.

"The first collision" is the first sphere–sphere or sphere–wall collision of the run; "the
sphere" is the first sphere of that event (``i`` of the event log) and the normal ``n`` points
from its partner (the wall's normal, or from the other sphere's centre) to it. The incident
velocity is the sphere's velocity relative to its partner just before the collision, taken as
the initial velocity plus gravity times the collision time: it assumes both bodies flew freely
from t = 0, which holds for impact set-ups (a sphere launched at a wall or at another sphere)
and is what the impact quantities are for. ``t`` is the unit vector of the incident tangential
velocity, so the rebound angle and e_t are signed: positive when the sphere keeps going forward.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: Below this fraction of the incident speed, the incident tangential velocity counts as zero
#: (a normal impact): its direction is then round-off, and the signed quantities use |v_t|.
NORMAL_IMPACT_FRACTION = 1e-12


@dataclass
class FirstCollision:
    """The first collision of a run and the state just after it (SI units).

    Attributes:
        time: Time of the collision [s].
        sphere: Index of the sphere (``i`` of the event log).
        partner: The other sphere's index, or −1 − w for plane w.
        e_n: Normal restitution of the collision [-].
        normal: Unit normal from the partner to the sphere, shape (3,).
        velocity_before: Sphere's velocity relative to its partner just before [m/s], (3,).
        velocity_after: The same just after [m/s], (3,).
        angular_velocity_after: Sphere's angular velocity just after [rad/s], (3,).
    """

    time: float
    sphere: int
    partner: int
    e_n: float
    normal: np.ndarray
    velocity_before: np.ndarray
    velocity_after: np.ndarray
    angular_velocity_after: np.ndarray

    def tangent(self) -> np.ndarray | None:
        """Unit incident tangential direction, or ``None`` for a normal impact."""
        v, n = self.velocity_before, self.normal
        vt = v - np.dot(v, n) * n
        norm = float(np.linalg.norm(vt))
        if norm <= NORMAL_IMPACT_FRACTION * float(np.linalg.norm(v)):
            return None
        return vt / norm


@dataclass
class RunRecord:
    """What a finished run leaves for the summaries.

    Attributes:
        events: Event log field → array (time, kind, i, j, e_n, stage, ...), shape (E,).
        counts: Executed events by kind over the whole run (``pair``, ``wall``, ``cell``, ...).
        first: The first collision, or ``None`` if there was none.
        t_end: End time of the run [s].
        position: Sphere centres at the end [m], (N, 3).
        velocity: Velocities at the end [m/s], (N, 3).
        at_rest: Whether every sphere is at rest (on a plane or asleep) at the end.
        kinetic_energy: Translational plus rotational kinetic energy at the end [J].
        dissipated_energy: Energy dissipated over the run [J] (initial minus final mechanical
            energy: collisions, friction and rolling resistance on planes, landings).
    """

    events: dict
    counts: dict
    first: FirstCollision | None
    t_end: float
    position: np.ndarray
    velocity: np.ndarray
    at_rest: bool
    kinetic_energy: float
    dissipated_energy: float


@dataclass(frozen=True)
class Summary:
    """A named summary quantity: ``function(record) -> float``, its unit and meaning."""

    function: Callable[[RunRecord], float]
    unit: str
    doc: str


def _first(fn):
    """Apply ``fn`` to the first collision, NaN if the run had none."""
    def wrapped(rec: RunRecord) -> float:
        return math.nan if rec.first is None else float(fn(rec.first))
    return wrapped


def e_n(c: FirstCollision) -> float:
    """Normal restitution of the first collision (from the event log) [-]."""
    return c.e_n


def impact_speed(c: FirstCollision) -> float:
    """Normal approach speed of the first collision, −v·n before it [m/s]."""
    return -float(np.dot(c.velocity_before, c.normal))


def incidence_angle(c: FirstCollision) -> float:
    """Angle between the incident relative velocity and −n [deg], 0 for a normal impact."""
    v, n = c.velocity_before, c.normal
    vn = -float(np.dot(v, n))
    return math.degrees(math.atan2(float(np.linalg.norm(v + vn * n)), vn))


def rebound_angle(c: FirstCollision) -> float:
    """Angle of the rebound velocity from n after the first collision [deg]; signed, > 0 when
    the sphere keeps moving forward (along the incident tangential direction)."""
    v, n = c.velocity_after, c.normal
    t = c.tangent()
    vn = float(np.dot(v, n))
    vt = float(np.linalg.norm(v - vn * n)) if t is None else float(np.dot(v, t))
    return math.degrees(math.atan2(vt, vn))


def e_t(c: FirstCollision) -> float:
    """Tangential restitution of the centre, v_t after / v_t before [-]; NaN for a normal
    impact."""
    t = c.tangent()
    if t is None:
        return math.nan
    return float(np.dot(c.velocity_after, t) / np.dot(c.velocity_before, t))


def spin_after(c: FirstCollision) -> float:
    """Angular velocity after the first collision about n × t [rad/s] (> 0: forward rolling,
    topspin); for a normal impact, its magnitude."""
    t = c.tangent()
    w = c.angular_velocity_after
    if t is None:
        return float(np.linalg.norm(w))
    return float(np.dot(w, np.cross(c.normal, t)))


def first_collision_time(c: FirstCollision) -> float:
    """Time of the first collision [s]."""
    return c.time


def time_to_rest(rec: RunRecord) -> float:
    """Time at which the last sphere came to rest [s] (the last logged collision or
    motion-state change); NaN if some sphere still moves at the end (no gravity: never)."""
    if not rec.at_rest:
        return math.nan
    t = rec.events.get("time")
    return float(t.max()) if t is not None and len(t) else 0.0


def final_height(rec: RunRecord) -> float:
    """Mean z coordinate of the sphere centres at the end [m]."""
    return float(np.mean(rec.position[:, 2]))


def final_speed(rec: RunRecord) -> float:
    """Largest centre speed at the end [m/s]."""
    return float(np.max(np.linalg.norm(rec.velocity, axis=1)))


def collisions(rec: RunRecord) -> float:
    """Collisions of the run (sphere–sphere and sphere–wall) [-]."""
    return float(rec.counts.get("pair", 0) + rec.counts.get("wall", 0))


def events(rec: RunRecord) -> float:
    """Events executed by the run: collisions, cell crossings and motion-state changes [-]."""
    return float(sum(rec.counts.get(k, 0) for k in ("pair", "wall", "cell", "state")))


def kinetic_energy(rec: RunRecord) -> float:
    """Kinetic energy (translational + rotational) at the end [J]."""
    return rec.kinetic_energy


def dissipated_energy(rec: RunRecord) -> float:
    """Energy dissipated over the run [J] (initial minus final mechanical energy)."""
    return rec.dissipated_energy


def _entry(fn, unit: str, first: bool = False) -> Summary:
    doc = " ".join((fn.__doc__ or "").split())
    return Summary(_first(fn) if first else fn, unit, doc)


#: Every summary quantity a sweep file may name.
SUMMARIES: dict[str, Summary] = {
    "e_n": _entry(e_n, "-", first=True),
    "e_t": _entry(e_t, "-", first=True),
    "rebound_angle": _entry(rebound_angle, "deg", first=True),
    "incidence_angle": _entry(incidence_angle, "deg", first=True),
    "impact_speed": _entry(impact_speed, "m/s", first=True),
    "spin_after": _entry(spin_after, "rad/s", first=True),
    "first_collision_time": _entry(first_collision_time, "s", first=True),
    "time_to_rest": _entry(time_to_rest, "s"),
    "final_height": _entry(final_height, "m"),
    "final_speed": _entry(final_speed, "m/s"),
    "kinetic_energy": _entry(kinetic_energy, "J"),
    "dissipated_energy": _entry(dissipated_energy, "J"),
    "collisions": _entry(collisions, "-"),
    "events": _entry(events, "-"),
}


def evaluate(names, record: RunRecord) -> dict[str, float]:
    """The named summaries of one run (name → value)."""
    return {name: SUMMARIES[name].function(record) for name in names}
