"""A backed pair collision (a sphere on a plane hit towards it; docs/enduring-contact.md,
"Backing") never gains kinetic energy through its friction (hsgran._settling
._dissipative_friction), against the same arithmetic as collide_pair: the collision model with
the backed sphere's reduced inverse mass, the support taking the impulse's part along its
normal."""

import math

import numpy as np
import pytest

from hsgran._settling import _backed_velocity, _dissipative_friction, _support_cos
from hsgran.contact.model import REC_SIZE, resolve
from hsgran.engine import Simulation
from hsgran.scene import parse_scene
from tests.scenes import FLOOR, friction_header, sphere

R = 0.00168  #: sphere radius [m] (the corpus sphere that gained energy this way)
RHO = 2700.0  #: density [kg/m³]
MASS = 4.0 / 3.0 * np.pi * R ** 3 * RHO
INERTIA = 0.4 * MASS * R * R
#: Relative kinetic energy a frictionless elastic collision keeps to (rounding) [-]
ENERGY_RTOL = 1e-12

SCENE = friction_header("{mu}", "1.0")


def _row(mu):
    sc = parse_scene(SCENE.format(mu=mu) + FLOOR + sphere(("0.0", "0.0", "0.001")))
    return np.ascontiguousarray(sc.pair_table())[0, 0].copy()


def _backed_collision(rng, row, friction):
    """A sphere moving on a plane of random normal b, hit by an immovable partner along a
    random normal n that presses it into b: (kinetic energy before, after) [J], or None."""
    b = rng.normal(size=3)
    b /= np.linalg.norm(b)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    c = _support_cos(n[0], n[1], n[2], b[0], b[1], b[2])
    if not 0.0 < c < 0.999:
        return None
    st = np.zeros((2, 7))
    v0 = rng.normal(size=3) * 1e-3
    v0 -= (v0 @ b) * b
    w = rng.normal(size=(2, 3)) * np.array([[1.0], [0.0]])
    st[0, 3:6] = v0
    w0 = w[0].copy()
    inv_m = np.array([1.0 / MASS, 1.0 / MASS])
    inv_mi = inv_m[0] * (1.0 - c * c)
    v = st[0, 3:6]
    if not resolve(v, w[0], st[1, 3:6], w[1], n[0], n[1], n[2], inv_mi, 0.0, 1.0 / INERTIA,
                   0.0, R, R, 2.0 / R, row, np.zeros(REC_SIZE), False, friction, False, False,
                   True, False):
        return None
    j = (st[0, 3:6] - v0) / inv_mi
    _backed_velocity(0, v0[0], v0[1], v0[2], j[0], j[1], j[2], b[0], b[1], b[2], st, inv_m)
    if friction:
        _dissipative_friction(0, 1, n[0], n[1], n[2], j[0], j[1], j[2], tuple(b), tuple(b), c,
                              0.0, inv_mi, 0.0, 1.0 / INERTIA, 0.0, R, R, st, w[0], w[1],
                              inv_m, True)
    before = 0.5 * MASS * v0 @ v0 + 0.5 * INERTIA * w0 @ w0
    after = 0.5 * MASS * st[0, 3:6] @ st[0, 3:6] + 0.5 * INERTIA * w[0] @ w[0]
    return before, after


@pytest.mark.parametrize("mu", [0.1, 0.5, 1.0])
def test_an_elastic_backed_collision_with_friction_gains_no_kinetic_energy(mu):
    rng = np.random.default_rng(7)
    row = _row(mu)
    n = 0
    for _ in range(4000):
        out = _backed_collision(rng, row, True)
        if out is None:
            continue
        before, after = out
        n += 1
        assert after <= before * (1.0 + ENERGY_RTOL)
    assert n > 500


def test_without_friction_the_backed_collision_keeps_its_energy():
    rng = np.random.default_rng(8)
    row = _row(0.5)
    for _ in range(2000):
        out = _backed_collision(rng, row, False)
        if out is not None:
            assert out[1] == pytest.approx(out[0], rel=ENERGY_RTOL)


HEAD_ON = friction_header("{mu}", "0.5") + FLOOR + sphere(
    ("0.0", "0.0", "0.001")) + sphere(("{x}", "0.0", "{z}"), ("{vx}", "0.0", "{vz}"))
#: The hit is one impulse and the plate's friction one more, in closed form: rounding, and
#: gravity's share (it tilts the approach off 45° by ~1e-6, which the spheres' friction at
#: their contact then acts on, and it acts over the nanosecond after the collision at which
#: the velocities are read) [-].
SUPPORT_RTOL = 1e-6


@pytest.mark.parametrize("mu", [0.1, 0.5])
def test_the_plate_under_a_backed_sphere_gives_friction_for_the_impulse_it_takes(mu):
    """A sphere at rest on a plate, hit head-on at 45° from above (no spin, so no friction at
    the spheres' contact): the plate takes the impulse's vertical part P = J cos 45°, and its
    friction for P acts on the lower sphere's foot (docs/enduring-contact.md, "Backing").
    Stopping the foot's slip takes 2/7 of the horizontal impulse J sin 45° (a solid sphere:
    1/m + R²/I = 7/(2m)); that is within the cone for μ ≥ 2/7, and the sphere rolls off with
    5/7 of the velocity the hit gave it, else the plate gives μ P and it slides off with
    J (sin 45° − μ cos 45°)/m. Before, the plate gave no friction here: a bed on a slope held
    by its bottom spheres' own weight alone slid down as a block."""
    s = 0.002 / math.sqrt(2.0)  # the line of centres at 45°
    # a gap of 1e-8 m: gravity bends the approach by 2e-7 m/s in the 2.4e-8 s before the hit
    gap, v = 1e-8, 0.3
    scene = parse_scene(HEAD_ON.format(mu=mu, x=repr(-s - gap), z=repr(0.001 + s + gap),
                                       vx=repr(v), vz=repr(-v)))
    sim = Simulation(scene, log_events=True)
    hits = []

    class Hits:
        def on_events(self, block):
            hits.extend(block.time[block.kind == 1].tolist())

    sim.run(until=1e-4, observers=[Hits()])
    assert len(hits) == 1  # one pair collision, before 1e-4 s
    t = hits[0] + 1e-9
    sim2 = Simulation(scene)
    sim2.run(until=t)
    _, vel = sim2.state_at(t)
    w = sim2.omg + sim2.alpha * (t - sim2.t_loc)[:, None]
    m = 1.0 / sim2.inv_m
    # J along the line of centres, from the upper sphere's change (gravity over t removed)
    v_up_before = np.array([v, 0.0, -v - 9.81 * t])
    dv_up = vel[1] - v_up_before
    j = m[1] * np.linalg.norm(dv_up)
    horizontal = j / np.sqrt(2.0)
    stick = 2.0 / 7.0 * horizontal
    friction = min(stick, mu * j / np.sqrt(2.0))
    assert vel[0, 0] == pytest.approx((horizontal - friction) / m[0], rel=SUPPORT_RTOL)
    assert vel[0, 2] == 0.0  # it stays on the plate
    r = 0.001
    foot_slip = vel[0, 0] - r * w[0, 1]  # x-velocity of the point at −R ẑ
    if mu >= 2.0 / 7.0:
        assert abs(foot_slip) <= SUPPORT_RTOL * vel[0, 0]  # rolling
    else:
        assert foot_slip > 0.1 * vel[0, 0]  # sliding
