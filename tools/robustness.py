"""The robustness corpus: granular scenes drawn from a seeded parameter space, each run in a
process of its own, and how each one ended (issue 25, item 3).

Usage:
    .venv/bin/python tools/robustness.py [--count 40] [--corpus-seed 0] [--first 0]
        [--max-count 3000] [--jobs 2] [--timeout 600] [--out FILE.csv|FILE.json]
        [--write-scenes DIR] [--dry-run]
    .venv/bin/python tools/robustness.py --sample [--jobs 2] [--out FILE]
    .venv/bin/python tools/robustness.py --rerun FILE.csv [--outcome timeout] [--max-count M]
        [--timeout 700] [--out FILE2.csv]

It is the yardstick of the settling rules (docs/enduring-contact.md): today's pairwise rules
are expected to fail on some scenes, and this tool measures how often and how, it does not make
them pass. Figures only, no pass/fail (exit code 0 whatever the outcomes; 2 on bad arguments).

**The scenes.** Scene ``I`` of corpus seed ``S`` (id ``S-I``) draws every parameter from
``numpy.random.default_rng(scene_seed(S, I))``, so a corpus is the same on every machine:

- N spheres, log-uniform in [100, 3000] (``--max-count M``: log-uniform in [100, M], the
  other draws unchanged);
- a fixed restitution e in [0.1, 0.95] for every pair, or the staged normal model (effect
  ``plasticity``, no fixed restitution: below the yield speed impacts are elastic); half of
  the staged scenes also lose energy below the yield speed (effect ``viscoelastic_damping``,
  docs/model.md §3.11: :func:`_draw_damping`, from a generator of its own, so every other
  draw is the same with it or without it);
- frictionless, sliding friction μ in [0, 0.8] (effects ``rotation``, ``friction``), or
  that and rolling friction μ_r in [0, 0.02] (``rolling_resistance``);
- base radius r in [0.5, 2] mm and a ratio q in [1, 3]: one fill with radii uniform in
  [r, q r] (q = 1: equal spheres), or a two-size mixture (fills of radius q r and r);
  one or two built-in sphere materials, a wall material; the [[contacts]] cover every pair;
- a geometry (:data:`KINDS`): ``box``; ``cut_box``, a box with 1–3 extra planes (chamfers
  with obtuse corners, overhangs with an acute corner against the floor, vertical slants with
  an acute and an obtuse corner between walls); ``wedge``, a V of two planes closed at its
  ends by the box; ``incline``, a tilted floor ending at the box's end wall (acute corner);
  ``polygon``, a horizontal cylinder of 6–32 planes closed at its ends by the box; ``chute``,
  a box periodic in x and y with gravity tilted along x (planes must stay parallel to
  periodic axes, so the floor stays flat);
- a pour: the fill region starts 1–20 mean diameters above the estimated bed surface (the
  height below which the container holds the N spheres at packing fraction
  :data:`BED_PACKING`); it is sized so that the spheres fill at most :data:`FILL_PACKING` of
  the volume their centres may take there; fill speed 0–0.05 m/s;
- the duration: the fall time from the top of the fill region to the bed surface plus
  :data:`SETTLE_TIME` (chutes: plus :data:`CHUTE_FLOW_TIME`; their spheres never stop).

A scene is **expected to come to rest** when it has friction and rolling resistance, is
not periodic (a chute tilts gravity by 5–30°, more than any μ_r ≤ 0.02 holds), and its
impacts lose energy however slow they are: a fixed restitution, or the staged model with
damping. Without damping the staged model's impacts below the yield speed are perfectly
elastic (docs/model.md §9), and the built-in materials yield at 0.013–18 m/s sphere on sphere
and 0.037–36 m/s on a wall (alumina on alumina never): most of a settling bed's last,
slow impacts return all their normal speed, and a sphere left bouncing straight up and down
on a floor, which no friction slows, bounces for ever (corpus 0-34 before the damping was
drawn: five glass spheres at up to 2.6 cm/s after 1 s, e = 1 below V_y = 36 m/s).

**What is measured** per scene (:func:`run_scene_text`, in the scene's own process, killed
after ``--timeout`` seconds of wall time): the outcome (``completed``; ``guard``, the collapse
guard's SimulationError "... without time advancing ...", its message followed by what the
sphere it names touches, :func:`guard_context`; ``timeout``, its message saying how fast the
simulated time still advanced; ``error`` with the message), the simulated time reached, wall
and CPU time, motion events (pair, wall, state, land) per particle, the run's counts by event
kind (hsgran.events.kinds), and, from frames every :data:`FRAME_INTERVAL`:

- worst overlap: the largest (σ − d)/σ of a touching pair over all frames, and the largest
  (R − h)/R of a sphere at distance h from a plane;
- time to rest: the first frame time after which the largest speed of every later frame is
  below :data:`REST_SPEED` (empty when the last frame is not below it);
- last arrival: a sphere *arrives* at its first collision or landing (event log) with a floor
  (a plane whose normal has a component against gravity; side walls, lids and overhangs do
  not count) or with a sphere that had arrived before; the last arrival is the latest of these
  times (empty if a sphere never arrived);
- bulk packing fraction of the bed at the last frame (:func:`bulk_packing_fraction`): the
  share of random probe points inside spheres, among probes at least
  :data:`WALL_CLEARANCE_DIAMETERS` mean diameters from every plane and at least
  :data:`SURFACE_DEPTH_DIAMETERS` below the bed surface of their column (columns
  :data:`COLUMN_DIAMETERS` wide, surface = highest sphere top of the bed in the column; the bed
  = spheres connected through contacts to a plane);
- of a completed scene, the spheres still moving at its end (``movers``) and how many of them
  roll alone on a plane to a stop the engine has scheduled (``rolling_alone``, the latest
  stop ``stops_by``; :func:`rolling_out`): the summary names the scenes expected to rest
  whose only movers are such spheres, which stop as the model says after the scene's end
  (they do not count as at rest);
- the energy the run dissipated (``Simulation.dissipated_energy``, every mechanism) and the
  part the collision model took (``collision_loss``), with the rule counts land, tc, hop and
  wedge;
- the cluster solves' work: their Gauss–Seidel sweeps and the contacts those visited
  (``solver_sweeps``, ``solver_visits``; docs/enduring-contact.md), where a dense scene's
  time goes, and how many of them froze their friction before it converged
  (``solver_frozen``: friction there holds only to the accuracy its sweeps reached).

Output: one line per scene as it ends; then the table in scene order, the message of every
scene that did not complete, outcomes by kind and a summary line (scenes, completed %, guard,
timeout, error, worst overlap, settle success among the scenes expected to rest); ``--out``
writes the rows as CSV (``.csv``) or JSON (otherwise). ``--write-scenes DIR`` saves every
scene as ``DIR/<id>.toml`` (run one with ``hsgran run``); ``--dry-run`` only lists the scenes
(and writes them). ``--sample`` runs :data:`SAMPLE`, six small short scenes (N ≤ 250: box,
cut box, wedge, incline, polygon, chute), under 2 minutes of CPU in all once compiled
(tests/test_robustness.py runs it as a slow test).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from hsgran._state import SOLVER_COUNTS
from hsgran.contact.viscous import dissipative_constant_for
from hsgran.engine import LARGE_FROM
from hsgran.events.kinds import EV_LAND, EV_PAIR, EV_WALL, EVENT_NAMES
from hsgran.materials import (
    BUILTIN_MATERIALS,
    MATERIAL_KEYS,
    effective_modulus,
    solid_sphere_mass,
)
from hsgran.placement import Space, overlapping_pairs
from hsgran.precompile import compile_all, jit_disabled
from hsgran.scene import TREATMENTS

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT / "tools") not in sys.path:  # settle_report, when loaded by file path (tests)
    sys.path.insert(0, str(ROOT / "tools"))

from settle_report import MOTION_EVENTS  # noqa: E402  (after the path set-up above)

# ---- the parameter space ------------------------------------------------------------------

#: Geometry kinds (module docstring).
KINDS = ("box", "cut_box", "wedge", "incline", "polygon", "chute")
#: Sphere count range [-]: from a pour that leaves a sparse layer to one that takes minutes.
COUNT_RANGE = (100, 3000)
#: Fixed restitution range [-]: from nearly plastic to nearly elastic.
RESTITUTION_RANGE = (0.1, 0.95)
#: Probability of a fixed restitution (else the staged model with plasticity).
FIXED_RESTITUTION_SHARE = 0.6
#: Share of the staged scenes drawn with viscous damping below the yield speed (effect
#: ``viscoelastic_damping``; the others keep the paper's elastic impacts there) [-].
DAMPED_SHARE = 0.5
#: Viscous restitution factor e_visc (docs/model.md §3.11) of a damped scene's reference pair
#: (its first sphere material on itself, at the mean radius) at DAMPING_SPEED [-]: the pair's
#: whole restitution there unless it yields below that speed. Hard beads such as glass
#: rebound at about 0.9 and above at such speeds (e.g. Foerster et al. 1994, Phys. Fluids 6,
#: 1108), and the range goes down to lossier pairs. Its top, 0.95, still brings a bouncing
#: sphere to rest within the SETTLE_TIME (corpus 0-34, docs/enduring-contact.md).
DAMPED_RESTITUTION_RANGE = (0.7, 0.95)
#: Impact speed at which a damped scene's restitution is drawn [m/s]: a bed's collisions.
DAMPING_SPEED = 0.1
#: Second entry of the seed of the damping draw's own generator (``[scene seed, this]``) [-].
DAMPING_STREAM = 1
#: Friction modes and their probabilities: none, sliding friction, sliding and rolling.
FRICTION_MODES = {"none": 0.25, "sliding": 0.35, "rolling": 0.40}
#: Largest sliding friction coefficient μ_s [-].
SLIDING_FRICTION_MAX = 0.8
#: Largest rolling friction coefficient μ_r [-] (dimensionless, torque μ_r R* F_n).
ROLLING_FRICTION_MAX = 0.02
#: Base radius range [m]: millimetre beads.
RADIUS_RANGE = (0.5e-3, 2e-3)
#: Largest ratio of the largest to the smallest radius [-].
RADIUS_RATIO_MAX = 3.0
#: Share of the scenes whose spheres are a two-size mixture (else a uniform range of radii).
MIXTURE_SHARE = 0.5
#: Share of single-range scenes that are monodisperse (ratio 1).
MONODISPERSE_SHARE = 0.2
#: Smallest size ratio of a two-size mixture [-] (closer sizes are a narrow range, not a mix).
MIXTURE_RATIO_MIN = 1.2
#: Range of the number share of the large spheres in a mixture [-].
MIXTURE_LARGE_SHARE = (0.1, 0.5)
#: Built-in sphere materials drawn from (hsgran.materials; their yield stresses give the
#: staged model something to do, alumina never yields).
SPHERE_MATERIALS = ("steel", "glass", "alumina", "aluminium_alloy")
#: Share of the scenes with two sphere materials (else one).
TWO_MATERIALS_SHARE = 0.5
#: Range of the number share of the first material in a range of radii of two materials [-].
FIRST_MATERIAL_SHARE = (0.3, 0.7)
#: Built-in wall materials drawn from.
WALL_MATERIALS = ("glass", "steel")
#: Pour height range, from the estimated bed surface to the fill region's bottom [mean
#: diameters].
DROP_RANGE = (1.0, 20.0)
#: Largest fill speed [m/s] (random directions).
FILL_SPEED_MAX = 0.05
#: Range of the depth of the bed if it lay flat, which sets the container's cross-section
#: [mean diameters]: from a layer two spheres deep to a column.
BED_DEPTH_RANGE = (2.0, 15.0)
#: Packing fraction assumed for the bed when sizing containers [-] (poured beads: 0.58-0.64).
BED_PACKING = 0.6
#: Packing fraction of the fill, relative to the volume of the fill region its centres may
#: take (at least one mean radius from every plane and region face) [-]: well below random
#: sequential addition's jamming (0.38), so every fill is placed (hsgran.placement).
FILL_PACKING = 0.25
#: Narrowest container width [largest diameters]: narrower columns only jam.
MIN_WIDTH_DIAMETERS = 4.0
#: Shortest periodic length [largest diameters]: the cell grid needs 3 cells of one largest
#: diameter on a periodic axis (hsgran.events.grid.MIN_PERIODIC_CELLS), this leaves margin.
MIN_PERIODIC_DIAMETERS = 6.0
#: Range of the horizontal aspect ratio of boxes, wedges and chutes [-].
ASPECT_RANGE = (0.5, 2.0)
#: Range of the aspect ratio of an incline's box, along the slope to across [-].
INCLINE_ASPECT_RANGE = (1.5, 4.0)
#: Angle of a wedge's planes from the horizontal [deg] (V opening 150° to 40°).
WEDGE_ANGLE_RANGE = (15.0, 70.0)
#: Slope of an incline [deg]: from one friction holds to one it does not.
INCLINE_ANGLE_RANGE = (5.0, 35.0)
#: Tilt of a chute's gravity [deg].
CHUTE_ANGLE_RANGE = (5.0, 30.0)
#: Number of planes of a polygonal cylinder.
POLYGON_SIDES = (6, 32)
#: Range of a polygonal cylinder's length over its diameter [-].
POLYGON_ASPECT_RANGE = (0.3, 1.5)
#: Number of extra planes of a cut box.
CUT_PLANES = (1, 3)
#: The kinds of extra plane of a cut box (module docstring).
CUT_KINDS = ("chamfer", "overhang", "slant")
#: Slope of a chamfer from the floor [deg] (obtuse corners 180° − β with the floor, 90° + β
#: with the wall).
CHAMFER_ANGLE_RANGE = (20.0, 70.0)
#: Height of a chamfer on its wall [share of the box width across it].
CHAMFER_HEIGHT_RANGE = (0.15, 0.5)
#: Farthest a chamfer reaches across the floor [share of the width]: the floor stays a floor.
CHAMFER_REACH = 0.6
#: Where an overhang meets the floor [share of the width from its wall].
OVERHANG_FOOT_RANGE = (0.05, 0.3)
#: How far an overhang leans over the floor at the box's top [share of the floor in front of
#: it]: below 1, so it never closes the container (its acute corner with the floor is
#: 90° − atan(share × floor / height)).
OVERHANG_LEAN_RANGE = (0.2, 0.6)
#: Acute angle between a slant (a vertical plane) and the wall it leaves [deg].
SLANT_ANGLE_RANGE = (40.0, 80.0)
#: Where a slant crosses the middle of the box [share of the width from its wall].
SLANT_FOOT_RANGE = (0.1, 0.35)
#: Standard gravity [m/s²].
GRAVITY = 9.81
#: Simulated time after the pour has landed [s]: the issue's "1 s to settle".
SETTLE_TIME = 1.0
#: Simulated flow time of a chute after the pour has landed [s]: chutes never come to rest.
CHUTE_FLOW_TIME = 0.5
#: Time between frames [s]: resolution of the time to rest.
FRAME_INTERVAL = 0.01

# ---- sizing containers ----------------------------------------------------------------------

#: Shortest fill region, along z [largest diameters].
FILL_MIN_HEIGHT_DIAMETERS = 2.0
#: Sample points of the volume estimates that size a container (a regular grid over its box):
#: the volumes come out to ~1 %, enough for packing targets with a safety factor.
VOXELS = 20_000
#: Factor by which a container grows until the bed and the fill fit in it.
SIZE_GROWTH = 1.1
#: Most growth steps (1.1⁸⁰ ≈ 2000: far past any need).
SIZE_STEPS = 80

# ---- measuring --------------------------------------------------------------------------------

#: Speed below which every sphere counts as at rest [m/s] (the issue's threshold: 1 µm/s
#: moves a millimetre bead a thousandth of its size in a second).
REST_SPEED = 1e-6
#: Relative gap up to which two spheres, or a sphere and a plane, touch for the bed of the
#: packing-fraction measurement [-]: spheres at rest touch within ~1e-9.
TOUCH_SLACK = 1e-3
#: Probe points within this many mean diameters of a plane are not measured (walls order a
#: packing over about two layers).
WALL_CLEARANCE_DIAMETERS = 2.0
#: ... nor within this many mean diameters below the bed surface of their column (the loose
#: top layers).
SURFACE_DEPTH_DIAMETERS = 2.0
#: Width of the columns that define the bed surface [mean diameters].
COLUMN_DIAMETERS = 2.0
#: Random probe points of a packing-fraction measurement: 1e5 probes in the measured region
#: give the fraction to ±0.0016.
PROBES = 200_000
#: Seed of the probe points (measurements are reproducible).
PROBE_SEED = 20_250_025
#: Nearest centres tested for each probe: more than can lie within one largest radius of a
#: point with radius ratios up to 3, bar pathological cases.
PROBE_NEIGHBOURS = 16
#: Fewest probes in the measured region for a packing fraction (else none is reported).
MIN_PROBES = 1000
#: Smallest measured region [mean sphere volumes] (else no packing fraction is reported): a
#: region a few spheres big gives the fraction of whichever spheres it happens to cut.
MIN_REGION_SPHERES = 50
#: Wall time between progress lines of a running scene [s].
PROGRESS_WALL = 2.0
#: Wall time over which a timed-out scene's pace is measured [s].
PACE_WALL = 60.0
#: What the collapse guard's SimulationError says (hsgran.engine.Simulation.run).
GUARD_TEXT = "without time advancing"
#: Default wall-time limit of one scene [s].
DEFAULT_TIMEOUT = 600.0
#: Default number of scenes run at once (the machines have two cores).
DEFAULT_JOBS = 2
#: The outcomes, in report order.
OUTCOMES = ("completed", "guard", "timeout", "error")
#: The rule counts of the settling treatment (docs/enduring-contact.md) reported with the
#: energy.
RULE_EVENTS = ("land", "tc", "hop", "wedge")

#: The fixed sample (``--sample``): (corpus seed, index, kind) of six small, short scenes,
#: drawn with N ≤ :data:`SAMPLE_MAX_COUNT` and :data:`SAMPLE_SETTLE_TIME`; the indices are
#: picked for variety: four scenes expected to rest, both restitution modes, a frictionless
#: wedge, a chute with the staged model.
SAMPLE = ((0, 7, "box"), (0, 23, "cut_box"), (0, 2, "wedge"), (0, 3, "incline"),
          (0, 17, "polygon"), (0, 5, "chute"))
#: Largest N of the sample's scenes.
SAMPLE_MAX_COUNT = 250
#: Settling (chutes: flow) time of the sample's scenes after the pour lands [s].
SAMPLE_SETTLE_TIME = 0.3


# ---- drawing a scene ---------------------------------------------------------------------------

@dataclass
class Container:
    """Where the spheres live: a box (its faces on non-periodic axes are walls) and extra
    planes, all lengths in m.

    Attributes:
        lower, upper: Corners of the box [m], shape (3,).
        planes: Extra planes, (point [m], unit normal pointing to the spheres) each.
        periodic: Periodic flag per axis.
        gravity: Gravitational acceleration [m/s²].
    """

    lower: np.ndarray
    upper: np.ndarray
    planes: list = field(default_factory=list)
    periodic: tuple = (False, False, False)
    gravity: tuple = (0.0, 0.0, -GRAVITY)


@dataclass
class SceneSpec:
    """One drawn scene.

    Attributes:
        id: ``S-I`` (corpus seed, index).
        kind: Geometry kind.
        n: Number of spheres.
        params: The drawn parameters (JSON-able, SI units).
        expected_rest: Whether the scene is expected to come to rest (module docstring).
        duration: Simulated time [s].
        text: The scene file (TOML).
    """

    id: str
    kind: str
    n: int
    params: dict
    expected_rest: bool
    duration: float
    text: str

    def compact(self) -> str:
        """The parameters in one short string."""
        p = self.params
        e = "staged" if p["restitution"] is None else f"e={p['restitution']:.2f}"
        if p["damping"] is not None:
            e += f"+visc(e={p['damped_restitution']:.2f}@{DAMPING_SPEED:g}m/s)"
        fr = {"none": "mu=0", "sliding": f"mu={p['mu']:.2f}",
              "rolling": f"mu={p['mu']:.2f},mur={p['mu_r']:.3f}"}[p["friction"]]
        size = f"r={p['radius'] * 1e3:.2f}mm×{p['ratio']:.2f}{'mix' if p['mixture'] else ''}"
        return (f"{e} {fr} {size} {'+'.join(p['materials'])}/{p['wall']} "
                f"drop={p['drop']:.1f}d {p['geometry']}")


def scene_seed(corpus_seed: int, index: int) -> int:
    """The seed of scene ``index`` of a corpus (independent streams per scene)."""
    return int(np.random.SeedSequence([corpus_seed, index]).generate_state(1)[0])


def _log_uniform(rng, lo: float, hi: float) -> float:
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _mean_cube(lo: float, hi: float) -> float:
    """Mean of r³ [m³] for r uniform in [lo, hi]."""
    return lo**3 if hi == lo else (hi**4 - lo**4) / (4.0 * (hi - lo))


def _draw_spheres(rng, n: int) -> dict:
    """Sizes, materials and fills of ``n`` spheres: fills as (count, material, (r_min, r_max)
    [m]), the mean sphere volume [m³], the largest radius and the mean diameter [m]."""
    r = rng.uniform(*RADIUS_RANGE)
    mixture = bool(rng.random() < MIXTURE_SHARE)
    two = bool(rng.random() < TWO_MATERIALS_SHARE)
    materials = [str(m) for m in rng.choice(SPHERE_MATERIALS, size=2 if two else 1,
                                            replace=False)]
    wall = str(rng.choice(WALL_MATERIALS))
    if mixture:
        ratio = rng.uniform(MIXTURE_RATIO_MIN, RADIUS_RATIO_MAX)
        big = min(n - 1, max(1, round(n * rng.uniform(*MIXTURE_LARGE_SHARE))))
        fills = [(big, materials[0], (ratio * r, ratio * r)),
                 (n - big, materials[-1], (r, r))]
        cube = (big * (ratio * r) ** 3 + (n - big) * r**3) / n
    else:
        ratio = 1.0 if rng.random() < MONODISPERSE_SHARE else rng.uniform(1.0, RADIUS_RATIO_MAX)
        if two:
            first = min(n - 1, max(1, round(n * rng.uniform(*FIRST_MATERIAL_SHARE))))
            fills = [(first, materials[0], (r, ratio * r)), (n - first, materials[1],
                                                             (r, ratio * r))]
        else:
            fills = [(n, materials[0], (r, ratio * r))]
        cube = _mean_cube(r, ratio * r)
    r_max = max(f[2][1] for f in fills)
    mean_r = sum(f[0] * 0.5 * (f[2][0] + f[2][1]) for f in fills) / n
    return dict(n=n, radius=float(r), ratio=float(ratio), mixture=mixture, materials=materials,
                wall=wall, fills=fills, volume=4.0 / 3.0 * math.pi * cube, r_max=float(r_max),
                d_mean=2.0 * mean_r)


def _draw_contact(rng) -> dict:
    """Restitution and friction: e (None: staged model), friction mode, μ_s, μ_r."""
    e = None
    if rng.random() < FIXED_RESTITUTION_SHARE:
        e = float(rng.uniform(*RESTITUTION_RANGE))
    mode = str(rng.choice(list(FRICTION_MODES), p=list(FRICTION_MODES.values())))
    mu = float(rng.uniform(0.0, SLIDING_FRICTION_MAX)) if mode != "none" else 0.0
    mu_r = float(rng.uniform(0.0, ROLLING_FRICTION_MAX)) if mode == "rolling" else 0.0
    return dict(restitution=e, friction=mode, mu=mu, mu_r=mu_r)


def reference_pair_damping(e: float, material, radius: float, speed: float) -> float:
    """The dissipative constant A [s] that gives two spheres of ``material`` and ``radius``
    [m] the viscous restitution factor ``e`` [-] at impact speed ``speed`` [m/s]
    (hsgran.contact.viscous.dissipative_constant_for, docs/model.md §3.11). Not
    hsgran.materials.pair_dissipative_constant, which is a pair's A from its materials'."""
    m_eff = solid_sphere_mass(material.density, radius) / 2.0  # two equal spheres
    return dissipative_constant_for(e, speed, m_eff, radius / 2.0,
                                    effective_modulus(material, material))


def _draw_damping(seed: int, contact: dict, spheres: dict) -> dict:
    """Viscous damping of a staged scene: for DAMPED_SHARE of them, the dissipative
    constant A [s] that gives the reference pair (the first sphere material on itself, both
    of the mean radius) the viscous factor e, drawn uniform in DAMPED_RESTITUTION_RANGE, at
    DAMPING_SPEED; every material of the scene gets this A, so every pair has it (a sphere
    on a wall, whose damping number is 2^(1/5) times smaller, a little less: e = 0.956 for
    0.95). Drawn from ``default_rng([seed, DAMPING_STREAM])``, not the scene's generator,
    so that the other draws stay as they were. Returns ``damping`` (A, or None) and
    ``damped_restitution`` (e, or None)."""
    none = dict(damping=None, damped_restitution=None)
    if contact["restitution"] is not None:
        return none
    rng = np.random.default_rng([seed, DAMPING_STREAM])
    if rng.random() >= DAMPED_SHARE:
        return none
    e = float(rng.uniform(*DAMPED_RESTITUTION_RANGE))
    a = reference_pair_damping(e, BUILTIN_MATERIALS[spheres["materials"][0]],
                               spheres["d_mean"] / 2.0, DAMPING_SPEED)
    return dict(damping=a, damped_restitution=e)


def draw_scene(corpus_seed: int, index: int, *, max_count: int = COUNT_RANGE[1],
               kind: str | None = None, settle_time: float = SETTLE_TIME,
               sid: str | None = None) -> SceneSpec:
    """Draw scene ``index`` of corpus ``corpus_seed`` (module docstring).

    Args:
        corpus_seed, index: Which scene.
        max_count: Largest N: N is log-uniform in [100, max_count] (the other draws do not
            depend on it).
        kind: Force a geometry kind (the kind is drawn anyway, so the other draws stay).
        settle_time: Simulated time after the pour lands [s] (chutes: the smaller of this
            and :data:`CHUTE_FLOW_TIME`).
        sid: The scene's id (default ``S-I``).
    """
    seed = scene_seed(corpus_seed, index)
    rng = np.random.default_rng(seed)
    drawn_kind = str(rng.choice(KINDS))
    kind = drawn_kind if kind is None else kind
    hi = max(COUNT_RANGE[0], min(COUNT_RANGE[1], max_count))
    n = round(_log_uniform(rng, COUNT_RANGE[0], hi))
    spheres = _draw_spheres(rng, n)
    contact = _draw_contact(rng)
    contact.update(_draw_damping(seed, contact, spheres))
    drop = float(rng.uniform(*DROP_RANGE))
    speed = float(rng.uniform(0.0, FILL_SPEED_MAX))
    depth = _log_uniform(rng, *BED_DEPTH_RANGE)
    area = n * spheres["volume"] / (BED_PACKING * depth * spheres["d_mean"])
    build, scale0, geometry = GEOMETRIES[kind](rng, area, spheres)
    need = n * spheres["volume"]
    container, h_bed, z0 = fit_container(build, scale0, need, drop * spheres["d_mean"],
                                         spheres["d_mean"] / 2.0, spheres["r_max"])
    g_down = -container.gravity[2]
    fall = math.sqrt(2.0 * (container.upper[2] - h_bed) / g_down)
    after = min(settle_time, CHUTE_FLOW_TIME) if kind == "chute" else settle_time
    params = dict(kind=kind, **{k: v for k, v in spheres.items() if k != "fills"},
                  **contact, drop=drop, speed=speed, bed_depth=depth, geometry=geometry,
                  fill_counts=[f[0] for f in spheres["fills"]], bed_height=h_bed,
                  fill_bottom=z0, fall_time=fall, scene_seed=seed)
    lossy = contact["restitution"] is not None or contact["damping"] is not None
    expected = contact["friction"] == "rolling" and not any(container.periodic) and lossy
    duration = float(f"{fall + after:.4g}")
    sid = sid or f"{corpus_seed}-{index}"
    text = scene_text(sid, kind, container, spheres, contact, z0, speed, duration,
                      seed % 2**31, params, expected)
    return SceneSpec(sid, kind, n, params, expected, duration, text)


def corpus(corpus_seed: int, count: int, *, first: int = 0,
           max_count: int = COUNT_RANGE[1]) -> list[SceneSpec]:
    """Scenes ``first`` … ``first + count − 1`` of a corpus."""
    return [draw_scene(corpus_seed, i, max_count=max_count) for i in range(first, first + count)]


def rerun(path: Path, outcomes: tuple[str, ...], *, max_count: int) -> list[SceneSpec]:
    """The scenes of an earlier run's CSV (``--out``) that ended with one of ``outcomes``,
    drawn again (``--rerun``): to run what timed out with a larger ``--timeout``. Each is
    drawn from its id with ``max_count``, which must be that run's ``--max-count``: a scene
    whose N differs from the CSV's is refused (ValueError naming it), since it would be
    another scene under the same id."""
    with path.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    if rows and not {"id", "n", "outcome"} <= set(rows[0]):
        raise ValueError(f"--rerun {path}: not a corpus CSV (no id, n and outcome columns)")
    specs = []
    for row in rows:
        if row["outcome"] not in outcomes:
            continue
        m = re.fullmatch(r"(\d+)-(\d+)", row["id"])
        if not m:
            raise ValueError(f"--rerun {path}: id {row['id']!r} is not a corpus scene (S-I)")
        spec = draw_scene(int(m.group(1)), int(m.group(2)), max_count=max_count)
        if str(spec.n) != row["n"]:
            raise ValueError(f"--rerun {path}: scene {row['id']} has N = {spec.n} with "
                             f"--max-count {max_count}, the CSV says {row['n']}: pass the "
                             f"--max-count of that run")
        specs.append(spec)
    return specs


def sample() -> list[SceneSpec]:
    """The fixed sample (:data:`SAMPLE`)."""
    return [draw_scene(s, i, kind=k, max_count=SAMPLE_MAX_COUNT, settle_time=SAMPLE_SETTLE_TIME,
                       sid=f"s-{k}") for s, i, k in SAMPLE]


# ---- geometries: each draws its parameters and returns (build(scale), first scale, label) ----

def _widths(rng, area: float, spheres: dict, aspect_range=ASPECT_RANGE,
            least: float = MIN_WIDTH_DIAMETERS) -> tuple[float, float]:
    """Horizontal sizes (x, y) [m] of a cross-section ``area`` [m²] with a drawn aspect."""
    aspect = rng.uniform(*aspect_range)
    smallest = least * 2.0 * spheres["r_max"]
    wx = max(smallest, math.sqrt(area * aspect))
    return wx, max(smallest, area / wx)


def _first_height(area: float, spheres: dict) -> float:
    """A first box height [m]: the bed and the fill stacked over the cross-section ``area``
    [m²]."""
    return spheres["n"] * spheres["volume"] * (1.0 / BED_PACKING + 1.0 / FILL_PACKING) / area


def _geometry_box(rng, area: float, spheres: dict):
    """A box of cross-section ``area`` [m²]; scale: its height [m]."""
    wx, wy = _widths(rng, area, spheres)

    def build(height):
        return Container(np.zeros(3), np.array([wx, wy, height]))
    return build, _first_height(wx * wy, spheres), f"box {wx * 1e3:.0f}x{wy * 1e3:.0f}mm"


def _on_side(point, normal, side: str, wx: float, wy: float):
    """A plane drawn against the x = 0 wall, moved to ``side`` of a box [0, wx] × [0, wy]."""
    p, v = np.array(point, dtype=float), np.array(normal, dtype=float)
    if side in ("y-", "y+"):
        p[[0, 1]], v[[0, 1]] = p[[1, 0]], v[[1, 0]]
    if side == "x+":
        p[0], v[0] = wx - p[0], -v[0]
    if side == "y+":
        p[1], v[1] = wy - p[1], -v[1]
    return p, v / np.linalg.norm(v)


def _cut(rng, kind: str, across: float, along: float):
    """One extra plane against the x = 0 wall of a box ``across`` wide (x) and ``along`` long
    (y): returns plane(height) -> (point, normal) in that frame, and a label."""
    if kind == "chamfer":
        beta = math.radians(rng.uniform(*CHAMFER_ANGLE_RANGE))
        h = min(rng.uniform(*CHAMFER_HEIGHT_RANGE), CHAMFER_REACH * math.tan(beta)) * across
        n = (math.sin(beta), 0.0, math.cos(beta))
        return (lambda height: ((0.0, 0.0, h), n)), f"chamfer{math.degrees(beta):.0f}"
    if kind == "overhang":
        foot = rng.uniform(*OVERHANG_FOOT_RANGE) * across
        lean = rng.uniform(*OVERHANG_LEAN_RANGE)

        def overhang(height):
            eps = math.atan(lean * (across - foot) / height)  # leans over by lean × floor
            return (foot, 0.0, 0.0), (math.cos(eps), 0.0, -math.sin(eps))
        return overhang, f"overhang{lean:.2f}"
    theta = math.radians(rng.uniform(*SLANT_ANGLE_RANGE))
    lean = 1.0 if rng.random() < 0.5 else -1.0  # which of the two walls gets the acute corner
    mid = rng.uniform(*SLANT_FOOT_RANGE) * across
    dx, dy = lean * math.cos(theta), math.sin(theta)  # the plane's direction in the floor
    point = (mid - 0.5 * along * dx / dy, 0.0, 0.0)  # where it meets the wall y = 0
    n = (dy, -dx, 0.0)
    return (lambda height: (point, n)), f"slant{math.degrees(theta):.0f}"


def _geometry_cut_box(rng, area: float, spheres: dict):
    """A box with 1–3 extra planes on distinct sides (:func:`_cut`); scale: its height [m]."""
    wx, wy = _widths(rng, area, spheres)
    count = int(rng.integers(CUT_PLANES[0], CUT_PLANES[1] + 1))
    sides = [str(s) for s in rng.choice(["x-", "x+", "y-", "y+"], size=count, replace=False)]
    cuts = []
    for side in sides:
        across, along = (wx, wy) if side[0] == "x" else (wy, wx)
        plane, label = _cut(rng, str(rng.choice(CUT_KINDS)), across, along)
        cuts.append((side, plane, f"{label}@{side}"))

    def build(height):
        planes = [_on_side(*plane(height), side, wx, wy) for side, plane, _ in cuts]
        return Container(np.zeros(3), np.array([wx, wy, height]), planes)
    label = f"box {wx * 1e3:.0f}x{wy * 1e3:.0f}mm " + ",".join(c[2] for c in cuts)
    return build, _first_height(wx * wy, spheres), label


def _geometry_wedge(rng, area: float, spheres: dict):
    """A V of two planes along y, apex at the origin, in a box that closes its ends and
    becomes its side walls where the V is wider than the box; scale: the box's height [m]."""
    wx, wy = _widths(rng, area, spheres)
    theta = math.radians(rng.uniform(*WEDGE_ANGLE_RANGE))
    s, c = math.sin(theta), math.cos(theta)
    below = 2.0 * spheres["r_max"]  # the box's floor, below the apex: never touched

    def build(height):
        return Container(np.array([-wx / 2, 0.0, -below]), np.array([wx / 2, wy, height]),
                         [(np.zeros(3), np.array([s, 0.0, c])),
                          (np.zeros(3), np.array([-s, 0.0, c]))])
    return (build, _first_height(wx * wy, spheres),
            f"wedge {math.degrees(theta):.0f}deg {wx * 1e3:.0f}x{wy * 1e3:.0f}mm")


