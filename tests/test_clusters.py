"""The cluster treatment of touching bodies (``[enduring_contact] treatment = "clusters"``,
hsgran._cluster; docs/enduring-contact.md, "Clusters of contacts") in the engine, against
closed forms: a sphere at rest in a V groove, rolling down a tilted groove, sliding into a
corner, a stack of spheres on a plate, and Newton's cradle of five on a plate."""

import math
from collections import namedtuple

import numba
import numpy as np
import pytest

from hsgran._cluster import (
    HAND_OVER_RAPID,
    REACH_SAFETY,
    STEP_MAX,
    STEP_TRAVEL_REL,
    _count,
    _creates_energy,
    _rebound,
    _step_of,
)
from hsgran._state import (
    CONTACTS_PER_BODY,
    I_FROZEN,
    I_SIZE,
    I_STEP_SWEEPS,
    I_SWEEPS,
    I_VISITS,
    MAX_CLUSTER_BODIES,
    WARM_EMPTY,
    Sizes,
)
from hsgran.engine import Simulation
from hsgran.events.kinds import EV_CLUSTER
from hsgran.onplane import MS_REST, MS_SLIDING
from hsgran.scene import parse_scene
from hsgran.wallspec import WK_BALL, WK_FACE, WK_MOVING, WK_PLANE
from tests.scenes import FLOOR, num, plane, sphere

R = 0.001  #: sphere radius of the scenes [m]
G = 9.81

HEAD = """
[scene]
name = "cluster case"
duration = {duration}
gravity = [{gravity}]
effects = [{effects}]
[output]
frame_interval = {duration}
[enduring_contact]
treatment = "{treatment}"
[[contacts]]
between = ["steel", "steel"]
sliding_friction = {mu}
restitution = {e}
rolling_friction = {mu_r}
"""


def scene(body, duration=0.2, gravity=(0.0, 0.0, -G), mu=0.3, e=0.5,
          effects='"gravity", "rotation", "friction"', treatment="clusters", mu_r=0.0):
    return parse_scene(HEAD.format(duration=duration, gravity=", ".join(num(g) for g in gravity),
                                   effects=effects, mu=mu, e=e, treatment=treatment,
                                   mu_r=mu_r) + body)


def groove(beta):
    """Two planes meeting along the x axis, normals at β from the vertical."""
    s, c = num(math.sin(beta)), num(math.cos(beta))
    return (plane(("0.0", "0.0", "0.0"), ("0.0", s, c))
            + plane(("0.0", "0.0", "0.0"), ("0.0", "-" + s, c)))


@pytest.mark.parametrize("beta_deg", [30.0, 45.0, 60.0])
def test_sphere_dropped_into_a_v_groove_comes_to_rest_at_its_bottom(beta_deg):
    """Dropped off-centre into a V groove, the sphere bounces and comes to rest touching both
    planes: centre above the groove's line at R / cos β."""
    b = math.radians(beta_deg)
    sim = Simulation(scene(groove(b) + sphere(("0.0", num(0.3 * R), num(3 * R)))))
    sim.run()
    assert sim.mstate[0] == MS_REST
    np.testing.assert_allclose(sim.vel[0], 0.0, atol=0.0)
    np.testing.assert_allclose(sim.pos[0], (0.0, 0.0, R / math.cos(b)), atol=1e-9 * R)


@pytest.mark.parametrize(("beta_deg", "theta_deg"), [(45.0, 5.0), (30.0, 10.0)])
def test_sphere_rolls_down_a_tilted_groove_at_the_closed_form_acceleration(beta_deg, theta_deg):
    """Placed touching both planes of a groove tilted by θ (gravity tilted instead), the sphere
    rolls on both without slip: x = a t² / 2 with a = g sin θ / (1 + (2/5) / cos² β)."""
    b = math.radians(beta_deg)
    th = math.radians(theta_deg)
    gravity = (G * math.sin(th), 0.0, -G * math.cos(th))
    t = 0.1
    sim = Simulation(scene(groove(b) + sphere(("0.0", "0.0", num(R / math.cos(b)))),
                           duration=t, gravity=gravity, mu=0.9))
    sim.run()
    pos, vel = sim.state_at(t)
    a = G * math.sin(th) / (1.0 + 0.4 / math.cos(b) ** 2)
    assert pos[0, 0] == pytest.approx(0.5 * a * t * t, rel=1e-9)
    assert vel[0, 0] == pytest.approx(a * t, rel=1e-9)
    assert abs(pos[0, 1]) <= 1e-10 * R  # across the groove: rounding only
    assert pos[0, 2] == pytest.approx(R / math.cos(b), rel=1e-12)


