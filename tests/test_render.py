"""``hsgran render``: pictures checked against the camera projection, movie files read back, and
bad input.

Every picture is rendered by the real command in a subprocess (VTK segfaults instead of raising
when the system GL libraries are missing, docs/architecture.md §6, and a crash must not take
pytest down);
bad input is checked in-process through :func:`hsgran.cli.main`, where it is refused before
anything imports pyvista. The trajectories are written with TrajectoryWriter directly (tiny,
known motions), except one run through the engine.

Projection used to predict pixels (written out here, independently of hsgran.animation): a
pinhole camera at ``eye`` looking at ``focal`` with vertical angle of view 30°; a point at
(x_r, y_u, d) along (right, up, forward) lands at column W/2 + f x_r/d, row H/2 − f y_u/d with
f = (H/2)/tan(15°), rows counted from the top.
"""

from __future__ import annotations

import importlib.util
import math
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from hsgran import animation, render
from hsgran.errors import EXIT_BAD_INPUT
from hsgran.io.h5md import TrajectoryWriter, read_trajectory
from tests.cli_errors import run_error

ROOT = Path(__file__).resolve().parents[1]

#: Why pictures cannot be rendered here, or None.
_SKIP = ("the render extra is not installed"
         if any(importlib.util.find_spec(m) is None for m in ("pyvista", "imageio"))
         else render.missing_system_libraries())
needs_gl = pytest.mark.skipif(_SKIP is not None, reason=str(_SKIP))

#: A scene text with one steel sphere and no walls (the stored scene only supplies the walls
#: and the title).
ONE_SPHERE = """
[scene]
name = "test"
duration = 0.2
[output]
frame_interval = 0.1
[[particles]]
material = "steel"
radius = 0.01
position = [0.0, 0.0, 0.0]
"""

RADIUS = 0.01
#: Background colour of the pictures (hsgran.render.BACKGROUND) in 0-255.
BACKGROUND = np.round(np.array(render.BACKGROUND) * 255)


def write_trajectory(path, time, position, velocity, *, radius=RADIUS, omega=None,
                     scene_text=ONE_SPHERE, events=None):
    """Write a trajectory of N spheres (position, velocity: (F, N, 3)) with TrajectoryWriter;
    ``events``: the event log as a mapping of its fields, or None."""
    time = np.asarray(time, dtype=float)
    position = np.asarray(position, dtype=float)
    f, n, _ = position.shape
    zeros = np.zeros(f)
    with TrajectoryWriter(
            path, radius=np.full(n, radius), mass=np.full(n, 0.03),
            material=np.zeros(n, dtype=int), material_names=["steel"], box_lower=None,
            box_upper=None, periodic=(False, False, False), angular_velocity=omega is not None,
            scene_text=scene_text, effects=["rotation"] if omega is not None else [], seed=0,
            version="test", log_events=events is not None) as writer:
        writer.append_frames(dict(
            step=np.arange(f), time=time, position=position,
            velocity=np.asarray(velocity, dtype=float),
            angular_velocity=None if omega is None else np.asarray(omega, dtype=float),
            kinetic_translational=zeros, kinetic_rotational=None if omega is None else zeros,
            potential=zeros, dissipated=zeros))
        if events is not None:
            writer.append_events(events)
    return path


def moving_sphere(path, speed=0.1):
    """One sphere moving along +x at ``speed`` from the origin, frames at 0, 0.1, 0.2 s."""
    t = np.array([0.0, 0.1, 0.2])
    v = np.array([speed, 0.0, 0.0])
    return write_trajectory(path, t, (t[:, None] * v)[:, None, :],
                            np.broadcast_to(v, (3, 1, 3)))


def hsgran(*argv, check=True) -> subprocess.CompletedProcess:
    """Run the hsgran command in a subprocess."""
    proc = subprocess.run([sys.executable, "-m", "hsgran", *map(str, argv), "--no-progress"],
                          capture_output=True, text=True, timeout=300)
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def read_png(path) -> np.ndarray:
    import imageio.v3 as iio

    return np.asarray(iio.imread(path))[..., :3].astype(float)


