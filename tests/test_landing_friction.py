"""A landing (a sphere meeting a fixed plane slower than the landing speed, which stops it on
the plane instead of a rebound) is a perfectly plastic impact: the plane takes the normal
impulse m |v_n| and gives its Coulomb friction for it (hsgran._settling._landing_friction,
docs/enduring-contact.md, "Landing"). Closed forms for a sphere without spin landing with a
velocity along the plane."""

import math

import pytest

from hsgran.engine import Simulation
from hsgran.scene import parse_scene
from tests.scenes import FLOOR, friction_header, num, sphere

R = 0.001  #: sphere radius [m]
G = 9.81  #: gravity [m/s²]
V_DOWN = 5e-4  #: approach speed, below the default landing speed of 1 mm/s [m/s]
GAP = 1e-9  #: height of the sphere's lowest point above the plate at t = 0 [m]
T_CHECK = 1e-4  #: when the velocity is read, long after the landing (~2e-6 s) [s]
#: The velocities are one impulse and a constant deceleration in closed form: what is left is
#: rounding of the landing time and of the plate's motion [-].
RTOL = 1e-9


def _landing(mu, vx):
    """(vx at T_CHECK, spin about y at T_CHECK, normal speed at the landing, landing time)."""
    scene = parse_scene(friction_header(num(mu), "0.5") + FLOOR
                        + sphere(("0.0", "0.0", num(R + GAP)), (num(vx), "0.0", num(-V_DOWN))))
    sim = Simulation(scene)
    sim.run(until=T_CHECK)
    _, vel = sim.state_at(T_CHECK)
    w = sim.omg + sim.alpha * (T_CHECK - sim.t_loc)[:, None]
    assert vel[0, 2] == 0.0  # on the plate
    t_land = (-V_DOWN + math.sqrt(V_DOWN ** 2 + 2.0 * G * GAP)) / G
    return vel[0, 0], w[0, 1], V_DOWN + G * t_land, t_land


def test_a_landing_sphere_that_slides_loses_mu_times_its_normal_speed():
    """μ |v_n| is less than the 2/7 of the speed that rolling needs: the sphere lands sliding,
    with μ v_n less speed (and spin μ m v_n R / I), then slides with deceleration μ g."""
    mu, vx = 0.5, 0.01
    v, wy, vn, t_land = _landing(mu, vx)
    assert mu * vn < 2.0 / 7.0 * vx
    sliding = T_CHECK - t_land
    assert v == pytest.approx(vx - mu * vn - mu * G * sliding, rel=RTOL)
    # spin: the landing's torque μ m v_n R / (2/5 m R²), then the plate's μ m g R / I
    assert wy == pytest.approx(2.5 * mu * (vn + G * sliding) / R, rel=RTOL)


def test_a_slow_landing_sphere_is_made_to_roll():
    """μ |v_n| exceeds the 2/7 of the speed that stopping the foot's slip takes: the sphere
    lands rolling with 5/7 of its speed, and rolls on (no rolling friction)."""
    mu, vx = 0.5, 1e-5
    v, wy, vn, _ = _landing(mu, vx)
    assert mu * vn > 2.0 / 7.0 * vx
    assert v == pytest.approx(5.0 / 7.0 * vx, rel=RTOL)
    assert wy * R == pytest.approx(v, rel=RTOL)


def test_without_friction_a_landing_keeps_the_speed_along_the_plate():
    v, wy, _, _ = _landing(0.0, 0.01)
    assert v == 0.01
    assert wy == 0.0