def test_sphere_sliding_down_a_frictionless_slope_comes_to_rest_in_the_corner():
    """A sphere let go on a frictionless slope (α) slides into the wall at its foot and rests
    in the corner, touching both."""
    al = math.radians(20.0)
    slope = plane(("0.0", "0.0", "0.0"), (num(math.sin(al)), "0.0", num(math.cos(al))))
    wall = plane(("0.02", "0.0", "0.0"), ("-1.0", "0.0", "0.0"))
    x0 = 0.005
    start = (x0 + R * math.sin(al), 0.0, -x0 * math.tan(al) + R * math.cos(al))
    sim = Simulation(scene(slope + wall + sphere(tuple(num(c) for c in start)), duration=0.5,
                           mu=0.0, effects='"gravity"'))
    sim.run()
    assert sim.mstate[0] == MS_REST
    # the corner: R from the wall, R from the slope
    xc = 0.02 - R
    zc = (R - xc * math.sin(al)) / math.cos(al)
    np.testing.assert_allclose(sim.pos[0], (xc, 0.0, zc), atol=1e-9 * R)


def _corner_case(seed, **kw):
    """A sphere let go above an incline (θ) that ends against a vertical wall at x = 0: every
    parameter drawn from ``seed`` (the single-sphere corners of tools/robustness.py's incline
    kind, where the pairwise rules stopped at the guard in 16 of 20 such draws); ``kw`` go to
    :func:`scene`."""
    rng = np.random.default_rng(seed)
    th = math.radians(rng.uniform(2.0, 40.0))
    e, mu = rng.uniform(0.1, 0.95), rng.uniform(0.05, 0.8)
    x0 = rng.uniform(3.0, 15.0) * R
    start = (x0, 0.0, math.tan(th) * x0 + R / math.cos(th) + rng.uniform(0.0, 5.0) * R)
    incline = plane(("0.0", "0.0", "0.0"), (num(-math.sin(th)), "0.0", num(math.cos(th))))
    wall = plane(("0.0", "0.0", "0.0"), ("1.0", "0.0", "0.0"))
    body = incline + wall + sphere(tuple(num(c) for c in start),
                                   (num(rng.uniform(-0.1, 0.1)), "0.0", "0.0"))
    return th, scene(body, duration=1.0, mu=mu, e=e, **kw)


@pytest.mark.parametrize("seed", range(6))
def test_sphere_rolling_down_an_incline_into_a_wall_comes_to_rest_in_the_corner(seed):
    """Whatever the incline, restitution and friction, the sphere bounces and rolls down into
    the corner and comes to rest there, R from the wall and R from the incline."""
    th, sc = _corner_case(seed)
    sim = Simulation(sc)
    sim.run()
    assert sim.mstate[0] == MS_REST
    np.testing.assert_allclose(sim.pos[0], (R, 0.0, (R + R * math.sin(th)) / math.cos(th)),
                               atol=1e-9 * R)


@pytest.mark.parametrize("seed", range(10))
def test_the_pairwise_rules_hand_a_slow_sphere_pressed_into_a_second_plane_to_a_solve(seed):
    """With the pairwise rules and rolling resistance, the sphere of the same corners comes to
    rest there too: rolling down into the wall slower than a hop, it is handed to the cluster
    solve, which holds it on both planes (hsgran._settling.rests_on_two_planes). Hopped off
    the wall instead, it rolled up, stopped, rolled back and hopped again, for ever."""
    th, sc = _corner_case(seed, treatment="pairwise", mu_r=0.008,
                          effects='"gravity", "rotation", "friction", "rolling_resistance"')
    sim = Simulation(sc)
    sim.run()
    assert sim.mstate[0] == MS_REST
    np.testing.assert_allclose(sim.pos[0], (R, 0.0, (R + R * math.sin(th)) / math.cos(th)),
                               atol=1e-9 * R)


def test_sphere_rolling_off_a_resting_sphere_never_overlaps_it():
    """A sphere let go on the shoulder of another resting on a plate rolls off it: the one
    below comes to rest while the other still moves on it (a solve that halts one partner of
    a moving contact must keep the other from closing on it), without a zero-time sequence
    and without an overlap beyond 1e-9 σ."""
    ang = math.radians(25.0)
    top = (2 * R * math.sin(ang), 0.0, R + 2 * R * math.cos(ang))
    body = FLOOR + sphere(("0.0", "0.0", num(R))) + sphere(tuple(num(c) for c in top))
    sim = Simulation(scene(body, duration=0.05))
    worst = 0.0
    while sim.time < 0.05:
        sim.run(max_collisions=20)
        pos, _ = sim.state_at(sim.time)
        worst = max(worst, (2 * R - np.linalg.norm(pos[1] - pos[0])) / (2 * R))
    assert worst <= 1e-9
    assert sim.pos[1, 2] < top[2] - 0.1 * R  # it has come down off the top


