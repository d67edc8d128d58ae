"""The cluster solver (hsgran.contact.cluster) against closed forms: simultaneous impacts
(Newton's cradle, a sphere on a plate hitting a wall) and resting contacts (a stack on a plate,
a sphere on three spheres, a sphere in a V groove, rolling down a groove, a sphere in a
corner)."""

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize

from hsgran.contact.cluster import (
    ANDERSON_AFTER,
    ANDERSON_MEMORY,
    DIRECT_AFTER,
    FRICTION_SWEEPS,
    MAX_SWEEPS,
    MPRGP_PER_CONTACT,
    NNLS_STEPS_PER_CONTACT,
    STALL_SWEEPS,
    _finish_frozen,
    _mprgp,
    _nnls,
    _push_normals,
    _worst,
    refine_normals,
    refined,
    solve,
    solve_polished,
    start,
)

#: Steel sphere of radius 1 mm: mass [kg] and moment of inertia [kg m²].
R = 1e-3
M = 7850.0 * 4.0 / 3.0 * math.pi * R**3
I = 0.4 * M * R * R
G = 9.81
#: Relative accuracy asked of a converged solve (the solver stops at 1e-12 change per sweep;
#: chains accumulate the residual over their length).
TOL = 1e-9
#: Convergence tolerance of the solves [m/s or m/s²]: 1e-13 of the speeds and accelerations
#: of these cases (~0.1–10).
SOLVE_TOL = 1e-13


class Cluster:
    """A cluster built contact by contact, for the solver's arrays."""

    def __init__(self, nb, radius=R, mass=M, inertia=I):
        self.inv_m = np.full(nb, 1.0 / mass)
        self.inv_i = np.full(nb, 1.0 / inertia)
        self.rad = np.full(nb, radius)
        self.v = np.zeros((nb, 3))
        self.w = np.zeros((nb, 3))
        self.rows = []

    def contact(self, a, b, n, target=0.0, mu=0.0, slip=(0.0, 0.0, 0.0), mur=0.0, vb=(0, 0, 0)):
        n = np.asarray(n, float) / np.linalg.norm(n)
        rb = self.rad[b] if b >= 0 else 0.0
        reff = self.rad[a] * rb / (self.rad[a] + rb) if b >= 0 else self.rad[a]
        self.rows.append((a, b, n, rb, np.asarray(vb, float), target, mu,
                          np.asarray(slip, float), mur, reff))

    def solve(self, rotation=True, friction=True, rolling=False, warm=None, friction_sweeps=None,
              stall=False, max_sweeps=MAX_SWEEPS, memory=ANDERSON_MEMORY, polish_stall=False):
        """Solve cold, or warm from ``warm`` = (pn, pt, hr) applied by ``start`` first; with
        ``friction_sweeps``, by ``solve_polished`` with that many tangential sweeps (and
        ``stall`` as its ``grow``, ``polish_stall`` as its own: the engine's steps); ``memory``
        0: plain Gauss–Seidel (``solve`` only)."""
        nc = len(self.rows)
        col = list(zip(*self.rows, strict=True))
        self.pn = np.zeros(nc)
        self.pt = np.zeros((nc, 3))
        self.hr = np.zeros((nc, 3))
        if warm is not None:
            self.pn[:], self.pt[:], self.hr[:] = warm
            start(nc, np.array(col[0], np.int64), np.array(col[1], np.int64), np.array(col[2]),
                  np.array(col[3], float), self.inv_m, self.inv_i, self.rad, self.v, self.w,
                  self.pn, self.pt, self.hr, rotation)
        args = (nc, np.array(col[0], np.int64), np.array(col[1], np.int64), np.array(col[2]),
                np.array(col[3], float), np.array(col[4]), np.array(col[5], float),
                np.array(col[6], float), np.array(col[7]), np.array(col[8], float),
                np.array(col[9], float), np.zeros((nc, 3)), self.inv_m, self.inv_i, self.rad,
                self.v, self.w, self.pn, self.pt, self.hr, rotation, friction, rolling,
                SOLVE_TOL)
        if friction_sweeps is None:
            sweeps, worst, self.stalled = solve(*args, max_sweeps, stall, memory)
            self.frozen = False
        else:
            sweeps, worst, self.stalled, self.frozen = solve_polished(*args, friction_sweeps,
                                                                      stall, polish_stall)
        self.sweeps = sweeps
        return worst


@pytest.mark.parametrize("e", [0.0, 0.3, 0.8, 1.0])
def test_newtons_cradle_of_five_takes_the_simultaneous_solution(e):
    """Ball 0 hits a row of four touching balls at v: solved together with Newton's law at
    each contact (docs/enduring-contact.md, "Clusters of contacts"), the row leaves at
    v(1 + e)/5 and ball 0 at v(1 − 4e)/5, which conserves momentum and loses energy for e < 1
    (none at e = 1)."""
    v = 0.5
    c = Cluster(5)
    c.v[0, 0] = v
    for k in range(4):  # contact k: a = ball k + 1, b = ball k, normal +x
        c.contact(k + 1, k, (1.0, 0.0, 0.0), target=e * v if k == 0 else 0.0)
    worst = c.solve()
    assert worst <= TOL * v
    np.testing.assert_allclose(c.v[1:, 0], v * (1 + e) / 5, rtol=TOL)
    assert c.v[0, 0] == pytest.approx(v * (1 - 4 * e) / 5, abs=TOL * v)
    assert c.v[:, 0].sum() == pytest.approx(v, rel=1e-12)
    ke = 0.5 * M * (c.v**2).sum()
    assert ke <= 0.5 * M * v * v * (1 + 1e-12)
    if e == 1.0:
        assert ke == pytest.approx(0.5 * M * v * v, rel=1e-9)


