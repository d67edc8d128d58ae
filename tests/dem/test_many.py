"""The fixed-step many-sphere integrator (hsgran.dem.many): binary impacts and conservation."""

import numpy as np
import pytest

from hsgran.dem.many import run_fixed_step, scene_contact_time
from hsgran.errors import InputError
from hsgran.scene import parse_scene

#: Steps per contact of these tests: finer than the DEM custom so that the integration error
#: (second order, ~1e-4 at t_c/50 for e_n) stays far below the checked tolerances.
STEPS = 100

PAIR = """
[scene]
name = "two spheres head-on"
duration = 1e-4
effects = {effects}
[output]
frame_interval = 1e-4
[[contacts]]
between = ["steel", "steel"]
{contact}
[[particles]]
material = "steel"
radius = 0.001
position = [0.0, 0.0, 0.0]
velocity = [0.5, 0.0, 0.0]
[[particles]]
material = "steel"
radius = 0.001
position = [0.00201, 0.0, 0.0]
velocity = [-0.5, 0.0, 0.0]
"""


def pair_run(contact: str, effects: str = "[]"):
    scene = parse_scene(PAIR.format(contact=contact, effects=effects))
    t_c = scene_contact_time(scene, 1.0)
    # 10 µm gap closed at 1 m/s: 10 µs, then the contact (~8 µs): 40 µs is past the rebound
    return scene, run_fixed_step(scene, dt=t_c / STEPS, until=4e-5, frame_interval=1e-5,
                                 contact_time=t_c)


def test_binary_impact_gives_the_prescribed_restitution():
    _, r = pair_run("restitution = 0.5")
    assert r.velocity[0, 0] == pytest.approx(-0.25, abs=1e-3)
    assert r.velocity[1, 0] == pytest.approx(0.25, abs=1e-3)


def test_elastic_impact_conserves_momentum_and_energy():
    scene, r = pair_run("sliding_friction = 0.3")
    mass = scene.mass()
    p = (mass[:, None] * r.velocity).sum(axis=0)
    assert np.allclose(p, 0.0, atol=1e-12 * mass.sum())
    assert r.kinetic_translational[-1] == pytest.approx(r.kinetic_translational[0], rel=1e-4)
    assert 0.0 < r.max_overlap < 0.05


def test_scenes_needing_a_contact_history_are_refused():
    with pytest.raises(InputError):
        pair_run("sliding_friction = 0.3", '["plasticity"]')
    with pytest.raises(InputError):
        pair_run("sliding_friction = 0.3", '["plasticity", "adhesion"]')
