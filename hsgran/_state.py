"""The engine's state by name (layer 5; used by :mod:`hsgran.engine` and the compiled loop).

The compiled event loop takes its arrays in eight groups. Each group is a named tuple: numba
compiles an attribute access (``flight.st``) to the same code as the positional one it replaces,
and a reader sees what each array is. The groups, and every field's role, are listed once here:

- which fields a checkpoint holds (``STORED``): everything the loop reads and writes between
  events; not the scratch space it overwrites before reading, nor the event calendar (rebuilt
  from the pending events) or the frame and log buffers (empty at every checkpoint);
- the checkpoint's dataset names: the field names, which are unique across groups;
- how each field is allocated (:data:`FIELDS`: dtype, shape in terms of the scene's sizes,
  initial value, and whether it is one of the per-sphere record fields that large systems pack
  into :data:`SPHERE_RECORD`): :func:`allocate` makes every array of a run from that table,
  and :class:`hsgran.engine.Simulation` then fills in the scene's values.
"""

from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass

import numpy as np

from hsgran.outlets import OL_SIZE
from hsgran.wallspec import CY_SIZE, GEO_SIZE, M_SIZE

#: What a prediction needs of every sphere. ``st``: one 64-byte row per sphere (``S_*`` columns
#: of hsgran._loop: position [m], velocity [m/s], local time [s], radius [m]); ``counter``:
#: event counters; with gravity ``acc`` [m/s²], motion state ``mstate`` (hsgran.onplane MS_*),
#: plane ``mplane`` (or −2 − b when asleep on sphere b), end time ``seg_end`` [s] and kind
#: ``seg_code`` (END_*) of the on-plane motion segment (or of a step of constrained motion, whose
#: contacts within ``seg_reach`` [m] of the sphere at the step's start the step's solve holds
#: apart, hsgran._cluster); without gravity, each sphere's earliest
#: pair contact at its last prediction (``pc_t`` [s], ``pc_partner`` or −1, ``pc_count``: the
#: partner's counter then), which lets a cell crossing look at the new layer of cells only.
#: ``present``: with outlets or inflows only (docs/open-systems.md), 1 for a sphere in the
#: system and 0 for one that has left or not yet entered (not in the grid or the calendar;
#: empty in a closed system).
Flight = namedtuple("Flight", "st counter acc mstate mplane seg_end seg_code seg_reach pc_t "
                              "pc_partner pc_count present")
#: What a collision needs in addition. ``omg`` spins [rad/s]; ``inv_m`` [1/kg], ``inv_i``
#: [1/(kg m²)]; ``mat`` material index; ``zstreak`` events in succession without the clock
#: advancing (collapse guard); ``alpha`` [rad/s²] and ``seg_dir`` (the direction a segment's end
#: refers to) only with gravity; ``t_last`` time of the last collision [s] (TC model);
#: ``row_tc`` scratch pair row for an elastic TC collision; ``rapid`` collisions in succession
#: within the TC time (jams). With observables on (hsgran._observe): ``led`` each sphere's
#: momentum ledger [kg m/s] and ``obs`` the sums of the current frame interval (``OB_*``).
Dyn = namedtuple("Dyn", "omg inv_m inv_i mat zstreak alpha seg_dir t_last row_tc rapid led obs")
#: The walls, one row each, planes first, then cylinders (``planes_kind``: hsgran.wallspec
#: ``WK_*``): a point at t = 0 [m] (a cylinder's centre), unit normal, material, velocity [m/s]
#: and angular velocity [rad/s] (of a moving plane: its velocity at its last collision; of a
#: cylinder: the normal and surface velocity at its last contact), the prescribed motion
#: (hsgran.wallspec ``M_*`` columns; kind MOT_FIXED for a fixed plane) and a cylinder's
#: geometry (``CY_*`` columns); and the outlets, regions where spheres leave the system
#: (``outlets``: one row of hsgran.outlets ``OL_*`` values each; docs/open-systems.md). The
#: parts of finite walls and the fixed spheres (docs/walls.md, "Finite walls") keep their
#: geometry in ``planes_geo`` (``FC_*`` columns for a face, ``BL_RADIUS`` for a ball) and the
#: faces' outlines and holes in ``face_lines`` (rows a, b, c of a u + b v ≤ c).
#: ``n_global``: G, the walls every prediction looks at (planes, cylinders, unbounded faces),
#: always the first rows 0 … G − 1; the other parts only through the cell lists
#: ``Grid.part_start``, ``Grid.part_items``.
Walls = namedtuple("Walls", "planes_p planes_n planes_mat planes_vel planes_omg planes_mot "
                            "planes_kind planes_cyl outlets planes_geo face_lines n_global")