def test_stack_of_three_on_a_plate_stays_at_rest():
    """Three spheres stacked on a plate, touching, stay where they are."""
    body = FLOOR + "".join(sphere(("0.0", "0.0", num((2 * k + 1) * R))) for k in range(3))
    sim = Simulation(scene(body, duration=0.05))
    p0 = sim.pos.copy()
    sim.run()
    np.testing.assert_allclose(sim.pos, p0, atol=1e-12 * R)
    assert (sim.mstate == MS_REST).all()


def test_an_impact_is_not_kept_as_a_force_for_the_next_steps_warm_start():
    """A sphere dropped from 0.1 mm onto a stack of two resting on a plate (e = 0.5): the
    steps that follow start warm from the forces kept per contact (hsgran._cluster._warm_load),
    which must be forces that persist. Kept after the impact's step, the impact's impulse
    over the step is a force of 24 times the weight of all three; a persisting contact force
    carries at most the weight above it."""
    body = (FLOOR + sphere(("0.0", "0.0", num(R))) + sphere(("0.0", "0.0", num(3 * R)))
            + sphere(("0.0", "0.0", num(5 * R + 1e-4))))
    sim = Simulation(scene(body, duration=0.05, e=0.5))
    weight = 3 * G / sim.inv_m[0]
    largest = 0.0
    while sim.time < 0.05:
        sim.run(max_collisions=1)
        kept = np.linalg.norm(sim.wm_f[:3, :, :3], axis=2)
        kept[sim.wm_q[:3] == WARM_EMPTY] = 0.0
        largest = max(largest, kept.max())
    assert sim.solver_counts()["solver_sweeps"] > 0  # the impact was a cluster's step
    assert largest <= weight


@pytest.mark.parametrize("approach", [3e-14, 1e-12])
def test_a_sphere_left_approaching_a_wall_it_touches_is_not_met_again_at_once(approach):
    """Two touching spheres fall side by side, one 1e-12 R from an upright wall (touching it,
    to the prediction: within PLANE_TOUCHING_REL) and drifting into it at ``approach`` [m/s],
    far above rounding. The wall contact is a cluster's (the sphere touches another body);
    the step's solve lets the gap close within the step (u ≥ −g/h) and gives it no impulse.
    Let fly, the sphere met the wall again at once, and the solve after gave it no impulse
    again: a sphere of the 2000-sphere pour met its side wall a thousand times at one instant
    until the collapse guard stopped the run (``_cluster._flies_clear``). It moves on in
    constrained motion instead."""
    v = ("-" + num(approach), "0.0", "0.0")
    x = R * (1.0 + 1e-12)
    body = (plane(("0.0", "0.0", "0.0"), ("1.0", "0.0", "0.0"))
            + sphere((num(x), "0.0", "0.05"), v) + sphere((num(x + 2 * R), "0.0", "0.05"), v))
    sim = Simulation(scene(body, duration=0.02, mu=0.0))
    sim.run()  # no SimulationError: the collapse guard is not reached
    pos, _ = sim.state_at(sim.time)
    assert sim.solver_counts()["solver_sweeps"] > 0  # the wall contact was a cluster's
    assert pos[0, 0] - R >= -1e-9 * R  # the wall
    assert np.linalg.norm(pos[1] - pos[0]) - 2 * R >= -1e-9 * 2 * R
    # they fell freely: nothing held them up
    np.testing.assert_allclose(pos[:, 2], 0.05 - 0.5 * G * 0.02 ** 2, atol=1e-9)


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_newtons_cradle_of_five_on_a_frictionless_plate(e):
    """Ball 0 slides at v into a row of four touching balls (0.1 mm away) on a frictionless
    plate: solved
    together (docs/enduring-contact.md), the row leaves at v(1 + e)/5 and ball 0 at
    v(1 − 4e)/5 (hsgran.contact.cluster's closed form, tests/contact/test_cluster.py)."""
    v = 0.1
    body = FLOOR + sphere(("0.0", "0.0", num(R)), (num(v), "0.0", "0.0"))
    body += "".join(sphere((num(1e-4 + 2 * R * k), "0.0", num(R))) for k in range(1, 5))
    sim = Simulation(scene(body, duration=0.002, mu=0.0, e=e, effects='"gravity"'))
    sim.run()
    np.testing.assert_allclose(sim.vel[1:, 0], v * (1 + e) / 5, rtol=1e-9)
    assert sim.vel[0, 0] == pytest.approx(v * (1 - 4 * e) / 5, abs=1e-9 * v)
    np.testing.assert_allclose(sim.vel[:, 2], 0.0, atol=1e-12)


