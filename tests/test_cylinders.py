"""Cylinder walls (docs/walls.md, "Cylinders"): the contact search against a fine-grid oracle,
elastic gases inside a drum and around a post, a ball bouncing in a drum under gravity, the drag
of a rotating drum, the scene keys, the file and the exported drawing."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from hsgran._cluster import STEP_MAX
from hsgran._flight import TOUCH_REL
from hsgran.engine import Simulation
from hsgran.errors import InputError
from hsgran.events.kinds import EV_LAND, EV_WALL
from hsgran.motion import cylinder_contact_time
from hsgran.onplane import MS_FLIGHT, MS_REST, MS_ROLLING
from hsgran.scene import parse_scene
from tests.observers import Keep

#: A contact time is a root of the squared-distance quartic to this share of ρ² [-] (rounding
#: of |q|² near ρ², a few ulp of the terms).
ROOT_REL = 1e-12
#: Elastic runs keep their energy to this share [-] (rounding over ~10⁴ collisions).
ENERGY_REL = 1e-11
#: Spheres stay clear of the walls to this [m] (the touching tolerance of the contact times).
OVERLAP_TOL = 1e-12


def run(text, **kw):
    """Run a scene; return the scene, its frames (time, position, velocity) and event log."""
    scene = parse_scene(text)
    sim = Simulation(scene, log_events=True)
    keep = Keep()
    sim.run(observers=[keep], **kw)
    frames = {name: keep.cat(name) for name in ("time", "position", "velocity",
                                                 "angular_velocity", "motion_state")
              if getattr(keep.frames[0], name) is not None}
    log = {name: keep.log(name) if keep.events else np.zeros(0)
           for name in ("time", "kind", "i", "j")}
    return scene, frames, log


def energy(scene, frames):
    """Kinetic plus potential energy of every frame [J] (no rotation in these scenes)."""
    m = scene.mass()
    ke = 0.5 * np.einsum("i,fik,fik->f", m, frames["velocity"], frames["velocity"])
    return ke - np.einsum("i,fik,k->f", m, frames["position"], scene.gravity)


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_the_contact_search_finds_the_first_touch(side):
    """Random parabolas inside (side +1) and outside (−1) a cylinder: the time found is a root
    of |q(τ)|² = ρ², and the sphere is clear of the surface on a fine grid before it."""
    rng = np.random.default_rng(11 if side > 0 else 12)
    found = 0
    for _ in range(300):
        rho = rng.uniform(0.01, 0.1)
        q0 = rng.normal(size=3)
        q0[2] = 0.0  # the axis is z: q lies in the x-y plane
        q0 *= (rng.uniform(0.0, 0.99) if side > 0 else rng.uniform(1.01, 3.0)) * rho \
            / np.linalg.norm(q0)
        u = np.array([*rng.normal(0.0, 0.5, 2), 0.0])
        g = np.array([*rng.normal(0.0, 10.0, 2), 0.0]) * rng.integers(0, 2)
        horizon = 1.0

        def clear(tau, q0=q0, u=u, g=g, rho=rho):
            q = q0[:, None] + np.outer(u, tau) + 0.5 * np.outer(g, tau * tau)
            return side * (rho * rho - (q * q).sum(0))

        tau = cylinder_contact_time(*q0, *u, *g, rho, side, horizon)
        grid = np.linspace(0.0, min(tau, horizon), 20001)[:-1]
        assert np.all(clear(grid) > -ROOT_REL * rho * rho)
        if tau < horizon:
            found += 1
            assert abs(clear(np.array([tau]))[0]) < ROOT_REL * rho * rho
        else:  # none within the horizon: the oracle finds none either
            ts = np.linspace(0.0, horizon, 200001)
            assert np.all(clear(ts) > -ROOT_REL * rho * rho)
    assert found > 50  # many flights meet the wall (inside: all that turn back or fall)


GAS = """
[scene]
name = "gas in a drum"
duration = 0.5
effects = []
seed = {seed}
[output]
frame_interval = 0.005
[[walls]]
kind = "cylinder"
center = [0.0, 0.0, 0.0]
axis = [{ax}, {ay}, {az}]
radius = 0.03
length = 0.02
material = "steel"
[[fill]]
count = 40
material = "steel"
radius = 0.002
region = {{ lower = [-0.03, -0.03, -0.03], upper = [0.03, 0.03, 0.03] }}
speed = 0.5
"""


@pytest.mark.parametrize(("seed", "axis"), [(1, (0.0, 1.0, 0.0)), (2, (1.0, 1.0, 1.0))])
def test_an_elastic_gas_in_a_closed_drum_keeps_its_energy_and_stays_inside(seed, axis):
    scene, frames, log = run(GAS.format(seed=seed, ax=axis[0], ay=axis[1], az=axis[2]))
    cyl = scene.cylinders[0]
    e = energy(scene, frames)
    assert abs(e[-1] / e[0] - 1.0) < ENERGY_REL
    gaps = cyl.distance(frames["position"]) - scene.radius
    assert gaps.min() > -OVERLAP_TOL
    for cap in scene.planes:
        assert (cap.distance(frames["position"]) - scene.radius).min() > -OVERLAP_TOL
    # the curved wall (the last wall row) was hit many times
    assert np.count_nonzero((log["kind"] == EV_WALL) & (log["j"] == -1 - 2)) > 100


POST = """
[scene]
name = "gas around a post"
duration = 0.5
effects = []
seed = 4
[output]
frame_interval = 0.005
[[walls]]
kind = "box"
lower = [-0.03, -0.03, -0.01]
upper = [0.03, 0.03, 0.01]
material = "steel"
[[walls]]
kind = "cylinder"
center = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
radius = 0.012
length = 0.02
side = "outside"
material = "steel"
[[fill]]
count = 40
material = "steel"
radius = 0.002
region = { lower = [-0.03, -0.03, -0.01], upper = [0.03, 0.03, 0.01] }
speed = 0.5
"""


def test_an_elastic_gas_around_a_post_keeps_its_energy_and_stays_outside():
    scene, frames, log = run(POST)
    e = energy(scene, frames)
    assert abs(e[-1] / e[0] - 1.0) < ENERGY_REL
    post = scene.cylinders[0]
    assert (post.distance(frames["position"]) - scene.radius).min() > -OVERLAP_TOL
    row = len(scene.planes)
    assert np.count_nonzero((log["kind"] == EV_WALL) & (log["j"] == -1 - row)) > 50


BALL = """
[scene]
name = "ball in a drum"
duration = {duration}
effects = ["gravity"{more}]
[output]
frame_interval = 0.01
[[walls]]
kind = "cylinder"
center = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
radius = 0.05
length = 0.01
angular_velocity = {omega}
material = "steel"
[[particles]]
material = "steel"
radius = 0.002
position = [{x}, 0.0, {z}]
velocity = [{u}, 0.0, {w}]
"""


def test_an_elastic_ball_bounces_in_a_drum_on_its_parabolas():
    """Every wall event finds the ball at R − r from the axis, and the energy is kept."""
    scene, frames, log = run(BALL.format(duration=2.0, more="", omega=0.0, x=0.01, z=0.0,
                                         u=0.3, w=0.2))
    e = energy(scene, frames)
    assert abs(e[-1] / e[0] - 1.0) < ENERGY_REL
    assert np.count_nonzero(log["kind"] == EV_WALL) > 20
    sim = Simulation(scene)
    for _ in range(20):  # the ball's stored state after each hit is where it touched
        sim.run(max_collisions=1)
        assert abs(np.hypot(sim.pos[0, 0], sim.pos[0, 2]) - (0.05 - 0.002)) < 1e-12


@pytest.mark.parametrize("omega", [4.0, -4.0])
def test_a_rotating_drum_drags_the_sphere_it_hits(omega):
    """Without gravity a sphere thrown straight at a rotating drum's wall leaves rolling on
    the surface (μ J_n exceeds the impulse that stops the slip): its tangential velocity is
    2/7 of the surface's, Ω R, in the surface's direction (MODEL §4, a solid sphere, k = 2/5),
    and the normal velocity is reversed (elastic)."""
    text = BALL.format(duration=0.2, more=', "friction", "rotation"', omega=omega, x=0.0,
                       z=0.0, u=0.0, w=-0.5).replace('effects = ["gravity", ', "effects = [")
    text += "[[contacts]]\nbetween = [\"steel\", \"steel\"]\nsliding_friction = 0.3\n"
    _scene, frames, log = run(text)
    assert np.count_nonzero(log["kind"] == EV_WALL) == 1
    v = frames["velocity"][-1, 0]
    # at the bottom (−z) the surface moves along Ω ŷ × (−R ẑ) = −Ω R x̂
    assert v[0] == pytest.approx(-2.0 / 7.0 * omega * 0.05, rel=1e-12)
    assert v[2] == pytest.approx(0.5, rel=1e-12)


@pytest.mark.parametrize(("change", "needle"), [
    (('side = "outside"', 'side = "around"'), "walls[0].side"),
    (('radius = 0.03', 'radius = -0.03'), "walls[0].radius"),
    (('length = 0.02', 'length = 0.0'), "walls[0].length"),
    (('axis = [0.0, 1.0, 0.0]', 'axis = [0.0, 0.0, 0.0]'), "walls[0].axis"),
    (('material = "steel"\n[[fill]]', 'material = "steel"\ncaps = true\n[[fill]]'),
     "walls[0].caps"),
    (('kind = "cylinder"', 'kind = "cylindre"'), "walls[0].kind"),
    (('length = 0.02', 'length = 0.02\nspin = 3.0'), "walls[0]"),
])
def test_bad_cylinders_name_their_key(change, needle):
    text = GAS.format(seed=1, ax=0.0, ay=1.0, az=0.0).replace(
        'length = 0.02', 'length = 0.02\nside = "outside"').replace(
        'region = { lower = [-0.03, -0.03, -0.03], upper = [0.03, 0.03, 0.03] }',
        'region = { lower = [0.04, -0.03, -0.03], upper = [0.09, 0.03, 0.03] }')
    parse_scene(text)  # the unchanged scene is valid
    old, new = change
    assert old in text
    with pytest.raises(InputError) as err:
        parse_scene(text.replace(old, new, 1))
    assert needle in str(err.value)


def test_spheres_must_start_on_the_cylinders_side():
    text = BALL.format(duration=0.1, more="", omega=0.0, x=0.049, z=0.0, u=0.0, w=0.0)
    with pytest.raises(InputError) as err:
        parse_scene(text)
    assert "particles[0].position" in str(err.value)
    assert "walls[0]" in str(err.value)


def test_turning_cylinders_are_refused_with_the_cluster_treatment():
    text = BALL.format(duration=0.1, more="", omega=2.0, x=0.0, z=0.0, u=0.0, w=0.0)
    with pytest.raises(InputError) as err:
        parse_scene(text + '[enduring_contact]\ntreatment = "clusters"\n')
    assert "enduring_contact.treatment" in str(err.value)
    assert "walls[0]" in str(err.value)


#: Off the drum's bottom the two spheres rock for about a second, some 10⁴ steps (0.6 s of CPU
#: compiled, 1–2 minutes in pure Python): without the compiler only the drop at the bottom runs.
ROCKING = pytest.mark.skipif(numba.config.DISABLE_JIT, reason="too slow without the compiler")


@pytest.mark.parametrize("x0", [0.0, pytest.param(0.004, marks=ROCKING),
                                pytest.param(0.011, marks=ROCKING)])
def test_two_spheres_in_a_fixed_drum_come_to_rest_at_its_bottom_as_a_cluster(x0):
    """Two spheres dropped side by side (offset by ``x0``) into a fixed drum with the cluster
    treatment (rolling resistance stops their rocking): they meet the inside of the cylinder
    and each other at once, a cluster with concave contacts (hsgran._cluster._sink), and come
    to rest touching the cylinder (R − r from its axis) and each other (within TOUCH_REL σ),
    never sinking into it by more than the touching tolerance. Rolling resistance alone takes
    2 μ_r of a rolling pendulum's amplitude every half swing (its work μ_r m g per length
    rolled against the potential m g ρ θ²/2), so the swing of x0 = 0.011 (θ ≈ 0.23 rad, half
    period π √(7ρ/5g) ≈ 0.26 s) lasts some 1.5 s after the landing; the sliding between the
    two spheres shortens it (at rest by 1.3 s)."""
    r, big = 0.002, 0.05
    text = BALL.format(duration=2.0, more=', "rotation", "friction", "rolling_resistance"',
                       omega=0.0, x=x0 - 0.00201, z=-0.03, u=0.0, w=0.0)
    text += ("[[particles]]\nmaterial = \"steel\"\nradius = 0.002\n"
             f"position = [{x0 + 0.00201}, 0.0, -0.03]\n"
             "[enduring_contact]\ntreatment = \"clusters\"\n"
             "[[contacts]]\nbetween = [\"steel\", \"steel\"]\nrestitution = 0.5\n"
             "sliding_friction = 0.3\nrolling_friction = 0.02\n")
    _, frames, _ = run(text)
    pos = frames["position"]
    from_axis = np.hypot(pos[..., 0], pos[..., 2])
    assert from_axis.max() <= big - r + OVERLAP_TOL
    gap = np.linalg.norm(pos[:, 0] - pos[:, 1], axis=-1) - 2 * r
    assert gap.min() > -OVERLAP_TOL
    assert np.all(frames["motion_state"][-1] == MS_REST)
    np.testing.assert_allclose(from_axis[-1], big - r, rtol=0, atol=1e-9)
    assert gap[-1] <= TOUCH_REL * 2 * r  # touching, as the treatment counts it
    assert np.all(pos[-1, :, 2] < -0.04)  # near the bottom


def test_cylinders_in_files_and_exported_drawings(tmp_path):
    from hsgran.api import run_scene
    from hsgran.io.h5md import read_trajectory

    text = BALL.format(duration=0.1, more="", omega=2.0, x=0.0, z=0.0, u=0.0, w=0.0)
    path = tmp_path / "drum.toml"
    path.write_text(text)
    scene = parse_scene(text)
    run_scene(path, tmp_path / "drum.h5")
    walls = read_trajectory(tmp_path / "drum.h5").walls
    assert walls.key == [w.key for w in scene.walls]
    k = len(scene.planes)
    assert walls.is_cylinder(k)
    assert not walls.is_cylinder(0)
    np.testing.assert_array_equal(walls.cylinder[k], scene.cylinders[0].row())
    np.testing.assert_array_equal(walls.point[k], scene.cylinders[0].center)
    pytest.importorskip("pyvista")
    import pyvista as pv

    from hsgran.export import export

    result = export(tmp_path / "drum.h5", "vtk", tmp_path / "vtk")
    reader = pv.get_reader(str(result.output))
    drawn = reader.read()[1]
    on_tube = np.abs(np.hypot(drawn.points[:, 0], drawn.points[:, 2]) - 0.05) < 1e-9
    assert np.count_nonzero(on_tube) > 100
    # the tube's normals point to the axis (the spheres are inside)
    centres = np.asarray(drawn.cell_centers().points)
    tube = np.abs(np.hypot(centres[:, 0], centres[:, 2]) - 0.05) < 1e-3
    n = np.asarray(drawn.cell_data["normal"])[tube]
    radial = centres[tube] * [1.0, 0.0, 1.0]
    assert np.all(np.einsum("ij,ij->i", n, radial) < 0.0)


# ---- on a cylinder: rolling, resting, carried round (docs/walls.md, "On a cylinder") ---------

ON = """
[scene]
name = "on a cylinder"
duration = {duration}
effects = ["gravity", "rotation", "friction"{more}]
[output]
frame_interval = {dt}
[[walls]]
kind = "cylinder"
center = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
radius = 0.05
length = 0.01
side = "{side}"
angular_velocity = {omega}
material = "steel"
[[particles]]
material = "steel"
radius = 0.002
position = [{x!r}, 0.0, {z!r}]
velocity = [{u!r}, 0.0, {w!r}]
angular_velocity = [0.0, {spin!r}, 0.0]
[[contacts]]
between = ["steel", "steel"]
sliding_friction = {mu}
{extra}
"""
G = 9.81  #: [m/s²] (the default gravity)
K = 0.4  #: I/(m r²) of a solid sphere
RHO = 0.05 - 0.002  #: the centre's distance from the axis inside the drum [m]


def on(duration=2.0, dt=0.001, more="", side="inside", omega=0.0, phi=0.0, rho=RHO, u=0.0,
       w=0.0, spin=0.0, mu=0.3, extra=""):
    """An ON scene with the sphere at angle phi [rad] from the bottom (inside; from the top
    outside), touching."""
    x = float(rho * np.sin(phi))
    z = float(-rho * np.cos(phi) if side == "inside" else rho * np.cos(phi))
    return ON.format(duration=duration, dt=dt, more=more, side=side, omega=omega, x=x, z=z, u=u,
                     w=w, spin=spin, mu=mu, extra=extra)


def angle(frames, side="inside"):
    """The sphere's angle from the bottom (inside) or the top (outside) in every frame [rad]."""
    x = frames["position"][:, 0]
    return np.arctan2(x[:, 0], -x[:, 2] if side == "inside" else x[:, 2])


