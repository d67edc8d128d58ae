"""Scene files: TOML in, a validated :class:`Scene` in SI units out (layer 4).

This module is the one place where user input about a whole scene is checked. Every problem is
an :class:`~hsgran.errors.InputError` whose one-line message starts with the key path of the
offending value (``particles[3].radius``, ``walls[0].normal``, ``materials.steel.yield_stress``),
so the command line can print it without a traceback. Everything downstream (assembly of the
physics, the engine, the writers) may assume the scene is consistent.

The format (every length in m, time in s, speed in m/s; docs/architecture.md §4)::

    [scene]
    name = "steel ball dropped on glass"   # optional; default: the file name
    duration = 1.0                         # required, > 0 [s]
    gravity = [0.0, 0.0, -9.81]            # optional, only with the 'gravity' effect [m/s^2]
    effects = ["gravity", "rotation"]      # optional, default [] (see hsgran.effects)
    seed = 1                               # optional, default 0: seeds every [[fill]]
    periodic = [true, true, false]         # optional, per axis; needs a box wall

    [output]
    frame_interval = 0.005                 # required, > 0 [s]

    [materials.NAME] ...                   # optional, see hsgran.materials (overrides built-ins)
    [[contacts]] ...                       # optional, see hsgran.materials

    [[walls]]                              # a plane: spheres live where the normal points
    kind = "plane"
    point = [0.0, 0.0, 0.0]
    normal = [0.0, 0.0, 1.0]
    material = "glass"

    [[walls]]                              # a box: six inward-facing planes, none on a
    kind = "box"                           # periodic axis (material optional when every
    lower = [0.0, 0.0, 0.0]                # axis is periodic); at most one box
    upper = [0.1, 0.1, 0.1]
    material = "glass"

    [[particles]]                          # one sphere
    material = "steel"
    radius = 0.005
    position = [0.0, 0.0, 0.1]
    velocity = [0.0, 0.0, 0.0]             # optional, default zero
    angular_velocity = [0.0, 0.0, 0.0]     # optional, default zero; non-zero needs 'rotation'

    [[fill]]                               # `count` random non-overlapping spheres
    count = 2000
    material = "glass"
    radius = [0.001, 0.0015]               # a number, or [min, max] for a uniform draw
    region = { lower = [0, 0, 0.05], upper = [0.1, 0.1, 0.1] }
    speed = 0.1                            # optional, default 0: random directions
    angular_velocity = [0.0, 0.0, 0.0]     # optional, default zero, the same for every sphere

Particle order: the ``[[particles]]`` in file order, then each ``[[fill]]`` in file order (a
fill's spheres in the order of their radius draw). Material ids: materials in order of first use
by particles, then by walls that produce at least one plane.

Fills are reproducible: one ``numpy.random.default_rng(scene.seed)`` serves all fills in file
order; :mod:`hsgran.placement` places each fill's spheres by random sequential addition, clear
of the walls and of everything already placed (explicit particles, earlier fills, its own fill).
A fill that cannot be completed within a bounded number of candidates is an error naming how
many spheres it placed. The final overlap check of all spheres uses
:func:`hsgran.placement.overlapping_pairs` (periodic images included).

The scene is assembled by :func:`_build` from parts (the [scene] table, the walls, the
particles, the fills, ...), each a function of the document and of the parts it needs; the order
of the calls there is the order of the checks.

Layer 4: imports ``errors``, ``system``, ``effects``, ``materials``, ``events.grid``,
``overrides`` and ``placement``.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from hsgran import shapes
from hsgran.effects import Effects
from hsgran.errors import InputError, check_number, check_positive, did_you_mean, short_repr

# a periodic axis must hold this many cells of the engine's grid, whose cell edge is at least the
# largest diameter (with fewer, a sphere and its own image would be neighbours)
from hsgran.events.grid import MIN_PERIODIC_CELLS
from hsgran.inflow import Inflow
from hsgran.materials import (
    PAIR_ROW_SIZE,
    Material,
    MaterialLibrary,
    pair_row,
    solid_sphere_mass,
)
from hsgran.outlets import OL_A, OL_B, OL_KIND, OL_SIZE, OUT_BELOW, OUT_BOX, inside_outlet
from hsgran.overrides import apply_overrides, names_override
from hsgran.placement import CONTACT_TOLERANCE, Fill, Space, fill_spheres, overlapping_pairs
from hsgran.system import available_memory
from hsgran.wallspec import (
    BL_RADIUS,
    CY_AXIS,
    CY_HALF,
    CY_OMEGA,
    CY_RADIUS,
    CY_SIDE,
    CY_SIZE,
    M_AMP,
    M_DIR,
    M_KIND,
    M_OMEGA,
    M_PHASE,
    M_SIZE,
    M_TRAVEL,
    MOT_OSCILLATION,
    MOT_VELOCITY,
    WK_BALL,
    wall_shift,
)

# ---- limits and tolerances ---------------------------------------------------------------

#: Gravity used when the 'gravity' effect is on and ``scene.gravity`` is not given [m/s²].
STANDARD_GRAVITY = (0.0, 0.0, -9.81)

#: Largest number of particles a scene may ask for. The engine's arrays, event queue, cell
#: grid and output buffers cost roughly :data:`BYTES_PER_PARTICLE` each, so 5×10⁷ particles is
#: already ~50 GB; refusing before allocating anything turns a typo into a message, not a crash.
MAX_PARTICLES = 50_000_000
#: Memory cost of one particle across scene building, engine, queue, grid, output buffers and
#: a checkpoint copy [bytes]: peak RSS measured at 0.58 kB (10⁶ spheres) to 0.94 kB (2×10⁵, where
#: the fixed 32 MB frame buffer weighs more) per sphere with every effect on, plus 0.33 kB for
#: the copy a checkpoint makes of the state.
BYTES_PER_PARTICLE = 1536
#: Share of the memory available when the scene is read that a run may plan to use: the rest
#: is headroom for the estimate's error and for the other processes on the machine.
MEMORY_SHARE = 0.8

#: Largest speed a scene may give a sphere, or a sphere's surface by its spin [m/s]. Beyond the
#: sound speed of every solid (~6 km/s in steel) impacts are hypervelocity: the quasi-static
#: contact law of MODEL §3 stopped holding long before, and past this the numbers are typos.
MAX_SPEED = 1e4
#: Largest gravitational acceleration [m/s²]: ~10⁶ g, the top of ultracentrifuges.
MAX_GRAVITY = 1e7

#: Largest scene file read [bytes]. tomllib holds a parsed [[particles]] entry in roughly 2 kB of
#: Python objects, so a 256 MB file of explicit particles already needs several GB; larger sets
#: belong in [[fill]] blocks.
MAX_SCENE_BYTES = 256 * 1024**2

#: Most output frames a scene may ask for (duration / frame_interval). Each frame stores every
#: particle, so a frame_interval far too small (a typo such as 1e-9) would otherwise fill the disk.
MAX_FRAMES = 10_000_000

#: A plane is parallel to a periodic axis when its unit normal's component along it is below
#: this (a tilted plane would break the periodic images).
PARALLEL_TOLERANCE = 1e-12

AXES = "xyz"

TOP_KEYS = ("scene", "output", "materials", "contacts", "walls", "particles", "fill",
            "enduring_contact", "outlets", "inflow")
ENDURING_KEYS = ("landing_speed", "rolling_convention", "tc_time", "treatment")
#: How touching spheres and walls are treated under gravity (docs/enduring-contact.md): the
#: pairwise rules of hsgran._settling, or clusters solved together (hsgran._cluster).
TREATMENTS = ("pairwise", "clusters")
#: Default rebound speed [m/s] below which a sphere bouncing on a plane stays on it (sliding,
#: rolling or resting, MODEL §5.3). Such a rebound would rise v²/2g = 51 nm, below any surface
#: roughness; giving it up costs at most ½ m v² of kinetic energy and the remaining bounces'
#: time 2v/(g(1 − e)) (1 ms at e = 0.8), both reported in docs/enduring-contact.md.
DEFAULT_LANDING_SPEED = 1e-3
#: Default TC time [s] (TC model, Luding & McNamara 1998): a collision of a sphere less than this
#: after its previous one is elastic. It is of the order of the Hertz contact duration of
#: millimetre steel spheres at 0.01–1 m/s (8–30 µs): collisions that close together are not
#: binary, and treating them as elastic ends inelastic collapse (sequences of ever-faster
#: collisions in clusters) at the price of the energy they would have dissipated; the run
#: summary counts them ("tc"). See docs/enduring-contact.md.
DEFAULT_TC_TIME = 1e-5
#: Rolling-friction conventions of MODEL §5.3: does the rolling torque act while sliding?
ROLLING_CONVENTIONS = {"A": "rolling torque also while sliding",
                       "B": "rolling torque only while rolling"}
SCENE_KEYS = ("name", "duration", "gravity", "effects", "seed", "periodic")
OUTPUT_KEYS = ("frame_interval", "observables")
PLANE_KEYS = ("kind", "point", "normal", "material", "motion", "hole")
BOX_KEYS = ("kind", "lower", "upper", "material", "motion")
#: Prescribed motions of a plane (hsgran.wallmotion) and the keys of each.
MOTION_KEYS = {"oscillation": ("kind", "amplitude", "frequency", "phase", "direction"),
               "velocity": ("kind", "velocity", "start", "travel")}
BOX_FACES = tuple(f"{side}_{axis}" for axis in "xyz" for side in ("lower", "upper"))
CYLINDER_KEYS = ("kind", "center", "axis", "radius", "length", "side", "caps",
                 "angular_velocity", "material")
CYLINDER_SIDES = ("inside", "outside")
WALL_KINDS = ("plane", "box", "cylinder", "polygon", "disk", "sphere", "mesh")
#: Keys of the finite walls and fixed spheres (docs/walls.md, "Finite walls").
POLYGON_KEYS = ("kind", "vertices", "material", "faces")
DISK_KEYS = ("kind", "center", "normal", "radius", "material", "faces", "corners")
SPHERE_KEYS = ("kind", "center", "radius", "material")
MESH_KEYS = ("kind", "file", "material", "faces", "scale", "offset")
#: Most triangles a mesh wall may have: each is up to 7 engine wall rows (two faces, three
#: edges, corners shared); a contact search looks only at those listed near the sphere, but
#: the start (placement clear of every part, the first predictions) visits them all.
MAX_TRIANGLES = 100_000
#: Keys of a plane's hole: a circle (a regular polygon of its area) or a rectangle.
HOLE_KEYS = {"circle": ("shape", "center", "radius", "corners"),
             "rectangle": ("shape", "center", "size", "axis")}
#: Which sides of a polygon or a disk spheres meet: both, or the front only (the side its
#: vertices turn counter-clockwise about, or its normal's).
FACE_SIDES = ("both", "front")
#: Most corners of a regular polygon standing for a circle.
MAX_CORNERS = 4096
PARTICLE_KEYS = ("material", "radius", "position", "velocity", "angular_velocity", "fixed")
FILL_KEYS = ("count", "material", "radius", "region", "speed", "angular_velocity", "fixed")
#: The random stream (with the scene's seed) that places fills of fixed spheres; they are
#: placed before the other fills, which keep theirs (docs/walls.md, "Finite walls").
FIXED_FILL_STREAM = 1
REGION_KEYS = ("lower", "upper")
#: Most spheres an inflow's rate may ask for over a run: its counts round(rate·interval·(k+1))
#: stay exact integers far below this (2⁵³), and no table could hold more.
MAX_INFLOW_SPHERES = 1e12
#: Keys of an ``[[inflow]]`` entry (docs/open-systems.md); a recirculating one has no count,
#: material or radius (it inserts the spheres that left).
INFLOW_KEYS = ("count", "material", "radius", "region", "rate", "interval", "start", "velocity",
               "speed", "recirculate")
INFLOW_OWN_KEYS = ("count", "material", "radius")
#: Keys of an ``[[outlets]]`` entry by kind (docs/open-systems.md).
OUTLET_KEYS = {"below": ("kind", "point", "normal"), "box": ("kind", "lower", "upper")}


# ---- the scene ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Plane:
    """An infinite plane wall.

    Attributes:
        point: A point of the plane [m], shape (3,).
        normal: Unit normal [-], shape (3,), pointing into the region where spheres live.
        material: Index into :attr:`Scene.material_names`.
        key: Key path for messages (``walls[0]``, ``walls[1].lower_z``).
        motion: Its prescribed motion, one row of ``hsgran.wallmotion`` ``M_*`` values, or
            ``None`` for a fixed plane; ``point`` is where it is at t = 0.
    """

    point: np.ndarray
    normal: np.ndarray
    material: int
    key: str
    motion: np.ndarray | None = None

    def point_at(self, t: float) -> np.ndarray:
        """A point of the plane at time t [s] [m], shape (3,)."""
        if self.motion is None:
            return self.point
        return self.point + self.motion[M_DIR:M_DIR + 3] * wall_shift(self.motion[None], 0, t)

    def distance(self, position: np.ndarray) -> np.ndarray:
        """Signed distance [m] of points (..., 3) from the plane, positive on the normal's side."""
        return (np.asarray(position) - self.point) @ self.normal


