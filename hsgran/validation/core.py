"""Shared machinery of the validation cases: result records, tolerances, engine runs, scene text.

A case compares hsgran with a reference in one or more :class:`Check` rows. A check holds the
compared :class:`Point` values (one per sweep point) and a kind:

* ``assert`` — the case fails when any point lies outside its tolerance;
* ``known`` — a documented disagreement of the model with the reference (for example the
  sticking range of oblique impacts, where a rigid tangential model gives e_t = 5/7): measured
  and reported with a sentence saying why, never counted as a pass;
* ``info`` — a qualitative comparison whose source gives no number to hold a tolerance to.

Every tolerance is a named constant below with the reason for its size; none is tuned to make a
case pass.

Layer 6.
"""

from __future__ import annotations

import csv
import math
import textwrap
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hsgran import refdata
from hsgran.engine import EventBlock, RunSummary, Simulation
from hsgran.errors import HsgranError, MissingDependency
from hsgran.events.kinds import EV_PAIR, EV_WALL
from hsgran.scene import Scene, load_scene, parse_scene

# ---- tolerances (each with the reason for its size) --------------------------------------

#: Digitised curves (Kratos tracings of Chung & Ooi's figures) carry ±1–2 % of the axis range
#: in each coordinate (hsgran/data/README.md). We take the upper end, because the real axis
#: ranges are unknown and the extent of the plotted data (a lower bound) stands in for them.
DIGITISING_FRACTION = 0.02
#: Closed forms are exact; the engine evaluates the same algebra in another order and carries
#: the state through free flight, so only round-off separates them (measured ≤ 1e-13). 1e-9,
#: the bound VALIDATION.md sets for closed forms, is millions of ulp yet far below any wrong
#: factor, sign or branch.
CLOSED_FORM_RTOL = 1e-9
#: Conservation laws and identities (momentum, J_n = (1 + e_n) m* v0, prescribed e_n): a few
#: products and sums of double-precision numbers, so 1e-12 relative is round-off only.
ROUNDOFF_RTOL = 1e-12
#: The capture speed is found by bisection on the engine's capture outcome; the bisection stops
#: at this relative bracket width, so the engine value is known to it (far below the 1e-3
#: printing unit of the MODEL §7.1 anchor).
BISECTION_RTOL = 1e-7
#: Relative slack added to a half-unit-in-the-last-digit tolerance: it only absorbs the binary
#: representation of the printed decimal numbers.
PRINTED_SLACK_RTOL = 1e-12
#: The Hertz contact durations of derived_hertz_chung_ooi_tests1_2.csv are ~1.2e-5 (at most
#: 1.8e-5) above the exact value (hsgran/data/README.md), so that column is trusted to 2e-5.
DERIVED_CONTACT_TIME_RTOL = 2e-5

#: Every tolerance rule by the name used in the report, with its reason (shown in report.md).
TOLERANCE_RULES = {
    "digitising": (
        f"{DIGITISING_FRACTION:.0%} of the figure's axis range in y, plus |slope| × "
        f"{DIGITISING_FRACTION:.0%} of the x range: the tracing error of a digitised point "
        "(hsgran/data/README.md states ±1–2 %; the axis ranges are unknown, so the data extent, "
        "a lower bound, stands in for them)"),
    "closed form": (
        f"relative {CLOSED_FORM_RTOL:g}: the closed form is exact, so only round-off may "
        "separate it from the engine (VALIDATION.md's bound for closed forms)"),
    "round-off": (
        f"relative {ROUNDOFF_RTOL:g}: a conservation law or identity evaluated in double "
        "precision"),
    "printed digit": (
        "one unit in the last printed digit of a MODEL §7.1 anchor: the anchors are "
        "rounded values of two independent implementations, and double rounding (to 5 figures, "
        "then 4) can move an entry by more than half a unit"),
    "half digit": (
        "half a unit in the last printed digit of a derived table (the table is the closed "
        "form rounded to the digits shown)"),
    "contact time": (
        f"relative {DERIVED_CONTACT_TIME_RTOL:g}: the derived contact durations are ~1.2e-5 "
        "above the exact Hertz value (hsgran/data/README.md)"),
    "bisection": (
        f"relative {BISECTION_RTOL:g}: width of the bisection bracket on the engine's capture "
        "outcome"),
    "exact": "zero: the quantity must come out exactly (no arithmetic acts on it)",
}

# ---- result records ----------------------------------------------------------------------

PASS = "pass"
FAIL = "FAIL"
KNOWN = "known"
INFO = "info"
CHECK_KINDS = ("assert", "known", "info")


