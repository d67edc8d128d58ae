"""Moving plane walls (hsgran.wallmotion): a piston's reflection, the work it does on a gas,
the bouncing ball on a vibrating plate against the exact map and the closed-form window of its
period-1 orbit, the scene keys, the file and the drawing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from hsgran.engine import Simulation
from hsgran.errors import InputError
from hsgran.events.kinds import EV_WALL
from hsgran.scene import parse_scene
from hsgran.wallmotion import moving_plane_contact_time
from hsgran.wallspec import M_KIND, MOT_FIXED
from tests.observers import Keep

G = 9.81  #: [m/s²]
RADIUS = 1e-3  #: [m]


def run(text, **kw):
    """Run a scene; return the simulation, its frames (time, position, velocity and, with
    observables, wall_impulse) and its event log (time, kind, i, j)."""
    sim = Simulation(parse_scene(text), log_events=True)
    keep = Keep()
    sim.run(observers=[keep], **kw)
    frames = {name: keep.cat(name) for name in ("time", "position", "velocity", "wall_impulse")
              if getattr(keep.frames[0], name) is not None}
    log = {name: keep.log(name) for name in ("time", "kind", "i", "j")} if keep.events else None
    return sim, frames, log


PISTON = """
[scene]
name = "piston"
duration = 0.5
effects = []
[output]
frame_interval = 0.05
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
material = "steel"
motion = {{ kind = "velocity", velocity = [{vx}, {vy}, 0.0], travel = 0.1, start = {start} }}
[[particles]]
material = "steel"
radius = 0.001
position = [0.05, 0.0, 0.0]
velocity = [{u}, 0.0, 0.0]
"""


@pytest.mark.parametrize(("vx", "vy", "u", "start"), [(0.1, 0.0, -0.3, 0.0),
                                                    (0.1, 0.05, -0.3, 0.02),
                                                    (0.2, 0.0, 0.0, 0.1)])
def test_a_piston_reflects_the_relative_velocity(vx, vy, u, start):
    """e = 1 against a wall moving at V: u' − V = −(u − V) along the normal, at the time the
    gap closes (the piston still before its start moves nothing)."""
    sim, _, log = run(PISTON.format(vx=vx, vy=vy, u=u, start=start))
    assert sim.vel[0, 0] == pytest.approx(2 * vx - u, rel=1e-13)
    assert sim.vel[0, 1] == 0.0  # frictionless: the piston's sideways motion does nothing
    # the sphere flies at u from x = 0.05 while the piston sits at 0 until `start`
    x_start = 0.05 + u * start
    t_hit = start + (x_start - RADIUS) / (vx - u)
    walls = log["time"][log["kind"] == EV_WALL]
    assert walls.shape == (1,)
    assert walls[0] == pytest.approx(t_hit, rel=1e-13)


GAS_PISTON = """
[scene]
name = "gas under a piston"
duration = {duration}
effects = []
seed = 4
[output]
frame_interval = {frame}
observables = true
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.02, 0.02, 0.04]
material = "glass"
motion = {{ upper_z = {{ kind = "velocity", velocity = [0.0, 0.0, -{speed}], travel = 0.02 }} }}
[[fill]]
count = 150
material = "glass"
radius = 0.001
region = {{ lower = [0.0, 0.0, 0.0], upper = [0.02, 0.02, 0.02] }}
speed = 1.0
"""


def test_a_piston_does_on_an_elastic_gas_the_work_the_gas_gains():
    """Each elastic hit gives the sphere J·V (its relative normal velocity reverses), so the
    kinetic energy the gas gains is the piston's work, −V Σ (impulse on the piston)."""
    speed, duration = 0.05, 0.3
    sim, frames, _ = run(GAS_PISTON.format(duration=duration, frame=0.01, speed=speed))
    mass = sim.mass
    kinetic = 0.5 * np.einsum("n,fnk,fnk->f", mass, frames["velocity"], frames["velocity"])
    top = next(k for k, p in enumerate(sim.scene.planes) if p.key.endswith("upper_z"))
    work = -(frames["wall_impulse"][:, top, :] @ np.array([0.0, 0.0, -speed])).sum()
    gained = kinetic[-1] - kinetic[0]
    assert work > 0.01 * kinetic[0]  # the piston did real work
    assert gained == pytest.approx(work, rel=1e-9)
    # the piston went down 15 mm; no sphere got through it
    assert frames["position"][-1, :, 2].max() < 0.04 - speed * duration