def test_an_unknown_treatment_is_a_one_line_error_naming_the_key():
    from hsgran.errors import InputError

    text = HEAD.format(duration=0.1, gravity="0.0, 0.0, -9.81", effects='"gravity"', mu=0.3,
                       e=0.5, treatment="soft", mu_r=0.0)
    with pytest.raises(InputError, match=r"enduring_contact\.treatment.*'pairwise', 'clusters'"):
        parse_scene(text + FLOOR + sphere(("0.0", "0.0", "0.002")))


@pytest.mark.parametrize("partner", ["sphere", "boundary"])
@pytest.mark.parametrize("closing", [True, False])
def test_a_slow_sphere_is_not_halted_while_a_moving_partner_closes_on_it(partner, closing):
    """A solve puts a body to rest only where nothing that goes on moving approaches it now
    (``_cluster._rest_candidates``): halted, it would be met at once, and the same solve would
    follow again and again (a zero-time sequence: a corpus box at 0.487 s). Side by side along
    x, so that neither rests on the other: a body at a standstill now and at the step's end
    rests unless its partner, a moving body or a moving boundary sphere, closes on it faster
    than the prediction's slack."""
    from hsgran._cluster import _rest_candidates
    from hsgran._state import F_LANDING_SPEED, GROUPS, Clus

    sim = Simulation(scene(FLOOR + sphere(("0.0", "0.0", num(R)))
                           + sphere((num(2 * R), "0.0", num(R)))))
    clus = sim._groups[GROUPS.index(Clus)]
    v_land = 1e-3
    fsc = np.zeros(16)
    fsc[F_LANDING_SPEED] = v_land
    speed = 1e-4 * (1.0 if closing else -1.0)  # towards the resting one (< v_land)
    for arr in (clus.cl_v, clus.cl_w, clus.cl_a, clus.cl_al, clus.ck_vb, clus.ck_ab):
        arr[:] = 0.0
    clus.ck_a[0] = 0  # the slow body, at x = 0; n from the partner (at +x) to it: −x
    clus.ck_n[0] = (-1.0, 0.0, 0.0)
    clus.ck_gap[0] = 0.0  # touching
    clus.ck_pn[0] = 1e-9  # and carrying an impulse in the step
    clus.cl_v[0] = (0.0, 5e-8, 0.0)  # at a standstill (below SLIP_REL × v_land), now and at
    # the step's end
    clus.cl_depth[:2] = 0
    if partner == "sphere":
        clus.ck_b[0] = 1
        clus.cl_v[1] = (-speed, 0.0, 0.0)
        clus.cl_a[1] = (-speed, 0.0, 0.0)  # goes on moving
        nb = 2
    else:
        clus.ck_b[0] = -1
        clus.ck_vb[0] = (-speed, 0.0, 0.0)
        clus.ck_ab[0] = (-speed, 0.0, 0.0)
        nb = 1
    _rest_candidates(nb, 1, clus, fsc, np.array([0.0, 0.0, -G]))
    assert (clus.cl_depth[0] < 0) == (not closing)
    if partner == "sphere":
        assert clus.cl_depth[1] == 0


def test_a_call_of_the_compiled_loop_ends_after_its_budget_of_solver_work(monkeypatch):
    """The run hands control back (``stop``, progress, checkpoints) after about
    VISITS_PER_CALL contact visits of the cluster solves, not only after EVENTS_PER_CALL
    events; cutting the run there changes nothing. A sphere rolling down a groove is solved
    again at every step's end (STEP_MAX = 0.1 ms): with a budget of one visit each solve
    ends a call."""
    import hsgran.engine as engine

    b, th = math.radians(45.0), math.radians(5.0)
    body = groove(b) + sphere(("0.0", "0.0", num(R / math.cos(b))))
    gravity = (G * math.sin(th), 0.0, -G * math.cos(th))
    whole = Simulation(scene(body, duration=0.05, gravity=gravity, mu=0.9))
    whole.run()
    monkeypatch.setattr(engine, "VISITS_PER_CALL", 1)
    cut = Simulation(scene(body, duration=0.05, gravity=gravity, mu=0.9))
    calls = []
    summary = cut.run(stop=lambda: calls.append(cut.time) and False)
    assert not summary.interrupted
    assert len(calls) >= 400  # one call per solve (500 step ends), not one for the run
    np.testing.assert_array_equal(cut.pos, whole.pos)
    np.testing.assert_array_equal(cut.vel, whole.vel)