def pixel(point, eye, focal, size, up_hint=(0.0, 0.0, 1.0), view_angle=30.0):
    """(column, row) of a world point, and the focal length [px] and depth [m]."""
    point, eye, focal = (np.asarray(v, dtype=float) for v in (point, eye, focal))
    forward = (focal - eye) / np.linalg.norm(focal - eye)
    right = np.cross(forward, up_hint)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = point - eye
    depth = rel @ forward
    f = 0.5 * size[1] / math.tan(math.radians(view_angle) / 2.0)
    return np.array([size[0] / 2 + f * (rel @ right) / depth,
                     size[1] / 2 - f * (rel @ up) / depth]), f, depth


def sphere_mask(image, keep_top=0.15, keep_right=0.2) -> np.ndarray:
    """Pixels that are not background, outside the title band and the legend column."""
    mask = np.abs(image - BACKGROUND).sum(axis=2) > 30
    h, w = mask.shape
    mask[: int(keep_top * h)] = False
    mask[:, int((1 - keep_right) * w):] = False
    return mask


def centroid(mask) -> np.ndarray:
    rows, cols = np.nonzero(mask)
    return np.array([cols.mean() + 0.5, rows.mean() + 0.5])  # pixel centres at half-integers


# ---- pictures ------------------------------------------------------------------------------

EYE, FOCAL = (0.05, -0.3, 0.1), (0.05, 0.0, 0.0)
SIZE = (320, 240)


@needs_gl
@pytest.mark.parametrize("style", ["mesh", "points"])
def test_sphere_appears_where_the_camera_projects_it_and_moves_with_the_trajectory(
        tmp_path, style):
    traj = moving_sphere(tmp_path / "one.h5", speed=0.1)
    frames = tmp_path / "frames"
    # 0.05 simulated s per video s at 20 fps: frames every 2.5 ms, most between stored frames
    hsgran("render", traj, "--frames", frames, "--size", "320x240", "--spheres", style,
           "--camera", "0.05,-0.3,0.1:0.05,0,0", "--color-by", "material", "--fps", "20",
           "--time-scale", "0.05")
    files = sorted(frames.glob("frame_*.png"))
    assert len(files) == 81                       # 0.2 s / 2.5 ms + 1
    assert not list(tmp_path.glob(".*part*"))     # no temporary left behind
    for k in (0, 13, 40, 80):
        image = read_png(files[k])
        assert image.shape == (240, 320, 3)
        assert image.std() > 5.0                  # not blank
        mask = sphere_mask(image)
        where, f, depth = pixel((0.1 * 0.0025 * k, 0.0, 0.0), EYE, FOCAL, SIZE)
        # the centre of the sphere's disk is the projected centre (a sphere's outline is
        # symmetric about it to well under a pixel this close to the axis)
        np.testing.assert_allclose(centroid(mask), where, atol=0.5)
        # true radius: the disk's area gives its radius, f R / d
        assert math.sqrt(mask.sum() / math.pi) == pytest.approx(f * RADIUS / depth, rel=0.04)
    # between t = 0 and t = 0.2 s the sphere moved 20 mm: 0.1 m/s × 0.2 s
    first = centroid(sphere_mask(read_png(files[0])))
    last = centroid(sphere_mask(read_png(files[80])))
    expected = pixel((0.02, 0.0, 0.0), EYE, FOCAL, SIZE)[0] - pixel((0, 0, 0), EYE, FOCAL, SIZE)[0]
    np.testing.assert_allclose(last - first, expected, atol=0.5)


@needs_gl
def test_mp4_has_the_expected_frame_count_and_size(tmp_path):
    import imageio.v2 as iio2

    traj = moving_sphere(tmp_path / "one.h5")
    movie = tmp_path / "movie.mp4"
    proc = hsgran("render", traj, "-o", movie, "--size", "160x96", "--fps", "10",
                  "--time-scale", "0.1")
    reader = iio2.get_reader(movie)
    try:
        assert reader.count_frames() == 21          # 0.2 s at 0.01 simulated s per frame
        assert tuple(reader.get_meta_data()["size"]) == (160, 96)
        assert reader.get_meta_data()["fps"] == pytest.approx(10.0)
        middle = np.asarray(reader.get_data(10), dtype=float)
        assert middle.std() > 5.0
    finally:
        reader.close()
    assert "21 frames" in proc.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["movie.mp4", "one.h5"]