BALL = """
[scene]
name = "ball on a vibrating plate"
duration = {duration}
gravity = [0.0, 0.0, -9.81]
effects = ["gravity"]
[output]
frame_interval = 0.005
[[contacts]]
between = ["steel", "steel"]
restitution = {e}
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "steel"
motion = {{ kind = "oscillation", amplitude = {amp!r}, frequency = {freq}, phase = {phase!r} }}
[[particles]]
material = "steel"
radius = 0.001
position = [0.0, 0.0, {z0!r}]
velocity = [0.0, 0.0, 0.0]
"""
FREQ = 20.0  #: plate frequency [Hz]


def ball_scene(e, gamma, duration, lift=0.0):
    """A ball above a plate vibrating at Γ = A ω²/g, started at the apex of the period-1 orbit
    (``lift`` [m] higher), and the plate's motion (A, ω, φ)."""
    omega = 2 * math.pi * FREQ
    amp = gamma * G / omega**2
    theta = math.acos(min(1.0, window(e)[0] / gamma))
    phase = theta + math.pi  # the apex comes half a period after a launch at phase θ
    period = 1.0 / FREQ
    z0 = 2 * amp * math.sin(theta) + RADIUS + G * period**2 / 8 + lift
    return BALL.format(duration=duration, e=e, amp=amp, freq=FREQ, phase=phase, z0=z0), \
        (amp, omega, phase, z0)


def window(e):
    """The Γ window of the stable period-1 orbit of a ball bouncing with restitution e on a
    plate z = A sin(ω t): it exists for Γ ≥ Γ₁ = π (1 − e)/(1 + e) and is stable below
    Γ₂ = √(Γ₁² + (2 (1 + e²)/(1 + e)²)²), where it period-doubles (the map's Jacobian at the
    orbit has determinant e² and trace 1 + e² − (1 + e)² Γ sin θ; derived in docs/walls.md)."""
    g1 = math.pi * (1 - e) / (1 + e)
    return g1, math.hypot(g1, 2 * (1 + e * e) / (1 + e) ** 2)


def exact_map(e, amp, omega, phase, z0, t_end):
    """The ball's impacts (times, post-impact velocities) by the exact map: each flight is a
    parabola, the next impact the first root of ball height − plate height, found on a grid
    of 1/4000 of a period and polished by Brent's method to 1e-15 s (an oracle independent of
    hsgran's conservative advancement)."""
    def plate(t):
        return amp * (math.sin(omega * t + phase) - math.sin(phase))

    def plate_speed(t):
        return amp * omega * math.cos(omega * t + phase)

    times, speeds = [], []
    t0, z, v = 0.0, z0 - RADIUS, 0.0
    step = 2 * math.pi / omega / 4000
    while True:
        def gap(t, t0=t0, z=z, v=v):
            tau = t - t0
            return z + v * tau - 0.5 * G * tau * tau - plate(t)

        a = t0 + 1e-9
        while gap(a + step) > 0.0:
            a += step
            if a > t_end:
                return np.array(times), np.array(speeds)
        t1 = brentq(gap, a, a + step, xtol=1e-15, rtol=1e-15)
        arrive = v - G * (t1 - t0)
        v = (1 + e) * plate_speed(t1) - e * arrive
        t0, z = t1, plate(t1)
        times.append(t1)
        speeds.append(v)


