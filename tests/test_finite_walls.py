"""Finite walls and fixed spheres (docs/walls.md, "Finite walls"): the contact searches against
sampled oracles, closed-form trajectories at a face, an edge, a corner, a fixed sphere and a
hole just cleared or just not, tiles of a plane against the plane, rolling over an edge, and
the scene keys."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from hsgran.engine import Simulation
from hsgran.errors import InputError
from hsgran.events.kinds import EV_WALL
from hsgran.facets import edge_contact_time, face_leave_time
from hsgran.onplane import MS_FLIGHT, MS_ROLLING
from hsgran.scene import parse_scene
from hsgran.shapes import plane_with_hole, polygon, rectangle, regular_polygon, weld
from hsgran.wallspec import GEO_SIZE, WK_BALL, WK_CYLINDER, WK_FACE
from tests.observers import Keep

G = 9.81  #: [m/s²] (the default gravity)
R = 0.001  #: sphere radius [m]
#: Closed-form times and positions agree to this share [-] (rounding of a few operations on
#: times of ~0.1 s and positions of ~0.1 m, with square roots).
CLOSED_REL = 1e-12
#: A contact time is a root of the distance to this share of r [-].
ROOT_REL = 1e-9
#: A grazing contact (a double root of the squared distance) is found to about √ε ≈ 1.5e-8 of
#: the contact distance, a few times that with the rounding of the coefficients [-].
DOUBLE_ROOT_REL = 1e-7

HEAD = """
[scene]
duration = {duration}
effects = [{effects}]
{gravity}
[output]
frame_interval = {dt}
"""
SPHERE = """
[[particles]]
material = "steel"
radius = {r}
position = [{x!r}, {y!r}, {z!r}]
velocity = [{u!r}, {v!r}, {w!r}]
"""
SQUARE = """
[[walls]]
kind = "polygon"
vertices = [[-0.05, -0.05, 0.0], [0.05, -0.05, 0.0], [0.05, 0.05, 0.0], [-0.05, 0.05, 0.0]]
material = "steel"
"""
ELASTIC = """
[[contacts]]
between = ["steel", "steel"]
restitution = 1.0
"""


def scene_text(walls, x, u=(0.0, 0.0, 0.0), duration=0.5, dt=0.01, gravity=True, extra="",
               effects='"gravity"', r=R):
    head = HEAD.format(duration=duration, dt=dt, effects=effects if gravity else "",
                       gravity="")
    x, u = [float(c) for c in x], [float(c) for c in u]
    return head + walls + SPHERE.format(r=r, x=x[0], y=x[1], z=x[2], u=u[0], v=u[1],
                                        w=u[2]) + extra


def run(text, **kw):
    """Run a scene; return the scene, its frames and its event log."""
    scene = parse_scene(text)
    sim = Simulation(scene, log_events=True)
    keep = Keep()
    summary = sim.run(observers=[keep], **kw)
    frames = {name: keep.cat(name) for name in ("time", "position", "velocity", "motion_state")
              if getattr(keep.frames[0], name) is not None}
    log = {name: keep.log(name) if keep.events else np.zeros(0)
           for name in ("time", "kind", "i", "j", "velocity")}
    return scene, frames, log, summary


# ---- the searches, against sampled oracles -------------------------------------------------

def test_the_edge_search_finds_the_first_touch_between_the_ends():
    """Random parabolas near an edge (the segment |s| ≤ half of the z axis): the time found is
    the first crossing into the line's cylinder of radius r with the foot between the ends
    (a fine grid's first such crossing), and where the distance from the line is r; crossings
    beyond the ends are the corners' (the second-entry path is exercised)."""
    rng = np.random.default_rng(5)
    found = second = 0
    half, r, horizon = 0.01, 0.002, 0.2
    ts = np.linspace(0.0, horizon, 200001)
    for _ in range(400):
        q0 = np.array([*rng.normal(0.0, 1.0, 2), 0.0])
        q0 *= rng.uniform(1.05, 4.0) * r / np.linalg.norm(q0)
        s0 = rng.uniform(-2.0, 2.0) * half
        vel = rng.normal(0.0, 0.1, 3)
        vel[:2] -= rng.uniform(0.0, 0.2) * q0[:2] / np.linalg.norm(q0)  # towards the line
        acc = rng.normal(0.0, 10.0, 3) * rng.integers(0, 2)
        x = (np.array([*q0[:2], s0])[:, None] + np.outer(vel, ts)
             + 0.5 * np.outer(acc, ts * ts))
        d = np.hypot(x[0], x[1]) - r
        into = np.flatnonzero((d[:-1] > 0.0) & (d[1:] <= 0.0))  # crossings into the tube
        between = into[np.abs(x[2, into + 1]) <= half]
        tau = edge_contact_time(*q0, vel[0], vel[1], 0.0, acc[0], acc[1], 0.0, s0, vel[2],
                                acc[2], r, half, horizon, 0.0, 0.0)
        if tau < horizon:
            found += 1
            assert between.size
            assert ts[between[0]] <= tau <= ts[between[0] + 1] + 1e-12
            xt = np.array([*q0[:2], s0]) + vel * tau + 0.5 * acc * tau * tau
            assert abs(math.hypot(xt[0], xt[1]) - r) < ROOT_REL * r
            assert abs(xt[2]) <= half
            if into[0] < between[0]:
                second += 1
        else:
            assert between.size == 0 or between[0] >= len(ts) - 2
    assert found > 60
    assert second > 0


def test_the_foot_leaves_a_face_when_the_oracle_says():
    """A centre moving on a square face with a rectangular hole (random starts, velocities and
    accelerations along it): the time its foot leaves the face is where a fine grid first finds
    it off the face."""
    parts = plane_with_hole(np.zeros(3), np.array([0.0, 0.0, 1.0]),
                            rectangle(np.zeros(3), np.array([0.0, 0.0, 1.0]), (0.02, 0.01)),
                            0, "p")
    face = parts[0]
    geo = face.geo[None].copy()
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(300):
        x0 = np.array([*rng.uniform(-0.04, 0.04, 2), 0.001])
        u, v = x0[:2] @ np.array([face.geo[0:3][:2], face.geo[3:6][:2]]).T
        if not face.on_face(u, v):
            continue
        vel = np.array([*rng.normal(0.0, 0.1, 2), 0.0])
        acc = np.array([*rng.normal(0.0, 2.0, 2), 0.0]) * rng.integers(0, 2)
        tau = face_leave_time(*x0, *vel, *acc, face.point[None], geo, face.lines, 0)
        t_end = min(tau, 1.0)
        ts = np.linspace(0.0, t_end, 4001)
        x = x0[:, None] + np.outer(vel, ts) + 0.5 * np.outer(acc, ts**2)
        d = x.T - face.point
        on = face.on_face(d @ face.geo[0:3], d @ face.geo[3:6])
        assert np.all(on[:-1])
        if tau < 1.0:
            after = x0 + vel * (tau * 1.0001) + 0.5 * acc * (tau * 1.0001) ** 2
            d = after - face.point
            assert not face.on_face(d @ face.geo[0:3], d @ face.geo[3:6])
        checked += 1
    assert checked > 100


# ---- closed forms in the engine -------------------------------------------------------------

def test_a_sphere_dropped_on_a_face_lands_at_the_free_fall_time():
    """Dropped from h above a square plate: the first wall event is at √(2(h − r)/g), and the
    face (not an edge or a corner) is met."""
    h = 0.1
    scene, _, log, _ = run(scene_text(SQUARE, (0.01, 0.02, h), duration=0.2, extra=ELASTIC))
    first = np.flatnonzero(log["kind"] == EV_WALL)[0]
    assert abs(log["time"][first] - math.sqrt(2.0 * (h - R) / G)) < CLOSED_REL
    assert scene.walls[-1 - log["j"][first]].kind == WK_FACE
    assert log["velocity"][first][2] == pytest.approx(math.sqrt(2.0 * G * (h - R)), rel=1e-12)


def flat_mesh(path, n=6, half=0.05):
    """An STL file of a square z = 0 of side 2 half cut into n × n squares of two triangles,
    the triangles' normals up."""
    import trimesh

    x = np.linspace(-half, half, n + 1)
    xx, yy = np.meshgrid(x, x, indexing="ij")
    vertices = np.column_stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)])
    faces = []
    for i in range(n):
        for j in range(n):
            a, b = i * (n + 1) + j, (i + 1) * (n + 1) + j
            faces += [[a, b, b + 1], [a, b + 1, a + 1]]
    trimesh.Trimesh(vertices, np.array(faces), process=False).export(str(path))
    return path


