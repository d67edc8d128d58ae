"""The compiled event loop against the pure-Python reference loop, event by event.

:mod:`hsgran.reference` is an independent, brute-force implementation of the same algorithm
(all pairs, a heapq of every predicted event, contact times derived afresh); only the collision
kernel is shared. Both must execute the same collisions in the same order, at the same times and
with the same impulses.

Why not bit for bit: the two queues predict a pair's contact from different instants. The
engine re-predicts a sphere whenever it crosses a cell face or pops a stale event, and computes
t_now + τ(t_now) from that instant; the reference predicts every pair once, after the later of the
two spheres' last collisions. The two sums differ in the last bit (the first such event comes
within the first 5-25 collisions of every scene below; before it the logs are bit-identical), and
hard-sphere dynamics amplifies the difference about tenfold per collision of a sphere (see
CROSS_CHECK_COLLISIONS in test_engine.py). The number of collisions of each scene is chosen so
the amplified difference stays far below :data:`AGREEMENT_RTOL`.

Which of the two spheres is logged as ``i`` is whichever prediction found the event, which also
depends on the queue design; pairs are therefore compared unordered.
"""

import numpy as np
import pytest

from hsgran.engine import Simulation
from hsgran.reference import ReferenceLoopError, run_reference
from hsgran.scene import parse_scene

#: Relative agreement of every collision time, impulse and restitution, and of the final state
#: (relative to its scale). Measured maxima (engine with its cell grid, JIT on and off alike):
#: gas 3.2e-13 (times) / 5.1e-12 (J_n); box 1.6e-11 / 4.3e-10 (J_n, J_t), 3.8e-11 (e_n); mixture
#: 6.7e-13 / 5.4e-11; final states 1.4e-10 at most. Round-off amplified by chaos is all that
#: separates the loops; a wrong formula on either side shows up at 1e-6 or worse, and the ~20x
#: margin lets the engine change its rounding (for example the order of its predictions) without
#: failing this test.
AGREEMENT_RTOL = 1e-8

#: Collisions compared in the elastic gas: ~9 per sphere, where the measured disagreement is
#: 5e-12 (it passes 1e-9 between 400 and 500 collisions).
GAS_COLLISIONS = 300
#: Collisions compared in the box with gravity, friction and plasticity: 0.29 s of simulated
#: time, when the spheres still carry 4 % of the initial kinetic energy and flights between
#: events are mostly above 0.5 ms (no sphere is near rest; the engine has no enduring contacts).
BOX_COLLISIONS = 250
#: Collisions compared in the polydisperse mixture under gravity: the disagreement grows faster
#: there (unequal masses, curved flights) and passes 1e-8 between 120 and 150 collisions.
MIXTURE_COLLISIONS = 80
#: The energy balance of the reference (initial = final + dissipated) closes to round-off: each
#: collision conserves or books energy to a few ulps; measured ≤ 3e-16 over these runs.
ENERGY_BALANCE_RTOL = 1e-12
#: Closed-form collision times on the ring are sums of a few numbers of order 0.01-0.06 s,
#: each rounded to 1 ulp.
RING_RTOL = 1e-12

GAS = """
[scene]
duration = 50.0
effects = []
seed = 3
periodic = [true, true, true]
[output]
frame_interval = 1.0
[materials.steel]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [{side}, {side}, {side}]
[[fill]]
count = 64
radius = 0.01
material = "steel"
speed = 1.0
region = {{ lower = [0.0, 0.0, 0.0], upper = [{side}, {side}, {side}] }}
"""
#: Side of the gas box [m]: 64 spheres of radius 1 cm at packing fraction 0.2.
GAS_SIDE = (64 * 4 / 3 * np.pi * 0.01**3 / 0.2) ** (1 / 3)

BOX = """
[scene]
duration = 10.0
effects = ["gravity", "rotation", "friction", "plasticity"]
seed = 1
[output]
frame_interval = 1.0
[materials.steel]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
yield_stress = 1.0e9
[[contacts]]
between = ["steel", "steel"]
sliding_friction = 0.3
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.1, 0.1, 0.1]
material = "steel"
[[fill]]
count = 24
radius = 0.008
material = "steel"
speed = 1.0
angular_velocity = [0.0, 20.0, -10.0]
region = { lower = [0.0, 0.0, 0.0], upper = [0.1, 0.1, 0.1] }
"""

