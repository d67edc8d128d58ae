"""Trajectory files in H5MD 1.1 (HDF5 for molecular data): :class:`TrajectoryWriter` and
:func:`read_trajectory`.

The layout, every attribute and every unit are described for users in
``docs/trajectory-format.md``; this docstring only gives the reasons behind the choices.

* Frames are buffered by the caller and appended in blocks (docs/architecture.md §4): every
  dataset is created once, chunked along time and resizable, compressed with ``lzf`` + shuffle
  (lossless, so a round trip is bit for bit).
* Every per-frame dataset comes from one table, :data:`FRAME_FIELDS`, which the writer, the
  reader and :func:`copy_frames` all walk, so a new frame quantity cannot be written and then
  forgotten by the reader or by resume.
* ``step`` and ``time`` exist once, in ``/particles/all/position``; every other time-dependent
  element (velocity, angular velocity, box edges, observables) hard-links them, which H5MD 1.1
  allows for elements sampled together and requires for the box.
* A killed writer leaves a readable file. The file is written in HDF5's single-writer /
  multiple-reader (SWMR) mode, which flushes metadata in an order that keeps the file on disk
  valid at every instant (without it, 9 of 25 files killed at random moments while appending
  would not open; with it 25 of 25 did). It is flushed after every append; the value datasets of
  a block are written before ``step``/``time``, and the reader takes the number of frames as the
  shortest time-dependent dataset, so a block cut in half is dropped whole.
  ``/parameters/hsgran@complete`` is ``False`` until :meth:`TrajectoryWriter.close`. A killed
  SWMR writer leaves a mark in the superblock that makes plain HDF5 readers refuse the file;
  :func:`read_trajectory` then opens it in SWMR-read mode, and ``hsgran run --resume`` writes
  it anew without the mark.
* Checkpoints (``/hsgran/checkpoint``) live in two preallocated slots written in turn; the
  ``index`` dataset (serial number, slot) is written last, in one 16-byte write after the slot
  was flushed and synced to disk, so a writer killed while it writes a checkpoint leaves the
  previous one intact and named.
* The box ``edges`` are a time-dependent element (one row per frame, constant) rather than a
  time-independent dataset, because MDAnalysis (2.x) reads ``box/edges/value[frame]`` whenever
  ``edges`` exists. They are written only when some axis is periodic: H5MD lets ``edges`` be
  omitted when every boundary is ``none``, and MDAnalysis would otherwise take a walled box for a
  periodic cell and apply minimum images through solid walls. The walls' corners are always in
  ``/parameters/hsgran@box_lower``/``box_upper``.
* The walls are stored as simulated (``/parameters/hsgran/walls``), not only as scene text:
  re-parsing the text would lose the overrides, and a scene of an older version may no
  longer parse. The engine's pair table is stored so that a resume can tell whether it would
  use the same contact laws.
* ``unit`` attributes are variable-length ASCII strings in H5MD unit notation (``m s-1``);
  MDAnalysis looks them up as Python strings, which fixed-length (bytes) attributes are not.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import h5py
import numpy as np

from hsgran.errors import InputError
from hsgran.shapes import Part, tables
from hsgran.system import available_memory
from hsgran.wallspec import (
    CY_FINITE,
    CY_RADIUS,
    CY_SIZE,
    FC_HOLE,
    FC_LINES,
    FC_NHOLE,
    GEO_SIZE,
    M_DIR,
    M_KIND,
    M_SIZE,
    MOT_FIXED,
    WK_BALL,
    WK_CYLINDER,
    WK_FACE,
    WK_MOVING,
    WK_PLANE,
    wall_shift,
)

#: H5MD specification version the files conform to (``/h5md@version``).
H5MD_VERSION = (1, 1)
#: Version of the H5MD ``units`` module whose unit strings we write.
UNITS_MODULE_VERSION = (1, 0)
#: Version of hsgran's own layout (``/parameters/hsgran@format_version``); bump it on any change
#: a reader must know about.
FORMAT_VERSION = 2

PARTICLES = "particles/all"
OBSERVABLES = "observables"
PARAMETERS = "parameters/hsgran"
EVENTS = "hsgran/events"
CHECKPOINT = "hsgran/checkpoint"
#: Group of :class:`Walls` and dataset of the pair table, in ``PARAMETERS``.
WALLS = "walls"
PAIR_TABLE = "pair_table"
#: What h5py and numpy raise on a damaged file (bad links, checksums, shapes, decompression,
#: absurd sizes); each is turned into a one-line :class:`~hsgran.errors.InputError`.
DAMAGED = (KeyError, ValueError, TypeError, OSError, RuntimeError, IndexError, AttributeError,
           MemoryError)
#: What HDF5 says when a plain open meets the mark of a SWMR writer (running or killed).
SWMR_MARK = "already open for write"
#: Suffix of a file while its layout is being made (see :class:`TrajectoryWriter`).
PART_SUFFIX = ".part"

#: Target size of one chunk [bytes]. lzf + shuffle runs several times faster on 64 KiB chunks
#: than on 1 MiB ones (measured: 1000-frame blocks of 10 particles, flushed after each block,
#: ~70 k vs ~17 k frames/s), partly because a chunk that a block leaves half full is compressed
#: again at every flush until it is full; the per-chunk overhead of HDF5 is still negligible.
CHUNK_BYTES = 1 << 16
#: Most rows per chunk (1-D series: step, time, energies, events; 4096 doubles = 32 KiB).
SERIES_CHUNK_ROWS = 4096
#: Chunk cache per dataset [bytes]: holds the half-full last chunk between two blocks, so it is
#: not read back and decompressed when the next block fills it.
CHUNK_CACHE_BYTES = 1 << 20
COMPRESSION = "lzf"

#: Units in H5MD's unit notation (units module, "SI" system).
UNIT_LENGTH = "m"
UNIT_VELOCITY = "m s-1"
UNIT_ANGULAR_VELOCITY = "rad s-1"
UNIT_MASS = "kg"
UNIT_ENERGY = "J"
UNIT_TIME = "s"
UNIT_IMPULSE = "kg m s-1"

#: Stands for the number of particles in :attr:`FrameField.shape`.
PER_PARTICLE = "N"
#: Shape symbol: the number of plane walls (:class:`Walls`).
PER_WALL = "W"
UNIT_IMPULSE_MOMENT = "kg m2 s-1"


@dataclass(frozen=True)
class FrameField:
    """Where and how one per-frame quantity is stored (an entry of :data:`FRAME_FIELDS`).

    Attributes:
        path: The H5MD time-dependent element that holds it; its ``value`` dataset is the data,
            its ``step`` and ``time`` are hard links to the position's.
        unit: H5MD unit string, or ``None`` for codes.
        dtype: Type stored.
        shape: Shape of one frame's row, :data:`PER_PARTICLE` standing for N and
            :data:`PER_WALL` for the number of planes.
        switch: Argument of :class:`TrajectoryWriter` that turns the field on
            (``angular_velocity``, ``motion_state``, ``observables``, ``open_system``), or
            ``None`` when every file has it.
        fill: The HDF5 fill value of its ``value`` dataset, or ``None`` (``id``: −1 marks a
            particle that is not in the system, as H5MD 1.1 provides).
    """

    path: str
    unit: str | None
    dtype: type
    shape: tuple
    switch: str | None = None
    fill: int | float | None = None

    def row_shape(self, n_particles: int, n_walls: int = 0) -> tuple:
        """Shape of one frame's row for ``n_particles`` particles and ``n_walls`` planes."""
        size = {PER_PARTICLE: n_particles, PER_WALL: n_walls}
        return tuple(size.get(d, d) for d in self.shape)