@pytest.mark.parametrize("faces", ["front", "both"])
def test_tiles_of_a_plane_give_the_planes_trajectory(faces, tmp_path):
    """Two triangles that tile a square, four that tile it about its middle, and a mesh of 72
    triangles read from an STL file: a sphere that bounces across them and then rolls over
    their shared sides follows the plane's trajectory to 1e-12 (the sides inside the flat
    surface are no contact geometry)."""
    plane = ("[[walls]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n"
             "material = \"steel\"\n")
    a, b, c, d, m = ([-0.05, -0.05, 0.0], [0.05, -0.05, 0.0], [0.05, 0.05, 0.0],
                     [-0.05, 0.05, 0.0], [0.0, 0.0, 0.0])

    def tiles(tris):
        return "".join(f"[[walls]]\nkind = \"polygon\"\nvertices = {t}\nmaterial = \"steel\"\n"
                       f"faces = \"{faces}\"\n" for t in tris)

    two = tiles([[a, b, c], [a, c, d]])
    four = tiles([[a, b, m], [b, c, m], [c, d, m], [d, a, m]])
    mesh = (f"[[walls]]\nkind = \"mesh\"\nfile = \"{flat_mesh(tmp_path / 'flat.stl')}\"\n"
            f"material = \"steel\"\nfaces = \"{faces}\"\n")
    extra = ("[[contacts]]\nbetween = [\"steel\", \"steel\"]\nrestitution = 0.5\n"
             "sliding_friction = 0.3\n")
    effects = '"gravity", "rotation", "friction"'
    start, vel = (-0.03, -0.02, 0.004), (0.05, 0.04, 0.0)
    runs = [run(scene_text(w, start, vel, duration=1.0, extra=extra, effects=effects))
            for w in (plane, two, four, mesh)]
    ref = runs[0][1]["position"]
    welded = [q for q in runs[3][0].parts if q.kind != WK_FACE]
    assert len(welded) == 2 * 24  # the outline's 24 edges and 24 corners only
    assert np.any(runs[0][1]["motion_state"] == MS_ROLLING)
    for _, frames, _, _ in runs[1:]:
        assert np.max(np.abs(frames["position"] - ref)) < CLOSED_REL * 0.1