@needs_gl
def test_mp4_size_is_rounded_up_to_macroblocks(tmp_path):
    import imageio.v2 as iio2

    traj = moving_sphere(tmp_path / "one.h5")
    movie = tmp_path / "odd.mp4"
    proc = hsgran("render", traj, "-o", movie, "--size", "150x90", "--fps", "5",
                  "--time-scale", "0.1")
    assert "160x96" in proc.stderr
    with iio2.get_reader(movie) as reader:
        assert tuple(reader.get_meta_data()["size"]) == (160, 96)


@needs_gl
def test_gif_follow_camera_keeps_the_sphere_centred(tmp_path):
    import imageio.v3 as iio

    traj = moving_sphere(tmp_path / "one.h5", speed=1.0)    # 20 cm: far out of a fixed view
    gif = tmp_path / "follow.gif"
    hsgran("render", traj, "-o", gif, "--size", "120x90", "--camera", "follow:0",
           "--color-by", "material", "--fps", "10", "--time-scale", "0.5")
    frames = np.asarray(iio.imread(gif, index=None))
    assert frames.shape[:3] == (5, 90, 120)                   # 0.2 s / 0.05 s + 1
    for image in frames[..., :3].astype(float):
        # the sphere is the only blue thing: steel is drawn in tab10 blue (31, 119, 180)
        blue = (image[..., 2] - image[..., 0] > 40) & (image[..., 2] > 60)
        blue[: int(0.35 * 90)] = False              # the title, time label and legend
        np.testing.assert_allclose(centroid(blue), (60.0, 45.0), atol=1.5)


@needs_gl
def test_still_png_at_a_time(tmp_path):
    traj = moving_sphere(tmp_path / "one.h5")
    still = tmp_path / "still.png"
    proc = hsgran("render", traj, "--at", "0.15", "-o", still, "--size", "320x240",
                  "--camera", "0.05,-0.3,0.1:0.05,0,0", "--color-by", "material")
    assert proc.stdout.startswith(f"wrote {still}: still, 320x240")
    image = read_png(still)
    where = pixel((0.015, 0.0, 0.0), EYE, FOCAL, SIZE)[0]
    np.testing.assert_allclose(centroid(sphere_mask(image)), where, atol=0.5)


@needs_gl
@pytest.mark.parametrize("style", ["mesh", "points"])
def test_a_sphere_that_has_left_the_system_is_not_drawn(tmp_path, style):
    """Sphere 1 leaves through an outlet before the last frame (NaN, id −1,
    docs/open-systems.md): the last picture shows sphere 0 alone."""
    t = np.array([0.0, 0.1, 0.2])
    position = np.zeros((3, 2, 3))
    position[:, 1] = (0.08, 0.0, 0.0)
    position[2, 1] = np.nan
    velocity = np.where(np.isnan(position), np.nan, 0.0)
    zeros = np.zeros(3)
    path = tmp_path / "left.h5"
    with TrajectoryWriter(
            path, radius=np.full(2, RADIUS), mass=np.full(2, 0.03), material=np.zeros(2, int),
            material_names=["steel"], box_lower=None, box_upper=None,
            periodic=(False, False, False), angular_velocity=False, scene_text=ONE_SPHERE,
            effects=[], seed=0, version="test", log_events=False, open_system=True) as writer:
        writer.append_frames(dict(step=np.arange(3), time=t, position=position,
                                  velocity=velocity, angular_velocity=None,
                                  kinetic_translational=zeros, kinetic_rotational=None,
                                  potential=zeros, dissipated=zeros,
                                  id=np.array([[0, 1], [0, 1], [0, -1]]), exited=zeros,
                                  entered=zeros))
    gone = pixel((0.08, 0.0, 0.0), EYE, FOCAL, SIZE)[0]
    masks = []
    for at in ("0.1", "0.2"):
        still = tmp_path / f"still_{at}.png"
        hsgran("render", path, "--at", at, "-o", still, "--size", "320x240", "--spheres",
               style, "--camera", "0.05,-0.3,0.1:0.05,0,0", "--color-by", "material")
        masks.append(sphere_mask(read_png(still)))
    rows, cols = np.mgrid[:SIZE[1], :SIZE[0]]
    near_gone = np.hypot(cols + 0.5 - gone[0], rows + 0.5 - gone[1]) < 4.0
    assert masks[0][near_gone].all()  # there while it is in the system
    assert not masks[1][near_gone].any()  # not drawn once it has left
    np.testing.assert_allclose(centroid(masks[1]), pixel((0.0, 0.0, 0.0), EYE, FOCAL, SIZE)[0],
                               atol=0.5)


