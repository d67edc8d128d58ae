"""The kinds of event of the event loop, defined once (layer 3: imports nothing from hsgran).

:data:`KINDS` is the table: for every kind its integer code, its name, whether executed events of
that kind are rows of the event log (``/hsgran/events``, :class:`hsgran.engine.EventBlock`) or
only counted in the run summary, and what it is. For each row the module also holds a plain
``int`` constant ``EV_<NAME>`` (``EV_PAIR == 1``), so that the compiled loop, which imports
them, sees compile-time constants; :data:`EVENT_NAMES` lists the names in code order (the
summary's counts). Adding a kind is one row of the table; docs/trajectory-format.md lists the
logged kinds, and tests/events/test_kinds.py checks that list against this table.

Every logged row has the fields of the event log: ``time``, ``i`` (the sphere), ``j``,
impulses, ``e_n``, ``stage`` and ``regime``; :attr:`EventKind.description` says what ``j``,
``stage`` and ``regime`` mean for the kind.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class EventKind:
    """One kind of event.

    Attributes:
        code: The integer in the event loop's calendar, the event log's ``kind`` and the index of
            the run summary's counts.
        name: Lower-case word for the summary and docs; ``EV_<NAME>`` is the module constant.
        logged: Whether executed events of this kind are rows of the event log (else they are
            only counted).
        description: One line: what the event is and, when logged, what ``j``, ``stage`` and
            ``regime`` of its row mean.
    """

    code: int
    name: str
    logged: bool
    description: str


#: Every kind of event, in code order (a kind's code is its position).
KINDS = (
    EventKind(0, "none", False, "nothing scheduled (a sphere without a pending event)"),
    EventKind(1, "pair", True,
              "sphere–sphere collision; j the partner sphere, stage the deepest normal-model "
              "stage, regime the tangential regime"),
    EventKind(2, "wall", True,
              "sphere–plane collision; j = −1 − w for plane w, stage and regime as for pair"),
    EventKind(3, "cell", False, "a sphere leaves its grid cell (on a periodic axis: wraps)"),
    EventKind(4, "frame", False, "output tick: every sphere is sampled at the frame time"),
    EventKind(5, "stale", False,
              "a popped pair event dropped because the partner had an event since"),
    EventKind(6, "miss", False,
              "a popped collision whose bodies were found not approaching (grazing round-off)"),
    EventKind(7, "state", True,
              "an on-plane motion segment ends (slide → roll, roll → rest, …); j = −1 − w for "
              "plane w, stage the new motion state, regime what ended the segment"),
    EventKind(8, "land", True,
              "a sphere reaches a plane too slowly to bounce and stays on it, or falls asleep "
              "on a sphere; j the plane (−1 − w) or sphere, stage the new motion state, "
              "regime 0"),
    EventKind(9, "tc", False,
              "a collision made elastic by the TC model (also counted and logged as pair or "
              "wall)"),
    EventKind(10, "hop", False,
              "touching spheres pressed together sent apart at the hop speed instead of "
              "colliding (also counted and logged as pair), or a sphere on a wall sent off "
              "another wall (logged as wall)"),
    EventKind(11, "wedge", True,
              "a sphere stopped in a zero-time wedge sequence; j the other body of the "
              "collision, stage the new motion state, regime 0"),
    EventKind(12, "cluster", False,
              "touching spheres and walls solved together (docs/enduring-contact.md, "
              "\"Clusters of contacts\"); a collision among them is also counted and logged "
              "as pair or wall, with stage −2; a segment's end as state"),
    EventKind(13, "exit", True,
              "a sphere's centre enters an outlet and the sphere leaves the system "
              "(docs/open-systems.md); j the outlet, stage its motion state before, regime 0, "
              "impulses 0, the velocity the one it left with"),
)

#: Names of the kinds in code order.
EVENT_NAMES = tuple(k.name for k in KINDS)

# The EV_* constants come from the table so that a new kind is one row; they are module
# globals (not attributes of a class) because numba folds only module-level ints.
globals().update({f"EV_{k.name.upper()}": k.code for k in KINDS})