@dataclass(frozen=True, eq=False)
class Cylinder:
    """A cylindrical wall, fixed or rotating about its axis (docs/walls.md, "Cylinders").

    Attributes:
        center: The middle of its axis [m], shape (3,).
        axis: Unit axis [-], shape (3,).
        radius: Radius R [m].
        half_length: Half its length [m]; inside, two planes (``caps``) close its ends,
            otherwise other walls or a periodic axis do.
        inside: Whether the spheres are inside it (else outside).
        angular_velocity: Ω [rad/s] about ``axis`` (right-handed); its surface moves at Ω R.
        material: Index into :attr:`Scene.material_names`.
        key: Key path for messages (``walls[0]``).
    """

    center: np.ndarray
    axis: np.ndarray
    radius: float
    half_length: float
    inside: bool
    angular_velocity: float
    material: int
    key: str

    def row(self) -> np.ndarray:
        """Its row of hsgran.wallspec ``CY_*`` values, shape (CY_SIZE,)."""
        row = np.zeros(CY_SIZE)
        row[CY_AXIS:CY_AXIS + 3] = self.axis
        row[CY_RADIUS] = self.radius
        row[CY_SIDE] = 1.0 if self.inside else -1.0
        row[CY_OMEGA] = self.angular_velocity
        row[CY_HALF] = self.half_length
        return row

    def distance(self, position: np.ndarray) -> np.ndarray:
        """Distance [m] of points (..., 3) from the surface, positive on the spheres' side."""
        d = np.asarray(position) - self.center
        q = d - np.multiply.outer(d @ self.axis, self.axis)
        rho = np.sqrt(np.einsum("...k,...k->...", q, q))
        return self.radius - rho if self.inside else rho - self.radius


@dataclass(frozen=True, eq=False)
class Outlet:
    """A region where spheres leave the system: a sphere whose centre enters it is removed
    (docs/open-systems.md).

    Attributes:
        row: Its ``hsgran.outlets`` ``OL_*`` values, shape (OL_SIZE,): the kind, then a point
            of the plane and its unit normal pointing away from the outlet (``below``), or the
            lower and upper corners (``box``) [m].
        key: Key path for messages (``outlets[0]``).
    """

    row: np.ndarray
    key: str

    @property
    def kind(self) -> str:
        """``"below"`` or ``"box"``."""
        return "below" if int(self.row[OL_KIND]) == OUT_BELOW else "box"

    def contains(self, position: np.ndarray) -> np.ndarray:
        """Whether points (..., 3) [m] are inside the outlet."""
        return inside_outlet(self.row, position)


@dataclass(eq=False)
class Scene:
    """A validated scene in SI units.

    Attributes:
        name: Human-readable name.
        duration: Simulated time [s].
        gravity: Gravitational acceleration [m/s²], shape (3,); zeros without the effect.
        effects: The enabled effects.
        seed: Seed of the random fills.
        periodic: Periodic flag per axis (x, y, z).
        box_lower, box_upper: Corners of the box wall [m], shape (3,), or ``None``.
        planes: Every plane wall, box faces and cylinder caps included (none on a periodic
            axis).
        frame_interval: Time between output frames [s].
        library: Built-in and declared materials and contacts.
        material_names: Materials used by particles or walls; the index is the material id.
        position: Sphere centres [m], shape (N, 3).
        velocity: Velocities [m/s], shape (N, 3).
        angular_velocity: Angular velocities [rad/s], shape (N, 3); zeros when not given.
        radius: Radii [m], shape (N,).
        material: Material id of each sphere, shape (N,), int64.
        text: The scene file's text, verbatim.
        source: The file's path, or ``"<string>"``.
        landing_speed: Rebound speed [m/s] below which a sphere stays on a plane, as given
            (the engine uses :attr:`effective_landing_speed`).
        rolling_convention: "A" (rolling torque also while sliding) or "B" (only while
            rolling), MODEL §5.3.
        tc_time: TC-model time [s]: collisions of a sphere closer together than this are
            elastic (0: off).
        treatment: "pairwise" (the enduring-contact rules) or "clusters" (touching bodies
            solved together), docs/enduring-contact.md.
        overrides: Key path → value changes applied to the file before validation
            (:mod:`hsgran.overrides`); ``text`` then ends with :func:`override_note`.
        observables: Sum the stress and the wall impulses of every frame interval
            (``[output] observables``, docs/observables.md).
        cylinders: The cylinder walls; the engine's wall rows are ``planes`` then these
            (:attr:`walls`).
        parts: The faces, edges and corners of the finite walls and the fixed spheres
            (:class:`hsgran.shapes.Part`), the engine's last wall rows.
        outlets: Regions where spheres leave the system (:class:`Outlet`).
        inflows: Spheres inserted during the run (:class:`hsgran.inflow.Inflow`); the rows an
            inflow owns come last in the particle table, absent (NaN position) until inserted.
        present: Which rows are in the system at t = 0, shape (N,) bool (all but the inflows'
            rows).
        space: Where spheres may be placed: the planes, cylinders and periodic box
            (hsgran.placement), for the inflows.
    """

    name: str
    duration: float
    gravity: np.ndarray
    effects: Effects
    seed: int
    periodic: tuple[bool, bool, bool]
    box_lower: np.ndarray | None
    box_upper: np.ndarray | None
    planes: list[Plane]
    frame_interval: float
    library: MaterialLibrary
    material_names: list[str]
    position: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    radius: np.ndarray
    material: np.ndarray
    text: str = ""
    source: str = "<string>"
    landing_speed: float = DEFAULT_LANDING_SPEED
    rolling_convention: str = "A"
    tc_time: float = DEFAULT_TC_TIME
    treatment: str = "pairwise"
    overrides: dict = field(default_factory=dict)
    observables: bool = False
    cylinders: tuple = ()
    parts: tuple = ()
    outlets: tuple = ()
    inflows: tuple = ()
    present: np.ndarray | None = None
    space: Space | None = None

    @property
    def open_system(self) -> bool:
        """Whether spheres may leave or enter (outlets or inflows)."""
        return bool(self.outlets or self.inflows)

    @property
    def unwraps(self) -> bool:
        """Whether gravity acts along a periodic axis: a sphere that wraps there moves by a box
        length in its stored position, and its potential energy −m g·x jumps (the engine
        keeps what the wraps hid, ``_state.F_UNWRAPPED``)."""
        return bool(any(p and g != 0.0 for p, g in zip(self.periodic, self.gravity,
                                                         strict=True)))

    @property
    def walls(self) -> tuple:
        """Every wall in the order of the engine's wall rows: the planes, the cylinders, then
        the parts of the finite walls and the fixed spheres."""
        return tuple(self.planes) + tuple(self.cylinders) + tuple(self.parts)

    @property
    def effective_landing_speed(self) -> float:
        """The landing speed the engine uses [m/s]: ``landing_speed``, but at least
        |g| tc_time / 2.

        A rebound slower than g_n tc_time / 2 comes back to the plane within tc_time, and the TC
        model makes that collision elastic: the sphere would bounce at that speed for ever and
        never land. Such rebounds land instead, which gives up at most ½ m (|g| tc_time / 2)²
        (½ m × 2.4e-9 m²/s² with the defaults) [OURS].
        """
        return max(self.landing_speed, float(np.linalg.norm(self.gravity)) * self.tc_time / 2.0)

    @property
    def n(self) -> int:
        """Number of spheres."""
        return int(self.radius.shape[0])

    @property
    def materials(self) -> list[Material]:
        """The used materials, indexed by material id."""
        return [self.library.materials[name] for name in self.material_names]

    def mass(self) -> np.ndarray:
        """Mass of every sphere, ρ 4/3 π R³ [kg], shape (N,)."""
        density = np.array([m.density for m in self.materials])
        return solid_sphere_mass(density[self.material], self.radius)

    def pair_table(self) -> np.ndarray:
        """Parameter rows of every pair of used materials (see :func:`hsgran.materials.pair_row`).

        Returns:
            ``float64`` array (M, M, PAIR_ROW_SIZE), symmetric in its first two indices. A pair
            that has no contact law (two rigid walls, which never meet) is all NaN.
        """
        mats = self.materials
        m = len(mats)
        table = np.full((m, m, PAIR_ROW_SIZE), np.nan)
        for i in range(m):
            for j in range(i, m):
                if mats[i].rigid and mats[j].rigid:
                    continue
                row = pair_row(mats[i], mats[j],
                               self.library.contact(mats[i].name, mats[j].name))
                table[i, j] = row
                table[j, i] = row
        return table


