"""The dimensionless Hertz–Mindlin impact (hsgran.dem.mindlin) is the physical one rescaled:
it gives hsgran.dem.single's outcome (Mindlin spring, the same Verlet scheme) for any size,
speed, material and restitution, so one table in (κ, e_n, q) serves every pair."""

from __future__ import annotations

import math

import pytest

from hsgran.dem.mindlin import MASS_RATIO_SOLID, oblique
from hsgran.dem.single import dashpot_coefficient, resolved_wall_impact
from hsgran.effects import Effects
from hsgran.materials import (
    BUILTIN_MATERIALS,
    P_E_STAR,
    Contact,
    effective_shear_modulus,
    pair_row,
)

B = BUILTIN_MATERIALS
FRICTION = Effects.parse(["rotation", "friction"])
#: Both integrations at 8000 steps per elastic contact time: they agree to the step's error.
STEPS = 8000.0
AGREE = 2e-4


@pytest.mark.parametrize(("sphere", "wall", "radius", "speed", "angle", "e", "mu"), [
    ("steel", "rigid", 1e-3, 1.0, 10.0, None, 0.3),
    ("glass", "steel", 4e-3, 0.2, 25.0, 0.6, 0.15),
    ("alumina", "glass", 2.5e-3, 3.9, 5.0, 0.98, 0.092),
    ("aluminium_alloy", "rigid", 0.1, 0.05, 40.0, 0.3, 0.5),
])
def test_scaling(sphere, wall, radius, speed, angle, e, mu):
    c = Contact(sliding_friction=mu, restitution=e)
    row = pair_row(B[sphere], B[wall], c)
    kappa = effective_shear_modulus(B[sphere], B[wall]) / row[P_E_STAR]
    ref = resolved_wall_impact(B[sphere], B[wall], radius, speed, angle, contact=c,
                               effects=FRICTION, steps_per_contact=STEPS, tangential="mindlin")
    vn, vt = speed * math.cos(math.radians(angle)), speed * math.sin(math.radians(angle))
    q = (2.0 / 7.0) * vt / (mu * (1.0 + ref.e_n) * vn)
    phi, e_n = oblique(q, kappa, dashpot_coefficient(e) if e else 0.0, MASS_RATIO_SOLID,
                       STEPS / 2.9432)
    assert e_n == pytest.approx(ref.e_n, abs=1e-6)
    e_t = 1.0 - phi * mu * (1.0 + e_n) * vn / vt  # J_t = φ μ J_n on the centre, MODEL §4.1
    assert e_t == pytest.approx(ref.e_t, abs=AGREE)
