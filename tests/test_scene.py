"""Scene files: the example loads as written, fills are reproducible and valid, and every broken
scene is refused with a one-line message naming the offending key path."""

import math
from pathlib import Path

import numpy as np
import pytest

import hsgran.scene as scene_module
from hsgran.errors import InputError
from hsgran.materials import PAIR_ROW_SIZE, pair_row
from hsgran.scene import load_scene, parse_scene

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"

EXAMPLE = """\
[scene]
name = "steel ball dropped on glass"
duration = 1.0                      # simulated time [s]
gravity = [0.0, 0.0, -9.81]         # [m/s^2]
effects = ["gravity", "rotation", "friction", "plasticity"]
seed = 1
# periodic = [false, false, false]  # per axis, needs a [[walls]] box
[output]
frame_interval = 0.005              # [s]
[materials.steel]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.30
yield_stress = 1.0e9
[materials.glass]
density = 2500.0
youngs_modulus = 70e9
poisson_ratio = 0.25
yield_stress = 3.0e9
[[contacts]]
between = ["steel", "glass"]
sliding_friction = 0.3
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "glass"
[[particles]]
material = "steel"
radius = 0.005
position = [0.0, 0.0, 0.10]
velocity = [0.2, 0.0, 0.0]
angular_velocity = [0.0, 0.0, 0.0]
"""

BALL = """
[[particles]]
material = "steel"
radius = 0.005
position = [0.0, 0.0, 0.1]
"""

BOX = """
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.1, 0.1, 0.2]
material = "glass"
"""


def scene_text(scene="", output="frame_interval = 0.01", body=BALL, duration="duration = 1.0"):
    """A small valid scene with the given pieces replaced."""
    return f"[scene]\n{duration}\n{scene}\n[output]\n{output}\n{body}"


def fill_text(count=300, radius="0.002", seed=5, speed=0.7, region_lower="[0.0, 0.0, 0.0]",
              region_upper="[0.1, 0.1, 0.1]", extra_scene="", body=BOX):
    return scene_text(
        scene=f"seed = {seed}\n{extra_scene}",
        body=body + f"""
[[fill]]
count = {count}
material = "glass"
radius = {radius}
region = {{ lower = {region_lower}, upper = {region_upper} }}
speed = {speed}
""")


def brute_force_overlaps(position, radius, period=None, rows=256):
    """All overlapping pairs (i, j), checked pair by pair (minimum image along periodic axes)."""
    found = []
    for start in range(0, len(radius), rows):
        delta = position[start:start + rows, None, :] - position[None, :, :]
        if period is not None:
            p = np.asarray(period, dtype=float)
            on = p > 0
            delta[..., on] -= p[on] * np.round(delta[..., on] / p[on])
        dist = np.sqrt((delta**2).sum(-1))
        reach = radius[start:start + rows, None] + radius[None, :]
        own = np.arange(start, min(start + rows, len(radius)))
        dist[own - start, own] = np.inf
        found.append(np.argwhere(dist < reach) + np.array([start, 0]))
    return np.concatenate(found)


# ---- the example and the scenario files ----------------------------------------------------