def test_a_sphere_thrown_at_an_edge_reflects_about_the_edges_normal():
    """No gravity: a sphere flying at the edge x = 0.05 of a plate (z = 0) from the side,
    offset so that it meets the edge at angle β: it touches when its distance from the edge's
    line is r, and leaves elastically with v − 2 (v·n) n, n from the edge to its centre."""
    beta = 0.4
    z0 = R * math.sin(beta)
    x0 = 0.06
    u = -0.1
    text = scene_text(SQUARE, (x0, 0.0, z0), (u, 0.0, 0.0), duration=0.2, gravity=False,
                      extra=ELASTIC)
    scene, _, log, _ = run(text)
    hits = np.flatnonzero(log["kind"] == EV_WALL)
    assert len(hits) == 1
    t_hit = (x0 - 0.05 - R * math.cos(beta)) / -u
    assert abs(log["time"][hits[0]] - t_hit) < CLOSED_REL
    part = scene.walls[-1 - log["j"][hits[0]]]
    assert part.kind == WK_CYLINDER
    n = np.array([math.cos(beta), 0.0, math.sin(beta)])
    v = np.array([u, 0.0, 0.0])
    assert np.allclose(log["velocity"][hits[0]], v - 2.0 * (v @ n) * n, rtol=0, atol=1e-14)


def test_a_sphere_thrown_at_a_corner_reflects_about_the_line_to_the_corner():
    """No gravity: a sphere flying along the diagonal at the corner (0.05, 0.05, 0) meets it
    when its centre is r away and comes straight back."""
    c = np.array([0.05, 0.05, 0.0])
    direction = np.array([1.0, 1.0, 0.5]) / 1.5
    x0 = c + 0.02 * direction
    v = -0.1 * direction
    scene, _, log, _ = run(scene_text(SQUARE, tuple(x0), tuple(v), duration=0.5,
                                           gravity=False, extra=ELASTIC))
    hits = np.flatnonzero(log["kind"] == EV_WALL)
    assert len(hits) == 1
    assert scene.walls[-1 - log["j"][hits[0]]].kind == WK_BALL
    assert abs(log["time"][hits[0]] - (0.02 - R) / 0.1) < CLOSED_REL
    assert np.allclose(log["velocity"][hits[0]], -v, rtol=0, atol=1e-14)


@pytest.mark.parametrize("clear", [True, False])
def test_a_sphere_falls_through_a_hole_it_just_clears(clear):
    """A plane z = 0 with a square hole of half width a; a sphere falls with its centre d from
    the hole's side x = a, inside the hole. d = r (1 + 1e-6) clears the side; d = r (1 − 1e-6)
    meets the edge where its centre is √(r² − d²) above the plane: at the closed-form time."""
    a = 0.005
    d = R * (1.0 + 1e-6 if clear else 1.0 - 1e-6)
    h = 0.05
    walls = ("[[walls]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n"
             f"material = \"steel\"\nhole = {{ shape = \"rectangle\", center = [0.0, 0.0, 0.0], "
             f"size = [{2 * a}, {2 * a}], axis = [1.0, 0.0, 0.0] }}\n")
    scene, frames, log, _ = run(scene_text(walls, (a - d, 0.0, h), duration=0.15, dt=0.01,
                                           extra=ELASTIC))
    hits = np.flatnonzero(log["kind"] == EV_WALL)
    if clear:
        assert len(hits) == 0
        assert frames["position"][-1, 0, 2] < -0.05
    else:
        z = math.sqrt(R * R - d * d)
        assert abs(log["time"][hits[0]] - math.sqrt(2.0 * (h - z) / G)) < 1e-9
        assert scene.walls[-1 - log["j"][hits[0]]].kind == WK_CYLINDER


