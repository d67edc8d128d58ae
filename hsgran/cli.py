"""The ``hsgran`` command line (layer 6: may import everything).

``main`` parses the command line with :mod:`argparse` subcommands and hands the parsed
arguments to one function per subcommand (:data:`HANDLERS`). More subcommands (run, render,
plot, validate) plug in the same way: an ``_add_NAME_parser`` function and a handler.

Bad input never shows a traceback: every :class:`~hsgran.errors.InputError`, and every usage
error of argparse itself, becomes exactly one line ``hsgran: error: ...`` on stderr and exit code
:data:`~hsgran.errors.EXIT_BAD_INPUT` (2). Numbers are parsed here rather than by argparse so
that ``nan`` and ``inf`` are refused with the option named (``--radius: must be a finite number
> 0, got 'nan'``).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import signal
import sys
import textwrap
import threading
from collections.abc import Callable
from dataclasses import asdict, replace

import numpy as np

from hsgran import __version__
from hsgran.effects import BEYOND_PAPER, Effects
from hsgran.errors import EXIT_BAD_INPUT, InputError, MissingDependency, did_you_mean
from hsgran.impact import (
    SOLID_SPHERE_INERTIA,
    ImpactResult,
    oblique_velocity,
    sphere_mass,
    sphere_sphere_impact,
    sphere_wall_impact,
)
from hsgran.materials import (
    Contact,
    Material,
    MaterialLibrary,
    check_material,
    effective_modulus,
    read_toml,
    with_overrides,
)
from hsgran.sweep import add_sweep_parser, cmd_sweep
from hsgran.validate import add_validate_parser, cmd_validate

PROG = "hsgran"

#: What docs/model.md marks as our own reconstruction; said by ``impact --help`` and under
#: the table.
RECONSTRUCTION_NOTE = (
    "Parts of this model are our reconstruction, marked [OURS] in docs/model.md: the "
    "elastic-plastic and fully plastic stages (§3.3-3.4), the f0 estimate of the adhesion line "
    "force from a work of adhesion (§3.8) and the rolling couple inside a collision (§5.2)."
)

#: The same, as the one last line of the ``hsgran impact`` table.
RECONSTRUCTION_LINE = ("note: our reconstruction ([OURS] in docs/model.md): §3.3-3.4 plastic "
                       "stages, §3.8 f0 estimate, §5.2 rolling couple")

#: Frame of every vector that ``hsgran impact`` reads or prints.
IMPACT_FRAME = (
    "wall normal +z (two spheres: +z points from the resting sphere's centre to the moving "
    "one's), the sphere moves towards +x before impact, spin about +y = n x t (positive = "
    "forward rolling, topspin); SI units"
)

#: argparse takes '-1e3' or '-inf' for an option unless it looks like a negative number; its own
#: pattern misses exponents and inf/nan, so ``--spin -1e3`` would be a usage error. None of
#: hsgran's options looks like a number, so widening the pattern cannot hide an option.
_NEGATIVE_NUMBER = re.compile(
    r"^-(?:(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?|inf(?:inity)?|nan)$", re.IGNORECASE)


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are InputErrors (one line, no usage dump).

    Abbreviated long options are refused: a script that abbreviates would break as soon as a
    new option shares the prefix.
    """

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER
        #: Subcommand parsers by name (filled by :func:`build_parser`).
        self.commands: dict[str, argparse.ArgumentParser] = {}

    def options(self) -> list[str]:
        """Every long option string this parser knows."""
        return [o for a in self._actions for o in a.option_strings if o.startswith("--")]

    def error(self, message: str):
        raise InputError(f"{message} (see '{self.prog} --help')")


# ---- numbers from the command line ------------------------------------------------------

def _number(text: str | None, option: str, requirement: str = "a finite number",
            accept: Callable[[float], bool] | None = None) -> float | None:
    """Parse ``text`` given to ``option``; ``None`` stays ``None``.

    Raises:
        InputError: not a number, not finite, or refused by ``accept`` (message ``requirement``).
    """
    if text is None:
        return None
    try:
        x = float(text)
    except ValueError:
        x = math.nan
    if not math.isfinite(x) or (accept is not None and not accept(x)):
        raise InputError(f"must be {requirement}, got {text!r}", option)
    return x


def _positive(text, option):
    return _number(text, option, "a finite number > 0", lambda x: x > 0.0)


def _non_negative(text, option):
    return _number(text, option, "a finite number >= 0", lambda x: x >= 0.0)


# ---- output helpers ----------------------------------------------------------------------