def _geometry_incline(rng, area: float, spheres: dict):
    """A floor tilted along x, descending to the box's end wall x = 0; scale: the box's
    height [m]."""
    lx, ly = _widths(rng, area, spheres, INCLINE_ASPECT_RANGE)
    beta = math.radians(rng.uniform(*INCLINE_ANGLE_RANGE))
    # the tilted floor rises from the end wall x = 0, above the box's floor (never touched)
    foot = np.array([0.0, 0.0, 2.0 * spheres["r_max"]])
    normal = np.array([-math.sin(beta), 0.0, math.cos(beta)])

    def build(height):
        return Container(np.zeros(3), np.array([lx, ly, height]), [(foot, normal)])
    first = _first_height(lx * ly, spheres) + lx * math.tan(beta)
    return build, first, f"incline {math.degrees(beta):.0f}deg {lx * 1e3:.0f}x{ly * 1e3:.0f}mm"


def _geometry_polygon(rng, area: float, spheres: dict):
    """A horizontal polygonal cylinder along y, its ends closed by the box; scale: the
    polygon's apothem [m] (the length follows a drawn length over diameter)."""
    sides = int(rng.integers(POLYGON_SIDES[0], POLYGON_SIDES[1] + 1))
    flat = bool(rng.random() < 0.5)  # a face at the bottom, else a vertex
    aspect = rng.uniform(*POLYGON_ASPECT_RANGE)
    phi0 = -math.pi / 2 + (0.0 if flat else math.pi / sides)
    least = MIN_WIDTH_DIAMETERS * 2.0 * spheres["r_max"]

    def build(apothem):
        # the box's faces a diameter beyond the polygon's corners: never touched
        outer = apothem / math.cos(math.pi / sides) + 2.0 * spheres["r_max"]
        length = max(least, 2.0 * aspect * apothem)
        planes = []
        for k in range(sides):
            phi = phi0 + 2.0 * math.pi * k / sides
            u = np.array([math.cos(phi), 0.0, math.sin(phi)])
            planes.append((apothem * u, -u))
        return Container(np.array([-outer, 0.0, -outer]), np.array([outer, length, outer]),
                         planes)
    need = spheres["n"] * spheres["volume"] * (1.0 / BED_PACKING + 1.0 / FILL_PACKING)
    first = (need / (2.0 * math.pi * aspect)) ** (1.0 / 3.0)
    return build, first, f"polygon{sides}{'flat' if flat else 'vertex'} L/D={aspect:.2f}"