def rolling_and_sliding(path):
    """Two spheres, one above the other, at 0.1 m/s along x for 0.1 s: sphere 0 rolls (ω = v/R
    about y, it turns by 1 rad), sphere 1 slides without spin."""
    t = np.array([0.0, 0.1])
    v = 0.1
    start = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.04]])
    vel = np.array([[v, 0.0, 0.0], [v, 0.0, 0.0]])
    omega = np.array([[0.0, v / RADIUS, 0.0], [0.0, 0.0, 0.0]])
    write_trajectory(path, t, start[None] + t[:, None, None] * vel[None],
                     np.broadcast_to(vel, (2, 2, 3)), omega=np.broadcast_to(omega, (2, 2, 3)))
    return start, start + 0.1 * vel


#: Camera of the rolling/sliding pictures: in front (−y), looking along the rolling axis, so a
#: turn about y turns the pattern in the picture's plane.
SPIN_EYE, SPIN_FOCAL = (0.005, -0.3, 0.02), (0.005, 0.0, 0.02)


def render_spin(tmp_path, style):
    """Frames at t = 0 and 0.1 s of :func:`rolling_and_sliding`; centres [px] in both."""
    before, after = rolling_and_sliding(tmp_path / "two.h5")
    frames = tmp_path / "frames"
    hsgran("render", tmp_path / "two.h5", "--frames", frames, "--size", "320x240",
           "--spheres", style, "--camera", "0.005,-0.3,0.02:0.005,0,0.02", "--color-by",
           "material", "--fps", "2", "--time-scale", "0.2")
    images = [read_png(p) for p in sorted(frames.glob("frame_*.png"))]
    centres = [[pixel(x, SPIN_EYE, SPIN_FOCAL, SIZE)[0] for x in xs] for xs in (before, after)]
    return images, centres


@needs_gl
def test_rolling_pattern_turns_and_sliding_pattern_does_not(tmp_path):
    from scipy.ndimage import shift

    (a, b), centres = render_spin(tmp_path, "mesh")
    half = 9                                     # a patch inside each sphere's disk (~15 px)
    change = []
    for k in range(2):
        # move the second picture by the sphere's displacement (to a fraction of a pixel), so
        # that only the turn of the pattern remains
        (c0, r0), (c1, r1) = centres[0][k], centres[1][k]
        moved = shift(b, (r0 - r1, c0 - c1, 0.0), order=1, mode="nearest")
        c, r = round(c0), round(r0)
        change.append(np.abs(a[r - half: r + half, c - half: c + half]
                             - moved[r - half: r + half, c - half: c + half]).mean())
    rolling, sliding = change
    assert rolling > 10.0, change
    assert rolling > 5.0 * sliding, change


@needs_gl
def test_rolling_marker_moves_round_and_sliding_marker_stays(tmp_path):
    images, centres = render_spin(tmp_path, "points")
    offsets = []                                  # marker centre − sphere centre [px]
    for image, frame_centres in zip(images, centres, strict=True):
        rows, cols = np.indices(image.shape[:2])
        # the light marker dot on the (darker) steel-blue sphere
        light = image.min(axis=2) > 170
        found = []
        for centre in frame_centres:
            near = (cols + 0.5 - centre[0]) ** 2 + (rows + 0.5 - centre[1]) ** 2 < 15.0**2
            found.append(centroid(light & near) - centre)
        offsets.append(found)
    rolling_shift = np.linalg.norm(offsets[1][0] - offsets[0][0])
    sliding_shift = np.linalg.norm(offsets[1][1] - offsets[0][1])
    # the dot is a few pixels wide: its thresholded centroid is good to about a pixel
    assert sliding_shift < 1.5, offsets
    assert rolling_shift > 4.0, offsets