#: Every per-frame quantity besides ``step`` and ``time``, by its name in a block of frames
#: (:class:`hsgran.engine.FrameBlock`, :meth:`TrajectoryWriter.append_frames`). The writer
#: creates, checks and appends, and :func:`read_trajectory` and :func:`copy_frames` read, what
#: this table lists: a new frame quantity is a field of the block and one entry here (and, for
#: an element under ``particles/all``, the :class:`Trajectory` attribute of the same name).
#: The order is that of the appends; ``position`` comes first because it owns the clock.
FRAME_FIELDS = {
    "position": FrameField(f"{PARTICLES}/position", UNIT_LENGTH, np.float64, (PER_PARTICLE, 3)),
    "velocity": FrameField(f"{PARTICLES}/velocity", UNIT_VELOCITY, np.float64,
                           (PER_PARTICLE, 3)),
    "angular_velocity": FrameField(f"{PARTICLES}/angular_velocity", UNIT_ANGULAR_VELOCITY,
                                   np.float64, (PER_PARTICLE, 3), "angular_velocity"),
    "motion_state": FrameField(f"{PARTICLES}/motion_state", None, np.int8, (PER_PARTICLE,),
                               "motion_state"),
    "kinetic_translational": FrameField(f"{OBSERVABLES}/kinetic_energy_translational",
                                        UNIT_ENERGY, np.float64, ()),
    "kinetic_rotational": FrameField(f"{OBSERVABLES}/kinetic_energy_rotational", UNIT_ENERGY,
                                     np.float64, (), "angular_velocity"),
    "potential": FrameField(f"{OBSERVABLES}/potential_energy", UNIT_ENERGY, np.float64, ()),
    "dissipated": FrameField(f"{OBSERVABLES}/dissipated_energy", UNIT_ENERGY, np.float64, ()),
    # sums over the interval that each frame closes (docs/observables.md)
    "impulse_moment": FrameField(f"{OBSERVABLES}/impulse_moment", UNIT_IMPULSE_MOMENT,
                                 np.float64, (3, 3), "observables"),
    "wall_impulse": FrameField(f"{OBSERVABLES}/wall_impulse", UNIT_IMPULSE, np.float64,
                               (PER_WALL, 3), "observables"),
    "unresolved_impulse": FrameField(f"{OBSERVABLES}/unresolved_support_impulse", UNIT_IMPULSE,
                                     np.float64, (3,), "observables"),
    "collisions": FrameField(f"{OBSERVABLES}/collisions", None, np.int64, (2,), "observables"),
    # in an open system (outlets or inflows, docs/open-systems.md): each particle's identifier,
    # −1 (the dataset's fill value) while it is not in the system, and the energy the particles
    # that left carried out and the inserted ones brought in
    "id": FrameField(f"{PARTICLES}/id", None, np.int64, (PER_PARTICLE,), "open_system",
                     fill=-1),
    "exited": FrameField(f"{OBSERVABLES}/exited_energy", UNIT_ENERGY, np.float64, (),
                         "open_system"),
    "entered": FrameField(f"{OBSERVABLES}/entered_energy", UNIT_ENERGY, np.float64, (),
                          "open_system"),
}
#: The element whose ``step`` and ``time`` datasets every other element links to.
CLOCK = "position"
#: Observable name in the file → field of a block of frames (:data:`FRAME_FIELDS`): the
#: energies (:attr:`Trajectory.energies`) and the interval sums (:attr:`Trajectory.sums`).
ENERGY_OBSERVABLES = {
    spec.path.rsplit("/", 1)[1]: name
    for name, spec in FRAME_FIELDS.items()
    if spec.path.startswith(OBSERVABLES + "/") and spec.unit == UNIT_ENERGY
}
SUM_OBSERVABLES = {
    spec.path.rsplit("/", 1)[1]: name
    for name, spec in FRAME_FIELDS.items()
    if spec.path.startswith(OBSERVABLES + "/") and spec.switch == "observables"
}

#: Event-log datasets: name → (dtype, unit or None); each has one scalar per event, except
#: those in :data:`EVENT_ROWS`.
EVENT_FIELDS = {
    "time": (np.float64, UNIT_TIME),
    "kind": (np.int8, None),
    "i": (np.int64, None),
    "j": (np.int64, None),
    "normal_impulse": (np.float64, UNIT_IMPULSE),
    "tangential_impulse": (np.float64, UNIT_IMPULSE),
    "e_n": (np.float64, None),
    "stage": (np.int8, None),
    "regime": (np.int8, None),
    "velocity": (np.float64, UNIT_VELOCITY),
}
#: Event-log datasets with a row per event, by name: the row's shape.
EVENT_ROWS = {"velocity": (3,)}

#: HDF5 file-format bounds: SWMR needs the 1.10 format (h5py 3 / HDF5 1.10 or newer to read).
LIBVER = ("v110", "latest")

_ASCII = h5py.string_dtype("ascii")
_UTF8 = h5py.string_dtype("utf-8")


