"""``hsgran plot``: what the figure holds (read back from its matplotlib artists), the files it
writes, and bad input. matplotlib runs in-process on its Agg canvas (no display, no GL)."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from hsgran import plot as hplot
from hsgran.cli import main
from hsgran.events.kinds import EV_PAIR, EV_STATE, EV_WALL
from hsgran.io.h5md import TrajectoryWriter, read_trajectory
from tests.cli_errors import run_error

pytest.importorskip("matplotlib")

ROOT = Path(__file__).resolve().parents[1]
G = 9.81
SCENE = """
[scene]
name = "two balls"
duration = 1.0
[output]
frame_interval = 0.01
[[particles]]
material = "steel"
radius = 0.01
position = [0.0, 0.0, 1.0]
"""


def write(path, n=2, frames=101, events=True, rotation=True):
    """n spheres in free fall from heights 1, 2, ... m (exact energies), optional events."""
    t = np.linspace(0.0, 1.0, frames)
    mass = np.full(n, 0.03)
    z0 = 1.0 + np.arange(n)
    position = np.zeros((frames, n, 3))
    position[:, :, 2] = z0 - 0.5 * G * t[:, None] ** 2
    velocity = np.zeros((frames, n, 3))
    velocity[:, :, 2] = -G * t[:, None]
    omega = np.zeros((frames, n, 3))
    omega[:, :, 1] = 10.0 * np.arange(1, n + 1)
    kinetic = 0.5 * mass.sum() * (G * t) ** 2
    potential = G * (mass * position[:, :, 2]).sum(axis=1)
    rotational = np.full(frames, 0.5 * (0.4 * 0.03 * 0.01**2) * (omega[0, :, 1] ** 2).sum())
    with TrajectoryWriter(
            path, radius=np.full(n, 0.01), mass=mass, material=np.zeros(n, dtype=int),
            material_names=["steel"], box_lower=None, box_upper=None,
            periodic=(False, False, False), angular_velocity=rotation, scene_text=SCENE,
            effects=["gravity", "rotation"], seed=0, version="test",
            log_events=events) as w:
        w.append_frames(dict(step=np.arange(frames), time=t, position=position,
                             velocity=velocity, angular_velocity=omega if rotation else None,
                             kinetic_translational=kinetic,
                             kinetic_rotational=rotational if rotation else None,
                             potential=potential, dissipated=np.zeros(frames)))
        if events:
            # particle 0: a pair collision with 1 at 0.2 s, a wall collision at 0.5 s, a state
            # change at 0.75 s; particle 1 only the pair collision
            w.append_events(dict(time=np.array([0.2, 0.5, 0.75]),
                                 kind=np.array([EV_PAIR, EV_WALL, EV_STATE]),
                                 i=np.array([0, 0, 0]), j=np.array([1, -1, -1]),
                                 normal_impulse=np.zeros(3), tangential_impulse=np.zeros(3),
                                 e_n=np.array([1.0, 1.0, np.nan]), stage=np.zeros(3, dtype=int),
                                 regime=np.zeros(3, dtype=int), velocity=np.zeros((3, 3))))
    return path


def curves(ax) -> dict:
    """Label → y data of every drawn (not marker-only) line of an axes."""
    return {line.get_label(): line.get_ydata() for line in ax.get_lines()
            if line.get_linestyle() != "None"}


def markers(ax):
    """(x, y) of every marker-only line of an axes."""
    return [line.get_xydata() for line in ax.get_lines() if line.get_linestyle() == "None"
            and line.get_marker() not in (None, "None", "")]


def test_energy_panel_draws_every_energy_and_their_balanced_sum(tmp_path):
    traj = read_trajectory(write(tmp_path / "fall.h5"))
    fig = hplot.figure(traj, [])
    (ax,) = fig.axes
    lines = curves(ax)
    assert set(lines) == {"translational kinetic", "rotational kinetic",
                          "potential (change since start)", "dissipated", "sum"}
    e = traj.energies
    np.testing.assert_allclose(lines["potential (change since start)"],
                               e["potential_energy"] - e["potential_energy"][0])
    # free fall: kinetic gained = potential lost, so the sum stays at the initial energy
    np.testing.assert_allclose(lines["sum"], lines["sum"][0], atol=1e-12)
    assert lines["sum"][0] == pytest.approx(e["kinetic_energy_rotational"][0])


def test_few_particles_get_height_speed_and_spin_with_their_events_marked(tmp_path):
    traj = read_trajectory(write(tmp_path / "fall.h5"))
    fig = hplot.figure(traj, hplot.select_particles(None, traj.n_particles), title="two balls")
    _, height, speed, spin = fig.axes
    assert [ax.get_ylabel() for ax in fig.axes[1:]] == ["height z [m]", "speed [m/s]",
                                                         "spin |ω| [rad/s]"]
    np.testing.assert_allclose(curves(height)["particle 0"], traj.position[:, 0, 2])
    np.testing.assert_allclose(curves(speed)["particle 1"], G * traj.time)
    np.testing.assert_allclose(curves(spin)["particle 1"], 20.0)
    # particle 0 has three events (pair, wall, state), particle 1 one (pair): four markers,
    # each on its particle's curve at the event's time
    points = np.concatenate(markers(height))
    assert sorted(points[:, 0].tolist()) == [0.2, 0.2, 0.5, 0.75]
    for t, z in points:
        on_0 = np.interp(t, traj.time, traj.position[:, 0, 2])
        on_1 = np.interp(t, traj.time, traj.position[:, 1, 2])
        assert min(abs(z - on_0), abs(z - on_1)) < 1e-12
    labels = height.get_legend().get_texts()
    assert [t.get_text() for t in labels] == ["particle 0", "particle 1",
                                              "sphere-sphere collision", "wall collision",
                                              "motion-state change"]
    assert fig.get_suptitle() == "two balls"


def test_many_particles_get_the_energy_panel_only_unless_picked(tmp_path):
    traj = read_trajectory(write(tmp_path / "many.h5", n=hplot.FEW_PARTICLES + 1))
    assert hplot.select_particles(None, traj.n_particles) == []
    assert len(hplot.figure(traj, []).axes) == 1
    assert hplot.select_particles("3, 1,3", traj.n_particles) == [1, 3]
    assert len(hplot.figure(traj, [1, 3]).axes) == 4


def test_without_event_log_the_figure_says_how_to_get_one(tmp_path):
    traj = read_trajectory(write(tmp_path / "quiet.h5", events=False, rotation=False))
    fig = hplot.figure(traj, [0])
    assert len(fig.axes) == 3                          # no spin without rotation
    assert "--events" in fig.get_suptitle()
    assert markers(fig.axes[1]) == []


def test_cli_writes_a_png_of_the_expected_size(tmp_path, capsys):
    import imageio.v3 as iio

    src = write(tmp_path / "fall.h5")
    assert main(["plot", str(src), "-o", str(tmp_path / "fig.png")]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'fig.png'}"
    image = iio.imread(tmp_path / "fig.png")
    height = (hplot.PANEL_HEIGHT * 4 + 0.8) * hplot.DPI
    assert image.shape[:2] == (round(height), round(hplot.FIGURE_WIDTH * hplot.DPI))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fall.h5", "fig.png"]


def test_cli_default_name_and_pdf(tmp_path):
    src = write(tmp_path / "fall.h5")
    assert main(["plot", str(src)]) == 0
    assert (tmp_path / "fall.png").is_file()
    assert main(["plot", str(src), "-o", str(tmp_path / "fig.pdf")]) == 0
    assert (tmp_path / "fig.pdf").read_bytes().startswith(b"%PDF")


def test_engine_run_marks_the_slide_to_roll_transition(tmp_path):
    from hsgran.api import run_scene

    out = tmp_path / "plate.h5"
    run_scene(ROOT / "scenarios" / "sphere_on_plate.toml", out, until=0.3, log_events=True,
              force=True)
    traj = read_trajectory(out)
    fig = hplot.figure(traj, [0])
    (points,) = markers(fig.axes[2])                  # speed panel: one state change
    # the slip vanishes at t1 = 0.0995 s (scenarios/sphere_on_plate.toml)
    assert points[0, 0] == pytest.approx(0.0995, abs=1e-3)




def test_help_states_the_real_threshold():
    from hsgran.cli import build_parser

    text = " ".join(build_parser().commands["plot"].format_help().split())
    assert f"at most {hplot.FEW_PARTICLES} particles" in text
    assert f"at most {hplot.FEW_PARTICLES})" in text


def test_bad_input_is_one_line_exit_2(tmp_path, capsys):
    src = write(tmp_path / "fall.h5")
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["x"] = 1
    assert "not found" in run_error(capsys, ["plot", str(tmp_path / "nope.h5")])
    assert "not an hsgran" in run_error(capsys, ["plot", str(other)])
    assert "--particles" in run_error(capsys, ["plot", str(src), "--particles", "0,5"])
    assert "--particles" in run_error(capsys, ["plot", str(src), "--particles", "first"])
    assert "unknown figure type" in run_error(capsys, ["plot", str(src), "-o",
                                                       str(tmp_path / "f.bmp")])
    (tmp_path / "fig.png").write_bytes(b"old")
    assert "--force" in run_error(capsys, ["plot", str(src), "-o", str(tmp_path / "fig.png")])
    assert (tmp_path / "fig.png").read_bytes() == b"old"