def test_a_sphere_dropped_on_a_fixed_sphere():
    """Dropped a horizontal distance b off a fixed sphere's top: it meets it where
    |x − c| = r + R_f, at the closed-form time, and leaves elastically about that normal;
    the fixed sphere (a particle with fixed = true, of a rigid material) never moves."""
    rf, b, h = 0.003, 0.002, 0.05
    text = scene_text("", (b, 0.0, h), duration=0.2, extra=ELASTIC.replace(
        "[\"steel\", \"steel\"]", "[\"steel\", \"rigid\"]") + (
        "[[particles]]\nmaterial = \"rigid\"\nradius = 0.003\nposition = [0.0, 0.0, 0.0]\n"
        "fixed = true\n"))
    scene, _, log, _ = run(text)
    assert scene.n == 1
    hits = np.flatnonzero(log["kind"] == EV_WALL)
    s = R + rf
    z = math.sqrt(s * s - b * b)
    t = math.sqrt(2.0 * (h - z) / G)
    assert abs(log["time"][hits[0]] - t) < CLOSED_REL
    n = np.array([b, 0.0, z]) / s
    v = np.array([0.0, 0.0, -G * t])
    assert np.allclose(log["velocity"][hits[0]], v - 2.0 * (v @ n) * n, rtol=0, atol=1e-12)


def test_a_sphere_rolls_off_the_edge_of_a_plate_at_the_closed_form_angle():
    """Rolling at v₀ to the edge of a plate, a sphere pivots about the edge and flies when
    g cos θ = v²/r: cos θ = (10/17)(1 + 7 v₀²/(10 g r)), rolling without slip throughout."""
    v0 = 0.02
    extra = ("[[contacts]]\nbetween = [\"steel\", \"steel\"]\nrestitution = 0.5\n"
             "sliding_friction = 100.0\n")
    text = scene_text(SQUARE, (0.03, 0.0, R), (v0, 0.0, 0.0), duration=1.5, dt=1e-4,
                      effects='"gravity", "rotation", "friction"', extra=extra)
    text = text.replace("velocity = [", f"angular_velocity = [0.0, {v0 / R!r}, 0.0]\nvelocity = [")
    _, frames, _, _ = run(text)
    x = frames["position"][:, 0]
    states = frames["motion_state"][:, 0]
    off = np.flatnonzero((states == MS_FLIGHT) & (x[:, 0] > 0.05))[0]
    theta = np.arctan2(x[:, 0] - 0.05, x[:, 2])  # from the vertical over the edge
    leave = math.acos(10.0 / 17.0 * (1.0 + 7.0 * v0 * v0 / (10.0 * G * R)))
    assert theta[off - 1] <= leave + 1e-6
    assert leave <= theta[off] + 1e-6
    assert frames["position"][-1, 0, 2] < -0.5  # it fell


# ---- the scene ------------------------------------------------------------------------------

def test_parts_of_the_walls():
    """A polygon is two faces, its edges and corners; a disk's polygon has the circle's area;
    a plane with a hole is a face with the hole's edges and corners; shared flat sides and
    repeated corners are welded away."""
    scene = parse_scene(scene_text(SQUARE, (0.0, 0.0, 0.01)))
    kinds = [p.kind for p in scene.parts]
    assert kinds == [WK_FACE] * 2 + [WK_CYLINDER] * 4 + [WK_BALL] * 4
    disk = regular_polygon(np.zeros(3), np.array([0.0, 0.0, 1.0]), 0.1, 16)
    area = 0.5 * abs(np.sum(disk[:, 0] * np.roll(disk[:, 1], -1)
                            - np.roll(disk[:, 0], -1) * disk[:, 1]))
    assert area == pytest.approx(math.pi * 0.01, rel=1e-12)
    parts = plane_with_hole(np.zeros(3), np.array([0.0, 0.0, 1.0]), disk, 0, "p")
    assert [p.kind for p in parts].count(WK_CYLINDER) == 16
    assert parts[0].geo.shape == (GEO_SIZE,)
    assert not parts[0].on_face(0.0, 0.0)
    assert parts[0].on_face(0.2, 0.0)
    tri = polygon(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float), 0, "t", False)
    assert [p.kind for p in tri] == [WK_FACE] + [WK_CYLINDER] * 3 + [WK_BALL] * 3