@dataclass
class Walls:
    """The walls a run simulated, one row each: the planes (box faces and cylinder caps
    included), then the cylinders, then the parts of finite walls and the fixed spheres
    (faces, edges, corners, balls: docs/walls.md, "Finite walls").

    Attributes:
        point: A point of each plane, the middle of each cylinder's axis [m], shape (W, 3).
        normal: Unit normal of each plane [-], shape (W, 3), pointing to where spheres live
            (zeros for a cylinder).
        material: Material index of each wall, shape (W,), into the material names.
        key: Key path of each wall in the scene (``walls[0]``, ``walls[1].lower_z``).
        motion: Each plane's prescribed motion, shape (W, 8): the ``M_*`` columns of
            :mod:`hsgran.wallspec` (kind 0 for a fixed plane; ``point`` is the plane at t = 0).
        cylinder: Each cylinder's geometry, shape (W, CY_SIZE): the ``CY_*`` columns of
            :mod:`hsgran.wallspec` (radius 0 for a plane; an edge of a finite wall has radius
            0 and ``CY_FINITE`` 1), or ``None`` without cylinders or edges (files before the
            edges have 7 columns, read with ``CY_FINITE`` 0).
        kind: Each wall's ``WK_*`` code of :mod:`hsgran.wallspec`, shape (W,), or ``None``
            without finite walls.
        geometry: Each face's ``FC_*`` and each ball's ``BL_RADIUS`` values, shape
            (W, GEO_SIZE); a face's ``FC_LINES`` and ``FC_HOLE`` are rows of ``lines``.
        lines: The faces' outlines and holes, rows (a, b, c) of a u + b v ≤ c, shape (L, 3).
    """

    point: np.ndarray
    normal: np.ndarray
    material: np.ndarray
    key: list[str]
    motion: np.ndarray | None = None
    cylinder: np.ndarray | None = None
    kind: np.ndarray | None = None
    geometry: np.ndarray | None = None
    lines: np.ndarray | None = None

    def is_cylinder(self, k: int) -> bool:
        """Whether wall k is a cylinder wall (not an edge of a finite wall)."""
        return self.cylinder is not None and self.cylinder[k, CY_RADIUS] > 0.0

    def is_part(self, k: int) -> bool:
        """Whether wall k is a face, an edge or a corner of a finite wall, or a fixed
        sphere."""
        return self.kind is not None and (
            int(self.kind[k]) in (WK_FACE, WK_BALL)
            or (self.cylinder is not None and self.cylinder[k, CY_FINITE] != 0.0))

    def part(self, k: int):
        """Wall k as a :class:`hsgran.shapes.Part` (if :meth:`is_part`)."""
        geo = self.geometry[k].copy()
        lines = np.zeros((0, 3))
        if int(self.kind[k]) == WK_FACE:
            start = int(geo[FC_LINES])
            stop = int(geo[FC_HOLE]) + int(geo[FC_NHOLE])
            lines = self.lines[start:stop]
            geo[FC_LINES] -= start
            geo[FC_HOLE] -= start
        part = Part(int(self.kind[k]), self.point[k], self.normal[k], geo,
                    self.cylinder[k] if self.cylinder is not None else np.zeros(CY_SIZE), lines,
                    int(self.material[k]), self.key[k], np.zeros((0, 3)))
        if part.kind == WK_FACE:
            return replace(part, corners=part.outline())
        return part

    def shift(self, k: int, t: float) -> np.ndarray:
        """How far plane k has moved at time t [s] [m], shape (3,)."""
        if self.motion is None or self.motion[k, M_KIND] == MOT_FIXED:
            return np.zeros(3)
        return self.motion[k, M_DIR:M_DIR + 3] * wall_shift(self.motion, k, float(t))

    @classmethod
    def of(cls, walls) -> Walls:
        """The walls of ``walls`` (:attr:`hsgran.scene.Scene.walls`): planes with ``point``,
        ``normal``, ``motion``, ``material`` and ``key`` attributes, and cylinders with
        ``center`` and ``row()`` in their place (:class:`hsgran.scene.Cylinder`)."""
        walls = list(walls)
        point, normal, motion, cylinder, kind = [], [], [], [], []
        parts = [w for w in walls if isinstance(w, Part)]  # (the last rows)
        for w in walls:
            is_cyl = hasattr(w, "row")
            is_part = isinstance(w, Part)
            point.append(w.center if is_cyl else w.point)
            normal.append(np.zeros(3) if is_cyl else w.normal)
            motion.append(np.zeros(M_SIZE) if is_cyl or w.motion is None else w.motion)
            cylinder.append(w.row() if is_cyl else w.cyl if is_part else np.zeros(CY_SIZE))
            kind.append(w.kind if is_part else WK_CYLINDER if is_cyl else
                        WK_PLANE if w.motion is None else WK_MOVING)
        has_cyl = WK_CYLINDER in kind
        t = tables(parts) if parts else None
        return cls(point=np.array(point, dtype=np.float64).reshape(-1, 3),
                   normal=np.array(normal, dtype=np.float64).reshape(-1, 3),
                   material=np.array([w.material for w in walls], dtype=np.int32),
                   key=[str(w.key) for w in walls],
                   motion=np.array(motion, dtype=np.float64).reshape(-1, M_SIZE),
                   cylinder=(np.array(cylinder, dtype=np.float64).reshape(-1, CY_SIZE)
                             if has_cyl else None),
                   kind=np.array(kind, dtype=np.int8) if parts else None,
                   geometry=(np.concatenate([np.zeros((len(walls) - len(parts), GEO_SIZE)),
                                             t.geo]) if parts else None),
                   lines=t.lines if parts else None)

    def __len__(self) -> int:
        return int(self.point.shape[0])


@dataclass
class Trajectory:
    """Everything :func:`read_trajectory` finds in a trajectory file (SI units).

    Attributes:
        time: Frame times [s], shape (F,).
        step: Frame numbers, shape (F,), int64.
        position: Positions [m], shape (F, N, 3).
        velocity: Velocities [m/s], shape (F, N, 3).
        angular_velocity: Angular velocities [rad/s], shape (F, N, 3), or ``None`` when the
            scene had no ``rotation``.
        radius: Radii [m], shape (N,).
        mass: Masses [kg], shape (N,).
        material: Material index of each particle, shape (N,), into ``material_names``.
        material_names: Material names.
        box_lower: Lower corner of the box [m], shape (3,), or ``None`` without a box.
        box_upper: Upper corner of the box [m], shape (3,), or ``None`` without a box.
        periodic: Periodicity of the x, y, z axes.
        energies: Observable name → values [J], shape (F,): ``kinetic_energy_translational``,
            ``potential_energy``, ``dissipated_energy``, with rotation
            ``kinetic_energy_rotational`` and in an open system ``exited_energy`` (carried out
            by the particles that left) and ``entered_energy`` (brought in by inflows).
        events: Event-log field → array, shape (E,), or ``None`` when events were not logged.
        scene_text: The scene file, verbatim.
        effects: Effects of the run.
        seed: Random seed of the run.
        version: hsgran version that wrote the file.
        summary: Run summary (empty when the writer did not finish).
        complete: ``False`` when the writer was interrupted before closing the file.
        creator_args: Command line or arguments of the run, as recorded.
        motion_state: Motion state of every particle in every frame, shape (F, N), int8
            (``hsgran.onplane.MS_*``: 0 flight, 1 sliding, 2 rolling, 3 at rest on a plane,
            4 asleep on another sphere), or ``None`` when the file has none.
        walls: The plane walls the run simulated, or ``None`` when the file does not hold them
            (written before they were stored, or by a writer not given them).
        scene_name: Name of the scene as run ("" when the file does not hold it).
        overrides: Key path → value changes the scene was run with.
        pair_table: The contact-law parameters of every pair of materials the engine used,
            shape (M, M, K) (``hsgran.materials.pair_row``), or ``None`` when not stored.
        sums: With ``[output] observables``, the sums over the interval each frame closes, by
            observable name (``impulse_moment`` [kg m²/s] (F, 3, 3), ``wall_impulse`` [N s]
            (F, W, 3), ``unresolved_support_impulse`` [N s] (F, 3), ``collisions`` (F, 2):
            pair, plane); empty otherwise. :mod:`hsgran.observables` turns them into stress,
            pressure and wall forces.
        id: In an open system (outlets or inflows, docs/open-systems.md), each particle's
            identifier (its index) in every frame, shape (F, N), int64, −1 while it is not in
            the system (its position, velocity and spin are then NaN); ``None`` otherwise (see
            :attr:`present`).
    """

    time: np.ndarray
    step: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray | None
    radius: np.ndarray
    mass: np.ndarray
    material: np.ndarray
    material_names: list[str]
    box_lower: np.ndarray | None
    box_upper: np.ndarray | None
    periodic: tuple[bool, bool, bool]
    energies: dict[str, np.ndarray]
    events: dict[str, np.ndarray] | None
    scene_text: str
    effects: list[str]
    seed: int
    version: str
    summary: dict
    complete: bool = True
    creator_args: str = ""
    motion_state: np.ndarray | None = None
    walls: Walls | None = None
    scene_name: str = ""
    overrides: dict = field(default_factory=dict)
    pair_table: np.ndarray | None = None
    sums: dict[str, np.ndarray] = field(default_factory=dict)
    id: np.ndarray | None = None

    @property
    def present(self) -> np.ndarray:
        """Whether each particle is in the system in each frame, shape (F, N) bool (all, unless
        the scene has outlets or inflows)."""
        if self.id is None:
            return np.ones(self.position.shape[:2], dtype=bool)
        return self.id >= 0

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return int(self.time.shape[0])

    @property
    def n_particles(self) -> int:
        """Number of particles N."""
        return int(self.radius.shape[0])