# ---- entry points ------------------------------------------------------------------------

def load_scene(path: str | Path, *, overrides=None) -> Scene:
    """Read and validate a scene file.

    Args:
        path: Path of a TOML scene file.
        overrides: Key path → value changes applied before validation (see
            :mod:`hsgran.overrides`), or ``None``.

    Returns:
        The validated :class:`Scene`.

    Raises:
        InputError: unreadable or too large file, TOML syntax error, or any invalid entry.
    """
    p = Path(path)
    try:
        size = p.stat().st_size
        if size > MAX_SCENE_BYTES:
            raise InputError(
                f"{p}: scene file is {size / 1024**2:.0f} MB, more than the "
                f"{MAX_SCENE_BYTES // 1024**2} MB limit; place many spheres with [[fill]] blocks")
        text = p.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise InputError(f"file not found: {p}") from None
    except (IsADirectoryError, PermissionError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read {p}: {exc.__class__.__name__}") from None
    return parse_scene(text, source=str(p), overrides=overrides)


def parse_scene(text: str, source: str = "<string>", *, overrides=None) -> Scene:
    """Validate the text of a scene file.

    Args:
        text: TOML text.
        source: Where the text comes from (kept in :attr:`Scene.source`, used in messages).
        overrides: Key path → value changes applied to the parsed document before validation
            (see :mod:`hsgran.overrides`), or ``None``. :attr:`Scene.text` then ends with them
            as comments, so a trajectory records what was run; an error in a value they set
            names the override.

    Returns:
        The validated :class:`Scene`.

    Raises:
        InputError: TOML syntax error or any invalid entry, naming the key path.
    """
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: TOML syntax error: {exc}") from None
    if not overrides:
        return _build(doc, text, source)
    doc = apply_overrides(doc, overrides)
    text += override_note(overrides)
    try:
        scene = _build(doc, text, source)
        scene.overrides = dict(overrides)
        return scene
    except InputError as exc:
        path = names_override(exc.key, overrides)
        if path is None:
            raise
        raise InputError(f"{exc} (value set by the override {path})") from None


def override_note(overrides) -> str:
    """The comment lines :func:`parse_scene` appends to :attr:`Scene.text` for ``overrides``
    (so that a trajectory's scene text says what was run)."""
    return "".join(f"\n# override: {k} = {v!r}" for k, v in overrides.items())


# ---- small validators --------------------------------------------------------------------

def _check_keys(table: dict, allowed, key: str) -> None:
    for k in table:
        if k not in allowed:
            path = f"{key}.{k}" if key else k
            raise InputError(
                f"unknown key '{k}'{did_you_mean(k, allowed)}; allowed: {', '.join(allowed)}",
                path)


def _table(value, key: str, what: str = "a table") -> dict:
    if not isinstance(value, dict):
        raise InputError(f"must be {what}, got {short_repr(value)}", key)
    return value


def _array_of_tables(doc: dict, name: str) -> list[dict]:
    value = doc.get(name, [])
    if not isinstance(value, list):
        raise InputError(f"must be an array of tables ([[{name}]]), not a single [{name}] table",
                         name)
    for k, item in enumerate(value):
        _table(item, f"{name}[{k}]")
    return value


def _require(table: dict, name: str, key: str, what: str):
    if name not in table:
        raise InputError(f"missing value ({what})", f"{key}.{name}")
    return table[name]


def _vector(value, key: str) -> np.ndarray:
    if not isinstance(value, list) or len(value) != 3:
        raise InputError(f"must be a list of 3 numbers [x, y, z], got {short_repr(value)}", key)
    return np.array([check_number(v, f"{key}[{i}]") for i, v in enumerate(value)])


def _length(vector: np.ndarray) -> float:
    """Euclidean length of a 3-vector, correctly rounded to within an ulp (math.hypot): a unit
    vector written in a scene stays as written when it is normalised (numpy's norm of
    (0, 0.28, 0.96) is 1 − 2⁻⁵³ with numpy 2.4, which would move it by an ulp)."""
    return math.hypot(*(float(v) for v in vector))


def _kind(table: dict, key: str, known: tuple, what: str, expected: str) -> str:
    """The ``kind`` of a table, one of ``known`` (``what`` names it in the message)."""
    kind = _string(_require(table, "kind", key, expected), f"{key}.kind")
    if kind not in known:
        raise InputError(f"unknown {what} '{kind}'{did_you_mean(kind, known)}; "
                         f"known: {', '.join(known)}", f"{key}.kind")
    return kind


def _direction(table: dict, name: str, key: str, meaning: str) -> np.ndarray:
    """The unit vector of ``table[name]`` (a non-zero [x, y, z]; ``meaning`` says what it
    points to, for the messages)."""
    vector = _vector(_require(table, name, key, f"[x, y, z] {meaning}"), f"{key}.{name}")
    length = _length(vector)
    if length == 0.0 or not math.isfinite(length):
        raise InputError(f"must be a non-zero vector ({meaning})", f"{key}.{name}")
    return vector / length


def _corners(table: dict, key: str) -> tuple[np.ndarray, np.ndarray]:
    """``lower`` and ``upper`` of a box [m], upper above lower on every axis."""
    lower = _vector(_require(table, "lower", key, "lowest corner [x, y, z] in m"),
                    f"{key}.lower")
    upper = _vector(_require(table, "upper", key, "highest corner [x, y, z] in m"),
                    f"{key}.upper")
    for i in range(3):
        if not lower[i] < upper[i]:
            raise InputError(
                f"must exceed lower on every axis ({AXES[i]}: upper "
                f"{_fmt(upper[i])} <= lower {_fmt(lower[i])})", f"{key}.upper")
    return lower, upper


def _check_magnitude(vector: np.ndarray, limit: float, unit: str, key: str) -> None:
    """Refuse a vector longer than ``limit`` (see :data:`MAX_SPEED`, :data:`MAX_GRAVITY`)."""
    with np.errstate(over="ignore"):  # 1e300 squared is inf, which is refused below
        size = float(np.sqrt(np.sum(np.square(vector, dtype=np.float64))))
    if not size <= limit:
        raise InputError(f"magnitude {size:.3g} is beyond {limit:.0e} {unit}: not a physical "
                         "value for this model", key)


def _string(value, key: str) -> str:
    if not isinstance(value, str):
        raise InputError(f"must be a string, got {short_repr(value)}", key)
    return value


def _count(value, key: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(f"must be a whole number, got {short_repr(value)}", key)
    if value < 1:
        raise InputError(f"must be >= 1, got {value}", key)
    return value


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def _fmt_apart(a: float, b: float) -> tuple[str, str]:
    """``a`` and ``b`` with the fewest significant digits (at least 6) that tell them apart."""
    for digits in range(6, 18):
        sa, sb = f"{a:.{digits}g}", f"{b:.{digits}g}"
        if sa != sb:
            return sa, sb
    return repr(a), repr(b)


# ---- the parts of a scene ----------------------------------------------------------------
#
# Each part is a function of the document and of the parts it needs, passed as arguments, so no
# part can be made before what it uses. _build calls them in the order of the checks: when a
# file has several problems, the first one in that order is reported.

@dataclass(frozen=True, eq=False)
class _Head:
    """The checked [scene] table (see :class:`Scene` for the fields)."""

    name: str
    duration: float
    effects: Effects
    gravity: np.ndarray
    seed: int
    periodic: tuple[bool, bool, bool]


@dataclass(frozen=True)
class _Enduring:
    """The checked [enduring_contact] table (see :class:`Scene` for the fields)."""

    landing_speed: float
    tc_time: float
    rolling_convention: str
    treatment: str


@dataclass(frozen=True, eq=False)
class _Walls:
    """The checked [[walls]] entries (dicts with the key path, kind, vectors and material
    name) and the box's corners [m] and key path (``None`` without a box)."""

    entries: list[dict]
    box_lower: np.ndarray | None
    box_upper: np.ndarray | None
    box_key: str | None


@dataclass(frozen=True, eq=False)
class _Spheres:
    """Sphere arrays in scene order: centres [m] (N, 3), velocities [m/s] (N, 3), angular
    velocities [rad/s] (N, 3), radii [m] (N,), material ids (N,)."""

    position: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    radius: np.ndarray
    material: np.ndarray

    def then(self, other: _Spheres) -> _Spheres:
        """These spheres followed by ``other``."""
        return _Spheres(*(np.concatenate([a, b])
                          for a, b in zip(self.arrays(), other.arrays(), strict=True)))

    def arrays(self) -> tuple[np.ndarray, ...]:
        return (self.position, self.velocity, self.angular_velocity, self.radius, self.material)


@dataclass(frozen=True)
class _Names:
    """How messages name spheres: the labels of the explicit particles (``particles[3]``), then
    (key, start, stop) of each fill's index range."""

    labels: list[str]
    fill_ranges: list[tuple[str, int, int]]

    def label(self, i: int) -> str:
        """How messages name sphere ``i``: ``particles[3]`` or ``fill[0] sphere 12``."""
        if i < len(self.labels):
            return self.labels[i]
        for key, start, stop in self.fill_ranges:
            if start <= i < stop:
                return f"{key} sphere {i - start}"
        return f"sphere {i}"

    def position_key(self, i: int) -> str:
        """Key path blamed for the position of sphere ``i``."""
        if i < len(self.labels):
            return f"{self.labels[i]}.position"
        for key, start, stop in self.fill_ranges:
            if start <= i < stop:
                return f"{key}.region"
        return "particles"


def _build(doc: dict, text: str, source: str) -> Scene:
    """Check a parsed document part by part and assemble the :class:`Scene`."""
    _check_keys(doc, TOP_KEYS, "")
    head = _parse_head(doc, source)
    frame_interval, observables = _parse_output(doc, head.duration)
    enduring = _parse_enduring(doc)
    library = MaterialLibrary()
    library.add_tables(doc, origin=source)
    walls = _parse_walls(doc, library, head.periodic, source)
    outlets = _parse_outlets(doc, head.periodic, None if walls.box_key is None
                             else (walls.box_lower, walls.box_upper))
    particles = _parse_particles(doc, library, head.effects)
    fixed = [p for p in particles if p["fixed"]]  # (walls: hsgran.shapes.ball)
    particles = [p for p in particles if not p["fixed"]]
    fixed_keys: set = set()
    fills = _parse_fills(doc, library, head.effects, walls, fixed_keys)
    fixed_fills = [f for f in fills if f.key in fixed_keys]  # (walls, placed first)
    fills = [f for f in fills if f.key not in fixed_keys]
    inflows = _parse_inflows(doc, library, walls, frame_interval, head.duration)
    _check_total(len(particles), [(f.key, f.count) for f in fills]
                 + [(f["key"], f["count"]) for f in inflows])
    _check_periodic_planes(walls, head.periodic)
    if len(particles) + sum(f.count for f in fills) + sum(f["count"] for f in inflows) == 0:
        raise InputError("the scene has no particles: add [[particles]], [[fill]] or "
                         "[[inflow]] blocks", "particles")

    sphere_materials = _unique([p["material"] for p in particles] + [f.material for f in fills]
                               + [f["material"] for f in inflows if not f["recirculate"]])
    material_names = _unique(sphere_materials + _wall_materials(walls, head.periodic)
                             + [p["material"] for p in fixed] + [f.material for f in fixed_fills])
    names = _sphere_names(particles, fills)
    explicit = _explicit_spheres(particles, material_names)
    planes = _make_planes(walls, head.periodic, material_names)
    cylinders = _make_cylinders(walls, material_names)
    parts = _make_parts(walls, material_names, fixed)
    _check_moving(planes, cylinders, enduring.treatment)
    space = _space(planes, cylinders, parts, walls, head.periodic)

    # everything that does not need the fills' positions, before the (costly) placement
    radii = np.concatenate([explicit.radius, [f.radius[1] for f in fills],
                            [f["radius"][1] for f in inflows if not f["recirculate"]]])
    _check_grid(walls, head.periodic, radii)
    if fixed_fills:
        parts = _place_fixed(head.seed, fixed_fills, explicit, space, parts, material_names)
        space = _space(planes, cylinders, parts, walls, head.periodic)
    if any(head.periodic) and parts:
        parts = _periodic_images(parts, walls, head.periodic, float(radii.max(initial=0.0)))
        space = _space(planes, cylinders, parts, walls, head.periodic)
    _check_explicit(walls, head.periodic, explicit.position, names)
    _check_overlaps(explicit.position, explicit.radius, space, names)
    _check_planes(planes + list(cylinders) + list(parts), explicit.position, explicit.radius,
                  names)
    counts = _sphere_counts(explicit, fills, material_names)
    for f in inflows:  # an inflow's spheres meet the same walls and spheres
        if not f["recirculate"]:
            counts[material_names.index(f["material"])] += f["count"]
    _check_friction(head.effects, library, material_names, counts,
                    planes + list(cylinders) + list(parts))
    _check_plasticity(doc, head.effects, sphere_materials)

    spheres = _place_fills(head.seed, fills, explicit, space, material_names)
    if fills:
        # placement guarantees both; re-checking all spheres costs little and guards it
        _check_overlaps(spheres.position, spheres.radius, space, names)
        _check_planes(planes + list(cylinders) + list(parts), spheres.position, spheres.radius,
                      names)
    _check_outlets(outlets, spheres.position, names)
    n_present = spheres.radius.shape[0]
    inflow_rows, reserve = _reserve_rows(head.seed, inflows, n_present, material_names)
    spheres = spheres.then(reserve)
    _check_inflows(inflow_rows, outlets, spheres.radius)
    if observables and (outlets or inflows):
        raise InputError("the observables (stress, wall impulses) are not kept for open systems "
                         "yet: a sphere that leaves or enters would unbalance the momentum "
                         "ledgers; remove 'observables' or the outlets and inflows",
                         "output.observables")

    return Scene(
        name=head.name,
        duration=head.duration,
        gravity=head.gravity,
        effects=head.effects,
        seed=head.seed,
        periodic=head.periodic,
        box_lower=walls.box_lower,
        box_upper=walls.box_upper,
        planes=planes,
        frame_interval=frame_interval,
        library=library,
        material_names=material_names,
        position=np.ascontiguousarray(spheres.position, dtype=np.float64),
        velocity=np.ascontiguousarray(spheres.velocity, dtype=np.float64),
        angular_velocity=np.ascontiguousarray(spheres.angular_velocity, dtype=np.float64),
        radius=np.ascontiguousarray(spheres.radius, dtype=np.float64),
        material=np.ascontiguousarray(spheres.material, dtype=np.int64),
        text=text,
        source=source,
        landing_speed=enduring.landing_speed,
        rolling_convention=enduring.rolling_convention,
        tc_time=enduring.tc_time,
        treatment=enduring.treatment,
        observables=observables,
        cylinders=cylinders,
        parts=parts,
        outlets=outlets,
        inflows=inflow_rows,
        present=np.arange(spheres.radius.shape[0]) < n_present,
        space=space,
    )


def _unique(names: list[str]) -> list[str]:
    """The names in order of first appearance, each once."""
    return list(dict.fromkeys(names))


# -- [scene], [output] and [enduring_contact] --

def _parse_head(doc: dict, source: str) -> _Head:
    sc = _table(doc.get("scene", {}), "scene", "a table ([scene])")
    _check_keys(sc, SCENE_KEYS, "scene")
    default_name = Path(source).stem if source != "<string>" else "unnamed"
    name = _string(sc.get("name", default_name), "scene.name")
    duration = check_positive(
        _require(sc, "duration", "scene", "simulated time in s"), "scene.duration", "s")
    effects = Effects.parse(sc.get("effects", []), "scene.effects")
    if "gravity" in sc:
        gravity = _vector(sc["gravity"], "scene.gravity")
        _check_magnitude(gravity, MAX_GRAVITY, "m/s^2", "scene.gravity")
        if not effects.gravity:
            raise InputError("listed but the 'gravity' effect is off: add \"gravity\" to "
                             "scene.effects or remove scene.gravity", "scene.gravity")
    elif effects.gravity:
        gravity = np.array(STANDARD_GRAVITY)
    else:
        gravity = np.zeros(3)
    seed = sc.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"must be a whole number >= 0, got {short_repr(seed)}", "scene.seed")
    periodic = sc.get("periodic", [False, False, False])
    if (not isinstance(periodic, list) or len(periodic) != 3
            or not all(isinstance(b, bool) for b in periodic)):
        raise InputError(f"must be a list of 3 booleans [x, y, z], got {short_repr(periodic)}",
                         "scene.periodic")
    return _Head(name, duration, effects, gravity, seed, tuple(periodic))


def _parse_enduring(doc: dict) -> _Enduring:
    tab = _table(doc.get("enduring_contact", {}), "enduring_contact",
                 "a table ([enduring_contact])")
    _check_keys(tab, ENDURING_KEYS, "enduring_contact")
    landing_speed = DEFAULT_LANDING_SPEED
    if "landing_speed" in tab:
        landing_speed = check_positive(tab["landing_speed"], "enduring_contact.landing_speed",
                                       "m/s")
    tc_time = DEFAULT_TC_TIME
    if "tc_time" in tab:
        tc_time = check_number(tab["tc_time"], "enduring_contact.tc_time")
        if tc_time < 0.0:
            raise InputError(f"must be >= 0 s (0 turns the TC model off), got "
                             f"{tab['tc_time']!r}", "enduring_contact.tc_time")
    conv = tab.get("rolling_convention", "A")
    if conv not in ROLLING_CONVENTIONS:
        raise InputError(f"must be \"A\" ({ROLLING_CONVENTIONS['A']}) or \"B\" "
                         f"({ROLLING_CONVENTIONS['B']}), got {short_repr(conv)}",
                         "enduring_contact.rolling_convention")
    treatment = tab.get("treatment", "pairwise")
    if treatment not in TREATMENTS:
        raise InputError(f"must be one of {', '.join(repr(t) for t in TREATMENTS)}, got "
                         f"{short_repr(treatment)}", "enduring_contact.treatment")
    return _Enduring(landing_speed, tc_time, conv, treatment)


def _parse_output(doc: dict, duration: float) -> tuple[float, bool]:
    """The frame interval [s], and whether the observables of docs/observables.md are summed."""
    out = _table(doc.get("output", {}), "output", "a table ([output])")
    observables = out.get("observables", False)
    if not isinstance(observables, bool):
        raise InputError(f"must be true or false, got {short_repr(observables)}",
                         "output.observables")
    _check_keys(out, OUTPUT_KEYS, "output")
    frame_interval = check_positive(
        _require(out, "frame_interval", "output", "time between frames in s"),
        "output.frame_interval", "s")
    frames = duration / frame_interval
    if frames > MAX_FRAMES:
        raise InputError(
            f"{_fmt(frame_interval)} s gives {frames:.3g} frames over "
            f"{_fmt(duration)} s, more than the limit of {MAX_FRAMES:.0e}",
            "output.frame_interval")
    return frame_interval, observables


def _material_name(library: MaterialLibrary, value, key: str) -> str:
    name = _string(value, key)
    library.material(name, key)  # raises with a "did you mean" hint
    return name


# -- [[walls]] --

def _parse_walls(doc: dict, library: MaterialLibrary, periodic: tuple,
                 source: str = "<string>") -> _Walls:
    entries: list[dict] = []
    box_lower = box_upper = None
    box_key: str | None = None
    for k, w in enumerate(_array_of_tables(doc, "walls")):
        key = f"walls[{k}]"
        kind = _kind(w, key, WALL_KINDS, "wall kind", "'plane' or 'box'")
        if kind == "cylinder":
            entries.append(_parse_cylinder(w, key, library, periodic))
            continue
        if kind in ("polygon", "disk", "sphere"):
            entries.append(_parse_finite(w, key, kind, library))
            continue
        if kind == "mesh":
            entries.append(_parse_mesh(w, key, library, source))
            continue
        if kind == "plane":
            _check_keys(w, PLANE_KEYS, key)
            point = _vector(_require(w, "point", key, "a point of the plane [x, y, z] in m"),
                            f"{key}.point")
            normal = _direction(w, "normal", key, "pointing to where the spheres live")
            material = _material_name(
                library, _require(w, "material", key, "a material name"), f"{key}.material")
            motion = (_parse_motion(w["motion"], f"{key}.motion", normal)
                      if "motion" in w else None)
            hole = _parse_hole(w["hole"], f"{key}.hole", point, normal) if "hole" in w else None
            if hole is not None and motion is not None:
                raise InputError("a plane with a hole cannot move yet", f"{key}.motion")
            entries.append(dict(kind=kind, key=key, point=point, normal=normal,
                                material=material, motion=motion, hole=hole))
        else:
            _check_keys(w, BOX_KEYS, key)
            if box_key is not None:
                raise InputError(f"a scene has at most one box ({box_key} is one); "
                                 "add further walls as planes", key)
            lower, upper = _corners(w, key)
            if "material" in w:
                material = _material_name(library, w["material"], f"{key}.material")
            elif all(periodic):
                material = None  # a fully periodic box has no walls to be made of anything
            else:
                raise InputError("missing value (a material name; the box has walls on its "
                                 "non-periodic axes)", f"{key}.material")
            box_lower, box_upper, box_key = lower, upper, key
            entries.append(dict(kind=kind, key=key, lower=lower, upper=upper,
                                material=material, motion=_box_motions(w, key, periodic)))
    if any(periodic) and box_key is None:
        axes = ", ".join(AXES[i] for i in range(3) if periodic[i])
        raise InputError(f"periodic along {axes} needs a [[walls]] entry of kind = \"box\" "
                         "giving the period", "scene.periodic")
    return _Walls(entries, box_lower, box_upper, box_key)


def _parse_outlets(doc: dict, periodic: tuple, box=None) -> tuple:
    """The ``[[outlets]]`` entries → :class:`Outlet` values (docs/open-systems.md); ``box``:
    the box's (lower, upper) corners, or ``None``."""
    outlets = []
    for k, t in enumerate(_array_of_tables(doc, "outlets")):
        key = f"outlets[{k}]"
        kind = _kind(t, key, tuple(OUTLET_KEYS), "outlet kind", "'below' or 'box'")
        _check_keys(t, OUTLET_KEYS[kind], key)
        row = np.zeros(OL_SIZE)
        if kind == "below":
            row[OL_KIND] = OUT_BELOW
            row[OL_A:OL_A + 3] = _vector(_require(t, "point", key, "a point of the plane "
                                                  "[x, y, z] in m"), f"{key}.point")
            normal = _direction(t, "normal", key, "pointing away from the outlet, to the "
                                "spheres that stay")
            for i in range(3):
                if periodic[i] and abs(normal[i]) > PARALLEL_TOLERANCE:
                    raise InputError(f"must be perpendicular to the periodic axis {AXES[i]} "
                                     "(a sphere would leave one image and not the next)",
                                     f"{key}.normal")
            row[OL_B:OL_B + 3] = normal
        else:
            row[OL_KIND] = OUT_BOX
            row[OL_A:OL_A + 3], row[OL_B:OL_B + 3] = _corners(t, key)
            for i in range(3):
                if periodic[i] and box is not None and not (
                        box[0][i] <= row[OL_A + i] and row[OL_B + i] <= box[1][i]):
                    raise InputError(f"must lie inside the periodic box along {AXES[i]} (the "
                                     "spheres' coordinates wrap there)", f"{key}.upper")
        outlets.append(Outlet(row, key))
    return tuple(outlets)


def _parse_finite(w: dict, key: str, kind: str, library: MaterialLibrary) -> dict:
    """A ``polygon``, ``disk`` or ``sphere`` entry → its checked values: the corners of its
    face, or a fixed sphere's centre and radius (docs/walls.md, "Finite walls")."""
    _check_keys(w, {"polygon": POLYGON_KEYS, "disk": DISK_KEYS, "sphere": SPHERE_KEYS}[kind],
                key)
    material = _material_name(library, _require(w, "material", key, "a material name"),
                              f"{key}.material")
    if kind == "sphere":
        center = _vector(_require(w, "center", key, "[x, y, z] in m"), f"{key}.center")
        radius = check_positive(_require(w, "radius", key, "in m"), f"{key}.radius", "m")
        return dict(kind=kind, key=key, center=center, radius=radius, material=material)
    faces = _face_sides(w, key)
    if kind == "polygon":
        value = _require(w, "vertices", key, "a list of [x, y, z] in m, in order around it")
        if not isinstance(value, list) or len(value) < shapes.MIN_SIDES:
            raise InputError(f"must be a list of at least {shapes.MIN_SIDES} points [x, y, z] "
                             f"in m, got {short_repr(value)}", f"{key}.vertices")
        corners = np.array([_vector(v, f"{key}.vertices[{i}]") for i, v in enumerate(value)])
        corner_key = f"{key}.vertices"
    else:
        center = _vector(_require(w, "center", key, "[x, y, z] in m"), f"{key}.center")
        normal = _direction(w, "normal", key, "its front side")
        radius = check_positive(_require(w, "radius", key, "in m"), f"{key}.radius", "m")
        corners = shapes.regular_polygon(center, normal, radius, _corner_count(w, key))
        corner_key = f"{key}.radius"
    try:
        shapes.polygon(corners, 0, key)  # (the checks of its corners)
    except ValueError as exc:
        raise InputError(str(exc), corner_key) from None
    return dict(kind="polygon", key=key, corners=corners, both=faces == "both",
                material=material)


def _parse_mesh(w: dict, key: str, library: MaterialLibrary, source: str) -> dict:
    """A ``mesh`` entry → its triangles [m] (T, 3, 3): an STL file (or any format trimesh
    reads) relative to the scene file's folder, times ``scale``, plus ``offset``. Triangles
    of no area are left out (they are no contact geometry)."""
    _check_keys(w, MESH_KEYS, key)
    material = _material_name(library, _require(w, "material", key, "a material name"),
                              f"{key}.material")
    name = _string(_require(w, "file", key, "a triangle mesh, e.g. an STL file"), f"{key}.file")
    path = Path(name)
    if not path.is_absolute() and source != "<string>":
        path = Path(source).parent / path
    faces = _face_sides(w, key)
    scale = check_positive(w.get("scale", 1.0), f"{key}.scale", "m per file unit")
    offset = _vector(w["offset"], f"{key}.offset") if "offset" in w else np.zeros(3)
    try:
        triangles = shapes.read_mesh(path)
    except Exception as exc:
        raise InputError(f"cannot read the mesh {path}: {exc.__class__.__name__}: {exc}",
                         f"{key}.file") from None
    if len(triangles) > MAX_TRIANGLES:
        raise InputError(f"{len(triangles)} triangles, more than {MAX_TRIANGLES}",
                         f"{key}.file")
    triangles = triangles * scale + offset
    parts = []
    for k, triangle in enumerate(triangles):
        try:
            parts += shapes.polygon(triangle, 0, key, faces == "both")
        except ValueError as exc:
            raise InputError(f"triangle {k}: {exc}", f"{key}.file") from None
    return dict(kind="mesh", key=key, parts=parts, material=material)


def _flag(table: dict, name: str, key: str) -> bool:
    """``table[name]``, true or false (false when not given)."""
    value = table.get(name, False)
    if not isinstance(value, bool):
        raise InputError(f"must be true or false, got {short_repr(value)}", f"{key}.{name}")
    return value


def _fixed(table: dict, key: str, motion: tuple) -> bool:
    """The ``fixed`` flag of a [[particles]] or [[fill]] entry; a fixed sphere may not be
    given any of the ``motion`` keys."""
    fixed = _flag(table, "fixed", key)
    for name in motion if fixed else ():
        if name in table:
            raise InputError("a fixed sphere does not move; remove it", f"{key}.{name}")
    return fixed


def _face_sides(table: dict, key: str) -> str:
    """``faces`` of a polygon, disk or mesh: which sides spheres meet (FACE_SIDES)."""
    faces = _string(table.get("faces", "both"), f"{key}.faces")
    if faces not in FACE_SIDES:
        raise InputError(f"unknown side '{faces}'{did_you_mean(faces, FACE_SIDES)}; known: "
                         f"{', '.join(FACE_SIDES)}", f"{key}.faces")
    return faces


def _corner_count(table: dict, key: str) -> int:
    """``corners`` of a circle's regular polygon (shapes.DEFAULT_SIDES unless given)."""
    value = table.get("corners", shapes.DEFAULT_SIDES)
    if (isinstance(value, bool) or not isinstance(value, int)
            or not shapes.MIN_SIDES <= value <= MAX_CORNERS):
        raise InputError(f"must be a whole number from {shapes.MIN_SIDES} to {MAX_CORNERS}, "
                         f"got {short_repr(value)}", f"{key}.corners")
    return value


def _parse_hole(tab, key: str, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """A plane's ``hole`` table → the corners [m] of the hole, a convex polygon in the plane."""
    tab = _table(tab, key, "a table: { shape = \"circle\", center, radius } or "
                           "{ shape = \"rectangle\", center, size }")
    shape = _string(_require(tab, "shape", key, "'circle' or 'rectangle'"), f"{key}.shape")
    if shape not in HOLE_KEYS:
        raise InputError(f"unknown shape '{shape}'{did_you_mean(shape, tuple(HOLE_KEYS))}; "
                         f"known: {', '.join(HOLE_KEYS)}", f"{key}.shape")
    _check_keys(tab, HOLE_KEYS[shape], key)
    center = _vector(_require(tab, "center", key, "[x, y, z] in m, in the plane"),
                     f"{key}.center")
    off = float(np.dot(center - point, normal))
    if abs(off) > shapes.FLAT_REL * (_length(center) + _length(point) + 1.0):
        raise InputError(f"must lie in the plane (it is {_fmt(off)} m off it)", f"{key}.center")
    if shape == "circle":
        radius = check_positive(_require(tab, "radius", key, "in m"), f"{key}.radius", "m")
        return shapes.regular_polygon(center, normal, radius, _corner_count(tab, key))
    size = _require(tab, "size", key, "[width, height] in m")
    if not isinstance(size, list) or len(size) != 2:
        raise InputError(f"must be [width, height] in m, got {short_repr(size)}",
                         f"{key}.size")
    size = [check_positive(v, f"{key}.size[{i}]", "m") for i, v in enumerate(size)]
    first = None
    if "axis" in tab:
        first = _direction(tab, "axis", key, "along the first side")
        if abs(float(np.dot(first, normal))) > 1.0 - PARALLEL_TOLERANCE:
            raise InputError("must not be along the plane's normal", f"{key}.axis")
    return shapes.rectangle(center, normal, size, first)


def _periodic_images(parts: tuple, walls: _Walls, periodic: tuple, r_max: float) -> tuple:
    """The parts with an image of every fixed sphere (or corner) within a sphere's reach of an
    end of a periodic axis, across it, so spheres on either side meet it; a face or an edge
    must keep clear of the ends by that reach (a sphere moving on it would change images)."""
    out = list(parts)
    lower, upper = walls.box_lower, walls.box_upper
    for k in range(3):
        if not periodic[k]:
            continue
        length = upper[k] - lower[k]
        for q in list(out):
            box = q.bounds()
            if q.kind != WK_BALL:
                corners = q.corners if box is None else np.array(box)
                if box is None and abs(q.normal[k]) > PARALLEL_TOLERANCE:
                    raise InputError(f"a plane with a hole must be parallel to the periodic "
                                     f"axis {AXES[k]}", f"{q.key}.normal")
                if len(corners) and (corners[:, k].min() - r_max < lower[k]
                                     or corners[:, k].max() + r_max > upper[k]):
                    raise InputError(
                        f"a finite wall must keep one sphere radius ({_fmt(r_max)} m) clear of "
                        f"the ends of the periodic axis {AXES[k]} (only fixed spheres may "
                        "reach across them)", q.key)
                continue
            for sign in (1.0, -1.0):
                if (box[0][k] - r_max < lower[k]) if sign > 0 else (box[1][k] + r_max
                                                                    > upper[k]):
                    shift = np.zeros(3)
                    shift[k] = sign * length
                    out.append(shapes.ball(q.point + shift, q.geo[BL_RADIUS], q.material,
                                           q.key))
    return tuple(out)


def _make_parts(walls: _Walls, material_names: list[str], fixed: list[dict]) -> tuple:
    """The parts of the finite walls and the fixed spheres (hsgran.shapes.Part), in file
    order, then the fixed [[particles]]."""
    parts = []
    for w in walls.entries:
        if w["kind"] not in ("polygon", "mesh", "sphere", "plane"):
            continue
        material = material_names.index(w["material"])
        if w["kind"] == "polygon":
            parts += shapes.polygon(w["corners"], material, w["key"], w["both"])
        elif w["kind"] == "mesh":
            parts += [replace(q, material=material) for q in w["parts"]]
        elif w["kind"] == "sphere":
            parts.append(shapes.ball(w["center"], w["radius"], material, w["key"]))
        elif w["kind"] == "plane" and w.get("hole") is not None:
            parts += shapes.plane_with_hole(w["point"], w["normal"], w["hole"], material,
                                            w["key"])
    for p in fixed:
        parts.append(shapes.ball(p["position"], p["radius"], material_names.index(p["material"]),
                                 p["key"]))
    parts = shapes.weld(parts)
    # the faces without outline first: every prediction looks at them (after the planes and
    # cylinders, the first wall rows), the others through the cell grid (engine._wall_lists)
    return tuple([q for q in parts if q.bounds() is None]
                 + [q for q in parts if q.bounds() is not None])


def _parse_cylinder(w: dict, key: str, library: MaterialLibrary, periodic: tuple) -> dict:
    """A ``kind = "cylinder"`` entry → its checked values (docs/walls.md, "Cylinders")."""
    _check_keys(w, CYLINDER_KEYS, key)
    center = _vector(_require(w, "center", key, "the middle of its axis [x, y, z] in m"),
                     f"{key}.center")
    axis = _vector(_require(w, "axis", key, "its direction [x, y, z]"), f"{key}.axis")
    length = _length(axis)
    if length == 0.0 or not math.isfinite(length):
        raise InputError("must be a non-zero vector (the cylinder's direction)", f"{key}.axis")
    axis = axis / length
    radius = check_positive(_require(w, "radius", key, "in m"), f"{key}.radius", "m")
    extent = check_positive(_require(w, "length", key, "in m, along the axis"),
                            f"{key}.length", "m")
    side = _string(w.get("side", "inside"), f"{key}.side")
    if side not in CYLINDER_SIDES:
        raise InputError(f"unknown side '{side}'{did_you_mean(side, CYLINDER_SIDES)}; known: "
                         f"{', '.join(CYLINDER_SIDES)}", f"{key}.side")
    inside = side == "inside"
    along = [i for i in range(3) if periodic[i]]
    for i in along:
        if abs(abs(axis[i]) - 1.0) > PARALLEL_TOLERANCE:
            raise InputError(f"a cylinder must lie along the periodic axis {AXES[i]}",
                             f"{key}.axis")
    caps = w.get("caps", inside and not along)
    if not isinstance(caps, bool):
        raise InputError(f"must be true or false, got {caps!r}", f"{key}.caps")
    if caps and not inside:
        raise InputError("only a cylinder with the spheres inside has caps (outside, close "
                         "the scene with planes or a box)", f"{key}.caps")
    if caps and along:
        raise InputError(f"a cylinder along the periodic axis {AXES[along[0]]} has no caps",
                         f"{key}.caps")
    omega = check_number(w.get("angular_velocity", 0.0), f"{key}.angular_velocity")
    material = _material_name(library, _require(w, "material", key, "a material name"),
                              f"{key}.material")
    return dict(kind="cylinder", key=key, center=center, axis=axis, radius=radius,
                half_length=0.5 * extent, inside=inside, caps=caps, angular_velocity=omega,
                material=material)


def _make_cylinders(walls: _Walls, material_names: list[str]) -> tuple:
    """The cylinder walls, in file order."""
    out = []
    for w in walls.entries:
        if w["kind"] != "cylinder":
            continue
        center = np.array(w["center"], dtype=float)
        axis = np.array(w["axis"], dtype=float)
        center.setflags(write=False)
        axis.setflags(write=False)
        out.append(Cylinder(center, axis, float(w["radius"]), float(w["half_length"]),
                            bool(w["inside"]), float(w["angular_velocity"]),
                            material_names.index(w["material"]), w["key"]))
    return tuple(out)


def _parse_motion(tab, key: str, normal: np.ndarray) -> np.ndarray:
    """A plane's ``motion`` table → its row of hsgran.wallmotion ``M_*`` values."""
    tab = _table(tab, key, "a table: { kind = \"oscillation\", ... } or "
                           "{ kind = \"velocity\", ... }")
    kind = _kind(tab, key, tuple(MOTION_KEYS), "motion", "'oscillation' or 'velocity'")
    _check_keys(tab, MOTION_KEYS[kind], key)
    row = np.zeros(M_SIZE)
    if kind == "oscillation":
        direction = (_vector(tab["direction"], f"{key}.direction") if "direction" in tab
                     else normal)
        length = _length(direction)
        if length == 0.0 or not math.isfinite(length):
            raise InputError("must be a non-zero vector", f"{key}.direction")
        row[M_KIND] = MOT_OSCILLATION
        row[M_DIR:M_DIR + 3] = direction / length
        row[M_AMP] = check_positive(_require(tab, "amplitude", key, "in m"),
                                    f"{key}.amplitude", "m")
        row[M_OMEGA] = 2.0 * math.pi * check_positive(
            _require(tab, "frequency", key, "in Hz"), f"{key}.frequency", "Hz")
        row[M_PHASE] = check_number(tab.get("phase", 0.0), f"{key}.phase")
    else:
        velocity = _vector(_require(tab, "velocity", key, "[x, y, z] in m/s"),
                           f"{key}.velocity")
        speed = float(np.linalg.norm(velocity))
        if speed == 0.0 or not math.isfinite(speed):
            raise InputError("must be a non-zero velocity in m/s", f"{key}.velocity")
        row[M_KIND] = MOT_VELOCITY
        row[M_DIR:M_DIR + 3] = velocity / speed
        row[M_AMP] = speed
        start = check_number(tab.get("start", 0.0), f"{key}.start")
        if start < 0.0:
            raise InputError(f"must be >= 0 s, got {start!r}", f"{key}.start")
        row[M_PHASE] = start
        row[M_TRAVEL] = check_positive(_require(tab, "travel", key,
                                                "distance in m after which it stops"),
                                       f"{key}.travel", "m")
    row.setflags(write=False)
    return row


def _box_motions(w: dict, key: str, periodic: tuple) -> dict:
    """The box's ``motion`` table: face name (``lower_z`` …) → motion row."""
    if "motion" not in w:
        return {}
    tab = _table(w["motion"], f"{key}.motion",
                 "a table of faces: { lower_z = { kind = \"oscillation\", ... } }")
    motions = {}
    for face, value in tab.items():
        fkey = f"{key}.motion.{face}"
        if face not in BOX_FACES:
            raise InputError(f"unknown face '{face}'{did_you_mean(face, BOX_FACES)}; known: "
                             f"{', '.join(BOX_FACES)}", fkey)
        axis = AXES.index(face[-1])
        if periodic[axis]:
            raise InputError(f"the box has no {face} face: the {face[-1]} axis is periodic",
                             fkey)
        normal = np.zeros(3)
        normal[axis] = 1.0 if face.startswith("lower") else -1.0
        motions[face] = _parse_motion(value, fkey, normal)
    return motions


def _check_moving(planes: list[Plane], cylinders: tuple, treatment: str) -> None:
    moving = ([p.key for p in planes if p.motion is not None]
              + [c.key for c in cylinders if c.angular_velocity != 0.0])
    if moving and treatment == "clusters":
        raise InputError(f"moving planes and turning cylinders ({moving[0]}) are not "
                         "supported with the cluster treatment yet; use \"pairwise\"",
                         "enduring_contact.treatment")


def _check_periodic_planes(walls: _Walls, periodic: tuple) -> None:
    for w in walls.entries:
        if w["kind"] != "plane":
            continue
        for i in range(3):
            if periodic[i] and abs(w["normal"][i]) > PARALLEL_TOLERANCE:
                raise InputError(
                    f"a plane wall must be parallel to the periodic axis {AXES[i]} (its "
                    f"normal needs a zero {AXES[i]} component)", f"{w['key']}.normal")


def _wall_materials(walls: _Walls, periodic: tuple) -> list[str]:
    """Materials of the walls that produce at least one plane, in file order."""
    return [w["material"] for w in walls.entries
            if w["material"] is not None and (w["kind"] != "box" or not all(periodic))]


def _make_planes(walls: _Walls, periodic: tuple, material_names: list[str]) -> list[Plane]:
    """Every plane wall, and the box's faces on its non-periodic axes, in file order."""
    planes = []
    for w in walls.entries:
        if w["kind"] in ("polygon", "sphere", "mesh"):
            continue  # (parts: _make_parts)
        if w["kind"] == "plane":
            if w.get("hole") is not None:
                continue  # a face with a hole (_make_parts)
            planes.append(_frozen_plane(w["point"], w["normal"],
                                        material_names.index(w["material"]), w["key"],
                                        w["motion"]))
            continue
        if w["kind"] == "cylinder":
            if w["caps"]:  # two planes close its ends, facing each other
                for end, sign in (("lower", 1.0), ("upper", -1.0)):
                    planes.append(_frozen_plane(
                        w["center"] - sign * w["half_length"] * w["axis"], sign * w["axis"],
                        material_names.index(w["material"]), f"{w['key']}.cap_{end}"))
            continue
        for i in range(3):
            if periodic[i]:
                continue
            for side, corner, sign in (("lower", w["lower"], 1.0), ("upper", w["upper"], -1.0)):
                normal = np.zeros(3)
                normal[i] = sign
                planes.append(_frozen_plane(corner.copy(), normal,
                                            material_names.index(w["material"]),
                                            f"{w['key']}.{side}_{AXES[i]}",
                                            w["motion"].get(f"{side}_{AXES[i]}")))
    return planes


def _frozen_plane(point: np.ndarray, normal: np.ndarray, material: int, key: str,
                  motion: np.ndarray | None = None) -> Plane:
    point = np.array(point, dtype=float)
    normal = np.array(normal, dtype=float)
    point.setflags(write=False)
    normal.setflags(write=False)
    return Plane(point, normal, material, key, motion)


def _space(planes: list[Plane], cylinders: tuple, parts: tuple, walls: _Walls,
           periodic: tuple) -> Space:
    """Where spheres may lie, for placement and the overlap checks."""
    if walls.box_key is None:
        origin, period = np.zeros(3), np.zeros(3)
    else:
        origin = walls.box_lower
        period = np.where(periodic, walls.box_upper - walls.box_lower, 0.0)
    return Space(plane_point=np.array([p.point for p in planes], dtype=float).reshape(-1, 3),
                 plane_normal=np.array([p.normal for p in planes], dtype=float).reshape(-1, 3),
                 origin=origin, period=period,
                 cyl_center=np.array([c.center for c in cylinders], dtype=float).reshape(-1, 3),
                 cyl_row=np.array([c.row() for c in cylinders],
                                  dtype=float).reshape(-1, CY_SIZE),
                 parts=shapes.tables(parts))


# -- [[particles]] --

def _parse_particles(doc: dict, library: MaterialLibrary, effects: Effects) -> list[dict]:
    out = []
    for k, p in enumerate(_array_of_tables(doc, "particles")):
        key = f"particles[{k}]"
        _check_keys(p, PARTICLE_KEYS, key)
        fixed = _fixed(p, key, ("velocity", "angular_velocity"))  # (a wall, any material)
        material = (_material_name if fixed else _particle_material)(
            library, _require(p, "material", key, "a material name"), f"{key}.material")
        radius = check_positive(_require(p, "radius", key, "in m"), f"{key}.radius", "m")
        position = _vector(_require(p, "position", key, "[x, y, z] in m"),
                           f"{key}.position")
        velocity = _vector(p["velocity"], f"{key}.velocity") if "velocity" in p \
            else np.zeros(3)
        _check_magnitude(velocity, MAX_SPEED, "m/s", f"{key}.velocity")
        omega = _angular_velocity(p, key, effects)
        _check_magnitude(omega * radius, MAX_SPEED, "m/s (surface speed |ω| R)",
                         f"{key}.angular_velocity")
        out.append(dict(key=key, material=material, radius=radius, position=position,
                        velocity=velocity, angular_velocity=omega, fixed=fixed))
    return out


def _particle_material(library: MaterialLibrary, value, key: str) -> str:
    name = _material_name(library, value, key)
    if math.isinf(library.materials[name].density):
        raise InputError(f"material '{name}' has infinite density: it can only be a wall "
                         "material", key)
    return name


def _angular_velocity(table: dict, key: str, effects: Effects) -> np.ndarray:
    if "angular_velocity" not in table:
        return np.zeros(3)
    omega = _vector(table["angular_velocity"], f"{key}.angular_velocity")
    if np.any(omega != 0.0) and not effects.rotation:
        raise InputError("is non-zero but the 'rotation' effect is off: add \"rotation\" to "
                         "scene.effects", f"{key}.angular_velocity")
    return omega


def _explicit_spheres(particles: list[dict], material_names: list[str]) -> _Spheres:
    """The [[particles]] as arrays (built only after the total count was accepted)."""
    n = len(particles)
    return _Spheres(
        position=np.array([p["position"] for p in particles]).reshape(n, 3),
        velocity=np.array([p["velocity"] for p in particles]).reshape(n, 3),
        angular_velocity=np.array([p["angular_velocity"] for p in particles]).reshape(n, 3),
        radius=np.array([p["radius"] for p in particles], dtype=float),
        material=np.array([material_names.index(p["material"]) for p in particles],
                          dtype=np.int64))


# -- [[fill]] --

def _radius_range(table: dict, key: str) -> tuple[float, float]:
    """(min, max) radius [m] of a ``radius`` key: a number or [min, max]."""
    r = _require(table, "radius", key, "in m: a number or [min, max]")
    if isinstance(r, list):
        if len(r) != 2:
            raise InputError(f"must be a number or [min, max], got {short_repr(r)}",
                             f"{key}.radius")
        r_min = check_positive(r[0], f"{key}.radius[0]", "m")
        r_max = check_positive(r[1], f"{key}.radius[1]", "m")
        if r_min > r_max:
            raise InputError(f"min {_fmt(r_min)} exceeds max {_fmt(r_max)}", f"{key}.radius")
        return r_min, r_max
    r = check_positive(r, f"{key}.radius", "m")
    return r, r


def _region(table: dict, key: str, r_max: float, walls: _Walls) -> tuple[np.ndarray, np.ndarray]:
    """The corners [m] of a ``region = { lower, upper }``: at least one diameter (2 r_max)
    wide, inside the box if there is one."""
    region = _table(_require(table, "region", key, "{ lower = [...], upper = [...] }"),
                    f"{key}.region")
    _check_keys(region, REGION_KEYS, f"{key}.region")
    lower = _vector(_require(region, "lower", f"{key}.region", "[x, y, z] in m"),
                    f"{key}.region.lower")
    upper = _vector(_require(region, "upper", f"{key}.region", "[x, y, z] in m"),
                    f"{key}.region.upper")
    for i in range(3):
        if upper[i] - lower[i] < 2.0 * r_max:
            raise InputError(
                f"region is {_fmt(upper[i] - lower[i])} m wide along {AXES[i]}, less "
                f"than one sphere diameter ({_fmt(2 * r_max)} m)", f"{key}.region.upper")
    if walls.box_key is not None:
        for i in range(3):
            if lower[i] < walls.box_lower[i] or upper[i] > walls.box_upper[i]:
                raise InputError(
                    f"region must lie inside the box {walls.box_key} (along {AXES[i]}: "
                    f"[{_fmt(lower[i])}, {_fmt(upper[i])}] is not inside "
                    f"[{_fmt(walls.box_lower[i])}, {_fmt(walls.box_upper[i])}])",
                    f"{key}.region")
    return lower, upper


def _parse_fills(doc: dict, library: MaterialLibrary, effects: Effects,
                 walls: _Walls, fixed_keys: set) -> list[Fill]:
    """The [[fill]] blocks; the keys of those of fixed spheres are added to ``fixed_keys``."""
    fills = []
    for k, f in enumerate(_array_of_tables(doc, "fill")):
        key = f"fill[{k}]"
        _check_keys(f, FILL_KEYS, key)
        count = _count(_require(f, "count", key, "number of spheres"), f"{key}.count")
        fixed = _fixed(f, key, ("speed", "angular_velocity"))
        if fixed:
            fixed_keys.add(key)
        material = (_material_name if fixed else _particle_material)(
            library, _require(f, "material", key, "a material name"), f"{key}.material")
        r_min, r_max = _radius_range(f, key)
        lower, upper = _region(f, key, r_max, walls)
        speed = check_number(f.get("speed", 0.0), f"{key}.speed")
        if speed < 0.0:
            raise InputError(f"must be >= 0 m/s, got {f['speed']!r}", f"{key}.speed")
        _check_magnitude(np.array([speed]), MAX_SPEED, "m/s", f"{key}.speed")
        omega = _angular_velocity(f, key, effects)
        _check_magnitude(omega * r_max, MAX_SPEED, "m/s (surface speed |ω| R)",
                         f"{key}.angular_velocity")
        fills.append(Fill(key, count, material, (r_min, r_max), lower, upper, speed, omega))
    return fills


def _place_fixed(seed: int, fills: list[Fill], explicit: _Spheres, space: Space, parts: tuple,
                 material_names: list[str]) -> tuple:
    """The parts with the fixed spheres of ``fills`` (a rough base, obstacles) as balls,
    placed clear of the walls, the explicit spheres and each other with their own stream of
    the scene's seed (FIXED_FILL_STREAM), before the other fills."""
    rng = np.random.default_rng([seed, FIXED_FILL_STREAM])
    position, radius = explicit.position, explicit.radius
    balls = []
    for f in fills:
        p, _, r = fill_spheres(rng, f, position, radius, space)
        position, radius = np.concatenate([position, p]), np.concatenate([radius, r])
        balls += [shapes.ball(c, float(rc), material_names.index(f.material), f.key)
                  for c, rc in zip(p, r, strict=True)]
    return tuple(parts) + tuple(balls)


def _place_fills(seed: int, fills: list[Fill], explicit: _Spheres, space: Space,
                 material_names: list[str]) -> _Spheres:
    """The explicit spheres followed by every fill's, placed in file order with one generator
    (see the module docstring)."""
    rng = np.random.default_rng(seed)
    spheres = explicit
    for f in fills:
        position, velocity, radius = fill_spheres(rng, f, spheres.position, spheres.radius,
                                                  space)
        spheres = spheres.then(_Spheres(
            position, velocity, np.broadcast_to(f.angular_velocity, position.shape), radius,
            np.full(f.count, material_names.index(f.material), np.int64)))
    return spheres


def _parse_inflows(doc: dict, library: MaterialLibrary, walls: _Walls,
                   frame_interval: float, duration: float) -> list[dict]:
    """The ``[[inflow]]`` entries → their checked values (docs/open-systems.md)."""
    inflows = []
    for k, t in enumerate(_array_of_tables(doc, "inflow")):
        key = f"inflow[{k}]"
        _check_keys(t, INFLOW_KEYS, key)
        recirculate = _flag(t, "recirculate", key)
        entry = dict(key=key, index=k, recirculate=recirculate, count=0, material=None,
                     radius=(0.0, 0.0))
        if recirculate:
            for name in INFLOW_OWN_KEYS:
                if name in t:
                    raise InputError("a recirculating inflow inserts the spheres that left "
                                     "through outlets, with their own size and material: "
                                     f"remove '{name}'", f"{key}.{name}")
        else:
            entry["count"] = _count(_require(t, "count", key, "number of spheres"),
                                    f"{key}.count")
            entry["material"] = _particle_material(
                library, _require(t, "material", key, "a material name"), f"{key}.material")
            entry["radius"] = _radius_range(t, key)
        entry["lower"], entry["upper"] = _region(t, key, entry["radius"][1], walls)
        entry["rate"] = check_positive(_require(t, "rate", key, "spheres per second"),
                                       f"{key}.rate", "1/s")
        if entry["rate"] * duration > MAX_INFLOW_SPHERES:
            raise InputError(f"asks for {entry['rate'] * duration:.3g} spheres over the run, "
                             f"more than {MAX_INFLOW_SPHERES:.0e}", f"{key}.rate")
        entry["interval"] = check_positive(t.get("interval", frame_interval),
                                           f"{key}.interval", "s")
        if duration / entry["interval"] > MAX_FRAMES:
            raise InputError(f"{_fmt(entry['interval'])} s gives more than {MAX_FRAMES:.0e} "
                             f"batches over {_fmt(duration)} s (each stops the event loop): "
                             "make it longer", f"{key}.interval")
        entry["start"] = check_number(t.get("start", 0.0), f"{key}.start")
        if entry["start"] < 0.0:
            raise InputError(f"must be >= 0 s, got {t['start']!r}", f"{key}.start")
        entry["velocity"] = (_vector(t["velocity"], f"{key}.velocity") if "velocity" in t
                             else np.zeros(3))
        _check_magnitude(entry["velocity"], MAX_SPEED, "m/s", f"{key}.velocity")
        entry["speed"] = check_number(t.get("speed", 0.0), f"{key}.speed")
        if entry["speed"] < 0.0:
            raise InputError(f"must be >= 0 m/s, got {t['speed']!r}", f"{key}.speed")
        _check_magnitude(np.array([entry["speed"]]), MAX_SPEED, "m/s", f"{key}.speed")
        inflows.append(entry)
    return inflows


def _reserve_rows(seed: int, inflows: list[dict], first: int, material_names: list[str]):
    """The :class:`~hsgran.inflow.Inflow` of each entry, with the particle table rows it owns
    from row ``first`` on, and those rows: absent (NaN position, zero velocity), radius drawn
    uniformly in the entry's range by a generator of the scene's seed and the inflow's index."""
    made = []
    rows = []
    start = first
    for f in inflows:
        count = f["count"]
        r_min, r_max = f["radius"]
        radius = (np.full(count, r_min) if r_min == r_max
                  else np.random.default_rng([seed, f["index"]]).uniform(r_min, r_max, count))
        material = (material_names.index(f["material"]) if f["material"] is not None else 0)
        rows.append(_Spheres(np.full((count, 3), np.nan), np.zeros((count, 3)),
                             np.zeros((count, 3)), radius, np.full(count, material, np.int64)))
        made.append(Inflow(key=f["key"], index=f["index"], rows=(start, start + count),
                           lower=f["lower"], upper=f["upper"], rate=f["rate"],
                           interval=f["interval"], start=f["start"], velocity=f["velocity"],
                           speed=f["speed"], recirculate=f["recirculate"]))
        start += count
    empty = _Spheres(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0),
                     np.zeros(0, np.int64))
    for r in rows:
        empty = empty.then(r)
    return tuple(made), empty


def _check_inflows(inflows: tuple, outlets: tuple, radius: np.ndarray) -> None:
    """A recirculating inflow's region holds the largest sphere; no inflow region reaches into
    an outlet (its spheres would leave as they arrive)."""
    for f in inflows:
        if f.recirculate and radius.size:
            widest = float(np.min(f.upper - f.lower))
            if widest < 2.0 * float(radius.max()):
                raise InputError(f"region is {_fmt(widest)} m wide, less than the diameter of "
                                 f"the largest sphere it may insert ({_fmt(2 * radius.max())} "
                                 "m)", f"{f.key}.region")
        corners = np.array([[(f.lower, f.upper)[(c >> a) & 1][a] for a in range(3)]
                            for c in range(8)])
        for o in outlets:
            reached = (o.contains(corners).any() if o.kind == "below" else
                       bool(np.all(o.row[OL_A:OL_A + 3] < f.upper)
                            and np.all(f.lower < o.row[OL_B:OL_B + 3])))
            if reached:
                raise InputError(f"region reaches into outlet {o.key} (the spheres it inserts "
                                 "would leave as they arrive)", f"{f.key}.region")


def _sphere_names(particles: list[dict], fills: list[Fill]) -> _Names:
    """Labels of the explicit particles and the index range each fill will take."""
    ranges = []
    start = len(particles)
    for f in fills:
        ranges.append((f.key, start, start + f.count))
        start += f.count
    return _Names([p["key"] for p in particles], ranges)


def _sphere_counts(explicit: _Spheres, fills: list[Fill], material_names: list[str]):
    """Number of spheres of each material, (M,) (fills by their requested counts)."""
    counts = np.bincount(explicit.material, minlength=len(material_names))
    for f in fills:
        counts[material_names.index(f.material)] += f.count
    return counts


def _check_total(n_explicit: int, blocks: list[tuple[str, int]]) -> None:
    """Refuse, before allocating anything, a particle count beyond the hard limit or
    beyond the memory this machine has available now (the key named is the fill or inflow
    (``blocks``: key path and count of each), or the particle list, that crosses the line)."""
    available = available_memory()
    budget = math.inf if available is None else MEMORY_SHARE * available
    total = 0
    for key, count in [("particles", n_explicit)] + [(f"{key}.count", count)
                                                      for key, count in blocks]:
        total += count
        need = total * BYTES_PER_PARTICLE
        if total > MAX_PARTICLES:
            raise InputError(
                f"the scene asks for {total:.3g} particles so far, more than the limit of "
                f"{MAX_PARTICLES:.0e} (at ~{BYTES_PER_PARTICLE / 1024:.1f} kB per particle "
                f"that would need ~{need / 1e9:.0f} GB of memory)", key)
        if need > budget:
            raise InputError(
                f"{total:,} particles need ~{need / 1e9:.3g} GB of memory (~"
                f"{BYTES_PER_PARTICLE / 1024:.1f} kB each), more than this machine can give "
                f"({available / 1e9:.3g} GB available)", key)


# -- cross checks --

def _check_explicit(walls: _Walls, periodic: tuple, position: np.ndarray,
                    names: _Names) -> None:
    """Explicit particles inside the periodic cell (the planes are checked separately)."""
    if walls.box_key is None:
        return
    for i in range(3):
        if not periodic[i]:
            continue
        lo, hi = walls.box_lower[i], walls.box_upper[i]
        bad = np.flatnonzero((position[:, i] < lo) | (position[:, i] >= hi))
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"{AXES[i]} = {_fmt(position[k, i])} lies outside the periodic box "
                f"[{_fmt(lo)}, {_fmt(hi)}) of {walls.box_key} along {AXES[i]}",
                f"{names.labels[k]}.position")


