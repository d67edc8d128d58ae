"""Materials, contact pairs and the per-pair constants of the collision model (layer 1).

A :class:`Material` holds bulk properties; a :class:`Contact` holds what belongs to a pair of
surfaces (friction, adhesion, an optional prescribed restitution, the model constants of
MODEL §8). :func:`pair_row` turns a pair into one flat ``float64`` row that the compiled
collision kernels read through the ``P_*`` indices below.

The critical values of MODEL §3.2–3.4 (δ_y, F_y, W_y, δ_p, W_p) scale with powers of the
effective radius R* alone (δ ∝ R*, F ∝ R*², W ∝ R*³), so the row stores them per unit R*: they
are computed once per pair of materials, and a collision of spheres of any size costs one
multiplication per value. :func:`critical_values` gives them in SI units for given sizes.

Layer 1: imports only ``errors``.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from hsgran.errors import InputError, check_number, did_you_mean

# ---- model constants (MODEL §8) -------------------------------------------------------

#: First-yield factor c = p0/σ_y for ν ≈ 0.3 (von Mises; Johnson 1985) [-]. MODEL §3.2, [LIT].
YIELD_FACTOR_DEFAULT = 1.6
#: Hardness factor κ = p_p/σ_y (Tabor-type hardness) [-]. MODEL §3.3, [LIT/OURS].
HARDNESS_FACTOR_DEFAULT = 2.8
#: ρ_p = δ_p/δ_y, onset of fully plastic contact (Kogut & Etsion 2002) [-]. MODEL §3.3.
PLASTIC_RATIO_DEFAULT = 110.0
#: Coefficient of the JKR-matched line-force estimate f0 = C (E* R* Δγ²)^(1/3) [-], with
#: C = (3/4)(8/(9π))^(1/3). MODEL §3.8, [OURS, low confidence].
JKR_LINE_FORCE_COEF = 0.75 * (8.0 / (9.0 * math.pi)) ** (1.0 / 3.0)

#: Moment of inertia factor of a solid sphere, I = k m R² (MODEL §8, [LIT]).
SOLID_SPHERE_INERTIA = 0.4


def solid_sphere_mass(density, radius):
    """Mass ρ 4/3 π R³ [kg] of solid spheres; density [kg/m³] and radius [m], scalars or arrays."""
    return density * (4.0 / 3.0 * math.pi) * radius**3


# ---- layout of a pair row (read by the compiled kernels) ---------------------------------
P_E_STAR = 0  #: effective modulus E* [Pa]
P_SIGMA_Y = 1  #: governing yield stress σ_y = min(σ1, σ2) [Pa]
P_DY_R = 2  #: δ_y / R* [-]
P_FY_R2 = 3  #: F_y / R*² [Pa]
P_WY_R3 = 4  #: W_y / R*³ [Pa]
P_WP_R3 = 5  #: W_p / R*³ [Pa]
P_RHO_P = 6  #: ρ_p = δ_p/δ_y [-]
P_A = 7  #: (λ − 1)/ln ρ_p, slope of the log pressure law [-]
P_P_P = 8  #: fully plastic mean pressure p_p = κ σ_y [Pa]
P_MU_S = 9  #: sliding friction μ_s [-]
P_MU_R = 10  #: rolling friction μ_r [-]
P_E_FIXED = 11  #: prescribed normal restitution, or -1 when the staged/elastic law applies [-]
P_F0 = 12  #: adhesion line force given directly [N/m] (0 if none)
P_F0_COEF = 13  #: f0 / R*^(1/3) from a work of adhesion [N/m^(4/3)] (0 if none)
P_G_RATIO = 14  #: κ = G*/E*, Mindlin's shear over Hertz's modulus (docs/model.md §4.5) [-]
P_VISC = 15  #: dissipative constant A of the pair (docs/model.md §3.11) [s]
PAIR_ROW_SIZE = 16

#: Marker stored in P_E_FIXED when no restitution is prescribed.
NO_FIXED_RESTITUTION = -1.0


@dataclass(frozen=True, slots=True)
class Material:
    """Bulk properties of a solid.

    Attributes:
        name: Identifier used in scenes and on the command line.
        density: Mass density ρ [kg/m³]; ``inf`` only for the built-in rigid wall.
        youngs_modulus: Young's modulus E [Pa]; ``inf`` means rigid (drops out of E*).
        poisson_ratio: Poisson ratio ν [-], in [-1, 0.5).
        yield_stress: Uniaxial yield stress σ_y [Pa]; ``inf`` means the body never yields.
        surface_energy: Surface free energy γ [J/m²]; 0 means no adhesion.
        dissipative_constant: Brilliantov et al.'s (1996) dissipative constant A [s], the
            viscous relaxation time of the bulk (docs/model.md §3.11); 0 means elastic. Used
            only by the ``viscoelastic_damping`` effect.
        source: Where the numbers come from.
    """

    name: str
    density: float
    youngs_modulus: float
    poisson_ratio: float
    yield_stress: float = math.inf
    surface_energy: float = 0.0
    source: str = ""
    dissipative_constant: float = 0.0

    @property
    def rigid(self) -> bool:
        """True when the material does not deform (E = ∞)."""
        return math.isinf(self.youngs_modulus)

    def shear_modulus(self) -> float:
        """G = E/(2(1 + ν)) [Pa] (∞ for a rigid body)."""
        if self.rigid:
            return math.inf
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    def compliance(self) -> float:
        """(1 − ν²)/E [1/Pa], this body's share of 1/E* (0 for a rigid body). MODEL §2."""
        return 0.0 if self.rigid else (1.0 - self.poisson_ratio**2) / self.youngs_modulus