class TrajectoryWriter:
    """Writes an H5MD 1.1 file; frames are buffered by the caller and appended in blocks.

    The whole layout is created here, empty; :meth:`append_frames` and :meth:`append_events`
    grow it. Use it as a context manager, or call :meth:`close`: only then is the file marked
    complete. Leaving a ``with`` block through an exception closes the file unmarked.

    Args:
        path: File to create (overwritten if it exists).
        radius: Particle radii [m], shape (N,).
        mass: Particle masses [kg], shape (N,).
        material: Material index of each particle, shape (N,), int, into ``material_names``.
        material_names: Material names.
        box_lower: Lower corner of the box [m], shape (3,), or ``None`` for no box.
        box_upper: Upper corner of the box [m], shape (3,), or ``None`` for no box.
        periodic: Periodicity of the x, y, z axes (3 bools); a periodic axis needs a box.
        angular_velocity: Whether frames carry angular velocities and rotational energy.
        scene_text: The scene file, stored verbatim.
        effects: Effects of the run.
        seed: Random seed of the run.
        version: hsgran version.
        log_events: Whether to create the event log (:meth:`append_events`).
        creator_args: Command line or arguments of the run, for the record.
        motion_state: Whether frames carry every particle's motion state.
        observables: Whether frames carry the interval sums (docs/observables.md).
        open_system: Whether particles may leave or enter the system: frames carry each
            particle's ``id`` (−1 while it is absent) and the energy carried out and brought in
            (docs/open-systems.md).
        checkpoint_layout: Shape and dtype of every checkpoint array by name (two slots are
            preallocated, see :meth:`write_checkpoint`), or ``None`` for no checkpoints.
        overrides: Key path → value changes the scene was run with (JSON-serialisable).
        walls: The plane walls simulated (with the overrides applied), or ``None`` to store
            none (readers then fall back to the scene text).
        scene_name: Name of the scene as run.
        pair_table: The engine's contact-law parameters of every pair of materials, shape
            (M, M, K) with M material names, or ``None``; ``hsgran run --resume`` compares it
            with the one it would use.

    Raises:
        InputError: The file cannot be created, or a periodic axis has no box.
        ValueError: Arrays of the wrong shape or content.
    """

    def __init__(
        self,
        path,
        *,
        radius,
        mass,
        material,
        material_names: list[str],
        box_lower,
        box_upper,
        periodic,
        angular_velocity: bool,
        scene_text: str,
        effects: list[str],
        seed: int,
        version: str,
        log_events: bool,
        creator_args: str = "",
        motion_state: bool = False,
        observables: bool = False,
        open_system: bool = False,
        checkpoint_layout: dict | None = None,
        overrides: dict | None = None,
        walls: Walls | None = None,
        scene_name: str = "",
        pair_table=None,
    ):
        radius = np.asarray(radius, dtype=np.float64)
        if radius.ndim != 1 or radius.shape[0] == 0:
            raise ValueError(f"radius: expected shape (N,) with N >= 1, got {radius.shape}")
        n = radius.shape[0]
        mass = _checked(mass, "mass", (n,), np.float64)
        material_in = np.asarray(material)
        if material_in.shape != (n,) or not np.issubdtype(material_in.dtype, np.integer):
            raise ValueError(
                f"material: expected integers of shape ({n},), "
                f"got {material_in.dtype} of shape {material_in.shape}"
            )
        material_names = [str(name) for name in material_names]
        if material_in.min() < 0 or material_in.max() >= len(material_names):
            raise ValueError(
                f"material: indices must lie in [0, {len(material_names)}) "
                f"(one per material name), got [{material_in.min()}, {material_in.max()}]"
            )
        periodic = tuple(bool(p) for p in periodic)
        if len(periodic) != 3:
            raise ValueError(f"periodic: expected 3 booleans, got {len(periodic)}")
        if (box_lower is None) != (box_upper is None):
            raise ValueError("box_lower and box_upper must be given together")
        if box_lower is not None:
            box_lower = _checked(box_lower, "box_lower", (3,), np.float64)
            box_upper = _checked(box_upper, "box_upper", (3,), np.float64)
            if not (np.all(np.isfinite(box_lower)) and np.all(np.isfinite(box_upper))):
                raise ValueError("box_lower, box_upper: must be finite")
            if np.any(box_upper <= box_lower):
                raise ValueError(
                    f"box: upper corner {box_upper} must exceed lower corner {box_lower}"
                )
        elif any(periodic):
            raise InputError("a periodic axis needs a box (box_lower and box_upper)")
        seed_attribute = _seed_attribute(seed)
        if walls is not None:
            walls = _checked_walls(walls, len(material_names))
        if pair_table is not None:
            pair_table = np.asarray(pair_table, dtype=np.float64)
            m = len(material_names)
            if pair_table.ndim != 3 or pair_table.shape[:2] != (m, m):
                raise ValueError(f"pair_table: expected shape ({m}, {m}, K), one row per pair "
                                 f"of material names, got {pair_table.shape}")

        self.path = os.fspath(path)
        self.n_particles = n
        #: planes of the observables' wall rows (:data:`PER_WALL`)
        self.n_walls = 0 if walls is None else len(walls)
        self.has_angular_velocity = bool(angular_velocity)
        self.has_motion_state = bool(motion_state)
        #: The switches of :attr:`FrameField.switch`.
        self.has_observables = bool(observables)
        self.has_open_system = bool(open_system)
        self._switches = {"angular_velocity": self.has_angular_velocity,
                          "motion_state": self.has_motion_state,
                          "observables": self.has_observables,
                          "open_system": self.has_open_system}
        self.has_events = bool(log_events)
        self.has_edges = any(periodic)
        self._edges = None if box_lower is None else box_upper - box_lower
        self._n_frames = 0
        self._n_events = 0
        self._last_step = None
        self._last_time = None
        self._closed = True
        self._checkpoint_serial = 0
        # The layout is made under a temporary name and the file appears under its own only
        # in SWMR mode: a reader never meets it half made, when neither a plain nor a SWMR
        # read can open it.
        part = self.path + PART_SUFFIX
        try:
            self._file = h5py.File(part, "w", libver=LIBVER, rdcc_nbytes=CHUNK_CACHE_BYTES)
        except OSError as exc:
            raise InputError(
                f"cannot create trajectory file {self.path}: {_one_line(exc)}"
            ) from None
        self._closed = False
        try:
            self._create_layout(
                radius=radius,
                mass=mass,
                material=material_in.astype(np.int32),
                material_names=material_names,
                box_lower=box_lower,
                box_upper=box_upper,
                periodic=periodic,
                scene_text=str(scene_text),
                effects=[str(e) for e in effects],
                seed=seed_attribute,
                version=str(version),
                creator_args=str(creator_args),
                overrides=json.dumps(dict(overrides or {}), default=_json_default),
                walls=walls,
                scene_name=str(scene_name),
                pair_table=pair_table,
            )
            self._checkpoint_layout = None
            if checkpoint_layout is not None:
                self._create_checkpoint_slots(checkpoint_layout)
            self._file.flush()
            # from here on no object or attribute may be created (SWMR), only written
            self._file.swmr_mode = True
            os.replace(part, self.path)
        except BaseException:
            self._file.close()
            self._closed = True
            if os.path.exists(part):
                os.unlink(part)
            raise

    # -- layout ---------------------------------------------------------------------------

    def _create_layout(
        self,
        *,
        radius,
        mass,
        material,
        material_names,
        box_lower,
        box_upper,
        periodic,
        scene_text,
        effects,
        seed,
        version,
        creator_args,
        overrides,
        walls,
        scene_name,
        pair_table,
    ):
        f = self._file
        n = self.n_particles

        h5md = f.create_group("h5md")
        h5md.attrs["version"] = np.array(H5MD_VERSION, dtype=np.int32)
        h5md.create_group("author").attrs["name"] = np.bytes_("hsgran user")
        creator = h5md.create_group("creator")
        creator.attrs["name"] = np.bytes_("hsgran")
        creator.attrs["version"] = np.bytes_(version.encode("ascii", "replace"))
        units = h5md.create_group("modules/units")
        units.attrs["version"] = np.array(UNITS_MODULE_VERSION, dtype=np.int32)
        units.attrs.create("system", "SI", dtype=_ASCII)

        particles = f.create_group(PARTICLES)
        clock = f.create_group(FRAME_FIELDS[CLOCK].path)
        self._step = _create_series(clock, "step", np.int64, None)
        self._time = _create_series(clock, "time", np.float64, UNIT_TIME)
        f.create_group(OBSERVABLES)
        self._values = {}
        for name, spec in FRAME_FIELDS.items():
            if spec.switch is not None and not self._switches[spec.switch]:
                continue
            group = clock if name == CLOCK else self._element(f, spec.path)
            self._values[name] = _create_value(group, spec.row_shape(n, self.n_walls),
                                               spec.dtype, spec.unit, spec.fill)

        box = particles.create_group("box")
        box.attrs["dimension"] = np.int32(3)
        boundary = [b"periodic" if p else b"none" for p in periodic]
        box.attrs["boundary"] = np.array(boundary, dtype="S8")
        self._box_edges = None
        if self.has_edges:
            self._box_edges = _create_value(
                self._element(box, "edges"), (3,), np.float64, UNIT_LENGTH
            )

        _set_unit(particles.create_dataset("radius", data=radius), UNIT_LENGTH)
        _set_unit(particles.create_dataset("mass", data=mass), UNIT_MASS)
        particles.create_dataset("species", data=material)

        parameters = f.create_group(PARAMETERS)
        attrs = parameters.attrs
        attrs["format_version"] = np.int32(FORMAT_VERSION)
        attrs["complete"] = np.False_
        attrs.create("version", version, dtype=_UTF8)
        attrs.create("scene_text", scene_text, dtype=_UTF8)
        attrs.create("effects", np.array(effects, dtype=object), dtype=_UTF8)
        attrs.create("material_names", np.array(material_names, dtype=object), dtype=_UTF8)
        attrs["seed"] = seed
        attrs.create("creator_args", creator_args, dtype=_UTF8)
        attrs.create("overrides", overrides, dtype=_UTF8)
        attrs.create("summary", "{}", dtype=_UTF8)
        attrs.create("scene_name", scene_name, dtype=_UTF8)
        if box_lower is not None:
            attrs["box_lower"] = box_lower
            attrs["box_upper"] = box_upper
        if walls is not None:
            group = parameters.create_group(WALLS)
            _set_unit(group.create_dataset("point", data=walls.point), UNIT_LENGTH)
            group.create_dataset("normal", data=walls.normal)
            group.create_dataset("material", data=walls.material)
            group.create_dataset("key", data=np.array(walls.key, dtype=object).reshape(-1),
                                 dtype=_UTF8)
            if walls.motion is not None and np.any(walls.motion[:, M_KIND] != MOT_FIXED):
                group.create_dataset("motion", data=walls.motion)
            if walls.cylinder is not None:
                group.create_dataset("cylinder", data=walls.cylinder)
            if walls.kind is not None:
                group.create_dataset("kind", data=walls.kind)
                group.create_dataset("geometry", data=walls.geometry)
                _set_unit(group.create_dataset("lines", data=walls.lines), UNIT_LENGTH)
        if pair_table is not None:
            parameters.create_dataset(PAIR_TABLE, data=pair_table)

        self._events = None
        if self.has_events:
            events = f.create_group(EVENTS)
            self._events = {name: _create_series(events, name, dtype, unit,
                                                 EVENT_ROWS.get(name, ()))
                            for name, (dtype, unit) in EVENT_FIELDS.items()}

    def _create_checkpoint_slots(self, layout: dict) -> None:
        group = self._file.create_group(CHECKPOINT)
        # storage is allocated now (data given), not at the first write, so that writing a
        # checkpoint changes no metadata
        group.create_dataset("index", data=np.array([0, -1], dtype=np.int64))
        for slot in ("0", "1"):
            g = group.create_group(slot)
            g.create_dataset("time", data=np.zeros(2))  # state time, end time of the run
            g.create_dataset("counts", data=np.zeros(3, dtype=np.int64))  # frames, events, version
            arrays = g.create_group("arrays")
            for name, (shape, dtype) in layout.items():
                arrays.create_dataset(name, data=np.zeros(shape, dtype=dtype))
        self._checkpoint_layout = {k: (tuple(shape), np.dtype(dt)) for k, (shape, dt) in
                                   layout.items()}

    def _element(self, parent, name):
        """A time-dependent element whose step and time are hard links to the position's."""
        group = parent.create_group(name)
        group["step"] = self._step
        group["time"] = self._time
        return group

    # -- appending ------------------------------------------------------------------------

    def append_frames(self, frames) -> None:
        """Append a block of F frames (F may be 0) and flush the file.

        Args:
            frames: ``step`` (frame numbers, shape (F,), int, non-decreasing), ``time`` (frame
                times [s], shape (F,), non-decreasing) and the fields of
                :data:`FRAME_FIELDS`, each of shape (F, *row) in its unit, as the attributes of
                an object (:class:`hsgran.engine.FrameBlock`) or the entries of a mapping. A
                field whose switch the writer was created without is ``None`` or absent; every
                other field is required.

        Raises:
            ValueError: A shape does not match, a field is missing, given against the writer's
                switches or unknown (in a mapping), steps or times decrease, or the writer is
                closed.
        """
        self._check_open()
        get = _block_fields(frames, ("step", "time", *FRAME_FIELDS), "frames")
        step_in = np.asarray(get("step"))
        if step_in.ndim != 1:
            raise ValueError(f"step: expected shape (F,), got {step_in.shape}")
        if step_in.size and not np.issubdtype(step_in.dtype, np.integer):
            raise ValueError(f"step: expected integers, got {step_in.dtype}")
        n_new = step_in.shape[0]
        step_arr = step_in.astype(np.int64, copy=False)
        time_arr = _checked(get("time"), "time", (n_new,), np.float64)
        values = []
        for name, spec in FRAME_FIELDS.items():
            given, dset = get(name), self._values.get(name)
            if (given is None) != (dset is None):
                raise ValueError(_optional_message(name, spec.switch, dset is not None))
            if dset is not None:
                shape = (n_new, *spec.row_shape(self.n_particles, self.n_walls))
                values.append((dset, _checked(given, name, shape, spec.dtype)))
        if n_new == 0:
            return
        _check_non_decreasing(step_arr, self._last_step, "step")
        _check_non_decreasing(time_arr, self._last_time, "time")
        if self._box_edges is not None:
            values.append((self._box_edges, np.broadcast_to(self._edges, (n_new, 3))))

        start, stop = self._n_frames, self._n_frames + n_new
        # Values first, step and time last: a writer killed in between leaves values longer
        # than step, and the reader drops the partial block (frames = shortest dataset).
        for dset, data in values:
            _append(dset, data, start, stop)
        _append(self._time, time_arr, start, stop)
        _append(self._step, step_arr, start, stop)
        self._file.flush()
        self._n_frames = stop
        self._last_step = step_arr[-1]
        self._last_time = time_arr[-1]

    def append_events(self, events) -> None:
        """Append a block of E logged events (E may be 0) and flush the file.

        Args:
            events: Every field of :data:`EVENT_FIELDS`, shape (E,) (or (E, *row) for those
                of :data:`EVENT_ROWS`), as the attributes of an object
                (:class:`hsgran.engine.EventBlock`) or the entries of a mapping.

        Raises:
            ValueError: The writer was created with ``log_events=False`` or is closed, or a
                field is missing, unknown (in a mapping) or of the wrong shape.
        """
        self._check_open()
        if self._events is None:
            raise ValueError("append_events: this writer was created with log_events=False")
        get = _block_fields(events, tuple(EVENT_FIELDS), "events")
        given = {name: get(name) for name in EVENT_FIELDS}
        for name, value in given.items():
            if value is None:
                raise ValueError(_optional_message(name, None, True))
        n_new = np.shape(given["time"])[0] if np.ndim(given["time"]) == 1 else -1
        if n_new < 0:
            raise ValueError(f"time: expected shape (E,), got {np.shape(given['time'])}")
        arrays = {
            name: _checked(given[name], name, (n_new, *EVENT_ROWS.get(name, ())), dtype)
            for name, (dtype, _unit) in EVENT_FIELDS.items()
        }
        if n_new == 0:
            return
        start, stop = self._n_events, self._n_events + n_new
        # "time" last, as for frames: the reader keeps the rows every field has.
        for name in EVENT_FIELDS:
            if name != "time":
                _append(self._events[name], arrays[name], start, stop)
        _append(self._events["time"], arrays["time"], start, stop)
        self._file.flush()
        self._n_events = stop

    def set_summary(self, summary: dict) -> None:
        """Store the run summary (a JSON string in ``/parameters/hsgran@summary``).

        Args:
            summary: JSON-serialisable mapping; numpy scalars and arrays are converted.

        Raises:
            ValueError: The summary cannot be written as JSON, or the writer is closed.
        """
        self._check_open()
        try:
            text = json.dumps(dict(summary), default=_json_default, sort_keys=True)
        except TypeError as exc:
            raise ValueError(f"summary: {exc}") from None
        self._file[PARAMETERS].attrs.create("summary", text, dtype=_UTF8)
        self._file.flush()

    def write_checkpoint(self, arrays: dict, time: float, frames: int, events: int,
                         version: int, t_end: float = float("nan")) -> None:
        """Store a restart state in the slot not holding the last one, then name it current.

        Args:
            arrays: Every array of the layout given at creation, by name.
            time: Simulated time of the state [s].
            frames: Frames of the file that the state follows (later ones are dropped on resume).
            events: Event-log rows that the state follows.
            version: Checkpoint layout version of the engine.
            t_end: End time of the run [s] (where a resume stops unless told otherwise).

        Raises:
            ValueError: The writer has no checkpoint slots, is closed, or an array does not
                match the layout.
        """
        self._check_open()
        if self._checkpoint_layout is None:
            raise ValueError("write_checkpoint: this writer was created without checkpoint slots")
        if set(arrays) != set(self._checkpoint_layout):
            raise ValueError("write_checkpoint: arrays do not match the layout given at creation")
        if frames > self._n_frames or events > self._n_events:
            raise ValueError(f"write_checkpoint: follows {frames} frames and {events} events, "
                             f"the file has {self._n_frames} and {self._n_events}")
        group = self._file[CHECKPOINT]
        index = group["index"]
        slot = 1 - int(index[1]) if index[1] >= 0 else 0
        target = group[str(slot)]
        for name, (shape, dtype) in self._checkpoint_layout.items():
            target["arrays"][name][...] = _checked(arrays[name], name, shape, dtype)
        target["time"][...] = np.array([time, t_end], dtype=np.float64)
        target["counts"][...] = np.array([frames, events, version], dtype=np.int64)
        self._file.flush()
        _sync(self.path)
        self._checkpoint_serial += 1
        index[...] = np.array([self._checkpoint_serial, slot], dtype=np.int64)
        self._file.flush()
        _sync(self.path)

    # -- closing --------------------------------------------------------------------------

    @property
    def n_frames(self) -> int:
        """Frames written so far."""
        return self._n_frames

    @property
    def n_events(self) -> int:
        """Events written so far."""
        return self._n_events

    @property
    def closed(self) -> bool:
        """Whether the file is closed."""
        return self._closed

    def close(self, complete: bool = True) -> None:
        """Mark the file complete (unless told otherwise) and close it; a second call does
        nothing."""
        self._finish(complete=complete)

    def _finish(self, complete: bool) -> None:
        if self._closed:
            return
        try:
            if complete:
                self._file[PARAMETERS].attrs["complete"] = np.True_
            self._file.flush()
        finally:
            self._file.close()
            self._closed = True

    def __enter__(self) -> TrajectoryWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        # A run that failed must not be marked complete; its frames are kept all the same.
        self._finish(complete=exc_type is None)

    def _check_open(self) -> None:
        if self._closed:
            raise ValueError(f"trajectory writer for {self.path} is closed")


