"""The public one-collision API rejects bad input with InputError and emits strict JSON."""

import json

import pytest

from hsgran.effects import Effects
from hsgran.errors import InputError
from hsgran.impact import oblique_velocity, sphere_sphere_impact, sphere_wall_impact
from hsgran.materials import BUILTIN_MATERIALS, Contact

STEEL = BUILTIN_MATERIALS["steel"]
RIGID = BUILTIN_MATERIALS["rigid"]


def test_rigid_material_cannot_be_a_sphere():
    with pytest.raises(InputError, match="rigid"):
        sphere_wall_impact(RIGID, STEEL, 0.01, [0, 0, -1], effects=Effects())
    with pytest.raises(InputError, match="material2"):
        sphere_sphere_impact(STEEL, RIGID, 0.01, 0.01, [0, 0, -1], [0, 0, 0], effects=Effects())


def test_friction_without_a_coefficient_names_the_fix():
    with pytest.raises(InputError, match="sliding_friction"):
        sphere_wall_impact(STEEL, STEEL, 0.01, [0, 0, -1], effects=Effects.all())


@pytest.mark.parametrize("angle", [True, -1.0, 90.0, "30"])
def test_oblique_velocity_rejects_bad_angles(angle):
    with pytest.raises(InputError, match="angle"):
        oblique_velocity(1.0, angle)


def test_to_dict_is_strict_json_with_prescribed_restitution():
    r = sphere_wall_impact(STEEL, STEEL, 0.01, [0, 0, -1], effects=Effects(),
                           contact=Contact(restitution=0.5))
    text = json.dumps(r.to_dict(), allow_nan=False)
    assert json.loads(text)["stage_impulses"] == [None, None, None]
    assert r.e_n == 0.5