class ValidationError(HsgranError):
    """A case could not be evaluated (for example its scene lacks a sphere it needs)."""


@dataclass
class Point:
    """One compared value.

    Attributes:
        at: Where in the sweep (``"θ = 40°"``).
        reference: Reference value, in the check's unit.
        value: hsgran's value, same unit.
        tolerance: Largest admissible |value − reference| (NaN for known/info checks).
    """

    at: str
    reference: float
    value: float
    tolerance: float = math.nan

    @property
    def deviation(self) -> float:
        """hsgran − reference."""
        return self.value - self.reference

    @property
    def ratio(self) -> float:
        """|deviation| / tolerance (0 for an exact match, inf outside a zero tolerance)."""
        dev = abs(self.deviation)
        if dev == 0.0:
            return 0.0
        if not math.isfinite(dev):
            return math.inf
        return dev / self.tolerance if self.tolerance > 0.0 else math.inf

    @property
    def ok(self) -> bool:
        """Within tolerance."""
        return self.ratio <= 1.0


@dataclass
class Check:
    """One row of the report: a quantity compared with one reference over a set of points.

    Attributes:
        quantity: What is compared, with its condition (``"e_t, sliding (θ > 35°)"``).
        reference: The reference (``"Chung & Ooi DEM, digitised"``).
        points: The compared values.
        rule: Name of the tolerance rule (a key of :data:`TOLERANCE_RULES`), or ``""``.
        kind: ``"assert"``, ``"known"`` or ``"info"`` (see the module notes).
        note: The sentence shown with a known disagreement or a qualitative comparison.
        unit: Unit of the values (``"m/s"``; ``""`` for dimensionless).
    """

    quantity: str
    reference: str
    points: list[Point]
    rule: str = ""
    kind: str = "assert"
    note: str = ""
    unit: str = ""

    def __post_init__(self):
        if self.kind not in CHECK_KINDS:
            raise ValueError(f"check kind must be one of {CHECK_KINDS}, got {self.kind!r}")
        if self.kind == "assert" and self.rule not in TOLERANCE_RULES:
            raise ValueError(f"asserted check {self.quantity!r} needs a tolerance rule")

    @property
    def worst(self) -> Point | None:
        """The point with the largest |deviation|/tolerance (largest |deviation| if unchecked)."""
        if not self.points:
            return None
        if self.kind == "assert":
            return max(self.points, key=lambda p: p.ratio)
        return max(self.points, key=lambda p: abs(p.deviation) if math.isfinite(p.deviation)
                   else math.inf)

    @property
    def status(self) -> str:
        """:data:`PASS`, :data:`FAIL`, :data:`KNOWN` or :data:`INFO`.

        An asserted check without points fails: a sweep that compared nothing proves nothing.
        """
        if self.kind == "known":
            return KNOWN
        if self.kind == "info":
            return INFO
        if not self.points:
            return FAIL
        return PASS if all(p.ok for p in self.points) else FAIL


@dataclass
class CaseResult:
    """What one validation case found.

    Attributes:
        name: Case name (``co4``).
        title: One-line title.
        checks: The report rows.
        notes: Sentences for the report: known disagreements, [OURS] parts, data caveats.
        scenes: Scene files the case ran.
        figure: Path of the figure written, or ``None``.
        wall_time: Seconds the case took.
        error: Message of an unexpected error that stopped the case (the case then fails).
    """

    name: str
    title: str
    checks: list[Check] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    scenes: list[str] = field(default_factory=list)
    figure: Path | None = None
    wall_time: float = 0.0
    error: str = ""

    @property
    def passed(self) -> bool:
        """No asserted check failed and nothing went wrong."""
        return not self.error and all(c.status != FAIL for c in self.checks)


# ---- tolerances from data ----------------------------------------------------------------

def digitising_tolerance(slope: float, x_span: float, y_span: float) -> float:
    """Largest admissible |y_digitised − y_model(x_digitised)| for one traced point.

    A point is misplaced by up to :data:`DIGITISING_FRACTION` of the axis range in y and in x;
    an x error shifts the comparison along the curve, changing y by |slope| times it.

    Args:
        slope: dy/dx of the model curve at the point [y unit / x unit].
        x_span, y_span: Axis ranges (here: the data extents, a lower bound).
    """
    return DIGITISING_FRACTION * (y_span + abs(slope) * x_span)


def extent(*arrays) -> float:
    """max − min over all values of the given arrays (a figure axis's data extent)."""
    values = np.concatenate([np.asarray(a, dtype=float).ravel() for a in arrays])
    return float(values.max() - values.min())


