"""The time-resolved single-contact reference (hsgran.dem.single) against closed forms and the
impulse model where MODEL.md claims they are the same physics."""

import itertools
import math

import pytest

from hsgran.contact.normal import hertz_contact_time
from hsgran.dem.single import dashpot_coefficient, resolved_wall_impact
from hsgran.effects import Effects
from hsgran.impact import oblique_velocity, sphere_wall_impact
from hsgran.materials import BUILTIN_MATERIALS, Contact, Material, pair_row

STEEL = BUILTIN_MATERIALS["steel"]
RADIUS = 5e-3  # the MODEL §7.1 regression sphere
FRICTION = Effects.parse(["rotation", "friction"])
STAGED = Effects.parse(["rotation", "friction", "plasticity"])
PLASTIC = Effects.parse(["plasticity"])

#: Velocity Verlet is second order: halving dt must cut the error by at least 2^ORDER_MIN
#: (2 would be the asymptotic factor 4; 1.7 leaves room for the pre-asymptotic range and the
#: sampled switch from loading to unloading at the peak).
ORDER_MIN = 1.7
#: At t_c/1000 the elastic-stage error is ~1e-10 (test below); 1e-6 leaves four decades.
FINE_TOL = 1e-6
#: The plastic stages' error at t_c/1000 is ~2e-7 (sampled peak); 2e-6 is ten times that.
FINE_PLASTIC_TOL = 2e-6


def elastic(speed, steps, **kw):
    return resolved_wall_impact(STEEL, STEEL, RADIUS, speed, contact=Contact(),
                                effects=Effects(), steps_per_contact=steps, **kw)


def test_elastic_hertz_gives_e_1_with_error_falling_at_second_order():
    errors = [abs(elastic(1.0, n).e_n - 1.0) for n in (20, 40, 80)]
    for coarse, fine in itertools.pairwise(errors):
        assert fine < coarse / 2**ORDER_MIN
    assert abs(elastic(1.0, 1000).e_n - 1.0) < FINE_TOL


def test_elastic_hertz_contact_time_and_peak_match_closed_forms():
    r = elastic(0.5, 1000)
    row = pair_row(STEEL, STEEL, Contact())
    mass = STEEL.density * 4 / 3 * math.pi * RADIUS**3
    t_c = hertz_contact_time(0.5, mass, RADIUS, row[0])
    # the force ends between two steps: the duration is known to one step
    assert abs(r.contact_time - t_c) <= 1.5 * r.dt
    imp = sphere_wall_impact(STEEL, STEEL, RADIUS, oblique_velocity(0.5, 0.0), contact=Contact(),
                             effects=Effects.parse(["plasticity"]))
    # the 0.5 m/s impact is elastic-plastic: compare with a Hertz peak instead
    hertz = sphere_wall_impact(STEEL, STEEL, RADIUS, oblique_velocity(0.5, 0.0),
                               contact=Contact(), effects=Effects())
    assert imp.stage == "elastic-plastic"
    assert r.delta_max == pytest.approx(hertz.delta_max, rel=FINE_TOL)


@pytest.mark.parametrize("speed", [0.1, 0.5, 5.0, 50.0])
def test_staged_restitution_converges_to_the_impulse_model(speed):
    imp = sphere_wall_impact(STEEL, STEEL, RADIUS, oblique_velocity(speed, 0.0),
                             contact=Contact(), effects=PLASTIC)
    errs = []
    for n in (50, 100, 200):
        r = resolved_wall_impact(STEEL, STEEL, RADIUS, speed, contact=Contact(),
                                 effects=PLASTIC, steps_per_contact=n)
        errs.append(abs(r.e_n - imp.e_n))
    assert errs[-1] < errs[0] or errs[-1] < FINE_TOL
    fine = resolved_wall_impact(STEEL, STEEL, RADIUS, speed, contact=Contact(),
                                effects=PLASTIC, steps_per_contact=1000)
    assert fine.e_n == pytest.approx(imp.e_n, abs=FINE_PLASTIC_TOL)
    assert fine.delta_max == pytest.approx(imp.delta_max, rel=1e-5)
    assert fine.residual_deformation == pytest.approx(imp.residual_deformation,
                                                      rel=1e-4, abs=1e-12)


def test_energy_bookkeeping_matches_the_impulse_model_with_friction():
    """Kinetic energy lost (normal plastic work + friction) equals the impulse model's."""
    contact = Contact(sliding_friction=0.3)
    for angle in (20.0, 60.0):  # rolling and sliding regimes
        imp = sphere_wall_impact(STEEL, STEEL, RADIUS, oblique_velocity(2.0, angle),
                                 contact=contact, effects=STAGED)
        r = resolved_wall_impact(STEEL, STEEL, RADIUS, 2.0, angle, contact=contact,
                                 effects=STAGED, steps_per_contact=1000)
        assert r.energy_lost > 0.0
        assert r.energy_lost == pytest.approx(imp.energy_lost, rel=1e-5)


