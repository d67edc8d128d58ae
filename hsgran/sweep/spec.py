"""Sweep files: TOML in, a validated :class:`SweepSpec` and its list of :class:`Case` out.

The format (full description with examples in docs/sweeps.md)::

    [sweep]
    scene = "kharaz_single.toml"     # base scene, relative to this file (required)
    name = "Kharaz oblique impacts"  # optional, for plot titles (default: the file name)
    combine = "grid"                 # "grid" (every combination, default) or "zip"
    seeds = [0, 1, 2]                # optional: scene.seed of each run, crossed with the
                                     # cases; or { start = 0, count = 10 }
    summaries = ["e_n", "rebound_angle", "spin_after"]   # what each run reports (required)
    trajectories = false             # write each case's HDF5 trajectory (default false)

    [vary]                           # what varies: a scene key path, or a parameter name
    "contacts[0].sliding_friction" = [0.1, 0.2, 0.3]    # a list of values
    angle = { start = 1, stop = 89, num = 45 }           # or a range: num (inclusive ends),
    speed = { start = 0.1, stop = 10, num = 5, log = true }  # log spacing, or step

    [set]                            # scene values computed from the parameters
    "particles[0].velocity" = ["3.9 * sin(radians(angle))", 0.0, "-3.9 * cos(radians(angle))"]

A ``[vary]`` key with a ``.`` or ``[`` is a scene key path (:mod:`hsgran.overrides`) and each
value is written there; a plain name is a parameter that ``[set]`` expressions (:mod:`.expr`)
turn into scene values. Every case of the sweep is one set of overrides of the base scene.

Every problem is an :class:`~hsgran.errors.InputError` naming the key (``vary.angle.num``).
"""

from __future__ import annotations

import ast
import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from hsgran.errors import InputError, check_number, did_you_mean, short_repr
from hsgran.overrides import names_override, parse_key_path
from hsgran.scene import parse_scene
from hsgran.sweep import expr
from hsgran.sweep.summaries import SUMMARIES

TOP_KEYS = ("sweep", "vary", "set")
SWEEP_KEYS = ("scene", "name", "combine", "seeds", "summaries", "trajectories")
COMBINE_MODES = ("grid", "zip")
RANGE_KEYS = ("start", "stop", "num", "step", "log")
SEED_RANGE_KEYS = ("start", "count")
#: The key path a seed is written to.
SEED_KEY = "scene.seed"

#: Most cases a sweep may have. A typo (``num = 1e7`` twice in a grid) would otherwise build a
#: list of 10¹⁴ cases before anything runs; a million cases of even one millisecond each is
#: already a large distributed job.
MAX_CASES = 1_000_000
#: Relative slack on the end of a ``step`` range, so that ``start = 0.1, stop = 0.3, step =
#: 0.1`` includes 0.3 despite 0.1 + 2 × 0.1 = 0.30000000000000004.
STEP_END_SLACK = 1e-9
#: Characters of the SHA-256 hex digest kept as a case id (64 bits: a collision among 10⁶
#: cases has a probability of ~3e-8).
CASE_ID_CHARS = 16


@dataclass(frozen=True)
class Case:
    """One run of a sweep.

    Attributes:
        index: Position in the sweep (grid order: first [vary] key slowest, seeds fastest).
        params: Swept value of each [vary] key (in file order).
        seed: The run's scene seed, or ``None`` when the sweep gives no seeds.
        overrides: Key path → value written into the base scene (see :mod:`hsgran.overrides`).
        case_id: Stable hash of the base scene text, the overrides and the seed: the name of
            the case's row file, so a rerun recognises the cases already done.
    """

    index: int
    params: dict
    seed: int | None
    overrides: dict
    case_id: str