#: Gravity [m/s²], box lengths [m] (periodic axes) and which axes are periodic; ``slack``: a
#: touching contact of a sphere in constrained motion (MS_SUPPORTED, hsgran._cluster) whose
#: normal velocity stays above −slack[0] [m/s] until its segment ends is no contact event (the
#: cluster solver's tolerance, not an approach; 0 without gravity).
Space = namedtuple("Space", "gravity box_len periodic slack")
#: The cell grid (hsgran.events.grid): origin [m], cell size [m], cells per axis, each sphere's
#: cell, the linked lists (``head``, ``nxt``, ``prv``), and scratch space: 27 list heads and
#: their image shifts [m], the per-axis list coordinates ``ac`` and shifts ``ah`` [m] of a
#: prediction, and a stack for waking sleepers; the cell lists of the parts of finite walls
#: (hsgran.events.grid.part_lists: list s holds the wall rows ``part_items[part_start[s]:
#: part_start[s + 1]]``; both empty without such parts).
Grid = namedtuple("Grid", "origin csize ncell cell head nxt prv heads shifts ac ah stack "
                          "part_start part_items")
#: One pending event per entry (sphere, and the frame tick last): time [s], sequence number,
#: kind (hsgran.events.kinds), partner, the partner's counter at prediction; ``cal`` the event
#: calendar (hsgran.events.calendar), whose keys are ``ev_t`` and ``ev_seq``.
Sched = namedtuple("Sched", "ev_t ev_seq ev_kind ev_partner ev_pcount cal")
#: Scratch of a cluster of contacts solved together (hsgran._cluster; with gravity only): the
#: bodies (``cl_body`` the sphere of each, ``cl_loc`` each sphere's body or −1, ``cl_was`` its
#: motion state before, ``cl_depth`` its contact distance from the event's spheres; inverse mass
#: [1/kg], inverse moment of inertia [1/(kg m²)], radius [m]; velocities ``cl_v`` [m/s] and
#: spins ``cl_w`` [rad/s], the step's end velocities ``cl_a`` [m/s] and spins ``cl_al``
#: [rad/s], ``cl_root`` the union-find links of the bodies whose motion over the step is
#: linear) and the contacts (``ck_*``: the arrays of hsgran.contact.cluster.solve, the partner
#: ``ck_q`` (a sphere, or −1 − w for plane w), its material ``ck_mat``, the immovable body's
#: acceleration ``ck_ab`` [m/s²], the gap ``ck_gap`` [m] at the step's start, ``ck_reb`` the
#: rebound target [m/s] of an impact, NaN for other contacts); and, kept
#: from solve to solve (not scratch), the contact forces of the last solve that warm-start
#: the next (``wm_q`` the partner of each of a sphere's WARM_SLOTS entries, a sphere or
#: −1 − w for plane w, or WARM_EMPTY; ``wm_f`` the force [N] and rolling torque [N m] on the
#: sphere, by the pair's lower sphere index).
Clus = namedtuple("Clus", "cl_body cl_loc cl_was cl_depth cl_inv_m cl_inv_i cl_rad cl_v cl_w "
                          "cl_a cl_al cl_root ck_a ck_b ck_q ck_mat ck_n ck_rb ck_vb ck_ab ck_gap "
                          "ck_reb ck_tgt ck_mu ck_slip ck_mur ck_reff ck_rslip ck_pn ck_pt ck_hr "
                          "wm_q wm_f")
