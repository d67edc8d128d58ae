"""hsgran.animation: what a movie frame shows, checked without a GL context.

Trajectories here are plain namespaces with the attributes :class:`Playback` reads, so the
tests do not depend on the file format.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hsgran import animation as an
from hsgran.contact.tangential import REGIME_ROLLING, REGIME_SLIDING
from hsgran.errors import InputError
from hsgran.events.kinds import EV_PAIR, EV_STATE, EV_WALL
from hsgran.onplane import MS_FLIGHT, MS_ROLLING, MS_SLIDING
from hsgran.scene import Plane

G = 9.81


def fake(time, position, velocity, *, radius=0.01, omega=None, events=None, motion_state=None,
         box=None, periodic=(False, False, False), effects=("gravity",)):
    time = np.asarray(time, dtype=float)
    position = np.asarray(position, dtype=float)
    n = position.shape[1]
    return SimpleNamespace(
        time=time, position=position, velocity=np.asarray(velocity, dtype=float),
        angular_velocity=None if omega is None else np.asarray(omega, dtype=float),
        radius=np.full(n, radius), material=np.zeros(n, dtype=int), material_names=["steel"],
        box_lower=None if box is None else np.asarray(box[0], dtype=float),
        box_upper=None if box is None else np.asarray(box[1], dtype=float),
        periodic=periodic, events=events, motion_state=motion_state, effects=list(effects),
        n_frames=time.shape[0], n_particles=n)


def thrown(times):
    """One sphere thrown at (1, 0, 2) m/s from the origin under gravity: exact parabola."""
    t = np.asarray(times)[:, None, None]
    v0 = np.array([1.0, 0.0, 2.0])
    a = np.array([0.0, 0.0, -G])
    return v0 * t + 0.5 * a * t**2, v0 + a * t


# ---- sampling ------------------------------------------------------------------------------

def test_default_time_scale_shows_every_stored_frame_once():
    time = np.linspace(0.0, 0.15, 76)
    times = an.sample_times(time, fps=30.0)
    np.testing.assert_allclose(times, time, atol=1e-12)


def test_slow_motion_samples_between_frames_and_ends_at_the_last():
    time = np.linspace(0.0, 1.0, 11)
    times = an.sample_times(time, fps=25.0, time_scale=0.1)   # 4 ms of simulated time per frame
    assert times.shape == (251,)
    assert times[-1] == 1.0
    np.testing.assert_allclose(np.diff(times), 0.004)


def test_start_end_and_at_are_checked_against_the_stored_range():
    time = np.linspace(0.0, 1.0, 11)
    assert an.sample_times(time, fps=10.0, at=0.35).tolist() == [0.35]
    np.testing.assert_allclose(an.sample_times(time, fps=10.0, time_scale=1.0, start=0.2,
                                               end=0.5), [0.2, 0.3, 0.4, 0.5])
    for kwargs, option in ((dict(at=1.5), "--at"), (dict(start=-1.0), "--start"),
                           (dict(start=0.6, end=0.4), "--end"),
                           (dict(time_scale=1e-9), "--time-scale")):
        with pytest.raises(InputError, match=option):
            an.sample_times(time, fps=10.0, **kwargs)


# ---- positions -----------------------------------------------------------------------------

@given(st.floats(0.0, 1.0))
@settings(max_examples=50, deadline=None)
def test_flight_between_frames_is_the_exact_parabola(s):
    frames = np.array([0.0, 0.05, 0.1])
    x, v = thrown(frames)
    play = an.Playback(fake(frames, x, v))
    t = 0.05 + 0.05 * s
    got_x, got_v = play.positions(t)
    want_x, want_v = thrown([t])
    np.testing.assert_allclose(got_x, want_x[0], atol=1e-12)
    np.testing.assert_allclose(got_v, want_v[0], atol=1e-12)


def test_a_bounce_between_frames_moves_on_the_chord():
    # no gravity: falls at 1 m/s onto z = 0 (touching at z = r) at t = 0.03, rebounds at 0.5 m/s;
    # x1 − x0 differs from (v0 + v1)/2 Δt, so the velocity changed abruptly on the way
    r = 0.01
    x = np.array([[[0.0, 0.0, r + 0.03]], [[0.0, 0.0, r + 0.5 * 0.07]]])
    v = np.array([[[0.0, 0.0, -1.0]], [[0.0, 0.0, 0.5]]])
    play = an.Playback(fake([0.0, 0.1], x, v, radius=r, effects=()))
    for t in np.linspace(0.0, 0.1, 21):
        z = play.positions(t)[0][0, 2]
        assert z == pytest.approx(r + 0.03 + 0.05 * t)   # the chord, above the floor
    # the velocity jumps at the middle rather than being averaged into a slow sphere
    assert play.positions(0.04)[1][0, 2] == -1.0
    assert play.positions(0.06)[1][0, 2] == 0.5


def test_periodic_axis_interpolates_the_short_way_round():
    box = ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    x = np.array([[[0.95, 0.5, 0.5]], [[0.05, 0.5, 0.5]]])      # crossed x = 1 → 0
    v = np.array([[[1.0, 0.0, 0.0]], [[1.0, 0.0, 0.0]]])
    play = an.Playback(fake([0.0, 0.1], x, v, box=box, periodic=(True, False, False),
                            effects=()))
    assert play.positions(0.025)[0][0, 0] == pytest.approx(0.975)
    assert play.positions(0.075)[0][0, 0] == pytest.approx(0.025)


# ---- spin ----------------------------------------------------------------------------------

def test_rolling_sphere_turns_by_distance_over_radius_and_a_sliding_one_does_not():
    r, v = 0.01, 0.5
    frames = np.linspace(0.0, 0.2, 5)
    x = np.zeros((5, 2, 3))
    x[:, :, 0] = v * frames[:, None]
    vel = np.broadcast_to([v, 0.0, 0.0], (5, 2, 3))
    omega = np.zeros((5, 2, 3))
    omega[:, 0, 1] = v / r                    # rolling forward along +x on a floor: ω ∥ +y
    play = an.Playback(fake(frames, x, vel, radius=r, omega=omega))
    t = 0.137
    rot = play.rotations(t)
    angle = v * t / r
    c, s = math.cos(angle), math.sin(angle)
    np.testing.assert_allclose(rot[0], [[c, 0, s], [0, 1, 0], [-s, 0, c]], atol=1e-9)
    np.testing.assert_allclose(rot[1], np.eye(3), atol=1e-12)
    # the contact point's body-fixed marker moves backwards then up: no slip at the contact
    bottom = rot[0] @ np.array([0.0, 0.0, -1.0])
    assert bottom[0] == pytest.approx(-math.sin(angle))


def test_spin_that_decreases_linearly_is_integrated_exactly():
    # ω(t) = 100 − 500 t about z: angle(t) = 100 t − 250 t²
    frames = np.array([0.0, 0.1, 0.2])
    omega = np.zeros((3, 1, 3))
    omega[:, 0, 2] = 100.0 - 500.0 * frames
    play = an.Playback(fake(frames, np.zeros((3, 1, 3)), np.zeros((3, 1, 3)), omega=omega))
    for t in (0.03, 0.1, 0.17, 0.2):
        angle = 100.0 * t - 250.0 * t**2
        rot = play.rotations(t)[0]
        assert math.atan2(rot[1, 0], rot[0, 0]) == pytest.approx(
            math.remainder(angle, 2 * math.pi), abs=1e-9)


def test_quaternions_compose_like_rotation_matrices():
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(2, 3))
    qa, qb = an.quaternion_from_rotation_vector(a), an.quaternion_from_rotation_vector(b)
    ra, rb = an.rotation_matrices(qa), an.rotation_matrices(qb)
    np.testing.assert_allclose(an.rotation_matrices(an.quaternion_multiply(qa, qb)), ra @ rb,
                               atol=1e-12)
    np.testing.assert_allclose(ra @ ra.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(ra @ a, a, atol=1e-12)           # the axis stays put


# ---- colours -------------------------------------------------------------------------------

def test_states_are_rebuilt_from_the_event_log_when_the_file_has_none():
    frames = np.array([0.0, 0.1, 0.2, 0.3])
    events = {"time": np.array([0.05, 0.15, 0.25]),
              "kind": np.array([EV_STATE, EV_STATE, EV_WALL]),
              "i": np.array([0, 0, 0]), "j": np.array([-1, -1, -1]),
              "stage": np.array([MS_SLIDING, MS_ROLLING, 0]), "regime": np.zeros(3)}
    traj = fake(frames, np.zeros((4, 1, 3)), np.zeros((4, 1, 3)), events=events)
    assert an.motion_states(traj)[:, 0].tolist() == [MS_FLIGHT, MS_SLIDING, MS_ROLLING,
                                                     MS_FLIGHT]
    stored = np.array([[2], [2], [2], [2]], dtype=np.int8)
    traj.motion_state = stored
    assert an.motion_states(traj)[:, 0].tolist() == [2, 2, 2, 2]
    traj.motion_state, traj.events = None, None
    assert set(an.motion_states(traj).ravel()) == {an.STATE_UNKNOWN}


def test_regime_colour_is_that_of_each_spheres_last_collision():
    frames = np.array([0.0, 0.1, 0.2])
    events = {"time": np.array([0.05, 0.06, 0.15]),
              "kind": np.array([EV_PAIR, EV_WALL, EV_PAIR]),
              "i": np.array([0, 1, 2]), "j": np.array([1, -1, 0]),
              "stage": np.zeros(3), "regime": np.array([REGIME_ROLLING, REGIME_SLIDING,
                                                         REGIME_SLIDING])}
    traj = fake(frames, np.zeros((3, 3, 3)), np.zeros((3, 3, 3)), events=events)
    play = an.Playback(traj, "regime")
    assert play.frame(0.0).values.tolist() == [an.REGIME_NO_COLLISION] * 3
    assert play.frame(0.1).values.tolist() == [REGIME_ROLLING + 1, REGIME_SLIDING + 1,
                                               an.REGIME_NO_COLLISION]
    assert play.frame(0.2).values.tolist() == [REGIME_SLIDING + 1, REGIME_SLIDING + 1,
                                               REGIME_SLIDING + 1]
    # going back in time starts over
    assert play.frame(0.0).values.tolist() == [an.REGIME_NO_COLLISION] * 3


def test_regime_without_events_and_unknown_colour_variables_are_refused():
    traj = fake([0.0], np.zeros((1, 1, 3)), np.zeros((1, 1, 3)))
    with pytest.raises(InputError, match="--events"):
        an.Playback(traj, "regime")
    with pytest.raises(InputError, match="--color-by"):
        an.Playback(traj, "temperature")


# ---- camera --------------------------------------------------------------------------------

@pytest.mark.parametrize("preset", ["iso", "side", "top"])
def test_presets_frame_the_whole_extent_inside_the_picture(preset):
    box = ([0.0, 0.0, 0.0], [0.05, 0.05, 0.10])
    x = np.array([[[0.025, 0.025, 0.05]]])
    traj = fake([0.0], x, np.zeros((1, 1, 3)), box=box)
    size = (1280, 720)
    cam = an.camera_at(an.CameraSpec(preset), traj, size)
    corners = np.array([[a, b, c] for a in (0, 0.05) for b in (0, 0.05) for c in (0, 0.1)])
    px = an.project(corners, cam, size)
    assert np.all(px >= 0)
    assert np.all(px <= np.array(size))
    # and it is tight: some corner reaches the fill fraction's border in one direction
    span = np.max(np.abs(px - np.array(size) / 2) / (np.array(size) / 2), axis=0)
    assert max(span) == pytest.approx(an.FRAME_FILL, rel=1e-6)
    np.testing.assert_allclose(an.project(cam.focal_point, cam, size), np.array(size) / 2)


def test_auto_follows_a_lone_sphere_on_a_long_path_only():
    far = fake([0.0, 1.0], [[[0.0, 0.0, 0.01]], [[3.0, 0.0, 0.01]]], np.zeros((2, 1, 3)))
    near = fake([0.0, 1.0], [[[0.0, 0.0, 0.01]], [[0.05, 0.0, 0.01]]], np.zeros((2, 1, 3)))
    assert an.resolve_camera(an.CameraSpec("auto"), far) == an.CameraSpec("follow", particle=0)
    assert an.resolve_camera(an.CameraSpec("auto"), near) == an.CameraSpec("iso")


@pytest.mark.parametrize(("text", "expected"), [
    ("iso", an.CameraSpec("iso")),
    ("Follow:3", an.CameraSpec("follow", particle=3)),
    ("1,2,3", an.CameraSpec("position", position=(1.0, 2.0, 3.0))),
    ("1,2,3:0,0,0.5", an.CameraSpec("position", position=(1.0, 2.0, 3.0),
                                    focal_point=(0.0, 0.0, 0.5))),
])
def test_camera_values_parse(text, expected):
    assert an.parse_camera(text) == expected


@pytest.mark.parametrize("text", ["diagonal", "follow:", "follow:-1", "1,2", "1,2,x",
                                  "1,2,3:4,5,6:7,8,9", "1,2,inf"])
def test_bad_camera_values_name_the_option(text):
    with pytest.raises(InputError, match="--camera"):
        an.parse_camera(text)


# ---- walls ---------------------------------------------------------------------------------

def test_box_faces_are_the_exact_faces_with_inward_normals():
    lower, upper = np.zeros(3), np.array([0.05, 0.05, 0.1])
    planes = [Plane(lower.copy(), np.array([0.0, 0.0, 1.0]), 0, "floor"),
              Plane(upper.copy(), np.array([-1.0, 0.0, 0.0]), 0, "x_upper")]
    floor, side = an.wall_patches(planes, lower + 0.01, upper - 0.01, lower, upper)
    np.testing.assert_allclose(np.sort(floor.corners[:, :2], axis=0)[[0, -1]],
                               [[0.0, 0.0], [0.05, 0.05]], atol=1e-15)
    assert np.all(floor.corners[:, 2] == 0.0)
    assert np.all(side.corners[:, 0] == pytest.approx(0.05))
    for patch in (floor, side):
        # counter-clockwise seen from the normal's side: the polygon faces the spheres
        c = patch.corners
        assert np.cross(c[1] - c[0], c[2] - c[1]) @ patch.normal > 0


def test_a_free_plane_extends_past_the_extent_on_every_side():
    plane = Plane(np.zeros(3), np.array([0.0, 0.0, 1.0]), 0, "floor")
    lower, upper = np.array([-1.0, -0.01, 0.0]), np.array([3.0, 0.01, 0.02])
    (patch,) = an.wall_patches([plane], lower, upper)
    xy = patch.corners[:, :2]
    assert xy[:, 0].min() < -1.0
    assert xy[:, 0].max() > 3.0
    assert xy[:, 1].min() < -0.01
    assert xy[:, 1].max() > 0.01
    margin = an.PATCH_MARGIN * 2.0          # of the longest in-plane half edge (2 m)
    assert patch.edge_u * patch.edge_v == pytest.approx((4.0 + 2 * margin) * (0.02 + 2 * margin))


def test_nice_step_above_is_the_next_1_2_5():
    assert [an.nice_step_above(x) for x in (0.292, 0.2, 0.21, 1.0, 3.3, 7.0)] == [
        pytest.approx(v) for v in (0.5, 0.2, 0.5, 1.0, 5.0, 10.0)]


def test_nice_spacing_is_1_2_5():
    assert [an.nice_spacing(x) for x in (0.0031, 0.0016, 0.008, 0.7, 40.0)] == [
        pytest.approx(v) for v in (0.002, 0.002, 0.01, 0.5, 50.0)]