def _geometry_chute(rng, area: float, spheres: dict):
    """A box periodic in x and y with gravity tilted along x; scale: its height [m]."""
    lx, ly = _widths(rng, area, spheres, least=MIN_PERIODIC_DIAMETERS)
    alpha = math.radians(rng.uniform(*CHUTE_ANGLE_RANGE))
    gravity = (GRAVITY * math.sin(alpha), 0.0, -GRAVITY * math.cos(alpha))

    def build(height):
        return Container(np.zeros(3), np.array([lx, ly, height]), [], (True, True, False),
                         gravity)
    return (build, _first_height(lx * ly, spheres),
            f"chute {math.degrees(alpha):.0f}deg {lx * 1e3:.0f}x{ly * 1e3:.0f}mm")


#: Geometry kind → its drawing function (rng, cross-section area [m²], spheres) ->
#: (build(scale) -> Container, first scale [m], label).
GEOMETRIES = {"box": _geometry_box, "cut_box": _geometry_cut_box, "wedge": _geometry_wedge,
              "incline": _geometry_incline, "polygon": _geometry_polygon,
              "chute": _geometry_chute}


def _voxels(c: Container):
    """Centres (M, 3) [m] of a regular grid over the box and the volume of one cell [m³]."""
    size = c.upper - c.lower
    h = (float(np.prod(size)) / VOXELS) ** (1.0 / 3.0)
    counts = np.maximum(4, np.ceil(size / h)).astype(int)
    axes = [c.lower[i] + (np.arange(counts[i]) + 0.5) * size[i] / counts[i] for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return grid, float(np.prod(size / counts))


def _clearance(points: np.ndarray, c: Container) -> np.ndarray:
    """Distance [m] of points (M, 3) from the nearest wall: extra planes and box faces on
    non-periodic axes (inf without any)."""
    d = np.full(points.shape[0], np.inf)
    for point, normal in c.planes:
        d = np.minimum(d, (points - point) @ normal)
    for i in range(3):
        if not c.periodic[i]:
            d = np.minimum(d, np.minimum(points[:, i] - c.lower[i], c.upper[i] - points[:, i]))
    return d


def fit_container(build, scale: float, volume: float, drop: float, r_mean: float,
                  r_max: float):
    """Grow a container until the bed and the pour fit in it.

    Args:
        build: scale [m] -> :class:`Container`.
        scale: First scale [m].
        volume: Volume of all spheres [m³].
        drop: Pour height above the bed surface [m].
        r_mean: Mean radius [m].
        r_max: Largest radius [m] (the fill region is at least
            :data:`FILL_MIN_HEIGHT_DIAMETERS` largest diameters tall).

    Returns:
        (container, bed surface height [m], bottom of the fill region [m]): the bed surface
        is the height below which the container holds ``volume / BED_PACKING``; the fill
        region (the box's x and y range, from the bed surface plus ``drop`` to the top) leaves
        its spheres' centres (at least ``r_mean`` from every plane and region face) room for a
        packing fraction of at most :data:`FILL_PACKING`.

    Raises:
        RuntimeError: nothing fits after :data:`SIZE_STEPS` steps (a bug in a geometry).
    """
    for _ in range(SIZE_STEPS):
        c = build(scale)
        points, cell = _voxels(c)
        room = _clearance(points, c)
        z = np.sort(points[room >= 0.0, 2])
        k = math.ceil(volume / BED_PACKING / cell)
        if k < z.size:
            h_bed = float(z[k])
            z0 = h_bed + drop
            centres = (room >= r_mean) & (points[:, 2] >= z0 + r_mean)
            if (c.upper[2] - z0 >= FILL_MIN_HEIGHT_DIAMETERS * 2.0 * r_max
                    and np.count_nonzero(centres) * cell * FILL_PACKING >= volume):
                return c, h_bed, z0
        scale *= SIZE_GROWTH
    raise RuntimeError(f"no container fits {volume:.3g} m³ of spheres")


# ---- the scene file ------------------------------------------------------------------------------

def _num(x: float) -> str:
    """A TOML float, 9 significant digits."""
    return repr(float(f"{float(x):.9g}"))


def _vec(v) -> str:
    return "[" + ", ".join(_num(x) for x in v) + "]"


def scene_text(sid: str, kind: str, c: Container, spheres: dict, contact: dict, z0: float,
               speed: float, duration: float, seed: int, params: dict, expected: bool) -> str:
    """The TOML scene file of a drawn scene (hsgran.scene's format)."""
    effects = ["gravity"]
    if contact["friction"] != "none":
        effects += ["rotation", "friction"]
    if contact["friction"] == "rolling":
        effects.append("rolling_resistance")
    if contact["restitution"] is None:
        effects.append("plasticity")
    if contact["damping"] is not None:
        effects.append("viscoelastic_damping")
    keys = ("n", "restitution", "damping", "friction", "mu", "mu_r", "radius", "ratio",
            "mixture", "drop", "speed", "geometry")
    compact = {k: params[k] for k in keys if k != "damping" or params[k] is not None}
    lines = [f"# robustness corpus scene {sid} (tools/robustness.py), kind {kind}",
             f"# expected to come to rest: {'yes' if expected else 'no'}",
             f"# parameters: {json.dumps(compact)}",
             "[scene]", f'name = "robustness {sid} {kind}"', f"duration = {_num(duration)}",
             f"gravity = {_vec(c.gravity)}", f"effects = {json.dumps(effects)}",
             f"seed = {seed}"]
    if any(c.periodic):
        lines.append(f"periodic = {json.dumps(list(c.periodic))}")
    lines += ["[output]", f"frame_interval = {_num(FRAME_INTERVAL)}"]
    names = list(dict.fromkeys(spheres["materials"] + [spheres["wall"]]))
    if contact["damping"] is not None:  # the built-in materials, with the drawn A
        for name in names:
            m = replace(BUILTIN_MATERIALS[name],
                        dissipative_constant=contact["damping"])
            lines.append(f"[materials.{name}]")
            lines += [f"{key} = {_num(getattr(m, key))}" for key in MATERIAL_KEYS]
    for i, a in enumerate(names):
        for b in names[i:]:
            lines += ["[[contacts]]", f'between = ["{a}", "{b}"]']
            if contact["restitution"] is not None:
                lines.append(f"restitution = {_num(contact['restitution'])}")
            if contact["friction"] != "none":
                lines.append(f"sliding_friction = {_num(contact['mu'])}")
            if contact["friction"] == "rolling":
                lines.append(f"rolling_friction = {_num(contact['mu_r'])}")
    lines += ["[[walls]]", 'kind = "box"', f"lower = {_vec(c.lower)}",
              f"upper = {_vec(c.upper)}", f'material = "{spheres["wall"]}"']
    for point, normal in c.planes:
        lines += ["[[walls]]", 'kind = "plane"', f"point = {_vec(point)}",
                  f"normal = {_vec(normal)}", f'material = "{spheres["wall"]}"']
    lower = [c.lower[0], c.lower[1], z0]
    for count, material, (r_lo, r_hi) in spheres["fills"]:
        radius = _num(r_lo) if r_lo == r_hi else f"[{_num(r_lo)}, {_num(r_hi)}]"
        lines += ["[[fill]]", f"count = {count}", f'material = "{material}"',
                  f"radius = {radius}",
                  f"region = {{ lower = {_vec(lower)}, upper = {_vec(c.upper)} }}",
                  f"speed = {_num(speed)}"]
    return "\n".join(lines) + "\n"


# ---- measuring ---------------------------------------------------------------------------------

def space_of(scene) -> Space:
    """The planes and periodic box of a scene, as hsgran.placement sees them."""
    origin = np.zeros(3) if scene.box_lower is None else scene.box_lower
    period = np.zeros(3) if scene.box_lower is None else np.where(
        scene.periodic, scene.box_upper - scene.box_lower, 0.0)
    return Space(plane_point=np.array([p.point for p in scene.planes]).reshape(-1, 3),
                 plane_normal=np.array([p.normal for p in scene.planes]).reshape(-1, 3),
                 origin=origin, period=period)


def plane_distances(position: np.ndarray, space: Space) -> np.ndarray:
    """Signed distance [m] of every centre (N, 3) from every plane, shape (N, P)."""
    return position @ space.plane_normal.T - np.einsum("pk,pk->p", space.plane_point,
                                                        space.plane_normal)


def worst_overlap(position: np.ndarray, radius: np.ndarray, space: Space) -> tuple[float, float]:
    """Largest overlaps of one configuration.

    Args:
        position: Centres [m], (N, 3).
        radius: Radii [m], (N,).
        space: Planes and periodic box (:func:`space_of`).

    Returns:
        (largest (σ − d)/σ over pairs at centre distance d below the sum of radii σ, largest
        (R − h)/R over spheres at distance h from a plane) [-], 0 where nothing overlaps
        (pairs within hsgran.placement.CONTACT_TOLERANCE of touching count as touching).
    """
    pairs, dist = overlapping_pairs(position, radius, space)
    pair = 0.0
    if dist.size:
        sigma = radius[pairs[:, 0]] + radius[pairs[:, 1]]
        pair = float(np.max((sigma - dist) / sigma))
    plane = 0.0
    if space.plane_normal.shape[0]:
        h = plane_distances(position, space)
        plane = max(0.0, float(np.max((radius[:, None] - h) / radius[:, None])))
    return pair, plane


def bed_mask(position: np.ndarray, radius: np.ndarray, space: Space,
             slack: float = TOUCH_SLACK) -> np.ndarray:
    """The bed: spheres connected to a plane through contacts (gaps within ``slack`` of the
    contact distance), shape (N,) bool."""
    n = radius.shape[0]
    pairs, _ = overlapping_pairs(position, radius * (1.0 + slack), space)
    graph = coo_matrix((np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    on_plane = np.zeros(n, dtype=bool)
    if space.plane_normal.shape[0]:
        on_plane = np.any(plane_distances(position, space) <= (radius * (1.0 + slack))[:, None],
                          axis=1)
    grounded = np.zeros(label.max() + 1, dtype=bool)
    grounded[label[on_plane]] = True
    return grounded[label]


def _wrapped(position: np.ndarray, space: Space) -> np.ndarray:
    """Centres moved into the periodic box along periodic axes."""
    x = position.copy()
    per = space.periodic
    if np.any(per):
        x[:, per] = space.origin[per] + np.mod(x[:, per] - space.origin[per], space.period[per])
    return x


def _with_images(x: np.ndarray, radius: np.ndarray, space: Space, margin: float):
    """Centres (wrapped) plus their periodic images within ``margin`` of the box, and radii."""
    for i in np.flatnonzero(space.periodic):
        lo, length = space.origin[i], space.period[i]
        near_lo = x[:, i] < lo + margin
        near_hi = x[:, i] >= lo + length - margin
        shifted = [x[near_lo] + np.eye(3)[i] * length, x[near_hi] - np.eye(3)[i] * length]
        radius = np.concatenate([radius, radius[near_lo], radius[near_hi]])
        x = np.concatenate([x, *shifted])
    return x, radius


def bulk_packing_fraction(position: np.ndarray, radius: np.ndarray, space: Space,
                          bed: np.ndarray | None = None, probes: int = PROBES,
                          seed: int = PROBE_SEED) -> tuple[float, int]:
    """Packing fraction of a bed away from its walls and its surface (module docstring).

    Random probe points fill the bed's bounding box (the periodic box along periodic axes);
    a probe is measured when it lies at least :data:`WALL_CLEARANCE_DIAMETERS` mean
    diameters from every plane and :data:`SURFACE_DEPTH_DIAMETERS` below the surface of its
    column (up = +z: gravity points down, or along the floor's normal in chutes); the result
    is the share of measured probes inside a sphere.

    Args:
        position: Centres [m], (N, 3).
        radius: Radii [m], (N,).
        space: Planes and periodic box (:func:`space_of`).
        bed: Which spheres form the bed (default :func:`bed_mask`).
        probes: Probe points drawn.
        seed: Seed of the probe points.

    Returns:
        (packing fraction [-], or NaN when fewer than :data:`MIN_PROBES` probes are measured
        or they span less than :data:`MIN_REGION_SPHERES` mean sphere volumes; number of
        probes measured).
    """
    bed = bed_mask(position, radius, space) if bed is None else bed
    if not bed.any():
        return math.nan, 0
    d = 2.0 * float(radius.mean())
    reach = float(radius.max())
    x = _wrapped(position, space)
    lo = np.where(space.periodic, space.origin, x[bed].min(axis=0) - reach)
    hi = np.where(space.periodic, space.origin + space.period, x[bed].max(axis=0) + reach)
    width = COLUMN_DIAMETERS * d
    ncol = np.maximum(1, np.ceil((hi[:2] - lo[:2]) / width)).astype(int)

    def column(points):
        c = np.clip(((points[:, :2] - lo[:2]) // width).astype(int), 0, ncol - 1)
        return c[:, 0] * ncol[1] + c[:, 1]
    surface = np.full(int(np.prod(ncol)), -np.inf)
    np.maximum.at(surface, column(x[bed]), x[bed, 2] + radius[bed])
    p = lo + (hi - lo) * np.random.default_rng(seed).random((probes, 3))
    keep = p[:, 2] <= surface[column(p)] - SURFACE_DEPTH_DIAMETERS * d
    if space.plane_normal.shape[0]:
        keep &= np.all(plane_distances(p, space) >= WALL_CLEARANCE_DIAMETERS * d, axis=1)
    p = p[keep]
    region = float(np.prod(hi - lo)) * p.shape[0] / probes
    if p.shape[0] < MIN_PROBES or region < MIN_REGION_SPHERES * float(np.mean(
            4.0 / 3.0 * math.pi * radius**3)):
        return math.nan, int(p.shape[0])
    centres, radii = _with_images(x, radius, space, reach)
    k = min(PROBE_NEIGHBOURS, centres.shape[0])
    dist, idx = cKDTree(centres).query(p, k=k, distance_upper_bound=reach)
    dist, idx = dist.reshape(p.shape[0], k), idx.reshape(p.shape[0], k)
    valid = idx < centres.shape[0]
    inside = valid & (dist < np.where(valid, radii[np.minimum(idx, centres.shape[0] - 1)], 0.0))
    return float(np.mean(inside.any(axis=1))), int(p.shape[0])


def time_to_rest(times, max_speed) -> float | None:
    """First frame time [s] after which the largest speed of every frame stays below
    :data:`REST_SPEED`; None when the last frame is not below it."""
    fast = np.flatnonzero(np.asarray(max_speed) >= REST_SPEED)
    if len(times) == 0 or (fast.size and fast[-1] == len(times) - 1):
        return None
    return float(times[fast[-1] + 1] if fast.size else times[0])


def classify(exc: BaseException) -> tuple[str, str, float | None]:
    """(outcome, message, guard time [s] or None) of an exception that ended a run: the
    collapse guard's SimulationError is ``guard``, anything else ``error``."""
    message = f"{type(exc).__name__}: {exc}"
    if type(exc).__name__ == "SimulationError" and GUARD_TEXT in str(exc):
        found = re.search(r"at t = (\S+) s", str(exc))
        return "guard", str(exc), float(found.group(1)) if found else None
    return "error", message, None


class Probe:
    """Observer of a run: overlaps and largest speed of every frame, arrivals from the event
    log, and the last frame (for the bed's packing fraction).

    Args:
        scene: The scene run.
        emit: Called with a progress dict at most every :data:`PROGRESS_WALL` seconds.
    """

    def __init__(self, scene, emit=None):
        self.space = space_of(scene)
        self.radius = scene.radius
        # the planes spheres can rest on (normal with a component against gravity): side
        # walls, lids and overhangs are met in flight, not arrived at
        self.floor = self.space.plane_normal @ -scene.gravity > 0.0
        self.times: list[float] = []
        self.max_speed: list[float] = []
        self.pair_overlap = 0.0
        self.plane_overlap = 0.0
        self.arrival = np.full(scene.n, np.nan)
        self.last = None
        self.sim = None
        self.emit = emit
        self.start = self.wall = time.perf_counter()

    def on_frames(self, block) -> None:
        for f in range(block.time.shape[0]):
            pos = block.position[f]
            pair, plane = worst_overlap(pos, self.radius, self.space)
            self.pair_overlap = max(self.pair_overlap, pair)
            self.plane_overlap = max(self.plane_overlap, plane)
            self.times.append(float(block.time[f]))
            self.max_speed.append(float(np.sqrt(np.max(np.sum(block.velocity[f] ** 2, axis=1)))))
            self.last = (pos.copy(), block.motion_state[f].copy())

    def on_events(self, block) -> None:
        if not np.isnan(self.arrival).any():
            return
        touch = np.isin(block.kind, (EV_PAIR, EV_WALL, EV_LAND))
        t, i, j = block.time[touch], block.i[touch], block.j[touch]
        waiting = np.isnan(self.arrival)
        rows = np.flatnonzero(waiting[i] | ((j >= 0) & waiting[np.maximum(j, 0)]))
        for k in rows:  # in time order: the bed grows from the planes
            a, b = int(i[k]), int(j[k])
            here = self.floor[-1 - b] if b < 0 else not np.isnan(self.arrival[b])
            if here and np.isnan(self.arrival[a]):
                self.arrival[a] = t[k]
            elif b >= 0 and np.isnan(self.arrival[b]) and not np.isnan(self.arrival[a]):
                self.arrival[b] = t[k]

    def tick(self) -> bool:
        """The run's ``stop`` callback: emits progress, never stops the run."""
        if self.emit is not None and time.perf_counter() - self.wall >= PROGRESS_WALL:
            self.wall = time.perf_counter()
            self.emit({"progress": self.partial()})
        return False

    def partial(self) -> dict:
        """What is known so far: time reached, CPU time, counts, worst overlaps."""
        out = {"t_reached": None, "cpu": _cpu_time(), "wall": time.perf_counter() - self.start,
               "pair_overlap": self.pair_overlap, "plane_overlap": self.plane_overlap}
        if self.sim is not None:
            out["t_reached"] = self.sim.time
            counts = zip(EVENT_NAMES, self.sim.counts, strict=True)
            out["events"] = {k: int(v) for k, v in counts if k != "none"}
            out.update(self.sim.solver_counts())
        return out


def _cpu_time() -> float:
    use = resource.getrusage(resource.RUSAGE_SELF)
    return use.ru_utime + use.ru_stime


def run_scene_text(text: str, emit=None) -> dict:
    """Run one scene file's text to its duration and measure it (module docstring).

    Args:
        text: The TOML scene.
        emit: Called with progress dicts while it runs (see :class:`Probe`).

    Returns:
        A result dict: outcome, message, t_reached [s], cpu [s], events by kind, pair_overlap
        and plane_overlap [-], time_to_rest [s], last_arrival [s], not_arrived, at_rest,
        bulk_packing [-], probes, dissipated and collision_loss [J], solver_sweeps,
        solver_visits and solver_frozen.
    """
    from hsgran.engine import Simulation, SimulationError  # the child's import, not the parent's
    from hsgran.onplane import MS_ASLEEP, MS_REST
    from hsgran.scene import parse_scene

    scene = parse_scene(text)
    sim = Simulation(scene, frame_buffer=1, log_events=True)
    probe = Probe(scene, emit)
    probe.sim = sim
    outcome, message, guard_time = "completed", "", None
    try:
        sim.run(observers=[probe], stop=probe.tick)
    except SimulationError as exc:
        outcome, message, guard_time = classify(exc)
        found = re.match(r"sphere (\d+) ", str(exc))
        if outcome == "guard" and found:
            message += "; " + guard_context(sim, probe.space, int(found.group(1)))
    result = probe.partial()
    result.update(outcome=outcome, message=message, guard_time=guard_time,
                  time_to_rest=time_to_rest(probe.times, probe.max_speed),
                  dissipated=float(sim.dissipated_energy()), collision_loss=sim.collision_loss)
    arrived = ~np.isnan(probe.arrival)
    result["not_arrived"] = int(np.count_nonzero(~arrived))
    result["last_arrival"] = float(np.max(probe.arrival)) if arrived.all() else None
    result["at_rest"] = result["bulk_packing"] = None
    result["probes"] = 0
    if probe.last is not None:
        pos, state = probe.last
        result["at_rest"] = int(np.count_nonzero((state == MS_REST) | (state == MS_ASLEEP)))
        phi, count = bulk_packing_fraction(pos, scene.radius, probe.space)
        result["bulk_packing"] = None if math.isnan(phi) else phi
        result["probes"] = count
    result["movers"] = result["rolling_alone"] = result["stops_by"] = None
    if outcome == "completed":
        result["movers"], result["rolling_alone"], result["stops_by"] = rolling_out(
            sim, probe.space, max(sim.time, scene.duration))
    return result


def _touching(pos, radius, sphere: int, space: Space):
    """Which spheres touch ``sphere`` within :data:`TOUCH_SLACK` (boolean mask, itself False),
    across periodic axes."""
    delta = pos - pos[sphere]
    per = space.periodic
    delta[:, per] -= space.period[per] * np.round(delta[:, per] / space.period[per])
    near = np.linalg.norm(delta, axis=1) <= (radius + radius[sphere]) * (1.0 + TOUCH_SLACK)
    near[sphere] = False
    return near


def rolling_out(sim, space: Space, t: float) -> tuple[int, int, float | None]:
    """The spheres still moving at time ``t`` [s] (≥ the last event; speed ≥
    :data:`REST_SPEED`), and which of them roll alone on a plane to a stop the engine has
    scheduled: motion state rolling, its segment ending where the speed vanishes
    (``END_STOP``), touching no other sphere (:func:`_touching`). Such a sphere decelerates
    at the closed-form (5/7) μ_r g of docs/model.md §5.3, whatever the scene around it: one
    still rolling at 3.1 mm/s on the floor (μ_r = 7e-4) at the end of corpus 0-15 (at N ≤
    3000), 1 s after the last arrival, stops 0.62 s later, moving as the model says.
    Returns (movers, of them rolling alone, the latest of their scheduled stops [s] or
    None)."""
    from hsgran.onplane import END_STOP, MS_ROLLING

    pos, vel = sim.state_at(t)
    speed = np.linalg.norm(vel, axis=1)
    movers = np.flatnonzero(speed >= REST_SPEED)
    alone, latest = 0, None
    if not sim.scene.effects.gravity:  # (no motion on planes)
        return len(movers), alone, latest
    for k in movers:
        if (sim.mstate[k] == MS_ROLLING and sim.seg_code[k] == END_STOP
                and not _touching(pos, sim.scene.radius, int(k), space).any()):
            alone += 1
            latest = max(latest or 0.0, float(sim.seg_end[k]))
    return len(movers), alone, latest


def guard_context(sim, space: Space, sphere: int) -> str:
    """Where the collapse guard stopped a run: the sphere's motion state and what it touches
    (within :data:`TOUCH_SLACK`) at the time of the last event."""
    from hsgran.onplane import MOTION_STATE_NAMES

    pos, _ = sim.state_at(sim.time)
    radius = sim.scene.radius
    near = _touching(pos, radius, sphere, space)
    planes = [sim.scene.planes[w].key for w in np.flatnonzero(
        plane_distances(pos[sphere:sphere + 1], space)[0] <= radius[sphere] * (1 + TOUCH_SLACK))]
    states = [MOTION_STATE_NAMES[sim.mstate[k]] for k in np.flatnonzero(near)]
    return (f"sphere {sphere} ({MOTION_STATE_NAMES[sim.mstate[sphere]]}) touches "
            f"{len(states)} spheres ({', '.join(states) or '-'}) and planes "
            f"{', '.join(planes) or '-'}")


def _child_main(path: str) -> int:
    """``--run-scene FILE``: run one scene, print JSON lines (progress, then the result)."""
    def emit(obj):
        print(json.dumps(obj), flush=True)
    try:
        result = run_scene_text(Path(path).read_text(), emit)
    except Exception as exc:  # a crash of the scene is its outcome, reported, not ours
        outcome, message, _ = classify(exc)
        result = {"outcome": outcome, "message": message, "cpu": _cpu_time()}
    emit({"result": result})
    return 0


# ---- running a corpus ----------------------------------------------------------------------------

#: Each scene's process runs its linear algebra on one thread (the dense finish of the cluster
#: solves, hsgran.contact.cluster.refine_normals, calls OpenBLAS: np.linalg.lstsq until
#: 2026-12-04, the products of its NNLS's QR updates since): the corpus runs ``--jobs``
#: scenes at once, one per core, and OpenBLAS's own threads made each scene's process take two
#: cores where the finish ran (corpus 0-79 on 2 cores, 2026-12-03: 49 s of CPU in 26.6 s of
#: wall where one thread takes 20.4 s in 20.6 s), so that CPU times counted the waiting and
#: scenes run side by side slowed each other. (The thread count can also change the last bits
#: of the finish's solutions, and so the trajectory.) A value the caller's environment sets is
#: kept.
CHILD_THREADS = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def run_child(spec: SceneSpec, path: Path, timeout: float) -> dict:
    """Run one scene (already written to ``path``) in a process of its own, killed after
    ``timeout`` seconds [s] of wall time; returns the report row."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    for name, value in CHILD_THREADS.items():
        env.setdefault(name, value)
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--run-scene",
                             str(path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, cwd=str(ROOT))
    timed_out = False
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        timed_out = True
        proc.kill()  # the scene's own process, started above
        out, err = proc.communicate()
    wall = time.perf_counter() - t0
    result, progress = None, []
    for line in out.splitlines():
        try:
            obj = json.loads(line)
        except json.JSONDecodeError:
            continue
        result = obj.get("result", result)
        if "progress" in obj:
            progress.append(obj["progress"])
    if result is None:
        result = dict(progress[-1]) if progress else {}
        result["outcome"] = "timeout" if timed_out else "error"
        result["message"] = (f"no result after {timeout:g} s of wall time{_pace(progress)}"
                             if timed_out else f"exit code {proc.returncode}: "
                             + (err.strip().splitlines() or [""])[-1])
    return make_row(spec, result, wall)


def _pace(progress: list[dict]) -> str:
    """How fast the simulated time still advanced over the last :data:`PACE_WALL` seconds of
    progress lines (tells a slow run from a stalled one)."""
    if len(progress) < 2 or progress[-1].get("t_reached") is None:
        return ""
    last = progress[-1]
    first = next((p for p in progress if p["wall"] >= last["wall"] - PACE_WALL), progress[0])
    if first is last:
        first = progress[-2]
    rate = (last["t_reached"] - first["t_reached"]) / (last["wall"] - first["wall"])
    return (f"; simulated time advanced {rate:.3g} s per wall second over the last "
            f"{last['wall'] - first['wall']:.0f} s")


def make_row(spec: SceneSpec, result: dict, wall: float) -> dict:
    """One report row: the scene's parameters and its result, flat (CSV-able)."""
    events = result.get("events") or {}
    motion = sum(events.get(k, 0) for k in MOTION_EVENTS)
    row = {"id": spec.id, "kind": spec.kind, "n": spec.n, "params": spec.compact(),
           "expected_rest": spec.expected_rest, "duration": spec.duration,
           "outcome": result["outcome"], "message": result.get("message", ""),
           "t_reached": result.get("t_reached"), "guard_time": result.get("guard_time"),
           "wall": wall, "cpu": result.get("cpu"),
           "events_per_particle": motion / spec.n,
           "pair_overlap": result.get("pair_overlap"),
           "plane_overlap": result.get("plane_overlap"),
           "time_to_rest": result.get("time_to_rest"),
           "last_arrival": result.get("last_arrival"),
           "not_arrived": result.get("not_arrived"), "at_rest": result.get("at_rest"),
           "bulk_packing": result.get("bulk_packing"), "probes": result.get("probes"),
           "movers": result.get("movers"), "rolling_alone": result.get("rolling_alone"),
           "stops_by": result.get("stops_by"),
           "dissipated": result.get("dissipated"),
           "collision_loss": result.get("collision_loss"),
           **{k: result.get(k) for k in SOLVER_COUNTS}}
    for name in EVENT_NAMES[1:]:
        row[f"ev_{name}"] = events.get(name)
    return row


def run_corpus(specs: list[SceneSpec], *, jobs: int = DEFAULT_JOBS,
               timeout: float = DEFAULT_TIMEOUT, scene_dir: Path | None = None,
               report=print) -> list[dict]:
    """Run scenes ``jobs`` at a time, each in its own process; rows in the order of ``specs``.
    ``report(line)`` is called as each scene ends. The loops with gravity are compiled first
    (seconds when the on-disk cache has them; tens of minutes on 2 cores when it has not,
    reported as ``# compiled ...`` lines), so that no scene's timeout is spent compiling;
    the version for large systems only where a scene is one (LARGE_FROM spheres)."""
    if not jit_disabled():
        names = ["gravity"] + (["gravity-large"] if specs and max(s.n for s in specs)
                               >= LARGE_FROM else [])
        report(f"# compiling the event loop with gravity: {', '.join(names)} "
               "(seconds when cached)")
        compile_all(names, jobs=jobs, report=lambda line: report(f"# compiled {line}"))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(scene_dir or tmp)
        folder.mkdir(parents=True, exist_ok=True)
        for spec in specs:
            (folder / f"{spec.id}.toml").write_text(spec.text)
        rows = {}
        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            futures = {pool.submit(run_child, spec, folder / f"{spec.id}.toml", timeout): spec
                       for spec in specs}
            for future in as_completed(futures):
                row = future.result()
                rows[row["id"]] = row
                report(format_row(row))
    return [rows[spec.id] for spec in specs]


# ---- reporting ---------------------------------------------------------------------------------

def _g(x, fmt: str) -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, fmt)


def format_row(row: dict) -> str:
    """One line of the table."""
    ended = row["outcome"]
    if ended == "guard":
        ended = f"guard@{_g(row['guard_time'], '.4g')}"
    elif ended == "timeout":
        ended = f"timeout@{_g(row['t_reached'], '.4g')}"
    worst = max(row["pair_overlap"] or 0.0, row["plane_overlap"] or 0.0)
    return (f"{row['id']:>9} {row['kind']:>8} {row['n']:>5} {ended:>15} "
            f"{_g(row['t_reached'], '.3f'):>6}/{row['duration']:<6.3f} "
            f"{row['wall']:>7.1f} {_g(row['events_per_particle'], '.3g'):>8} "
            f"{_g(row['ev_wedge'], 'd'):>6} {worst:>9.2e} {_g(row['time_to_rest'], '.3f'):>6} "
            f"{_g(row['last_arrival'], '.3f'):>6} {_g(row['bulk_packing'], '.3f'):>6} "
            f"{'yes' if row['expected_rest'] else 'no':>4}  {row['params']}")


HEADER = (f"{'id':>9} {'kind':>8} {'N':>5} {'outcome':>15} {'t [s]/end':>13} "
          f"{'wall[s]':>7} {'ev/part':>8} {'wedge':>6} {'overlap':>9} {'rest':>6} "
          f"{'arrive':>6} {'phi':>6} {'exp':>4}  parameters")


def summary(rows: list[dict]) -> list[str]:
    """The message of every scene that did not complete, outcomes by kind and the summary
    line."""
    lines = [f"{r['id']:>9} {r['kind']:>8} {r['outcome']}: {r['message']}" for r in rows
             if r["outcome"] != "completed"]
    lines.append(f"{'kind':>8} " + " ".join(f"{o:>9}" for o in OUTCOMES))
    for kind in KINDS:
        mine = [r for r in rows if r["kind"] == kind]
        if mine:
            lines.append(f"{kind:>8} " + " ".join(
                f"{sum(r['outcome'] == o for r in mine):>9}" for o in OUTCOMES))
    count = {o: sum(r["outcome"] == o for r in rows) for o in OUTCOMES}
    worst, where = 0.0, "-"
    for r in rows:
        w = max(r["pair_overlap"] or 0.0, r["plane_overlap"] or 0.0)
        if w > worst:
            worst, where = w, r["id"]
    expected = [r for r in rows if r["expected_rest"]]
    settled = sum(r["outcome"] == "completed" and r["time_to_rest"] is not None
                  for r in expected)
    share = 100.0 * count["completed"] / len(rows) if rows else 0.0
    rate = f"{settled}/{len(expected)}" + (f" ({100.0 * settled / len(expected):.0f}%)"
                                            if expected else "")
    lines.append(f"scenes {len(rows)}, completed {count['completed']} ({share:.0f}%), guard "
                 f"{count['guard']}, timeout {count['timeout']}, error {count['error']}; "
                 f"worst overlap {worst:.3g} ({where}); at rest among the scenes expected to "
                 f"rest {rate}")
    rolling = [r for r in expected if r["outcome"] == "completed" and r["time_to_rest"] is None
               and r.get("movers") and r.get("rolling_alone") == r.get("movers")]
    if rolling:
        lines.append(
            f"of the others, {len(rolling)} end with nothing moving but spheres rolling alone "
            "on a plane to a stop the engine has scheduled (rolling_out): "
            + ", ".join(f"{r['id']} ({_g(r['movers'], 'd')} spheres, stopped by "
                        f"{float(r['stops_by']):.3f} s)" for r in rolling))
    return lines


def write_rows(rows: list[dict], path: Path) -> None:
    """Rows as CSV (``.csv``) or JSON (any other suffix)."""
    if path.suffix.lower() == ".csv":
        with path.open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]) if rows else ["id"])
            writer.writeheader()
            writer.writerows(rows)
    else:
        path.write_text(json.dumps(rows, indent=1))


def with_treatment(spec: SceneSpec, treatment: str) -> SceneSpec:
    """The scene with its enduring contact treated as ``treatment`` (hsgran.scene.TREATMENTS)."""
    return replace(spec, text=spec.text + f'\n[enduring_contact]\ntreatment = '
                               f'"{treatment}"\n')


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=40, help="scenes of the corpus")
    ap.add_argument("--corpus-seed", type=int, default=0)
    ap.add_argument("--first", type=int, default=0, help="index of the first scene")
    ap.add_argument("--max-count", type=int, default=COUNT_RANGE[1], help="largest N")
    ap.add_argument("--sample", action="store_true", help="the fixed small sample instead")
    ap.add_argument("--jobs", type=int, default=DEFAULT_JOBS, help="scenes run at once")
    ap.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT,
                    help="wall-time limit of one scene [s]")
    ap.add_argument("--out", type=Path, help="rows as CSV (.csv) or JSON")
    ap.add_argument("--write-scenes", type=Path, metavar="DIR", help="save the scene files")
    ap.add_argument("--dry-run", action="store_true", help="draw and list, do not run")
    ap.add_argument("--treatment", choices=TREATMENTS, default="pairwise",
                    help="[enduring_contact] treatment of every scene (docs/enduring-contact.md)")
    ap.add_argument("--rerun", type=Path, metavar="CSV",
                    help="the scenes of an earlier --out CSV that did not complete (see "
                         "--outcome), drawn again with --max-count, instead of --first/--count")
    ap.add_argument("--outcome", action="append", choices=OUTCOMES, metavar="OUTCOME",
                    help="with --rerun: the outcomes to run again (repeatable; default every "
                         f"one but completed; one of {', '.join(OUTCOMES)})")
    ap.add_argument("--run-scene", metavar="FILE", help=argparse.SUPPRESS)  # one child
    args = ap.parse_args(argv)
    if args.run_scene:
        return _child_main(args.run_scene)
    if args.count < 0 or args.jobs < 1 or args.timeout <= 0 or args.max_count < 1:
        ap.error("--count >= 0, --jobs >= 1, --timeout > 0 and --max-count >= 1")
    if args.outcome and not args.rerun:
        ap.error("--outcome needs --rerun")
    if args.rerun and args.sample:
        ap.error("--rerun and --sample exclude each other")
    if args.rerun:
        wanted = tuple(args.outcome or [o for o in OUTCOMES if o != "completed"])
        try:
            specs = rerun(args.rerun, wanted, max_count=args.max_count)
        except (OSError, ValueError) as exc:  # (the columns are checked in rerun)
            ap.error(str(exc) if isinstance(exc, ValueError) else f"--rerun {args.rerun}: {exc}")
    elif args.sample:
        specs = sample()
    else:
        specs = corpus(args.corpus_seed, args.count, first=args.first, max_count=args.max_count)
    if args.treatment != "pairwise":
        specs = [with_treatment(spec, args.treatment) for spec in specs]
    if args.dry_run:
        if args.write_scenes:
            args.write_scenes.mkdir(parents=True, exist_ok=True)
            for spec in specs:
                (args.write_scenes / f"{spec.id}.toml").write_text(spec.text)
        for spec in specs:
            print(f"{spec.id:>9} {spec.kind:>8} {spec.n:>5} {spec.duration:6.3f} s "
                  f"rest {'yes' if spec.expected_rest else 'no ':3} {spec.compact()}")
        return 0
    t0 = time.perf_counter()
    print(HEADER, flush=True)
    rows = run_corpus(specs, jobs=args.jobs, timeout=args.timeout, scene_dir=args.write_scenes,
                      report=lambda line: print(line, flush=True))
    print(f"# in scene order (wall {time.perf_counter() - t0:.0f} s):")
    print(HEADER)
    for row in rows:
        print(format_row(row))
    for line in summary(rows):
        print(line)
    if args.out:
        write_rows(rows, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