@pytest.mark.parametrize(("entry", "key", "words"), [
    ('kind = "polygon"\nvertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.2, 0.2, 0.0], '
     '[0.0, 1.0, 0.0]]\nmaterial = "steel"', "walls[0].vertices", "convex"),
    ('kind = "polygon"\nvertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.1], '
     '[0.0, 1.0, 0.0]]\nmaterial = "steel"', "walls[0].vertices", "one plane"),
    ('kind = "polygon"\nvertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]\nmaterial = "steel"',
     "walls[0].vertices", "at least 3"),
    ('kind = "disk"\ncenter = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nradius = 0.1\n'
     'corners = 2\nmaterial = "steel"', "walls[0].corners", "from 3"),
    ('kind = "disk"\ncenter = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nradius = 0.1\n'
     'faces = "back"\nmaterial = "steel"', "walls[0].faces", "unknown side"),
    ('kind = "plane"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmaterial = "steel"\n'
     'hole = { shape = "oval", center = [0.0, 0.0, 0.0] }', "walls[0].hole.shape",
     "unknown shape"),
    ('kind = "plane"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmaterial = "steel"\n'
     'hole = { shape = "circle", center = [0.0, 0.0, 0.0], size = 1.0 }',
     "walls[0].hole.size", "unknown key"),
    ('kind = "sphere"\ncenter = [0.0, 0.0, 0.0]\nradius = -1.0\nmaterial = "steel"',
     "walls[0].radius", "m"),
    # a pentagram turns one way at every corner, but twice round
    ('kind = "polygon"\nvertices = [[1.0, 0.0, 0.0], [-0.809, 0.588, 0.0], '
     '[0.309, -0.951, 0.0], [0.309, 0.951, 0.0], [-0.809, -0.588, 0.0]]\nmaterial = "steel"',
     "walls[0].vertices", "convex"),
    ('kind = "polygon"\nvertices = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], '
     '[0.0, 1.0, 0.0]]\nmaterial = "steel"', "walls[0].vertices", "written twice"),
    ('kind = "plane"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmaterial = "steel"\n'
     'hole = { shape = "circle", center = [0.0, 0.0, 0.01], radius = 0.1 }',
     "walls[0].hole.center", "in the plane"),
    ('kind = "mesh"\nfile = "hopper.stll"\nmaterial = "steel"', "walls[0].file",
     "cannot read"),
])
def test_bad_finite_walls_are_refused_with_their_key(entry, key, words):
    text = HEAD.format(duration=1.0, dt=0.1, effects='"gravity"', gravity="") + \
        "[[walls]]\n" + entry + "\n" + SPHERE.format(r=R, x=0.0, y=0.0, z=0.5, u=0.0, v=0.0,
                                                      w=0.0)
    with pytest.raises(InputError) as err:
        parse_scene(text)
    assert err.value.key == key
    assert words in str(err.value)


def test_a_fixed_sphere_cannot_move_and_spheres_may_not_start_in_a_wall():
    base = HEAD.format(duration=1.0, dt=0.1, effects='"gravity"', gravity="")
    fixed = ("[[particles]]\nmaterial = \"steel\"\nradius = 0.01\nposition = [0.0, 0.0, 0.0]\n"
             "fixed = true\nvelocity = [1.0, 0.0, 0.0]\n")
    with pytest.raises(InputError) as err:
        parse_scene(base + fixed + SPHERE.format(r=R, x=0.0, y=0.0, z=0.5, u=0.0, v=0.0, w=0.0))
    assert err.value.key == "particles[0].velocity"
    with pytest.raises(InputError) as err:
        parse_scene(base + SQUARE + SPHERE.format(r=R, x=0.0, y=0.0, z=0.0005, u=0.0, v=0.0,
                                                  w=0.0))
    assert "penetrates wall walls[0]" in str(err.value)


def test_fills_keep_clear_of_finite_walls_and_fixed_spheres():
    """A fill whose region holds a plate, a plane's hole rim and fixed spheres places every
    sphere clear of every part."""
    text = HEAD.format(duration=1.0, dt=0.1, effects='"gravity"', gravity="") + SQUARE + """
[[walls]]
kind = "sphere"
center = [0.0, 0.0, 0.01]
radius = 0.004
material = "steel"
[[walls]]
kind = "plane"
point = [0.0, 0.0, -0.01]
normal = [0.0, 0.0, 1.0]
material = "steel"
hole = { shape = "circle", center = [0.0, 0.0, -0.01], radius = 0.006, corners = 12 }
[[fill]]
count = 300
material = "steel"
radius = 0.001
region = { lower = [-0.02, -0.02, -0.015], upper = [0.02, 0.02, 0.02] }
"""
    scene = parse_scene(text)
    assert len(scene.parts) > 20
    for part in scene.parts:
        assert np.all(part.distance(scene.position) >= scene.radius * (1.0 - 1e-12))