@dataclass(frozen=True, slots=True)
class Contact:
    """Properties of a pair of surfaces (MODEL §2–§5, §8).

    Attributes:
        sliding_friction: Coulomb coefficient μ_s [-]; ``None`` = not given.
        rolling_friction: Dimensionless rolling friction μ_r [-] (torque μ_r R* F_n).
        restitution: Prescribed normal restitution e_n in [0, 1] that bypasses the normal
            model (MODEL §3.9), or ``None``.
        adhesion_line_force: Dunn's line force f0 [N/m], or ``None``.
        work_of_adhesion: Dupré work of adhesion Δγ [J/m²]; ``None`` = 2 (γ1 γ2)^(1/2).
        yield_factor: c = p0/σ_y at first yield [-], or ``"jackson-green"`` for
            1.295 exp(0.736 ν) with ν of the yielding body.
        hardness_factor: κ = p_p/σ_y [-] ([OURS] default 2.8).
        plastic_ratio: ρ_p = δ_p/δ_y [-] ([OURS] default 110).
    """

    sliding_friction: float | None = None
    rolling_friction: float = 0.0
    restitution: float | None = None
    adhesion_line_force: float | None = None
    work_of_adhesion: float | None = None
    yield_factor: float | str = YIELD_FACTOR_DEFAULT
    hardness_factor: float = HARDNESS_FACTOR_DEFAULT
    plastic_ratio: float = PLASTIC_RATIO_DEFAULT


def _src(text: str) -> str:
    return text