#: Output buffers: frame times [s], positions [m], velocities [m/s], spins [rad/s], the event
#: log (floats ``log_f``: time, J_n, J_t, e_n, and sphere i's velocity after the event; ints
#: ``log_i``: kind, i, j, stage, regime) and
#: motion states per frame; with observables on, ``fr_obs`` the sums ``obs`` of the interval
#: each frame closes; in an open system, ``fr_pres`` whether each sphere is in the system,
#: ``fr_left`` the energy the spheres that left carried out until the frame (F_EXITED) and
#: ``fr_in`` the energy the inserted ones brought in (F_ENTERED) [J]; with gravity along a
#: periodic axis, ``fr_unwrap`` the potential energy the wraps hid until the frame (F_UNWRAPPED).
Out = namedtuple("Out", "fr_time fr_pos fr_vel fr_omg log_f log_i fr_ms fr_obs fr_pres "
                        "fr_left fr_in fr_unwrap")

#: The groups in the order the loop takes them.
GROUPS = (Flight, Dyn, Walls, Space, Grid, Sched, Clus, Out)

#: Fields the loop overwrites before it reads them (not stored in checkpoints).
SCRATCH = frozenset({"row_tc", "heads", "shifts", "ac", "ah", "stack"}) | (
    set(Clus._fields) - {"wm_q", "wm_f"})
#: Fields rebuilt or emptied rather than stored: the calendar (rebuilt from ``ev_t``/``ev_seq``)
#: and the output buffers (handed to the observers before every checkpoint).
NOT_STORED = SCRATCH | {"cal"} | set(Out._fields)


def stored_fields(groups) -> dict:
    """The arrays a checkpoint holds, by field name (views of the live arrays).

    Args:
        groups: The group tuples (:data:`GROUPS` order).
    """
    return {name: array for group in groups
            for name, array in zip(group._fields, group, strict=True) if name not in NOT_STORED}


# ---- scalars and switches of the compiled loop -------------------------------------------


# float scalars
F_T_CUR = 0  #: time of the last popped event [s]
F_T_END = 1  #: stop before events later than this [s]
F_FRAME_DT = 2  #: frame interval [s]
F_DISSIPATED = 3  #: energy the collision model took so far (hops: negative) [J]
F_LANDING_SPEED = 4  #: rebound speed below which a sphere stays on a plane [m/s]
F_CHI = 5  #: rolling-torque convention while sliding (hsgran.onplane CONVENTION_A/_B)
#: TC model (Luding & McNamara 1998) [s]: a collision of a sphere less than this after its
#: previous collision is elastic (e_n = 1; friction still acts), which ends the infinite
#: sequences of ever-smaller collisions of inelastic collapse in clusters; 0 turns it off
F_TC_TIME = 6
F_CLUSTER_LOSS = 7  #: energy the contact clusters took so far [J] (part of F_DISSIPATED)
#: mechanical energy (kinetic and potential, −m g·x) the spheres that left through an outlet
#: carried out of the system [J] (docs/open-systems.md)
F_EXITED = 8
#: mechanical energy the spheres inserted by inflows brought into the system [J]
F_ENTERED = 9
#: potential energy the wraps on periodic axes hid [J]: a sphere that wraps along an axis with
#: gravity moves by one box length in its stored position, not in its motion, so the potential
#: of the unwrapped positions is −Σ m g·x of the stored ones plus this
#: (docs/trajectory-format.md, "Observables")
F_UNWRAPPED = 10
F_SIZE = 11
# int scalars
I_SEQ = 0  #: next sequence number (tie-break)
I_N_FRAMES = 1  #: frames in the buffer
I_N_LOG = 2  #: event-log entries in the buffer
I_FRAME_INDEX = 3  #: index of the next frame (its time is index × frame_dt)
I_N_EVENTS = 4  #: events executed in total
I_COLLAPSED = 5  #: sphere that triggered the collapse guard, or −1
I_PEND_A = 6  #: a sphere whose next event must be predicted before the next pop, or −1
I_PEND_B = 7  #: a second one, or −1
I_PEND_LAYER = 8  #: the cell face that the sphere in I_PEND_A just crossed (EV_CELL), or −1
I_SWEEPS = 9  #: Gauss–Seidel sweeps of the cluster solves so far (hsgran._cluster; their cost)
I_SHORT = 10  #: cluster segments cut to the shortest (MIN_SEGMENT_REL)
I_UNSOLVED = 11  #: cluster force solves that ended short of the slack (not converged)
I_STEP_SWEEPS = 12  #: the part of I_SWEEPS spent on the steps' force solves
I_VISITS = 13  #: contacts visited by the cluster solves (sweeps × contacts: the solves' work)
#: cluster solves whose friction and rolling couples were frozen before they converged
#: (hsgran.contact.cluster.solve_polished: FRICTION_SWEEPS reached, or a stall)
I_FROZEN = 14
I_SIZE = 15
#: The cluster solves' counters, by the name runs report them under (``RunSummary`` fields,
#: the trajectory's stored summary, the corpus's columns): one place to add one.
SOLVER_COUNTS = {"solver_sweeps": I_SWEEPS, "solver_visits": I_VISITS, "solver_frozen": I_FROZEN}

