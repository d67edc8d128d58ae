"""Event-driven engine: conservation, exactness and cross-checks (issue: the engine)."""

from pathlib import Path

import numba
import numpy as np
import pytest

from hsgran import _state as es
from hsgran._predict import LAYER_MIN_CELLS
from hsgran.engine import Simulation
from hsgran.scene import load_scene, parse_scene
from tests.observers import Keep

#: Relative kinetic-energy drift allowed for an elastic gas: each collision conserves energy to
#: a few ulps, and the errors of 1e5 collisions add up like a random walk (~1e-16 × √1e5 × N).
GAS_ENERGY_RTOL = 1e-12
#: Overlap tolerance as a fraction of the radius (issue: no pair overlaps by more than 1e-9 R).
OVERLAP_RTOL = 1e-9

GAS = """
[scene]
name = "elastic gas"
duration = {duration}
effects = []
seed = {seed}
periodic = [true, true, true]
[output]
frame_interval = {frame}
[materials.steel]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [{side}, {side}, {side}]
material = "steel"
[[fill]]
count = {count}
radius = 0.01
material = "steel"
speed = 1.0
region = {{ lower = [0.0, 0.0, 0.0], upper = [{side}, {side}, {side}] }}
"""


def gas(count=500, phi=0.2, duration=1.0, frame=0.1, seed=1):
    side = (count * 4 / 3 * np.pi * 0.01**3 / phi) ** (1 / 3)
    return parse_scene(
        GAS.format(count=count, side=side, duration=duration, frame=frame, seed=seed)
    )


def min_pair_gap(pos, radius, box_len):
    d = pos[:, None, :] - pos[None, :, :]
    d -= box_len * np.round(d / box_len)
    dist = np.sqrt((d**2).sum(-1))
    np.fill_diagonal(dist, np.inf)
    return (dist - (radius[:, None] + radius[None, :])).min()