def _groups(sim):
    """The engine's state groups a test hands to a kernel: (Flight, Dyn, Space)."""
    from hsgran._state import GROUPS, Dyn, Flight, Space

    return tuple(sim._groups[GROUPS.index(g)] for g in (Flight, Dyn, Space))


def _enter_plane(sim, i, w, rolling):
    """``hsgran._flight.enter_plane`` on sphere i and plane w of ``sim`` at t = 0, with
    friction and rotation (and rolling resistance if ``rolling``)."""
    from hsgran._flight import enter_plane
    from hsgran._state import GROUPS, Walls
    from hsgran.onplane import END_NONE

    flight, dyn, space = _groups(sim)
    walls = sim._groups[GROUPS.index(Walls)]
    enter_plane(i, w, 0.0, END_NONE, flight, dyn, walls, space.gravity, sim.pair_table, sim.fsc,
                True, rolling, True)


@pytest.mark.parametrize(("normal", "carried"), [
    ((0.0, 0.0, 1.0), True),  # a floor
    ((0.0, 0.6, 0.8), True),  # an incline
    ((0.0, -0.9997230906718257, -0.02353172279227536), False),  # a corpus overhang
    ((0.0, 0.0, -1.0), False),  # a ceiling
])
def test_a_sphere_put_on_a_plane_that_gravity_pulls_it_from_flies(normal, carried):
    """A cluster solve that leaves a sphere one touching contact, with a plane, puts it on that
    plane (``_cluster._apply_states``), and a collision with another wall puts a sphere back on
    the plane it slides on (``_settling.collide_wall``). On an overhanging plane (−g·n < 0)
    the sphere flies instead: in on-plane motion it slid along the plane with a negative load,
    its friction pushing it, its spin's end predicted again every 1e-17 s (corpus scene 0-15
    stopped at the collapse guard at 0.606 s). (The sphere touches the plane: one that does
    not flies, below.)"""
    from hsgran.onplane import MS_FLIGHT

    point = tuple(num(c) for c in np.array([0.0, 0.0, 0.01]) - R * np.array(normal))
    sim = Simulation(scene(FLOOR + plane(point, tuple(num(c) for c in normal))
                           + sphere(("0.0", "0.0", "0.01"), ("0.003", "0.0", "0.0")),
                           effects='"gravity", "rotation", "friction", "rolling_resistance"'))
    flight, dyn, space = _groups(sim)
    dyn.omg[0] = (0.0, 0.01, 0.0)
    _enter_plane(sim, 0, 1, rolling=True)
    if carried:
        assert flight.mstate[0] == MS_SLIDING
        assert flight.mplane[0] == 1
        assert float(np.dot(flight.acc[0], normal)) == pytest.approx(0.0, abs=1e-15)
    else:
        assert flight.mstate[0] == MS_FLIGHT
        assert list(flight.acc[0]) == list(space.gravity)
        assert list(dyn.alpha[0]) == [0.0, 0.0, 0.0]


@pytest.mark.parametrize("lift", [1e-11, 1e-7, 1e-6])
def test_a_sphere_put_on_a_plane_it_does_not_touch_flies_and_is_not_moved(lift):
    """A cluster solve counts a plane within TOUCH_REL (1e-6 of σ) as touching and can leave a
    sphere at rest or moving on it that far above it. Moved down onto the plane when it is put
    there, the sphere went into a smaller neighbour on the same plane: in corpus scene 0-28
    (a V wedge) a sphere of 4.45 mm resting 4.3 nm above its plane was put back on it by a
    collision and overlapped its 1.59 mm neighbour by 2.2e-7 σ (worst overlap 3.8e-8 σ in
    the frames). A sphere beyond the prediction's touching distance of the plane flies
    instead, unmoved, and falls onto it; one within rounding of it is put on it."""
    from hsgran._flight import PLANE_TOUCHING_REL
    from hsgran.onplane import MS_FLIGHT

    r_small = R / 3.0
    z_big = R + lift * R
    # the small sphere on the floor, touching the big one (centre distance R + r_small)
    dz = z_big - r_small
    dx = math.sqrt((R + r_small) ** 2 - dz * dz)
    sim = Simulation(scene(FLOOR + sphere(("0.0", "0.0", num(z_big)))
                           + sphere((num(dx), "0.0", num(r_small)), radius=num(r_small))))
    flight, _, space = _groups(sim)
    before = sim.pos[0].copy()
    _enter_plane(sim, 0, 0, rolling=False)
    gap = float(np.linalg.norm(sim.pos[0] - sim.pos[1])) - (R + r_small)
    # no overlap beyond what a snap within touching can make (the old snap from any height:
    # lift R (R - r)/(R + r))
    assert gap >= -PLANE_TOUCHING_REL * R
    if lift * R > PLANE_TOUCHING_REL * R:
        assert flight.mstate[0] == MS_FLIGHT
        assert list(sim.pos[0]) == list(before)
        assert list(flight.acc[0]) == list(space.gravity)
    else:
        assert flight.mstate[0] != MS_FLIGHT
        assert sim.pos[0][2] == pytest.approx(R, abs=PLANE_TOUCHING_REL * R)