# the sums of one frame interval (``obs``, hsgran._observe), observables on only
OB_MOMENT = 0  #: Σ b ⊗ J over the contacts' impulses [kg m²/s], 3 × 3 row-major (9 entries)
OB_N_PAIR = 9  #: sphere–sphere collisions
OB_N_WALL = 10  #: sphere–plane collisions
#: impulse the spheres gave each plane [N s], 3 per plane, then 3 for the support that could
#: not be traced to a plane
OB_WALL = 11


def obs_size(planes: int) -> int:
    """Entries of ``obs`` for a scene of ``planes`` planes."""
    return OB_WALL + 3 * (planes + 1)

# effect and engine switches: the ``flags`` argument, a bool array of FL_SIZE entries. They are
# run-time values, so one compiled loop serves every scene with gravity and one every scene
# without (a cold compile costs tens of seconds; gravity alone is a compile-time constant, see
# run_loop); a disabled effect is skipped by one predictable branch and its code never runs.
FL_PLASTICITY = 0  #: staged normal model (MODEL §3); else elastic Hertz
FL_FRICTION = 1  #: tangential impulse (MODEL §4)
FL_ROLLING = 2  #: rolling resistance (MODEL §5)
FL_ADHESION = 3  #: adhesion in recovery (MODEL §3.8)
FL_ROTATION = 4  #: spins are tracked
FL_GRAVITY = 5  #: parabolic flight, on-plane motion states
FL_LOG = 6  #: record every event in the log buffer
#: touching spheres and walls are solved as clusters (hsgran._cluster) instead of by the
#: pairwise rules of hsgran._settling (docs/enduring-contact.md)
FL_CLUSTERS = 7
FL_COMPLIANCE = 8  #: tangential compliance, beyond the paper (docs/model.md §4.5)
FL_VISCOUS = 9  #: viscoelastic damping, beyond the paper (docs/model.md §3.11)
FL_SIZE = 10

# What a prediction reads of a neighbour sits in one 64-byte row (one cache line) of ``st``:
S_X = 0  #: position x, y, z at the sphere's local time [m] (columns 0–2)
S_V = 3  #: velocity at the local time [m/s] (columns 3–5)
S_T = 6  #: local time: the stored state is valid at this instant [s]
S_R = 7  #: radius [m]
S_WIDTH = 8


# ---- allocation ----------------------------------------------------------------------------

#: Cache-line size [bytes] to which the per-sphere rows and records are aligned.
CACHE_LINE = 64