def crossings(t, y):
    """Times [s] at which y passes zero (linear interpolation between frames)."""
    k = np.flatnonzero(np.sign(y[1:]) != np.sign(y[:-1]))
    return t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])


@pytest.mark.parametrize("amplitude", [0.02, 0.3])
def test_a_sphere_rolling_in_a_cylinder_is_a_pendulum(amplitude):
    """Released at rest at an angle φ₀, it rolls (friction holds it: tan φ₀ < 7/2 μ) with the
    period of a pendulum of length ρ = R − r and g/(1 + k): T = 4 K(sin²(φ₀/2)) / ω₀,
    ω₀ = √(5 g / 7 ρ) (Landau & Lifshitz, Mechanics §11), keeping its energy and the surface."""
    scene, frames, _ = run(on(duration=3.0, dt=0.0005, phi=amplitude))
    assert set(np.unique(frames["motion_state"])) == {MS_ROLLING}  # throughout
    phi = angle(frames)
    period = 2.0 * np.mean(np.diff(crossings(frames["time"], phi)))
    omega0 = np.sqrt(G / ((1.0 + K) * RHO))
    exact = 4.0 * ellipk(np.sin(amplitude / 2.0) ** 2) / omega0
    assert period == pytest.approx(exact, rel=1e-6)
    if amplitude < 0.05:  # the small-amplitude closed form, to its own O(φ₀²/16)
        assert period == pytest.approx(2.0 * np.pi / omega0, rel=amplitude**2 / 8)
    m = scene.mass()[0]
    v = frames["velocity"][:, 0]
    spin = frames["angular_velocity"][:, 0]
    e = (0.5 * m * (v * v).sum(1) + 0.5 * K * m * 0.002**2 * (spin * spin).sum(1)
         + m * G * frames["position"][:, 0, 2])
    # within a segment the parabola's speed errs by O(CURVE_STEP²); across them nothing drifts
    scale = m * G * RHO * (1.0 - np.cos(amplitude))
    assert np.ptp(e) < 1e-5 * scale
    assert abs(e[-1000:].mean() - e[:1000].mean()) < 1e-6 * scale
    d = np.hypot(frames["position"][:, 0, 0], frames["position"][:, 0, 2])
    assert d.max() <= RHO * (1.0 + 1e-15)  # never into the wall
    assert d.min() > RHO * (1.0 - 1e-9)  # and on it but for the segments' chords