def _check_overlaps(position: np.ndarray, radius: np.ndarray, space: Space,
                    names: _Names) -> None:
    pairs, dist = overlapping_pairs(position, radius, space)
    if pairs.shape[0]:
        order = np.lexsort((pairs[:, 0], pairs[:, 1]))
        i, j = (int(v) for v in pairs[order[0]])
        d, s = _fmt_apart(float(dist[order[0]]), float(radius[i] + radius[j]))
        raise InputError(
            f"overlaps {names.label(i)} (centre distance {d} m < sum of radii {s} m, beyond "
            f"the tolerance of {CONTACT_TOLERANCE:g} of it)", names.position_key(j))


def _check_planes(walls: list, position: np.ndarray, radius: np.ndarray,
                  names: _Names) -> None:
    """Every sphere on the spheres' side of every wall (planes and cylinders)."""
    for plane in walls:
        d = plane.distance(position)
        bad = np.flatnonzero(d < radius * (1.0 - CONTACT_TOLERANCE))
        if bad.size:
            k = int(bad[0])
            where = ("lies behind" if d[k] < 0.0 else "penetrates")
            dk, rk = _fmt_apart(float(d[k]), float(radius[k]))
            raise InputError(
                f"{names.label(k)} {where} wall {plane.key} (centre {dk} m from "
                f"{'the plane' if isinstance(plane, Plane) else 'its surface'}, "
                f"radius {rk} m, beyond the tolerance of {CONTACT_TOLERANCE:g} of the radius; "
                "the normal points to where spheres live)", names.position_key(k))