def test_stack_on_a_plate_is_static_with_the_weights_above_each_contact():
    """Three spheres stacked on a plate (force level, gravity −z): no acceleration, and each
    contact carries the weight of the spheres above it."""
    c = Cluster(3)
    c.v[:, 2] = -G  # the "velocities" are accelerations: gravity
    c.contact(0, -1, (0, 0, 1), mu=0.3)
    c.contact(1, 0, (0, 0, 1), mu=0.3)
    c.contact(2, 1, (0, 0, 1), mu=0.3)
    worst = c.solve()
    assert worst <= TOL * G
    np.testing.assert_allclose(c.v, 0.0, atol=TOL * G)
    np.testing.assert_allclose(c.pn, [3 * M * G, 2 * M * G, M * G], rtol=TOL)


def _three_below(top_radius):
    """Unit normals from three spheres of radius R (centres in a triangle, touching) to a
    sphere of radius top_radius resting on them."""
    s = 2 * R / math.sqrt(3)  # centre distance from the triangle's axis
    h = math.sqrt((R + top_radius) ** 2 - s * s)
    out = []
    for k in range(3):
        phi = 2 * math.pi * k / 3
        d = np.array([-s * math.cos(phi), -s * math.sin(phi), h])
        out.append(d / np.linalg.norm(d))
    return out, h / (R + top_radius)


def test_sphere_on_three_fixed_spheres_is_static():
    """A sphere on three touching spheres held where they are: static, each normal force
    m g / (3 cos θ) (θ: contact normal from the vertical), no friction needed."""
    normals, cos_t = _three_below(R)
    c = Cluster(1)
    c.v[0, 2] = -G
    for n in normals:
        c.contact(0, -1, n, mu=0.0)
    worst = c.solve(friction=False)
    assert worst <= TOL * G
    np.testing.assert_allclose(c.v, 0.0, atol=TOL * G)
    np.testing.assert_allclose(c.pn, M * G / (3 * cos_t), rtol=TOL)


@pytest.mark.parametrize(("mu", "static"), [(0.0, False), (0.5, True)])
def test_sphere_on_three_spheres_on_a_plate_needs_friction_to_stand(mu, static):
    """The same pyramid with the three lower spheres free on a plate: with friction (μ = 0.5
    at every contact) it stands; without, the lower spheres are pushed apart and the top one
    falls (downward acceleration)."""
    normals, _ = _three_below(R)
    c = Cluster(4)
    c.v[:, 2] = -G
    for k, n in enumerate(normals):
        c.contact(3, k, n, mu=mu)
        c.contact(k, -1, (0, 0, 1), mu=mu)
    c.solve(friction=mu > 0)
    if static:
        np.testing.assert_allclose(c.v, 0.0, atol=1e-7 * G)
        np.testing.assert_allclose(c.w, 0.0, atol=1e-7 * G / R)
        top = sum(c.pn[2 * k] * normals[k][2] + c.pt[2 * k, 2] for k in range(3))
        assert top == pytest.approx(M * G, rel=1e-7)  # the top sphere's weight
        assert c.pn[1::2].sum() == pytest.approx(4 * M * G, rel=1e-7)  # all on the plate
    else:
        assert c.v[3, 2] < -0.1 * G
        assert np.hypot(c.v[:3, 0], c.v[:3, 1]).min() > 0.01 * G


@pytest.mark.parametrize("scale", [1.0, 0.9, 1.2])
def test_warm_start_from_a_solution_converges_at_once_to_the_same_motion(scale):
    """The pyramid on a plate with friction and rolling resistance, solved cold, then again
    from the same gravity warm from its impulses (scaled: an earlier, nearby solve): exact,
    the solve ends in the first sweeps; scaled, it converges again to the same motion (rest),
    in fewer sweeps than cold."""
    normals, _ = _three_below(R)

    def pyramid():
        c = Cluster(4)
        c.v[:, 2] = -G
        for k, n in enumerate(normals):
            c.contact(3, k, n, mu=0.5, mur=0.01)
            c.contact(k, -1, (0, 0, 1), mu=0.5, mur=0.01)
        return c

    cold = pyramid()
    cold.solve(rolling=True)
    warm = pyramid()
    warm.solve(rolling=True, warm=(scale * cold.pn, scale * cold.pt, scale * cold.hr))
    np.testing.assert_allclose(warm.v, 0.0, atol=1e-7 * G)
    np.testing.assert_allclose(warm.w, 0.0, atol=1e-7 * G / R)
    assert warm.pn[1::2].sum() == pytest.approx(4 * M * G, rel=1e-7)
    if scale == 1.0:
        assert warm.sweeps <= 2
        np.testing.assert_allclose(warm.pn, cold.pn, rtol=1e-12)
    else:
        assert warm.sweeps < cold.sweeps


def _pyramid(mu=0.5, mur=0.01):
    """Three spheres on a plate and one on them, falling at g for a unit step [m/s]."""
    normals, _ = _three_below(R)
    c = Cluster(4)
    c.v[:, 2] = -G
    c.v[3, 0] = 0.3 * G  # the top one also moving sideways: friction must hold it
    for k, n in enumerate(normals):
        c.contact(3, k, n, mu=mu, mur=mur)
        c.contact(k, -1, (0, 0, 1), mu=mu, mur=mur)
    return c


@pytest.mark.parametrize("polish_stall", [False, True])
@pytest.mark.parametrize("friction_sweeps", [1, 3, 10])
def test_polished_solve_meets_the_normal_conditions_where_friction_is_cut_short(
        friction_sweeps, polish_stall):
    """solve_polished with the tangential sweeps cut short (as where a slipping mode converges
    slowly): the normal velocities still meet their targets to the tolerance and every
    impulse and rolling couple ends inside its cone, however short the cut; the solve says
    that it froze them (what the engine counts as I_FROZEN). With ``polish_stall`` (the
    engine's steps) the normals are finished directly with friction frozen and the cones
    clipped between rounds (``_finish_frozen``), in place of the proportional polish's sweeps:
    each round's finish may leave a cone exceeded by what it changed its normal impulse, a
    rounding-level part of the impulses here."""
    c = _pyramid()
    worst = c.solve(rolling=True, friction_sweeps=friction_sweeps, polish_stall=polish_stall)
    assert c.frozen
    assert worst <= SOLVE_TOL
    if polish_stall:
        assert c.sweeps == friction_sweeps  # no polish sweeps: finished directly
    cones = np.linalg.norm(c.pt, axis=1) - 0.5 * c.pn
    assert cones.max() <= 1e-15 * c.pn.max()
    reff = np.array([row[9] for row in c.rows])
    assert (np.linalg.norm(c.hr, axis=1) - 0.01 * reff * c.pn).max() <= 1e-15 * c.pn.max() * R