def test_finite_walls_in_files_and_exported_drawings(tmp_path):
    """The parts go to the file with their kinds, geometry and lines and come back as the
    scene's parts; the exported drawing holds the plate's faces, the plane with its hole and
    the fixed sphere."""
    from hsgran.api import run_scene
    from hsgran.io.h5md import read_trajectory

    text = scene_text(SQUARE + """
[[walls]]
kind = "plane"
point = [0.0, 0.0, -0.02]
normal = [0.0, 0.0, 1.0]
material = "steel"
hole = { shape = "circle", center = [0.0, 0.0, -0.02], radius = 0.01, corners = 8 }
[[walls]]
kind = "sphere"
center = [0.02, 0.0, 0.01]
radius = 0.004
material = "steel"
""", (0.0, 0.0, 0.05), duration=0.05)
    path = tmp_path / "finite.toml"
    path.write_text(text)
    scene = parse_scene(text)
    run_scene(path, tmp_path / "finite.h5")
    walls = read_trajectory(tmp_path / "finite.h5").walls
    assert walls.key == [w.key for w in scene.walls]
    assert [k for k in range(len(walls)) if walls.is_part(k)] == list(range(len(scene.walls)))
    for k, part in enumerate(scene.parts):
        back = walls.part(k)
        assert back.kind == part.kind
        np.testing.assert_array_equal(back.point, part.point)
        np.testing.assert_array_equal(back.geo, part.geo)
        np.testing.assert_array_equal(back.cyl, part.cyl)
        np.testing.assert_array_equal(back.lines, part.lines)
        if part.kind == WK_FACE and len(part.corners):
            np.testing.assert_allclose(back.corners, part.outline(), atol=1e-15)
    pytest.importorskip("pyvista")
    import pyvista as pv

    from hsgran.export import export

    result = export(tmp_path / "finite.h5", "vtk", tmp_path / "vtk")
    drawn = pv.get_reader(str(result.output)).read()[1]
    points = np.asarray(drawn.points)
    centres = np.asarray(drawn.cell_centers().points)
    normals = np.asarray(drawn.cell_data["normal"])[np.abs(centres[:, 2]) < 1e-12]
    assert sorted(normals[:, 2]) == [-1.0, 1.0]  # both faces of the square
    floor = points[np.abs(points[:, 2] + 0.02) < 1e-12]
    r_floor = np.hypot(floor[:, 0], floor[:, 1])
    assert r_floor.min() > 0.0099  # the hole is not drawn over
    # the floor's triangles cover its rectangle less the hole, once
    cells = drawn.extract_cells(np.flatnonzero(np.abs(centres[:, 2] + 0.02) < 1e-12))
    area = float(np.sum(cells.compute_cell_sizes()["Area"]))
    hole = next(q for q in scene.parts if q.kind == WK_FACE and not len(q.outline())).hole()
    hole_area = 0.5 * abs(np.sum(hole[:, 0] * np.roll(hole[:, 1], -1)
                                 - np.roll(hole[:, 0], -1) * hole[:, 1]))
    assert area == pytest.approx(ConvexHull(floor[:, :2]).volume - hole_area, rel=1e-9)
    on_ball = np.abs(np.linalg.norm(points - [0.02, 0.0, 0.01], axis=1) - 0.004) < 1e-9
    assert np.count_nonzero(on_ball) > 50


BED = """
[scene]
duration = {duration}
effects = ["gravity"]
periodic = [true, true, false]
[output]
frame_interval = 0.01
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.02, 0.02, 0.05]
material = "steel"
[[contacts]]
between = ["steel", "steel"]
restitution = 1.0
[[fill]]
count = 60
material = "steel"
radius = 0.0005
region = {{ lower = [0.0, 0.0, 0.004], upper = [0.02, 0.02, 0.03] }}
speed = 0.1
"""


def bed(n=80, seed=2):
    """A bed of fixed spheres on the floor of a periodic box, as [[particles]] fixed."""
    rng = np.random.default_rng(seed)
    text = ""
    for x, y in rng.uniform(0.0, 0.02, (n, 2)).tolist():
        text += (f"[[particles]]\nmaterial = \"steel\"\nradius = 0.001\n"
                 f"position = [{x!r}, {y!r}, 0.001]\nfixed = true\n")
    return text