def _check_outlets(outlets: tuple, position: np.ndarray, names: _Names) -> None:
    """No sphere starts inside an outlet (it would leave at t = 0: a mistake of the scene)."""
    for outlet in outlets:
        bad = np.flatnonzero(outlet.contains(position))
        if bad.size:
            k = int(bad[0])
            raise InputError(f"{names.label(k)} starts inside outlet {outlet.key} (its centre "
                             "would leave the system at once)", names.position_key(k))


def _check_grid(walls: _Walls, periodic: tuple, radius: np.ndarray) -> None:
    """Periodic axes hold enough cells (checked before any fill is placed)."""
    if walls.box_key is None or radius.size == 0:
        return
    d_max = 2.0 * float(radius.max())
    for i in range(3):
        length = walls.box_upper[i] - walls.box_lower[i]
        if periodic[i] and length < MIN_PERIODIC_CELLS * d_max:
            raise InputError(
                f"the box is {_fmt(length)} m long along periodic axis {AXES[i]}, less than "
                f"{MIN_PERIODIC_CELLS} x the largest diameter ({_fmt(d_max)} m): the cell "
                f"grid needs at least {MIN_PERIODIC_CELLS} cells along a periodic axis; "
                "enlarge the box or make the axis non-periodic", f"scene.periodic[{i}]")