#: Each sphere's bookkeeping in one record of two cache lines (from LARGE_FROM spheres on, see
#: hsgran.engine), so that an event on a sphere fetches it in one go instead of one line from
#: each of a dozen arrays (at N = 10⁶ these arrays do not fit the cache and every separate array
#: costs a miss). The loop sees each field as an array of its own (a strided view), so its code
#: is the same as with separate arrays. First line: the pending event and the kept pair contact
#: (read at every pop and prediction); second line: the sphere's constants, collision history,
#: calendar position (``where``, ``qnext``, ``qprev``: hsgran.events.calendar) and cell.
SPHERE_RECORD = np.dtype({
    "names": ["ev_t", "ev_seq", "ev_pcount", "counter", "pc_t", "pc_count", "ev_partner",
              "pc_partner", "ev_kind", "inv_m", "inv_i", "t_last", "where", "mat", "zstreak",
              "rapid", "cell", "qnext", "qprev"],
    "formats": ["f8", "i8", "i8", "i8", "f8", "i8", "i4", "i4", "i1", "f8", "f8", "f8", "i8",
                "i4", "i4", "i4", ("i4", (3,)), "i4", "i4"],
    "offsets": [0, 8, 16, 24, 32, 40, 48, 52, 56, 64, 72, 80, 88, 96, 100, 104, 108, 120, 124],
    "itemsize": 2 * CACHE_LINE})

#: Fewest entries of a record field that the loop sees: numpy calls an array of one element
#: contiguous whatever its stride, and numba would compile a second loop for a one-sphere scene
#: (or for the one-entry dummies); below this the entries beyond the spheres are unused.
FIELD_MIN = 2


#: Most bodies a cluster of contacts solves together (hsgran._cluster): moving spheres beyond
#: are its boundary, moving as they were. The room is the scene's spheres up to this many
#: (4.4 kB of scratch each, for 16 contacts of 33 numbers; at most 290 MB, in pages the
#: system commits only as a solve first uses them). A boundary inside a connected bed holds
#: the bodies it touches as if immovable while they fall onto it, and such a step has no
#: solution: a silo of 12,150 beads whose flowing bed of ~7,000 exceeded the room of 4,096
#: it had until 2026-12-08 took 46–52 s of CPU a step and ended 7e-3 m/s short of its
#: targets; with the whole bed in the room, 3 s, met to 1e-12 m/s (docs/enduring-contact.md,
#: "The room is the scene").
MAX_CLUSTER_BODIES = 1 << 16
#: Room for contacts per body of a cluster: a sphere among spheres three times smaller touches
#: up to ~30 of them, but each contact is stored once, by the first of its two bodies, so a
#: cluster averages about 3 (half the coordination number of a pile) plus its walls.
CONTACTS_PER_BODY = 16
#: Contact forces kept per sphere to warm-start the next solve (hsgran._cluster): each pair is
#: kept once, by its lower sphere, so a sphere keeps about half its contacts (up to ~15 of the
#: ~30 a sphere among spheres three times smaller has) and its walls; a contact with no room
#: starts cold, which costs sweeps, not accuracy.
WARM_SLOTS = 16
#: Partner code of an empty warm-start slot (spheres are ≥ 0, planes −1 − w).
WARM_EMPTY = -(1 << 62)