#: Built-in materials. Each entry says where its numbers come from; "handbook" values are
#: typical room-temperature figures, not measurements of a particular specimen.
BUILTIN_MATERIALS: dict[str, Material] = {
    m.name: m
    for m in (
        Material("steel", 7800.0, 200e9, 0.30, 1.0e9, 0.0,
                 _src("MODEL §7.1 regression sphere (hardened steel; E, ν, ρ handbook)")),
        Material("glass", 2500.0, 70e9, 0.25, 3.0e9, 0.0,
                 _src("soda-lime glass anvil of Kharaz et al. 2001 (E, ν); ρ handbook; "
                      "σ_y = 3 GPa as in the project's example scene (brittle: nominal)")),
        Material("alumina", 4000.0, 380e9, 0.23, math.inf, 0.0,
                 _src("Al2O3 spheres of Kharaz et al. 2001 / Chung & Ooi 2011 test 4; "
                      "no yield stress in the sources: treated as elastic")),
        Material("aluminium_alloy", 2700.0, 70e9, 0.33, 276e6, 0.0,
                 _src("Chung & Ooi 2011 tests 4 and 6 (E, ν, ρ); σ_y handbook 6061-T6")),
        Material("magnesium_alloy", 1800.0, 40e9, 0.35, math.inf, 0.0,
                 _src("Chung & Ooi 2011 test 2 (E, ν, ρ); no yield stress given")),
        Material("cast_iron", 7000.0, 100e9, 0.25, math.inf, 0.0,
                 _src("Chung & Ooi 2011 test 3 (E, ν, ρ); no yield stress given")),
        Material("limestone", 2500.0, 20e9, 0.25, math.inf, 0.0,
                 _src("Chung & Ooi 2011 test 1 (E, ν, ρ)")),
        Material("ammonium_fluorescein", 1350.0, 1.2e9, 0.30, 35.3e6 / 1.6, 0.1,
                 _src("Wall et al. 1990 microspheres as modelled by Pasha et al. 2014 "
                      "(ρ, E, ν; σ_y = p_y/1.6 with p_y = 35.3 MPa, MODEL §7.1); "
                      "γ = 0.1 J/m² so that 2(γ1γ2)^(1/2) = Γ = 0.2 J/m² against silicon")),
        Material("silicon", 2329.0, 182e9, 0.30, math.inf, 0.1,
                 _src("Pasha et al. 2014 (E, ν); ρ handbook; γ as for ammonium_fluorescein")),
        Material("rigid", math.inf, math.inf, 0.0, math.inf, 0.0,
                 _src("ideal rigid wall: drops out of E* (MODEL §2)")),
    )
}

#: Built-in contact properties of material pairs (unordered), with sources.
BUILTIN_CONTACTS: dict[frozenset, tuple[Contact, str]] = {
    frozenset(("alumina", "glass")): (
        Contact(sliding_friction=0.092),
        "Kharaz et al. 2001 / Chung & Ooi 2011 test 4: μ = 0.092",
    ),
    frozenset(("ammonium_fluorescein", "silicon")): (
        Contact(work_of_adhesion=0.2),
        "Pasha et al. 2014: interface energy Γ = 0.2 J/m²",
    ),
}


def pair_key(a: str, b: str) -> frozenset:
    """Unordered key of a material pair."""
    return frozenset((a, b))


# ---- validation helpers ------------------------------------------------------------------

def check_material(m: Material, key: str) -> Material:
    """Check that a material's numbers are physical; return it unchanged.

    Raises:
        InputError: naming the offending key (``materials.steel.poisson_ratio``).
    """
    rigid_ok = m.name == "rigid"
    rho = check_number(m.density, f"{key}.density", allow_inf=rigid_ok)
    if rho <= 0:
        raise InputError(f"must be > 0 kg/m^3, got {m.density!r}", f"{key}.density")
    e = check_number(m.youngs_modulus, f"{key}.youngs_modulus", allow_inf=rigid_ok)
    if e <= 0:
        raise InputError(f"must be > 0 Pa, got {m.youngs_modulus!r}", f"{key}.youngs_modulus")
    nu = check_number(m.poisson_ratio, f"{key}.poisson_ratio")
    if not -1.0 < nu < 0.5:
        raise InputError(f"must be in (-1, 0.5), got {m.poisson_ratio!r}", f"{key}.poisson_ratio")
    sy = check_number(m.yield_stress, f"{key}.yield_stress", allow_inf=True)
    if sy <= 0:
        raise InputError(f"must be > 0 Pa (inf: never yields), got {m.yield_stress!r}",
                         f"{key}.yield_stress")
    g = check_number(m.surface_energy, f"{key}.surface_energy")
    if g < 0:
        raise InputError(f"must be >= 0 J/m^2, got {m.surface_energy!r}", f"{key}.surface_energy")
    a = check_number(m.dissipative_constant, f"{key}.dissipative_constant")
    if a < 0:
        raise InputError(f"must be >= 0 s, got {m.dissipative_constant!r}",
                         f"{key}.dissipative_constant")
    return m


