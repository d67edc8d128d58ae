"""Every shipped scenario loads and runs through ``hsgran run`` and writes a readable trajectory.

The runs are cut short with ``--until`` (the full runs are what the README shows); the scenes'
own durations are run by the slow test at the end.
"""

from pathlib import Path

import numpy as np
import pytest

from hsgran.cli import main
from hsgran.io.h5md import read_trajectory
from hsgran.scene import load_scene

SCENARIOS = sorted((Path(__file__).parents[1] / "scenarios").glob("*.toml"))
#: Simulated time of the short runs [s]: a few frames of every scenario, seconds of wall time.
SHORT = 0.01


def test_the_issue_scenarios_are_shipped():
    names = {p.stem for p in SCENARIOS}
    assert {"steel_ball_on_glass", "granular_gas", "falling_box", "sphere_on_plate"} <= names


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_scenario_runs_and_writes_h5md(path, tmp_path, capsys):
    scene = load_scene(path)
    out = tmp_path / "out.h5"
    code = main(["run", str(path), "-o", str(out), "--until", str(SHORT), "--events",
                 "--no-progress"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "events/s" in printed
    traj = read_trajectory(out)
    assert traj.complete
    n_frames = int(np.floor(SHORT / scene.frame_interval + 1e-9)) + 1
    assert traj.position.shape == (n_frames, scene.n, 3)
    assert np.all(np.isfinite(traj.position))
    np.testing.assert_array_equal(traj.position[0], scene.position)
    assert traj.scene_text == scene.text


@pytest.mark.slow
@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_scenario_runs_its_whole_duration(path, tmp_path):
    out = tmp_path / "out.h5"
    assert main(["run", str(path), "-o", str(out), "--no-progress"]) == 0
    assert read_trajectory(out).complete