MIXTURE = """
[scene]
duration = 10.0
effects = ["gravity"]
seed = 1
periodic = [true, true, false]
[output]
frame_interval = 1.0
[materials.steel]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[materials.glass]
density = 2500.0
youngs_modulus = 63e9
poisson_ratio = 0.22
[[contacts]]
between = ["steel", "glass"]
restitution = 0.8
[[contacts]]
between = ["glass", "glass"]
restitution = 0.9
[[contacts]]
between = ["steel", "steel"]
restitution = 0.95
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.08, 0.08, 0.1]
material = "steel"
[[fill]]
count = 16
radius = [0.004, 0.008]
material = "glass"
speed = 1.0
region = { lower = [0.0, 0.0, 0.0], upper = [0.08, 0.08, 0.1] }
[[fill]]
count = 8
radius = 0.006
material = "steel"
speed = 1.0
region = { lower = [0.0, 0.0, 0.0], upper = [0.08, 0.08, 0.1] }
"""

# Two spheres on a periodic ring of three cells, approaching each other across the boundary:
# they meet at t = 0.008 s through the boundary, then every 0.01 s alternately directly and
# across the boundary again (equal masses, elastic: they swap velocities).
RING = """
[scene]
duration = 0.05
effects = []
periodic = [true, true, true]
[output]
frame_interval = 1.0
[materials.steel]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.06, 0.06, 0.06]
[[particles]]
material = "steel"
radius = 0.01
position = [0.018, 0.02, 0.02]
velocity = [-1.0, 0.0, 0.0]
[[particles]]
material = "steel"
radius = 0.01
position = [0.042, 0.02, 0.02]
velocity = [1.0, 0.0, 0.0]
"""
RING_TIMES = [0.008, 0.018, 0.028, 0.038, 0.048]

# A sphere at rest on a plane under gravity: touching with zero normal speed, which neither loop
# can treat (no enduring contacts yet).
RESTING = """
[scene]
duration = 1.0
effects = ["gravity"]
[output]
frame_interval = 1.0
[materials.steel]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "steel"
[[particles]]
material = "steel"
radius = 0.01
position = [0.0, 0.0, 0.01]
"""

LOG_FIELDS = ("time", "kind", "i", "j", "normal_impulse", "tangential_impulse", "e_n", "stage",
              "regime")


class Log:
    """Observer keeping the engine's event blocks."""

    def __init__(self):
        self.blocks = []

    def on_events(self, block):
        self.blocks.append(block)

    def field(self, name):
        if not self.blocks:
            return np.array([])
        return np.concatenate([getattr(b, name) for b in self.blocks])


def run_engine(scene, collisions=None, brute_force=False):
    """The engine's collision log (dict of arrays) and the simulation after the run."""
    log = Log()
    sim = Simulation(scene, brute_force=brute_force, log_events=True)
    sim.run(max_collisions=collisions, observers=[log])
    return {name: log.field(name) for name in LOG_FIELDS}, sim


def unordered_pairs(i, j):
    return np.sort(np.stack([i, j]), axis=0)


def assert_same_events(eng, ref):
    assert len(eng["time"]) == ref.collisions
    np.testing.assert_array_equal(unordered_pairs(eng["i"], eng["j"]),
                                  unordered_pairs(ref.i, ref.j))
    for name in ("kind", "stage", "regime"):
        np.testing.assert_array_equal(eng[name], getattr(ref, name), err_msg=name)
    for name in ("time", "normal_impulse", "tangential_impulse", "e_n"):
        np.testing.assert_allclose(eng[name], getattr(ref, name), rtol=AGREEMENT_RTOL, atol=0,
                                   err_msg=name)


def assert_same_final_state(sim, ref, scene):
    """Final positions (nearest image), velocities and spins agree relative to their scales."""
    assert sim.time == pytest.approx(ref.t_end, rel=AGREEMENT_RTOL)
    pos, vel = sim.state_at(ref.t_end)
    d = pos - ref.position
    if any(scene.periodic):
        per = np.asarray(scene.periodic)
        length = (scene.box_upper - scene.box_lower)[per]
        d[:, per] -= length * np.round(d[:, per] / length)
    size = float(np.max(np.ptp(ref.position, axis=0)))
    assert np.max(np.abs(d)) <= AGREEMENT_RTOL * size
    np.testing.assert_allclose(vel, ref.velocity, rtol=0,
                               atol=AGREEMENT_RTOL * np.max(np.abs(ref.velocity)))
    if scene.effects.rotation:
        np.testing.assert_allclose(sim.omg, ref.angular_velocity, rtol=0,
                                   atol=AGREEMENT_RTOL * np.max(np.abs(ref.angular_velocity)))
    else:
        assert ref.angular_velocity is None