def check_contact(c: Contact, key: str) -> Contact:
    """Check that a contact's numbers are physical; return it unchanged.

    Raises:
        InputError: naming the offending key.
    """
    if c.sliding_friction is not None:
        if check_number(c.sliding_friction, f"{key}.sliding_friction") < 0:
            raise InputError(f"must be >= 0, got {c.sliding_friction!r}",
                             f"{key}.sliding_friction")
    if check_number(c.rolling_friction, f"{key}.rolling_friction") < 0:
        raise InputError(f"must be >= 0, got {c.rolling_friction!r}", f"{key}.rolling_friction")
    if c.restitution is not None:
        e = check_number(c.restitution, f"{key}.restitution")
        if not 0.0 <= e <= 1.0:
            raise InputError(f"must be in [0, 1], got {c.restitution!r}", f"{key}.restitution")
    for name in ("adhesion_line_force", "work_of_adhesion"):
        v = getattr(c, name)
        if v is not None and check_number(v, f"{key}.{name}") < 0:
            raise InputError(f"must be >= 0, got {v!r}", f"{key}.{name}")
    if c.adhesion_line_force is not None and c.work_of_adhesion is not None:
        raise InputError("give adhesion_line_force or work_of_adhesion, not both", key)
    if isinstance(c.yield_factor, str):
        if c.yield_factor != "jackson-green":
            raise InputError(f"must be a number or 'jackson-green', got {c.yield_factor!r}",
                             f"{key}.yield_factor")
    elif check_number(c.yield_factor, f"{key}.yield_factor") <= 0:
        raise InputError(f"must be > 0, got {c.yield_factor!r}", f"{key}.yield_factor")
    if check_number(c.hardness_factor, f"{key}.hardness_factor") <= 0:
        raise InputError(f"must be > 0, got {c.hardness_factor!r}", f"{key}.hardness_factor")
    if check_number(c.plastic_ratio, f"{key}.plastic_ratio") <= 1:
        raise InputError(f"must be > 1, got {c.plastic_ratio!r}", f"{key}.plastic_ratio")
    yf = 1.6 if isinstance(c.yield_factor, str) else float(c.yield_factor)
    if c.hardness_factor <= 2.0 * yf / 3.0:
        raise InputError(
            f"hardness_factor {c.hardness_factor} must exceed (2/3) yield_factor = {2 * yf / 3:.3g}"
            " (the mean pressure may only rise after first yield, MODEL §3.3)",
            f"{key}.hardness_factor",
        )
    return c


# ---- the pair row ------------------------------------------------------------------------

def yield_factor_of(contact: Contact, yielding: Material) -> float:
    """First-yield factor c for a pair (MODEL §3.2).

    Args:
        contact: Pair properties (``yield_factor`` a number or ``"jackson-green"``).
        yielding: The body that yields first (the one with the lower σ_y).

    Returns:
        c [-]; Jackson–Green gives 1.295 exp(0.736 ν) (≈ 1.61 at ν = 0.3).
    """
    if contact.yield_factor == "jackson-green":
        return 1.295 * math.exp(0.736 * yielding.poisson_ratio)
    return float(contact.yield_factor)


def effective_modulus(m1: Material, m2: Material) -> float:
    """E* with 1/E* = (1 − ν1²)/E1 + (1 − ν2²)/E2 [Pa] (MODEL §2).

    Raises:
        InputError: when both bodies are rigid (a contact needs one compliant body).
    """
    s = m1.compliance() + m2.compliance()
    if s <= 0.0:
        raise InputError(f"materials '{m1.name}' and '{m2.name}' are both rigid: no contact law")
    return 1.0 / s


def effective_shear_modulus(m1: Material, m2: Material) -> float:
    """G* with 1/G* = (2 − ν1)/G1 + (2 − ν2)/G2 [Pa] (Mindlin 1949; a rigid body drops out;
    docs/model.md §4.5)."""
    return 1.0 / sum((2.0 - m.poisson_ratio) / m.shear_modulus() for m in (m1, m2)
                     if not m.rigid)