MU_R = 0.05  #: rolling friction of the turning-drum tests [-]
OMEGA = 2.0  #: the drum's angular velocity [rad/s]


def drum_oracle(t, phi0, dphi0):
    """φ(t) of a sphere rolling in the drum turning at OMEGA (faster than the sphere moves on
    it, so the rolling resistance always points along the surface's motion): (1 + k) ρ φ'' =
    −g sin φ − μ_r (g cos φ + ρ φ'²) (MODEL §5.3 in the tangent plane, the load with the
    centripetal term), by scipy's DOP853 to 1e-12."""
    def rhs(_, y):
        phi, dphi = y
        return [dphi, -(G * np.sin(phi) + MU_R * (G * np.cos(phi) + RHO * dphi**2))
                / ((1.0 + K) * RHO)]

    sol = solve_ivp(rhs, (0.0, t[-1]), [phi0, dphi0], method="DOP853", t_eval=t, rtol=1e-12,
                    atol=1e-14)
    return sol.y[0]


def test_a_sphere_in_a_turning_drum_rolls_about_the_steady_angle():
    """Rolling in place at the bottom of a drum turning at Ω (spin Ω R / r: no slip), the
    sphere is carried up and rocks about the angle where the rolling resistance balances
    gravity, tan φ_s = μ_r (against the surface's motion: φ_s = −atan μ_r here), following
    the equation of motion's solution; placed at φ_s, it stays there."""
    rolling = f"rolling_friction = {MU_R}"
    spin = OMEGA * 0.05 / 0.002
    _, frames, _ = run(on(duration=2.0, more=', "rolling_resistance"', omega=OMEGA,
                          spin=spin, extra=rolling))
    phi = angle(frames)
    np.testing.assert_allclose(phi, drum_oracle(frames["time"], 0.0, 0.0), atol=2e-6)
    steady = -np.arctan(MU_R)
    assert phi.min() < steady < phi.max()
    assert set(np.unique(frames["motion_state"])) == {MS_ROLLING}
    _, frames, log = run(on(duration=2.0, more=', "rolling_resistance"', omega=OMEGA,
                            phi=steady, spin=spin, extra=rolling))
    assert np.abs(angle(frames) - steady).max() < 1e-12
    assert log["time"].size == 0  # no event at all: the steady state is one segment