def geometric_grid(lo: float, hi: float, n: int) -> list[float]:
    """``n`` ≥ 2 points from ``lo`` to ``hi`` (both > 0) spaced evenly in log10, like
    ``numpy.geomspace`` but through Python's math: numpy picks its vector kernels of log and
    power by CPU at run time and their last bit differs between CPUs with and without AVX-512,
    which changed the scene files generated from these grids from machine to machine."""
    a, b = math.log10(lo), math.log10(hi)
    step = (b - a) / (n - 1)
    grid = [math.pow(10.0, k * step + a) for k in range(n)]
    grid[0], grid[-1] = lo, hi
    return grid


def central_slope(func: Callable[[float], float], x: float, h: float) -> float:
    """Central difference (f(x + h) − f(x − h)) / 2h of a closed-form curve."""
    return (func(x + h) - func(x - h)) / (2.0 * h)


def printed_unit(ref: float, figures: int) -> float:
    """One unit in the last digit of ``ref`` printed with ``figures`` significant figures."""
    return 10.0 ** (math.floor(math.log10(abs(ref))) - (figures - 1))


def half_unit(text: str) -> float:
    """Half a unit in the last printed digit of a decimal string (``'40.340'`` → 5e-4)."""
    mantissa, _, exponent = text.strip().lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 0.5 * 10.0 ** (int(exponent or 0) - decimals)


def closed_form_tolerance(reference: float, scale: float = 0.0) -> float:
    """:data:`CLOSED_FORM_RTOL` relative to ``max(|reference|, scale)``.

    ``scale`` is the natural size of the quantity, for references that can be zero (a slip
    that vanishes in the rolling regime is compared on the scale of the impact speed).
    """
    return CLOSED_FORM_RTOL * max(abs(reference), scale)


def roundoff_tolerance(reference: float, scale: float = 0.0) -> float:
    """:data:`ROUNDOFF_RTOL` relative to ``max(|reference|, scale)``."""
    return ROUNDOFF_RTOL * max(abs(reference), scale)


