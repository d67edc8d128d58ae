"""A backed pair collision (a sphere on a plane hit towards it; docs/enduring-contact.md,
"Backing") never gains kinetic energy through its friction (hsgran._settling
._dissipative_friction), against the same arithmetic as collide_pair: the collision model with
the backed sphere's reduced inverse mass, the support taking the impulse's part along its
normal."""

import numpy as np
import pytest

from hsgran._settling import _backed_velocity, _dissipative_friction, _support_cos
from hsgran.contact.model import REC_SIZE, resolve
from hsgran.scene import parse_scene
from tests.scenes import FLOOR, sphere

R = 0.00168  #: sphere radius [m] (the corpus sphere that gained energy this way)
RHO = 2700.0  #: density [kg/m³]
MASS = 4.0 / 3.0 * np.pi * R ** 3 * RHO
INERTIA = 0.4 * MASS * R * R
#: Relative kinetic energy a frictionless elastic collision keeps to (rounding) [-]
ENERGY_RTOL = 1e-12

SCENE = """
[scene]
name = "backing"
duration = 0.1
gravity = [0.0, 0.0, -9.81]
effects = ["gravity", "rotation", "friction"]
[output]
frame_interval = 0.1
[[contacts]]
between = ["steel", "steel"]
sliding_friction = {mu}
restitution = 1.0
"""


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