def _check_friction(effects: Effects, library: MaterialLibrary, names: list[str],
                    counts: np.ndarray, planes: list[Plane]) -> None:
    """Every pair of materials that can meet has a sliding friction (with 'friction')."""
    if not effects.friction:
        return
    used = [names[i] for i in range(len(names)) if counts[i] > 0]
    pairs = []
    for a_i, a in enumerate(used):
        for b in used[a_i:]:
            if a != b or counts[names.index(a)] >= 2:
                pairs.append((a, b))
    wall_materials = list(dict.fromkeys(names[p.material] for p in planes))
    pairs += [(a, w) for a in used for w in wall_materials]
    for a, b in dict.fromkeys(pairs):
        if library.contact(a, b).sliding_friction is None:
            raise InputError(
                f"the 'friction' effect is on but materials '{a}' and '{b}' meet with no "
                f"sliding_friction: add [[contacts]] between = [\"{a}\", \"{b}\"] with "
                "sliding_friction", "contacts")


def _check_plasticity(doc: dict, effects: Effects, sphere_materials: list[str]) -> None:
    if not effects.plasticity:
        return
    declared = doc.get("materials", {})
    for name in sphere_materials:
        if name in declared and "yield_stress" not in declared[name]:
            raise InputError(
                f"missing value: the 'plasticity' effect is on and particles are made of "
                f"'{name}'; give its yield stress in Pa (inf: never yields)",
                f"materials.{name}.yield_stress")
