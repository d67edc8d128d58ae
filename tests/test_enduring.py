"""Enduring contact on a plane: sliding, rolling, rest, inclines, and bouncing that ends on the
plate (issue: sliding, rolling and resting; MODEL §5.3)."""

import math

import numpy as np
import pytest

from hsgran.api import run_scene
from hsgran.engine import Simulation
from hsgran.io import read_trajectory
from hsgran.onplane import END_SLIP, END_STOP, MS_REST, MS_ROLLING, MS_SLIDING
from hsgran.refdata import read_csv
from hsgran.scene import parse_scene

#: Engine vs closed form evaluated here: both are the same algebra in a different order, so
#: they agree to rounding (measured ≤ 3e-15 relative); 1e-9 is the issue's bound.
CLOSED_FORM_RTOL = 1e-9
#: The shipped table has 6 significant digits: half a unit of the 6th digit, relative to the
#: smallest tabulated value's leading digit (0.031205 → 5e-7 / 0.031 = 1.6e-5).
TABLE_RTOL = 2e-5
K = 0.4  #: I/(m R²) of a solid sphere

PLATE = """
[scene]
name = "sphere on plate"
duration = {duration}
gravity = [0.0, 0.0, {gz}]
effects = ["gravity", "rotation", "friction", "rolling_resistance"]
[output]
frame_interval = {frame}
[enduring_contact]
rolling_convention = "{conv}"
[materials.m]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[[contacts]]
between = ["m", "m"]
sliding_friction = {mu_s}
rolling_friction = {mu_r}
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [{nx}, 0.0, {nz}]
material = "m"
[[particles]]
material = "m"
radius = {r}
position = [{px}, 0.0, {pz}]
velocity = [{vx}, 0.0, {vz}]
angular_velocity = [0.0, {omega}, 0.0]
"""


def plate_scene(v0, omega0, r, mu_s, mu_r, g, conv, duration=None):
    """Sphere on a horizontal plate moving along +x; omega0 > 0 is forward (topspin) roll:
    rolling forwards along +x with a +z normal means ω along +y with v = R ω."""
    return parse_scene(PLATE.format(
        duration=duration or 100.0, gz=-g, frame=duration or 100.0, conv=conv, mu_s=mu_s,
        mu_r=mu_r, nx=0.0, nz=1.0, r=r, px=0.0, pz=r, vx=v0, vz=0.0, omega=omega0))


class Keep:
    def __init__(self):
        self.events = []

    def on_events(self, b):
        self.events.append(b)

    def log(self, name):
        return np.concatenate([getattr(b, name) for b in self.events])


def run_plate(scene):
    """(slide-end time, speed at roll start, slide distance, stop time, stop distance)."""
    keep = Keep()
    Simulation(scene, log_events=True).run(observers=[keep])
    t, stage, regime = keep.log("time"), keep.log("stage"), keep.log("regime")
    rolls = np.flatnonzero((stage == MS_ROLLING) & (regime == END_SLIP))
    rests = np.flatnonzero(stage == MS_REST)
    assert len(rolls) == 1
    assert len(rests) == 1
    t1, t2 = t[rolls[0]], t[rests[0]]
    sim = Simulation(scene)
    sim.run(until=t1)
    x1, v1 = sim.pos[0, 0], sim.vel[0, 0]
    assert sim.mstate[0] == MS_ROLLING
    sim.run()
    assert sim.mstate[0] == MS_REST
    np.testing.assert_array_equal(sim.vel[0], 0.0)
    np.testing.assert_allclose(sim.pos[0, 2], scene.radius[0], rtol=1e-15)
    return t1, v1, x1, t2, sim.pos[0, 0]


def closed_form(v0, omega0, r, mu_s, mu_r, g, conv):
    """MODEL §5.3, phases 1 and 2, for a launch with u0 = v0 − R Ω0 > 0."""
    chi = 1.0 if conv == "A" else 0.0
    u0 = v0 - r * omega0
    assert u0 > 0
    if omega0 < 0 and chi:
        # backspin, convention A: the rolling torque helps until the spin passes zero
        t1 = (u0 - 2 * mu_r * r * abs(omega0) / (mu_s + mu_r)) / (g * (3.5 * mu_s - 2.5 * mu_r))
    else:
        t1 = u0 / (g * (3.5 * mu_s - 2.5 * chi * mu_r))
    v1 = v0 - mu_s * g * t1
    x1 = v0 * t1 - mu_s * g * t1**2 / 2
    t2 = v1 * (1 + K) / (mu_r * g)
    x2 = v1**2 * (1 + K) / (2 * mu_r * g)
    return t1, v1, x1, t1 + t2, x1 + x2