def test_the_engine_books_a_solve_whose_friction_froze():
    """hsgran._cluster._count books a solve's sweeps (a step's also as step sweeps), the
    contacts they visited (sweeps × contacts), and one frozen solve (I_FROZEN) where its
    friction was frozen before it converged."""
    isc = np.zeros(I_SIZE, np.int64)
    _count(isc, 12, 5, True, True)
    _count(isc, 3, 4, False, False)
    assert (isc[I_SWEEPS], isc[I_STEP_SWEEPS], isc[I_VISITS], isc[I_FROZEN]) == (15, 12, 72, 1)


def test_the_run_summary_reports_the_cluster_solves_work():
    """A run with cluster solves (a sphere dropped into a V groove) says in its summary how many
    sweeps its solves took, how many contacts they visited and in how many friction froze
    unconverged; the numbers are those the engine counted in the call, and a run without
    solves (the same sphere dropped on a plate, pairwise) prints no such line."""
    sim = Simulation(scene(groove(math.radians(45.0))
                           + sphere(("0.0", num(0.3 * R), num(3 * R)))))
    summary = sim.run()
    assert summary.solver_sweeps > 0
    assert summary.solver_visits >= summary.solver_sweeps
    assert (summary.solver_sweeps, summary.solver_visits, summary.solver_frozen) == (
        int(sim.isc[I_SWEEPS]), int(sim.isc[I_VISITS]), int(sim.isc[I_FROZEN]))
    assert (f"cluster solves: {summary.solver_sweeps:,} sweeps, "
            f"{summary.solver_visits:,} contact visits, friction frozen unconverged in "
            f"{summary.solver_frozen:,}") in summary.lines()
    plain = Simulation(scene(FLOOR + sphere(("0.0", "0.0", num(3 * R))), treatment="pairwise"))
    quiet = plain.run()
    assert quiet.solver_visits == 0
    assert not any(line.startswith("cluster solves") for line in quiet.lines())


#: 40 spheres poured onto a floor tilted by 7° (gravity tilted in a box periodic along x and
#: y): μ = 0.53 > tan 7°, no rolling friction, so no sphere can rest on the floor alone.
BUZZING_BED = """
[scene]
name = "bed on a 7 degree chute"
duration = {duration}
gravity = [1.1955, 0.0, -9.7369]
effects = ["gravity", "rotation", "friction"]
seed = 7
periodic = [true, true, false]
[output]
frame_interval = {duration}
[[contacts]]
between = ["steel", "steel"]
restitution = 0.41
sliding_friction = 0.53
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.006, 0.006, 0.03]
material = "steel"
[[fill]]
count = 40
material = "steel"
radius = 0.000675
region = {{ lower = [0.0, 0.0, 0.004], upper = [0.006, 0.006, 0.03] }}
"""


@pytest.mark.skipif(numba.config.DISABLE_JIT,
                    reason="too slow without the compiler: the streak is 2**17 collisions")
def test_a_bed_that_nothing_holds_alone_is_handed_over_by_its_tc_streak_and_comes_to_rest():
    """With the pairwise rules, the bed of BUZZING_BED jams, but none of its spheres can rest
    alone on the tilted floor, so none can sleep on another: its collisions come within the
    TC time of each other and stay elastic, and it buzzed for ever (1.2 million TC collisions
    of one sphere in a row by 0.4 s). The streak hands it to the cluster solve
    (hsgran._cluster.HAND_OVER_RAPID), whose friction holds it: every sphere at rest, and no
    sphere left with a streak that long."""
    sim = Simulation(parse_scene(BUZZING_BED.format(duration=0.6)))
    sim.run()
    assert (sim.mstate == MS_REST).all()
    assert sim.counts[EV_CLUSTER] > 0
    assert sim.rapid.max() < HAND_OVER_RAPID