def pair_dissipative_constant(m1: Material, m2: Material) -> float:
    """The pair's dissipative constant A [s]: each body's A weighted by its share of the
    deformation, (1 − ν²)/E (docs/model.md §3.11, [OURS]; for two equal materials, theirs)."""
    c1, c2 = m1.compliance(), m2.compliance()
    return (m1.dissipative_constant * c1 + m2.dissipative_constant * c2) / (c1 + c2)


def work_of_adhesion(m1: Material, m2: Material, contact: Contact) -> float:
    """Δγ [J/m²]: the pair's value if given, else 2 (γ1 γ2)^(1/2) (MODEL §3.8, [OURS])."""
    if contact.work_of_adhesion is not None:
        return float(contact.work_of_adhesion)
    return 2.0 * math.sqrt(m1.surface_energy * m2.surface_energy)


def pair_row(m1: Material, m2: Material, contact: Contact) -> np.ndarray:
    """Flat parameter row of a material pair for the compiled kernels.

    Args:
        m1, m2: The two materials (order does not matter).
        contact: Pair properties; ``sliding_friction=None`` is stored as 0.

    Returns:
        ``float64`` array of length :data:`PAIR_ROW_SIZE`, indexed by the ``P_*`` constants.

    References:
        MODEL §2 (E*, σ_y = min), §3.2 (δ_y, F_y, W_y), §3.3–3.4 (λ, W_p, p_p), §3.8 (f0).
    """
    e_star = effective_modulus(m1, m2)
    # The body that reaches c σ_y first yields first (MODEL §2 takes the lower σ_y); on a tie
    # in σ_y the lower c decides, so the result does not depend on which body is called 1.
    yielding = min((m1, m2), key=lambda m: (m.yield_stress, yield_factor_of(contact, m)))
    sigma = yielding.yield_stress
    c = yield_factor_of(contact, yielding)
    kappa = float(contact.hardness_factor)
    rho_p = float(contact.plastic_ratio)
    lam = kappa / (2.0 * c / 3.0)  # λ = p_p / p̄_y with p̄_y = (2/3) c σ_y (§3.2-3.3)
    big_l = math.log(rho_p)
    row = np.zeros(PAIR_ROW_SIZE)
    row[P_E_STAR] = e_star
    row[P_SIGMA_Y] = sigma
    row[P_RHO_P] = rho_p
    row[P_A] = (lam - 1.0) / big_l
    if math.isinf(sigma):
        # Never yields: every impact stays in the elastic stage (T0 < W_y = ∞).
        row[P_DY_R] = row[P_FY_R2] = row[P_WY_R3] = row[P_WP_R3] = row[P_P_P] = math.inf
    else:
        pcs = math.pi * c * sigma
        dy_r = (pcs / (2.0 * e_star)) ** 2  # §3.2 δ_y = R* (π c σ_y / 2E*)²
        fy_r2 = pcs**3 / (6.0 * e_star**2)  # §3.2 F_y = (π c σ_y)³ R*² / (6 E*²)
        wy_r3 = pcs**5 / (60.0 * e_star**4)  # §3.2 W_y = (π c σ_y)⁵ R*³ / (60 E*⁴)
        # §3.4: W_p = W_y + F_y δ_y [(λ ρ_p² − 1)/2 − (λ − 1)(ρ_p² − 1)/(4L)]
        bracket = (lam * rho_p**2 - 1.0) / 2.0 - (lam - 1.0) * (rho_p**2 - 1.0) / (4.0 * big_l)
        row[P_DY_R] = dy_r
        row[P_FY_R2] = fy_r2
        row[P_WY_R3] = wy_r3
        row[P_WP_R3] = wy_r3 + fy_r2 * dy_r * bracket
        row[P_P_P] = kappa * sigma
    row[P_G_RATIO] = effective_shear_modulus(m1, m2) / e_star
    row[P_VISC] = pair_dissipative_constant(m1, m2)
    row[P_MU_S] = 0.0 if contact.sliding_friction is None else float(contact.sliding_friction)
    row[P_MU_R] = float(contact.rolling_friction)
    row[P_E_FIXED] = (NO_FIXED_RESTITUTION if contact.restitution is None
                      else float(contact.restitution))
    if contact.adhesion_line_force is not None:
        row[P_F0] = float(contact.adhesion_line_force)
    else:
        dgamma = work_of_adhesion(m1, m2, contact)
        # §3.8 [OURS]: f0 = 0.4924 (E* R* Δγ²)^(1/3); the R*^(1/3) factor is applied per event.
        row[P_F0_COEF] = JKR_LINE_FORCE_COEF * (e_star * dgamma**2) ** (1.0 / 3.0)
    return row