@pytest.mark.parametrize("row", range(8))
def test_sphere_on_plate_reproduces_the_shipped_closed_form_table(row):
    tab = read_csv("derived_sphere_on_plate_closed_form.csv")
    conv = tab["convention"][row][0]
    args = (tab["v0_m_s"][row], tab["omega0_rad_s"][row], tab["radius_m"][row],
            tab["mu_s"][row], tab["mu_r_dimensionless"][row], tab["g_m_s2"][row])
    got = run_plate(plate_scene(*args, conv))
    want = [tab[k][row] for k in ("t_slide_end_s", "v_at_roll_start_m_s", "x_slide_m",
                                  "t_stop_s", "x_stop_m")]
    np.testing.assert_allclose(got, want, rtol=TABLE_RTOL)


CASES = [
    # v0, Ω0 (+ topspin, − backspin), R, μ_s, μ_r, g
    (1.0, 0.0, 0.01, 0.3, 0.01, 9.81),
    (2.5, -150.0, 0.005, 0.4, 0.02, 9.81),  # backspin
    (0.8, 40.0, 0.01, 0.25, 0.005, 9.81),  # topspin, still slipping forwards
    (0.3, -5.0, 0.02, 0.6, 0.1, 3.7),  # backspin on another planet
]


@pytest.mark.parametrize("conv", ["A", "B"])
@pytest.mark.parametrize("case", CASES, ids=["plain", "backspin", "topspin", "mars"])
def test_sphere_on_plate_equals_the_closed_form_to_1e9(case, conv):
    got = run_plate(plate_scene(*case, conv))
    np.testing.assert_allclose(got, closed_form(*case, conv), rtol=CLOSED_FORM_RTOL)


def incline(theta_deg, mu_s, mu_r, v0=0.0):
    """A sphere touching a plane tilted by θ about y (the fall line is +x), started with speed
    v0 along the fall line, rolling (no slip) if it moves."""
    th = math.radians(theta_deg)
    n = (math.sin(th), 0.0, math.cos(th))  # normal tilted towards +x: downhill is +x
    r = 0.01
    v = (v0 * math.cos(th), 0.0, -v0 * math.sin(th))
    omega = v0 / r
    return parse_scene(PLATE.format(
        duration=0.5, gz=-9.81, frame=0.05, conv="A", mu_s=mu_s, mu_r=mu_r, nx=n[0], nz=n[2],
        r=r, px=r * n[0], pz=r * n[2], vx=v[0], vz=v[2], omega=omega)), th


def distance_along_fall_line(sim, scene, th, t):
    pos, _ = sim.state_at(t)
    d = pos[0] - scene.position[0]
    return d[0] * math.cos(th) - d[2] * math.sin(th)


@pytest.mark.parametrize("theta", [5.0, 20.0, 40.0])
def test_incline_rolls_at_five_sevenths_g_sin_theta_below_the_slip_angle(theta):
    mu_s = 0.3  # rolls while tan θ ≤ 3.5 μ_s = 1.05 (θ ≤ 46.4°)
    scene, th = incline(theta, mu_s, 0.0)
    sim = Simulation(scene)
    assert sim.mstate[0] == MS_ROLLING
    sim.run(until=0.5)
    a = 5.0 / 7.0 * 9.81 * math.sin(th)
    got = distance_along_fall_line(sim, scene, th, 0.5)
    np.testing.assert_allclose(got, 0.5 * a * 0.5**2, rtol=CLOSED_FORM_RTOL)
    # no slip: ω R equals the speed
    _, vel = sim.state_at(0.5)
    np.testing.assert_allclose(np.linalg.norm(vel[0]), a * 0.5, rtol=CLOSED_FORM_RTOL)