def test_elastic_gas_conserves_energy_and_momentum_over_1e5_collisions():
    scene = gas(count=500, duration=100.0, frame=0.05)
    keep = Keep()
    sim = Simulation(scene)
    summary = sim.run(max_collisions=100_000, observers=[keep])
    assert summary.collisions == 100_000
    ke = keep.cat("kinetic_translational")
    assert np.max(np.abs(ke - ke[0])) / ke[0] < GAS_ENERGY_RTOL
    p = np.einsum("n,fnk->fk", scene.mass(), keep.cat("velocity"))
    p_scale = np.sum(scene.mass()) * 1.0
    assert np.max(np.abs(p - p[0])) / p_scale < GAS_ENERGY_RTOL
    box_len = scene.box_upper - scene.box_lower
    for frame in keep.cat("position")[:: max(1, len(ke) // 20)]:
        assert min_pair_gap(frame, scene.radius, box_len) > -OVERLAP_RTOL * 0.01


#: Collisions over which the cell grid and all-pairs runs must agree exactly. The two paths
#: round differently (the periodic image shift is applied at other times), and a hard-sphere gas
#: amplifies a difference about tenfold per collision (mean free path / radius), so 1e-16 grows
#: to O(1) after ~16 collisions per sphere (measured: 1e-9 is reached near 580); 400 is ~6
#: per sphere.
CROSS_CHECK_COLLISIONS = 400
#: The same, ~6 per sphere, for 500 spheres (~2800 cell crossings on the cell grid).
CROSS_CHECK_COLLISIONS_500 = 3000


@pytest.mark.parametrize(("count", "collisions"), [
    (64, CROSS_CHECK_COLLISIONS),
    # the all-pairs run of 500 spheres takes ~10 min in pure Python: the compiled run only
    pytest.param(500, CROSS_CHECK_COLLISIONS_500, marks=pytest.mark.skipif(
        numba.config.DISABLE_JIT, reason="all-pairs oracle too slow without the compiler")),
])
def test_cell_grid_and_all_pairs_give_the_same_event_sequence(count, collisions):
    # with at least LAYER_MIN_CELLS cells per axis every cell crossing looks at the new layer of
    # neighbouring cells only (hsgran._loop._predict); the all-pairs run has one cell per axis
    # and looks at everybody at every prediction, so it is the oracle of that shortcut too
    scene = gas(count=count, duration=50.0, frame=1.0, seed=3)
    logs = []
    for brute in (False, True):
        keep = Keep()
        sim = Simulation(scene, brute_force=brute, log_events=True)
        summary = sim.run(max_collisions=collisions, observers=[keep])
        logs.append((keep.log("i"), keep.log("j"), keep.log("time")))
        if not brute:
            assert np.all(sim.ncell >= LAYER_MIN_CELLS)
            assert summary.events["cell"] > collisions // 2
    (i1, j1, t1), (i2, j2, t2) = logs
    assert len(t1) == len(t2) == collisions
    pairs1 = np.sort(np.stack([i1, j1]), axis=0)
    pairs2 = np.sort(np.stack([i2, j2]), axis=0)
    assert np.array_equal(pairs1, pairs2)
    np.testing.assert_allclose(t1, t2, rtol=1e-9)


def test_two_runs_of_the_same_scene_are_identical():
    scene = gas(count=200, duration=5.0, frame=0.5, seed=7)
    runs = []
    for _ in range(2):
        keep = Keep()
        Simulation(scene, log_events=True).run(max_collisions=5000, observers=[keep])
        runs.append((keep.cat("position"), keep.log("time"), keep.log("i")))
    for a, b in zip(runs[0], runs[1], strict=True):
        assert np.array_equal(a, b)


SMALL_POUR = Path(__file__).resolve().parents[1] / "tools" / "scenes" / "small_pour.toml"


@pytest.mark.parametrize(("scene", "collisions"), [
    (gas(count=200, duration=50.0, frame=0.5, seed=5), 20_000),
    # gravity, friction, planes, sleeping and landing; JIT only (slow in pure Python)
    pytest.param(SMALL_POUR, 30_000, marks=pytest.mark.skipif(
        numba.config.DISABLE_JIT, reason="too slow without the compiler")),
], ids=["elastic_gas", "small_pour"])
def test_large_system_layout_runs_the_same_events(scene, collisions):
    """The layout for large systems (per-sphere records, a calendar with time buckets, prefetch
    hints; engine.LARGE_FROM) changes where the data lie, never which event comes next: the
    runs are identical to the bit, also across a checkpoint taken and restored in it."""
    if isinstance(scene, Path):
        scene = load_scene(scene)
    runs = []
    for large in (False, True):
        keep = Keep()
        sim = Simulation(scene, log_events=True, large=large)
        sim.run(max_collisions=collisions // 2, observers=[keep])
        if large:
            # continue in a fresh simulation from a checkpoint (the calendar is rebuilt)
            state = sim.checkpoint()
            sim = Simulation(scene, log_events=True, large=True)
            sim.restore(state)
        sim.run(max_collisions=collisions - collisions // 2, observers=[keep])
        assert sim.collisions > 0
        runs.append((keep.log("time"), keep.log("i"), keep.log("j"), keep.log("kind"),
                     sim.pos.copy(), sim.vel.copy()))
    for a, b in zip(runs[0], runs[1], strict=True):
        assert np.array_equal(a, b)


BALL = """
[scene]
name = "ball"
duration = {duration}
gravity = [0.0, 0.0, -9.81]
effects = ["gravity"]
[output]
frame_interval = {frame}
[materials.steel]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[[contacts]]
between = ["steel", "steel"]
restitution = {e}
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "steel"
[[particles]]
material = "steel"
radius = 0.005
position = [0.0, 0.0, {h}]
velocity = [0.3, -0.2, {vz}]
"""


def test_bouncing_ball_flight_times_shrink_by_restitution():
    e = 0.8
    scene = parse_scene(BALL.format(duration=1.5, frame=0.5, e=e, h=0.2, vz=0.0))
    keep = Keep()
    Simulation(scene, log_events=True).run(observers=[keep])
    t = keep.log("time")
    assert len(t) >= 8
    flights = np.diff(t)
    np.testing.assert_allclose(flights[1:] / flights[:-1], e, rtol=1e-9)
    np.testing.assert_allclose(keep.log("e_n"), e, rtol=0, atol=0)


def test_positions_at_frame_times_follow_the_parabola_exactly():
    h, vz, g = 0.5, 1.0, 9.81
    scene = parse_scene(BALL.format(duration=0.3, frame=0.01, e=1.0, h=h, vz=vz))
    keep = Keep()
    Simulation(scene).run(observers=[keep])
    t = keep.cat("time")
    np.testing.assert_allclose(t, 0.01 * np.arange(len(t)), rtol=0, atol=1e-15)
    pos = keep.cat("position")[:, 0]
    want = np.stack([0.3 * t, -0.2 * t, h + vz * t - 0.5 * g * t**2], axis=1)
    np.testing.assert_allclose(pos, want, rtol=0, atol=1e-15)


@pytest.mark.parametrize("seed", [1, 2])
def test_frames_do_not_change_the_trajectory(seed):
    """Delayed states: sampling more often must give the same collisions bit for bit."""
    scene = gas(count=100, duration=3.0, frame=0.5, seed=seed)
    logs = []
    for frame in (0.5, 0.01):
        scene.frame_interval = frame
        keep = Keep()
        Simulation(scene, log_events=True).run(observers=[keep])
        logs.append(keep.log("time"))
    assert np.array_equal(logs[0], logs[1])


def test_run_summary_says_when_gravity_meets_no_losses():
    """A scene with gravity whose collisions are elastic (no restitution below 1, no
    plasticity) says so in its run summary; the example scene with plasticity, or the same
    scene with a restitution, does not."""
    from hsgran.engine import LOSSLESS_NOTE
    from hsgran.scene import load_scene

    path = Path(__file__).resolve().parents[1] / "scenarios" / "steel_ball_on_glass.toml"
    lossless = {"scene.effects": ["gravity", "rotation", "friction"], "scene.duration": 0.05}
    for overrides, noted in ((lossless, True),
                             ({**lossless, "contacts[0].restitution": 0.9}, False),
                             ({"scene.duration": 0.05}, False)):
        summary = Simulation(load_scene(path, overrides=overrides)).run()
        assert (f"note: {LOSSLESS_NOTE}" in summary.lines()) is noted, overrides


def test_progress_bar_postfix_has_no_stray_comma(capsys):
    from hsgran.scene import load_scene

    path = Path(__file__).resolve().parents[1] / "scenarios" / "steel_ball_on_glass.toml"
    Simulation(load_scene(path, overrides={"scene.duration": 0.05})).run(progress=True)
    err = capsys.readouterr().err
    assert "collisions]" in err
    assert ", ," not in err


#: Mechanical energy an elastic gas under gravity may seem to lose or gain, relative to the
#: energy gravity fed it: each collision conserves energy to a few ulps, and the parabolas'
#: positions and velocities at a frame round separately.
GRAVITY_GAS_ENERGY_RTOL = 1e-9


def test_gravity_along_a_periodic_axis_keeps_the_energy_the_wraps_hide():
    """An elastic gas falling along a periodic axis: every wrap moves a sphere's stored
    position back by a box length, which raises −m g·x by m g L, but not its motion. The
    potential energy of the frames is that of the unwrapped positions, so the mechanical energy
    is conserved and nothing is dissipated, though the spheres wrap many times
    (docs/trajectory-format.md, "Observables"). Without the wraps' share, each wrap would show
    m g L = 0.032 J as dissipated (−14.9 J in all before 2026-12-07)."""
    text = GAS.format(count=40, side=0.1, duration=0.5, frame=0.05, seed=3).replace(
        'effects = []', 'effects = ["gravity"]\ngravity = [9.81, 0.0, 0.0]')
    text += '[[contacts]]\nbetween = ["steel", "steel"]\nrestitution = 1.0\n'
    scene = parse_scene(text)
    assert scene.unwraps
    keep = Keep()
    sim = Simulation(scene)
    sim.run(observers=[keep])
    mass = scene.mass()
    wraps = -sim.fsc[es.F_UNWRAPPED] / (9.81 * 0.1 * mass[0])
    assert wraps > 100  # ~0.5 g t² / L = 12 per sphere
    kinetic = keep.cat("kinetic_translational")
    gained = kinetic[-1] - kinetic[0]
    assert gained > 0.1
    np.testing.assert_allclose(keep.cat("dissipated"), 0.0, rtol=0,
                               atol=GRAVITY_GAS_ENERGY_RTOL * gained)
    np.testing.assert_allclose(keep.cat("potential") - keep.cat("potential")[0], -(
        kinetic - kinetic[0]), rtol=0, atol=GRAVITY_GAS_ENERGY_RTOL * gained)
    assert abs(sim.dissipated_energy()) <= GRAVITY_GAS_ENERGY_RTOL * gained