@dataclass(frozen=True)
class Sizes:
    """The sizes every field's shape is made of (:data:`FIELDS`)."""

    n: int  #: spheres
    gravity: bool  #: the scene has gravity (motion states, on-plane segments)
    rotation: bool  #: spins are tracked
    planes: int  #: planes
    cells: int  #: cells of the grid
    row: int  #: length of a pair-table row (hsgran.materials P_*)
    frames: int  #: frames in the frame buffer
    log: int  #: entries in the event-log buffer
    #: contacts may be solved as clusters (scratch for them): with gravity, in either
    #: treatment (the pairwise rules' last resort, hsgran._cluster.hands_over)
    clusters: bool = False
    observables: bool = False  #: stress and wall impulses are summed (hsgran._observe)
    outlets: int = 0  #: outlets
    lines: int = 0  #: rows of the faces' outlines and holes (hsgran.facets)
    part_items: int = 0  #: entries of the parts' cell lists (0: no such parts)
    open_system: bool = False  #: spheres may leave or enter (outlets or inflows)
    #: gravity acts along a periodic axis: wraps change the stored positions' potential energy
    unwraps: bool = False

    def value(self, symbol) -> int:
        """The size a shape symbol stands for (an int stands for itself)."""
        if isinstance(symbol, int):
            return symbol
        n, g, r = self.n, self.gravity, self.rotation
        return {
            "n": n,
            "m": max(n, FIELD_MIN),  # per-sphere record fields the loop sees
            "e": n + 1,  # event entries: every sphere and the frame tick
            "g": n if g else 1,  # per sphere with gravity only
            "gr": n if g and r else 1,  # per sphere with gravity and rotation
            "r": n if r else 1,  # per sphere with rotation only
            "c": max(1 if g else n, FIELD_MIN),  # kept pair contacts: without gravity only
            "planes": self.planes, "cells": self.cells, "row": self.row,
            "frames": self.frames, "log": self.log,
            "fr": self.frames if r else 1,  # spin frames: with rotation only
            "nr": n if r else 1,
            # cluster scratch: bodies and contacts (with gravity only)
            "cb": min(n, MAX_CLUSTER_BODIES) if self.clusters else 1,
            "ck": CONTACTS_PER_BODY * min(n, MAX_CLUSTER_BODIES) if self.clusters else 1,
            "cn": n if self.clusters else 1,
            # observables (none when off: hsgran._observe tests the ledger's length)
            "on": n if self.observables else 0,
            "ob": obs_size(self.planes) if self.observables else 0,
            "fo": self.frames if self.observables else 0,
            # an open system: which spheres are present (none in a closed one)
            "outlets": self.outlets,
            "lines": max(self.lines, 1),
            "pi": self.part_items,
            "ps": self.cells + 1 if self.part_items else 0,
            "op": n if self.open_system else 0,
            "fp": self.frames if self.open_system else 0,
            # gravity along a periodic axis: the potential energy the wraps hid, per frame
            "fu": self.frames if self.unwraps else 0,
        }[symbol]


@dataclass(frozen=True)
class Field:
    """How one array of the engine state is allocated."""

    group: str  #: the named tuple it belongs to (``Flight`` …), or "calendar"
    name: str
    dtype: str
    shape: tuple  #: of :meth:`Sizes.value` symbols and ints
    fill: float = 0  #: initial value
    packed: bool = False  #: a :data:`SPHERE_RECORD` field (packed in records for large systems)
    aligned: bool = False  #: rows start on a cache-line boundary


def _f(group, name, dtype, shape, fill=0, packed=False, aligned=False):
    return Field(group, name, dtype, shape, fill, packed, aligned)


