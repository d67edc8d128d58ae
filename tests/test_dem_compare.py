"""tools/dem_compare.py: the LAMMPS input it writes for a scene, and the scenes it refuses."""

import math

import numpy as np
import pytest

from hsgran.contact.normal import hertz_contact_time
from hsgran.scene import parse_scene

CHUTE = """
[scene]
name = "tilted bed"
duration = 0.1
gravity = [1.0, 0.0, -9.0]
effects = ["gravity", "rotation", "friction"]
seed = 4
periodic = [true, true, false]
[output]
frame_interval = 0.01
[[contacts]]
between = ["aluminium_alloy", "aluminium_alloy"]
restitution = 0.4
sliding_friction = 0.5
[[contacts]]
between = ["aluminium_alloy", "glass"]
restitution = 0.4
sliding_friction = 0.5
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.008, 0.009, 0.02]
material = "glass"
[[fill]]
count = 12
material = "aluminium_alloy"
radius = 0.0007
region = { lower = [0.0, 0.0, 0.005], upper = [0.008, 0.009, 0.02] }
"""


CYLINDER = """
[[walls]]
kind = "cylinder"
center = [0.004, 0.0045, 0.0]
axis = [0.0, 0.0, 1.0]
radius = 0.004
length = 0.02
material = "glass"
"""


def test_a_box_scene_becomes_lammps_commands_with_its_materials_walls_and_state(load_tool):
    """Every sphere at its position with its diameter and density, one wall/gran per plane
    (the floor and lid on the non-periodic axis), gravity along the scene's, the scene's
    restitution and friction, and a step of a twentieth of the stiffest pair's Hertz contact
    at the fastest reachable impact."""
    tool = load_tool("dem_compare")
    scene = parse_scene(CHUTE)
    cfg = tool.lammps_config(scene, 20.0, [0.05, 0.1])
    cmds = cfg["commands"]
    assert "boundary p p f" in cmds
    walls = [c for c in cmds if c.startswith("fix wall")]
    assert len(walls) == 2
    assert walls[0].endswith("zplane 0.0 NULL")
    assert walls[1].endswith("zplane NULL 0.02")
    assert all("hertz/material 70000000000.0 0.4 0.25" in c for c in walls)  # glass
    assert all("tangential mindlin NULL 1.0 0.5" in c for c in walls)
    grav = next(c for c in cmds if c.startswith("fix grav")).split()
    g = np.array([1.0, 0.0, -9.0])
    assert math.isclose(float(grav[4]), np.linalg.norm(g), rel_tol=1e-15)
    assert np.allclose([float(x) for x in grav[6:9]], g / np.linalg.norm(g), rtol=0, atol=1e-15)
    atoms = [c.split() for c in cmds if c.startswith("create_atoms")]
    assert len(atoms) == 12
    for q, a in enumerate(atoms):
        assert np.array_equal([float(x) for x in a[3:6]], scene.position[q])  # to the bit
    dens = [c for c in cmds if c.startswith("set atom")]
    assert all(c.endswith("diameter 0.0014 density 2700.0") for c in dens)
    assert cfg["velocity"] == scene.velocity.tolist()
    # the step: the Al pair (softer than Al on glass? both E = 70 GPa; the pair of two
    # spheres has the smaller mass and radius) at the fastest initial speed plus a fall
    # through the box's largest extent
    m = 2700.0 * 4.0 / 3.0 * math.pi * 0.0007**3
    v = float(np.max(np.linalg.norm(scene.velocity, axis=1))) + math.sqrt(
        2.0 * np.linalg.norm(g) * 0.02)
    e_star = 70e9 / (2.0 * (1.0 - 0.33**2))
    tc = hertz_contact_time(v, m / 2.0, 0.00035, e_star)
    assert math.isclose(cfg["tc"], tc, rel_tol=1e-12)
    assert math.isclose(cfg["dt"], tc / 20.0, rel_tol=1e-12)


@pytest.mark.parametrize(("change", "message"), [
    (("restitution = 0.4\nsliding_friction = 0.5\n[[walls]]",
      "restitution = 0.3\nsliding_friction = 0.5\n[[walls]]"), "contacts.restitution"),
    (('effects = ["gravity", "rotation", "friction"]',
      'effects = ["gravity", "rotation", "friction", "rolling_resistance"]'),
     "rolling_resistance"),
    (('periodic = [true, true, false]\n', ''), None),
])
def test_a_scene_lammps_is_not_given_is_refused_in_one_line(load_tool, capsys, change,
                                                            message):
    """A second restitution, rolling friction, a cylinder: exit code 2 and one line that
    names what is not given."""
    tool = load_tool("dem_compare")
    text = CHUTE.replace(*change)
    assert text != CHUTE
    if message is None:  # a closed silo: a cylinder on the box's floor
        text += CYLINDER
        message = "cylinders"
    scene = parse_scene(text)
    with pytest.raises(SystemExit) as ex:
        tool.lammps_config(scene, 20.0, [0.1])
    assert ex.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert message in err


def test_the_bed_is_measured_along_the_slope_and_above_the_floor(load_tool):
    """The mean velocity along gravity's part in the floor's plane, the mean height above the
    floor, and the largest speed; with gravity normal to the floor, the mean speed."""
    tool = load_tool("dem_compare")
    scene = parse_scene(CHUTE)
    x = np.array([[0.001, 0.002, 0.0007], [0.003, 0.004, 0.0021]])
    v = np.array([[0.3, 0.1, 0.0], [0.1, -0.1, 0.4]])
    flow, height, fastest = tool._measures(scene, x, v)
    assert flow == pytest.approx(0.2, rel=1e-15)  # gravity's floor part is along x
    assert height == pytest.approx(0.0014, rel=1e-15)
    assert fastest == pytest.approx(np.sqrt(0.18), rel=1e-15)
    level = parse_scene(CHUTE.replace("gravity = [1.0, 0.0, -9.0]", "gravity = [0.0, 0.0, -9.81]"))
    flow, _, _ = tool._measures(level, x, v)
    assert flow == pytest.approx(np.linalg.norm(v, axis=1).mean(), rel=1e-15)