# -- reading ------------------------------------------------------------------------------


def read_trajectory(path) -> Trajectory:
    """Read a whole hsgran trajectory file into memory.

    A file whose writer was killed reads too: it holds every block appended before the kill
    (``complete`` is then ``False`` and ``summary`` empty).

    Args:
        path: Trajectory file (``.h5``).

    Returns:
        The :class:`Trajectory`.

    Raises:
        InputError: The file does not exist, is not HDF5, or is not an hsgran trajectory; the
            message is one line.
    """
    path = os.fspath(path)
    with _open_trajectory(path) as f:
        try:
            _check_size(f, path)
            return _read(f)
        except DAMAGED as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(
                f"{path} is not a readable hsgran trajectory: {_one_line(exc)}"
            ) from None


@dataclass
class StoredCheckpoint:
    """The current checkpoint of a trajectory file and what a resumed run needs besides it.

    Attributes:
        arrays: Engine state arrays by name.
        time: Simulated time of the state [s].
        t_end: End time of the run that stored it [s] (NaN if not recorded).
        frames: Frames of the file the state follows.
        events: Event-log rows the state follows.
        version: Engine checkpoint layout version.
        scene_text: The scene file of the run.
        log_events: Whether the run logs events.
        complete: Whether the file was closed as complete.
        creator_args: Command line of the run.
        overrides: Key path → value changes of the scene the run used.
        hsgran_version: hsgran version that wrote the file.
        pair_table: The engine's pair table of the run (see :class:`Trajectory`), or ``None``
            when the file does not hold it.
    """

    arrays: dict
    time: float
    t_end: float
    frames: int
    events: int
    version: int
    scene_text: str
    log_events: bool
    complete: bool
    creator_args: str
    overrides: dict
    hsgran_version: str = ""
    pair_table: np.ndarray | None = None