#: Every array of the engine state: the fields of the groups, in the groups' order, and the
#: calendar's per-entry links. One entry per array, so a new field is one line here (and one
#: name in its group).
FIELDS = (
    _f("Flight", "st", "f8", ("n", 8), aligned=True),
    _f("Flight", "counter", "i8", ("m",), packed=True),
    _f("Flight", "acc", "f8", ("g", 3)),
    _f("Flight", "mstate", "i1", ("g",)),
    _f("Flight", "mplane", "i4", ("g",), fill=-1),
    _f("Flight", "seg_end", "f8", ("g",), fill=np.inf),
    _f("Flight", "seg_code", "i1", ("g",)),
    _f("Flight", "seg_reach", "f8", ("g",), fill=-1.0),
    _f("Flight", "pc_t", "f8", ("c",), fill=np.inf, packed=True),
    _f("Flight", "pc_partner", "i4", ("c",), fill=-1, packed=True),
    _f("Flight", "pc_count", "i8", ("c",), packed=True),
    _f("Flight", "present", "i1", ("op",), fill=1),
    _f("Dyn", "omg", "f8", ("r", 3)),
    _f("Dyn", "inv_m", "f8", ("m",), packed=True),
    _f("Dyn", "inv_i", "f8", ("m",), packed=True),
    _f("Dyn", "mat", "i4", ("m",), packed=True),
    _f("Dyn", "zstreak", "i4", ("m",), packed=True),
    _f("Dyn", "alpha", "f8", ("gr", 3)),
    _f("Dyn", "seg_dir", "f8", ("g", 3)),
    _f("Dyn", "t_last", "f8", ("m",), fill=-np.inf, packed=True),
    _f("Dyn", "row_tc", "f8", ("row",)),
    _f("Dyn", "rapid", "i4", ("m",), packed=True),
    _f("Dyn", "led", "f8", ("on", 3)),
    _f("Dyn", "obs", "f8", ("ob",)),
    _f("Walls", "planes_p", "f8", ("planes", 3)),
    _f("Walls", "planes_n", "f8", ("planes", 3)),
    _f("Walls", "planes_mat", "i8", ("planes",)),
    _f("Walls", "planes_vel", "f8", ("planes", 3)),
    _f("Walls", "planes_omg", "f8", ("planes", 3)),
    _f("Walls", "planes_mot", "f8", ("planes", M_SIZE)),
    _f("Walls", "planes_kind", "i8", ("planes",)),
    _f("Walls", "planes_cyl", "f8", ("planes", CY_SIZE)),
    _f("Walls", "planes_geo", "f8", ("planes", GEO_SIZE)),
    _f("Walls", "face_lines", "f8", ("lines", 3)),
    _f("Walls", "n_global", "i8", (1,)),
    _f("Walls", "outlets", "f8", ("outlets", OL_SIZE)),
    _f("Space", "gravity", "f8", (3,)),
    _f("Space", "box_len", "f8", (3,)),
    _f("Space", "periodic", "?", (3,)),
    _f("Space", "slack", "f8", (1,)),
    _f("Grid", "origin", "f8", (3,)),
    _f("Grid", "csize", "f8", (3,)),
    _f("Grid", "ncell", "i8", (3,)),
    _f("Grid", "cell", "i4", ("m", 3), packed=True),
    _f("Grid", "head", "i4", ("cells",), fill=-1),
    _f("Grid", "nxt", "i4", ("n",), fill=-1),
    _f("Grid", "prv", "i4", ("n",), fill=-1),
    _f("Grid", "heads", "i4", (27,)),
    _f("Grid", "shifts", "f8", (27, 3)),
    _f("Grid", "ac", "i8", (3, 3)),
    _f("Grid", "ah", "f8", (3, 3)),
    _f("Grid", "stack", "i4", ("g",)),
    _f("Grid", "part_start", "i8", ("ps",)),
    _f("Grid", "part_items", "i8", ("pi",)),
    _f("Sched", "ev_t", "f8", ("e",), fill=np.inf, packed=True),
    _f("Sched", "ev_seq", "i8", ("e",), packed=True),
    _f("Sched", "ev_kind", "i1", ("e",), packed=True),
    _f("Sched", "ev_partner", "i4", ("e",), fill=-1, packed=True),
    _f("Sched", "ev_pcount", "i8", ("e",), packed=True),
    _f("calendar", "where", "i8", ("e",), packed=True),
    _f("calendar", "qnext", "i4", ("e",), packed=True),
    _f("calendar", "qprev", "i4", ("e",), packed=True),
    _f("Clus", "cl_body", "i4", ("cb",)),
    _f("Clus", "cl_loc", "i4", ("cn",), fill=-1),
    _f("Clus", "cl_was", "i1", ("cb",)),
    _f("Clus", "cl_depth", "i4", ("cb",)),
    _f("Clus", "cl_inv_m", "f8", ("cb",)),
    _f("Clus", "cl_inv_i", "f8", ("cb",)),
    _f("Clus", "cl_rad", "f8", ("cb",)),
    _f("Clus", "cl_v", "f8", ("cb", 3)),
    _f("Clus", "cl_w", "f8", ("cb", 3)),
    _f("Clus", "cl_a", "f8", ("cb", 3)),
    _f("Clus", "cl_al", "f8", ("cb", 3)),
    _f("Clus", "cl_root", "i4", ("cb",)),
    _f("Clus", "ck_a", "i8", ("ck",)),
    _f("Clus", "ck_b", "i8", ("ck",)),
    _f("Clus", "ck_q", "i8", ("ck",)),
    _f("Clus", "ck_mat", "i8", ("ck",)),
    _f("Clus", "ck_n", "f8", ("ck", 3)),
    _f("Clus", "ck_rb", "f8", ("ck",)),
    _f("Clus", "ck_vb", "f8", ("ck", 3)),
    _f("Clus", "ck_ab", "f8", ("ck", 3)),
    _f("Clus", "ck_gap", "f8", ("ck",)),
    _f("Clus", "ck_reb", "f8", ("ck",)),
    _f("Clus", "ck_tgt", "f8", ("ck",)),
    _f("Clus", "ck_mu", "f8", ("ck",)),
    _f("Clus", "ck_slip", "f8", ("ck", 3)),
    _f("Clus", "ck_mur", "f8", ("ck",)),
    _f("Clus", "ck_reff", "f8", ("ck",)),
    _f("Clus", "ck_rslip", "f8", ("ck", 3)),
    _f("Clus", "ck_pn", "f8", ("ck",)),
    _f("Clus", "ck_pt", "f8", ("ck", 3)),
    _f("Clus", "ck_hr", "f8", ("ck", 3)),
    _f("Clus", "wm_q", "i8", ("cn", WARM_SLOTS), fill=WARM_EMPTY),
    _f("Clus", "wm_f", "f8", ("cn", WARM_SLOTS, 6)),
    _f("Out", "fr_time", "f8", ("frames",)),
    _f("Out", "fr_pos", "f8", ("frames", "n", 3)),
    _f("Out", "fr_vel", "f8", ("frames", "n", 3)),
    _f("Out", "fr_omg", "f8", ("fr", "nr", 3)),
    _f("Out", "log_f", "f8", ("log", 7)),
    _f("Out", "log_i", "i8", ("log", 5)),
    _f("Out", "fr_ms", "i1", ("frames", "n")),
    _f("Out", "fr_obs", "f8", ("fo", "ob")),
    _f("Out", "fr_pres", "i1", ("fp", "op")),
    _f("Out", "fr_left", "f8", ("fp",)),
    _f("Out", "fr_in", "f8", ("fp",)),
    _f("Out", "fr_unwrap", "f8", ("fu",)),
)