def test_a_direct_finish_that_cannot_meet_the_normals_leaves_the_impulses_as_they_were():
    """A sphere pressed head-on against a fixed wall by a boundary that moves into it: with
    friction frozen, no normal impulses meet both contacts, so the direct finish
    (``_finish_frozen``) falls short of the tolerance, says so, and puts the velocities and
    impulses back bit for bit, for the proportional polish to start from where the friction
    sweeps ended (a normal impulse it took towards zero under an unclipped tangential one gave
    that polish a ratio |P_t|/P_n far outside the cone: corpus scene 0-6 ran off to 1e300)."""
    c = _pressed_into_a_wall(0.0, 0.5)
    c.v[0] = (0.02, 0.0, 0.0)  # sliding along the wall too: friction carries impulses
    c.solve(rotation=True, max_sweeps=50)
    nc = len(c.rows)
    col = list(zip(*c.rows, strict=True))
    before = (c.v.copy(), c.w.copy(), c.pn.copy(), c.pt.copy(), c.hr.copy())
    assert c.pn.min() > 0.0
    assert np.linalg.norm(c.pt, axis=1).min() > 0.0
    worst = _finish_frozen(nc, np.array(col[0], np.int64), np.array(col[1], np.int64),
                           np.array(col[2]), np.array(col[3], float), np.array(col[4]),
                           np.array(col[5], float), np.array(col[6], float),
                           np.array(col[8], float), np.array(col[9], float), c.inv_m, c.inv_i,
                           c.rad, c.v, c.w, c.pn, c.pt, c.hr, True, True, False, SOLVE_TOL)
    assert worst > 1e-3  # the boundary closes at 10 mm/s: nothing meets both contacts
    for was, now in zip(before, (c.v, c.w, c.pn, c.pt, c.hr), strict=True):
        np.testing.assert_array_equal(now, was)


def test_polished_solve_that_converges_is_the_plain_solve():
    """Where friction converges within its sweeps, solve_polished is solve, bit for bit."""
    plain, polished = _pyramid(), _pyramid()
    plain.solve(rolling=True)
    polished.solve(rolling=True, friction_sweeps=10**6)
    assert not polished.frozen
    assert polished.sweeps == plain.sweeps
    np.testing.assert_array_equal(polished.pn, plain.pn)
    np.testing.assert_array_equal(polished.v, plain.v)


@pytest.mark.parametrize("beta_deg", [20.0, 45.0, 70.0])
def test_sphere_in_a_v_groove_is_static(beta_deg):
    """A sphere in a horizontal V groove (plane normals at β from the vertical): static, each
    normal force m g / (2 cos β)."""
    b = math.radians(beta_deg)
    c = Cluster(1)
    c.v[0, 2] = -G
    c.contact(0, -1, (0, math.sin(b), math.cos(b)))
    c.contact(0, -1, (0, -math.sin(b), math.cos(b)))
    worst = c.solve(friction=False)
    assert worst <= TOL * G
    np.testing.assert_allclose(c.v, 0.0, atol=TOL * G)
    np.testing.assert_allclose(c.pn, M * G / (2 * math.cos(b)), rtol=TOL)


@pytest.mark.parametrize(("beta_deg", "theta_deg"), [(30.0, 10.0), (45.0, 5.0), (60.0, 15.0)])
def test_sphere_rolls_down_a_groove_at_the_closed_form_acceleration(beta_deg, theta_deg):
    """A sphere at rest in a V groove tilted by θ along its axis (x) rolls on both planes
    without slip: its rolling radius is R cos β, so a = g sin θ / (1 + (2/5)/cos² β), and
    the spin's rate is a / (R cos β) about the axis across the groove."""
    b = math.radians(beta_deg)
    th = math.radians(theta_deg)
    c = Cluster(1)
    c.v[0] = (G * math.sin(th), 0.0, -G * math.cos(th))
    c.contact(0, -1, (0, math.sin(b), math.cos(b)), mu=0.9)
    c.contact(0, -1, (0, -math.sin(b), math.cos(b)), mu=0.9)
    worst = c.solve()
    assert worst <= TOL * G
    a = G * math.sin(th) / (1 + 0.4 / math.cos(b) ** 2)
    np.testing.assert_allclose(c.v[0], (a, 0.0, 0.0), atol=TOL * G)
    np.testing.assert_allclose(c.w[0], (0.0, a / (R * math.cos(b)), 0.0), rtol=TOL,
                               atol=TOL * G / R)
    assert np.linalg.norm(c.pt, axis=1).max() <= 0.9 * c.pn.min()


def test_sphere_slides_down_a_frictionless_slope_into_a_corner_and_rests_there():
    """Impact: a sphere sliding down a slope (angle α) into a vertical wall at speed v stops
    against both (e = 0; the two normals leave it no direction to go); force level: it then
    rests in the corner, the slope carrying m g / cos α and the wall m g tan α."""
    al = math.radians(25.0)
    n_slope = np.array([math.sin(al), 0.0, math.cos(al)])  # slope falling towards +x
    n_wall = np.array([-1.0, 0.0, 0.0])  # wall at the foot, facing −x
    v = 0.2
    c = Cluster(1)
    c.v[0] = v * np.array([math.cos(al), 0.0, -math.sin(al)])  # down the slope
    c.contact(0, -1, n_slope, target=0.0)
    c.contact(0, -1, n_wall, target=0.0)
    c.solve(friction=False)
    np.testing.assert_allclose(c.v[0], 0.0, atol=TOL * v)
    d = Cluster(1)
    d.v[0, 2] = -G
    d.contact(0, -1, n_slope)
    d.contact(0, -1, n_wall)
    d.solve(friction=False)
    np.testing.assert_allclose(d.v[0], 0.0, atol=TOL * G)
    np.testing.assert_allclose(d.pn, [M * G / math.cos(al), M * G * math.tan(al)], rtol=TOL)