def read_checkpoint(path) -> StoredCheckpoint:
    """Read the current checkpoint of a trajectory file (for ``hsgran run --resume``).

    Raises:
        InputError: The file is missing, not an hsgran trajectory, or holds no checkpoint.
    """
    path = os.fspath(path)
    with _open_trajectory(path) as f:
        try:
            _check_size(f, path)
            if CHECKPOINT not in f:
                raise InputError(f"{path} holds no checkpoint (it was written without them)")
            group = f[CHECKPOINT]
            slot = int(group["index"][1])
            if slot < 0:
                raise InputError(f"{path} holds no checkpoint yet (the run stopped before its "
                                 "first one): run the scene again")
            target = group[str(slot)]
            frames, events, version = (int(x) for x in target["counts"][()])
            params = f[PARAMETERS].attrs
            return StoredCheckpoint(
                arrays={name: d[()] for name, d in target["arrays"].items()},
                time=float(target["time"][0]), t_end=float(target["time"][1]), frames=frames,
                events=events, version=version,
                scene_text=_text(params["scene_text"]), log_events=EVENTS in f,
                complete=bool(params.get("complete", False)),
                creator_args=_text(params.get("creator_args", "")),
                overrides=json.loads(_text(params.get("overrides", "{}"))),
                hsgran_version=_text(params["version"]),
                pair_table=_read_pair_table(f[PARAMETERS]))
        except DAMAGED as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(f"{path}: unreadable checkpoint: {_one_line(exc)}") from None