def test_example_loads_with_the_values_written():
    s = parse_scene(EXAMPLE)
    assert s.name == "steel ball dropped on glass"
    assert s.duration == 1.0
    np.testing.assert_array_equal(s.gravity, [0.0, 0.0, -9.81])
    assert s.effects.enabled() == ("gravity", "rotation", "friction", "plasticity")
    assert s.seed == 1
    assert s.periodic == (False, False, False)
    assert s.box_lower is None
    assert s.box_upper is None
    assert s.frame_interval == 0.005
    assert s.material_names == ["steel", "glass"]
    assert len(s.planes) == 1
    plane = s.planes[0]
    np.testing.assert_array_equal(plane.point, [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(plane.normal, [0.0, 0.0, 1.0])
    assert s.material_names[plane.material] == "glass"
    assert plane.key == "walls[0]"
    assert s.n == 1
    np.testing.assert_array_equal(s.position, [[0.0, 0.0, 0.10]])
    np.testing.assert_array_equal(s.velocity, [[0.2, 0.0, 0.0]])
    np.testing.assert_array_equal(s.angular_velocity, np.zeros((1, 3)))
    np.testing.assert_array_equal(s.radius, [0.005])
    np.testing.assert_array_equal(s.material, [0])
    assert s.material.dtype == np.int64
    assert s.position.dtype == np.float64
    steel = s.library.materials["steel"]
    assert (steel.density, steel.youngs_modulus, steel.poisson_ratio, steel.yield_stress) == (
        7800.0, 200e9, 0.30, 1.0e9)
    assert s.library.materials["glass"].yield_stress == 3.0e9
    assert s.library.contact("glass", "steel").sliding_friction == 0.3
    np.testing.assert_allclose(s.mass(), [7800.0 * 4.0 / 3.0 * math.pi * 0.005**3], rtol=1e-15)
    assert s.text == EXAMPLE
    assert s.source == "<string>"


def test_example_scenario_file_is_the_example_verbatim():
    text = (SCENARIOS / "steel_ball_on_glass.toml").read_text()
    body = "".join(line + "\n" for line in text.splitlines() if not line.startswith("# ")
                   or line.startswith("# periodic"))
    assert body == EXAMPLE


@pytest.mark.parametrize("name", ["steel_ball_on_glass", "granular_gas", "falling_box"])
def test_scenario_files_load(name):
    path = SCENARIOS / f"{name}.toml"
    s = load_scene(path)
    assert s.n >= 1
    assert s.source == str(path)
    assert s.text == path.read_text()
    assert brute_force_overlaps(s.position, s.radius,
                                None if s.box_lower is None
                                else np.where(s.periodic, s.box_upper - s.box_lower, 0.0)).size == 0


def test_granular_gas_scenario_is_a_periodic_elastic_gas():
    s = load_scene(SCENARIOS / "granular_gas.toml")
    assert s.periodic == (True, True, True)
    assert s.planes == []
    assert s.effects.enabled() == ()
    np.testing.assert_array_equal(s.gravity, np.zeros(3))
    fraction = np.sum(4.0 / 3.0 * np.pi * s.radius**3) / np.prod(s.box_upper - s.box_lower)
    assert 0.1 <= fraction <= 0.3
    assert 1000 <= s.n <= 10000


def test_falling_box_scenario_is_closed_and_has_every_contact():
    s = load_scene(SCENARIOS / "falling_box.toml")
    assert len(s.planes) == 6
    assert 2000 <= s.n <= 3000
    assert s.effects.enabled() == ("gravity", "rotation", "friction", "plasticity")
    assert np.all((s.radius >= 0.001) & (s.radius <= 0.002))
    assert not np.isnan(s.pair_table()).any()


# ---- walls ---------------------------------------------------------------------------------

def test_box_gives_six_inward_planes():
    s = parse_scene(scene_text(body=BOX + BALL.replace("[0.0, 0.0, 0.1]", "[0.05, 0.05, 0.1]")))
    np.testing.assert_array_equal(s.box_lower, [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(s.box_upper, [0.1, 0.1, 0.2])
    assert [p.key for p in s.planes] == [f"walls[0].{side}_{axis}" for axis in "xyz"
                                          for side in ("lower", "upper")]
    centre = np.array([0.05, 0.05, 0.1])
    for p in s.planes:
        assert np.linalg.norm(p.normal) == 1.0
        assert p.distance(centre) > 0  # the inside is where the normals point
        assert s.material_names[p.material] == "glass"


def test_periodic_axis_has_no_walls():
    s = parse_scene(scene_text(scene="periodic = [true, false, true]",
                               body=BOX + BALL.replace("[0.0, 0.0, 0.1]", "[0.05, 0.05, 0.1]")))
    assert s.periodic == (True, False, True)
    assert [p.key for p in s.planes] == ["walls[0].lower_y", "walls[0].upper_y"]


def test_fully_periodic_box_needs_no_material():
    body = BOX.replace('material = "glass"\n', "") + BALL.replace("[0.0, 0.0, 0.1]",
                                                                  "[0.0, 0.099, 0.15]")
    s = parse_scene(scene_text(scene="periodic = [true, true, true]", body=body))
    assert s.planes == []
    assert s.material_names == ["steel"]


def test_plane_normal_is_normalised():
    body = BALL + '[[walls]]\nkind = "plane"\npoint = [0, 0, 0]\nnormal = [0, 0, 7]\n' \
                  'material = "glass"\n'
    s = parse_scene(scene_text(body=body))
    np.testing.assert_array_equal(s.planes[0].normal, [0.0, 0.0, 1.0])


def test_touching_a_plane_and_a_neighbour_is_allowed():
    body = ('[[walls]]\nkind = "plane"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nmaterial = "glass"\n'
            + BALL.replace("0.1]", "0.005]") + BALL.replace("0.1]", "0.015]"))
    assert parse_scene(scene_text(body=body)).n == 2


# ---- gravity and materials -----------------------------------------------------------------

def test_gravity_defaults_to_standard_with_the_effect_and_zero_without():
    s = parse_scene(scene_text(scene='effects = ["gravity"]'))
    np.testing.assert_array_equal(s.gravity, [0.0, 0.0, -9.81])
    s = parse_scene(scene_text())
    np.testing.assert_array_equal(s.gravity, np.zeros(3))


def test_builtin_materials_serve_and_declared_ones_override():
    s = parse_scene(scene_text(body=BALL.replace("steel", "alumina")))
    assert s.materials[0].youngs_modulus == 380e9
    declared = "[materials.steel]\ndensity = 1000.0\nyoungs_modulus = 1e9\npoisson_ratio = 0.2\n"
    s = parse_scene(scene_text(body=declared + BALL))
    np.testing.assert_allclose(s.mass(), [1000.0 * 4.0 / 3.0 * math.pi * 0.005**3])


def test_infinite_yield_stress_is_allowed_with_plasticity():
    declared = ("[materials.steel]\ndensity = 7800.0\nyoungs_modulus = 200e9\n"
                "poisson_ratio = 0.3\nyield_stress = inf\n")
    s = parse_scene(scene_text(scene='effects = ["plasticity"]', body=declared + BALL))
    assert math.isinf(s.materials[0].yield_stress)


def test_pair_table_is_symmetric_and_made_of_pair_rows():
    body = EXAMPLE.split("[[particles]]")[1]
    text = EXAMPLE + "[[particles]]" + body.replace("steel", "alumina").replace("0.10]", "0.30]")
    text = text.replace('sliding_friction = 0.3\n', 'sliding_friction = 0.3\n[[contacts]]\n'
                        'between = ["alumina", "steel"]\nsliding_friction = 0.1\n'
                        '[[contacts]]\nbetween = ["alumina", "alumina"]\nsliding_friction = 0.2\n')
    s = parse_scene(text)
    table = s.pair_table()
    m = len(s.material_names)
    assert m == 3
    assert table.shape == (m, m, PAIR_ROW_SIZE)
    np.testing.assert_array_equal(table, table.transpose(1, 0, 2))
    lib = s.library
    for i, a in enumerate(s.material_names):
        for j, b in enumerate(s.material_names):
            row = pair_row(lib.materials[a], lib.materials[b], lib.contact(a, b))
            np.testing.assert_array_equal(table[i, j], row)


def test_pair_table_leaves_two_rigid_walls_blank():
    walls = "".join(f'[[walls]]\nkind = "plane"\npoint = [0, 0, {z}]\nnormal = [0, 0, {n}]\n'
                    'material = "rigid"\n' for z, n in ((0, 1), (1, -1)))
    s = parse_scene(scene_text(body=walls + BALL))
    table = s.pair_table()
    assert s.material_names == ["steel", "rigid"]
    assert np.isnan(table[1, 1]).all()
    assert np.isfinite(table[0, 1, 0])


# ---- fills ---------------------------------------------------------------------------------

def test_fill_is_reproducible_from_the_seed():
    a = parse_scene(fill_text(seed=11, radius="[0.001, 0.003]"))
    b = parse_scene(fill_text(seed=11, radius="[0.001, 0.003]"))
    c = parse_scene(fill_text(seed=12, radius="[0.001, 0.003]"))
    for name in ("position", "velocity", "radius", "angular_velocity", "material"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert not np.array_equal(a.position, c.position)
    assert not np.array_equal(a.velocity, c.velocity)
    assert not np.array_equal(a.radius, c.radius)


def test_fill_spheres_are_valid():
    s = parse_scene(fill_text(count=400, radius="[0.002, 0.004]", speed=0.7,
                              region_lower="[0.0, 0.0, 0.05]", region_upper="[0.1, 0.1, 0.2]"))
    assert s.n == 400
    assert brute_force_overlaps(s.position, s.radius).size == 0
    lower = np.array([0.0, 0.0, 0.05])
    upper = np.array([0.1, 0.1, 0.2])
    assert np.all(s.position - s.radius[:, None] >= lower)
    assert np.all(s.position + s.radius[:, None] <= upper)
    np.testing.assert_allclose(np.linalg.norm(s.velocity, axis=1), 0.7, rtol=1e-12)
    assert np.all((s.radius >= 0.002) & (s.radius <= 0.004))
    assert s.radius.std() > 0.0003  # a real spread, not a single size
    # random directions: the mean velocity of 400 unit vectors is small
    assert np.linalg.norm(s.velocity.mean(axis=0)) < 0.7 * 5.0 / math.sqrt(400)
    np.testing.assert_array_equal(s.angular_velocity, np.zeros((400, 3)))


def test_monodisperse_fill_with_spin():
    text = fill_text(count=50, radius="0.003", speed=0.0,
                     extra_scene='effects = ["rotation"]').replace(
        "speed = 0.0", "speed = 0.0\nangular_velocity = [0.0, 0.0, 3.0]")
    s = parse_scene(text)
    np.testing.assert_array_equal(s.radius, np.full(50, 0.003))
    np.testing.assert_array_equal(s.velocity, np.zeros((50, 3)))
    np.testing.assert_array_equal(s.angular_velocity, np.tile([0.0, 0.0, 3.0], (50, 1)))


def test_fill_avoids_explicit_particles_and_planes():
    slope = ('[[walls]]\nkind = "plane"\npoint = [0.05, 0.05, 0.05]\n'
             'normal = [0.0, 0.6, 0.8]\nmaterial = "glass"\n')
    big = BALL.replace("0.005", "0.02").replace("[0.0, 0.0, 0.1]", "[0.05, 0.05, 0.15]")
    s = parse_scene(fill_text(count=300, body=BOX + slope + big))
    assert s.n == 301
    assert brute_force_overlaps(s.position, s.radius).size == 0
    for plane in s.planes:
        assert np.all(plane.distance(s.position) >= s.radius)
    np.testing.assert_array_equal(s.position[0], [0.05, 0.05, 0.15])  # explicit ones first
    assert s.material_names == ["steel", "glass"]


def test_fill_in_a_periodic_box_respects_the_images():
    # an explicit sphere straddling the x boundary: the fill must avoid its image
    edge = BALL.replace("0.005", "0.01").replace("[0.0, 0.0, 0.1]", "[0.001, 0.05, 0.05]")
    s = parse_scene(fill_text(count=300, extra_scene="periodic = [true, true, true]",
                              body=BOX.replace("0.2]", "0.1]") + edge))
    assert s.planes == []
    assert brute_force_overlaps(s.position, s.radius, period=[0.1, 0.1, 0.1]).size == 0


def test_fill_that_cannot_be_placed_says_how_many_it_placed():
    # 0.5 of the region's volume: above what random placement reaches, below the refusal limit
    with pytest.raises(InputError, match=r"^fill\[0\]\.count: placed only \d+ of 200 spheres"):
        parse_scene(fill_text(count=200, radius="0.0049", region_upper="[0.06, 0.06, 0.06]"))


# ---- broken scenes -------------------------------------------------------------------------

BROKEN = [
    # (id, text, key path that must start the message, fragment the message must contain)
    ("toml-syntax", "[scene\nduration = 1", "<string>", "TOML syntax error"),
    ("unknown-top-key", scene_text() + "[[partciles]]\n", "partciles", "did you mean 'particles'"),
    ("unknown-scene-key", scene_text(scene="durration = 2.0"), "scene.durration",
     "did you mean 'duration'"),
    ("missing-duration", scene_text(duration=""), "scene.duration", "missing"),
    ("zero-duration", scene_text(duration="duration = 0.0"), "scene.duration", "> 0"),
    ("nan-duration", scene_text(duration="duration = nan"), "scene.duration", "finite"),
    ("text-duration", scene_text(duration='duration = "1 s"'), "scene.duration", "number"),
    ("unknown-effect", scene_text(scene='effects = ["gravity", "rotation", "fricton"]'),
     "scene.effects[2]", "did you mean 'friction'"),
    ("friction-without-rotation", scene_text(scene='effects = ["friction"]'), "scene.effects",
     "'rotation'"),
    ("gravity-without-effect", scene_text(scene="gravity = [0.0, 0.0, -9.81]"), "scene.gravity",
     "listed but the 'gravity' effect is off"),
    ("gravity-two-components", scene_text(scene='effects = ["gravity"]\ngravity = [0.0, -9.81]'),
     "scene.gravity", "3 numbers"),
    ("negative-seed", scene_text(scene="seed = -1"), "scene.seed", ">= 0"),
    ("periodic-not-list", scene_text(scene="periodic = true"), "scene.periodic", "3 booleans"),
    ("missing-output", "[scene]\nduration = 1.0\n" + BALL, "output.frame_interval", "missing"),
    ("negative-frame-interval", scene_text(output="frame_interval = -0.01"),
     "output.frame_interval", "> 0"),
    ("too-many-frames", scene_text(output="frame_interval = 1e-9"), "output.frame_interval",
     "frames"),
    ("unknown-output-key", scene_text(output="frame_interval = 0.01\nframe_intervall = 0.02"),
     "output.frame_intervall", "did you mean 'frame_interval'"),
    ("bad-poisson-ratio", scene_text(body="[materials.steel]\ndensity = 7800.0\n"
                                          "youngs_modulus = 200e9\npoisson_ratio = 0.6\n" + BALL),
     "materials.steel.poisson_ratio", "(-1, 0.5)"),
    ("unknown-material", scene_text(body=BALL.replace('"steel"', '"steal"')),
     "particles[0].material", "did you mean 'steel'"),
    ("rigid-particle", scene_text(body=BALL.replace('"steel"', '"rigid"')),
     "particles[0].material", "infinite density"),
    ("missing-radius", scene_text(body=BALL.replace("radius = 0.005\n", "")),
     "particles[0].radius", "missing"),
    ("negative-radius", scene_text(body=BALL.replace("0.005", "-0.005")), "particles[0].radius",
     "> 0"),
    ("radius-as-text", scene_text(body=BALL.replace("0.005", '"5 mm"')), "particles[0].radius",
     "number"),
    ("infinite-position", scene_text(body=BALL.replace("0.1]", "inf]")),
     "particles[0].position[2]", "finite"),
    ("missing-position", scene_text(body=BALL.replace("position = [0.0, 0.0, 0.1]\n", "")),
     "particles[0].position", "missing"),
    ("misspelt-particle-key", scene_text(body=BALL.replace("position", "positon")),
     "particles[0].positon", "did you mean 'position'"),
    ("spin-without-rotation",
     scene_text(body=BALL + "angular_velocity = [0.0, 1.0, 0.0]\n"),
     "particles[0].angular_velocity", "'rotation' effect is off"),
    ("overlapping-particles", scene_text(body=BALL + BALL.replace("0.1]", "0.109]")),
     "particles[1].position", "overlaps particles[0]"),
    ("wall-kind-missing", scene_text(body=BALL + '[[walls]]\nnormal = [0, 0, 1]\n'),
     "walls[0].kind", "missing"),
    ("wall-kind-unknown", scene_text(body=BALL + '[[walls]]\nkind = "plain"\n'),
     "walls[0].kind", "did you mean 'plane'"),
    ("zero-normal", scene_text(body=BALL + '[[walls]]\nkind = "plane"\npoint = [0, 0, 0]\n'
                                           'normal = [0, 0, 0]\nmaterial = "glass"\n'),
     "walls[0].normal", "non-zero"),
    ("wall-material-unknown", scene_text(body=BALL + '[[walls]]\nkind = "plane"\n'
                                                     'point = [0, 0, 0]\nnormal = [0, 0, 1]\n'
                                                     'material = "glas"\n'),
     "walls[0].material", "did you mean 'glass'"),
    ("penetrates-plane", scene_text(body=BALL + '[[walls]]\nkind = "plane"\n'
                                                'point = [0, 0, 0.098]\nnormal = [0, 0, 1]\n'
                                                'material = "glass"\n'),
     "particles[0].position", "penetrates wall walls[0]"),
    ("behind-plane", scene_text(body=BALL + '[[walls]]\nkind = "plane"\n'
                                            'point = [0, 0, 0]\nnormal = [0, 0, -1]\n'
                                            'material = "glass"\n'),
     "particles[0].position", "behind wall walls[0]"),
    ("box-upside-down", scene_text(body=BALL + BOX.replace("[0.1, 0.1, 0.2]", "[0.1, -0.1, 0.2]")),
     "walls[0].upper", "(y: upper"),
    ("outside-box", scene_text(body=BOX + BALL), "particles[0].position", "walls[0].lower_x"),
    ("two-boxes", scene_text(body=BOX + BOX + BALL), "walls[1]", "at most one box"),
    ("box-without-material", scene_text(body=BOX.replace('material = "glass"\n', "") + BALL),
     "walls[0].material", "missing"),
    ("periodic-without-box", scene_text(scene="periodic = [true, false, false]"),
     "scene.periodic", "box"),
    ("periodic-box-too-short",
     scene_text(scene="periodic = [false, false, true]",
                body=BOX.replace("0.2]", "0.02]") + BALL.replace("0.1]", "0.01]").replace(
                    "[0.0, 0.0", "[0.05, 0.05")),
     "scene.periodic[2]", "at least 3 cells"),
    ("outside-periodic-cell",
     scene_text(scene="periodic = [true, true, true]",
                body=BOX + BALL.replace("[0.0, 0.0, 0.1]", "[0.05, 0.1, 0.1]")),
     "particles[0].position", "outside the periodic box"),
    ("plane-tilted-to-periodic-axis",
     scene_text(scene="periodic = [true, false, false]",
                body=BOX + '[[walls]]\nkind = "plane"\npoint = [0, 0, 0.01]\n'
                           'normal = [0.1, 0, 1]\nmaterial = "glass"\n'
                     + BALL.replace("[0.0, 0.0, 0.1]", "[0.05, 0.05, 0.1]")),
     "walls[1].normal", "parallel to the periodic axis x"),
    ("friction-pair-without-coefficient",
     scene_text(scene='effects = ["rotation", "friction"]',
                body=BALL + '[[walls]]\nkind = "plane"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n'
                            'material = "glass"\n'),
     "contacts", 'between = ["steel", "glass"] with sliding_friction'),
    ("friction-particle-pair-without-coefficient",
     scene_text(scene='effects = ["rotation", "friction"]',
                body=BALL + BALL.replace("0.1]", "0.2]")),
     "contacts", 'between = ["steel", "steel"]'),
    ("plasticity-without-yield-stress",
     scene_text(scene='effects = ["plasticity"]',
                body="[materials.steel]\ndensity = 7800.0\nyoungs_modulus = 200e9\n"
                     "poisson_ratio = 0.3\n" + BALL),
     "materials.steel.yield_stress", "plasticity"),
    ("contact-unknown-material",
     scene_text(body='[[contacts]]\nbetween = ["steel", "glas"]\nsliding_friction = 0.3\n'
                     + BALL),
     "contacts[0].between", "did you mean 'glass'"),
    ("empty-scene", scene_text(body=""), "particles", "no particles"),
    ("particles-as-table", scene_text(body=BALL.replace("[[particles]]", "[particles]")),
     "particles", "array of tables"),
    ("too-many-particles", fill_text(count=60_000_000), "fill[0].count", "kB per particle"),
    ("gravity-absurd", scene_text(scene='effects = ["gravity"]\ngravity = [0.0, 0.0, -1e300]'),
     "scene.gravity", "not a physical value"),
    ("speed-absurd", scene_text(body=BALL + "velocity = [0.0, 3e4, 0.0]\n"),
     "particles[0].velocity", "beyond 1e+04 m/s"),
    ("spin-absurd", scene_text(scene='effects = ["rotation"]',
                               body=BALL + "angular_velocity = [0.0, 3e6, 0.0]\n"),
     "particles[0].angular_velocity", "surface speed"),
    ("fill-speed-absurd", fill_text(speed=2e4), "fill[0].speed", "beyond 1e+04 m/s"),
    ("fill-count-zero", fill_text(count=0), "fill[0].count", ">= 1"),
    ("fill-count-fraction", fill_text(count=1.5), "fill[0].count", "whole number"),
    ("fill-radius-reversed", fill_text(radius="[0.003, 0.001]"), "fill[0].radius", "exceeds"),
    ("fill-radius-three", fill_text(radius="[0.001, 0.002, 0.003]"), "fill[0].radius",
     "[min, max]"),
    ("fill-region-typo", fill_text().replace("{ lower =", "{ lowr ="), "fill[0].region.lowr",
     "did you mean 'lower'"),
    ("fill-region-outside-box", fill_text(region_upper="[0.1, 0.1, 0.3]"), "fill[0].region",
     "inside the box"),
    ("fill-region-too-thin", fill_text(region_upper="[0.1, 0.003, 0.1]"),
     "fill[0].region.upper", "diameter"),
    ("fill-negative-speed", fill_text(speed=-1.0), "fill[0].speed", ">= 0"),
    ("fill-spin-without-rotation",
     fill_text().replace("speed = 0.7", "speed = 0.7\nangular_velocity = [1.0, 0.0, 0.0]"),
     "fill[0].angular_velocity", "'rotation' effect is off"),
    ("fill-too-dense", fill_text(count=5000, radius="0.005"), "fill[0].count",
     "more than random placement can reach"),
    ("fill-unknown-key", fill_text().replace("speed =", "sped ="), "fill[0].sped",
     "did you mean 'speed'"),
    ("fill-as-table", fill_text().replace("[[fill]]", "[fill]"), "fill", "array of tables"),
]


@pytest.mark.parametrize(("text", "key", "fragment"), [pytest.param(*c[1:], id=c[0])
                                                       for c in BROKEN])
def test_broken_scene_is_refused_with_the_key_path(text, key, fragment):
    with pytest.raises(InputError) as info:
        parse_scene(text)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(key), message
    assert fragment in message, message


def test_the_first_problem_in_the_order_of_the_checks_is_reported():
    """[scene], [output], walls, particles, fills, then the cross checks (hsgran.scene._build)."""
    bad_fill = fill_text(speed=-1.0)
    assert bad_fill.count("frame_interval = 0.01") == 1
    cases = [
        (bad_fill.replace("duration = 1.0", "duration = -1.0"), "scene.duration"),
        (bad_fill.replace("frame_interval = 0.01", "frame_interval = 0.0"),
         "output.frame_interval"),
        (bad_fill.replace('kind = "box"', 'kind = "boxx"'), "walls[0].kind"),
        (bad_fill + BALL.replace("0.005", "-0.005"), "particles[0].radius"),
        (bad_fill + BALL.replace("[0.0, 0.0, 0.1]", "[0.0, 0.0, 0.5]"), "fill[0].speed"),
        (fill_text() + BALL.replace("[0.0, 0.0, 0.1]", "[0.0, 0.0, 0.5]"),
         "particles[0].position"),
    ]
    for text, key in cases:
        with pytest.raises(InputError) as info:
            parse_scene(text)
        assert info.value.key == key, str(info.value)


def test_load_scene_reports_a_missing_file(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        load_scene(tmp_path / "nope.toml")


def test_load_scene_names_the_file_in_syntax_errors(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[scene\n")
    with pytest.raises(InputError, match=r"bad\.toml: TOML syntax error"):
        load_scene(path)


def test_scene_name_defaults_to_the_file_name(tmp_path):
    path = tmp_path / "my_drop.toml"
    path.write_text(scene_text())
    assert load_scene(path).name == "my_drop"


def test_a_scene_larger_than_the_memory_available_is_refused_before_allocating(monkeypatch):
    monkeypatch.setattr(scene_module, "available_memory", lambda: 10**9)  # a 1 GB machine
    limit = int(scene_module.MEMORY_SHARE * 10**9 / scene_module.BYTES_PER_PARTICLE)
    with pytest.raises(InputError) as err:
        parse_scene(fill_text(count=limit + 1))
    assert err.value.key == "fill[0].count"
    assert "GB of memory" in str(err.value)
    assert "1 GB available" in str(err.value)


def test_penetration_message_shows_the_difference():
    """A centre written to 12 decimals just inside contact is refused with numbers that differ
    (not 'centre 0.005 m from the plane, radius 0.005 m')."""
    body = (BALL.replace("[0.0, 0.0, 0.1]", "[0.0, 0.0, 0.004999999999]")
            + '[[walls]]\nkind = "plane"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n'
              'material = "glass"\n')
    with pytest.raises(InputError) as err:
        parse_scene(scene_text(body=body))
    assert "centre 0.004999999999 m from the plane, radius 0.005 m" in str(err.value)
    # within the documented tolerance (1e-12 of the radius) contact is accepted
    ok = body.replace("0.004999999999]", "0.004999999999999999]")
    assert parse_scene(scene_text(body=ok)).n == 1