def slides_down(theta, mu_s, mu_r):
    """Start a sphere at rest on the incline, check that it slides and has covered
    ½ g (sin θ − μ_s cos θ) t² along the fall line at t = 0.5 s; returns the simulation."""
    scene, th = incline(theta, mu_s, mu_r)
    sim = Simulation(scene)
    assert sim.mstate[0] == MS_SLIDING
    sim.run(until=0.5)
    a = 9.81 * (math.sin(th) - mu_s * math.cos(th))
    got = distance_along_fall_line(sim, scene, th, 0.5)
    np.testing.assert_allclose(got, 0.5 * a * 0.5**2, rtol=CLOSED_FORM_RTOL)
    return sim


@pytest.mark.parametrize("theta", [50.0, 70.0])
def test_incline_slides_above_the_slip_angle(theta):
    slides_down(theta, 0.3, 0.0)


def test_slip_angle_boundary_is_tan_theta_equals_seven_halves_mu_s():
    mu_s = 0.2
    boundary = math.degrees(math.atan(3.5 * mu_s))
    below, _ = incline(boundary - 0.01, mu_s, 0.0)
    above, _ = incline(boundary + 0.01, mu_s, 0.0)
    assert Simulation(below).mstate[0] == MS_ROLLING
    assert Simulation(above).mstate[0] == MS_SLIDING


def test_a_slope_that_rolling_friction_holds_but_sliding_friction_does_not_is_slid_down():
    # μ_r > μ_s (unusual): the rolling torque could hold the spin at tan θ = 0.1, but friction
    # cannot hold the contact point, so the sphere slides down without spinning (convention A:
    # the resisting couple cancels the friction torque)
    sim = slides_down(math.degrees(math.atan(0.1)), mu_s=0.05, mu_r=0.2)
    assert np.all(sim.alpha[0] == 0.0)  # the spin stays zero


def test_rolling_friction_holds_a_sphere_on_a_gentle_slope():
    mu_r = 0.05  # holds while tan θ ≤ μ_r (θ ≤ 2.86°)
    held, _ = incline(2.5, 0.3, mu_r)
    sim = Simulation(held)
    assert sim.mstate[0] == MS_REST
    sim.run()
    np.testing.assert_array_equal(sim.pos[0], held.position[0])
    rolls, _ = incline(3.5, 0.3, mu_r)
    assert Simulation(rolls).mstate[0] == MS_ROLLING


def test_sphere_rolling_uphill_stops_and_rolls_back_down():
    mu_r = 0.01
    theta = 10.0
    scene, th = incline(theta, 0.3, mu_r, v0=-0.5)  # launched uphill, rolling
    keep = Keep()
    sim = Simulation(scene, log_events=True)
    sim.run(observers=[keep])
    g = 9.81
    t_stop = 0.5 / _uphill_deceleration(th, mu_r)
    stops = keep.log("time")[keep.log("regime") == END_STOP]
    np.testing.assert_allclose(stops[0], t_stop, rtol=CLOSED_FORM_RTOL)
    accel = (g * math.sin(th) - mu_r * g * math.cos(th)) / (1 + K)
    want = -0.5 * t_stop / 2 + 0.5 * accel * (0.5 - t_stop) ** 2
    np.testing.assert_allclose(distance_along_fall_line(sim, scene, th, 0.5), want,
                               rtol=CLOSED_FORM_RTOL)


def _uphill_deceleration(th, mu_r, g=9.81):
    """Deceleration of a sphere rolling up an incline of θ [rad] against rolling friction μ_r
    [m/s²] (MODEL §5.3)."""
    return (g * math.sin(th) + mu_r * g * math.cos(th)) / (1 + K)


@pytest.mark.parametrize("theta", [10.0, 19.0, 33.0])
@pytest.mark.parametrize("v0", [-0.5, -3.6e-6])
def test_sphere_rolling_uphill_stops_once(theta, v0):
    """A sphere rolling up an incline stops once and rolls back down: one END_STOP event, not
    a stop at the same instant after each stop, every one from the round-off the last left
    across the rolling direction (a corpus sphere did ~250 after each bounce; ROLL_REST_TIME).
    Launched at 0.5 m/s and at 3.6 µm/s, the speed of that corpus sphere."""
    scene, th = incline(theta, 0.3, 0.01, v0=v0)
    keep = Keep()
    sim = Simulation(scene, log_events=True)
    sim.run(observers=[keep])
    assert np.count_nonzero(keep.log("regime") == END_STOP) == 1
    np.testing.assert_allclose(keep.log("time")[keep.log("regime") == END_STOP],
                               -v0 / _uphill_deceleration(th, 0.01), rtol=CLOSED_FORM_RTOL)