@dataclass
class SweepSpec:
    """A validated sweep file.

    Attributes:
        name: Title of the sweep.
        source: Path of the sweep file.
        text: The sweep file's text.
        scene_path: Path of the base scene.
        scene_text: The base scene's text (shipped to the workers, which need no shared disk
            to read it).
        combine: "grid" or "zip".
        vary: [vary] key → list of values.
        set: [set] key path → parsed value template (see :func:`_template`).
        seeds: Seeds, or ``None``.
        summaries: Names of the summary quantities (keys of :data:`SUMMARIES`).
        trajectories: Write each case's trajectory.
    """

    name: str
    source: str
    text: str
    scene_path: Path
    scene_text: str
    combine: str
    vary: dict[str, list]
    set: dict = field(default_factory=dict)
    seeds: list[int] | None = None
    summaries: list[str] = field(default_factory=list)
    trajectories: bool = False

    @property
    def parameters(self) -> list[str]:
        """The swept keys, in file order."""
        return list(self.vary)

    def cases(self) -> list[Case]:
        """Every case of the sweep, in order.

        Raises:
            InputError: a [set] expression cannot be evaluated for some case.
        """
        if self.combine == "zip":
            combos = list(zip(*self.vary.values(), strict=True))
        else:
            combos = list(itertools.product(*self.vary.values()))
        out = []
        for combo in combos:
            params = dict(zip(self.vary, combo, strict=True))
            for seed in (self.seeds if self.seeds is not None else [None]):
                overrides = {k: v for k, v in params.items() if _is_key_path(k)}
                named = {k: v for k, v in params.items() if not _is_key_path(k)}
                for path, template in self.set.items():
                    overrides[path] = _fill(template, named, f"set.{path}")
                if seed is not None:
                    overrides[SEED_KEY] = seed
                out.append(Case(len(out), params, seed, overrides,
                                case_id(self.scene_text, overrides)))
        return out


def case_id(scene_text: str, overrides: dict) -> str:
    """Stable id of a run: a hash of the base scene's text and the overrides (seed included).

    The hsgran version is left out on purpose: upgrading hsgran does not redo a finished sweep
    (start a new results folder to rerun it).
    """
    doc = json.dumps({"scene": scene_text, "overrides": [[k, v] for k, v in overrides.items()]},
                     sort_keys=True, allow_nan=True)
    return hashlib.sha256(doc.encode()).hexdigest()[:CASE_ID_CHARS]


def _is_key_path(key: str) -> bool:
    return "." in key or "[" in key


# ---- reading ---------------------------------------------------------------------------------

def load_sweep(path) -> SweepSpec:
    """Read and validate a sweep file, and read its base scene's text.

    Raises:
        InputError: unreadable file, TOML error or any invalid entry, naming the key.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"sweep file not found: {p}")
    if not p.is_file():
        raise InputError(f"{p} is not a file")
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read {p}: {exc.__class__.__name__}") from None
    return parse_sweep(text, source=str(p), base_dir=p.parent)


def parse_sweep(text: str, source: str = "<string>", base_dir: Path | str = ".") -> SweepSpec:
    """Validate the text of a sweep file.

    Args:
        text: TOML text.
        source: Where it comes from (messages, default name).
        base_dir: Folder the base scene's path is relative to.

    Raises:
        InputError: naming the key.
    """
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: TOML syntax error: {exc}") from None
    _check_keys(doc, TOP_KEYS, "")
    sw = _table(doc.get("sweep"), "sweep", "[sweep] table")
    _check_keys(sw, SWEEP_KEYS, "sweep")
    scene_path, scene_text = _scene(sw, Path(base_dir))
    name = sw.get("name", Path(source).stem if source != "<string>" else "sweep")
    if not isinstance(name, str):
        raise InputError(f"must be a string, got {short_repr(name)}", "sweep.name")
    combine = sw.get("combine", "grid")
    if combine not in COMBINE_MODES:
        raise InputError(f"must be \"grid\" or \"zip\", got {short_repr(combine)}",
                         "sweep.combine")
    trajectories = sw.get("trajectories", False)
    if not isinstance(trajectories, bool):
        raise InputError(f"must be true or false, got {short_repr(trajectories)}",
                         "sweep.trajectories")
    summaries = _summaries(sw)
    seeds = _seeds(sw["seeds"]) if "seeds" in sw else None

    vary_doc = _table(doc.get("vary"), "vary", "[vary] table of swept keys")
    if not vary_doc:
        raise InputError("is empty: give at least one key to sweep", "vary")
    vary = {k: _values(k, v) for k, v in vary_doc.items()}
    set_doc = doc.get("set", {})
    if not isinstance(set_doc, dict):
        raise InputError("must be a table of key path = expression", "set")
    templates, used = {}, set()
    for path, value in set_doc.items():
        key = f"set.{path}"
        parse_key_path_checked(path, key)
        if path in vary:
            raise InputError("is also swept in [vary]: give it in one place only", key)
        templates[path] = _template(value, key, used)
    for name_ in sorted(used - set(vary)):
        raise InputError(f"uses '{name_}', which is not a [vary] key"
                         f"{did_you_mean(name_, vary)}", _user_of(name_, set_doc))
    for k in vary:
        if _is_key_path(k):
            parse_key_path_checked(k, f"vary.{k}")
        elif k not in used:
            raise InputError("is neither a scene key path (like contacts[0].sliding_friction) "
                             "nor a parameter that a [set] expression uses", f"vary.{k}")
    if seeds is not None and (SEED_KEY in vary or SEED_KEY in templates):
        raise InputError(f"{SEED_KEY} is also set by sweep.seeds: give it in one place only",
                         "sweep.seeds")
    sizes = [len(v) for v in vary.values()]
    if combine == "zip" and len(set(sizes)) > 1:
        listing = ", ".join(f"{k}: {n}" for k, n in zip(vary, sizes, strict=True))
        raise InputError(f"combine = \"zip\" needs [vary] lists of one length, got {listing}",
                         "vary")
    total = (sizes[0] if combine == "zip" else math.prod(sizes)) * len(seeds or [None])
    if total > MAX_CASES:
        raise InputError(f"the sweep has {total:,} cases, more than the limit of "
                         f"{MAX_CASES:,}", "vary")
    spec = SweepSpec(name=name, source=source, text=text, scene_path=scene_path,
                     scene_text=scene_text, combine=combine, vary=vary, set=templates,
                     seeds=seeds, summaries=summaries, trajectories=trajectories)
    _check_paths(spec)
    return spec


def parse_key_path_checked(path: str, key: str) -> None:
    """Check a key path's syntax; errors name the sweep-file key."""
    try:
        parse_key_path(path)
    except InputError as exc:
        raise InputError(f"bad key path: {exc}", key) from None