def test_the_ball_on_a_vibrating_plate_follows_the_exact_map():
    e, gamma, duration = 0.5, 1.3, 1.0
    text, (amp, omega, phase, z0) = ball_scene(e, gamma, duration, lift=0.0004)
    _, frames, log = run(text)
    hits = log["time"][log["kind"] == EV_WALL]
    times, speeds = exact_map(e, amp, omega, phase, z0, duration)
    assert hits.shape == times.shape
    np.testing.assert_allclose(hits, times, rtol=0, atol=1e-12)
    # every frame on the oracle's parabolas
    t = frames["time"]
    k = np.searchsorted(times, t) - 1
    t0 = np.where(k >= 0, times[np.maximum(k, 0)], 0.0)
    v0 = np.where(k >= 0, speeds[np.maximum(k, 0)], 0.0)
    z_start = np.where(k >= 0, amp * (np.sin(omega * t0 + phase) - math.sin(phase)) + RADIUS,
                       z0)
    tau = t - t0
    z = z_start + v0 * tau - 0.5 * G * tau**2
    np.testing.assert_allclose(frames["position"][:, 0, 2], z, rtol=0, atol=1e-12)
    np.testing.assert_allclose(frames["velocity"][:, 0, 2], v0 - G * tau, rtol=0, atol=1e-10)


@pytest.mark.parametrize("gamma", [1.1, 1.3, 1.5])
def test_inside_the_window_the_period_one_orbit_attracts(gamma):
    """Started off the orbit; near Γ₂ an eigenvalue of the map nears −1 (−0.88 at Γ = 1.5), so
    the run is long enough for 0.88^200."""
    e = 0.5
    assert window(e)[0] < gamma < window(e)[1]
    text, (_, omega, phase, _) = ball_scene(e, gamma, 10.0, lift=0.0003)
    _, _, log = run(text)
    hits = log["time"][log["kind"] == EV_WALL]
    period = 1.0 / FREQ
    np.testing.assert_allclose(np.diff(hits[-10:]), period, rtol=0, atol=1e-9)
    theta = math.acos(window(e)[0] / gamma)  # the launch phase of the stable orbit
    launch = np.mod(omega * hits[-10:] + phase - theta + math.pi, 2 * math.pi) - math.pi
    np.testing.assert_allclose(launch, 0.0, atol=1e-7)


@pytest.mark.parametrize("gamma", [1.55, 1.6])
def test_above_the_window_the_orbit_period_doubles(gamma):
    e = 0.5
    assert gamma > window(e)[1]
    text, _ = ball_scene(e, gamma, 6.0, lift=0.0003)
    _, _, log = run(text)
    gaps = np.diff(log["time"][log["kind"] == EV_WALL])[-10:]
    period = 1.0 / FREQ
    np.testing.assert_allclose(gaps[:-1] + gaps[1:], 2 * period, rtol=0, atol=1e-9)
    assert abs(gaps[0] - gaps[1]) > 0.1 * period
    np.testing.assert_allclose(gaps[2:], gaps[:-2], rtol=0, atol=1e-9)


def test_the_contact_search_never_steps_past_a_root():
    """Random flights against an oscillating plane: the time found is a root of the gap, and
    the gap is positive on a fine grid before it (no earlier contact was missed)."""
    rng = np.random.default_rng(7)
    mot = np.zeros((1, 8))
    for _ in range(300):
        amp, omega = rng.uniform(1e-4, 2e-3), rng.uniform(20.0, 400.0)
        cn = rng.uniform(-1.0, 1.0)
        mot[0] = [1.0, 0.0, 0.0, 1.0, amp, omega, rng.uniform(0, 2 * math.pi), 0.0]
        t0 = rng.uniform(0.0, 1.0)
        g0 = rng.uniform(0.0, 5e-3) + abs(cn) * 2 * amp
        vn, gn = rng.uniform(-0.5, 0.5), rng.uniform(-10.0, 0.0)

        def gap(tau, t0=t0, g0=g0, vn=vn, gn=gn, cn=cn, amp=amp, omega=omega, ph=mot[0, 6]):
            return (g0 + vn * tau + 0.5 * gn * tau * tau
                    - cn * amp * (np.sin(omega * (t0 + tau) + ph) - np.sin(omega * t0 + ph)))

        tau = moving_plane_contact_time(g0, vn, gn, mot, 0, cn, t0, RADIUS, 1.0)
        grid = np.linspace(0.0, min(tau, 1.0), 20001)[:-1]
        assert np.all(gap(grid) > -1e-13)
        if tau < 1.0:
            assert abs(gap(tau)) < 1e-13