def test_a_rolling_speed_below_what_the_load_gives_in_the_rest_time_is_none():
    """plane_segment: a velocity of 1e-30 m/s across the last rolling direction after a stop
    (its round-off) does not start a segment that ends 1e-31 s later: the sphere starts from
    rest down the fall line, a segment without end; 1e-6 m/s (a real speed) still rolls and
    stops."""
    from hsgran.onplane import ROLL_REST_TIME, plane_segment

    th = math.radians(19.0)
    n = np.array([math.sin(th), 0.0, math.cos(th)])
    up = np.array([-math.cos(th), 0.0, math.sin(th)])
    g = np.array([0.0, 0.0, -9.81])
    side = np.array([0.0, 1.0, 0.0])
    for speed, stops in ((1e-30, False), (0.5 * ROLL_REST_TIME * 9.81 * math.cos(th), False),
                         (1e-6, True)):
        v = speed * (0.6 * up + 0.8 * side)
        w = np.cross(n, v) / 0.01
        sdir = side.copy()
        state, *_, dur, code = plane_segment(v, w, n, g, 0.01, K, 0.3, 0.01, 1.0, END_STOP,
                                             sdir)
        assert state == MS_ROLLING
        if stops:
            assert code == END_STOP
            assert dur > 0.0
        else:
            assert code != END_STOP
            assert dur == math.inf
            assert not v.any()


BOUNCE = """
[scene]
name = "dropped ball"
duration = 8.0
gravity = [0.0, 0.0, -9.81]
effects = ["gravity", "rotation", "friction", "rolling_resistance"]
[output]
frame_interval = 0.1
[enduring_contact]
landing_speed = {landing}
[materials.m]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[[contacts]]
between = ["m", "m"]
restitution = {e}
sliding_friction = 0.3
rolling_friction = 0.01
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "m"
[[particles]]
material = "m"
radius = 0.005
position = [0.0, 0.0, {h}]
"""


@pytest.mark.parametrize("landing_speed", [1e-3, 1e-6])
@pytest.mark.parametrize("e", [0.5, 0.8, 0.95])
def test_dropped_ball_comes_to_rest_after_the_geometric_series_of_bounces(e, landing_speed):
    h, g = 0.1, 9.81
    scene = parse_scene(BOUNCE.format(e=e, h=h + 0.005, landing=landing_speed))
    # below |g| tc_time / 2 (4.9e-5 m/s with the default TC time) a rebound would come back
    # within tc_time and be elastic for ever: the engine lands it at that speed instead
    landing = max(landing_speed, g * scene.tc_time / 2)
    assert scene.effective_landing_speed == pytest.approx(landing, rel=1e-15)
    keep = Keep()
    sim = Simulation(scene, log_events=True)
    summary = sim.run(observers=[keep])
    assert sim.mstate[0] == MS_REST
    kinds = keep.log("kind")
    assert kinds[-1] == 8  # landed
    t_land = keep.log("time")[-1]
    # bounces until the rebound speed e^k v0 falls below the landing speed
    v0 = math.sqrt(2 * g * h)
    n_bounces = math.ceil(math.log(landing / v0) / math.log(e))
    assert summary.collisions <= n_bounces + 1
    # geometric series: all infinitely many bounces end at t_fall + 2 e v0 / (g (1 − e));
    # landing early gives up at most the remaining bounces, 2 v_land / (g (1 − e))
    t_inf = math.sqrt(2 * h / g) + 2 * e * v0 / (g * (1 - e))
    assert t_inf - 2 * landing / (g * (1 - e)) <= t_land <= t_inf


