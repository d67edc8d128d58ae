"""Scene files: TOML in, a validated :class:`Scene` in SI units out (layer 4).

This module is the one place where user input about a whole scene is checked. Every problem is
an :class:`~hsgran.errors.InputError` whose one-line message starts with the key path of the
offending value (``particles[3].radius``, ``walls[0].normal``, ``materials.steel.yield_stress``),
so the command line can print it without a traceback. Everything downstream (assembly of the
physics, the engine, the writers) may assume the scene is consistent.

The format (every length in m, time in s, speed in m/s; DESIGN.md §4)::

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
order; for each fill it draws the radii (polydisperse only), then candidate centres in blocks,
then the velocity directions. Spheres are placed by random sequential addition, largest first:
each takes uniform candidate centres until one clears the walls and everything already placed
(explicit particles, earlier fills, its own fill), found through a cell grid in a compiled kernel
(~10⁵ spheres at packing fraction 0.2 in about a second). A fill that cannot be completed within
a bounded number of candidates is an error naming how many spheres it placed. The final overlap
check of all spheres uses :class:`scipy.spatial.cKDTree` (periodic images included).

Layer 4: imports ``errors``, ``_jit``, ``effects``, ``materials`` and ``overrides``.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from hsgran._jit import njit
from hsgran.effects import Effects
from hsgran.errors import InputError, check_number, check_positive, did_you_mean, short_repr
from hsgran.materials import (
    PAIR_ROW_SIZE,
    Material,
    MaterialLibrary,
    pair_row,
    solid_sphere_mass,
)
from hsgran.overrides import apply_overrides, names_override
from hsgran.system import available_memory

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
#: contact law of MODEL.md §3 stopped holding long before, and past this the numbers are typos.
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

#: Relative tolerance of the overlap and wall-penetration checks. Spheres written by hand as
#: touching (centre distance = R1 + R2 in decimal) differ from exact contact by a few ulp after
#: parsing and subtraction; 1e-12 accepts those and nothing a simulation could notice.
CONTACT_TOLERANCE = 1e-12

#: A plane is parallel to a periodic axis when its unit normal's component along it is below
#: this (a tilted plane would break the periodic images).
PARALLEL_TOLERANCE = 1e-12

#: A periodic axis must hold at least this many cells of the engine's cell grid, whose cell edge
#: is at least the largest diameter; with fewer, a particle and its own image would be neighbours.
MIN_PERIODIC_CELLS = 3

#: A [[fill]] gives up after this many candidate positions per requested sphere (plus
#: :data:`FILL_MIN_ATTEMPTS`). Random sequential addition of equal spheres jams at a packing
#: fraction of ≈ 0.38; up to ≈ 0.3 it needs a few tens of candidates per sphere at the end, so
#: this budget only runs out for requests that cannot be met, and bounds the time they waste.
FILL_ATTEMPTS_PER_SPHERE = 300
#: Minimum candidate budget of a fill (small fills in awkward regions deserve a fair try).
FILL_MIN_ATTEMPTS = 100_000
#: Packing fraction above which a fill is refused without trying (random close packing of equal
#: spheres is 0.64, and random sequential addition stays far below it).
FILL_PACKING_LIMIT = 0.64
#: Most candidate positions drawn in one batch (bounds the temporary arrays to a few tens of MB).
FILL_MAX_BATCH = 1 << 18
#: Random sequential addition jamming fraction of equal spheres, quoted in messages.
RSA_JAMMING_FRACTION = 0.38

AXES = "xyz"

TOP_KEYS = ("scene", "output", "materials", "contacts", "walls", "particles", "fill",
            "enduring_contact")
ENDURING_KEYS = ("landing_speed", "rolling_convention", "tc_time")
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
OUTPUT_KEYS = ("frame_interval",)
PLANE_KEYS = ("kind", "point", "normal", "material")
BOX_KEYS = ("kind", "lower", "upper", "material")
WALL_KINDS = ("plane", "box")
PARTICLE_KEYS = ("material", "radius", "position", "velocity", "angular_velocity")
FILL_KEYS = ("count", "material", "radius", "region", "speed", "angular_velocity")
REGION_KEYS = ("lower", "upper")


# ---- the scene ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Plane:
    """An infinite plane wall.

    Attributes:
        point: A point of the plane [m], shape (3,).
        normal: Unit normal [-], shape (3,), pointing into the region where spheres live.
        material: Index into :attr:`Scene.material_names`.
        key: Key path for messages (``walls[0]``, ``walls[1].lower_z``).
    """

    point: np.ndarray
    normal: np.ndarray
    material: int
    key: str

    def distance(self, position: np.ndarray) -> np.ndarray:
        """Signed distance [m] of points (..., 3) from the plane, positive on the normal's side."""
        return (np.asarray(position) - self.point) @ self.normal


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
        planes: Every plane wall, box faces included (none on a periodic axis).
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
        overrides: Key path → value changes applied to the file before validation
            (:mod:`hsgran.overrides`); ``text`` then ends with :func:`override_note`.
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
    overrides: dict = field(default_factory=dict)

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
        return _SceneBuilder(doc, text, source).build()
    doc = apply_overrides(doc, overrides)
    text += override_note(overrides)
    try:
        scene = _SceneBuilder(doc, text, source).build()
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