def test_moving_walls_in_scenes_and_files(tmp_path):
    text, _ = ball_scene(0.5, 1.3, 0.1)
    scene = parse_scene(text)
    assert scene.planes[0].motion is not None
    assert scene.planes[0].point_at(0.0) == pytest.approx([0.0, 0.0, 0.0], abs=1e-18)
    path = tmp_path / "ball.toml"
    path.write_text(text)
    from hsgran.api import run_scene
    from hsgran.io.h5md import read_trajectory

    run_scene(path, tmp_path / "ball.h5")
    walls = read_trajectory(tmp_path / "ball.h5").walls
    assert walls.motion is not None
    assert walls.motion[0, M_KIND] != MOT_FIXED
    np.testing.assert_allclose(walls.shift(0, 0.0125), scene.planes[0].point_at(0.0125),
                               atol=1e-18)


@pytest.mark.parametrize(("motion", "needle"), [
    ('{ kind = "wobble" }', "walls[0].motion.kind"),
    ('{ kind = "oscillation", amplitude = 0.001 }', "walls[0].motion.frequency"),
    ('{ kind = "oscillation", amplitude = -1.0, frequency = 5.0 }', "walls[0].motion.amplitude"),
    ('{ kind = "velocity", velocity = [0.0, 0.0, 0.0], travel = 1.0 }',
     "walls[0].motion.velocity"),
    ('{ kind = "velocity", velocity = [0.0, 0.0, 1.0] }', "walls[0].motion.travel"),
    ('{ kind = "oscillation", amplitude = 0.001, frequency = 5.0, speed = 1 }',
     "walls[0].motion"),
])
def test_bad_motions_name_their_key(motion, needle):
    text = PISTON.format(vx=0.1, vy=0.0, u=0.0, start=0.0)
    text = text.replace(text[text.index("motion = {"):text.index("}\n[[particles]]") + 1],
                        f"motion = {motion}")
    with pytest.raises(InputError) as err:
        parse_scene(text)
    assert needle in str(err.value)


def test_exported_walls_move_with_the_plate(tmp_path):
    pytest.importorskip("pyvista")
    import pyvista as pv

    from hsgran.api import run_scene
    from hsgran.export import export

    text, (amp, omega, phase, _) = ball_scene(0.5, 1.3, 0.02)
    path = tmp_path / "ball.toml"
    path.write_text(text)
    run_scene(path, tmp_path / "ball.h5")
    result = export(tmp_path / "ball.h5", "vtk", tmp_path / "vtk")
    reader = pv.get_reader(str(result.output))
    for k, t in enumerate(reader.time_values):
        reader.set_active_time_value(t)
        walls = reader.read()[1]
        z = amp * (math.sin(omega * t + phase) - math.sin(phase))
        np.testing.assert_allclose(walls.points[:, 2], z, atol=1e-15, err_msg=f"frame {k}")


def test_the_force_on_a_vibrating_plate_follows_the_ball_it_drives():
    """On the period-1 orbit each bounce gives the plate the impulse m g T (the ball's momentum
    is the same one period later), so the plate's force averaged over each period is the
    ball's weight; within a period it is one impulse at the launch phase θ."""
    e, gamma = 0.5, 1.3
    text, (_, omega, phase, _) = ball_scene(e, gamma, 2.0, lift=0.0003)
    period = 1.0 / FREQ
    text = text.replace("frame_interval = 0.005",
                        f"frame_interval = {period / 4!r}\nobservables = true")
    sim, frames, log = run(text)
    weight = float(sim.mass[0]) * G
    impulse = frames["wall_impulse"][1:, 0, 2]  # on the plate, per quarter period [N s]
    per_period = impulse[-40:].reshape(10, 4).sum(axis=1)
    np.testing.assert_allclose(per_period, -weight * period, rtol=1e-9)
    hits = log["time"][log["kind"] == EV_WALL]
    quarter = np.floor(np.mod(omega * hits[-10:] + phase, 2 * math.pi) / (math.pi / 2))
    theta = math.acos(window(e)[0] / gamma)
    assert np.all(quarter == math.floor(theta / (math.pi / 2)))  # every hit in θ's quarter