def test_trajectory_frames_record_sliding_rolling_and_rest_at_the_closed_form_times(tmp_path):
    case = CASES[0]
    t1, _, _, t2, _ = closed_form(*case, "A")
    scene = plate_scene(*case, "A", duration=1.2 * t2)
    scene.frame_interval = t2 / 40  # no frame falls on a transition: t1, t2 are no multiples
    out = tmp_path / "plate.h5"
    run_scene(scene, out)
    traj = read_trajectory(out)
    want = np.where(traj.time < t1, MS_SLIDING, np.where(traj.time < t2, MS_ROLLING, MS_REST))
    np.testing.assert_array_equal(traj.motion_state[:, 0], want)
    assert {MS_SLIDING, MS_ROLLING, MS_REST} <= set(traj.motion_state[:, 0].tolist())


#: Relative tolerance of the energy books of a sphere on a plate: the initial energy, the
#: closed-form loss and the frame energies are sums of a few products each.
ENERGY_RTOL = 1e-12


@pytest.mark.parametrize("case", CASES[:3], ids=["plain", "backspin", "topspin"])
def test_energy_lost_on_a_plate_is_dissipated_energy_and_follows_the_closed_form(case):
    """Sliding friction and rolling resistance on a plane are counted as dissipated (MODEL.md
    §5.3): at rest everything the sphere had is dissipated, and at the end of sliding the loss
    is the closed form's."""
    v0, omega0, r = case[:3]
    t1, v1, _, t2, _ = closed_form(*case, "A")
    scene = plate_scene(*case, "A", duration=1.1 * t2)
    scene.frame_interval = t2 / 37
    sim = Simulation(scene)
    m = sim.mass[0]
    inertia = sim.inertia[0]
    e0 = 0.5 * m * v0**2 + 0.5 * inertia * omega0**2
    frames = []

    class Frames:
        def on_frames(self, b):
            frames.append(b)

    sim.run(until=t1, observers=[Frames()])
    # at roll onset the sphere rolls: ω1 = v1 / R
    want = e0 - (0.5 * m * v1**2 + 0.5 * inertia * (v1 / r) ** 2)
    assert sim.dissipated_energy(t1) == pytest.approx(want, rel=ENERGY_RTOL)
    sim.run(observers=[Frames()])
    assert sim.dissipated_energy() == pytest.approx(e0, rel=ENERGY_RTOL)
    assert sim.collision_loss == 0.0  # no collision: all of it went to friction on the plate
    diss = np.concatenate([b.dissipated for b in frames])
    assert diss[0] == pytest.approx(0.0, abs=ENERGY_RTOL * e0)
    assert diss[-1] == pytest.approx(e0, rel=ENERGY_RTOL)
    assert np.all(np.diff(diss) >= -ENERGY_RTOL * e0)  # never gained back


def test_a_snapped_spin_end_leaves_no_rolling_spin_that_ends_again_at_once():
    """A sphere sliding at 7e-12 m/s on a 6.4° plane of a corpus polygon, spinning about the
    normal at 1.4e-9 rad/s, rolling spin 4e-18 rad/s: its spin end (END_SPIN, convention A)
    came 3e-20 s later, was snapped, and came again, until the collapse guard stopped the run
    at 0.1996 s. The rolling spin's direction, from a rolling spin near the rounding of the
    whole spin, left the plane by 3e-8, and the snap along it made the next one. The state
    below is the loop's (its direction the old one): the first segment may still end at once,
    but the one after its snap, along a direction in the plane, does not."""
    from hsgran.onplane import CONVENTION_A, END_SPIN, plane_segment

    n = np.array([-0.1119644759894172, -0.0, 0.993712209906075])
    g = np.array([0.0, 0.0, -9.81])
    v = np.array([-2.2085576388032713e-18, 6.5980862024088053e-12, -2.4884468184647297e-19])
    w = np.array([-1.5396419682819323e-10, 4.5301837348345403e-18, 1.3664700426144004e-09])
    sdir = np.array([2.8530182941052638e-08, 9.9999999999999967e-01, 0.0])
    for k in range(4):
        state, *_, dur, code = plane_segment(v, w, n, g, 0.00199925069, 0.4, 0.708646531,
                                             0.0110893784, CONVENTION_A, END_SPIN, sdir)
        assert state == MS_SLIDING
        assert abs(np.dot(sdir, n)) < 1e-15  # the next snap's direction lies in the plane
        if code != END_SPIN:
            break
        assert k == 0 or dur > 1e-12, "a spin end again within round-off of the clock"
    rolling = w - np.dot(w, n) * n
    assert np.linalg.norm(rolling) < 1e-20
