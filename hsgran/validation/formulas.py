"""Closed forms of docs/model.md that the validation compares the engine with (layer 6).

These are written again here, from the equations of docs/model.md, rather than imported from the
collision kernels: a reference evaluated by the code under test would check nothing. They are
plain Python (scalar in, scalar out) and use scipy only for root finding and the incomplete
beta function.

Provenance follows docs/model.md: §3.1–3.2 and §3.6 [LIT]; the elastic–plastic and fully plastic
stages §3.3–3.4 are **[OURS]** reconstructions; the recovery §3.7 [YT]/[LIT]; the f0 estimate
of §3.8 [OURS, low confidence]; §4 rigid-body tangential model [P]/[LIT]; §5.3 [LIT].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq
from scipy.special import betaincinv

#: Moment of inertia factor of a solid sphere, k = I/(m R²) (MODEL §4.3, §8).
K_SOLID = 0.4
#: Model defaults of MODEL §8: first-yield factor c, hardness factor κ, ρ_p = δ_p/δ_y.
YIELD_FACTOR, HARDNESS_FACTOR, PLASTIC_RATIO = 1.6, 2.8, 110.0
#: Exact Hertz contact-duration coefficient: t_c = C (m*²/(R* E*² v0))^(1/5) with
#: C = 2 (15/16)^(2/5) ∫0^1 (1 − x^(5/2))^(−1/2) dx, the integral being (2/5) B(2/5, 1/2).
HERTZ_TC_COEF = (2.0 * (15.0 / 16.0) ** 0.4 * 0.4
                 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9))
#: Coefficient of the JKR-matched line force f0 = C (E* R* Δγ²)^(1/3), C = (3/4)(8/(9π))^(1/3)
#: (MODEL §3.8, [OURS]).
JKR_LINE_FORCE_COEF = 0.75 * (8.0 / (9.0 * math.pi)) ** (1.0 / 3.0)
#: Relative tolerance of the root finds below: far below the 1e-9 of the comparisons.
ROOT_RTOL = 1e-15


# ---- effective properties (MODEL §2) --------------------------------------------------

def effective_modulus(e1: float, nu1: float, e2: float = math.inf, nu2: float = 0.0) -> float:
    """E* [Pa] from 1/E* = (1 − ν1²)/E1 + (1 − ν2²)/E2 (a rigid body, E = ∞, drops out)."""
    return 1.0 / ((1.0 - nu1**2) / e1 + (0.0 if math.isinf(e2) else (1.0 - nu2**2) / e2))


def sphere_mass(density: float, radius: float) -> float:
    """ρ (4/3) π R³ [kg]."""
    return density * 4.0 / 3.0 * math.pi * radius**3


def jkr_line_force(e_star: float, r_star: float, work_of_adhesion: float) -> float:
    """f0 = 0.4924 (E* R* Δγ²)^(1/3) [N/m] (MODEL §3.8, [OURS, low confidence])."""
    return JKR_LINE_FORCE_COEF * (e_star * r_star * work_of_adhesion**2) ** (1.0 / 3.0)


# ---- normal model (MODEL §3) ----------------------------------------------------------

@dataclass(frozen=True)
class NormalOutcome:
    """Result of the staged normal model for one impact (SI units)."""

    e_n: float  #: normal restitution [-]
    stage: str  #: "elastic", "elastic-plastic" or "fully-plastic"
    captured: bool  #: adhesion won (W_A ≥ W_r)
    delta_max: float  #: maximum compression [m]
    force_max: float  #: force at maximum compression [N]
    radius_max: float  #: contact radius at maximum compression [m]


@dataclass(frozen=True)
class StagedPair:
    """A pair in the staged normal model of MODEL §3 (SI units).

    Attributes:
        e_star, r_star, m_star: Effective modulus [Pa], radius [m] and mass [kg] (§2).
        sigma_y: Governing yield stress [Pa] (``inf``: never yields).
        line_force: Adhesion line force f0 [N/m] (0: no adhesion).
        c, kappa, rho_p: Model constants of §8.
    """

    e_star: float
    r_star: float
    m_star: float
    sigma_y: float
    line_force: float = 0.0
    c: float = YIELD_FACTOR
    kappa: float = HARDNESS_FACTOR
    rho_p: float = PLASTIC_RATIO

    # §3.2 first yield
    @property
    def delta_y(self) -> float:
        """δ_y = R* (π c σ_y / (2E*))² [m]."""
        return self.r_star * (math.pi * self.c * self.sigma_y / (2.0 * self.e_star)) ** 2

    @property
    def force_y(self) -> float:
        """F_y = (4/3) E* R*^(1/2) δ_y^(3/2) [N]."""
        return 4.0 / 3.0 * self.e_star * math.sqrt(self.r_star) * self.delta_y**1.5

    @property
    def work_y(self) -> float:
        """W_y = (2/5) F_y δ_y [J]."""
        return 0.4 * self.force_y * self.delta_y

    # §3.3 elastic–plastic law [OURS]
    @property
    def _lam_l(self) -> tuple[float, float]:
        lam = self.kappa * self.sigma_y / (2.0 / 3.0 * self.c * self.sigma_y)  # p_p / p̄_y
        return lam, math.log(self.rho_p)

    def work_ep(self, u: float) -> float:
        """W(δ) of §3.3 at u = δ/δ_y ∈ [1, ρ_p] [J]."""
        lam, big_l = self._lam_l
        brace = (u * u - 1.0) / 2.0 + (lam - 1.0) / big_l * (
            u * u * math.log(u) / 2.0 - u * u / 4.0 + 0.25)
        return self.work_y + self.force_y * self.delta_y * brace

    def force_ep(self, u: float) -> float:
        """F = F_y u [1 + (λ − 1) ln(u)/L] of §3.3 [N]."""
        lam, big_l = self._lam_l
        return self.force_y * u * (1.0 + (lam - 1.0) * math.log(u) / big_l)

    @property
    def work_p(self) -> float:
        """W_p = W(δ_p) [J] (§3.4)."""
        return self.work_ep(self.rho_p)

    @property
    def speed_y(self) -> float:
        """V_y = (2 W_y/m*)^(1/2) [m/s] (§3.2)."""
        return math.sqrt(2.0 * self.work_y / self.m_star)

    @property
    def speed_p(self) -> float:
        """V_p = (2 W_p/m*)^(1/2) [m/s] (§3.4)."""
        return math.sqrt(2.0 * self.work_p / self.m_star)

    def impact(self, v0: float) -> NormalOutcome:
        """Maximum compression (§3.5), recovery (§3.7), adhesion (§3.8), e_n (§3.9).

        Args:
            v0: Normal impact speed [m/s], > 0.
        """
        e, r = self.e_star, self.r_star
        t0 = 0.5 * self.m_star * v0**2
        if math.isinf(self.sigma_y) or t0 <= self.work_y:
            stage = "elastic"
            d = (15.0 * self.m_star * v0**2 / (16.0 * e * math.sqrt(r))) ** 0.4
            f = 4.0 / 3.0 * e * math.sqrt(r) * d**1.5
        elif t0 <= self.work_p:
            stage = "elastic-plastic"
            u = brentq(lambda x: self.work_ep(x) - t0, 1.0, self.rho_p, xtol=1e-300,
                       rtol=ROOT_RTOL, maxiter=500)
            d = u * self.delta_y
            f = self.force_ep(u)
        else:
            stage = "fully-plastic"
            p_p = self.kappa * self.sigma_y
            d_p = self.rho_p * self.delta_y
            d = math.sqrt(d_p**2 + 2.0 * (t0 - self.work_p) / (math.pi * r * p_p))
            f = math.pi * r * d * p_p
        a = math.sqrt(r * d)  # a² = R* δ in every stage (§3.3, [OURS])
        d_r = 3.0 * f / (4.0 * e * a)  # recovered deformation (§3.7)
        w_r = 0.4 * f * d_r
        w_a = 4.0 * math.pi / 3.0 * self.line_force * a * d_r  # §3.8
        captured = w_a >= w_r
        e_n = 0.0 if captured else math.sqrt((w_r - w_a) / t0)
        return NormalOutcome(e_n, stage, captured, d, f, a)

    def capture_speed(self, low: float, high: float) -> float:
        """Impact speed [m/s] below which adhesion captures the sphere (W_A = W_r, §3.8).

        Args:
            low, high: A bracket [m/s]: captured at ``low``, rebounding at ``high``.
        """
        def margin(v: float) -> float:
            out = self.impact(v)
            a, f = out.radius_max, out.force_max
            d_r = 3.0 * f / (4.0 * self.e_star * a)
            return 0.4 * f * d_r - 4.0 * math.pi / 3.0 * self.line_force * a * d_r

        return brentq(margin, low, high, xtol=1e-300, rtol=ROOT_RTOL, maxiter=500)


# ---- Hertz impact (MODEL §3.1) --------------------------------------------------------

def hertz_maxima(e_star: float, r_star: float, m_star: float, v0: float) -> dict[str, float]:
    """δ_max [m], F_max [N], a_max [m] and the exact contact duration t_c [s] of an elastic
    impact at normal speed v0 [m/s] (MODEL §3.1)."""
    d = (15.0 * m_star * v0**2 / (16.0 * e_star * math.sqrt(r_star))) ** 0.4
    return {"delta_max": d,
            "force_max": 4.0 / 3.0 * e_star * math.sqrt(r_star) * d**1.5,
            "radius_max": math.sqrt(r_star * d),
            "contact_time": HERTZ_TC_COEF * (m_star**2 / (r_star * e_star**2 * v0)) ** 0.2}


def hertz_force(delta: float, e_star: float, r_star: float) -> float:
    """F = (4/3) E* R*^(1/2) δ^(3/2) [N] (MODEL §3.1)."""
    return 4.0 / 3.0 * e_star * math.sqrt(r_star) * max(delta, 0.0) ** 1.5


def hertz_pulse(t: float, force_max: float, contact_time: float) -> float:
    """Force [N] at time t [s] after first contact of an elastic Hertz impact.

    From energy conservation, t(δ) = (δ_max/v0) ∫0^(δ/δ_max) (1 − x^(5/2))^(−1/2) dx; with
    s = (δ/δ_max)^(5/2) this is 2t/t_c = I_s(2/5, 1/2) (regularised incomplete beta) while
    loading, mirrored while unloading, and F/F_max = s^(3/5).
    """
    if t <= 0.0 or t >= contact_time:
        return 0.0
    phase = 1.0 - abs(1.0 - 2.0 * t / contact_time)
    return force_max * float(betaincinv(0.4, 0.5, phase)) ** 0.6


# ---- rigid-body tangential model (MODEL §4) -------------------------------------------

@dataclass(frozen=True)
class WallOblique:
    """Outcome of a sphere–wall impact in the rigid-body tangential model (MODEL §4.3).

    Frame: wall normal n, the contact point slips along t̂ before impact, spins about n × t̂
    (positive: forward rolling for a sphere moving along +t̂).
    """

    regime: str  #: "rolling" or "sliding"
    v_t: float  #: centre tangential velocity after [m/s]
    v_n: float  #: centre normal velocity after (away from the wall) [m/s]
    omega: float  #: spin after [rad/s]
    slip: float  #: contact-point tangential velocity after, u′ = v_t − R ω [m/s]
    impulse_t: float  #: tangential impulse per unit mass J_t/m [m/s]


def wall_oblique(v_n0: float, v_t0: float, omega0: float, radius: float, mu: float,
                 e_n: float) -> WallOblique:
    """Rigid-body outcome of a sphere hitting a wall (MODEL §4.2–4.3, with initial spin).

    Args:
        v_n0: Normal approach speed [m/s], > 0.
        v_t0: Centre tangential velocity before [m/s] (along t̂).
        omega0: Spin before about n × t̂ [rad/s] (positive = topspin).
        radius: Sphere radius [m].
        mu: Sliding friction μ_s [-].
        e_n: Normal restitution of the impact [-].

    The contact-point slip u0 = v_t0 − R ω0 decides: the impulse that stops it is
    J_stick = m_t* |u0| with m_t* = (2/7) m; Coulomb allows μ (1 + e_n) m v_n0.
    """
    u0 = v_t0 - radius * omega0
    j_stick = K_SOLID / (1.0 + K_SOLID) * abs(u0)  # (2/7)|u0|, per unit mass
    j_lim = mu * (1.0 + e_n) * v_n0
    regime = "rolling" if j_stick <= j_lim else "sliding"
    j_t = j_stick if regime == "rolling" else j_lim
    s = math.copysign(1.0, u0) if u0 != 0.0 else 0.0
    v_t = v_t0 - s * j_t
    omega = omega0 + s * j_t / (K_SOLID * radius)
    return WallOblique(regime, v_t, e_n * v_n0, omega, v_t - radius * omega, j_t)


def critical_angle_deg(mu: float, e_n: float) -> float:
    """θ_c from tan θ_c = (1 + 1/k) μ (1 + e_n) (MODEL §4.3) [deg]."""
    return math.degrees(math.atan((1.0 + 1.0 / K_SOLID) * mu * (1.0 + e_n)))


# ---- enduring contact (MODEL §5.3; incline: rigid-body mechanics [LIT]) ----------------

def incline_acceleration(theta: float, mu_s: float, mu_r: float, g: float) -> tuple[str, float]:
    """Motion of a sphere released at rest on a plane tilted by θ [rad].

    At rest, friction m g sin θ must stay below μ_s m g cos θ and its torque below the rolling
    couple μ_r R m g cos θ: rest when tan θ ≤ μ_r and tan θ ≤ μ_s. Rolling needs a friction
    force below μ_s m g cos θ, i.e. tan θ ≤ (1 + 1/k) μ_s − μ_r/k (= 3.5 μ_s − 2.5 μ_r, the
    rolling torque acting); then the centre accelerates at g (sin θ − μ_r cos θ)/(1 + k).
    Otherwise it slides at g (sin θ − μ_s cos θ).

    Returns:
        (motion, acceleration along the fall line [m/s²]); motion is "rest", "rolling" or
        "sliding".
    """
    if math.tan(theta) <= mu_r and math.tan(theta) <= mu_s:
        return "rest", 0.0
    if math.tan(theta) <= (1.0 + 1.0 / K_SOLID) * mu_s - mu_r / K_SOLID:
        return "rolling", g * (math.sin(theta) - mu_r * math.cos(theta)) / (1.0 + K_SOLID)
    return "sliding", g * (math.sin(theta) - mu_s * math.cos(theta))


def plate_closed_form(v0: float, omega0: float, radius: float, mu_s: float, mu_r: float,
                      g: float, convention: str) -> dict[str, float]:
    """Sphere launched along a horizontal plate: slide, roll, stop (MODEL §5.3).

    Args:
        v0: Initial centre speed [m/s], > 0.
        omega0: Initial spin [rad/s] (positive = forward rolling); the slip u0 = v0 − R Ω0
            must be positive.
        radius: Sphere radius [m].
        mu_s, mu_r: Sliding and rolling friction [-].
        g: Gravitational acceleration [m/s²].
        convention: "A" (rolling torque also while sliding) or "B" (only while rolling).

    Returns:
        t_slide [s], v_roll [m/s], x_slide [m], t_stop [s], x_stop [m].
    """
    chi = 1.0 if convention == "A" else 0.0
    u0 = v0 - radius * omega0
    if u0 <= 0.0:
        raise ValueError("the closed form needs a forward slip u0 = v0 − R Ω0 > 0")
    k = K_SOLID
    if omega0 < 0.0 and chi:
        # backspin, convention A: the rolling torque helps friction until the spin passes zero
        t1 = ((u0 - 2.0 * mu_r * radius * abs(omega0) / (mu_s + mu_r))
              / (g * ((1.0 + 1.0 / k) * mu_s - mu_r / k)))
    else:
        t1 = u0 / (g * ((1.0 + 1.0 / k) * mu_s - chi * mu_r / k))
    v1 = v0 - mu_s * g * t1
    x1 = v0 * t1 - mu_s * g * t1**2 / 2.0
    t2 = v1 * (1.0 + k) / (mu_r * g)
    x2 = v1**2 * (1.0 + k) / (2.0 * mu_r * g)
    return {"t_slide": t1, "v_roll": v1, "x_slide": x1, "t_stop": t1 + t2, "x_stop": x1 + x2}


def pair_rigid(v1, w1, v2, w2, normal, m1: float, m2: float, r1: float, r2: float, mu: float,
               e_n: float):
    """Two solid spheres in the rigid-body impulse model (MODEL §2, §4.1–4.2), vector form.

    Args:
        v1, w1, v2, w2: Centre velocities [m/s] and spins [rad/s] before, (3,) each.
        normal: Unit normal from sphere 2 to sphere 1 at contact, (3,).
        m1, m2: Masses [kg]; r1, r2: radii [m].
        mu: Sliding friction [-]; e_n: normal restitution of the impact [-].

    Returns:
        (v1′, w1′, v2′, w2′, regime, J_n [N s], J_t [N s], slip before (3,), slip after (3,)).
    """
    n = np.asarray(normal, dtype=float)
    i1, i2 = K_SOLID * m1 * r1**2, K_SOLID * m2 * r2**2

    def slip(a1, b1, a2, b2):
        dv = (a1 - a2) - np.cross(r1 * b1 + r2 * b2, n)
        return dv, dv - np.dot(dv, n) * n

    dv, dvt = slip(v1, w1, v2, w2)
    v0 = -float(np.dot(dv, n))
    m_eff = 1.0 / (1.0 / m1 + 1.0 / m2)
    m_t = 1.0 / (1.0 / m1 + 1.0 / m2 + r1**2 / i1 + r2**2 / i2)
    j_n = (1.0 + e_n) * m_eff * v0
    size = float(np.linalg.norm(dvt))
    if size > 0.0:
        t_hat = dvt / size
        j_stick, j_lim = m_t * size, mu * j_n
        regime = "rolling" if j_stick <= j_lim else "sliding"
        j_t = min(j_stick, j_lim)
    else:
        t_hat, regime, j_t = np.zeros(3), "none", 0.0
    imp = j_n * n - j_t * t_hat
    v1a, v2a = v1 + imp / m1, v2 - imp / m2
    w1a = w1 + np.cross(-r1 * n, imp) / i1
    w2a = w2 + np.cross(r2 * n, -imp) / i2
    return v1a, w1a, v2a, w2a, regime, j_n, j_t, dvt, slip(v1a, w1a, v2a, w2a)[1]