#: Bytes of frames or event-log rows :func:`copy_frames` holds at once: a block is read and
#: appended before the next, so a resume needs this much, whatever the file's size.
COPY_BYTES = 64 * 2**20


def copy_frames(path, writer: TrajectoryWriter, frames: int, events: int) -> None:
    """Append the first ``frames`` frames and ``events`` event rows of ``path`` to ``writer``.

    Used by resume to write the file anew up to its checkpoint; blocks keep memory bounded.

    Raises:
        InputError: The file is unreadable or shorter than asked.
    """
    path = os.fspath(path)
    with _open_trajectory(path) as f:
        try:
            clock = f[FRAME_FIELDS[CLOCK].path]
            if clock["step"].shape[0] < frames:
                raise InputError(f"{path} has fewer frames than its checkpoint follows")
            values = _stored_frame_fields(f)
            frame_bytes = sum(d.dtype.itemsize * int(np.prod(d.shape[1:]))
                              for d in values.values())
            block = max(1, COPY_BYTES // frame_bytes)
            for a in range(0, frames, block):
                b = min(frames, a + block)
                writer.append_frames({"step": clock["step"][a:b], "time": clock["time"][a:b],
                                      **{name: d[a:b] for name, d in values.items()}})
            if events:
                group = f[EVENTS]
                rows = COPY_BYTES // sum(np.dtype(t).itemsize * int(np.prod(EVENT_ROWS.get(k, ())))
                                         for k, (t, _) in EVENT_FIELDS.items())
                for a in range(0, events, rows):
                    b = min(events, a + rows)
                    writer.append_events({name: _event_field(group, name, a, b)
                                          for name in EVENT_FIELDS})
        except DAMAGED as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(f"{path}: cannot copy its frames: {_one_line(exc)}") from None


def _open_trajectory(path: str) -> h5py.File:
    """Open an hsgran trajectory for reading, or raise a one-line :class:`InputError`."""
    if not os.path.exists(path):
        raise InputError(f"trajectory file not found: {path}")
    if os.path.isdir(path):
        raise InputError(f"{path} is a directory, not a trajectory file")
    try:
        is_hdf5 = h5py.is_hdf5(path)
    except OSError as exc:
        raise InputError(f"cannot read {path}: {_one_line(exc)}") from None
    if not is_hdf5:
        raise InputError(f"{path} is not an HDF5 file, so not an hsgran trajectory")
    try:
        # No file locking: the file may be read while a simulation still appends to it.
        f = h5py.File(path, "r", locking=False)
    except OSError as plain:
        # A SWMR writer that is running or was killed leaves a mark that makes plain opens
        # fail; only then open in SWMR mode, which retries every unreadable piece of metadata
        # many times with growing pauses: on a damaged file it would hang for minutes.
        if SWMR_MARK not in str(plain):
            raise InputError(f"cannot open {path}: {_one_line(plain)}") from None
        try:
            f = h5py.File(path, "r", locking=False, swmr=True)
        except OSError as exc:
            raise InputError(f"cannot open {path}: {_one_line(exc)}") from None
    try:
        for required in ("h5md", f"{PARTICLES}/position/value", PARAMETERS):
            if not _has(f, required):
                raise InputError(f"{path} is not an hsgran trajectory (it has no /{required})")
    except BaseException:
        f.close()
        raise
    return f


#: Share of the available memory that reading one trajectory may take: a damaged file can
#: claim datasets of any size, and the claim is checked before anything is allocated.
READ_MEMORY_SHARE = 0.5


def _check_size(f: h5py.File, path: str) -> None:
    """Refuse a file whose datasets would not fit in memory (damaged, or simply too big)."""
    total = 0

    def visit(_name, obj):
        nonlocal total
        if isinstance(obj, h5py.Dataset) and obj.dtype.kind in "biufS":
            total += int(np.prod(obj.shape, dtype=np.float64)) * obj.dtype.itemsize

    f.visititems(visit)
    available = available_memory()
    if available is not None and total > READ_MEMORY_SHARE * available:
        raise InputError(f"{path} holds {total / 1e9:.3g} GB of data, more than can be read "
                         f"into the {available / 1e9:.3g} GB of memory available (damaged, or "
                         "read it in parts with h5py)")


def _stored_frame_fields(f: h5py.File) -> dict:
    """The ``value`` dataset of every field of :data:`FRAME_FIELDS` the file has, by name (a
    field without a switch is required: its absence raises ``KeyError``, a damaged file)."""
    return {name: f[spec.path]["value"] for name, spec in FRAME_FIELDS.items()
            if spec.switch is None or spec.path in f}


def _read(f: h5py.File) -> Trajectory:
    particles = f[PARTICLES]
    clock = f[FRAME_FIELDS[CLOCK].path]
    stored = _stored_frame_fields(f)
    series = [clock["step"], clock["time"], *stored.values()]
    if "edges" in particles["box"]:
        series.append(particles["box/edges/value"])
    n_frames = min(d.shape[0] for d in series)
    values = {name: d[:n_frames] for name, d in stored.items()}
    # elements under particles/all are Trajectory attributes (absent: None), observables go
    # to Trajectory.energies by their name in the file
    per_particle = {name: values.get(name) for name, spec in FRAME_FIELDS.items()
                    if spec.path.startswith(PARTICLES + "/")}
    energies = {observable: values[name] for observable, name in ENERGY_OBSERVABLES.items()
                if name in values}
    sums = {observable: values[name] for observable, name in SUM_OBSERVABLES.items()
            if name in values}

    params = f[PARAMETERS].attrs
    boundary = [_text(b) for b in particles["box"].attrs["boundary"]]
    events = None
    if EVENTS in f:
        group = f[EVENTS]
        n_events = min(group[name].shape[0] for name in EVENT_FIELDS if name in group)
        events = {name: _event_field(group, name, 0, n_events) for name in EVENT_FIELDS}
    return Trajectory(
        time=clock["time"][:n_frames],
        step=clock["step"][:n_frames],
        **per_particle,
        radius=particles["radius"][()],
        mass=particles["mass"][()],
        material=particles["species"][()],
        material_names=[_text(s) for s in params["material_names"]],
        box_lower=np.asarray(params["box_lower"]) if "box_lower" in params else None,
        box_upper=np.asarray(params["box_upper"]) if "box_upper" in params else None,
        periodic=tuple(b == "periodic" for b in boundary),
        energies=energies,
        events=events,
        scene_text=_text(params["scene_text"]),
        effects=[_text(s) for s in params["effects"]],
        seed=int(params["seed"]),
        version=_text(params["version"]),
        summary=json.loads(_text(params["summary"])) if "summary" in params else {},
        complete=bool(params.get("complete", False)),
        creator_args=_text(params.get("creator_args", "")),
        walls=_read_walls(f[PARAMETERS]),
        scene_name=_text(params.get("scene_name", "")),
        overrides=json.loads(_text(params.get("overrides", "{}"))),
        pair_table=_read_pair_table(f[PARAMETERS]),
        sums=sums,
    )