def _json_ready(value):
    """``value`` with every non-finite float turned into ``None`` (strict JSON)."""
    if isinstance(value, dict):
        return {k: _json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_json_ready(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


def _fmt(value) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "(" + ", ".join(_fmt(v) for v in value) + ")"
    if isinstance(value, (float, int, np.floating)):
        x = float(value)
        if math.isnan(x):
            return "n/a"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return f"{x:.6g}" if x != 0.0 else "0"
    return str(value)


def _table(rows: list[tuple[str, object, str]]) -> str:
    cells = [(q, _fmt(v), u) for q, v, u in rows]
    wq = max(len("quantity"), *(len(q) for q, _, _ in cells))
    wv = max(len("value"), *(len(v) for _, v, _ in cells))
    lines = [f"{'quantity':<{wq}}  {'value':<{wv}}  unit"]
    lines += [f"{q:<{wq}}  {v:<{wv}}  {u}".rstrip() for q, v, u in cells]
    return "\n".join(lines)


# ---- hsgran impact -------------------------------------------------------------------------

def _paragraphs(*paragraphs: str, width: int = 79) -> str:
    """Paragraphs filled to ``width`` for a raw-text argparse description."""
    return "\n\n".join(textwrap.fill(" ".join(p.split()), width) for p in paragraphs) + "\n"


_IMPACT_DESCRIPTION = _paragraphs(
    "One collision: a sphere hitting a wall (--wall MAT), or a sphere hitting another sphere "
    "at rest (--other MAT --other-radius R2), computed with the collision model of Yu, "
    "Elghannay & Tafti (2017) as specified in docs/model.md. Prints a table, or one JSON object "
    "with --json.",
    f"Frame: {IMPACT_FRAME}. The resting sphere lies below the moving one, so --angle has the "
    "same meaning for a wall and for a sphere.",
    "Every effect of the paper is on unless --effects picks a subset (comma-separated, from: "
    f"{', '.join(Effects.names())}; 'none' for none); 'friction' needs 'rotation', "
    "'rolling_resistance' and 'tangential_compliance' need 'friction'. "
    f"{' and '.join(BEYOND_PAPER)} are physics beyond the paper (docs/model.md §4.5, §3.11; "
    "the compliance table and the combination of viscous and plastic losses are our own "
    "reconstructions [OURS]): they are on only when named. 'gravity' is accepted and ignored "
    "(one impact has no free flight). The pair's contact properties come from the built-in "
    "library or a --materials file, with the overrides below applied; with 'friction' on, the "
    "pair needs a sliding friction (--friction, or sliding_friction in a --materials file).",
    RECONSTRUCTION_NOTE,
)

_IMPACT_EPILOG = """\
examples:
  hsgran impact --sphere steel --wall steel --radius 0.005 --speed 1 --angle 0 \\
      --effects plasticity
  hsgran impact --sphere alumina --wall glass --radius 0.0025 --speed 3.9 \\
      --angle 40 --restitution 0.98 --json
  hsgran impact --sphere steel --other steel --radius 0.005 --other-radius 0.005 \\
      --speed 2 --angle 30 --spin -100 --friction 0.3
"""


def _add_impact_parser(sub) -> None:
    p = sub.add_parser(
        "impact", help="one sphere-wall or sphere-sphere collision",
        description=_IMPACT_DESCRIPTION, epilog=_IMPACT_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    bodies = p.add_argument_group("bodies")
    bodies.add_argument("--sphere", metavar="MAT", required=True,
                        help="material of the moving sphere")
    target = bodies.add_mutually_exclusive_group(required=True)
    target.add_argument("--wall", metavar="MAT", help="material of the wall (flat, fixed)")
    target.add_argument("--other", metavar="MAT",
                        help="material of the other sphere, at rest below the moving one")
    bodies.add_argument("--radius", metavar="R", required=True,
                        help="radius of the moving sphere [m]")
    bodies.add_argument("--other-radius", metavar="R2",
                        help="radius of the other sphere [m] (required with --other)")
    bodies.add_argument("--materials", metavar="FILE.toml",
                        help="[materials.NAME] and [[contacts]] tables added to the built-ins")
    motion = p.add_argument_group("motion before impact")
    motion.add_argument("--speed", metavar="V", required=True,
                        help="speed of the moving sphere's centre [m/s]")
    motion.add_argument("--angle", metavar="DEG", required=True,
                        help="impact angle from the wall normal, in [0, 90) [deg]")
    motion.add_argument("--spin", metavar="W", default="0",
                        help="spin about n x t [rad/s]; > 0 forward rolling (topspin), "
                             "< 0 backspin (default 0; needs the 'rotation' effect)")
    model = p.add_argument_group("model")
    model.add_argument("--effects", metavar="LIST",
                       help="comma-separated effects to switch on (default: all)")
    model.add_argument("--friction", metavar="MU_S",
                       help="sliding friction coefficient of the pair [-]")
    model.add_argument("--rolling-friction", metavar="MU_R",
                       help="rolling friction coefficient of the pair [-] (couple mu_r R* F_n)")
    model.add_argument("--restitution", metavar="E_N",
                       help="prescribed normal restitution in [0, 1]; bypasses the normal model")
    model.add_argument("--yield-stress", metavar="PA",
                       help="yield stress of the moving sphere's material, and of the other "
                            "sphere's with --other [Pa]; not of a wall (the pair yields at "
                            "the smaller of its two yield stresses)")
    model.add_argument("--dissipative-constant", metavar="S",
                       help="dissipative constant A of the moving sphere's material, and of "
                            "the other sphere's with --other [s] (viscoelastic_damping, "
                            "docs/model.md §3.11)")
    model.add_argument("--work-of-adhesion", metavar="J_M2",
                       help="work of adhesion of the pair [J/m^2] (f0 estimated from it)")
    out = p.add_argument_group("output")
    out.add_argument("--json", action="store_true",
                     help="print one JSON object (SI units, frame as above) instead of a table")


def _impact_effects(text: str | None) -> Effects:
    if text is None:
        effects = Effects.all()
    else:
        names = [s.strip() for s in text.split(",") if s.strip()]
        effects = Effects.parse([] if names == ["none"] else names, key="--effects")
    # 'gravity' has nothing to act on during one instantaneous impact.
    return effects.without("gravity")


def _library(path: str | None) -> MaterialLibrary:
    lib = MaterialLibrary()
    if path is None:
        return lib
    try:
        doc = read_toml(path)
    except InputError as exc:
        raise InputError(str(exc), "--materials") from None
    try:
        lib.add_tables(doc, origin=path)
    except InputError as exc:
        raise InputError(str(exc), path) from None
    return lib


def _sphere_material(lib: MaterialLibrary, name: str, option: str,
                     yield_stress: float | None, dissipative: float | None = None) -> Material:
    m = lib.material(name, option)
    if not math.isfinite(m.density):
        raise InputError(f"material '{name}' has no finite density: it can only be a wall",
                         option)
    if yield_stress is not None:
        m = check_material(replace(m, yield_stress=yield_stress), f"{option} {name}")
    if dissipative is not None:
        m = check_material(replace(m, dissipative_constant=dissipative), f"{option} {name}")
    return m


def _contact_overrides(args: argparse.Namespace) -> dict:
    """The pair overrides given on the command line, parsed (``None`` = not given)."""
    return {
        "sliding_friction": _non_negative(args.friction, "--friction"),
        "rolling_friction": _non_negative(args.rolling_friction, "--rolling-friction"),
        "restitution": _number(args.restitution, "--restitution", "a finite number in [0, 1]",
                               lambda x: 0.0 <= x <= 1.0),
        "work_of_adhesion": _non_negative(args.work_of_adhesion, "--work-of-adhesion"),
    }


def _pair_contact(lib: MaterialLibrary, a: str, b: str, overrides: dict,
                  effects: Effects) -> Contact:
    contact = lib.contact(a, b)
    if overrides["work_of_adhesion"] is not None:
        # A line force declared for the pair would clash with the work of adhesion given here.
        contact = replace(contact, adhesion_line_force=None)
    contact = with_overrides(contact, **overrides)
    if effects.friction and contact.sliding_friction is None:
        raise InputError(
            f"no sliding friction is known for the pair {a}/{b} and the 'friction' effect is on: "
            "pass --friction MU_S (or declare sliding_friction in a [[contacts]] table of a "
            "--materials file), or leave 'friction' out of --effects")
    return contact


def cmd_impact(args: argparse.Namespace) -> int:
    """``hsgran impact``: one collision, printed as a table or as JSON.

    Returns:
        Exit code 0.

    Raises:
        InputError: any bad option, material or combination.
    """
    radius = _positive(args.radius, "--radius")
    speed = _positive(args.speed, "--speed")
    angle = _number(args.angle, "--angle", "a finite number in [0, 90) degrees from the normal",
                    lambda x: 0.0 <= x < 90.0)
    spin = _number(args.spin, "--spin")
    yield_stress = _positive(args.yield_stress, "--yield-stress")
    dissipative = _non_negative(args.dissipative_constant, "--dissipative-constant")
    if args.other is not None and args.other_radius is None:
        raise InputError("missing value: the radius of the other sphere [m] is required with "
                         "--other", "--other-radius")
    if args.wall is not None and args.other_radius is not None:
        raise InputError("only applies with --other (a wall has no radius)", "--other-radius")
    other_radius = _positive(args.other_radius, "--other-radius")
    overrides = _contact_overrides(args)
    effects = _impact_effects(args.effects)
    if spin != 0.0 and not effects.rotation:
        raise InputError("a spin needs the 'rotation' effect; add it to --effects", "--spin")

    lib = _library(args.materials)
    sphere = _sphere_material(lib, args.sphere, "--sphere", yield_stress, dissipative)
    if args.wall is not None:
        body2 = lib.material(args.wall, "--wall")
    else:
        body2 = _sphere_material(lib, args.other, "--other", yield_stress, dissipative)
    contact = _pair_contact(lib, sphere.name, body2.name, overrides, effects)

    velocity = oblique_velocity(speed, angle)
    omega = np.array([0.0, spin, 0.0])
    if args.wall is not None:
        result = sphere_wall_impact(sphere, body2, radius, velocity, omega, contact=contact,
                                    effects=effects)
        r_eff, m_eff = radius, sphere_mass(sphere, radius)
    else:
        result = sphere_sphere_impact(sphere, body2, radius, other_radius, velocity,
                                      np.zeros(3), omega, np.zeros(3), contact=contact,
                                      effects=effects)
        m1, m2 = sphere_mass(sphere, radius), sphere_mass(body2, other_radius)
        r_eff, m_eff = 1.0 / (1.0 / radius + 1.0 / other_radius), 1.0 / (1.0 / m1 + 1.0 / m2)

    inputs = {
        "mode": "sphere-wall" if args.wall is not None else "sphere-sphere",
        "sphere": sphere.name, "wall": args.wall, "other": args.other,
        "radius": radius, "other_radius": other_radius,
        "speed": speed, "angle": angle, "spin": spin,
        "velocity_before": velocity, "angular_velocity_before": omega,
        "normal": [0.0, 0.0, 1.0], "frame": IMPACT_FRAME,
        "materials_file": args.materials,
        "overrides": {**overrides, "yield_stress": yield_stress,
                      "dissipative_constant": dissipative},
        "sphere_material": asdict(sphere),
        ("wall_material" if args.wall is not None else "other_material"): asdict(body2),
        "contact": asdict(contact),
        "effective_radius": r_eff, "effective_mass": m_eff,
        "effective_modulus": effective_modulus(sphere, body2),
    }
    derived = _impact_derived(result, velocity, omega, radius, other_radius)
    if args.json:
        doc = {**result.to_dict(), "derived": derived, "input": inputs,
               "effects": list(effects.enabled()), "version": __version__}
        print(json.dumps(_json_ready(doc), indent=2, allow_nan=False))
    else:
        print(_impact_table(result, inputs, derived, effects, sphere, body2, contact))
    return 0


def _slip_x(v1, w1, v2, w2, r1, r2) -> float:
    """x component of the contact-point slip ΔV = (V1 − V2) − (R1 ω1 + R2 ω2) × n, n = +z."""
    return float((v1[0] - v2[0]) - (r1 * w1[1] + r2 * w2[1]))


def _impact_derived(result: ImpactResult, velocity, omega, radius: float,
                    other_radius: float | None) -> dict:
    r2 = 0.0 if other_radius is None else other_radius
    v_after, w_after = result.velocity_after, result.angular_velocity_after
    v2_after, w2_after = result.other_velocity_after, result.other_angular_velocity_after
    rel_n_after = float(v_after[2] - v2_after[2])
    slip_after = _slip_x(v_after, w_after, v2_after, w2_after, radius, r2)
    v_t0 = float(velocity[0])
    separating = rel_n_after > 0.0
    return {
        "tangential_velocity_before": v_t0,
        "tangential_velocity_after": float(v_after[0]),
        "e_t": float(v_after[0]) / v_t0 if v_t0 > 0.0 else math.nan,
        "slip_before": _slip_x(velocity, omega, np.zeros(3), np.zeros(3), radius, r2),
        "slip_after": slip_after,
        "rebound_angle": (math.degrees(math.atan2(float(v_after[0] - v2_after[0]), rel_n_after))
                          if separating else math.nan),
        "contact_patch_rebound_angle": (math.degrees(math.atan2(slip_after, rel_n_after))
                                        if separating else math.nan),
        "spin_change": float(w_after[1] - omega[1]),
        "inertia_factor": SOLID_SPHERE_INERTIA,
    }


def _governing(sphere: Material, body2: Material, wall: bool) -> str:
    """Which body's yield stress governs the pair (the smaller one, MODEL §2)."""
    if sphere.yield_stress == body2.yield_stress:
        return "both"
    if sphere.yield_stress < body2.yield_stress:
        return "sphere"
    return "wall" if wall else "other sphere"


def _impact_table(result: ImpactResult, inputs: dict, derived: dict, effects: Effects,
                  sphere: Material, body2: Material, contact: Contact) -> str:
    wall = inputs["mode"] == "sphere-wall"
    crit = result.critical
    target = (f"a {body2.name} wall" if wall else
              f"a {body2.name} sphere (R2 = {_fmt(inputs['other_radius'])} m) at rest")
    rows = [
        ("impact speed V", inputs["speed"], "m/s"),
        ("angle from the normal", inputs["angle"], "deg"),
        ("spin before (about +y)", inputs["spin"], "rad/s"),
        ("normal impact speed v0", result.impact_speed, "m/s"),
        ("stage", result.stage, ""),
        ("regime", result.regime, ""),
        ("captured", result.captured, ""),
        ("normal restitution e_n", result.e_n, "-"),
        ("tangential restitution e_t", derived["e_t"], "-"),
        ("velocity after", result.velocity_after, "m/s"),
        ("angular velocity after", result.angular_velocity_after, "rad/s"),
    ]
    if not wall:
        rows += [("other sphere velocity after", result.other_velocity_after, "m/s"),
                 ("other sphere angular velocity after", result.other_angular_velocity_after,
                  "rad/s")]
    rows += [
        ("rebound angle from the normal", derived["rebound_angle"], "deg"),
        ("contact-patch rebound angle", derived["contact_patch_rebound_angle"], "deg"),
        ("contact-point slip before / after",
         (derived["slip_before"], derived["slip_after"]), "m/s"),
        ("normal impulse J_n", result.normal_impulse, "N s"),
        ("tangential impulse J_t", result.tangential_impulse, "N s"),
        ("rolling-couple impulse H", result.rolling_impulse, "N m s"),
        ("max compression delta_max", result.delta_max, "m"),
        ("residual deformation", result.residual_deformation, "m"),
        ("max contact radius a_max", result.contact_radius_max, "m"),
        ("max normal force F_max", result.force_max, "N"),
        ("contact time (Hertz)", result.contact_time, "s"),
        ("kinetic energy lost", result.energy_lost, "J"),
        ("yield speed V_y", crit.speed_y, "m/s"),
        ("full-plasticity speed V_p", crit.speed_p, "m/s"),
        ("yield force F_y", crit.force_y, "N"),
        (f"governing yield stress ({_governing(sphere, body2, wall)})",
         min(sphere.yield_stress, body2.yield_stress), "Pa"),
        ("effective radius R*", inputs["effective_radius"], "m"),
        ("effective mass m*", inputs["effective_mass"], "kg"),
        ("effective modulus E*", inputs["effective_modulus"], "Pa"),
        ("sliding friction mu_s", contact.sliding_friction, "-"),
        ("rolling friction mu_r", contact.rolling_friction, "-"),
        ("prescribed restitution", contact.restitution, "-"),
    ]
    head = "\n".join(textwrap.fill(line, 79, subsequent_indent="  ") for line in (
        f"hsgran impact: {sphere.name} sphere (R = {_fmt(inputs['radius'])} m) on {target}",
        f"frame: {IMPACT_FRAME}",
        f"effects: {', '.join(effects.enabled()) or 'none'}"))
    return f"{head}\n\n{_table(rows)}\n\n{RECONSTRUCTION_LINE}"


# ---- run ---------------------------------------------------------------------------------

#: Exit codes of a run ended by a signal: 128 + the signal's number, as shells report it.
EXIT_SIGNAL = {signal.SIGINT: 128 + signal.SIGINT, signal.SIGTERM: 128 + signal.SIGTERM}

_RUN_EPILOG = """\
checkpoints: a run with -o stores a restart state in its file every --checkpoint-wall
  seconds of wall time (default 60), at every multiple of --checkpoint-every simulated
  seconds if given, at the end, and when Ctrl-C or SIGTERM stops it (exit 130 / 143, after
  the current batch of events). 'hsgran run --resume OUT.h5' continues from the last one
  and gives, bit for bit, the frames an uninterrupted run gives; with --until it also
  extends a finished run. A hard kill loses at most the work since the last checkpoint.
enduring contact: with gravity, rules of hsgran's own ([OURS], not from the paper) end the
  infinite collision sequences of inelastic collapse: landing on a plane below
  landing_speed, the TC model, sleeping and held resting spheres, hops, and stopping a
  sphere wedged between immovable bodies. The summary counts them (land, tc, hop, wedge);
  their parameters and costs in accuracy: docs/enduring-contact.md.
walls: spheres resting, rolling and sliding on a cylinder or on a moving plane move in
  segments of hsgran's own ([OURS]), and a collision with a cylinder takes a flat wall's
  contact radius; their bounds and checks: docs/walls.md.
"""


class _StopRequest:
    """Signal handler that asks the engine to stop after the current batch of events."""

    def __init__(self):
        self.signum: int | None = None

    def __call__(self, signum, frame) -> None:
        self.signum = self.signum or signum

    def requested(self) -> bool:
        """Whether a signal arrived."""
        return self.signum is not None


def _add_run_parser(sub) -> None:
    p = sub.add_parser(
        "run", help="run a scene file and write its trajectory (HDF5, H5MD 1.1)",
        description="Run a scene (TOML) with the event-driven engine and write an HDF5 "
                    "trajectory following H5MD 1.1 (layout: docs/trajectory-format.md). "
                    "Prints a summary: events by kind, simulated time, wall time, events/s.",
        epilog=_RUN_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", metavar="SCENE.toml", nargs="?", help="scene file")
    p.add_argument("-o", "--output", metavar="OUT.h5", help="trajectory file to write")
    p.add_argument("--resume", metavar="OUT.h5",
                   help="continue the run of this trajectory file from its last checkpoint")
    p.add_argument("--until", metavar="T", help="end time [s] (default: the scene's duration; "
                   "with --resume, the end time of the original run)")
    p.add_argument("--events", action="store_true", help="record every collision in the file")
    p.add_argument("--force", action="store_true", help="overwrite an existing output file")
    p.add_argument("--checkpoint-every", metavar="T",
                   help="also store a checkpoint at every multiple of T simulated seconds")
    p.add_argument("--checkpoint-wall", metavar="S",
                   help="store a checkpoint every S seconds of wall time (default 60; 0: only "
                        "at the end and when interrupted)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _run_options(args: argparse.Namespace) -> dict:
    """Check the option combination of ``hsgran run``; the keyword arguments of the API."""
    if args.resume is not None:
        for given, option in ((args.scene, "SCENE.toml"), (args.output, "-o"),
                              (args.events or None, "--events"), (args.force or None, "--force")):
            if given is not None:
                raise InputError(f"--resume continues the file's own run: drop {option}")
    elif args.scene is None:
        raise InputError("missing SCENE.toml (or --resume OUT.h5)")
    wall = (None if args.checkpoint_wall is None
            else _non_negative(args.checkpoint_wall, "--checkpoint-wall"))
    return {
        "until": None if args.until is None else _positive(args.until, "--until"),
        "checkpoint_every": (None if args.checkpoint_every is None
                             else _positive(args.checkpoint_every, "--checkpoint-every")),
        **({} if wall is None else {"checkpoint_wall": wall or None}),
        "progress": not args.no_progress,
    }


def cmd_run(args: argparse.Namespace) -> int:
    """``hsgran run``: run a scene and write its trajectory, or resume one."""
    from hsgran.api import resume_run, run_scene
    from hsgran.engine import SimulationError

    options = _run_options(args)
    output = args.resume if args.resume is not None else args.output
    request = _StopRequest()
    # handlers can only be installed from the main thread (not when main() runs in a worker)
    main_thread = threading.current_thread() is threading.main_thread()
    previous = {sig: signal.signal(sig, request) for sig in EXIT_SIGNAL} if main_thread else {}
    try:
        if args.resume is not None:
            summary = resume_run(args.resume, stop=request.requested, **options)
        else:
            summary = run_scene(args.scene, args.output, log_events=args.events,
                                force=args.force, creator_args=" ".join(sys.argv),
                                stop=request.requested, **options)
    except SimulationError as exc:
        print(f"{PROG}: simulation stopped: {_one_line(exc)}", file=sys.stderr)
        return 1
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    for line in summary.lines():
        print(line)
    if output:
        print(f"trajectory: {output}")
    if summary.interrupted:
        name = signal.Signals(request.signum).name
        how = (f"resume with: {PROG} run --resume {output}" if output
               else "nothing was written (no -o)")
        print(f"{PROG}: interrupted by {name} at t = {summary.simulated_time:.9g} s; {how}",
              file=sys.stderr)
        return EXIT_SIGNAL[request.signum]
    return 0


# ---- render and plot ---------------------------------------------------------------------

_SIZE = re.compile(r"^\s*(\d+)\s*[xX]\s*(\d+)\s*$")

_RENDER_EPILOG = """\
cameras: auto (iso, or follow:0 for a lone sphere far smaller than its path), iso, side, top,
  follow:K (follow particle K), X,Y,Z (camera position in m, looking at the scene's centre),
  X,Y,Z:FX,FY,FZ (position and point looked at)
colours (--color-by): speed (colour bar), state (flight, sliding, rolling, at rest, asleep),
  material, regime (tangential regime of each sphere's last collision; needs 'run --events')
examples:
  hsgran render out.h5 -o movie.mp4
  hsgran render out.h5 -o slow.gif --time-scale 0.1 --size 640x360 --color-by state
  hsgran render out.h5 --at 0.05 -o still.png --camera follow:0
  hsgran render out.h5 --frames frames/ --fps 25
"""


def _size(text: str) -> tuple[int, int]:
    match = _SIZE.match(text)
    if not match:
        raise InputError(f"expected WIDTHxHEIGHT in pixels (e.g. 1280x720), got {text!r}",
                         "--size")
    return int(match.group(1)), int(match.group(2))


def _add_render_parser(sub) -> None:
    # Values and defaults are spelt out here rather than imported: importing the renderer's
    # modules (numba, h5py) would slow down every other subcommand. tests/test_render.py checks
    # that they match hsgran.render and hsgran.animation.
    p = sub.add_parser(
        "render", help="render a trajectory offscreen: MP4, GIF, PNG frames or one still",
        description=_paragraphs(
            "Render an HDF5 trajectory of 'hsgran run' without a display (VTK with EGL): "
            "spheres at their true radii with a pattern that turns with their spin, plane walls "
            "as finite patches, a time label and a colour legend. See docs/rendering.md."),
        epilog=_RENDER_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("trajectory", metavar="OUT.h5", help="trajectory file")
    p.add_argument("-o", "--output", metavar="FILE",
                   help="movie (.mp4, .gif) or, with --at, still (.png); default: the "
                        "trajectory's name with .mp4 (.png with --at)")
    p.add_argument("--frames", metavar="DIR", help="write PNG frames into DIR instead")
    p.add_argument("--at", metavar="T", help="render one still at simulated time T [s]")
    p.add_argument("--start", metavar="T0", help="first simulated time of the movie [s]")
    p.add_argument("--end", metavar="T1", help="last simulated time of the movie [s]")
    p.add_argument("--fps", metavar="FPS", help="frames per second of video (default 30)")
    p.add_argument("--size", metavar="WxH", help="picture size in pixels (default 1280x720; "
                                                 "MP4 rounds up to multiples of 16)")
    p.add_argument("--camera", metavar="CAM", default="auto",
                   help="auto (default), iso, side, top, follow:K, X,Y,Z or X,Y,Z:FX,FY,FZ")
    p.add_argument("--color-by", metavar="VAR", default="speed",
                   help="what the sphere colours show: speed (default), state, material or "
                        "regime")
    p.add_argument("--time-scale", metavar="S",
                   help="simulated seconds per second of video (0.1: ten times slower than "
                        "real time; default: one movie frame per stored frame)")
    p.add_argument("--spheres", metavar="STYLE", default="auto",
                   help="mesh (a turning pattern), points (fast impostors with spin "
                        "markers) or auto (default: meshes up to 50 spheres)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def cmd_render(args: argparse.Namespace) -> int:
    """``hsgran render``: movie, frames or still of a trajectory."""
    from hsgran.render import DEFAULT_FPS, DEFAULT_SIZE, render

    size = DEFAULT_SIZE if args.size is None else _size(args.size)
    fps = DEFAULT_FPS if args.fps is None else _positive(args.fps, "--fps")
    result = render(
        args.trajectory, args.output, frames_dir=args.frames,
        at=_number(args.at, "--at", "a finite number"),
        start=_number(args.start, "--start", "a finite number"),
        end=_number(args.end, "--end", "a finite number"),
        fps=fps, size=size, camera=args.camera, color_by=args.color_by,
        time_scale=_positive(args.time_scale, "--time-scale"), spheres=args.spheres,
        force=args.force, progress=not args.no_progress)
    width, height = result.size
    what = ("still" if result.kind == "png" else
            f"{result.frames} frames, {result.frames / result.fps:.1f} s of video at "
            f"{result.fps:g} fps, {result.time_scale:.3g} simulated s per video s")
    print(f"wrote {result.output}: {what}, {width}x{height}, "
          f"{1e3 * result.seconds_per_frame:.0f} ms/frame")
    return 0


def _add_export_parser(sub) -> None:
    p = sub.add_parser(
        "export", help="write a trajectory for ParaView (VTK) or OVITO (extended XYZ)",
        description=_paragraphs(
            "Write an HDF5 trajectory of 'hsgran run' in the files outside viewers open: "
            "--format vtk, a ParaView collection (NAME.pvd, one .vtp per frame with radius, "
            "velocity, spin, motion state, material and id per sphere, and walls.vtp); "
            "--format xyz, one extended-XYZ file of all frames for OVITO (or ASE). Values "
            "stay in SI units (metres, not ångström)."))
    p.add_argument("trajectory", metavar="OUT.h5", help="trajectory file")
    p.add_argument("--format", required=True, choices=("vtk", "xyz"),
                   help="vtk (ParaView, needs the render extra) or xyz (OVITO, needs ASE)")
    p.add_argument("-o", "--output", metavar="PATH",
                   help="directory (vtk) or file (xyz); default: the trajectory's name with "
                        "_vtk or .xyz")
    p.add_argument("--every", metavar="K", help="write every K-th frame (default 1)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output")


def cmd_export(args: argparse.Namespace) -> int:
    """``hsgran export``: a trajectory for ParaView or OVITO."""
    from hsgran.export import export

    every = 1 if args.every is None else _number(args.every, "--every", "a whole number >= 1",
                                                 lambda x: x >= 1 and x == int(x))
    result = export(args.trajectory, args.format, args.output, every=int(every),
                    force=args.force)
    print(f"wrote {result.output}: {result.frames} frames, {len(result.files)} files")
    return 0


def _add_fields_parser(sub) -> None:
    p = sub.add_parser(
        "fields", help="profiles of packing fraction, velocity, granular temperature and "
                       "kinetic stress along an axis",
        description=_paragraphs(
            "Coarse-grain a trajectory of 'hsgran run' in slabs normal to an axis, each sphere "
            "counted with the exact fraction of its volume in each slab, averaged over the "
            "frames of a time window (hsgran.fields). Prints a table, or writes CSV."))
    p.add_argument("trajectory", metavar="OUT.h5", help="trajectory file (with a box)")
    p.add_argument("--axis", default="z", help="x, y or z (default z)")
    p.add_argument("--bins", metavar="B", default="20", help="number of slabs (default 20)")
    p.add_argument("--from", dest="start", metavar="T0", help="start of the window [s]")
    p.add_argument("--to", dest="end", metavar="T1", help="end of the window [s]")
    p.add_argument("--csv", metavar="FILE", help="write the profiles as CSV instead")


def cmd_fields(args: argparse.Namespace) -> int:
    """``hsgran fields``: slab profiles of a trajectory."""
    from hsgran.fields import profiles, table, write_csv

    bins = _number(args.bins, "--bins", "a whole number >= 1", lambda x: x >= 1 and x == int(x))
    p = profiles(args.trajectory, args.axis, int(bins),
                 start=_number(args.start, "--from", "a finite number"),
                 end=_number(args.end, "--to", "a finite number"))
    if args.csv:
        write_csv(p, args.csv)
        print(f"wrote {args.csv}: {p.centres.shape[0]} slabs, {p.frames} frames")
    else:
        print(table(p))
    return 0


def _add_observables_parser(sub) -> None:
    p = sub.add_parser(
        "observables", help="pressure, stress, wall forces and collision rates per frame "
                            "interval (scenes with [output] observables = true)",
        description=_paragraphs(
            "The observables the event loop summed exactly over each frame interval "
            "(hsgran.observables, docs/observables.md): collisional and kinetic pressure, the "
            "force on every plane, the support not traced to a plane, and the collision "
            "rates. Prints each quantity's mean over the intervals from --from on with its "
            "standard error (block averages), or writes every interval as CSV."))
    p.add_argument("trajectory", metavar="OUT.h5", help="trajectory file")
    p.add_argument("--volume", metavar="V", help="volume for the stress [m³] (default: the box)")
    p.add_argument("--from", dest="start", metavar="T0", default="0",
                   help="average the intervals that start at or after T0 [s] (default 0)")
    p.add_argument("--csv", metavar="FILE", help="write every interval as CSV instead")


def cmd_observables(args: argparse.Namespace) -> int:
    """``hsgran observables``: the interval observables of a trajectory."""
    from hsgran.io.h5md import read_trajectory
    from hsgran.observables import interval_observables, summary, write_csv

    volume = _number(args.volume, "--volume", "a positive volume in m³", lambda x: x > 0)
    start = _number(args.start, "--from", "a finite number")
    obs = interval_observables(read_trajectory(args.trajectory), volume)
    if args.csv:
        write_csv(obs, args.csv)
        print(f"wrote {args.csv}: {obs.start.shape[0]} intervals")
    else:
        print(summary(obs, start))
    return 0


def _add_plot_parser(sub) -> None:
    p = sub.add_parser(
        "plot", help="plot energies (and, for a few particles, height, speed, spin) vs time, "
                     "or the results of a sweep",
        description="Plot a trajectory with matplotlib: translational, rotational, potential "
                    "and dissipated energy against time; for scenes of at most "
                    "10 particles (or those picked with --particles) also "
                    "their height, speed and spin, with the collisions of the event log "
                    "marked ('hsgran run --events'). Given the RESULTS/ folder of "
                    "'hsgran sweep', plot each summary quantity against the swept parameters "
                    "(docs/sweeps.md).")
    p.add_argument("trajectory", metavar="OUT.h5|RESULTS/",
                   help="trajectory file, or the results folder of a sweep")
    p.add_argument("-o", "--output", metavar="FIG",
                   help="figure (.png, .pdf or .svg); default: the trajectory's name with .png")
    p.add_argument("--particles", metavar="LIST",
                   help="particles to plot against time: comma-separated indices, 'all' or "
                        "'none' (default: all when there are at most 10)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output")


def cmd_plot(args: argparse.Namespace) -> int:
    """``hsgran plot``: energies and few-particle histories of a trajectory."""
    from hsgran.plot import plot

    output = plot(args.trajectory, args.output, particles=args.particles, force=args.force)
    print(f"wrote {output}")
    return 0


def _add_compile_parser(sub) -> None:
    from hsgran.precompile import VERSIONS

    p = sub.add_parser(
        "compile", help="compile the event loop ahead of the first run (setup does this)",
        description="Compile the versions of the compiled event loop (with and without "
                    "gravity, each for ordinary and for large systems) into numba's on-disk "
                    "cache, side by side in separate processes. Otherwise the first run that "
                    "needs a version compiles it: 3 min without gravity, 14 min with it, on 2 "
                    "cores (2026-12-03). The cache "
                    "is kept per version of hsgran's sources (under ~/.cache/hsgran, or "
                    "NUMBA_CACHE_DIR).")
    p.add_argument("versions", nargs="*", metavar="VERSION",
                   help=f"versions to compile: {', '.join(VERSIONS)} (default: all)")
    p.add_argument("--jobs", metavar="N", help="parallel processes (default: one per core, "
                                               "at most one per version)")


def cmd_compile(args: argparse.Namespace) -> int:
    """``hsgran compile``: fill the on-disk cache with every version of the event loop."""
    from hsgran.precompile import VERSIONS, default_jobs, main_report

    for name in args.versions:
        if name not in VERSIONS:
            raise InputError(f"unknown version {name!r}{did_you_mean(name, VERSIONS)} "
                             f"(one of: {', '.join(VERSIONS)})")
    jobs = default_jobs()
    if args.jobs is not None:
        try:
            jobs = int(args.jobs)
        except ValueError:
            jobs = 0
        if jobs < 1:
            raise InputError(f"--jobs must be a whole number >= 1, not {args.jobs!r}")
    return main_report(args.versions or None, jobs)


# ---- main --------------------------------------------------------------------------------

#: Handler of each subcommand: takes the parsed arguments, returns the exit code.
HANDLERS: dict[str, Callable[[argparse.Namespace], int]] = {
    "impact": cmd_impact,
    "run": cmd_run,
    "render": cmd_render,
    "export": cmd_export,
    "fields": cmd_fields,
    "observables": cmd_observables,
    "plot": cmd_plot,
    "validate": cmd_validate,
    "sweep": cmd_sweep,
    "compile": cmd_compile,
}


def build_parser() -> argparse.ArgumentParser:
    """The ``hsgran`` argument parser with every subcommand."""
    parser = _Parser(
        prog=PROG,
        description="Event-driven hard-sphere granular simulator with the impulse-based "
                    "collision model of Yu, Elghannay & Tafti (2017).")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    _add_impact_parser(sub)
    _add_run_parser(sub)
    _add_render_parser(sub)
    _add_export_parser(sub)
    _add_fields_parser(sub)
    _add_observables_parser(sub)
    _add_plot_parser(sub)
    add_validate_parser(sub)
    add_sweep_parser(sub)
    _add_compile_parser(sub)
    parser.commands = dict(sub.choices)
    return parser


def _unrecognized(parser: _Parser, command: str | None, extra: list[str]) -> InputError:
    """Error for arguments no parser took, with a hint for a misspelt option."""
    target = parser.commands.get(command, parser)
    options = target.options() if isinstance(target, _Parser) else []
    word = extra[0].split("=", 1)[0]
    hint = did_you_mean(word, options) if word.startswith("--") else ""
    return InputError(f"unrecognized arguments: {' '.join(extra)}{hint} "
                      f"(see '{target.prog} --help')")


def _one_line(message: str) -> str:
    return " ".join(str(message).split())


def main(argv: list[str] | None = None) -> int:
    """Run the ``hsgran`` command line.

    Args:
        argv: Arguments without the program name (default: ``sys.argv[1:]``).

    Returns:
        Exit code: 0 on success, :data:`~hsgran.errors.EXIT_BAD_INPUT` (2) on bad input.
    """
    parser = build_parser()
    try:
        try:
            args, extra = parser.parse_known_args(argv)
        except SystemExit as exc:  # --help and --version exit through argparse
            return exc.code if isinstance(exc.code, int) else 0
        if extra:
            raise _unrecognized(parser, args.command, extra)
        if args.command is None:
            raise InputError(f"missing command: one of {', '.join(HANDLERS)} "
                             f"(see '{PROG} --help')")
        return HANDLERS[args.command](args)
    except (InputError, MissingDependency) as exc:  # bad input, or an extra not installed
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