@needs_gl
def test_state_colours_follow_the_engine_sliding_then_rolling(tmp_path):
    from hsgran.api import run_scene

    out = tmp_path / "plate.h5"
    # the paper's sphere on a plate: slides until t1 = 0.0995 s, then rolls
    run_scene(ROOT / "scenarios" / "sphere_on_plate.toml", out, until=0.3, log_events=True,
              force=True)
    colours = {}
    for at in ("0.05", "0.25"):
        still = tmp_path / f"state_{at}.png"
        hsgran("render", out, "--at", at, "-o", still, "--size", "160x120", "--color-by",
               "state", "--camera", "follow:0")
        image = read_png(still)
        # the followed sphere sits at the picture's centre; average its middle
        colours[at] = image[55:65, 75:85].reshape(-1, 3).mean(axis=0)
    red, green, blue = colours["0.05"]
    assert red > green > blue                         # sliding: orange
    red, green, blue = colours["0.25"]
    assert green > max(red, blue)                     # rolling: green



# ---- walls ---------------------------------------------------------------------------------

#: A sweep's wall overrides: the floor of tests/sweep/scenes.py's BALL moved down and tilted
#: about x (a unit normal, so the scene stores it as given).
TILTED_FLOOR = {"walls[0].point": [0.0, 0.0, -0.002], "walls[0].normal": [0.0, 0.28, 0.96]}


def swept_ball(path):
    """The ball of the sweep tests run as one case of a sweep with TILTED_FLOOR."""
    from hsgran.sweep.case import run_case
    from tests.sweep.scenes import BALL

    run_case(BALL, TILTED_FLOOR, source="ball.toml", trajectory=path)
    return path


def test_render_draws_the_walls_a_sweep_case_simulated(tmp_path):
    traj = read_trajectory(swept_ball(tmp_path / "case.h5"))
    planes, name = render.wall_planes(traj)
    assert name == "ball on glass"
    (floor,) = planes
    np.testing.assert_array_equal(floor.point, TILTED_FLOOR["walls[0].point"])
    np.testing.assert_array_equal(floor.normal, TILTED_FLOOR["walls[0].normal"])
    assert traj.material_names[floor.material] == "glass"
    # the rectangle drawn lies in the tilted plane and faces the spheres' side
    lower, upper = animation.scene_extent(traj)
    (patch,) = animation.wall_patches(planes, lower, upper, traj.box_lower, traj.box_upper)
    np.testing.assert_allclose(patch.normal, TILTED_FLOOR["walls[0].normal"])
    offsets = (patch.corners - floor.point) @ floor.normal
    np.testing.assert_allclose(offsets, 0.0, atol=1e-15)


def test_a_file_without_walls_rebuilds_them_from_its_scene_text_and_overrides(tmp_path, capsys):
    path = swept_ball(tmp_path / "case.h5")
    with h5py.File(path, "r+") as f:  # as written before the walls were stored
        del f["parameters/hsgran/walls"]
    traj = read_trajectory(path)
    assert traj.walls is None
    (floor,), name = render.wall_planes(traj)
    np.testing.assert_array_equal(floor.normal, TILTED_FLOOR["walls[0].normal"])
    assert name == "ball on glass"
    assert capsys.readouterr().err == ""


def test_a_scene_text_that_no_longer_parses_warns_and_draws_the_box_only(tmp_path, capsys):
    path = tmp_path / "old.h5"
    write_trajectory(path, [0.0], np.zeros((1, 1, 3)), np.zeros((1, 1, 3)),
                     scene_text=ONE_SPHERE + "[[walls]]\nkind = \"cone\"\n")
    planes, name = render.wall_planes(read_trajectory(path))
    assert planes == []
    assert name == ""
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("warning: the file holds no walls")
    assert "walls[0].kind" in err


# ---- bad input -----------------------------------------------------------------------------



@pytest.fixture
def one(tmp_path):
    return moving_sphere(tmp_path / "one.h5")


def test_missing_file_is_one_line_exit_2(capsys, tmp_path):
    err = run_error(capsys, ["render", str(tmp_path / "nope.h5"), "-o", str(tmp_path / "m.mp4")])
    assert "not found" in err


def test_non_hsgran_hdf5_is_one_line_exit_2(capsys, tmp_path):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["data"] = np.arange(3)
    err = run_error(capsys, ["render", str(other), "-o", str(tmp_path / "m.mp4")])
    assert "not an hsgran trajectory" in err