def _check_paths(spec: SweepSpec) -> None:
    """The first case must make a valid scene: every override path leads somewhere in the base
    scene, and the scene with the first case's values passes validation (a later case with a
    bad value is a failed case, recorded, not a bad sweep file)."""
    case = spec.cases()[0]
    try:
        parse_scene(spec.scene_text, source=str(spec.scene_path), overrides=case.overrides)
    except InputError as exc:
        path = names_override(exc.key, case.overrides) or ""
        where = f"vary.{path}" if path in spec.vary else (
            f"set.{path}" if path in spec.set else ("sweep.seeds" if path == SEED_KEY
                                                    else "sweep.scene"))
        raise InputError(f"{exc} (first case of the sweep)", where) from None


def _user_of(name: str, set_doc: dict) -> str:
    for path, value in set_doc.items():
        if name in json.dumps(value):
            return f"set.{path}"
    return "set"


# ---- pieces ------------------------------------------------------------------------------

def _check_keys(table: dict, allowed, key: str) -> None:
    for k in table:
        if k not in allowed:
            path = f"{key}.{k}" if key else k
            raise InputError(f"unknown key '{k}'{did_you_mean(k, allowed)}; allowed: "
                             f"{', '.join(allowed)}", path)


def _table(value, key: str, what: str) -> dict:
    if value is None:
        raise InputError(f"missing {what}", key)
    if not isinstance(value, dict):
        raise InputError(f"must be a {what}, got {short_repr(value)}", key)
    return value


def _scene(sw: dict, base: Path) -> tuple[Path, str]:
    if "scene" not in sw:
        raise InputError("missing value (path of the base scene file)", "sweep.scene")
    if not isinstance(sw["scene"], str) or not sw["scene"]:
        raise InputError(f"must be the path of a scene file, got {short_repr(sw['scene'])}",
                         "sweep.scene")
    path = base / sw["scene"]
    if not path.is_file():
        raise InputError(f"base scene not found: {path}", "sweep.scene")
    try:
        return path, path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read {path}: {exc.__class__.__name__}", "sweep.scene") from None


def _summaries(sw: dict) -> list[str]:
    names = sw.get("summaries")
    if names is None:
        raise InputError(f"missing value: a list of summary quantities from "
                         f"{', '.join(SUMMARIES)}", "sweep.summaries")
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise InputError(f"must be a non-empty list of names, got {short_repr(names)}",
                         "sweep.summaries")
    for k, n in enumerate(names):
        if n not in SUMMARIES:
            raise InputError(f"unknown summary '{n}'{did_you_mean(n, SUMMARIES)}; known: "
                             f"{', '.join(SUMMARIES)}", f"sweep.summaries[{k}]")
    if len(set(names)) != len(names):
        raise InputError("lists a summary twice", "sweep.summaries")
    return list(names)