def test_sphere_on_a_plate_hitting_a_wall_rebounds_along_the_plate():
    """A sphere lying on a plate meets a wall head-on at v with e: the plate takes nothing,
    the sphere rebounds at e v along the plate."""
    e, v = 0.6, 0.3
    c = Cluster(1)
    c.v[0, 0] = -v
    c.contact(0, -1, (0, 0, 1), mu=0.3)
    c.contact(0, -1, (1, 0, 0), target=e * v, mu=0.3)
    c.solve()
    np.testing.assert_allclose(c.v[0], (e * v, 0.0, 0.0), atol=TOL * v)
    assert c.pn[0] == pytest.approx(0.0, abs=TOL * M * v)


def _pressed_into_a_wall(delta_deg, mu, speed=0.01):
    """A sphere at rest on a fixed wall (normal +z) and touched from above by a boundary that
    moves down into it at ``speed`` [m/s], its normal tilted by δ from the vertical: the
    sphere can only get out sideways, which friction forbids where tan δ < 2 μ (the two
    contacts' friction, each μ times a normal impulse of about the same size, against the
    boundary's sideways push, tan δ times it): then no impulses meet both contacts."""
    d = math.radians(delta_deg)
    c = Cluster(1)
    c.contact(0, -1, (0, 0, 1), mu=mu)
    c.contact(0, -1, (math.sin(d), 0, -math.cos(d)), mu=mu, vb=(0, 0, -speed))
    return c


@pytest.mark.parametrize("rotation", [True, False])
@pytest.mark.parametrize(("delta_deg", "mu"), [(10.0, 0.5), (20.0, 0.2)])
def test_a_solve_with_no_solution_stalls_at_its_first_check(rotation, delta_deg, mu):
    """Pressed into a wall by a moving boundary and locked by friction, the impulses grow
    by the same amount every sweep: the solve without ``stall`` runs out its sweeps with
    the contacts still closing; with it, it stops at the first comparison of two spans
    (2 × STALL_SWEEPS sweeps) and says so; solve_polished then freezes friction there and
    meets the normal conditions, or with ``grow`` hands the cluster back unfinished."""
    c = _pressed_into_a_wall(delta_deg, mu)
    assert c.solve(rotation=rotation, max_sweeps=4000) > 1e-3  # approaching at ~ mm/s
    assert c.sweeps == 4000
    assert not c.stalled
    c = _pressed_into_a_wall(delta_deg, mu)
    assert c.solve(rotation=rotation, stall=True) > 1e-3
    assert c.sweeps == 2 * STALL_SWEEPS
    assert c.stalled
    c = _pressed_into_a_wall(delta_deg, mu)
    worst = c.solve(rotation=rotation, friction_sweeps=FRICTION_SWEEPS)
    assert worst <= SOLVE_TOL
    assert not c.stalled
    assert (np.linalg.norm(c.pt, axis=1) - mu * c.pn).max() <= 1e-15 * c.pn.max()
    c = _pressed_into_a_wall(delta_deg, mu)
    c.solve(rotation=rotation, friction_sweeps=FRICTION_SWEEPS, stall=True)
    assert c.stalled
    assert c.sweeps == 2 * STALL_SWEEPS


def test_a_frictionless_solve_with_no_solution_stalls_where_the_cluster_can_grow():
    """Frictionless, a sphere pressed head-on against a wall by a boundary that moves into it
    has no way out: with ``grow`` solve_polished stops at the first comparison of two spans;
    without it, the solve runs to MAX_SWEEPS as before (its caller falls back)."""
    c = _pressed_into_a_wall(0.0, 0.0)
    c.solve(friction=False, friction_sweeps=FRICTION_SWEEPS, stall=True)
    assert c.stalled
    assert c.sweeps == 2 * STALL_SWEEPS
    c = _pressed_into_a_wall(0.0, 0.0)
    assert c.solve(friction=False, friction_sweeps=FRICTION_SWEEPS) > 1e-3
    assert not c.stalled
    assert c.sweeps == MAX_SWEEPS


def test_a_solve_with_a_solution_does_not_stall():
    """Where friction lets the sphere out (tan δ > 2 μ), the solve converges as without
    ``stall``, bit for bit; so does a column of 20 spheres on a plate, whose convergence is
    slow (sweeps ∝ its length squared)."""
    for make in (lambda: _pressed_into_a_wall(40.0, 0.1), lambda: _column(20)):
        plain, watched = make(), make()
        plain.solve()
        watched.solve(stall=True)
        assert not watched.stalled
        assert watched.sweeps == plain.sweeps < MAX_SWEEPS
        np.testing.assert_array_equal(watched.v, plain.v)
        np.testing.assert_array_equal(watched.pn, plain.pn)


def _column(n):
    """n spheres stacked on a plate under gravity, with friction (force level)."""
    c = Cluster(n)
    c.v[:, 2] = -G
    c.contact(0, -1, (0, 0, 1), mu=0.5)
    for k in range(1, n):
        c.contact(k, k - 1, (0, 0, 1), mu=0.5)
    return c


