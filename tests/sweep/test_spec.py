"""Sweep files: expansion into cases, and bad input as one line with exit code 2."""

from __future__ import annotations

import math

import pytest

from hsgran.errors import InputError
from hsgran.sweep.spec import load_sweep, parse_sweep
from tests.cli_errors import run_error
from tests.sweep.scenes import write


def spec_of(tmp_path, text):
    write(tmp_path)
    return parse_sweep(text, source=str(tmp_path / "s.toml"), base_dir=tmp_path)


def test_grid_crosses_every_value_first_key_slowest(tmp_path):
    cases = load_sweep(write(tmp_path)).cases()
    assert [(c.params["contacts[0].sliding_friction"], c.params["angle"]) for c in cases] == [
        (0.1, 10.0), (0.1, 30.0), (0.1, 50.0), (0.3, 10.0), (0.3, 30.0), (0.3, 50.0)]
    c = cases[4]
    assert c.overrides["contacts[0].sliding_friction"] == 0.3
    assert c.overrides["particles[0].velocity"] == [2 * math.sin(math.radians(30.0)), 0.0,
                                                    -2 * math.cos(math.radians(30.0))]
    assert len({c.case_id for c in cases}) == 6


def test_case_ids_are_stable_and_depend_on_the_scene(tmp_path):
    first = [c.case_id for c in load_sweep(write(tmp_path)).cases()]
    assert first == [c.case_id for c in load_sweep(write(tmp_path)).cases()]
    other = load_sweep(write(tmp_path, scene=(tmp_path / "ball.toml").read_text() + "\n#\n"))
    assert not set(first) & {c.case_id for c in other.cases()}


def test_zip_ranges_and_seeds(tmp_path):
    spec = spec_of(tmp_path, """
[sweep]
scene = "ball.toml"
combine = "zip"
seeds = { start = 3, count = 2 }
summaries = ["e_n"]
[vary]
"contacts[0].sliding_friction" = { start = 0.1, stop = 0.3, step = 0.1 }
"particles[0].radius" = { start = 0.001, stop = 0.004, num = 3 }
""")
    cases = spec.cases()
    assert len(cases) == 6
    assert [c.seed for c in cases] == [3, 4] * 3
    assert [c.overrides["scene.seed"] for c in cases] == [3, 4] * 3
    assert [c.params["contacts[0].sliding_friction"] for c in cases[::2]] == pytest.approx(
        [0.1, 0.2, 0.3], rel=1e-15)
    assert [c.params["particles[0].radius"] for c in cases[::2]] == [0.001, 0.0025, 0.004]


def test_log_range_ends_exactly(tmp_path):
    spec = spec_of(tmp_path, """
[sweep]
scene = "ball.toml"
summaries = ["e_n"]
[vary]
v = { start = 0.01, stop = 100.0, num = 5, log = true }
[set]
"particles[0].velocity" = [0, 0, "-v"]
""")
    assert spec.vary["v"] == pytest.approx([0.01, 0.1, 1.0, 10.0, 100.0], rel=1e-12)
    assert spec.vary["v"][0] == 0.01
    assert spec.vary["v"][-1] == 100.0


BAD = [
    ('[sweep]\nscene = "ball.toml"\nsumaries = ["e_n"]\n[vary]\n"scene.duration" = [1.0]\n',
     "sweep.sumaries: unknown key 'sumaries' (did you mean 'summaries'?)"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n[vary]\n"particles[4].radius" = [1.0]\n',
     "vary.particles[4].radius: particles[4].radius: index 4 out of range"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n[vary]\n"particles[0]..radius" = [1]\n',
     "vary.particles[0]..radius: bad key path"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n[vary]\n"scene.duration" = []\n',
     "vary.scene.duration: is an empty list"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n[vary]\n'
     '"scene.duration" = { start = "a", stop = 2, num = 3 }\n',
     "vary.scene.duration.start: must be a number, got 'a'"),
    ('[sweep]\nscene = "nowhere.toml"\nsummaries = ["e_n"]\n[vary]\n"scene.duration" = [1.0]\n',
     "sweep.scene: base scene not found"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["rebound_angel"]\n[vary]\n'
     '"scene.duration" = [1.0]\n',
     "sweep.summaries[0]: unknown summary 'rebound_angel' (did you mean 'rebound_angle'?)"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n[vary]\nangle = [1.0]\n',
     "vary.angle: is neither a scene key path"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n[vary]\nangle = [1.0]\n[set]\n'
     '"particles[0].radius" = "angel * 0.001"\n', "set.particles[0].radius: uses 'angel'"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n[vary]\nangle = [1.0]\n[set]\n'
     '"particles[0].radius" = "__import__(\'os\')"\n', "unknown function '__import__'"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\ncombine = "zip"\n[vary]\n'
     '"scene.duration" = [1.0, 2.0]\n"scene.seed" = [1]\n', "combine = \"zip\" needs"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n[vary]\n'
     '"contacts[0].slidng_friction" = [0.2]\n', "did you mean 'sliding_friction'"),
    ('[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n', "vary: missing [vary] table"),
    ('[sweep\n', "TOML syntax error"),
]


@pytest.mark.parametrize(("text", "message"), BAD)
def test_bad_sweep_files_exit_2_with_one_line(tmp_path, capsys, text, message):
    write(tmp_path, sweep=text)
    err = run_error(capsys, ["sweep", str(tmp_path / "sweep.toml"), "-o",
                             str(tmp_path / "out"), "--no-progress"])
    assert message in err


def test_output_that_is_a_file_exits_2(tmp_path, capsys):
    sweep = write(tmp_path)
    (tmp_path / "out").write_text("")
    err = run_error(capsys, ["sweep", str(sweep), "-o", str(tmp_path / "out")])
    assert "-o: " in err
    assert "is a file, not a folder" in err


def test_missing_sweep_file_and_bad_workers_exit_2(tmp_path, capsys):
    assert "sweep file not found" in run_error(
        capsys, ["sweep", str(tmp_path / "none.toml"), "-o", str(tmp_path / "o")])
    sweep = write(tmp_path)
    assert "--workers: must be a whole number >= 1" in run_error(
        capsys, ["sweep", str(sweep), "-o", str(tmp_path / "o"), "--workers", "0"])


def test_expression_errors_name_the_set_key(tmp_path):
    with pytest.raises(InputError) as err:
        spec_of(tmp_path, '[sweep]\nscene = "ball.toml"\nsummaries = ["e_n"]\n[vary]\n'
                          'x = [0.0]\n[set]\n"particles[0].radius" = "1 / x"\n')
    assert err.value.key == "set.particles[0].radius"
    assert "division by zero" in str(err.value)


def test_sweep_help_points_to_the_docs(capsys):
    from hsgran.cli import main

    assert main(["sweep", "--help"]) == 0
    out = capsys.readouterr().out
    for text in ("docs/sweeps.md", "[vary]", "rebound_angle"):
        assert text in out


@pytest.mark.parametrize(("name", "cases"), [("kharaz_angle.toml", 45),
                                             ("normal_speed.toml", 25)])
def test_shipped_example_sweeps_load(name, cases):
    from pathlib import Path

    spec = load_sweep(Path(__file__).resolve().parents[2] / "scenarios" / "sweeps" / name)
    assert len(spec.cases()) == cases
