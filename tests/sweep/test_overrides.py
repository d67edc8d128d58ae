"""hsgran.overrides: key paths into a parsed scene, and the errors that name them."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from hsgran.errors import InputError
from hsgran.overrides import apply_overrides, format_key_path, parse_key_path
from hsgran.scene import parse_scene
from tests.sweep.scenes import BALL


def test_key_paths_split_into_keys_and_indices_and_back():
    parts = parse_key_path("particles[0].velocity[2]")
    assert parts == ["particles", 0, "velocity", 2]
    assert format_key_path(parts) == "particles[0].velocity[2]"
    assert parse_key_path("materials.steel.yield_stress") == ["materials", "steel",
                                                              "yield_stress"]


@pytest.mark.parametrize("path", ["", "a..b", "a[x]", "a[0", "a b", ".a", "a[-1]"])
def test_malformed_key_paths_are_refused(path):
    with pytest.raises(InputError):
        parse_key_path(path)


def test_overrides_change_a_copy_in_order():
    doc = tomllib.loads(BALL)
    out = apply_overrides(doc, {"particles[0].velocity": [1.0, 0.0, -2.0],
                                "particles[0].velocity[2]": -3.0,
                                "contacts[0].sliding_friction": 0.1,
                                "enduring_contact.tc_time": 0.0})
    assert out["particles"][0]["velocity"] == [1.0, 0.0, -3.0]
    assert out["contacts"][0]["sliding_friction"] == 0.1
    assert out["enduring_contact"] == {"tc_time": 0.0}   # a missing table is created
    assert doc == tomllib.loads(BALL)                      # the input is left alone


@pytest.mark.parametrize(("path", "message"), [
    ("particles[3].radius", "index 3 out of range: particles has 1 entries"),
    ("scene.duration.x", "scene.duration is not a table"),
    ("scene[0]", "scene is not an array"),
    ("walls[0].normal[5]", "index 5 out of range: walls[0].normal has 3 entries"),
])
def test_bad_paths_name_the_override(path, message):
    with pytest.raises(InputError) as err:
        apply_overrides(tomllib.loads(BALL), {path: 1.0})
    assert err.value.key == path
    assert message in str(err.value)
    assert "\n" not in str(err.value)


def test_parse_scene_applies_overrides_before_validation():
    scene = parse_scene(BALL, overrides={"particles[0].velocity": [0.0, 0.0, -2.0],
                                         "scene.seed": 7})
    assert np.array_equal(scene.velocity[0], [0.0, 0.0, -2.0])
    assert scene.seed == 7
    assert "# override: scene.seed = 7" in scene.text


def test_invalid_override_value_names_the_override():
    with pytest.raises(InputError) as err:
        parse_scene(BALL, overrides={"particles[0].radius": -1.0})
    assert str(err.value).startswith("particles[0].radius: must be > 0")
    assert "value set by the override particles[0].radius" in str(err.value)


def test_unknown_overridden_key_gets_a_hint():
    with pytest.raises(InputError) as err:
        parse_scene(BALL, overrides={"contacts[0].slidng_friction": 0.2})
    assert "did you mean 'sliding_friction'" in str(err.value)