@pytest.mark.parametrize("n", [5, 20])
def test_anderson_acceleration_finds_a_columns_forces_in_far_fewer_sweeps(n):
    """A column of n spheres on a plate (force level): plain Gauss–Seidel needs sweeps of the
    order of n² (the weight reaches the plate one contact per sweep, and back); with Anderson's
    combination after ANDERSON_AFTER sweeps the same forces, contact k carrying the weight of
    the n − k spheres above it, come in a fraction of them (measured: 5 spheres 330 → 37
    sweeps; 20 spheres 5,197 → 181)."""
    plain, fast = _column(n), _column(n)
    assert plain.solve(memory=0) <= SOLVE_TOL
    assert fast.solve() <= SOLVE_TOL
    weight = M * G * (n - np.arange(n))
    np.testing.assert_allclose(plain.pn, weight, rtol=TOL)
    np.testing.assert_allclose(fast.pn, weight, rtol=TOL)
    np.testing.assert_allclose(fast.v, 0.0, atol=n * SOLVE_TOL)
    assert plain.sweeps > 4 * ANDERSON_AFTER
    assert fast.sweeps < plain.sweeps / 8


def test_acceleration_does_not_wedge_a_sphere_with_forces_its_motion_does_not_ask():
    """A sphere (aluminium, r = 1.71 mm) sliding along the groove between a wall and a resting
    sphere whose normals are 162° apart, μ = 0.62, μ_r = 0.02, warm from its last step's
    forces (corpus scene 0-17 at 0.3472 s, to six digits). Friction tilts both contact forces
    by up to 32°, so a pair of opposite forces along the line of the two contacts, of any size,
    meets both contacts: Gauss–Seidel drifts along them at a constant rate, and the secant of
    Anderson's combination ran off along that family, multiplying the impulses by 10⁴ (which
    the next steps' warm starts carried into the bed). The solve keeps them at the weight's
    scale, still meeting both contacts."""
    nc = 2
    cn = np.array([[1.0, 0.0, 0.0], [-0.950646, 0.0267682, 0.309122]])
    inv_m = np.array([17789.2])
    inv_i = np.array([1.52699e10])
    rad = np.array([0.00170659])
    v = np.array([[0.0, -2.96231e-4, 2.56470e-5]])
    w = np.array([[1.09535, -0.0150293, -0.173566]])
    pn = np.array([6.13539e-8, 7.00928e-8])
    pt = np.array([[0.0, -4.49065e-10, 1.71182e-8], [5.27954e-9, -1.04099e-9, 1.63264e-8]])
    hr = np.array([[0.0, 1.79299e-13, 2.06989e-12], [-3.68235e-13, -9.73647e-14, -1.12400e-12]])
    zeros = np.zeros((nc, 3))
    sweeps, worst, _ = solve(nc, np.zeros(nc, np.int64), np.full(nc, -1, np.int64), cn,
                             np.array([0.0, 0.00170659]), zeros, np.array([0.0, -2.77625e-9]),
                             np.full(nc, 0.624656), zeros.copy(), np.full(nc, 0.0198426),
                             np.array([0.00170659, 0.00085330]), zeros.copy(), inv_m, inv_i,
                             rad, v, w, pn, pt, hr, True, True, True, 1e-12, FRICTION_SWEEPS,
                             True)
    assert sweeps > ANDERSON_AFTER  # the acceleration had its turn
    assert worst <= 1e-12
    weight = G / inv_m[0] * 1e-4  # the sphere's weight over the step [N s]
    assert pn.max() < 10 * weight


def test_a_small_cluster_is_solved_as_before_the_acceleration():
    """A solve that converges within ANDERSON_AFTER sweeps never starts the acceleration: the
    results are those of plain Gauss–Seidel, bit for bit (a sphere sliding on a plate into a
    wall, with friction at both contacts)."""
    runs = []
    for memory in (0, ANDERSON_MEMORY):
        c = Cluster(1)
        c.v[0] = (-0.3, 0.1, 0.0)
        c.contact(0, -1, (0, 0, 1), mu=0.3)
        c.contact(0, -1, (1, 0, 0), target=0.18, mu=0.3)
        c.solve(memory=memory)
        runs.append(c)
    assert runs[0].sweeps < ANDERSON_AFTER
    assert runs[1].sweeps == runs[0].sweeps
    np.testing.assert_array_equal(runs[0].v, runs[1].v)
    np.testing.assert_array_equal(runs[0].w, runs[1].w)
    np.testing.assert_array_equal(runs[0].pt, runs[1].pt)


def test_spare_rows_of_the_body_arrays_change_nothing():
    """The engine hands the solver its scratch arrays, with a row for every body of the largest
    cluster it can hold: an accelerated solve (a column of 20, past ANDERSON_AFTER sweeps)
    gives the same impulses and velocities, bit for bit, with 50 spare rows after the
    contacts' bodies, and leaves the spare rows as they were."""
    n, spare = 20, 50
    tight, roomy = _column(n), _column(n)
    for name in ("inv_m", "inv_i", "rad"):
        setattr(roomy, name, np.concatenate([getattr(roomy, name), np.full(spare, 7.0)]))
    rng = np.random.default_rng(3)
    roomy.v = np.concatenate([roomy.v, rng.normal(size=(spare, 3))])
    roomy.w = np.concatenate([roomy.w, rng.normal(size=(spare, 3))])
    left_v, left_w = roomy.v[n:].copy(), roomy.w[n:].copy()
    assert tight.solve() <= SOLVE_TOL
    roomy.solve()
    assert tight.sweeps > ANDERSON_AFTER
    assert roomy.sweeps == tight.sweeps
    np.testing.assert_array_equal(roomy.pn, tight.pn)
    np.testing.assert_array_equal(roomy.pt, tight.pt)
    np.testing.assert_array_equal(roomy.v[:n], tight.v)
    np.testing.assert_array_equal(roomy.w[:n], tight.w)
    np.testing.assert_array_equal(roomy.v[n:], left_v)
    np.testing.assert_array_equal(roomy.w[n:], left_w)