def _aligned(shape, dtype) -> np.ndarray:
    """Zeroed array whose first element starts on a cache-line boundary."""
    count = int(np.prod(shape))
    item = np.dtype(dtype).itemsize
    buf = np.zeros(count * item + CACHE_LINE, dtype=np.uint8)
    off = -buf.ctypes.data % CACHE_LINE
    return buf[off:off + count * item].view(dtype).reshape(shape)


def _records(count: int) -> np.ndarray:
    """Zeroed :data:`SPHERE_RECORD` array whose first record starts a cache-line pair."""
    size = SPHERE_RECORD.itemsize
    buf = np.zeros((count + 1) * size, dtype=np.uint8)
    off = -buf.ctypes.data % size
    return buf[off:off + count * size].view(SPHERE_RECORD)


def allocate(sizes: Sizes, packed: bool) -> dict:
    """Every array of :data:`FIELDS`, by name, at its initial value.

    Args:
        sizes: The scene's sizes.
        packed: Pack the record fields into one :data:`SPHERE_RECORD` per entry (large
            systems; the loop then sees strided views), else one array per field.

    Returns:
        Arrays by field name (the calendar's links included).
    """
    rec = _records(max(sizes.value("m"), sizes.value("e"))) if packed else None
    arrays = {}
    for f in FIELDS:
        shape = tuple(sizes.value(s) for s in f.shape)
        if f.packed and packed:
            a = rec[f.name][:shape[0]]
        elif f.aligned:
            a = _aligned(shape, f.dtype)
        else:
            a = np.zeros(shape, dtype=f.dtype)
        if f.fill:
            a[...] = f.fill
        arrays[f.name] = a
    return arrays


def groups_of(arrays: dict, calendar) -> tuple:
    """The group tuples (:data:`GROUPS`) over ``arrays`` (by field name) and the event
    calendar; the tuples hold references, so the compiled loop updates the arrays in place."""
    return tuple(group(*(calendar if name == "cal" else arrays[name] for name in group._fields))
                 for group in GROUPS)