def test_a_sphere_rolls_off_a_post_where_its_load_vanishes():
    """Released near the top of a horizontal post with friction enough to roll (μ = 100), it
    rolls down and flies off where the surface no longer presses it: cos θ = 10/17 cos θ₀
    (energy with I = 2/5 m r², and the centripetal load m v²/ρ = m g cos θ)."""
    rho = 0.05 + 0.002
    theta0 = 0.01
    _, frames, _ = run(on(duration=0.6, dt=0.0002, side="outside", rho=rho, phi=theta0,
                          mu=100.0))
    theta = angle(frames, "outside")
    states = frames["motion_state"][:, 0]
    first = np.flatnonzero(states == MS_FLIGHT)[0]
    assert np.all(states[:first] == MS_ROLLING)
    leave = np.arccos(10.0 / 17.0 * np.cos(theta0))
    assert theta[first - 1] <= leave <= theta[first] + 1e-9


def test_a_ball_dropped_into_a_drum_lands_rolls_and_comes_to_rest():
    """With restitution 0.5 the bounces die out, the ball lands on the drum and rolls; rolling
    resistance stops it within |φ| ≤ atan μ_r, and then nothing happens any more."""
    text = on(duration=6.0, dt=0.01, more=', "rolling_resistance"', phi=0.2, rho=0.03,
              u=0.2, extra=f"restitution = 0.5\nrolling_friction = {MU_R}")
    scene, frames, log = run(text)
    assert np.count_nonzero(log["kind"] == EV_LAND) >= 1
    states = frames["motion_state"][:, 0]
    assert states[-1] == MS_REST
    rest = np.flatnonzero(states == MS_REST)[0]
    assert np.all(states[rest:] == MS_REST)
    assert abs(angle(frames)[-1]) <= np.arctan(MU_R) + 1e-12
    assert log["time"][-1] <= frames["time"][rest]
    gaps = scene.cylinders[0].distance(frames["position"]) - scene.radius
    assert gaps.min() > -OVERLAP_TOL