def _refine(c, pn=None, tol=SOLVE_TOL):
    """Run refine_normals on Cluster ``c`` (normals only) from impulses ``pn`` (applied to
    ``c.v`` first) or none; returns (worst, pn)."""
    col = list(zip(*c.rows, strict=True))
    nc = len(c.rows)
    ca, cb, cn = np.array(col[0], np.int64), np.array(col[1], np.int64), np.array(col[2])
    pn = np.zeros(nc) if pn is None else np.asarray(pn, float).copy()
    for k in range(nc):  # the starting impulses in the velocities, as the solver keeps them
        c.v[ca[k]] += c.inv_m[ca[k]] * pn[k] * cn[k]
        if cb[k] >= 0:
            c.v[cb[k]] -= c.inv_m[cb[k]] * pn[k] * cn[k]
    worst = refine_normals(nc, ca, cb, cn, np.array(col[4]), np.array(col[5], float), c.inv_m,
                           c.v, pn, tol)
    return worst, pn


def _frictionless_column(n, h=1e-4):
    """n spheres stacked on a plate at the end of a step h without contacts (each at −g h),
    frictionless: the normal problem of a step."""
    c = Cluster(n)
    c.v[:, 2] = -G * h
    c.contact(0, -1, (0.0, 0.0, 1.0))
    for k in range(1, n):
        c.contact(k, k - 1, (0.0, 0.0, 1.0))
    return c


@pytest.mark.parametrize("n", [40, 80])
def test_a_slow_frictionless_step_is_finished_directly_after_its_sweeps(n):
    """A frictionless column of n spheres (a step's problem): the sweeps alone need more than
    DIRECT_AFTER (its weight reaches the plate one contact per sweep); the engine's solve
    (``polish_stall``) stops them there and finishes directly, with every contact met to the
    tolerance and contact k carrying the n − k spheres above it."""
    h = 1e-4
    swept, direct = _frictionless_column(n, h), _frictionless_column(n, h)
    assert swept.solve(rotation=False, friction=False) <= SOLVE_TOL
    assert swept.sweeps > DIRECT_AFTER
    worst = direct.solve(rotation=False, friction=False, friction_sweeps=FRICTION_SWEEPS,
                         polish_stall=True)
    assert worst <= SOLVE_TOL
    assert direct.sweeps == DIRECT_AFTER
    assert not direct.stalled
    assert not direct.frozen
    weight = M * G * h * np.arange(n, 0, -1)
    np.testing.assert_allclose(direct.pn, weight, rtol=1e-9)
    np.testing.assert_allclose(direct.v, 0.0, atol=n * SOLVE_TOL)


def test_a_frictionless_step_the_sweeps_meet_is_not_finished_directly():
    """Where the sweeps converge within DIRECT_AFTER (a short column), the engine's frictionless
    solve is the plain solve, bit for bit."""
    plain, step = _frictionless_column(5), _frictionless_column(5)
    plain.solve(rotation=False, friction=False, stall=True)
    step.solve(rotation=False, friction=False, friction_sweeps=FRICTION_SWEEPS,
               polish_stall=True)
    assert step.sweeps == plain.sweeps < DIRECT_AFTER
    np.testing.assert_array_equal(step.pn, plain.pn)
    np.testing.assert_array_equal(step.v, plain.v)


@pytest.mark.parametrize("n", [1, 5, 20])
def test_the_normal_refinement_gives_a_columns_weights_at_once(n):
    """A column of n spheres on a plate at the end of a step h without contacts (each at
    −g h): the finish (refine_normals) meets every contact (velocity 0) and gives
    contact k the impulse of the n − k spheres above it, from no impulse and from a wrong one."""
    h = 1e-4
    for start_pn in (None, np.full(n, 3.0 * M * G * h)):
        c = _frictionless_column(n, h)
        worst, pn = _refine(c, start_pn)
        assert worst <= SOLVE_TOL
        np.testing.assert_allclose(pn, M * G * h * np.arange(n, 0, -1), rtol=1e-9)
        np.testing.assert_allclose(c.v, 0.0, atol=SOLVE_TOL)


def test_the_normal_refinement_meets_a_jammed_row_that_has_many_solutions():
    """A row of four spheres jammed between two walls, the middle ones driven into them (its
    impulses are not unique: any compression of the whole row meets every contact): the
    finish meets every contact with impulses ≥ 0 and leaves no sphere approaching a wall or a
    neighbour."""
    c = Cluster(4)
    c.v[1, 0], c.v[2, 0] = 0.3, -0.2
    c.contact(0, -1, (1.0, 0.0, 0.0))  # the wall at left pushes +x on sphere 0
    for k in range(1, 4):
        c.contact(k, k - 1, (1.0, 0.0, 0.0))
    c.contact(3, -1, (-1.0, 0.0, 0.0))  # the wall at right
    worst, pn = _refine(c)
    assert worst <= SOLVE_TOL
    assert np.all(pn >= 0.0)
    np.testing.assert_allclose(c.v, 0.0, atol=SOLVE_TOL)  # nothing can move in a jammed row


def _column_problem(n, h=1e-4):
    """A column of n spheres on a plate at the end of a step h without contacts (each at
    −g h), as _mprgp takes it: (ca, cb, cn, inv_m, q) with q each contact's normal velocity
    without normal impulses less its target 0."""
    ca = np.arange(n, dtype=np.int64)
    cb = np.arange(-1, n - 1, dtype=np.int64)
    cn = np.tile([0.0, 0.0, 1.0], (n, 1))
    q = np.zeros(n)
    q[0] = -G * h  # the base approaches the plate; the others' relative velocity is 0
    return ca, cb, cn, np.full(n, 1.0 / M), q


@pytest.mark.parametrize("n", [5, 40, 80])
def test_projected_conjugate_gradients_give_a_columns_weights(n):
    """MPRGP (_mprgp) on a column of n spheres, whose Delassus matrix is a path's (condition
    number ∝ n², Gauss–Seidel's sweeps ∝ n²), from impulses too large everywhere (every contact
    on the free face): each contact gets the weight of the spheres above it over the step, to
    the tolerance's impulse, in at most 2n iterations (conjugate gradients: n on a fixed face;
    measured: n)."""
    h = 1e-4
    ca, cb, cn, inv_m, q = _column_problem(n, h)
    lam = np.full(n, 3.0 * n * M * G * h)
    it = _mprgp(n, ca, cb, cn, inv_m, q, lam, SOLVE_TOL)
    assert it <= 2 * n
    np.testing.assert_allclose(lam, M * G * h * np.arange(n, 0, -1), rtol=0,
                               atol=n * SOLVE_TOL * M)


