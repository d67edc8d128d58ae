"""The simulation: builds the state from a scene and drives the compiled event loop (layer 5).

How a run proceeds (:meth:`Simulation.run`)::

    build state (struct of arrays; angular velocities only with `rotation`)
    predict every sphere's next event; schedule the frame tick at t = 0; build the event calendar
    repeat, in compiled code (hsgran._loop.run_loop):
        pop the earliest entry
        frame tick  -> sample every sphere's parabola at that time into the frame buffer
        stale pair  -> the partner had an event since: re-predict the owner only
        cell exit   -> move the sphere to its new cell (wrap on periodic axes), re-predict it
        collision   -> advance the one or two spheres, apply the collision model, bump their
                       counters, re-predict them
        stop when the buffer is full, the event budget is spent, or the next event is past t_end
    between compiled calls: hand full buffers to the observers, update the progress bar,
        take a checkpoint when one is due, stop early when asked to (an interrupt)

Observers are plain objects with any of ``on_frames(block)``, ``on_events(block)``,
``on_checkpoint(checkpoint)`` and ``on_finish(summary)``; the engine never imports a writer or
a renderer.

Checkpoints (:meth:`Simulation.checkpoint`, :meth:`Simulation.restore`) hold every array the
compiled loop reads or writes, except the event calendar: it is rebuilt from each sphere's
pending event (time, sequence number), whose order is total, so a restored run pops the same
events in the same order and continues bit for bit. They are taken only between compiled
calls, when no event is half done and every buffered frame has been handed to the observers;
where the calls are cut does not change the run (a call that stops at a checkpoint time leaves
no pending re-prediction behind, and the next one starts from the same pending events).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hsgran import _loop as ev
from hsgran import _state as es
from hsgran._cluster import slack
from hsgran._exchange import enter_sphere, sphere_energy
from hsgran._flight import MAX_ZERO_TIME_EVENTS
from hsgran._state import FIELDS, SOLVER_COUNTS, Sizes, allocate, groups_of, stored_fields
from hsgran.contact import compliance, viscous
from hsgran.contact.model import REC_SIZE
from hsgran.errors import HsgranError
from hsgran.events.calendar import calendar_build, new_calendar
from hsgran.events.grid import cell_coordinates, insert_all, part_lists, plan_grid, remove, slot_of
from hsgran.inflow import place_batch
from hsgran.materials import P_E_FIXED, P_VISC, SOLID_SPHERE_INERTIA
from hsgran.onplane import CONVENTION_A, CONVENTION_B
from hsgran.shapes import tables
from hsgran.wallspec import WK_CYLINDER, WK_MOVING, cylinder_bounds

#: Bytes of frame buffer the engine may hold; frames are handed to observers when it is full.
FRAME_BUFFER_BYTES = 32 * 2**20
#: Most frames buffered at once (1000-frame blocks append at ~1e6 frames/s in h5py,
#: docs/architecture.md §4).
FRAME_BUFFER_MAX = 1000
#: Event-log entries buffered before they are handed to observers.
LOG_BUFFER = 1 << 16
#: Events of any kind (collisions, cell crossings, motion-state changes, frames, stale and
#: missed events) popped per compiled call between progress updates. It bounds how long an
#: interrupt waits for the engine to notice it (~0.2 s at 1e6 events/s), also in runs where
#: cell crossings outnumber collisions.
EVENTS_PER_CALL = 200_000
#: Contact visits of the cluster solves (hsgran._cluster; ``Simulation.isc[I_VISITS]``) after
#: which a compiled call returns too: where events are solves of a dense bed in constrained
#: motion (~10⁵–10⁶ visits each), EVENTS_PER_CALL of them took half an hour, and ``stop``,
#: the progress bar and the checkpoints by wall time waited as long. 10⁸ visits are ~0.1–0.5 s
#: of solving on these machines.
VISITS_PER_CALL = 100_000_000
#: Version of the checkpoint layout (:meth:`Simulation.checkpoint`); a checkpoint of another
#: version is refused rather than misread (2: the pair contacts kept for cell crossings; 3: the
#: "wedge" event count; 4: per-sphere fields at least FIELD_MIN long; 5: arrays named by field,
#: hsgran._state, scratch space no longer stored; 6: the "cluster" event count, the cluster
#: slack ``Space.slack`` and the cluster scalars; 7: the observables' ledger and sums; 8: the
#: planes' prescribed motions ``planes_mot``; 9: the walls' kinds and the cylinders,
#: ``planes_kind`` and ``planes_cyl``; 10: the cluster solves' warm-start forces ``wm_q`` and
#: ``wm_f``; 11: open systems: the outlets and each sphere's presence, ``outlets`` and
#: ``present``, the energy carried out and brought in, ``F_EXITED`` and ``F_ENTERED``, and the
#: inflows' progress ``inflow_state``; 12: the finite walls and fixed spheres, ``planes_geo``
#: and ``face_lines``, and the edges' column ``CY_FINITE`` of ``planes_cyl``; 13: the count
#: of walls every prediction looks at ``n_global``, in place of their rows; 14: the cluster
#: solves' warm-start forces under gravity with either treatment, since the pairwise rules
#: hand zero-time sequences over to cluster solves; 15: the count of cluster solves whose
#: friction was frozen unconverged, ``I_FROZEN``; 16: constrained motion in steps, each
#: sphere's ``seg_reach``); 17: the potential energy the wraps on periodic axes hid,
#: ``F_UNWRAPPED``.
CHECKPOINT_VERSION = 17


class SimulationError(HsgranError):
    """The run cannot continue (for example inelastic collapse without a remedy)."""


@dataclass
class FrameBlock:
    """Frames sampled exactly at the frame times (SI units).

    Each field besides ``step`` and ``time`` has its entry in ``hsgran.io.h5md.FRAME_FIELDS``,
    which says where the trajectory file stores it (tests/io checks that the two agree).
    """

    step: np.ndarray  #: frame index (F,)
    time: np.ndarray  #: [s] (F,)
    position: np.ndarray  #: [m] (F, N, 3)
    velocity: np.ndarray  #: [m/s] (F, N, 3)
    angular_velocity: np.ndarray | None  #: [rad/s] (F, N, 3), None without rotation
    kinetic_translational: np.ndarray  #: Σ ½ m v² [J] (F,)
    kinetic_rotational: np.ndarray | None  #: Σ ½ I ω² [J] (F,)
    #: −Σ m g·x [J] (F,); with gravity along a periodic axis, of the unwrapped positions (the
    #: stored ones' plus what the wraps hid), so it falls steadily as a chute flows
    potential: np.ndarray
    #: energy dissipated since t = 0 [J] (F,): the initial mechanical energy minus the present
    #: one (:meth:`Simulation.mechanical_energy`), so it counts every loss: collisions, sliding
    #: friction and rolling resistance on planes, landings and spheres put to rest
    dissipated: np.ndarray
    motion_state: np.ndarray  #: ``hsgran.onplane.MS_*`` of every sphere (F, N) int8
    # With ``[output] observables`` (else None), the sums over the interval each frame closes
    # (from the previous frame; zero at the first), hsgran._observe:
    #: Σ b ⊗ J over every impulse a sphere took at a contact [kg m²/s] (F, 3, 3)
    impulse_moment: np.ndarray | None = None
    #: impulse each plane took from the spheres [N s] (F, planes, 3)
    wall_impulse: np.ndarray | None = None
    #: support impulse not traced to a plane [N s] (F, 3)
    unresolved_impulse: np.ndarray | None = None
    #: pair and plane collisions (F, 2) int64
    collisions: np.ndarray | None = None
    # With outlets or inflows (else None; docs/open-systems.md): spheres not in the system
    # (left, or not yet inserted) have NaN positions,
    # velocities and spins and motion state hsgran.onplane.MS_ABSENT, and
    #: each sphere's identifier (its index), −1 while it is not in the system (F, N) int64
    id: np.ndarray | None = None
    #: mechanical energy the spheres that left carried out of the system until the frame [J]
    #: (F,); the dissipated energy does not count it
    exited: np.ndarray | None = None
    #: mechanical energy the spheres inserted by inflows brought in until the frame [J] (F,)
    entered: np.ndarray | None = None


@dataclass
class EventBlock:
    """Executed collisions (the event log); ``hsgran.io.h5md.EVENT_FIELDS`` stores each field."""

    time: np.ndarray  #: [s]
    kind: np.ndarray  #: event kind code: the logged rows of hsgran.events.kinds.KINDS
    i: np.ndarray  #: sphere index
    j: np.ndarray  #: partner sphere, or −1 − w for plane w
    normal_impulse: np.ndarray  #: J_n [N s]
    tangential_impulse: np.ndarray  #: J_t [N s]
    e_n: np.ndarray  #: normal restitution [-]
    stage: np.ndarray  #: normal-model stage code (kinds 7, 8, 11: the new motion state)
    regime: np.ndarray  #: tangential regime (kinds 7, 8, 11: what ended the last segment)
    #: sphere i's velocity right after the event [m/s] (E, 3) (kind 13, exit: the velocity it
    #: left the system with)
    velocity: np.ndarray

    @classmethod
    def concatenate(cls, blocks) -> EventBlock:
        """One block holding ``blocks`` in order (empty arrays when there are none)."""
        names = cls.__dataclass_fields__
        if not blocks:
            return cls(**{k: np.zeros((0, 3) if k == "velocity" else 0) for k in names})
        return cls(**{k: np.concatenate([getattr(b, k) for b in blocks]) for k in names})


@dataclass
class RunSummary:
    """What a run did."""

    events: dict = field(default_factory=dict)  #: counts by kind (pair, wall, cell, frame, stale)
    simulated_time: float = 0.0  #: [s]
    wall_time: float = 0.0  #: [s]
    collisions: int = 0  #: pair + wall events
    events_per_second: float = 0.0  #: all executed events (collisions and cell crossings) / s
    interrupted: bool = False  #: the run stopped early because ``stop()`` said so
    notes: list = field(default_factory=list)  #: what a user should know about the scene
    #: Gauss–Seidel sweeps of the cluster solves (docs/enduring-contact.md, "Clusters of
    #: contacts") and the contacts they visited (sweeps × contacts): the treatment's work
    #: (these three are the counters named in hsgran._state.SOLVER_COUNTS)
    solver_sweeps: int = 0
    solver_visits: int = 0
    #: of those solves, how many froze their friction and rolling couples before these had
    #: converged (``FRICTION_SWEEPS`` reached, or a stall): friction holds there only to the
    #: accuracy its sweeps reached
    solver_frozen: int = 0

    def lines(self) -> list[str]:
        """Human-readable summary."""
        by_kind = ", ".join(f"{k} {v:,}" for k, v in self.events.items() if v)
        solver = ([f"cluster solves: {self.solver_sweeps:,} sweeps, "
                   f"{self.solver_visits:,} contact visits, friction frozen unconverged in "
                   f"{self.solver_frozen:,}"] if self.solver_visits else [])
        return [f"events: {by_kind or 'none'}"] + solver + [
            f"simulated time {self.simulated_time:.6g} s, wall time {self.wall_time:.3f} s, "
            f"{self.events_per_second:,.0f} events/s"] + [f"note: {n}" for n in self.notes]


#: The note of a scene with gravity whose collisions lose no normal energy.
LOSSLESS_NOTE = ("no collision loses normal energy (no restitution below 1, no plasticity, "
                 "adhesion or viscoelastic damping): under gravity the spheres bounce for ever "
                 "unless friction stops them")


def scene_notes(scene, pair_table: np.ndarray) -> list[str]:
    """What a user should know about a scene before trusting its run: today, whether it has
    gravity but no normal losses (docs/model.md §3.9: without restitution and plasticity the
    collisions are elastic)."""
    eff = scene.effects
    if not eff.gravity or eff.plasticity or eff.adhesion:
        return []
    rows = pair_table.reshape(-1, pair_table.shape[-1])
    rows = rows[~np.isnan(rows[:, P_E_FIXED])]
    fixed = rows[:, P_E_FIXED]
    if np.any((fixed >= 0.0) & (fixed < 1.0)):
        return []
    if eff.viscoelastic_damping and np.any(rows[:, P_VISC] > 0.0):
        return []
    return [LOSSLESS_NOTE]


@dataclass
class Checkpoint:
    """A complete restart state of a :class:`Simulation` (see the module notes).

    Attributes:
        arrays: Every state array by field name (hsgran._state: ``st``, ``counter``, …,
            ``ev_pcount``, and ``fsc``, ``isc``, ``counts``, ``rec``); copies, not views.
        time: Time of the last processed event, or the end of the last call [s].
        frames: Frames handed to the observers so far.
        events: Event-log entries handed to the observers so far.
        version: :data:`CHECKPOINT_VERSION` of the layout.
    """

    arrays: dict
    time: float
    frames: int
    events: int
    version: int = CHECKPOINT_VERSION


def _mechanical(kin_t, kin_r, pot):
    """Kinetic (translational and, when given, rotational) plus potential energy [J]."""
    return kin_t + (kin_r if kin_r is not None else 0.0) + pot


#: Spheres from which a scene is run as a large system: the per-sphere fields packed in records
#: (SPHERE_RECORD), an event calendar with time buckets (hsgran.events.calendar) and prefetch
#: hints in the loop. Below, everything fits the cache: each field is an array of its own, every
#: event stays in one heap, and there are no hints, all of which would only cost time there
#: (measured with tools/bench_engine.py). The compiled loop has a version for each kind (a
#: second compile for the first large scene).
LARGE_FROM = 1 << 16


def _flags(eff, log_events: bool, clusters: bool = False) -> np.ndarray:
    """The loop's switches (hsgran._state FL_*) for an effect set (``clusters``: the scene's
    enduring-contact treatment is "clusters", which needs gravity)."""
    flags = np.zeros(es.FL_SIZE, dtype=np.bool_)
    for k, on in ((es.FL_PLASTICITY, eff.plasticity), (es.FL_FRICTION, eff.friction),
                  (es.FL_ROLLING, eff.rolling_resistance), (es.FL_ADHESION, eff.adhesion),
                  (es.FL_ROTATION, eff.rotation), (es.FL_GRAVITY, eff.gravity),
                  (es.FL_LOG, log_events), (es.FL_CLUSTERS, clusters and eff.gravity),
                  (es.FL_COMPLIANCE, eff.tangential_compliance),
                  (es.FL_VISCOUS, eff.viscoelastic_damping)):
        flags[k] = bool(on)
    return flags


def _grid_plan(scene, brute_force: bool):
    """(origin [m], cell size [m], cells per axis, box length on periodic axes [m]) of the cell
    grid (hsgran.events.grid.plan_grid): cells at least one largest diameter wide over the box,
    or over the spheres when there is none; one cell per axis for the all-pairs mode."""
    periodic = np.array(scene.periodic, dtype=np.bool_)
    radius = np.asarray(scene.radius, dtype=np.float64)
    if scene.box_lower is not None:
        lower = np.asarray(scene.box_lower, dtype=np.float64)
        upper = np.asarray(scene.box_upper, dtype=np.float64)
    else:
        pos = np.asarray(scene.position, dtype=np.float64)
        lower = np.nanmin(pos - radius[:, None], axis=0, initial=np.inf)
        upper = np.nanmax(pos + radius[:, None], axis=0, initial=-np.inf)
        for f in scene.inflows:  # where its spheres will appear (absent rows are NaN)
            lower = np.minimum(lower, f.lower)
            upper = np.maximum(upper, f.upper)
        for c in scene.cylinders:  # the spheres inside a cylinder may go anywhere in it
            if c.inside:
                lo, hi = cylinder_bounds(c.center, c.row())
                lower = np.minimum(lower, lo)
                upper = np.maximum(upper, hi)
    box_len = np.where(periodic, upper - lower, 0.0)
    origin, csize, ncell = plan_grid(lower, upper, periodic, 2.0 * float(radius.max()), scene.n)
    if brute_force:
        csize = csize * ncell
        ncell = np.ones(3, dtype=np.int64)
    elif np.any(periodic & (ncell < 3)):
        raise SimulationError("a periodic axis needs at least 3 cells of one largest diameter")
    return origin, csize, ncell, box_len


#: The box of a part of a finite wall is grown by the largest radius and this share of it
#: more [-] before it is listed in the cells it meets (events.grid.part_lists): a centre a
#: radius away from the part, rounded by ~1e-16 of its coordinates, is still inside it.
PART_REACH_REL = 1e-9


def _wall_lists(scene, origin, csize, ncell):
    """(G, the parts' cell lists ``start``, ``items``): the first G walls (planes, cylinders
    and unbounded faces, which the scene puts first among its parts) are looked at always, the
    other parts of finite walls (and the fixed spheres) through the cells their box meets,
    grown by the largest radius (events.grid.part_lists)."""
    n_global = len(scene.planes) + len(scene.cylinders)
    local, lower, upper = [], [], []
    reach = float(np.max(scene.radius)) * (1.0 + PART_REACH_REL)
    for k, q in enumerate(scene.parts, start=len(scene.planes) + len(scene.cylinders)):
        box = q.bounds()
        if box is None:
            if local:  # (_predict.near_wall relies on the order)
                raise SimulationError("the faces without outline must come first among the "
                                      "scene's parts (hsgran.scene._make_parts orders them so)")
            n_global += 1
        else:
            local.append(k)
            lower.append(box[0] - reach)
            upper.append(box[1] + reach)
    if not local:
        return n_global, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    start, items = part_lists(np.array(lower), np.array(upper), origin, csize, ncell,
                              np.asarray(scene.periodic, dtype=bool))
    return n_global, start, np.array(local, dtype=np.int64)[items]


def _fill_from_scene(a: dict, scene, mass: np.ndarray) -> None:
    """Write the scene's values into freshly allocated state arrays (hsgran._state.allocate):
    the spheres' rows, spins, inverse masses, materials, accelerations, the planes, gravity,
    the periodic axes, and every sphere's cell and place in the cell lists (the grid's
    geometry, ``origin``, ``csize``, ``ncell``, is already set)."""
    n = scene.n
    st = a["st"]
    st[:, es.S_X:es.S_X + 3] = scene.position
    st[:, es.S_V:es.S_V + 3] = scene.velocity
    st[:, es.S_R] = scene.radius
    radius = st[:, es.S_R]
    if scene.effects.rotation:
        a["omg"][:] = scene.angular_velocity
    a["inv_m"][:n] = 1.0 / mass
    a["inv_i"][:n] = 1.0 / (SOLID_SPHERE_INERTIA * mass * radius**2)
    a["mat"][:n] = scene.material
    a["gravity"][:] = scene.gravity
    a["acc"][:] = a["gravity"]
    a["periodic"][:] = scene.periodic
    for k, p in enumerate(scene.planes):  # the wall rows: planes, then cylinders
        a["planes_p"][k] = p.point
        a["planes_n"][k] = p.normal
        a["planes_mat"][k] = p.material
        if p.motion is not None:
            a["planes_mot"][k] = p.motion
            a["planes_kind"][k] = WK_MOVING
    for k, c in enumerate(scene.cylinders, start=len(scene.planes)):
        a["planes_p"][k] = c.center
        a["planes_mat"][k] = c.material
        a["planes_kind"][k] = WK_CYLINDER
        a["planes_cyl"][k] = c.row()
    if scene.parts:  # the parts of finite walls and the fixed spheres (hsgran.shapes)
        rows = slice(len(scene.planes) + len(scene.cylinders), None)
        t = tables(scene.parts)
        a["planes_p"][rows], a["planes_n"][rows], a["planes_kind"][rows] = (t.point, t.normal,
                                                                             t.kind)
        a["planes_cyl"][rows], a["planes_geo"][rows] = t.cyl, t.geo
        a["planes_mat"][rows] = [q.material for q in scene.parts]
        a["face_lines"][:len(t.lines)] = t.lines
    for k, o in enumerate(scene.outlets):
        a["outlets"][k] = o.row
    present = _present(scene)
    if scene.open_system:
        a["present"][:] = present
    cell = a["cell"][:n]
    # a sphere not in the system (an inflow's, NaN) is in no cell list
    cell[:] = cell_coordinates(np.where(present[:, None], st[:, es.S_X:es.S_X + 3], a["origin"]),
                               a["origin"], a["csize"], a["ncell"], a["periodic"])
    insert_all(cell, a["head"], a["nxt"], a["prv"], a["ncell"])
    for i in np.flatnonzero(~present):
        remove(i, slot_of(cell[i, 0], cell[i, 1], cell[i, 2], a["ncell"]), a["head"], a["nxt"],
               a["prv"])


def _present(scene) -> np.ndarray:
    """Which spheres are in the system at t = 0 (N,) bool."""
    return (np.ones(scene.n, dtype=bool) if scene.present is None
            else np.asarray(scene.present, dtype=bool))


class Simulation:
    """An event-driven run of a :class:`~hsgran.scene.Scene`.

    Args:
        scene: The validated scene.
        brute_force: Test every pair instead of using the cell grid (for cross-checks; O(N²)):
            the grid then has one cell per axis, which holds every sphere.
        log_events: Record every collision (see :class:`EventBlock`).
        frame_buffer: Frames buffered between observer calls (default from
            :data:`FRAME_BUFFER_BYTES`).
        large: Run as a large system (see :data:`LARGE_FROM`; default: from that many
            spheres on). The events and their order are the same either way; only the speed
            differs (for tests and benchmarks).
    """

    def __init__(self, scene, *, brute_force: bool = False, log_events: bool = False,
                 frame_buffer: int | None = None, large: bool | None = None):
        self.scene = scene
        eff = scene.effects
        n = scene.n
        self.n = n
        self.rotation = bool(eff.rotation)
        self.log_events = bool(log_events)
        clusters = scene.treatment == "clusters"
        self.flags = _flags(eff, self.log_events, clusters)
        if eff.tangential_compliance:
            compliance.check_table()
        if eff.viscoelastic_damping:
            viscous.check_table()
        self.mass = np.ascontiguousarray(scene.mass(), dtype=np.float64)  # [kg]
        self.inertia = SOLID_SPHERE_INERTIA * self.mass * scene.radius**2  # [kg m²]
        self.pair_table = np.ascontiguousarray(scene.pair_table())
        self.notes = scene_notes(scene, self.pair_table)  #: see RunSummary.notes
        origin, csize, ncell, box_len = _grid_plan(scene, brute_force)
        n_global, part_start, part_items = _wall_lists(scene, origin, csize, ncell)
        per_frame = max(1, n * 3 * 8 * (3 if self.rotation else 2) + n)  # + motion states
        sizes = Sizes(n=n, gravity=bool(eff.gravity), rotation=self.rotation,
                      planes=len(scene.walls), cells=int(np.prod(ncell)),
                      row=self.pair_table.shape[-1],
                      frames=frame_buffer or max(1, min(FRAME_BUFFER_MAX,
                                                        FRAME_BUFFER_BYTES // per_frame)),
                      log=LOG_BUFFER if self.log_events else 1,
                      clusters=bool(eff.gravity),
                      observables=bool(scene.observables), outlets=len(scene.outlets),
                      lines=sum(len(q.lines) for q in scene.parts),
                      part_items=len(part_items),
                      open_system=scene.open_system, unwraps=scene.unwraps)
        if large is None:
            large = n >= LARGE_FROM
        a = allocate(sizes, packed=large)
        a["origin"][:], a["csize"][:], a["ncell"][:], a["box_len"][:] = (origin, csize, ncell,
                                                                          box_len)
        _fill_from_scene(a, scene, self.mass)
        a["n_global"][0] = n_global
        if len(part_items):
            a["part_start"][:], a["part_items"][:] = part_start, part_items
        if eff.gravity:  # (cluster solves: the treatment's, or the pairwise rules' last resort)
            a["slack"][0] = slack(scene.effective_landing_speed)
        # one pending event per sphere, entry n is the frame tick
        calendar = new_calendar(n + 1, a["where"], a["qnext"], a["qprev"], buckets=large)
        self._groups = groups_of(a, calendar)
        self._expose(a, n, calendar)
        #: mechanical energy of the scene as given [J] (before spheres are put on planes)
        self.energy0 = float(_mechanical(*self._energies(
            self.pos[None], self.vel[None], self.omg[None] if self.rotation else None,
            _present(scene)[None]))[0])
        #: each inflow's next batch and the spheres it has inserted (hsgran.inflow)
        self.inflow_state = np.zeros((len(scene.inflows), 2), dtype=np.int64)
        #: which spheres have been in the system (the inflows' rows count once inserted)
        self.entered = (_present(scene) if scene.inflows else np.zeros(0, dtype=bool)).astype(
            np.int8)
        # scratch of an insertion: the neighbours of the sphere that enters
        self._around = np.zeros(n if scene.inflows else 0, dtype=np.int64)
        self.fsc = np.zeros(es.F_SIZE)
        self.fsc[es.F_FRAME_DT] = scene.frame_interval
        self.fsc[es.F_LANDING_SPEED] = scene.effective_landing_speed
        self.fsc[es.F_CHI] = (CONVENTION_A if scene.rolling_convention == "A" else CONVENTION_B)
        self.fsc[es.F_TC_TIME] = scene.tc_time
        self.isc = np.zeros(es.I_SIZE, dtype=np.int64)
        self.isc[es.I_COLLAPSED] = -1
        self.isc[es.I_PEND_A] = self.isc[es.I_PEND_B] = self.isc[es.I_PEND_LAYER] = -1
        self.counts = np.zeros(len(ev.EVENT_NAMES), dtype=np.int64)
        self.rec = np.zeros(REC_SIZE)
        self._frames_emitted = 0
        self._events_emitted = 0
        # the frame tick at t = 0 goes first among simultaneous entries (lowest sequence number)
        self.ev_t[n] = 0.0
        self.ev_seq[n] = 0
        self.isc[es.I_SEQ] = 1
        flight, dyn, walls, space, grid, sched = self._groups[:6]
        ev.init(flight, dyn, walls, space, grid, sched, self.pair_table, self.fsc, self.isc,
                self.flags)
        if scene.observables:
            # each sphere's momentum ledger starts at t = 0 (hsgran._observe)
            self.led[:] = self.mass[:, None] * self.vel

        # compile (or load from the cache) now, so run() times only the run: with t_end < 0
        # the loop returns before touching any event
        self.fsc[es.F_T_END] = -1.0
        self._call(1)

    def _expose(self, a: dict, n: int, calendar) -> None:
        """The state arrays as attributes, each with one entry per sphere (per-sphere record
        fields are longer for the loop, see hsgran._state.FIELD_MIN); views, not copies."""
        for f in FIELDS:
            if f.group != "calendar":
                setattr(self, f.name, a[f.name])
        for name in ("counter", "inv_m", "inv_i", "mat", "zstreak", "t_last", "rapid", "cell"):
            setattr(self, name, a[name][:n])
        nc = 1 if self.scene.effects.gravity else n
        for name in ("pc_t", "pc_partner", "pc_count"):
            setattr(self, name, a[name][:nc])
        self.calendar = calendar
        # one 64-byte row per sphere: position, velocity, local time, radius (hsgran._state S_*)
        self.state = a["st"]
        self.pos = self.state[:, es.S_X:es.S_X + 3]
        self.vel = self.state[:, es.S_V:es.S_V + 3]
        self.t_loc = self.state[:, es.S_T]
        self.radius = self.state[:, es.S_R]

    @property
    def time(self) -> float:
        """Time of the last processed event [s]."""
        return float(self.fsc[es.F_T_CUR])

    @property
    def collisions(self) -> int:
        """Collisions (pair and wall events) executed so far."""
        return int(self.isc[es.I_N_EVENTS])

    def state_at(self, t: float):
        """Positions [m] and velocities [m/s] of all spheres at time ``t`` ≥ the last event
        (NaN for spheres that have left the system, as in the frames)."""
        dt = (t - self.t_loc)[:, None]
        g = self.acc if self.scene.effects.gravity else self.gravity[None, :]
        pos, vel = self.pos + dt * (self.vel + 0.5 * g * dt), self.vel + g * dt
        if self.scene.open_system:
            gone = self.present == 0
            pos[gone] = np.nan
            vel[gone] = np.nan
        return pos, vel

    def _energies(self, pos, vel, omg, present=None):
        """(translational, rotational or None, potential) energy of frames [J], each (F,), of
        the spheres in the system (``present`` (F, N), or all).

        Potential energy is −Σ m g·x of the given positions (zero at the origin); on a periodic
        axis along which gravity acts the callers add what the wraps hid (``F_UNWRAPPED``).
        """
        if present is not None:
            keep = present[..., None].astype(bool)
            pos = np.where(keep, pos, 0.0)
            vel = np.where(keep, vel, 0.0)
            omg = None if omg is None else np.where(keep, omg, 0.0)
        kin_t = 0.5 * np.einsum("n,fnk,fnk->f", self.mass, vel, vel)
        kin_r = (0.5 * np.einsum("n,fnk,fnk->f", self.inertia, omg, omg)
                 if omg is not None else None)
        pot = -np.einsum("n,fnk,k->f", self.mass, pos, self.gravity)
        return kin_t, kin_r, pot

    def energies_at(self, t: float | None = None):
        """(translational, rotational or None, potential) energy of all spheres at ``t`` ≥ the
        last event (default: the time of the last event) [J]; spins turn on planes."""
        t = self.time if t is None else t
        pos, vel = self.state_at(t)
        omg = None
        if self.rotation:
            omg = self.omg + (self.alpha * (t - self.t_loc)[:, None]
                              if self.scene.effects.gravity else 0.0)
        kin_t, kin_r, pot = self._energies(pos[None], vel[None],
                                           None if omg is None else omg[None],
                                           self.present[None] if self.scene.open_system else None)
        if self.scene.unwraps:
            pot = pot + self.fsc[es.F_UNWRAPPED]
        return float(kin_t[0]), None if kin_r is None else float(kin_r[0]), float(pot[0])

    def solver_counts(self) -> dict:
        """The cluster solves' counters so far, by name (``_state.SOLVER_COUNTS``)."""
        return {k: int(self.isc[i]) for k, i in SOLVER_COUNTS.items()}

    def mechanical_energy(self, t: float | None = None) -> float:
        """Kinetic (both kinds) plus potential energy of all spheres at ``t`` [J] (see
        :meth:`energies_at`)."""
        return float(_mechanical(*self.energies_at(t)))

    @property
    def collision_loss(self) -> float:
        """Energy the collision model took so far [J] (part of :meth:`dissipated_energy`;
        hops count negative)."""
        return float(self.fsc[es.F_DISSIPATED])

    @property
    def exited_energy(self) -> float:
        """Mechanical energy the spheres that left through an outlet carried out so far [J]
        (docs/open-systems.md)."""
        return float(self.fsc[es.F_EXITED])

    @property
    def entered_energy(self) -> float:
        """Mechanical energy the spheres inserted by inflows brought in so far [J]."""
        return float(self.fsc[es.F_ENTERED])

    def dissipated_energy(self, t: float | None = None) -> float:
        """Energy dissipated since t = 0, up to ``t`` [J]: the initial mechanical energy and
        what inflows brought in, minus that at ``t`` and what the spheres that left carried out
        (see :class:`FrameBlock`)."""
        return (self.energy0 + self.entered_energy - self.mechanical_energy(t)
                - self.exited_energy)

    def _call(self, max_collisions: int) -> int:
        """Run the compiled loop for at most ``max_collisions`` collisions, at most
        :data:`EVENTS_PER_CALL` events of any kind and about :data:`VISITS_PER_CALL` contact
        visits of the cluster solves (the event that passes it ends the call)."""
        return ev.run_loop(*self._groups, self.pair_table, self.fsc, self.isc, self.counts,
                           max_collisions, EVENTS_PER_CALL, VISITS_PER_CALL, self.rec,
                           self.flags)

    def _frame_block(self) -> FrameBlock | None:
        f = int(self.isc[es.I_N_FRAMES])
        if f == 0:
            return None
        pos = self.fr_pos[:f].copy()
        vel = self.fr_vel[:f].copy()
        omg = self.fr_omg[:f].copy() if self.rotation else None
        open_system = self.scene.open_system
        present = self.fr_pres[:f].astype(bool) if open_system else None
        exited = self.fr_left[:f].copy() if open_system else None
        entered = self.fr_in[:f].copy() if open_system else None
        kin_t, kin_r, pot = self._energies(pos, vel, omg, present)
        if self.scene.unwraps:
            pot = pot + self.fr_unwrap[:f]
        dissipated = self.energy0 - _mechanical(kin_t, kin_r, pot)
        if open_system:
            dissipated = dissipated + entered - exited
        step = np.arange(self._frames_emitted, self._frames_emitted + f, dtype=np.int64)
        self._frames_emitted += f
        self.isc[es.I_N_FRAMES] = 0
        block = FrameBlock(step, self.fr_time[:f].copy(), pos, vel, omg, kin_t, kin_r, pot,
                           dissipated, self.fr_ms[:f].copy())
        if self.scene.observables:
            sums = self.fr_obs[:f]
            planes = len(self.scene.walls)
            block.impulse_moment = sums[:, es.OB_MOMENT:es.OB_MOMENT + 9].reshape(f, 3, 3).copy()
            block.wall_impulse = sums[:, es.OB_WALL:es.OB_WALL + 3 * planes].reshape(
                f, planes, 3).copy()
            block.unresolved_impulse = sums[:, -3:].copy()
            block.collisions = np.rint(sums[:, [es.OB_N_PAIR, es.OB_N_WALL]]).astype(np.int64)
        if open_system:
            block.id = np.where(present, np.arange(self.n), -1)
            block.exited = exited
            block.entered = entered
        return block

    def _event_block(self) -> EventBlock | None:
        m = int(self.isc[es.I_N_LOG])
        if m == 0:
            return None
        f, i = self.log_f[:m], self.log_i[:m]
        self.isc[es.I_N_LOG] = 0
        self._events_emitted += m
        return EventBlock(f[:, 0].copy(), i[:, 0].astype(np.int8), i[:, 1].copy(),
                          i[:, 2].copy(), f[:, 1].copy(), f[:, 2].copy(), f[:, 3].copy(),
                          i[:, 3].astype(np.int8), i[:, 4].astype(np.int8), f[:, 4:7].copy())

    def _state_arrays(self) -> dict:
        """The arrays a checkpoint holds, by field name (views of the live arrays)."""
        arrays = stored_fields(self._groups)
        arrays.update(fsc=self.fsc, isc=self.isc, counts=self.counts, rec=self.rec,
                      inflow_state=self.inflow_state, entered=self.entered)
        return arrays

    def checkpoint(self) -> Checkpoint:
        """A restart state of the run as it stands (call between runs or from ``on_checkpoint``).

        Returns:
            A :class:`Checkpoint` whose arrays are copies.

        Raises:
            SimulationError: frames or log entries are still buffered (they belong to the
                observers before a checkpoint can describe what they have received).
        """
        if self.isc[es.I_N_FRAMES] or self.isc[es.I_N_LOG]:
            raise SimulationError("checkpoint with buffered frames or events: flush them first")
        return Checkpoint({k: a.copy() for k, a in self._state_arrays().items()},
                          self.time, self._frames_emitted, self._events_emitted)

    def checkpoint_layout(self) -> dict:
        """Shape and dtype of every checkpoint array, by name (for writers that preallocate)."""
        return {k: (a.shape, a.dtype) for k, a in self._state_arrays().items()}

    def restore(self, checkpoint: Checkpoint) -> None:
        """Continue from ``checkpoint``: copy its arrays in and rebuild the event calendar.

        Args:
            checkpoint: Taken from a simulation of the same scene (and event logging).

        Raises:
            SimulationError: the checkpoint's version, names, shapes or types do not match.
        """
        if checkpoint.version != CHECKPOINT_VERSION:
            raise SimulationError(f"checkpoint version {checkpoint.version} is not "
                                  f"{CHECKPOINT_VERSION}, the one this hsgran reads")
        live = self._state_arrays()
        if set(checkpoint.arrays) != set(live):
            missing = sorted(set(live) ^ set(checkpoint.arrays))
            raise SimulationError(f"checkpoint does not match the scene (arrays {missing})")
        for name, target in live.items():
            source = np.asarray(checkpoint.arrays[name])
            if source.shape != target.shape or source.dtype != target.dtype:
                raise SimulationError(
                    f"checkpoint does not match the scene: {name} is {source.dtype}"
                    f"{list(source.shape)}, expected {target.dtype}{list(target.shape)}")
        for name, target in live.items():
            target[...] = checkpoint.arrays[name]
        sched = self._groups[5]
        calendar_build(sched.cal, sched.ev_t, sched.ev_seq, 0.0)
        self._frames_emitted = int(checkpoint.frames)
        self._events_emitted = int(checkpoint.events)

    def _next_batch(self) -> float:
        """Time of the next inflow batch [s] (inf without one to come)."""
        times = [f.batch_time(int(k)) for f, (k, done) in zip(self.scene.inflows,
                                                            self.inflow_state, strict=True)
                 if not f.exhausted(int(done))]
        return min(times, default=math.inf)

    def _insert_batches(self, t: float) -> None:
        """Insert every inflow batch due at time t [s] (hsgran.inflow): place its spheres
        clear of the walls and of the spheres in the system, and let them in
        (hsgran._exchange.enter_sphere)."""
        scene = self.scene
        flight, dyn, walls, space, grid, sched = self._groups[:6]
        grav_on = bool(scene.effects.gravity)
        self.fsc[es.F_T_CUR] = t
        for f, state in zip(scene.inflows, self.inflow_state, strict=True):
            k, done = int(state[0]), int(state[1])
            if f.exhausted(done) or f.batch_time(k) > t:
                continue
            rows = self._waiting_rows(f)[:max(0, f.target(k) - done)]
            if rows.size == 0:
                state[0] = k + 1
                continue
            pos, _ = self.state_at(t)
            here = self.present == 1
            placed, velocity = place_batch(f, k, scene.seed, self.radius[rows], pos[here],
                                           self.radius[here], scene.space)
            for i, x, v in zip(rows, placed, velocity, strict=True):
                if np.isnan(x[0]):
                    continue  # no room this time: it waits for the next batch
                if self.present[i]:  # a sphere in the cell lists twice would loop them
                    raise SimulationError(f"inflow {f.key}: sphere {i} is already in the system")
                self.state[i, es.S_X:es.S_X + 3] = x
                self.state[i, es.S_V:es.S_V + 3] = v
                self.state[i, es.S_T] = t
                if self.rotation:
                    self.omg[i] = 0.0
                enter_sphere(int(i), t, flight, dyn, walls, space, grid, sched, self.isc,
                             grav_on, self.rotation, self._around)
                self.entered[i] = 1
                self.fsc[es.F_ENTERED] += sphere_energy(int(i), self.state, self.omg,
                                                        self.inv_m, self.inv_i, self.gravity,
                                                        self.rotation)
                done += 1
            state[0], state[1] = k + 1, done

    def _waiting_rows(self, f) -> np.ndarray:
        """The rows an inflow inserts next, lowest first: its own not yet inserted, or (when
        recirculating) the spheres that have left."""
        if not f.recirculate:
            return f.rows[0] + np.flatnonzero(self.entered[f.rows[0]:f.rows[1]] == 0)
        return np.flatnonzero((self.present == 0) & (self.entered == 1))

    def _checkpoint(self, observers) -> None:
        self._flush(observers)
        wanted = [ob for ob in observers if hasattr(ob, "on_checkpoint")]
        if wanted:
            ck = self.checkpoint()
            for ob in wanted:
                ob.on_checkpoint(ck)

    def _flush(self, observers) -> None:
        frames = self._frame_block()
        if frames is not None:
            for ob in observers:
                if hasattr(ob, "on_frames"):
                    ob.on_frames(frames)
        events = self._event_block()
        if events is not None:
            for ob in observers:
                if hasattr(ob, "on_events"):
                    ob.on_events(events)

    def run(self, until: float | None = None, *, max_collisions: int | None = None,
            observers=(), progress: bool = False, checkpoint_every: float | None = None,
            checkpoint_wall: float | None = None,
            stop: Callable[[], bool] | None = None) -> RunSummary:
        """Run until time ``until`` [s] (default: the scene's duration) or a collision count.

        Args:
            until: End time [s]; frames are sampled at every multiple of the frame interval up
                to and including it.
            max_collisions: Stop after this many more collisions (pair and wall events).
            observers: Objects with optional ``on_frames``, ``on_events``, ``on_checkpoint``,
                ``on_finish``.
            progress: Show a tqdm progress bar over simulated time.
            checkpoint_every: Hand a checkpoint to the observers at every multiple of this
                simulated time [s] (``None``: not by simulated time).
            checkpoint_wall: ... and whenever this much wall time [s] has passed since the
                last one (``None``: not by wall time). A checkpoint is also handed over when the
                run reaches ``until`` and when ``stop`` ends it.
            stop: Called between compiled calls (at most :data:`EVENTS_PER_CALL` events, or
                about :data:`VISITS_PER_CALL` contact visits of the cluster solves, apart); when
                it returns True the run flushes, hands over a checkpoint and returns with
                ``interrupted`` set.

        Returns:
            :class:`RunSummary` of this call.

        Raises:
            SimulationError: the collapse guard stopped the run (see ``hsgran._loop``).
        """
        t_end = self.scene.duration if until is None else float(until)
        counts0 = self.counts.copy()
        solver0 = self.solver_counts()
        done0 = self.collisions
        t_ck = (math.inf if not checkpoint_every
                else (math.floor(self.time / checkpoint_every) + 1) * checkpoint_every)
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=t_end, unit="s(sim)", bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g}"
                       " s [{elapsed}<{remaining}{postfix}]")
        wall0 = time.perf_counter()
        wall_ck = wall0
        interrupted = finished = False
        try:
            while True:
                budget = EVENTS_PER_CALL
                if max_collisions is not None:
                    budget = min(budget, max_collisions - (self.collisions - done0))
                    if budget <= 0:
                        break
                # a call ends at the next checkpoint time, where cutting the run changes
                # nothing, and at an inflow's next batch (inserted between calls)
                t_in = self._next_batch()
                self.fsc[es.F_T_END] = min(t_end, t_ck, t_in)
                status = self._call(budget)
                if status == ev.STATUS_DONE and t_in <= min(t_end, t_ck):
                    self._insert_batches(t_in)
                    continue
                if status in (ev.STATUS_FRAMES_FULL, ev.STATUS_LOG_FULL):
                    self._flush(observers)
                if bar is not None:
                    bar.n = min(self.time, t_end)
                    bar.set_postfix_str(f"{self.collisions:,} collisions", refresh=True)
                if status == ev.STATUS_COLLAPSE:
                    i = int(self.isc[es.I_COLLAPSED])
                    raise SimulationError(
                        f"sphere {i} had more than {MAX_ZERO_TIME_EVENTS} collisions without "
                        f"time advancing at t = {self.time:.9g} s (inelastic collapse)")
                if status == ev.STATUS_DONE and t_ck >= t_end:
                    self.fsc[es.F_T_CUR] = max(self.time, t_end)
                    finished = True
                    break
                if stop is not None and stop():
                    interrupted = True
                    break
                if status == ev.STATUS_DONE:  # at a checkpoint time
                    t_ck += checkpoint_every
                    self._checkpoint(observers)
                    wall_ck = time.perf_counter()
                elif (checkpoint_wall is not None
                      and time.perf_counter() - wall_ck >= checkpoint_wall):
                    self._checkpoint(observers)
                    wall_ck = time.perf_counter()
        finally:
            if bar is not None:
                bar.close()
            self._flush(observers)  # whatever ends the run, buffered frames and events reach disk
        if finished or interrupted:
            self._checkpoint(observers)
        wall = time.perf_counter() - wall0
        d = self.counts - counts0
        names = ev.EVENT_NAMES
        events = {names[k]: int(d[k]) for k in range(1, len(names))}
        executed = events["pair"] + events["wall"] + events["cell"]
        summary = RunSummary(events=events, simulated_time=min(self.time, t_end), wall_time=wall,
                             collisions=events["pair"] + events["wall"],
                             events_per_second=executed / wall if wall > 0 else math.inf,
                             interrupted=interrupted, notes=list(self.notes),
                             **{k: v - solver0[k] for k, v in self.solver_counts().items()})
        for ob in observers:
            if hasattr(ob, "on_finish"):
                ob.on_finish(summary)
        return summary