# ---- a silo's corner: a flat floor and an upright side (docs/walls.md, "Cylinders") ---------

SILO = """
[scene]
name = "silo corner"
duration = {duration}
effects = ["gravity", "rotation", "friction"]
[output]
frame_interval = 0.001
[[walls]]
kind = "cylinder"
center = [0.0, 0.0, 0.05]
axis = [0.0, 0.0, 1.0]
radius = 0.02
length = 0.1
caps = false
material = "steel"
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "steel"
[[particles]]
material = "steel"
radius = 0.002
position = [{x!r}, 0.0, {z!r}]
velocity = [0.0, {u!r}, 0.0]
[[contacts]]
between = ["steel", "steel"]
restitution = 0.5
sliding_friction = 0.3
"""
SILO_RHO = 0.02 - 0.002  #: the centre's distance from the axis against the side [m]


#: Share of its rolling speed a sphere rolling on a silo's floor along its side keeps over 0.3 s
#: at 0.1 m/s [-]: each hop turns its velocity by a chord's angle but not its spin, and the
#: floor's friction takes the slip this leaves (measured 0.995 at 0.1 m/s, 0.99995 at
#: 0.01 m/s: the loss grows as the square of the speed).
CHORD_KEEP = 0.99


@pytest.mark.parametrize("u", [0.01, 0.1, 1.0])
def test_a_sphere_sliding_on_a_silo_floor_follows_its_side(u):
    """Sent along the side of an upright cylinder on its floor, a sphere stays on the floor
    and against the side (within the chords of its hops, nanometres): the side carries none
    of its weight, so it does not move onto it, and it hops off it ([OURS],
    docs/enduring-contact.md, "Hops"). It used to move onto the side, fall back onto the
    floor at once, and back again, until the collapse guard stopped it. Slow (c²/ρ ≪ g), it
    rolls round at 5/7 of its speed once friction with the floor has made it roll, less
    what turning in chords costs (CHORD_KEEP); fast (1 m/s, c²/ρ = 2.8 g), the side's
    friction slows it, and it never speeds up."""
    _, frames, log = run(SILO.format(duration=0.3, x=SILO_RHO, z=0.002, u=u))
    pos, vel = frames["position"][:, 0], frames["velocity"][:, 0]
    assert np.all(frames["motion_state"][:, 0] != MS_FLIGHT)
    assert np.abs(pos[:, 2] - 0.002).max() <= OVERLAP_TOL
    rho = np.hypot(pos[:, 0], pos[:, 1])
    assert rho.max() <= SILO_RHO + OVERLAP_TOL
    assert rho.min() >= SILO_RHO * (1.0 - 1e-6)
    rolled = frames["time"] > 2.0 / 7.0 * u / (0.3 * G) + 0.01
    speed = np.linalg.norm(vel[rolled], axis=1) / (5.0 / 7.0 * u)
    assert speed.max() <= 1.0 + 1e-9
    assert np.all(np.diff(speed) <= 1e-9)
    if u <= 0.1:
        assert speed.min() >= CHORD_KEEP
    turned = np.unwrap(np.arctan2(pos[:, 1], pos[:, 0]))
    assert turned[-1] >= 0.3 * CHORD_KEEP * speed.min() * 5.0 / 7.0 * u / SILO_RHO * 0.9
    assert np.count_nonzero(log["kind"] == EV_LAND) == 0