@dataclass(frozen=True, slots=True)
class CriticalValues:
    """Critical values of a pair for given sizes (MODEL §3.2–3.4), SI units."""

    delta_y: float  #: deformation at first yield [m]
    force_y: float  #: force at first yield [N]
    work_y: float  #: compression work at first yield [J]
    speed_y: float  #: impact speed at first yield V_y [m/s]
    delta_p: float  #: deformation at full plasticity [m]
    force_p: float  #: force at full plasticity [N]
    work_p: float  #: compression work at full plasticity [J]
    speed_p: float  #: impact speed at full plasticity V_p [m/s]


def critical_values(row: np.ndarray, r_eff: float, m_eff: float) -> CriticalValues:
    """Critical values of a pair row for effective radius ``r_eff`` [m] and mass ``m_eff`` [kg].

    References:
        MODEL §3.2 (δ_y, F_y, W_y, V_y), §3.4 (δ_p, F_p, W_p, V_p).
    """
    dy = row[P_DY_R] * r_eff
    wy = row[P_WY_R3] * r_eff**3
    wp = row[P_WP_R3] * r_eff**3
    dp = row[P_RHO_P] * dy
    return CriticalValues(
        delta_y=dy,
        force_y=row[P_FY_R2] * r_eff**2,
        work_y=wy,
        speed_y=math.sqrt(2.0 * wy / m_eff),
        delta_p=dp,
        force_p=math.pi * r_eff * dp * row[P_P_P],
        work_p=wp,
        speed_p=math.sqrt(2.0 * wp / m_eff),
    )


# ---- tables from TOML --------------------------------------------------------------------

MATERIAL_KEYS = ("density", "youngs_modulus", "poisson_ratio", "yield_stress", "surface_energy",
                 "dissipative_constant")
CONTACT_KEYS = ("between", "sliding_friction", "rolling_friction", "restitution",
                "adhesion_line_force", "work_of_adhesion", "yield_factor", "hardness_factor",
                "plastic_ratio")
_REQUIRED_MATERIAL_KEYS = ("density", "youngs_modulus", "poisson_ratio")


def material_from_table(name: str, table, key: str) -> Material:
    """Build a material from a ``[materials.NAME]`` table.

    Raises:
        InputError: unknown or missing keys, non-physical numbers (named by key path).
    """
    if not isinstance(table, dict):
        raise InputError("must be a table of material properties", key)
    for k in table:
        if k not in MATERIAL_KEYS:
            raise InputError(f"unknown key '{k}'{did_you_mean(k, MATERIAL_KEYS)}", f"{key}.{k}")
    for k in _REQUIRED_MATERIAL_KEYS:
        if k not in table:
            raise InputError("missing value", f"{key}.{k}")
    vals = {k: check_number(table[k], f"{key}.{k}", allow_inf=(k == "yield_stress")) for k in table}
    m = Material(name=name, source=f"user table [{key}]", **vals)
    return check_material(m, key)