def test_coulomb_friction_sticking_and_sliding_limits():
    """Rolling regime: slip ends at zero and ω′ = 5/7 v_t/R; sliding: J_t = μ J_n."""
    contact = Contact(sliding_friction=0.3)
    v = 1.0
    stick = resolved_wall_impact(STEEL, STEEL, RADIUS, v, 10.0, contact=contact,
                                 effects=FRICTION, steps_per_contact=500)
    vt0 = v * math.sin(math.radians(10.0))
    assert stick.velocity_after[0] - RADIUS * stick.spin_after == pytest.approx(0.0, abs=1e-9)
    assert stick.spin_after == pytest.approx(5.0 / 7.0 * vt0 / RADIUS, rel=1e-9)
    slide = resolved_wall_impact(STEEL, STEEL, RADIUS, v, 70.0, contact=contact,
                                 effects=FRICTION, steps_per_contact=500)
    vn0 = v * math.cos(math.radians(70.0))
    vt0 = v * math.sin(math.radians(70.0))
    # tangential impulse per unit mass = μ (1 + e_n) v_n0 (elastic: e_n ≈ 1)
    dvt = vt0 - slide.velocity_after[0]
    assert dvt == pytest.approx(0.3 * (1.0 + slide.e_n) * vn0, rel=1e-9)
    assert slide.velocity_after[0] - RADIUS * slide.spin_after > 0.0


def test_adhesive_capture_speed_matches_the_impulse_model():
    """MODEL §7.1: ammonium fluorescein on silicon is captured below 1.157 m/s."""
    af, si = BUILTIN_MATERIALS["ammonium_fluorescein"], BUILTIN_MATERIALS["silicon"]
    eff = Effects.parse(["plasticity", "adhesion"])
    contact = Contact(work_of_adhesion=0.2)
    r_micro = 2.45e-6
    low = resolved_wall_impact(af, si, r_micro, 1.0, contact=contact, effects=eff,
                               steps_per_contact=400)
    high = resolved_wall_impact(af, si, r_micro, 2.0, contact=contact, effects=eff,
                                steps_per_contact=400)
    imp = sphere_wall_impact(af, si, r_micro, oblique_velocity(2.0, 0.0), contact=contact,
                             effects=eff)
    assert low.captured
    assert low.e_n == 0.0
    assert not high.captured
    assert high.e_n == pytest.approx(imp.e_n, abs=1e-3)


def test_dashpot_gives_the_prescribed_restitution_at_every_speed():
    for e in (0.5, 0.9):
        coef = dashpot_coefficient(e)
        assert coef > 0.0
        for v in (0.01, 1.0, 20.0):
            r = resolved_wall_impact(STEEL, STEEL, RADIUS, v, contact=Contact(restitution=e),
                                     effects=Effects(), steps_per_contact=1000)
            assert r.e_n == pytest.approx(e, abs=1e-4)


def test_mindlin_spring_recoils_at_small_angles():
    """A tangential spring returns stored energy: e_t above the rigid model's 5/7 (§4.4)."""
    alumina = BUILTIN_MATERIALS["alumina"]
    rigid = BUILTIN_MATERIALS["rigid"]
    contact = Contact(sliding_friction=0.092)
    r = resolved_wall_impact(alumina, rigid, 2.5e-3, 3.9, 5.0, contact=contact,
                             effects=FRICTION, steps_per_contact=200, tangential="mindlin")
    assert r.e_t > 5.0 / 7.0 + 0.05
    c = resolved_wall_impact(alumina, rigid, 2.5e-3, 3.9, 5.0, contact=contact,
                             effects=FRICTION, steps_per_contact=200)
    assert c.e_t == pytest.approx(5.0 / 7.0, rel=1e-6)


def test_rejects_rigid_sphere_and_unknown_tangential_model():
    from hsgran.errors import InputError

    with pytest.raises(InputError):
        resolved_wall_impact(BUILTIN_MATERIALS["rigid"], STEEL, 1e-3, 1.0)
    with pytest.raises(InputError):
        resolved_wall_impact(STEEL, STEEL, 1e-3, 1.0, tangential="spring")
    soft = Material("soft", 1000.0, 1e6, 0.3)
    assert resolved_wall_impact(soft, STEEL, 1e-3, 1.0, effects=Effects()).e_n > 0.99