def _read_walls(parameters: h5py.Group) -> Walls | None:
    if WALLS not in parameters:
        return None
    group = parameters[WALLS]
    cylinder = group["cylinder"][()] if "cylinder" in group else None
    if cylinder is not None and cylinder.shape[1] < CY_SIZE:  # (written before the edges)
        cylinder = np.pad(cylinder, ((0, 0), (0, CY_SIZE - cylinder.shape[1])))
    return Walls(point=group["point"][()], normal=group["normal"][()],
                 material=group["material"][()], key=[_text(k) for k in group["key"][()]],
                 motion=group["motion"][()] if "motion" in group else None,
                 cylinder=cylinder,
                 kind=group["kind"][()] if "kind" in group else None,
                 geometry=group["geometry"][()] if "geometry" in group else None,
                 lines=group["lines"][()] if "lines" in group else None)


def _read_pair_table(parameters: h5py.Group) -> np.ndarray | None:
    return parameters[PAIR_TABLE][()] if PAIR_TABLE in parameters else None


# -- helpers ------------------------------------------------------------------------------


def _event_field(group, name: str, a: int, b: int) -> np.ndarray:
    """Rows a:b of an event-log dataset; a ``velocity`` that a file of format 1 lacks is NaN."""
    if name not in group and name in EVENT_ROWS:
        return np.full((b - a, *EVENT_ROWS[name]), np.nan)
    return group[name][a:b]


def _create_value(group, row_shape, dtype, unit, fill=None):
    """The resizable, chunked, compressed ``value`` dataset of a time-dependent element
    (``fill``: its HDF5 fill value, or ``None``)."""
    row_bytes = int(np.prod(row_shape, dtype=np.int64)) * np.dtype(dtype).itemsize
    rows = max(1, min(SERIES_CHUNK_ROWS, CHUNK_BYTES // max(row_bytes, 1)))
    dset = group.create_dataset(
        "value",
        shape=(0, *row_shape),
        maxshape=(None, *row_shape),
        dtype=dtype,
        chunks=(rows, *row_shape),
        compression=COMPRESSION,
        shuffle=True,
        fillvalue=fill,
    )
    if unit is not None:
        _set_unit(dset, unit)
    return dset


def _create_series(group, name: str, dtype, unit, row=()):
    """A resizable, chunked, compressed dataset that grows by appends along its first axis
    (step, time, the event log; ``row``: the shape of one entry)."""
    dset = group.create_dataset(
        name,
        shape=(0, *row),
        maxshape=(None, *row),
        dtype=dtype,
        chunks=(SERIES_CHUNK_ROWS, *row),
        compression=COMPRESSION,
        shuffle=True,
    )
    if unit is not None:
        _set_unit(dset, unit)
    return dset


def _set_unit(dset, unit: str) -> None:
    dset.attrs.create("unit", unit, dtype=_ASCII)


def _append(dset, data, start: int, stop: int) -> None:
    dset.resize(stop, axis=0)
    dset[start:stop] = data


def _checked(value, name: str, shape: tuple, dtype) -> np.ndarray:
    array = np.asarray(value)
    if array.shape != shape:
        raise ValueError(f"{name}: expected shape {shape}, got {array.shape}")
    return array.astype(dtype, copy=False)


def _check_non_decreasing(values: np.ndarray, last, name: str) -> None:
    # H5MD: step and time are "in monotonically increasing order".
    if np.any(np.diff(values) < 0) or (last is not None and values[0] < last):
        raise ValueError(f"{name}: frames must be appended in non-decreasing {name}")


def _optional_message(name: str, switch: str | None, enabled: bool) -> str:
    if switch is None:
        return f"{name}: required"
    if enabled:
        return f"{name}: required, the writer was created with {switch}=True"
    return f"{name}: must be None, the writer was created with {switch}=False"


def _block_fields(block, names: tuple, what: str):
    """A function giving a block's field by name (``None`` if absent); the block is an object
    with the fields as attributes or a mapping, whose keys must all be ``names`` (a typo would
    otherwise read as a field left out)."""
    if isinstance(block, Mapping):
        unknown = sorted(set(block) - set(names))
        if unknown:
            raise ValueError(f"{what}: unknown field {unknown[0]!r}; known: {', '.join(names)}")
        return block.get
    return lambda name: getattr(block, name, None)


def _checked_walls(walls: Walls, n_materials: int) -> Walls:
    p = len(walls.point)
    point = _checked(walls.point, "walls.point", (p, 3), np.float64)
    normal = _checked(walls.normal, "walls.normal", (p, 3), np.float64)
    material = _checked(walls.material, "walls.material", (p,), np.int32)
    if not (np.all(np.isfinite(point)) and np.all(np.isfinite(normal))):
        raise ValueError("walls: points and normals must be finite")
    if p and (material.min() < 0 or material.max() >= n_materials):
        raise ValueError(f"walls.material: indices must lie in [0, {n_materials}) "
                         "(one per material name)")
    if len(walls.key) != p:
        raise ValueError(f"walls.key: expected {p} key paths, got {len(walls.key)}")
    motion = (None if walls.motion is None
              else _checked(walls.motion, "walls.motion", (p, M_SIZE), np.float64))
    cylinder = (None if walls.cylinder is None
                else _checked(walls.cylinder, "walls.cylinder", (p, CY_SIZE), np.float64))
    kind = geometry = lines = None
    if walls.kind is not None:
        kind = _checked(walls.kind, "walls.kind", (p,), np.int8)
        geometry = _checked(walls.geometry, "walls.geometry", (p, GEO_SIZE), np.float64)
        lines = np.zeros((0, 3)) if walls.lines is None else walls.lines
        lines = _checked(lines, "walls.lines", (len(lines), 3), np.float64)
    return Walls(point, normal, material, [str(k) for k in walls.key], motion, cylinder, kind,
                 geometry, lines)


def _seed_attribute(seed):
    seed = int(seed)
    if -(2**63) <= seed < 2**63:
        return np.int64(seed)
    if 0 <= seed < 2**64:
        return np.uint64(seed)
    raise ValueError(f"seed: {seed} does not fit in 64 bits")


def _json_default(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"{type(obj).__name__} is not JSON-serialisable")


def _text(value) -> str:
    if isinstance(value, bytes | np.bytes_):
        return value.decode("utf-8", "replace")
    return str(value)


def _has(f: h5py.File, name: str) -> bool:
    try:
        return name in f
    except (KeyError, TypeError, ValueError, RuntimeError, OSError):  # damaged links
        return False


def _sync(path: str) -> None:
    """Ask the OS to put the file's written data on disk (a power cut then loses nothing
    before this point); HDF5's flush only hands the data to the OS."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__