def contact_from_table(table, key: str, known_materials) -> tuple[frozenset, Contact]:
    """Build a contact from a ``[[contacts]]`` entry; returns (pair key, contact).

    Raises:
        InputError: unknown keys, unknown materials, non-physical numbers.
    """
    if not isinstance(table, dict):
        raise InputError("must be a table", key)
    for k in table:
        if k not in CONTACT_KEYS:
            raise InputError(f"unknown key '{k}'{did_you_mean(k, CONTACT_KEYS)}", f"{key}.{k}")
    between = table.get("between")
    if between is None:
        raise InputError("missing value (a list of two material names)", f"{key}.between")
    if (not isinstance(between, list) or len(between) != 2
            or not all(isinstance(b, str) for b in between)):
        raise InputError(f"must be a list of two material names, got {between!r}",
                         f"{key}.between")
    for b in between:
        if b not in known_materials:
            raise InputError(f"unknown material '{b}'{did_you_mean(b, known_materials)}",
                             f"{key}.between")
    kwargs = {k: v for k, v in table.items() if k != "between"}
    for k, v in kwargs.items():
        if not (k == "yield_factor" and isinstance(v, str)):
            kwargs[k] = check_number(v, f"{key}.{k}")
    return pair_key(*between), check_contact(Contact(**kwargs), key)


@dataclass(slots=True)
class MaterialLibrary:
    """Materials and pair contacts by name: the built-ins plus user tables.

    Attributes:
        materials: Material by name.
        contacts: Contact by unordered pair of names.
        contact_sources: Where each contact entry came from.
    """

    materials: dict[str, Material] = field(default_factory=lambda: dict(BUILTIN_MATERIALS))
    contacts: dict[frozenset, Contact] = field(
        default_factory=lambda: {k: c for k, (c, _) in BUILTIN_CONTACTS.items()})
    contact_sources: dict[frozenset, str] = field(
        default_factory=lambda: {k: s for k, (_, s) in BUILTIN_CONTACTS.items()})

    def material(self, name: str, key: str = "material") -> Material:
        """Material called ``name``.

        Raises:
            InputError: unknown name, with a "did you mean" hint.
        """
        try:
            return self.materials[name]
        except KeyError:
            raise InputError(
                f"unknown material '{name}'{did_you_mean(name, self.materials)}; "
                f"known: {', '.join(sorted(self.materials))}", key) from None

    def contact(self, a: str, b: str) -> Contact:
        """Contact of materials ``a`` and ``b`` (defaults when none is declared)."""
        return self.contacts.get(pair_key(a, b), Contact())

    def add_tables(self, doc: dict, origin: str = "") -> None:
        """Add ``[materials.NAME]`` and ``[[contacts]]`` entries of a parsed TOML document.

        Raises:
            InputError: for any bad entry (key paths as in the document).
        """
        mats = doc.get("materials", {})
        if not isinstance(mats, dict):
            raise InputError("must be a table of [materials.NAME] tables", "materials")
        for name, table in mats.items():
            self.materials[name] = material_from_table(name, table, f"materials.{name}")
        contacts = doc.get("contacts", [])
        if not isinstance(contacts, list):
            raise InputError("must be an array of tables ([[contacts]])", "contacts")
        for k, table in enumerate(contacts):
            key, c = contact_from_table(table, f"contacts[{k}]", self.materials)
            self.contacts[key] = c
            self.contact_sources[key] = f"{origin} contacts[{k}]".strip()

    @classmethod
    def from_toml(cls, path: str | Path) -> MaterialLibrary:
        """Built-ins plus the tables of a TOML file.

        Raises:
            InputError: unreadable file, TOML syntax error, or a bad entry.
        """
        lib = cls()
        lib.add_tables(read_toml(path), origin=str(path))
        return lib


def read_toml(path: str | Path) -> dict:
    """Parse a TOML file.

    Raises:
        InputError: missing or unreadable file, or a syntax error (one line, with the position).
    """
    p = Path(path)
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise InputError(f"file not found: {p}") from None
    except (IsADirectoryError, PermissionError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read {p}: {exc.__class__.__name__}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{p}: TOML syntax error: {exc}") from None


def with_overrides(contact: Contact, **overrides) -> Contact:
    """Copy of ``contact`` with the non-``None`` overrides applied, then checked."""
    changes = {k: v for k, v in overrides.items() if v is not None}
    return check_contact(replace(contact, **changes), "contact")