def _sliding_cluster(velocities, partners):
    """A cluster for hsgran._cluster._step_of: bodies of radius R at ``velocities`` [m/s], each
    body b touching the immovable partner ``partners[b]`` below it (normal +z): a wall kind
    (hsgran.wallspec ``WK_*``, as wall b) or "sphere" (a sphere at rest)."""
    nb = len(velocities)
    walls = namedtuple("W", "planes_kind")(np.array(
        [k if k != "sphere" else WK_PLANE for k in partners], dtype=np.int64))
    clus = namedtuple("C", "cl_rad cl_v ck_a ck_b ck_q ck_n ck_vb")(
        np.full(nb, R), np.array(velocities, dtype=float), np.arange(nb),
        np.full(nb, -1), np.array([100 + b if k == "sphere" else -1 - b
                                   for b, k in enumerate(partners)]),
        np.tile([0.0, 0.0, 1.0], (nb, 1)), np.zeros((nb, 3)))
    return nb, clus, walls


@pytest.mark.parametrize(("kind", "slowed"), [(WK_PLANE, False), (WK_MOVING, False),
                                             (WK_FACE, True), (WK_BALL, True),
                                             ("sphere", True)])
def test_a_bed_sliding_as_a_block_takes_steps_of_its_relative_motions(kind, slowed):
    """A step's length is set by the relative motions within the cluster and against its
    immovable partners (docs/enduring-contact.md, "Step length and reach"): three spheres
    sliding together at 1 m/s along an unbounded plane take the longest step, STEP_MAX (their
    relative speed is the landing speed); on a finite wall's face, a corner or a resting
    sphere, whose contact the slide carries them off or turns, the step lets them slide
    STEP_TRAVEL_REL of their radius."""
    v_land = 1e-3
    nb, clus, walls = _sliding_cluster([[1.0, 0.0, 0.0]] * 3, [kind] * 3)
    h, reach = _step_of(nb, nb, 0.1, clus, walls, np.array([0.0, 0.0, -G]), v_land)
    v_rel = (1.0 if slowed else 0.0) + v_land
    assert h == pytest.approx(min(STEP_MAX, STEP_TRAVEL_REL * R / v_rel), rel=1e-12)
    assert reach == pytest.approx(REACH_SAFETY * (v_rel * h + G * h * h), rel=1e-12)


def test_a_step_is_cut_by_bodies_moving_apart_and_by_a_normal_speed_at_a_plane():
    """Two spheres parting at ±0.5 m/s about their mean velocity (3 m/s along the plane) close
    or open their distance at 1 m/s, twice the largest speed about the mean; a sphere falling
    onto the plane at 0.2 m/s cuts the step at that speed."""
    v_land = 1e-3
    gravity = np.array([0.0, 0.0, -G])
    nb, clus, walls = _sliding_cluster([[3.5, 0.0, 0.0], [2.5, 0.0, 0.0]], [WK_PLANE] * 2)
    h, _ = _step_of(nb, nb, 0.1, clus, walls, gravity, v_land)
    assert h == pytest.approx(STEP_TRAVEL_REL * R / (1.0 + v_land), rel=1e-12)
    nb, clus, walls = _sliding_cluster([[3.0, 0.0, -0.2], [3.0, 0.0, 0.0]], [WK_PLANE] * 2)
    h, _ = _step_of(nb, nb, 0.1, clus, walls, gravity, v_land)
    assert h == pytest.approx(STEP_TRAVEL_REL * R / (0.2 + v_land), rel=1e-12)


@pytest.mark.parametrize("e", [0.0, 0.5, 0.95, 1.0])
def test_a_rebound_in_a_step_never_outruns_the_motion_without_contacts(e):
    """An impact within a step of h = 1e-4 s (hsgran._cluster._rebound): whatever the
    approach u < 0 and gravity's relative acceleration a_n along the normal, the normal speed
    at the step's end is at most |u + h a_n|, that of the motion without contacts; where
    gravity presses the pair together it is −e u + h a_n, the impact at the step's start; where
    it pulls them apart, −e (u + h a_n), the impact at its end. Taken at the start there, a
    glass sphere in a groove of resting spheres left an overhanging one faster than it came
    (corpus 0-15: 2.4 → 3.5 mm/s, every 0.06 s for 0.4 s)."""
    h = 1e-4
    for u in (-1e-3, -2.4e-3, -0.1, -3.0):
        for an in (-G, -6.0, -1.0, 0.0, 1.0, 6.0, G):
            reb = _rebound(e, u, an, h)
            assert abs(reb) <= abs(u + h * an) * (1.0 + 1e-15)
            expected = -e * u + h * an if an <= 0.0 else -e * (u + h * an)
            assert reb == expected
    # the 0-15 contact: 2.4 mm/s along a groove met a sphere at 0.51 of its normal, a_n = 6 m/s²;
    # at the step's start the rebound would leave at 1.8 mm/s along that normal, faster than
    # the 1.2 mm/s it came with
    u = -2.442e-3 * 0.51
    assert -0.95 * u + h * 6.0 > abs(u + h * 6.0)
    assert _rebound(0.95, u, 6.0, h) < abs(u + h * 6.0)