@pytest.mark.parametrize("n", [5, 20])
def test_projected_conjugate_gradients_build_a_columns_weights_from_none(n):
    """The column from no impulse: its contacts above the base, met until the base pushes,
    join the free face one proportioning step at a time, so MPRGP takes about 4n iterations
    (measured 15 and 77), within its limit (MPRGP_PER_CONTACT n) for short columns; longer
    ones are finished by refine_normals' NNLS."""
    h = 1e-4
    ca, cb, cn, inv_m, q = _column_problem(n, h)
    lam = np.zeros(n)
    it = _mprgp(n, ca, cb, cn, inv_m, q, lam, SOLVE_TOL)
    assert it < MPRGP_PER_CONTACT * n
    np.testing.assert_allclose(lam, M * G * h * np.arange(n, 0, -1), rtol=0,
                               atol=n * SOLVE_TOL * M)


def test_projected_conjugate_gradients_release_a_contact_that_pulls():
    """A sphere leaving a plate upwards at 1 mm/s beside a column of two resting on the same
    plate, started from impulses on every contact: the leaving sphere's contact must end at
    no impulse (it would pull), the column's carry its weights."""
    h = 1e-4
    ca = np.array([0, 1, 2], np.int64)
    cb = np.array([-1, 0, -1], np.int64)
    cn = np.tile([0.0, 0.0, 1.0], (3, 1))
    q = np.array([-G * h, 0.0, 1e-3])
    lam = np.full(3, M * G * h)
    _mprgp(3, ca, cb, cn, np.full(3, 1.0 / M), q, lam, SOLVE_TOL)
    np.testing.assert_allclose(lam, [2 * M * G * h, M * G * h, 0.0], rtol=0, atol=SOLVE_TOL * M)


def _least_distance(ca, cb, cn, cvb, target, inv_m, v0):
    """The test's oracle for a normal problem: the velocities [m/s] nearest to ``v0`` (the
    bodies' velocities without normal impulses) in the metric of the masses that meet every
    contact, J v ≥ target + the partner's velocity, by scipy's NNLS on the problem's
    least-distance form (Lawson & Hanson 1974, ch. 23), written here from the book with dense
    matrices, apart from the engine's implementation."""
    nc, nb = len(ca), len(inv_m)
    jac = np.zeros((nc, 3 * nb))
    for k in range(nc):
        jac[k, 3 * ca[k]:3 * ca[k] + 3] = cn[k]
        if cb[k] >= 0:
            jac[k, 3 * cb[k]:3 * cb[k] + 3] = -cn[k]
    root = np.sqrt(np.repeat(inv_m, 3))
    wall = np.array([cvb[k] @ cn[k] if cb[k] < 0 else 0.0 for k in range(nc)])
    g = jac * root  # y = √M (v − v0): the contacts ask g y ≥ b
    b = target + wall - jac @ v0.reshape(-1)
    scale = np.abs(b).max()
    e = np.vstack([g.T, b[None, :] / scale])
    f = np.zeros(e.shape[0])
    f[-1] = 1.0
    u, _ = scipy.optimize.nnls(e, f, maxiter=50 * nc)
    res = e @ u - f
    y = -res[:-1] / res[-1] * scale
    return v0 + (root * y).reshape(nb, 3), jac @ (v0.reshape(-1) + root * y) - wall - target


def _with_normals(ca, cb, cn, inv_m, v, pn, sign):
    """The bodies' velocities ``v`` (a copy) with ``sign`` times what the normal impulses ``pn``
    give them (hsgran.contact.cluster._push_normals)."""
    out = v.copy()
    _push_normals(len(ca), ca, cb, cn, inv_m, pn, out, sign)
    return out


def _normal_velocities(ca, cb, cn, cvb, v):
    """Each contact's relative normal velocity [m/s] at the bodies' velocities ``v``."""
    return np.array([(v[ca[k]] - (v[cb[k]] if cb[k] >= 0 else cvb[k])) @ cn[k]
                     for k in range(len(ca))])


def test_the_finish_meets_a_stalled_wedge_step_as_least_distance_does():
    """A stalled step of corpus 0-79 (109 spheres in a 62° wedge, its normal problem at t =
    0.114 s: 307 contacts, 15 of them redundant, tests/contact/data/stalled_wedge_step.npz):
    projected conjugate gradients leave it ~1e-8 m/s short, and the active-set rounds that
    the NNLS replaced came no closer (each dropped its negative impulses without stepping
    back). The finish meets every contact to the tolerance, with impulses ≥ 0 that carry only
    at contacts on their targets, and the velocities are the oracle's (scipy's NNLS)."""
    data = np.load(Path(__file__).parent / "data" / "stalled_wedge_step.npz")
    ca, cb, cn, cvb = data["ca"], data["cb"], data["cn"], data["cvb"]
    target, inv_m, tol = data["target"], data["inv_m"], float(data["tol"])
    v, pn = data["v"].copy(), data["pn"].copy()
    nc = len(ca)
    expected, slack = _least_distance(ca, cb, cn, cvb, target, inv_m,
                                      _with_normals(ca, cb, cn, inv_m, v, pn, -1.0))
    assert slack.min() > -1e-15  # the oracle meets it: the problem has a solution
    worst, steps = refined(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol)
    assert 0 < steps < NNLS_STEPS_PER_CONTACT * nc
    assert worst <= tol
    assert np.all(pn >= 0.0)
    # the shortfall reported is the one the velocities it left give, to their rounding (the
    # bodies move at up to 0.05 m/s: 1e-17 m/s an operation, a few of them per contact)
    no_spin = np.zeros_like(v)
    assert _worst(nc, ca, cb, cn, np.zeros(nc), cvb, target, np.zeros(len(v)), v, no_spin,
                  False) == pytest.approx(worst, rel=1e-9, abs=1e-16)
    np.testing.assert_allclose(v, expected, rtol=0, atol=tol)