def test_the_cell_lists_of_fixed_spheres_give_the_all_pairs_trajectory():
    """Spheres bouncing elastically on a bed of fixed spheres in a periodic box (fixed spheres
    near its sides have images across them): the run through the cells' lists of parts and
    the run that looks at every wall (all-pairs mode) give the same trajectory, and no sphere
    overlaps a fixed one or passes through the bed."""
    text = BED.format(duration=0.08) + bed()
    scene = parse_scene(text)
    balls = [q for q in scene.parts if q.kind == WK_BALL]
    assert len(balls) > 80  # the images
    runs = []
    for brute in (False, True):
        sim = Simulation(scene, brute_force=brute)
        keep = Keep()
        summary = sim.run(observers=[keep])
        runs.append((keep.cat("position"), summary))
    (pos, summary), (ref, _) = runs
    assert summary.events["wall"] > 100
    # (an elastic gas is chaotic: the two runs' rounding, ~1e-18 m at first, grows five-fold
    # a frame; a missed contact would differ by a radius at once)
    assert np.max(np.abs(pos - ref)) < 1e-12
    centres = np.array([q.point for q in balls])
    d = pos[:, :, None, :] - centres[None, None]
    gap = np.linalg.norm(d, axis=-1) - 0.0015
    assert gap.min() > -1e-12
    assert pos[:, :, 2].min() > 0.0


def test_a_fixed_sphere_is_met_across_the_end_of_a_periodic_axis():
    """A fixed sphere near the upper end of the periodic x axis; a sphere dropped near the
    lower end, b across the end from it, meets its image at the closed-form time."""
    rf, b, h = 0.001, 0.0012, 0.02
    text = (BED.format(duration=0.1).split("[[fill]]")[0]
            + "[[particles]]\nmaterial = \"steel\"\nradius = 0.001\n"
            "position = [0.0195, 0.01, 0.001]\nfixed = true\n"
            + SPHERE.format(r=0.0005, x=0.0195 + b - 0.02, y=0.01, z=h, u=0.0, v=0.0, w=0.0))
    scene, _, log, _ = run(text)
    hits = np.flatnonzero(log["kind"] == EV_WALL)
    s = rf + 0.0005
    z = 0.001 + math.sqrt(s * s - b * b)
    assert abs(log["time"][hits[0]] - math.sqrt(2.0 * (h - z) / G)) < CLOSED_REL
    assert scene.walls[-1 - log["j"][hits[0]]].point[0] == pytest.approx(0.0195 - 0.02)


def test_a_finite_wall_must_keep_clear_of_the_ends_of_a_periodic_axis():
    text = BED.format(duration=0.1).split("[[fill]]")[0] + """
[[walls]]
kind = "polygon"
vertices = [[0.0, 0.005, 0.01], [0.01, 0.005, 0.01], [0.01, 0.015, 0.01]]
material = "steel"
""" + SPHERE.format(r=0.0005, x=0.01, y=0.01, z=0.02, u=0.0, v=0.0, w=0.0)
    with pytest.raises(InputError) as err:
        parse_scene(text)
    assert err.value.key == "walls[1]"
    assert "periodic axis x" in str(err.value)


def test_a_mesh_file_that_cannot_be_read_is_refused(tmp_path):
    bad = tmp_path / "bad.stl"
    bad.write_text("solid nothing\nendsolid nothing\n")
    text = scene_text(f"[[walls]]\nkind = \"mesh\"\nfile = \"{bad}\"\nmaterial = \"steel\"\n",
                      (0.0, 0.0, 0.01))
    with pytest.raises(InputError) as err:
        parse_scene(text)
    assert err.value.key == "walls[0].file"
    text = text.replace(str(bad), str(tmp_path / "missing.stl"))
    with pytest.raises(InputError) as err:
        parse_scene(text)
    assert err.value.key == "walls[0].file"


def test_a_fill_of_fixed_spheres_makes_a_rough_base():
    """A fill with fixed = true: its spheres are fixed-sphere walls (with images across the
    periodic ends), placed clear of each other; the moving fill keeps clear of them."""
    text = BED.format(duration=0.1) + """
[[fill]]
count = 40
material = "rigid"
radius = 0.001
region = { lower = [0.0, 0.0, 0.0], upper = [0.02, 0.02, 0.002] }
fixed = true
"""
    scene = parse_scene(text)
    assert scene.n == 60
    balls = [q for q in scene.parts if q.kind == WK_BALL]
    inside = [q for q in balls if np.all((q.point >= 0.0) & (q.point <= 0.02))]
    assert len(inside) == 40
    assert len(balls) > 40  # images
    centres = np.array([q.point for q in inside])
    d = np.linalg.norm(centres[:, None] - centres[None], axis=-1) + np.eye(40)
    assert d.min() >= 0.002 * (1.0 - 1e-12)
    for q in balls:
        assert np.all(q.distance(scene.position) >= scene.radius * (1.0 - 1e-12))
    with pytest.raises(InputError) as err:
        parse_scene(text.replace("fixed = true", "fixed = true\nspeed = 0.1"))
    assert err.value.key == "fill[1].speed"