def _resting_step(end_speed, tgt=0.0, partner_velocity=0.0, rebound=math.nan, pn=None):
    """A sphere of mass 1 kg resting on a plane (normal +z) for hsgran._cluster._creates_energy:
    at rest at the step's start, a step of h = 1e-4 s whose solve gave its contact the impulse
    that ends the step at ``end_speed`` [m/s] along +x (a frozen friction impulse; 0: the
    plane holds it) and at ``tgt`` [m/s] along the normal, the contact's target (an impact's
    rebound ``rebound`` [m/s], NaN: none), with the normal impulse ``pn`` [N s] (None: the one
    that gives the sphere that normal speed; more: a body wedged against others), the plane
    moving at ``partner_velocity`` [m/s] along +x."""
    h = 1e-4
    pt = end_speed  # the tangential impulse [N s] that gives a mass of 1 kg that speed
    clus = namedtuple("C", "cl_inv_m cl_inv_i cl_v cl_w cl_a cl_al ck_pn ck_pt ck_tgt ck_reb "
                           "ck_a ck_b ck_n ck_ab")(
        np.array([1.0]), np.array([1.0]), np.zeros((1, 3)), np.zeros((1, 3)),
        np.array([[end_speed, 0.0, tgt]]), np.zeros((1, 3)),
        np.array([h * G + tgt if pn is None else pn]), np.array([[pt, 0.0, 0.0]]),
        np.array([tgt]), np.array([rebound]), np.array([0]), np.array([-1]),
        np.array([[0.0, 0.0, 1.0]]), np.array([[partner_velocity, 0.0, 0.0]]))
    return _creates_energy(1, 1, h, clus, np.array([0.0, 0.0, -G]), True, 1e-10)


def test_a_step_whose_frozen_friction_gives_energy_is_not_taken():
    """A step's solve may meet its contacts and still give its bodies energy, which frozen
    friction can do (hsgran._cluster._creates_energy; corpus 0-37 sent a resting sphere off
    at 90 m/s): a sphere at rest on a fixed plane given 0.01 m/s along it gains 5e-5 J, far
    more than the ½ m (h g)² = 4.8e-7 J that holding it loses; held still, or given that
    speed by the plane moving beneath it, or lifted by a rebound or an opening target, it
    gains nothing it may not. A rebound supplies at most its binary rebound's energy, however
    large the impulse the solve put on it (corpus 0-6: 16.5 N s on a rebound of 1.9 mm/s)."""
    assert _resting_step(0.01)
    assert not _resting_step(0.0)
    assert not _resting_step(1e-4)  # 5e-9 J gained, less than the 4.8e-7 J the hold loses
    assert not _resting_step(0.01, partner_velocity=0.01)  # the plane carried it
    assert not _resting_step(0.0, tgt=0.05, rebound=0.05)  # a rebound at its target
    assert not _resting_step(0.0, tgt=0.05)  # an overlap opened at its target
    # a wedged body: 16.5 N s at the rebound's 1.9 mm/s would allow 0.03 J, the rebound 2e-6 J
    assert _resting_step(0.01, tgt=1.9e-3, rebound=1.9e-3, pn=16.5)
    assert not _resting_step(0.01, tgt=1.9e-3, pn=16.5)  # an opening: its impulse's work


@pytest.mark.parametrize("n", [1, 4097, 12150, 28800])
def test_a_clusters_room_holds_every_sphere_of_a_silo(n):
    """The cluster scratch holds every sphere of the scene, up to MAX_CLUSTER_BODIES: a bed
    beyond the room is the solve's boundary, held as if immovable while it falls onto the
    bodies it touches, and that step has no solution (the Beverloo silo of 12,150 beads,
    docs/enduring-contact.md, "A hand-over takes over a dense flow"). The silos of
    tools/beverloo.py (up to 28,800 beads) fit whole; without gravity there are no clusters."""
    assert MAX_CLUSTER_BODIES >= 28800
    sizes = Sizes(n=n, gravity=True, rotation=True, planes=2, cells=8, row=4, frames=1, log=1,
                  clusters=True)
    assert (sizes.value("cb"), sizes.value("ck")) == (n, CONTACTS_PER_BODY * n)
    without = Sizes(n=n, gravity=False, rotation=True, planes=2, cells=8, row=4, frames=1,
                    log=1)
    assert (without.value("cb"), without.value("ck")) == (1, 1)