def _seeds(value) -> list[int]:
    key = "sweep.seeds"
    if isinstance(value, dict):
        _check_keys(value, SEED_RANGE_KEYS, key)
        start, count = value.get("start", 0), value.get("count")
        for k, v in (("start", start), ("count", count)):
            if isinstance(v, bool) or not isinstance(v, int) or v < (1 if k == "count" else 0):
                raise InputError(f"must be a whole number >= {1 if k == 'count' else 0}, got "
                                 f"{short_repr(v)}", f"{key}.{k}")
        return list(range(start, start + count))
    if not isinstance(value, list) or not value:
        raise InputError(f"must be a non-empty list of seeds or {{ start, count }}, got "
                         f"{short_repr(value)}", key)
    for k, s in enumerate(value):
        if isinstance(s, bool) or not isinstance(s, int) or s < 0:
            raise InputError(f"must be a whole number >= 0, got {short_repr(s)}", f"{key}[{k}]")
    if len(set(value)) != len(value):
        raise InputError("lists a seed twice", key)
    return list(value)


def _values(name: str, value) -> list:
    """The values of one [vary] entry: a list, or a range table."""
    key = f"vary.{name}"
    if isinstance(value, list):
        if not value:
            raise InputError("is an empty list: give at least one value", key)
        return value
    if not isinstance(value, dict):
        raise InputError(f"must be a list of values or a range {{ start, stop, num }}, got "
                         f"{short_repr(value)}", key)
    _check_keys(value, RANGE_KEYS, key)
    for k in ("start", "stop"):
        if k not in value:
            raise InputError("missing value (a range needs start, stop and num or step)",
                             f"{key}.{k}")
    start = check_number(value["start"], f"{key}.start")
    stop = check_number(value["stop"], f"{key}.stop")
    log = value.get("log", False)
    if not isinstance(log, bool):
        raise InputError(f"must be true or false, got {short_repr(log)}", f"{key}.log")
    if ("num" in value) == ("step" in value):
        raise InputError("a range needs exactly one of num and step", key)
    if "step" in value:
        if log:
            raise InputError("log = true needs num, not step", f"{key}.step")
        step = check_number(value["step"], f"{key}.step")
        if step == 0.0 or (stop - start) / step < 0.0:
            raise InputError(f"must be non-zero and lead from start to stop, got {step!r}",
                             f"{key}.step")
        count = math.floor((stop - start) / step * (1.0 + STEP_END_SLACK) + STEP_END_SLACK) + 1
        if count > MAX_CASES:
            raise InputError(f"gives {count:,} values, more than {MAX_CASES:,}", f"{key}.step")
        return [start + k * step for k in range(count)]
    num = value["num"]
    if isinstance(num, bool) or not isinstance(num, int) or num < 1:
        raise InputError(f"must be a whole number >= 1, got {short_repr(num)}", f"{key}.num")
    if num > MAX_CASES:
        raise InputError(f"must be at most {MAX_CASES:,}, got {num:,}", f"{key}.num")
    if num == 1:
        return [start]
    if log:
        if start <= 0.0 or stop <= 0.0:
            raise InputError("log = true needs start > 0 and stop > 0", key)
        ratio = math.log(stop / start) / (num - 1)
        inner = [start * math.exp(k * ratio) for k in range(1, num - 1)]
    else:
        inner = [start + k * (stop - start) / (num - 1) for k in range(1, num - 1)]
    return [start, *inner, stop]


def _template(value, key: str, used: set):
    """A [set] value: strings become parsed expressions, lists are templates element-wise."""
    if isinstance(value, str):
        tree = expr.parse_expression(value, key)
        used |= expr.names_used(tree)
        return tree
    if isinstance(value, list):
        return [_template(v, f"{key}[{k}]", used) for k, v in enumerate(value)]
    if isinstance(value, dict):
        return {k: _template(v, f"{key}.{k}", used) for k, v in value.items()}
    return value


def _fill(template, params: dict, key: str):
    if isinstance(template, list):
        return [_fill(v, params, f"{key}[{k}]") for k, v in enumerate(template)]
    if isinstance(template, dict):
        return {k: _fill(v, params, f"{key}.{k}") for k, v in template.items()}
    if isinstance(template, ast.Expression):
        return expr.evaluate(template, params, key)
    return template
