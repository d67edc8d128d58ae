"""Inelastic collapse: the TC model ends it in clusters, and a sphere on a plate hit from above is
backed by the plate (issue: sliding, rolling and resting; docs/enduring-contact.md)."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from hsgran.engine import Simulation
from hsgran.onplane import MS_ASLEEP, MS_REST
from hsgran.scene import parse_scene
from tests.scenes import FLOOR, plane, sphere

ROW = """
[scene]
name = "three in a row"
duration = 0.01
effects = []
[output]
frame_interval = 0.01
[enduring_contact]
tc_time = {tc}
[[contacts]]
between = ["steel", "steel"]
restitution = {e}
""" + (sphere(("0.0", "0.0", "0.0"), ("1.0", "0.0", "0.0"))
       + sphere(("0.00201", "0.0", "0.0")) + sphere(("0.00402", "0.0", "0.0")))

#: Three spheres in a row, the first hitting the other two, collapse (infinitely many
#: collisions in finite time, all velocities equal in the limit) for e < 7 − 4√3 = 0.072
#: (McNamara & Young 1994). In floating point the sequence ends when the velocities agree to
#: rounding: measured 42 collisions at e = 0.05 without the TC model, 4 with it.
E_COLLAPSE = 0.05
#: Momentum is exchanged by impulses; rounding of a few dozen collisions.
MOMENTUM_RTOL = 1e-12


def row(tc):
    return parse_scene(ROW.format(tc=tc, e=E_COLLAPSE))


def momentum_energy(sim):
    m = 1.0 / sim.inv_m
    return (m[:, None] * sim.vel).sum(axis=0), 0.5 * (m * (sim.vel ** 2).sum(axis=1)).sum()


def test_three_in_a_row_collapse_to_one_velocity_without_the_tc_model():
    sim = Simulation(row(0.0))
    summary = sim.run()
    assert summary.events["tc"] == 0
    assert summary.collisions >= 30
    np.testing.assert_allclose(sim.vel[:, 0], 1.0 / 3.0, rtol=1e-12)


def test_tc_model_ends_the_collapse_in_a_few_collisions_conserving_momentum():
    sim = Simulation(row(1e-5))
    p0, k0 = momentum_energy(sim)
    summary = sim.run()
    p1, k1 = momentum_energy(sim)
    assert summary.events["tc"] >= 1
    assert summary.collisions <= 6
    np.testing.assert_allclose(p1, p0, rtol=MOMENTUM_RTOL, atol=MOMENTUM_RTOL * abs(p0[0]))
    # the TC collisions are elastic: less is dissipated than by the collapse (k = k0/3)
    assert k0 / 3.0 < k1 < k0
    # the spheres separate in order along x
    v = sim.vel[:, 0]
    assert v[0] <= v[1] <= v[2]


STACK = """
[scene]
name = "hit from above"
duration = {duration}
gravity = [0.0, 0.0, -9.81]
effects = ["gravity"]
[output]
frame_interval = {duration}
[[contacts]]
between = ["steel", "steel"]
restitution = {e}
""" + FLOOR + sphere(("0.0", "0.0", "0.001")) + sphere(("{x}", "0.0", "{z}"),
                                                      ("0.0", "0.0", "{vz}"))

#: The rebound off a backed sphere is one impulse in closed form; rounding only.
REBOUND_RTOL = 1e-9


@pytest.mark.parametrize("e", [0.3, 0.8])
def test_sphere_on_plate_hit_from_above_is_backed_by_the_plate(e):
    gap, v0, g = 1e-4, -0.5, 9.81
    t_hit = (v0 + math.sqrt(v0 * v0 + 2.0 * g * gap)) / g  # gap + v0 t − g t²/2 = 0
    v_hit = v0 - g * t_hit
    sim = Simulation(parse_scene(STACK.format(duration=t_hit + 1e-6, e=e, x=0.0,
                                              z=0.003 + gap, vz=v0)))
    assert sim.mstate[0] == MS_REST  # starts on the plate
    sim.run()
    assert sim.collisions == 1  # the lower sphere never hits the plate
    pos, vel = sim.state_at(t_hit + 1e-6)
    # the lower sphere stays at rest on the plate; the upper one rebounds as off a wall
    assert sim.mstate[0] == MS_REST
    np.testing.assert_array_equal(vel[0], 0.0)
    assert pos[0, 2] == pytest.approx(0.001, rel=1e-15)
    assert vel[1, 2] == pytest.approx(-e * v_hit - g * 1e-6, rel=REBOUND_RTOL)


def test_oblique_hit_moves_a_backed_sphere_along_the_plate_only():
    # the upper sphere hits at 45°: the lower one is pushed along the plate and stays on it
    sim = Simulation(parse_scene(STACK.format(duration=0.02, e=0.5, x=-0.002 / math.sqrt(2),
                                              z=0.001 + 0.002 / math.sqrt(2) + 1e-6, vz=-0.3)))
    sim.run()
    pos, vel = sim.state_at(0.02)
    assert pos[0, 2] == pytest.approx(0.001, rel=1e-12)
    assert vel[0, 2] == 0.0
    assert vel[0, 0] > 0.0
    d = np.linalg.norm(pos[1] - pos[0])
    assert d >= 0.002 * (1 - 1e-12)


WEDGE = """
[scene]
name = "wedge"
duration = 0.5
gravity = [0.0, 0.0, -9.81]
effects = {effects}
[output]
frame_interval = 0.05
[[contacts]]
between = ["steel", "steel"]
restitution = 0.5
sliding_friction = 0.3
""" + (FLOOR + plane(("0.0", "0.0", "0.0"), ("1.0", "0.0", "0.0"))
       + plane(("0.00375", "0.0", "0.0"), ("-1.0", "0.0", "0.0"))
       + sphere(("0.00275", "0.0", "0.001")) + sphere(("0.0012", "0.0", "0.004")))

#: Collisions the wedge takes to come to rest (measured 2505 without rotation): a bound far
#: below the ~6e5 per simulated second of the endless TC-elastic buzz it made before jammed
#: spheres could fall asleep.
WEDGE_MAX_COLLISIONS = 20_000
#: The wedged sphere falls asleep where its last bounce left it, between the wall and the
#: sphere: a gap to the wall of at most 1e-3 R [m].
WEDGE_WALL_GAP = 1e-6


@pytest.mark.parametrize("effects", ['["gravity"]', '["gravity", "rotation", "friction"]'])
def test_sphere_wedged_between_a_wall_and_a_sphere_comes_to_rest(effects):
    # A sphere dropped into a gap narrower than itself, between a side wall and a sphere in
    # the opposite corner: it leans on that sphere at 61° from the vertical (too steep to fall
    # asleep on it as on a pile) and on the wall. Jammed, it falls asleep on the sphere.
    sim = Simulation(parse_scene(WEDGE.format(effects=effects)))
    frames = []
    summary = sim.run(observers=[SimpleNamespace(on_frames=frames.append)])
    assert summary.collisions <= WEDGE_MAX_COLLISIONS
    assert summary.events["wedge"] == 0  # a jammed sphere that can fall asleep does so first
    assert list(sim.mstate) == [MS_REST, MS_REST]
    assert sim.mplane[1] == -2  # asleep on sphere 0
    assert frames[-1].motion_state[-1].tolist() == [MS_REST, MS_ASLEEP]  # as the file says
    np.testing.assert_array_equal(sim.vel, 0.0)
    d = np.linalg.norm(sim.pos[1] - sim.pos[0])
    assert d == pytest.approx(0.002, rel=1e-9)
    # at the wall, up to where the buzz left it when it fell asleep (measured 1e-8 and 3e-7 m)
    assert 0.001 <= sim.pos[1, 0] <= 0.001 + WEDGE_WALL_GAP
    assert d >= 0.002 * (1.0 - 1e-9)  # no overlap beyond 1e-9 R


PAIR_ON_PLATE = """
[scene]
name = "slider meets a resting sphere"
duration = 0.01
gravity = [0.0, 0.0, -9.81]
effects = ["gravity"]
[output]
frame_interval = 0.01
[[contacts]]
between = ["steel", "steel"]
restitution = 0.9
""" + (FLOOR + sphere(("0.0", "0.0", "0.001"), ("{v}", "0.0", "0.0"))
       + sphere(("0.002000001", "0.0", "0.001")))


def test_spheres_on_a_plate_meeting_slower_than_the_landing_speed_stop_together():
    # 5e-4 m/s < landing speed 1e-3 m/s: both stop where they meet, no collision
    sim = Simulation(parse_scene(PAIR_ON_PLATE.format(v=5e-4)))
    summary = sim.run()
    assert summary.collisions == 0
    assert summary.events["land"] == 1
    assert list(sim.mstate) == [MS_REST, MS_REST]
    np.testing.assert_array_equal(sim.vel, 0.0)
    assert sim.pos[1, 0] - sim.pos[0, 0] == pytest.approx(0.002, rel=1e-12)


def test_spheres_on_a_plate_meeting_faster_collide():
    # 0.05 m/s: a collision, the resting sphere moves off along the plate (no friction here)
    sim = Simulation(parse_scene(PAIR_ON_PLATE.format(v=0.05)))
    summary = sim.run()
    assert summary.collisions == 1
    assert sim.vel[1, 0] > 0.04
    assert sim.vel[1, 2] == 0.0