@pytest.fixture(scope="module")
def gas():
    scene = parse_scene(GAS.format(side=GAS_SIDE))
    return scene, run_reference(scene, max_collisions=GAS_COLLISIONS)


@pytest.fixture(scope="module")
def box():
    scene = parse_scene(BOX)
    return scene, run_reference(scene, max_collisions=BOX_COLLISIONS)


@pytest.fixture(scope="module")
def mixture():
    scene = parse_scene(MIXTURE)
    return scene, run_reference(scene, max_collisions=MIXTURE_COLLISIONS)


def test_elastic_periodic_gas_has_the_reference_event_sequence(gas):
    scene, ref = gas
    eng, sim = run_engine(scene, GAS_COLLISIONS)
    assert_same_events(eng, ref)
    assert_same_final_state(sim, ref, scene)


@pytest.mark.parametrize("brute_force", [False, True], ids=["cell_grid", "all_pairs"])
def test_rough_plastic_spheres_in_a_box_have_the_reference_event_sequence(box, brute_force):
    scene, ref = box
    assert set(ref.kind.tolist()) == {1, 2}  # both pair and wall collisions are compared
    assert len(set(ref.stage.tolist())) > 1  # elastic and plastic stages occur
    eng, sim = run_engine(scene, BOX_COLLISIONS, brute_force=brute_force)
    assert_same_events(eng, ref)
    assert_same_final_state(sim, ref, scene)


def test_fixed_restitution_mixture_has_the_reference_event_sequence(mixture):
    scene, ref = mixture
    assert set(np.round(ref.e_n, 12).tolist()) == {0.8, 0.9, 0.95}  # every contact was used
    eng, sim = run_engine(scene, MIXTURE_COLLISIONS)
    assert_same_events(eng, ref)
    assert_same_final_state(sim, ref, scene)


@pytest.mark.parametrize("name", ["gas", "box", "mixture"])
def test_reference_energy_balance_closes(name, request):
    """Initial energy = final energy + dissipated (kinetic, rotational and potential)."""
    scene, ref = request.getfixturevalue(name)
    m = scene.mass()
    inertia = 0.4 * m * scene.radius**2

    def energy(pos, vel, omg):
        e = 0.5 * m @ np.sum(vel**2, axis=1) - m @ (pos @ scene.gravity)
        return e if omg is None else e + 0.5 * inertia @ np.sum(omg**2, axis=1)

    omg0 = scene.angular_velocity if scene.effects.rotation else None
    e0 = energy(scene.position, scene.velocity, omg0)
    e1 = energy(ref.position, ref.velocity, ref.angular_velocity)
    assert abs(e0 - e1 - ref.dissipated) <= ENERGY_BALANCE_RTOL * e0


def test_reference_meets_periodic_images_at_the_closed_form_times():
    ref = run_reference(parse_scene(RING))
    np.testing.assert_allclose(ref.time, RING_TIMES, rtol=RING_RTOL, atol=0)
    np.testing.assert_array_equal(unordered_pairs(ref.i, ref.j), [[0] * 5, [1] * 5])
    np.testing.assert_allclose(ref.velocity[:, 0], [1.0, -1.0], rtol=RING_RTOL)  # five swaps


def test_reference_stops_on_a_resting_sphere_instead_of_sinking_or_looping():
    with pytest.raises(ReferenceLoopError, match="without time advancing"):
        run_reference(parse_scene(RESTING))


@pytest.mark.parametrize("brute_force", [False, True], ids=["three_cells", "all_pairs"])
def test_engine_meets_periodic_images_like_the_reference(brute_force):
    scene = parse_scene(RING)
    eng, sim = run_engine(scene, brute_force=brute_force)
    if not brute_force:
        assert sim.ncell[0] == 3
    np.testing.assert_allclose(eng["time"], RING_TIMES, rtol=RING_RTOL, atol=0)