def _random_bed(seed, h=1e-4):
    """A normal problem drawn at random from a class the corpus meets (seeded): spheres of an FCC
    packing (lattice constant 2√2 R, every neighbour touching) that lie in a V of two planes
    at a random opening and tilt, with a random number of sites left empty; every touching
    pair and every sphere within 0.05 R of a plane a contact, the normals jittered by about
    1e-3 rad (a real bed is never a perfect lattice); 15 to 200 spheres from the base up, in
    beds 1 to 4 cells wide and up to 15 high; velocities −g h plus random ones of up to 1
    nm/s to 1 mm/s (from a bed pressed by its weight alone, where many contacts are on the
    edge of carrying, to a stirred one); targets mostly 0 (touching), some −gap/h (closing),
    some small openings (+1e-8 m/s, an overlap taken back) and some rebounds (up to +2
    mm/s). Returns (ca, cb, cn, cvb, target, inv_m, v)."""
    rng = np.random.default_rng(seed)
    half = math.radians(rng.uniform(25.0, 70.0))  # half the V's opening
    tilt = rng.uniform(-0.3, 0.3)
    planes = [np.array([math.cos(half), 0.0, math.sin(half)]),
              np.array([-math.cos(half), 0.0, math.sin(half)])]
    for p in planes:
        p[0], p[2] = (p[0] * math.cos(tilt) - p[2] * math.sin(tilt),
                      p[0] * math.sin(tilt) + p[2] * math.cos(tilt))
    a = 2.0 * math.sqrt(2.0) * R
    basis = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]]) * a
    wide, deep, tall = rng.integers(1, 5), rng.integers(1, 3), rng.integers(3, 16)
    sites = np.array([np.array([i, j, k]) * a + s for i in range(-wide, wide + 1)
                      for j in range(deep) for k in range(tall) for s in basis])
    sites = sites + rng.uniform(-0.5, 0.5, 3) * a
    inside = np.all(sites @ np.array(planes).T >= R * (1 - 1e-12), axis=1)
    sites = sites[inside]
    keep = rng.random(len(sites)) > rng.uniform(0.0, 0.3)
    sites = sites[keep]
    sites = sites[np.argsort(sites[:, 2])][:rng.integers(15, 200)]  # a bed, from its base up
    nb = len(sites)
    rows = []
    for i in range(nb):
        for j in range(i):
            d = sites[i] - sites[j]
            if abs(np.linalg.norm(d) - 2 * R) < 1e-9 * R:
                rows.append((i, j, d / np.linalg.norm(d)))
        for p in planes:
            if sites[i] @ p - R < 0.05 * R:
                rows.append((i, -1, p.copy()))
    ca = np.array([r[0] for r in rows], np.int64)
    cb = np.array([r[1] for r in rows], np.int64)
    cn = np.array([r[2] for r in rows]) + rng.normal(0.0, 1e-3, (len(rows), 3))
    cn /= np.linalg.norm(cn, axis=1)[:, None]
    kind = rng.random(len(rows))
    target = np.where(kind < 0.7, 0.0, np.where(kind < 0.85, -rng.uniform(0, 1e-3, len(rows)),
                      np.where(kind < 0.95, 1e-8, rng.uniform(0, 2e-3, len(rows)))))
    v = rng.uniform(-1.0, 1.0, (nb, 3)) * 10.0 ** rng.uniform(-9.0, -3.0)
    v[:, 2] -= G * h
    return ca, cb, cn, np.zeros((len(rows), 3)), target, np.full(nb, 1.0 / M), v


#: Random beds of _random_bed the NNLS finish is checked on (cold and warm) [-].
RANDOM_BEDS = 30


def test_the_nnls_finish_meets_random_wedge_beds_as_least_distance_does():
    """Normal problems of random FCC beds in V wedges (:func:`_random_bed`, RANDOM_BEDS seeds;
    20 to 670 contacts, many of them redundant): wherever the oracle (scipy's NNLS) finds the
    velocities that meet every contact, the NNLS finish does too, to its tolerance, from no
    impulse and from wrong ones on half the contacts, and gives the oracle's
    velocities; every seed counts (the rate asked is 100 %). (Conjugate gradients alone meet
    these beds too, unlike the stalled wedge step above: the test is of the NNLS's answers.)"""
    tol = 1e-12
    sizes = []
    for seed in range(RANDOM_BEDS):
        ca, cb, cn, cvb, target, inv_m, v0 = _random_bed(seed)
        nc = len(ca)
        sizes.append(nc)
        expected, slack = _least_distance(ca, cb, cn, cvb, target, inv_m, v0)
        assert slack.min() > -1e-15, seed  # (the class always has a solution)
        q = _normal_velocities(ca, cb, cn, cvb, v0) - target
        for warm in (False, True):
            lam = np.zeros(nc)
            if warm:  # a wrong start: impulses up to 3 weights over the step on half of them
                rng = np.random.default_rng(seed)
                lam = np.where(rng.random(nc) < 0.5, rng.uniform(0.0, 3.0 * M * G * 1e-4, nc), 0.0)
            steps = _nnls(nc, ca, cb, cn, inv_m, q, lam, tol)
            assert 0 <= steps < NNLS_STEPS_PER_CONTACT * nc, (seed, warm)
            assert np.all(lam >= 0.0)
            v = _with_normals(ca, cb, cn, inv_m, v0, lam, 1.0)
            u = _normal_velocities(ca, cb, cn, cvb, v)
            assert (u - target).min() >= -tol, (seed, warm)
            assert np.abs((u - target)[lam > 0]).max(initial=0.0) <= tol, (seed, warm)
            np.testing.assert_allclose(v, expected, rtol=0, atol=tol, err_msg=str((seed, warm)))
    assert min(sizes) < 60  # the class spans small and large beds
    assert max(sizes) > 300