@pytest.mark.parametrize(("options", "named"), [
    (["--color-by", "colour"], "--color-by"),
    (["--camera", "diagonal"], "--camera"),
    (["--camera", "follow:7"], "--camera"),
    (["--camera", "1,2"], "--camera"),
    (["--size", "big"], "--size"),
    (["--size", "4x4"], "--size"),
    (["--fps", "0"], "--fps"),
    (["--fps", "nan"], "--fps"),
    (["--time-scale", "-1"], "--time-scale"),
    (["--spheres", "cubes"], "--spheres"),
    (["--at", "5"], "--at"),
    (["--start", "0.15", "--end", "0.05"], "--end"),
    (["--time-scale", "1e-9"], "--time-scale"),
])
def test_unknown_option_values_are_one_line_exit_2(capsys, tmp_path, one, options, named):
    target = "still.png" if "--at" in options else "m.mp4"
    err = run_error(capsys, ["render", str(one), "-o", str(tmp_path / target), *options])
    assert named in err
    assert not (tmp_path / target).exists()


@pytest.mark.parametrize(("output", "extra", "expected"), [
    ("m.avi", [], "unknown movie type"),
    ("m.png", [], "--at"),
    ("m.mp4", ["--at", "0.1"], "PNG"),
])
def test_output_types_are_checked(capsys, tmp_path, one, output, extra, expected):
    err = run_error(capsys, ["render", str(one), "-o", str(tmp_path / output), *extra])
    assert expected in err


def test_regime_needs_the_event_log(capsys, tmp_path, one):
    err = run_error(capsys, ["render", str(one), "-o", str(tmp_path / "m.mp4"),
                             "--color-by", "regime"])
    assert "--events" in err


def test_existing_output_needs_force(capsys, tmp_path, one):
    (tmp_path / "m.mp4").write_bytes(b"old")
    err = run_error(capsys, ["render", str(one), "-o", str(tmp_path / "m.mp4")])
    assert "--force" in err
    assert (tmp_path / "m.mp4").read_bytes() == b"old"


def test_frames_folder_with_other_files_is_refused(capsys, tmp_path, one):
    folder = tmp_path / "frames"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    err = run_error(capsys, ["render", str(one), "--frames", str(folder), "--force"])
    assert "notes.txt" in err


def test_missing_system_libraries_say_what_to_install(capsys, tmp_path, one, monkeypatch):
    monkeypatch.setattr(render, "missing_system_libraries",
                        lambda: "offscreen rendering needs the system libraries libegl1 ...")
    err = run_error(capsys, ["render", str(one), "-o", str(tmp_path / "m.mp4")])
    assert "libegl1" in err


def test_missing_render_extra_names_it(capsys, tmp_path, one, monkeypatch):
    from hsgran.errors import MissingDependency

    def missing():
        raise MissingDependency("rendering needs the 'render' extra (pyvista is missing): "
                                f"{render.RENDER_EXTRA}")

    monkeypatch.setattr(render, "missing_system_libraries", lambda: None)
    monkeypatch.setattr(render, "_import_pyvista", missing)
    err = run_error(capsys, ["render", str(one), "-o", str(tmp_path / "m.mp4")])
    assert ".[render]" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.h5"]


def test_bad_input_in_a_subprocess_has_no_traceback(tmp_path):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["data"] = np.arange(3)
    proc = hsgran("render", other, "-o", tmp_path / "m.mp4", check=False)
    assert proc.returncode == EXIT_BAD_INPUT
    assert proc.stderr.startswith("hsgran: error: ")
    assert proc.stderr.count("\n") == 1
    assert "Traceback" not in proc.stderr


def test_help_states_the_real_defaults():
    from hsgran.cli import build_parser

    text = " ".join(build_parser().commands["render"].format_help().split())
    assert f"default {render.DEFAULT_FPS:g})" in text
    assert f"default {render.DEFAULT_SIZE[0]}x{render.DEFAULT_SIZE[1]};" in text
    for value in animation.COLOR_BY:
        assert value in text
    assert f"up to {render.MESH_SPHERES_MAX} spheres" in text


# ---- the benchmark tool ----------------------------------------------------------------------

@needs_gl
def test_bench_render_prints_ms_per_frame():
    proc = subprocess.run([sys.executable, str(ROOT / "tools" / "bench_render.py"), "--sizes",
                           "3,60", "--frames", "2", "--size", "96x64"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    rows = [line.split() for line in proc.stdout.splitlines() if line[:8].strip().isdigit()]
    assert [(r[0], r[1]) for r in rows] == [("3", "mesh"), ("60", "points")]
    assert all(float(r[2]) > 0.0 for r in rows)
    assert "targets:" in proc.stdout