def printed_rows(name: str) -> list[dict[str, str]]:
    """Rows of a reference-data CSV as printed (strings), to know each value's precision."""
    with refdata.data_path(name).open(newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def long_series(table: dict, series: str, quantity: str, xcol: str, ycol: str):
    """(x, y) of one series and quantity of a long-format reference table, sorted by x."""
    mask = np.array([s == series and q == quantity
                     for s, q in zip(table["series"], table["quantity"], strict=True)])
    x = np.asarray(table[xcol])[mask]
    y = np.asarray(table[ycol])[mask]
    order = np.argsort(x)
    return x[order], y[order]


def quantity_extent(table: dict, quantity: str, xcol: str, ycol: str) -> tuple[float, float]:
    """Data extents (x span, y span) of one quantity over every series (one figure's axes)."""
    mask = np.array([q == quantity for q in table["quantity"]])
    return extent(np.asarray(table[xcol])[mask]), extent(np.asarray(table[ycol])[mask])


# ---- running scenes through the engine ---------------------------------------------------

#: The engine's event log of one run, concatenated.
EventLog = EventBlock


class _Collector:
    """Engine observer that keeps every event block."""

    def __init__(self):
        self.blocks = []

    def on_events(self, block) -> None:
        self.blocks.append(block)

    def log(self) -> EventLog:
        return EventBlock.concatenate(self.blocks)


@dataclass
class EngineRun:
    """A scene run through :class:`hsgran.engine.Simulation` with the event log on.

    Attributes:
        scene: The scene.
        sim: The simulation after the run (its state is the state at the end).
        log: Every event of the run.
        summary: The run summary.
        t_end: End time of the run [s].
    """

    scene: Scene
    sim: Simulation
    log: EventLog
    summary: RunSummary
    t_end: float

    def collisions(self, i: int) -> np.ndarray:
        """Indices into the log of the collisions (pair or wall) of sphere ``i``."""
        lg = self.log
        hit = (lg.kind == EV_PAIR) | (lg.kind == EV_WALL)
        return np.flatnonzero(hit & ((lg.i == i) | ((lg.kind == EV_PAIR) & (lg.j == i))))

    def only_collision(self, i: int) -> int:
        """Index into the log of sphere ``i``'s one impact.

        A sphere left touching its partner with a normal velocity of round-off size (a
        captured sphere: e_n = 0 exactly in theory, ~1e-17 m/s of approach in floating point)
        meets it again at once; such repeats carry an impulse of round-off size and are not
        second impacts.

        Raises:
            ValidationError: the sphere never collided, or collided again with an impulse
                above round-off (the set-up of a one-impact case is then broken).
        """
        k = self.collisions(i)
        if len(k) == 0:
            raise ValidationError(f"{self.scene.source}: sphere {i} never collided")
        first = abs(float(self.log.normal_impulse[k[0]]))
        later = np.abs(self.log.normal_impulse[k[1:]])
        if np.any(later > ROUNDOFF_RTOL * first):
            raise ValidationError(f"{self.scene.source}: sphere {i} collided {len(k)} times, "
                                  "expected one impact")
        return int(k[0])

    def velocity(self, i: int) -> np.ndarray:
        """Centre velocity of sphere ``i`` at the end of the run [m/s]."""
        _, vel = self.sim.state_at(self.t_end)
        return vel[i].copy()

    def position(self, i: int) -> np.ndarray:
        """Centre of sphere ``i`` at the end of the run [m]."""
        pos, _ = self.sim.state_at(self.t_end)
        return pos[i].copy()

    def spin(self, i: int) -> np.ndarray:
        """Angular velocity of sphere ``i`` at the end of the run [rad/s].

        On a plane the engine advances the spin analytically between events: the stored value
        is that of the sphere's last event, so the angular acceleration is applied up to the
        end time.
        """
        if not self.sim.rotation:
            return np.zeros(3)
        omega = self.sim.omg[i].copy()
        if self.scene.effects.gravity:
            omega += self.sim.alpha[i] * (self.t_end - self.sim.t_loc[i])
        return omega


def run_engine(scene: Scene, until: float | None = None) -> EngineRun:
    """Run a scene with the event log on and keep everything a case needs.

    Args:
        scene: The scene.
        until: End time [s] (default: the scene's duration).
    """
    collector = _Collector()
    sim = Simulation(scene, log_events=True)
    summary = sim.run(until, observers=[collector])
    t_end = scene.duration if until is None else float(until)
    return EngineRun(scene, sim, collector.log(), summary, t_end)


def material_of(scene: Scene, i: int) -> str:
    """Material name of sphere ``i``."""
    return scene.material_names[int(scene.material[i])]


# ---- scene text --------------------------------------------------------------------------

def fnum(x: float) -> str:
    """A float as TOML text that reads back to the same double (shortest round trip)."""
    x = float(x)
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return repr(x)


def fvec(v: Sequence[float]) -> str:
    """A 3-vector as a TOML array."""
    return "[" + ", ".join(fnum(c) for c in v) + "]"


def comment_block(text: str, width: int = 99) -> str:
    """``text`` (paragraphs separated by blank lines) as TOML comment lines."""
    out = []
    for para in textwrap.dedent(text).strip().split("\n\n"):
        out += ["# " + line for line in textwrap.wrap(" ".join(para.split()), width - 2)]
        out.append("#")
    return "\n".join(out[:-1])


@dataclass
class SceneText:
    """Builder of a scene file's text (the format of :mod:`hsgran.scene`)."""

    comment: str
    name: str
    duration: float
    effects: Sequence[str]
    frame_interval: float | None = None
    gravity: Sequence[float] | None = None
    enduring: dict[str, object] = field(default_factory=dict)
    materials: dict[str, dict[str, float]] = field(default_factory=dict)
    contacts: list[dict[str, object]] = field(default_factory=list)
    walls: list[dict[str, object]] = field(default_factory=list)
    particles: list[tuple[str, dict[str, object]]] = field(default_factory=list)

    def material(self, name: str, **props: float) -> None:
        """Declare ``[materials.NAME]``."""
        self.materials[name] = props

    def contact(self, a: str, b: str, **props: object) -> None:
        """Declare a ``[[contacts]]`` entry between materials ``a`` and ``b``."""
        self.contacts.append({"between": [a, b], **props})

    def plane(self, point, normal, material: str) -> None:
        """Add a plane wall."""
        self.walls.append({"kind": "plane", "point": point, "normal": normal,
                           "material": material})

    def particle(self, label: str, material: str, radius: float, position, velocity=None,
                 angular_velocity=None) -> None:
        """Add one sphere; ``label`` becomes a comment above it."""
        entry: dict[str, object] = {"material": material, "radius": radius,
                                    "position": position}
        if velocity is not None:
            entry["velocity"] = velocity
        if angular_velocity is not None:
            entry["angular_velocity"] = angular_velocity
        self.particles.append((label, entry))

    def text(self) -> str:
        """The TOML text."""
        lines = [comment_block(self.comment), "", "[scene]", f"name = {_toml_value(self.name)}",
                 f"duration = {fnum(self.duration)}"]
        if self.gravity is not None:
            lines.append(f"gravity = {fvec(self.gravity)}")
        lines.append("effects = [" + ", ".join(f'"{e}"' for e in self.effects) + "]")
        lines += ["", "[output]",
                  f"frame_interval = {fnum(self.frame_interval or self.duration)}"]
        if self.enduring:
            lines += ["", "[enduring_contact]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in self.enduring.items()]
        for name, props in self.materials.items():
            lines += ["", f"[materials.{name}]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in props.items()]
        for c in self.contacts:
            lines += ["", "[[contacts]]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in c.items()]
        for w in self.walls:
            lines += ["", "[[walls]]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in w.items()]
        for label, p in self.particles:
            lines += ["", f"[[particles]]  # {label}" if label else "[[particles]]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in p.items()]
        return "\n".join(lines) + "\n"


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return fnum(v)
    if isinstance(v, (list, tuple, np.ndarray)):
        items = list(v)
        if len(items) == 3 and all(isinstance(c, (int, float, np.floating)) and
                                   not isinstance(c, bool) for c in items):
            return fvec([float(c) for c in items])
        return "[" + ", ".join(_toml_value(c) for c in items) + "]"
    if isinstance(v, np.floating):
        return fnum(float(v))
    raise TypeError(f"no TOML form for {v!r}")


# ---- context handed to a case ------------------------------------------------------------

@dataclass
class CaseContext:
    """What a case gets to run: where its scene files are, where its figure goes.

    Attributes:
        scenes_dir: Directory of the scene files (``scenarios/validation``), or ``None`` to use
            the texts built into hsgran.
        builtin: Scene file name → text, as built by the case (used when ``scenes_dir`` is
            ``None`` or lacks the file).
        figure_path: Where to write the case's figure (PNG).
        used: Scene sources the case loaded (filled by :meth:`scene`).
    """

    scenes_dir: Path | None
    builtin: dict[str, str]
    figure_path: Path
    used: list[str] = field(default_factory=list)

    def scene(self, filename: str) -> Scene:
        """Load one of the case's scene files (the built-in text if the file is absent)."""
        if self.scenes_dir is not None and (self.scenes_dir / filename).is_file():
            path = self.scenes_dir / filename
            self.used.append(str(path))
            return load_scene(path)
        if filename not in self.builtin:
            raise ValidationError(f"no scene file {filename}")
        self.used.append(f"{filename} (built in)")
        return parse_scene(self.builtin[filename], source=f"<built-in {filename}>")


# ---- the case registry entry ------------------------------------------------------------

@dataclass(frozen=True)
class Case:
    """A validation case.

    Attributes:
        name: Short name used by ``--case`` and in file names.
        title: One-line title.
        what: What the case runs and what it compares (a paragraph for the report and docs).
        scenes: Builds the case's scene files: file name → TOML text.
        run: Runs the case (scenes through the engine, comparison, figure).
    """

    name: str
    title: str
    what: str
    scenes: Callable[[], dict[str, str]]
    run: Callable[[CaseContext], CaseResult]


# ---- figures -----------------------------------------------------------------------------

#: Figure size of one panel [inch] and raster resolution [dpi].
PANEL_SIZE, DPI = (5.0, 3.6), 110


def new_figure(ncols: int = 1, nrows: int = 1, title: str = ""):
    """A matplotlib figure (Agg canvas, no pyplot state) and its axes array (flattened).

    Raises:
        MissingDependency: matplotlib is not installed.
    """
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        raise MissingDependency("validation figures need matplotlib (the 'dev' or 'render' "
                                "extra): pip install -e '.[dev]'") from None
    fig = Figure(figsize=(PANEL_SIZE[0] * ncols, PANEL_SIZE[1] * nrows + (0.4 if title else 0)),
                 layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    if title:
        fig.suptitle(title, fontsize=11)
    return fig, axes


def save_figure(fig, path: Path) -> Path:
    """Write a figure as PNG; returns the path."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI)
    return path


def finish_figure(fig, ctx: CaseContext, res: CaseResult) -> CaseResult:
    """Write a case's figure to its path, record it in the result, and return the result."""
    res.figure = save_figure(fig, ctx.figure_path)
    return res


#: Plot styles shared by every figure: reference data as open markers, hsgran as lines/dots.
DATA_STYLE = {"linestyle": "none", "marker": "o", "markerfacecolor": "none", "markersize": 5}
MODEL_STYLE = {"linewidth": 1.6}
ENGINE_STYLE = {"linestyle": "none", "marker": ".", "markersize": 5}