# ---- the builder -------------------------------------------------------------------------

@dataclass
class _Fill:
    """A parsed [[fill]] block, before placement."""

    key: str
    count: int
    material: str
    radius: tuple[float, float]  # (min, max); equal for monodisperse
    lower: np.ndarray
    upper: np.ndarray
    speed: float
    angular_velocity: np.ndarray


@dataclass
class _SceneBuilder:
    """Checks a parsed TOML document step by step and assembles the :class:`Scene`."""

    doc: dict
    text: str
    source: str
    library: MaterialLibrary = field(default_factory=MaterialLibrary)

    def build(self) -> Scene:
        doc = self.doc
        _check_keys(doc, TOP_KEYS, "")
        self._parse_scene_table()
        self._parse_output()
        self._parse_enduring()
        self.library.add_tables(doc, origin=self.source)
        self._parse_walls()
        particles = self._parse_particles()
        fills = self._parse_fills()
        self._check_total(len(particles), fills)
        self._check_periodic_planes()

        n_explicit = len(particles)
        if n_explicit + sum(f.count for f in fills) == 0:
            raise InputError("the scene has no particles: add [[particles]] or [[fill]] blocks",
                             "particles")
        names = [p["material"] for p in particles] + [f.material for f in fills]
        self.material_names = list(dict.fromkeys(names))
        self.particle_material_names = list(self.material_names)
        self.labels = [p["key"] for p in particles]

        # explicit particles: arrays built only after the total count was accepted
        position = np.array([p["position"] for p in particles]).reshape(n_explicit, 3)
        velocity = np.array([p["velocity"] for p in particles]).reshape(n_explicit, 3)
        omega = np.array([p["angular_velocity"] for p in particles]).reshape(n_explicit, 3)
        radius = np.array([p["radius"] for p in particles], dtype=float)
        material = np.array([self.material_names.index(p["material"]) for p in particles],
                            dtype=np.int64)

        # everything that does not need the fills' positions, before the (costly) placement
        self._check_grid(np.concatenate([radius, [f.radius[1] for f in fills]]))
        self._check_explicit(position)
        self._check_overlaps(position, radius)
        planes = self._make_planes()
        self._check_planes(planes, position, radius)
        counts = np.bincount(material, minlength=len(self.material_names))
        for f in fills:
            counts[self.material_names.index(f.material)] += f.count
        self._check_friction(counts, planes)
        self._check_plasticity()

        for f in fills:
            pos, vel, rad = self._place(f, position, radius)
            position = np.concatenate([position, pos])
            velocity = np.concatenate([velocity, vel])
            omega = np.concatenate([omega, np.broadcast_to(f.angular_velocity, pos.shape)])
            radius = np.concatenate([radius, rad])
            material = np.concatenate(
                [material, np.full(f.count, self.material_names.index(f.material), np.int64)])
            self.fill_ranges.append((f.key, len(radius) - f.count, len(radius)))
        if fills:
            # placement guarantees both; re-checking all spheres costs little and guards it
            self._check_overlaps(position, radius)
            self._check_planes(planes, position, radius)

        return Scene(
            name=self.name,
            duration=self.duration,
            gravity=self.gravity,
            effects=self.effects,
            seed=self.seed,
            periodic=self.periodic,
            box_lower=self.box_lower,
            box_upper=self.box_upper,
            planes=planes,
            frame_interval=self.frame_interval,
            library=self.library,
            material_names=self.material_names,
            position=np.ascontiguousarray(position, dtype=np.float64),
            velocity=np.ascontiguousarray(velocity, dtype=np.float64),
            angular_velocity=np.ascontiguousarray(omega, dtype=np.float64),
            radius=np.ascontiguousarray(radius, dtype=np.float64),
            material=np.ascontiguousarray(material, dtype=np.int64),
            text=self.text,
            source=self.source,
            landing_speed=self.landing_speed,
            rolling_convention=self.rolling_convention,
            tc_time=self.tc_time,
        )

    # -- [scene] and [output] --

    def _parse_scene_table(self) -> None:
        sc = _table(self.doc.get("scene", {}), "scene", "a table ([scene])")
        _check_keys(sc, SCENE_KEYS, "scene")
        default_name = Path(self.source).stem if self.source != "<string>" else "unnamed"
        self.name = _string(sc.get("name", default_name), "scene.name")
        self.duration = check_positive(
            _require(sc, "duration", "scene", "simulated time in s"), "scene.duration", "s")
        self.effects = Effects.parse(sc.get("effects", []), "scene.effects")
        if "gravity" in sc:
            g = _vector(sc["gravity"], "scene.gravity")
            _check_magnitude(g, MAX_GRAVITY, "m/s^2", "scene.gravity")
            if not self.effects.gravity:
                raise InputError("listed but the 'gravity' effect is off: add \"gravity\" to "
                                 "scene.effects or remove scene.gravity", "scene.gravity")
            self.gravity = g
        elif self.effects.gravity:
            self.gravity = np.array(STANDARD_GRAVITY)
        else:
            self.gravity = np.zeros(3)
        seed = sc.get("seed", 0)
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise InputError(f"must be a whole number >= 0, got {short_repr(seed)}", "scene.seed")
        self.seed = seed
        periodic = sc.get("periodic", [False, False, False])
        if (not isinstance(periodic, list) or len(periodic) != 3
                or not all(isinstance(b, bool) for b in periodic)):
            raise InputError(f"must be a list of 3 booleans [x, y, z], got {short_repr(periodic)}",
                             "scene.periodic")
        self.periodic = tuple(periodic)

    def _parse_enduring(self) -> None:
        tab = _table(self.doc.get("enduring_contact", {}), "enduring_contact",
                     "a table ([enduring_contact])")
        _check_keys(tab, ENDURING_KEYS, "enduring_contact")
        self.landing_speed = DEFAULT_LANDING_SPEED
        if "landing_speed" in tab:
            self.landing_speed = check_positive(tab["landing_speed"],
                                                "enduring_contact.landing_speed", "m/s")
        self.tc_time = DEFAULT_TC_TIME
        if "tc_time" in tab:
            self.tc_time = check_number(tab["tc_time"], "enduring_contact.tc_time")
            if self.tc_time < 0.0:
                raise InputError(f"must be >= 0 s (0 turns the TC model off), got "
                                 f"{tab['tc_time']!r}", "enduring_contact.tc_time")
        conv = tab.get("rolling_convention", "A")
        if conv not in ROLLING_CONVENTIONS:
            raise InputError(f"must be \"A\" ({ROLLING_CONVENTIONS['A']}) or \"B\" "
                             f"({ROLLING_CONVENTIONS['B']}), got {short_repr(conv)}",
                             "enduring_contact.rolling_convention")
        self.rolling_convention = conv

    def _parse_output(self) -> None:
        out = _table(self.doc.get("output", {}), "output", "a table ([output])")
        _check_keys(out, OUTPUT_KEYS, "output")
        self.frame_interval = check_positive(
            _require(out, "frame_interval", "output", "time between frames in s"),
            "output.frame_interval", "s")
        frames = self.duration / self.frame_interval
        if frames > MAX_FRAMES:
            raise InputError(
                f"{_fmt(self.frame_interval)} s gives {frames:.3g} frames over "
                f"{_fmt(self.duration)} s, more than the limit of {MAX_FRAMES:.0e}",
                "output.frame_interval")

    def _material_name(self, value, key: str) -> str:
        name = _string(value, key)
        self.library.material(name, key)  # raises with a "did you mean" hint
        return name

    # -- [[walls]] --

    def _parse_walls(self) -> None:
        self.walls: list[dict] = []
        self.box_lower = self.box_upper = None
        self.box_key: str | None = None
        for k, w in enumerate(_array_of_tables(self.doc, "walls")):
            key = f"walls[{k}]"
            kind = _string(_require(w, "kind", key, "'plane' or 'box'"), f"{key}.kind")
            if kind not in WALL_KINDS:
                raise InputError(f"unknown wall kind '{kind}'{did_you_mean(kind, WALL_KINDS)}; "
                                 f"known: {', '.join(WALL_KINDS)}", f"{key}.kind")
            if kind == "plane":
                _check_keys(w, PLANE_KEYS, key)
                point = _vector(_require(w, "point", key, "a point of the plane [x, y, z] in m"),
                                f"{key}.point")
                normal = _vector(_require(w, "normal", key, "[x, y, z] pointing to the spheres"),
                                 f"{key}.normal")
                length = float(np.linalg.norm(normal))
                if length == 0.0 or not math.isfinite(length):
                    raise InputError("must be a non-zero vector (it points to where the spheres "
                                     "live)", f"{key}.normal")
                material = self._material_name(
                    _require(w, "material", key, "a material name"), f"{key}.material")
                self.walls.append(dict(kind=kind, key=key, point=point,
                                       normal=normal / length, material=material))
            else:
                _check_keys(w, BOX_KEYS, key)
                if self.box_key is not None:
                    raise InputError(f"a scene has at most one box ({self.box_key} is one); "
                                     "add further walls as planes", key)
                lower = _vector(_require(w, "lower", key, "lowest corner [x, y, z] in m"),
                                f"{key}.lower")
                upper = _vector(_require(w, "upper", key, "highest corner [x, y, z] in m"),
                                f"{key}.upper")
                for i in range(3):
                    if not lower[i] < upper[i]:
                        raise InputError(
                            f"must exceed lower on every axis ({AXES[i]}: upper "
                            f"{_fmt(upper[i])} <= lower {_fmt(lower[i])})", f"{key}.upper")
                if "material" in w:
                    material = self._material_name(w["material"], f"{key}.material")
                elif all(self.periodic):
                    material = None  # a fully periodic box has no walls to be made of anything
                else:
                    raise InputError("missing value (a material name; the box has walls on its "
                                     "non-periodic axes)", f"{key}.material")
                self.box_lower, self.box_upper, self.box_key = lower, upper, key
                self.walls.append(dict(kind=kind, key=key, lower=lower, upper=upper,
                                       material=material))
        if any(self.periodic) and self.box_key is None:
            axes = ", ".join(AXES[i] for i in range(3) if self.periodic[i])
            raise InputError(f"periodic along {axes} needs a [[walls]] entry of kind = \"box\" "
                             "giving the period", "scene.periodic")

    def _check_periodic_planes(self) -> None:
        for w in self.walls:
            if w["kind"] != "plane":
                continue
            for i in range(3):
                if self.periodic[i] and abs(w["normal"][i]) > PARALLEL_TOLERANCE:
                    raise InputError(
                        f"a plane wall must be parallel to the periodic axis {AXES[i]} (its "
                        f"normal needs a zero {AXES[i]} component)", f"{w['key']}.normal")

    def _make_planes(self) -> list[Plane]:
        planes = []
        wall_names = [w["material"] for w in self.walls
                      if w["material"] is not None
                      and (w["kind"] == "plane" or not all(self.periodic))]
        for name in wall_names:
            if name not in self.material_names:
                self.material_names.append(name)
        for w in self.walls:
            if w["kind"] == "plane":
                planes.append(_frozen_plane(w["point"], w["normal"],
                                            self.material_names.index(w["material"]), w["key"]))
                continue
            for i in range(3):
                if self.periodic[i]:
                    continue
                for side, corner, sign in (("lower", w["lower"], 1.0), ("upper", w["upper"], -1.0)):
                    normal = np.zeros(3)
                    normal[i] = sign
                    planes.append(_frozen_plane(corner.copy(), normal,
                                                self.material_names.index(w["material"]),
                                                f"{w['key']}.{side}_{AXES[i]}"))
        return planes

    # -- [[particles]] --

    def _parse_particles(self) -> list[dict]:
        out = []
        for k, p in enumerate(_array_of_tables(self.doc, "particles")):
            key = f"particles[{k}]"
            _check_keys(p, PARTICLE_KEYS, key)
            material = self._particle_material(
                _require(p, "material", key, "a material name"), f"{key}.material")
            radius = check_positive(_require(p, "radius", key, "in m"), f"{key}.radius", "m")
            position = _vector(_require(p, "position", key, "[x, y, z] in m"),
                               f"{key}.position")
            velocity = _vector(p["velocity"], f"{key}.velocity") if "velocity" in p \
                else np.zeros(3)
            _check_magnitude(velocity, MAX_SPEED, "m/s", f"{key}.velocity")
            omega = self._angular_velocity(p, key)
            _check_magnitude(omega * radius, MAX_SPEED, "m/s (surface speed |ω| R)",
                             f"{key}.angular_velocity")
            out.append(dict(key=key, material=material, radius=radius, position=position,
                            velocity=velocity, angular_velocity=omega))
        return out

    def _particle_material(self, value, key: str) -> str:
        name = self._material_name(value, key)
        if math.isinf(self.library.materials[name].density):
            raise InputError(f"material '{name}' has infinite density: it can only be a wall "
                             "material", key)
        return name

    def _angular_velocity(self, table: dict, key: str) -> np.ndarray:
        if "angular_velocity" not in table:
            return np.zeros(3)
        omega = _vector(table["angular_velocity"], f"{key}.angular_velocity")
        if np.any(omega != 0.0) and not self.effects.rotation:
            raise InputError("is non-zero but the 'rotation' effect is off: add \"rotation\" to "
                             "scene.effects", f"{key}.angular_velocity")
        return omega

    # -- [[fill]] --

    def _parse_fills(self) -> list[_Fill]:
        fills = []
        for k, f in enumerate(_array_of_tables(self.doc, "fill")):
            key = f"fill[{k}]"
            _check_keys(f, FILL_KEYS, key)
            count = _count(_require(f, "count", key, "number of spheres"), f"{key}.count")
            material = self._particle_material(
                _require(f, "material", key, "a material name"), f"{key}.material")
            r = _require(f, "radius", key, "in m: a number or [min, max]")
            if isinstance(r, list):
                if len(r) != 2:
                    raise InputError(f"must be a number or [min, max], got {short_repr(r)}",
                                     f"{key}.radius")
                r_min = check_positive(r[0], f"{key}.radius[0]", "m")
                r_max = check_positive(r[1], f"{key}.radius[1]", "m")
                if r_min > r_max:
                    raise InputError(f"min {_fmt(r_min)} exceeds max {_fmt(r_max)}",
                                     f"{key}.radius")
            else:
                r_min = r_max = check_positive(r, f"{key}.radius", "m")
            region = _table(_require(f, "region", key, "{ lower = [...], upper = [...] }"),
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
            if self.box_key is not None:
                for i in range(3):
                    if lower[i] < self.box_lower[i] or upper[i] > self.box_upper[i]:
                        raise InputError(
                            f"region must lie inside the box {self.box_key} (along {AXES[i]}: "
                            f"[{_fmt(lower[i])}, {_fmt(upper[i])}] is not inside "
                            f"[{_fmt(self.box_lower[i])}, {_fmt(self.box_upper[i])}])",
                            f"{key}.region")
            speed = check_number(f.get("speed", 0.0), f"{key}.speed")
            if speed < 0.0:
                raise InputError(f"must be >= 0 m/s, got {f['speed']!r}", f"{key}.speed")
            _check_magnitude(np.array([speed]), MAX_SPEED, "m/s", f"{key}.speed")
            omega = self._angular_velocity(f, key)
            _check_magnitude(omega * r_max, MAX_SPEED, "m/s (surface speed |ω| R)",
                             f"{key}.angular_velocity")
            fills.append(_Fill(key, count, material, (r_min, r_max), lower, upper, speed, omega))
        self.fill_ranges: list[tuple[str, int, int]] = []
        return fills

    def _check_total(self, n_explicit: int, fills: list[_Fill]) -> None:
        """Refuse, before allocating anything, a particle count beyond the hard limit or
        beyond the memory this machine has available now (the key named is the fill, or the
        particle list, that crosses the line)."""
        available = available_memory()
        budget = math.inf if available is None else MEMORY_SHARE * available
        total = 0
        for key, count in [("particles", n_explicit)] + [(f"{f.key}.count", f.count)
                                                          for f in fills]:
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

    def _place(self, f: _Fill, placed_pos: np.ndarray, placed_rad: np.ndarray):
        """Draw radii, positions and velocities of one fill (see the module docstring)."""
        rng = self.rng
        r_min, r_max = f.radius
        if r_min == r_max:
            radii = np.full(f.count, r_min)
        else:
            radii = rng.uniform(r_min, r_max, f.count)
        volume = float(np.prod(f.upper - f.lower))
        fraction = float(np.sum(4.0 / 3.0 * math.pi * radii**3)) / volume
        if fraction > FILL_PACKING_LIMIT:
            raise InputError(
                f"{f.count} spheres would fill {fraction:.2f} of the region's volume, more than "
                f"random placement can reach (~{RSA_JAMMING_FRACTION} for equal spheres): lower "
                "count or radius, or enlarge the region", f"{f.key}.count")
        budget = max(FILL_MIN_ATTEMPTS, FILL_ATTEMPTS_PER_SPHERE * f.count)
        positions, attempts = _random_sequential_addition(
            rng, radii, f.lower, f.upper, self._fill_planes(), placed_pos, placed_rad,
            self._box_shift(), budget)
        n_placed = int(np.sum(~np.isnan(positions[:, 0])))
        if n_placed < f.count:
            raise InputError(
                f"placed only {n_placed} of {f.count} spheres after {attempts} random attempts "
                f"(the spheres would fill {fraction:.2f} of the region; random sequential "
                f"placement of equal spheres jams near {RSA_JAMMING_FRACTION}): lower count or "
                "radius, or enlarge the region", f"{f.key}.count")
        direction = rng.standard_normal((f.count, 3))
        norm = np.linalg.norm(direction, axis=1, keepdims=True)
        norm[norm == 0.0] = 1.0  # probability zero; keeps the arithmetic finite
        velocity = f.speed * direction / norm
        return positions, velocity, radii

    @property
    def rng(self) -> np.random.Generator:
        if not hasattr(self, "_rng"):
            self._rng = np.random.default_rng(self.seed)
        return self._rng

    def _fill_planes(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(point, unit normal) of every plane a fill must keep clear of (box faces included)."""
        planes = [(w["point"], w["normal"]) for w in self.walls if w["kind"] == "plane"]
        if self.box_key is not None:
            for i in range(3):
                if not self.periodic[i]:
                    e = np.zeros(3)
                    e[i] = 1.0
                    planes += [(self.box_lower, e), (self.box_upper, -e)]
        return planes

    def _box_shift(self):
        """(origin, boxsize) for periodic cKDTrees, or None without periodic axes."""
        if not any(self.periodic):
            return None
        size = np.where(self.periodic, self.box_upper - self.box_lower, 0.0)
        return self.box_lower, size

    # -- cross checks --

    def _label(self, i: int) -> str:
        """How messages name sphere ``i``: ``particles[3]`` or ``fill[0] sphere 12``."""
        if i < len(self.labels):
            return self.labels[i]
        for key, start, stop in self.fill_ranges:
            if start <= i < stop:
                return f"{key} sphere {i - start}"
        return f"sphere {i}"

    def _position_key(self, i: int) -> str:
        """Key path blamed for the position of sphere ``i``."""
        if i < len(self.labels):
            return f"{self.labels[i]}.position"
        for key, start, stop in self.fill_ranges:
            if start <= i < stop:
                return f"{key}.region"
        return "particles"

    def _check_explicit(self, position: np.ndarray) -> None:
        """Explicit particles inside the periodic cell (the planes are checked later)."""
        if self.box_key is None:
            return
        for i in range(3):
            if not self.periodic[i]:
                continue
            lo, hi = self.box_lower[i], self.box_upper[i]
            bad = np.flatnonzero((position[:, i] < lo) | (position[:, i] >= hi))
            if bad.size:
                k = int(bad[0])
                raise InputError(
                    f"{AXES[i]} = {_fmt(position[k, i])} lies outside the periodic box "
                    f"[{_fmt(lo)}, {_fmt(hi)}) of {self.box_key} along {AXES[i]}",
                    f"{self.labels[k]}.position")

    def _check_overlaps(self, position: np.ndarray, radius: np.ndarray) -> None:
        pairs, dist = _overlapping_pairs(position, radius, self._box_shift())
        if pairs.shape[0]:
            order = np.lexsort((pairs[:, 0], pairs[:, 1]))
            i, j = (int(v) for v in pairs[order[0]])
            d = dist[order[0]]
            raise InputError(
                f"overlaps {self._label(i)} (centre distance {_fmt(d)} m < sum of radii "
                f"{_fmt(radius[i] + radius[j])} m)", self._position_key(j))

    def _check_planes(self, planes: list[Plane], position: np.ndarray,
                      radius: np.ndarray) -> None:
        for plane in planes:
            d = plane.distance(position)
            bad = np.flatnonzero(d < radius * (1.0 - CONTACT_TOLERANCE))
            if bad.size:
                k = int(bad[0])
                where = ("lies behind" if d[k] < 0.0 else "penetrates")
                raise InputError(
                    f"{self._label(k)} {where} wall {plane.key} (centre {_fmt(d[k])} m from "
                    f"the plane, radius {_fmt(radius[k])} m; the normal points to where spheres "
                    "live)", self._position_key(k))

    def _check_grid(self, radius: np.ndarray) -> None:
        """Periodic axes hold enough cells (checked before any fill is placed)."""
        if self.box_key is None or radius.size == 0:
            return
        d_max = 2.0 * float(radius.max())
        for i in range(3):
            length = self.box_upper[i] - self.box_lower[i]
            if self.periodic[i] and length < MIN_PERIODIC_CELLS * d_max:
                raise InputError(
                    f"the box is {_fmt(length)} m long along periodic axis {AXES[i]}, less than "
                    f"{MIN_PERIODIC_CELLS} x the largest diameter ({_fmt(d_max)} m): the cell "
                    f"grid needs at least {MIN_PERIODIC_CELLS} cells along a periodic axis; "
                    "enlarge the box or make the axis non-periodic", f"scene.periodic[{i}]")

    def _check_friction(self, counts: np.ndarray, planes: list[Plane]) -> None:
        """Every pair of materials that can meet has a sliding friction (with 'friction')."""
        if not self.effects.friction:
            return
        names = self.material_names
        used = [names[i] for i in range(len(names)) if counts[i] > 0]
        pairs = []
        for a_i, a in enumerate(used):
            for b in used[a_i:]:
                if a != b or counts[names.index(a)] >= 2:
                    pairs.append((a, b))
        wall_materials = list(dict.fromkeys(names[p.material] for p in planes))
        pairs += [(a, w) for a in used for w in wall_materials]
        for a, b in dict.fromkeys(pairs):
            if self.library.contact(a, b).sliding_friction is None:
                raise InputError(
                    f"the 'friction' effect is on but materials '{a}' and '{b}' meet with no "
                    f"sliding_friction: add [[contacts]] between = [\"{a}\", \"{b}\"] with "
                    "sliding_friction", "contacts")

    def _check_plasticity(self) -> None:
        if not self.effects.plasticity:
            return
        declared = self.doc.get("materials", {})
        for name in self.particle_material_names:
            if name in declared and "yield_stress" not in declared[name]:
                raise InputError(
                    f"missing value: the 'plasticity' effect is on and particles are made of "
                    f"'{name}'; give its yield stress in Pa (inf: never yields)",
                    f"materials.{name}.yield_stress")


def _frozen_plane(point: np.ndarray, normal: np.ndarray, material: int, key: str) -> Plane:
    point = np.array(point, dtype=float)
    normal = np.array(normal, dtype=float)
    point.setflags(write=False)
    normal.setflags(write=False)
    return Plane(point, normal, material, key)


# ---- geometry kernels --------------------------------------------------------------------

def _tree(position: np.ndarray, shift) -> cKDTree:
    """cKDTree of points, periodic along the axes given by ``shift = (origin, boxsize)``."""
    if shift is None:
        return cKDTree(position)
    origin, size = shift
    x = position - origin
    periodic = size > 0.0
    if np.any(periodic):
        wrapped = np.mod(x[:, periodic], size[periodic])
        # np.mod can round a tiny negative up to exactly the box size
        wrapped[wrapped >= size[periodic]] = 0.0
        x[:, periodic] = wrapped
    return cKDTree(x, boxsize=size)


def _overlapping_pairs(position: np.ndarray, radius: np.ndarray, shift):
    """Pairs (i < j) of overlapping spheres and their centre distances."""
    if len(radius) < 2:
        return np.empty((0, 2), dtype=np.intp), np.empty(0)
    tree = _tree(position, shift)
    pairs = tree.query_pairs(2.0 * float(radius.max()), output_type="ndarray")
    if pairs.shape[0] == 0:
        return pairs, np.empty(0)
    dist = _pair_distance(position, pairs[:, 0], position, pairs[:, 1], shift)
    overlap = dist < (radius[pairs[:, 0]] + radius[pairs[:, 1]]) * (1.0 - CONTACT_TOLERANCE)
    return pairs[overlap], dist[overlap]


def _pair_distance(pa, ia, pb, ib, shift) -> np.ndarray:
    """Minimum-image centre distances between pa[ia] and pb[ib]."""
    delta = pa[ia] - pb[ib]
    if shift is not None:
        size = shift[1]
        periodic = size > 0.0
        if np.any(periodic):
            d = delta[:, periodic]
            delta[:, periodic] = d - size[periodic] * np.round(d / size[periodic])
    return np.sqrt(np.einsum("ij,ij->i", delta, delta))


def _random_sequential_addition(rng, radii, lower, upper, planes, placed_pos, placed_rad,
                                shift, budget):
    """Place spheres of the given radii at random without overlaps (random sequential addition).

    Spheres are tried largest first (small ones then fill the gaps). Each sphere takes uniform
    candidate centres in the region until one clears the walls and every sphere placed so far;
    neighbours are found in a cell grid whose cell edge is at least the largest diameter, so a
    candidate is compared with the spheres of 27 cells only.

    Uniform numbers are drawn by numpy in blocks and consumed in order by the compiled kernel,
    so the result depends on the seed alone (compiled or not, NUMBA_DISABLE_JIT=1 included).

    Args:
        rng: Random generator (consumed reproducibly).
        radii: Radii [m], shape (n,).
        lower, upper: Region corners [m]; every sphere lies wholly inside.
        planes: (point, unit normal) pairs; every sphere stays on the normal's side.
        placed_pos, placed_rad: Spheres already in the scene [m], shapes (m, 3), (m,).
        shift: (box origin, box size with 0 on non-periodic axes), or None.
        budget: Most candidate centres to draw.

    Returns:
        (positions (n, 3) with NaN rows for spheres not placed, candidates drawn).
    """
    n = radii.shape[0]
    order = np.argsort(-radii, kind="stable")
    r_all_max = float(max(radii.max(), placed_rad.max() if placed_rad.size else 0.0))
    reach = 2.0 * r_all_max  # farthest centre distance at which two spheres can overlap

    # grid domain: the whole box along periodic axes, the region plus `reach` elsewhere
    period = np.zeros(3) if shift is None else shift[1].astype(float)
    dom_lo = np.where(period > 0, shift[0] if shift is not None else 0.0, lower - reach)
    span = np.where(period > 0, period, (upper - lower) + 2.0 * reach)
    keep = np.ones(placed_rad.shape[0], dtype=bool)
    for i in range(3):
        if period[i] == 0.0:
            keep &= (placed_pos[:, i] >= dom_lo[i]) & (placed_pos[:, i] < dom_lo[i] + span[i])
    old_pos, old_rad = placed_pos[keep], placed_rad[keep]
    # cell edge >= reach; coarser when the spheres are sparse, so the grid stays ~ O(n) cells
    max_cells = max(1000, 4 * (n + old_rad.shape[0]))
    edge = max(reach, float(np.prod(span) / max_cells) ** (1.0 / 3.0))
    ncell = np.where(period > 0, np.floor(span / edge), np.ceil(span / edge))
    ncell = np.maximum(ncell, 1.0).astype(np.int64)
    cell = span / ncell

    cap = old_rad.shape[0] + n
    grid_pos = np.empty((cap, 3))
    grid_rad = np.empty(cap)
    grid_pos[: old_rad.shape[0]] = old_pos
    grid_rad[: old_rad.shape[0]] = old_rad
    head = np.full(int(np.prod(ncell)), -1, dtype=np.int64)
    nxt = np.full(cap, -1, dtype=np.int64)
    _grid_insert_all(grid_pos, old_rad.shape[0], head, nxt, dom_lo, cell, ncell, period)

    plane_point = np.array([pt for pt, _ in planes], dtype=float).reshape(-1, 3)
    plane_normal = np.array([nv for _, nv in planes], dtype=float).reshape(-1, 3)
    positions = np.full((n, 3), np.nan)
    state = np.array([0, old_rad.shape[0]], dtype=np.int64)  # next sphere in `order`, grid fill
    attempts = 0
    while state[0] < n and attempts < budget:
        block = int(min(budget - attempts, max(4096, 2 * (n - state[0]))))
        u = rng.random((block, 3))
        used = _rsa_kernel(u, order, radii, lower, upper, plane_point, plane_normal,
                           grid_pos, grid_rad, head, nxt, dom_lo, cell, ncell, period,
                           positions, state)
        attempts += used
    return positions, attempts


@njit
def _cell_of(x, dom_lo, cell, ncell, period):
    """Flat index of the grid cell holding point x (wrapped along periodic axes)."""
    flat = 0
    for a in range(3):
        c = math.floor((x[a] - dom_lo[a]) / cell[a])
        if period[a] > 0.0:
            c %= ncell[a]
        else:
            c = min(max(c, 0), ncell[a] - 1)
        flat = flat * ncell[a] + c
    return flat


@njit
def _grid_insert_all(grid_pos, count, head, nxt, dom_lo, cell, ncell, period):
    """Insert the first ``count`` points of ``grid_pos`` into the linked-cell grid."""
    for p in range(count):
        c = _cell_of(grid_pos[p], dom_lo, cell, ncell, period)
        nxt[p] = head[c]
        head[c] = p


@njit(allocates=True)
def _rsa_kernel(u, order, radii, lower, upper, plane_point, plane_normal, grid_pos, grid_rad,
                head, nxt, dom_lo, cell, ncell, period, positions, state):
    """Consume uniform triples ``u`` as candidate centres; returns how many were used.

    ``state`` = [next index into ``order``, number of spheres in the grid], updated in place.
    """
    k = state[0]
    filled = state[1]
    n = order.shape[0]
    x = np.empty(3)
    idx = np.empty(3, dtype=np.int64)
    used = 0
    while k < n and used < u.shape[0]:
        s = order[k]
        r = radii[s]
        for a in range(3):
            x[a] = lower[a] + r + u[used, a] * (upper[a] - lower[a] - 2.0 * r)
        used += 1
        ok = True
        for q in range(plane_point.shape[0]):
            d = 0.0
            for a in range(3):
                d += (x[a] - plane_point[q, a]) * plane_normal[q, a]
            if d < r:
                ok = False
                break
        if ok:
            for a in range(3):
                idx[a] = math.floor((x[a] - dom_lo[a]) / cell[a])
            # own cell first: that is where a rejected candidate usually finds its overlap
            for ox in range(3):
                if not ok:
                    break
                dx = ox if ox < 2 else -1
                for oy in range(3):
                    if not ok:
                        break
                    dy = oy if oy < 2 else -1
                    for oz in range(3):
                        dz = oz if oz < 2 else -1
                        flat = 0
                        inside = True
                        for a in range(3):
                            c = idx[a] + (dx if a == 0 else (dy if a == 1 else dz))
                            if period[a] > 0.0:
                                c %= ncell[a]
                            elif c < 0 or c >= ncell[a]:
                                inside = False
                            flat = flat * ncell[a] + c
                        if not inside:
                            continue
                        p = head[flat]
                        while p >= 0:
                            d2 = 0.0
                            for a in range(3):
                                e = x[a] - grid_pos[p, a]
                                if period[a] > 0.0:  # minimum image
                                    if e > 0.5 * period[a]:
                                        e -= period[a]
                                    elif e < -0.5 * period[a]:
                                        e += period[a]
                                d2 += e * e
                            reach = r + grid_rad[p]
                            if d2 < reach * reach:
                                ok = False
                                break
                            p = nxt[p]
                        if not ok:
                            break
        if ok:
            for a in range(3):
                grid_pos[filled, a] = x[a]
                positions[s, a] = x[a]
            grid_rad[filled] = r
            c = _cell_of(x, dom_lo, cell, ncell, period)
            nxt[filled] = head[c]
            head[c] = filled
            filled += 1
            k += 1
    state[0] = k
    state[1] = filled
    return used
