"""Input that cannot break hsgran: generated scene files and damaged trajectory files.

Whatever the input, the command line ends with exit code 0 or 2 and, on 2, one line on stderr;
never a traceback (an exception escaping :func:`hsgran.cli.main` fails these tests outright).
Scenes are mutations of a small valid one (values swapped for junk of every type, keys deleted
or misspelt, tables emptied, the text cut or garbled); trajectories are a valid file truncated or
with bytes overwritten, given to ``plot`` and ``run --resume``.
"""

from __future__ import annotations

import copy
import math
import os
import tomllib

import hypothesis.strategies as st
import pytest
from hypothesis import HealthCheck, given, settings

from hsgran.api import run_scene
from hsgran.cli import main

NOJIT = os.environ.get("NUMBA_DISABLE_JIT") == "1"
#: Generated cases per test: each runs the command line once (a tiny scene, a few ms of
#: simulated time); fewer without the compiled engine, which is ~100x slower. The suite's cases
#: are the same at every run (derandomized); a longer campaign with fresh cases:
#: ``HSGRAN_FUZZ_EXAMPLES=2000 pytest tests/test_fuzz.py``.
EXAMPLES = int(os.environ.get("HSGRAN_FUZZ_EXAMPLES", 25 if NOJIT else 80))
FUZZ_SETTINGS = settings(max_examples=EXAMPLES, deadline=None,
                         derandomize="HSGRAN_FUZZ_EXAMPLES" not in os.environ,
                         suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                HealthCheck.too_slow])

BASE = """
[scene]
name = "fuzz"
duration = 0.004
gravity = [0.0, 0.0, -9.81]
effects = ["gravity", "rotation", "friction", "plasticity"]
seed = 1
[output]
frame_interval = 0.001
[[contacts]]
between = ["steel", "glass"]
sliding_friction = 0.3
restitution = 0.8
[[contacts]]
between = ["steel", "steel"]
sliding_friction = 0.2
[materials.rubberish]
density = 1200.0
youngs_modulus = 5e7
poisson_ratio = 0.45
yield_stress = 1e7
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.01, 0.01, 0.01]
material = "glass"
[[particles]]
material = "steel"
radius = 0.001
position = [0.005, 0.005, 0.0011]
velocity = [0.1, 0.0, -0.2]
angular_velocity = [0.0, 3.0, 0.0]
[[fill]]
count = 3
material = "steel"
radius = [0.0005, 0.0008]
region = { lower = [0.0, 0.0, 0.004], upper = [0.01, 0.01, 0.01] }
speed = 0.1
"""

JUNK = st.one_of(
    st.none(), st.booleans(), st.integers(-10**12, 10**12),
    st.sampled_from([0.0, -0.0, -1.0, 1e-300, 1e300, -1e300, math.nan, math.inf, -math.inf,
                     1e9, 1e-9, 3.5]),
    st.text(max_size=12), st.lists(st.floats(allow_nan=True), max_size=5),
    st.sampled_from([[], {}, {"x": 1}, [[1.0, 2.0]], ["steel", "glass"], ["gravity"],
                     ["rotation", "friction"], ["adhesion"], [True, False, True]]),
)


def _paths(node, prefix=()):
    """Every key path of a parsed TOML document (tables, arrays and leaves)."""
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, (*prefix, i))


def _toml_value(v) -> str:
    if v is None:
        return '""'
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return '"' + v.encode("unicode_escape").decode("ascii").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f'"{k}" = {_toml_value(x)}' for k, x in v.items()) + "}"
    raise TypeError(v)