#: A sphere held against a cylinder's side in steps stays on it to this share of ρ [-]: each
#: step moves it along a chord, which dips inside by (h u)²/2ρ (1.5e-7 ρ at 0.1 m/s).
SIDE_KEEP_REL = 1e-6


@pytest.mark.parametrize("treatment", ["pairwise", "clusters"])
@pytest.mark.parametrize("u", [1e-5, 0.001, 0.1])
def test_a_sphere_falling_along_a_silo_side_it_grazes_stays_on_it(u, treatment):
    """Put against the side of an upright cylinder far above its floor, moving along the side
    at u and not across it, a sphere falls along the side. Its straight path would leave the
    cylinder at once (the curvature presses it into the side at no normal speed), so a binary
    collision gives it no impulse and meets it again at the same instant: such a sequence goes
    to the cluster solve (docs/enduring-contact.md, "A binary collision that ends nothing"),
    which holds the sphere inside. It used to stop at the collapse guard at t = 0, in both
    treatments (a silo of 28,800 beads at 0.17 s); at 1e-5 m/s, where a step sinks it into
    the side by ~1e-20 m, below the rounding, the solve gave no impulse and let it fly, and the
    prediction met it at once (it now stays in constrained motion, _cluster._presses). The
    side carries none of its weight: the sphere falls freely but for the side's friction, at
    most μ u²/ρ, and the lead of the steps (θ = 1: each moves with its end velocity, ahead of
    the parabola by g h / 2 per unit time, h ≤ STEP_MAX)."""
    duration, z0, mu = 0.02, 0.05, 0.3
    text = (SILO.format(duration=duration, x=SILO_RHO, z=z0, u=u)
            + f'[enduring_contact]\ntreatment = "{treatment}"\n')
    _, frames, _ = run(text)
    t, pos = frames["time"], frames["position"][:, 0]
    assert t[-1] == pytest.approx(duration, rel=1e-12)
    rho = np.hypot(pos[:, 0], pos[:, 1])
    assert rho.max() <= SILO_RHO + OVERLAP_TOL
    assert rho.min() >= SILO_RHO * (1.0 - SIDE_KEEP_REL)
    fall = z0 - pos[:, 2]
    assert np.all(fall <= 0.5 * G * t ** 2 + 0.5 * G * STEP_MAX * t + OVERLAP_TOL)
    assert np.all(fall >= 0.5 * (G - mu * u ** 2 / SILO_RHO) * t ** 2 - OVERLAP_TOL)


def test_a_sphere_dropped_into_a_silo_corner_rests_on_the_floor():
    """Dropped from 1 mm beside the side, it bounces, lands on the floor (not the side, which
    carries none of its weight) and stays at rest in the corner."""
    _, frames, log = run(SILO.format(duration=0.3, x=SILO_RHO, z=0.003, u=0.0))
    states = frames["motion_state"][:, 0]
    assert states[-1] == MS_REST
    rest = np.flatnonzero(states == MS_REST)[0]
    assert np.all(states[rest:] == MS_REST)
    assert np.ptp(frames["position"][rest:, 0], axis=0).max() == 0.0
    assert abs(frames["position"][-1, 0, 2] - 0.002) <= OVERLAP_TOL
    landed = log["j"][log["kind"] == EV_LAND]
    assert landed.size >= 1
    assert np.all(landed == -1)  # the floor: planes come first, wall 0