def test_a_sphere_moving_along_an_edge_flies_at_its_end():
    """On top of the upper edge of an upright fin, moving along it at v (v² > g r, so the
    corner does not hold it): held by the edge until its centre passes the edge's end, then in
    free flight from there (the parabola from the end, at v)."""
    fin = """
[[walls]]
kind = "polygon"
vertices = [[-0.05, 0.0, 0.0], [0.05, 0.0, 0.0], [0.05, 0.0, 0.01], [-0.05, 0.0, 0.01]]
material = "steel"
"""
    v = 0.2
    _, frames, _, _ = run(scene_text(fin, (0.0, 0.0, 0.01 + R), (v, 0.0, 0.0), duration=0.4,
                                     dt=0.01, extra=ELASTIC))
    t = frames["time"]
    x = frames["position"][:, 0]
    before = t <= 0.25 - 1e-9
    np.testing.assert_allclose(x[before, 2], 0.01 + R, rtol=0, atol=1e-12)
    after = t > 0.25
    tau = t[after] - 0.25
    # at the end it grazes the corner: a double root of the contact search, found to ~√ε of
    # the contact distance (DOUBLE_ROOT_REL), whose collision deflects it by that share of v
    slack = 2.0 * v * DOUBLE_ROOT_REL * tau + 1e-12
    assert np.all(np.abs(x[after, 0] - (0.05 + v * tau)) <= slack)
    assert np.all(np.abs(x[after, 2] - (0.01 + R - 0.5 * G * tau**2)) <= slack)


def test_a_triangle_written_twice_keeps_its_rim():
    """Two copies of one triangle (an STL defect) are one plate with its edges and corners."""
    tri = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    parts = weld(polygon(tri, 0, "a") + polygon(tri.copy(), 0, "b"))
    assert [q.kind for q in parts].count(WK_FACE) == 2  # its two sides, once each
    assert [q.kind for q in parts].count(WK_CYLINDER) == 3
    assert [q.kind for q in parts].count(WK_BALL) == 3


POCKET = """
[scene]
name = "pocket"
duration = 0.5
gravity = {gravity}
effects = ["gravity", "rotation", "friction"]
[output]
frame_interval = 0.01
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "steel"
[[contacts]]
between = ["steel", "steel"]
restitution = 0.5
sliding_friction = 0.3
"""


@pytest.mark.parametrize("treatment", ["pairwise", "clusters"])
@pytest.mark.parametrize("tilt", [0.0, 15.0, 30.0])
def test_a_bead_dropped_into_a_pocket_of_fixed_beads_rests_there(tilt, treatment):
    """Three fixed beads on a floor (a rough base's pocket; gravity tilted by ``tilt`` degrees,
    a chute's, less than the 37° of the pocket's walls, so that it holds the bead), a bead
    dropped into it from 0.2 mm: it bounces, falls asleep on the fixed beads
    ([OURS], docs/walls.md, "Resting on fixed spheres") and stays there, touching them and
    overlapping none. It used to buzz between them until the collapse guard stopped the run
    (a 440-bead chute at 0.044 s). The cluster treatment, which takes the fixed beads as
    immovable partners, rests it there too."""
    r, s = 0.001, 0.0021
    g = 9.81
    th = math.radians(tilt)
    text = POCKET.format(gravity=[g * math.sin(th), 0.0, -g * math.cos(th)])
    text += f'[enduring_contact]\ntreatment = "{treatment}"\n'
    centres = np.array([[s / math.sqrt(3.0) * math.cos(a), s / math.sqrt(3.0) * math.sin(a), r]
                        for a in (0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0)])
    for c in centres.tolist():
        text += (f"[[particles]]\nmaterial = \"steel\"\nradius = {r}\nposition = {c!r}\n"
                 "fixed = true\n")
    # dropped from 0.2 mm above where it rests: its rebounds cannot lift it over the rim
    rest = r + math.sqrt(4.0 * r * r - s * s / 3.0)
    text += SPHERE.format(r=r, x=0.0, y=0.0, z=rest + 2e-4, u=0.0, v=0.0, w=0.0)
    _, frames, _, summary = run(text)
    pos = frames["position"][:, 0]
    gaps = np.linalg.norm(pos[:, None, :] - centres[None], axis=-1) - 2.0 * r
    assert gaps.min() > -1e-12
    assert frames["motion_state"][-1, 0] == 3  # at rest (MS_REST)
    assert np.ptp(pos[-10:], axis=0).max() == 0.0
    assert gaps[-1].min() < 1e-9  # on the fixed beads
    assert pos[-1, 2] > r  # above the floor, in the pocket
    assert summary.events["land" if treatment == "pairwise" else "cluster"] >= 1