def _toml(doc: dict) -> str:
    """A TOML document written as inline values under each top-level key."""
    lines = []
    for key, value in doc.items():
        if isinstance(value, dict) and all(isinstance(x, dict) for x in value.values()) \
                and value:
            for sub, table in value.items():
                lines.append(f'[{key}."{sub}"]')
                lines += [f'"{k}" = {_toml_value(v)}' for k, v in table.items()]
        elif isinstance(value, dict):
            lines.append(f'[{key}]')
            lines += [f'"{k}" = {_toml_value(v)}' for k, v in value.items()]
        elif isinstance(value, list) and value and all(isinstance(x, dict) for x in value):
            for table in value:
                lines.append(f'[[{key}]]')
                lines += [f'"{k}" = {_toml_value(v)}' for k, v in table.items()]
        else:
            lines.insert(0, f'"{key}" = {_toml_value(value)}')
    return "\n".join(lines) + "\n"


@st.composite
def scenes(draw):
    """Scene text: the base with 1–3 mutations of its parsed document, or its text garbled."""
    if draw(st.integers(0, 9)) == 0:
        text = BASE
        cut = draw(st.integers(0, len(text)))
        junk = draw(st.text(max_size=8))
        return text[:cut] + junk + text[cut + draw(st.integers(0, 20)):]
    doc = copy.deepcopy(tomllib.loads(BASE))
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(doc) if p]
        path = draw(st.sampled_from(paths))
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        action = draw(st.sampled_from(["junk", "junk", "delete", "rename", "duplicate"]))
        last = path[-1]
        if action == "junk":
            parent[last] = draw(JUNK)
        elif action == "delete":
            del parent[last]
        elif action == "rename" and isinstance(parent, dict):
            parent[last + draw(st.sampled_from(["s", "_", "x"]))] = parent.pop(last)
        elif action == "duplicate" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[last]))
    return _toml(doc)


def _cli(capsys, argv) -> int:
    code = main(argv)
    _, err = capsys.readouterr()
    assert code in (0, 2), (code, err)
    assert "Traceback" not in err
    if code == 2:
        assert err.startswith("hsgran: error: "), err
        assert err.count("\n") == 1, err
    return code


def test_the_base_scene_is_valid(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(_toml(tomllib.loads(BASE)))
    assert _cli(capsys, ["run", str(path), "--no-progress"]) == 0


@FUZZ_SETTINGS
@given(text=scenes())
def test_any_scene_file_runs_or_is_refused_in_one_line(tmp_path, capsys, text):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    out = tmp_path / "out.h5"
    if out.exists():
        out.unlink()
    code = _cli(capsys, ["run", str(path), "-o", str(out), "--no-progress"])
    assert out.exists() == (code == 0)  # refused: no file, not even half of one


@pytest.fixture(scope="module")
def trajectory(tmp_path_factory):
    """A valid trajectory with an event log and checkpoints (a path: hypothesis would print
    its bytes in a failure report)."""
    d = tmp_path_factory.mktemp("fuzz")
    (d / "scene.toml").write_text(BASE)
    run_scene(d / "scene.toml", d / "good.h5", log_events=True, checkpoint_every=0.001)
    return d / "good.h5"


@FUZZ_SETTINGS
@given(data=st.data())
def test_any_damaged_trajectory_is_read_or_refused_in_one_line(tmp_path, capsys, trajectory,
                                                               data):
    raw = bytearray(trajectory.read_bytes())
    if data.draw(st.booleans(), label="truncate"):
        raw = raw[:data.draw(st.integers(0, len(raw) - 1), label="length")]
    else:
        for _ in range(data.draw(st.integers(1, 16), label="hits")):
            at = data.draw(st.integers(0, len(raw) - 1), label="offset")
            raw[at] = data.draw(st.integers(0, 255), label="byte")
    path = tmp_path / "damaged.h5"
    path.write_bytes(bytes(raw))
    for name in ("damaged.png", "damaged.h5.resume-tmp"):
        (tmp_path / name).unlink(missing_ok=True)
    _cli(capsys, ["plot", str(path), "-o", str(tmp_path / "damaged.png"), "--force"])
    _cli(capsys, ["run", "--resume", str(path), "--until", "0.005", "--no-progress"])
