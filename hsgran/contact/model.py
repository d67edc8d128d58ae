"""One collision, in the fixed order of MODEL §6.

:func:`resolve` is the compiled kernel: it takes the two bodies' velocities and spins (updated
in place), the contact normal, inverse masses and inertias, lever arms, the pair row, a record
array, and the effect flags. :func:`make_resolver` closes over an :class:`~hsgran.effects.Effects`
value so the flags are compile-time constants: a disabled effect's code is compiled away. The
event loop (hsgran._loop) instead passes the flags as run-time switches, so that one compiled
loop serves every scene: a disabled effect then costs one predictable branch and its code
never runs. ``tools/bench_contact.py`` measures both.

Order (MODEL §6): relative contact velocity → normal model (fixed restitution, or elastic
Hertz, or the staged model; then adhesion in recovery) → rolling couple → tangential impulse
with the updated spins → apply J = J_n n − J_t t̂ → record.

A wall is body 2 with zero inverse mass and inertia, lever arm 0 and curvature 0 (flat); a moving
wall has a velocity but no spin.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np

from hsgran._jit import njit
from hsgran.contact.adhesion import adhesion_work, line_force
from hsgran.contact.compliance import compliant_impulse
from hsgran.contact.normal import (
    STAGE_ELASTIC,
    STAGE_FIXED,
    elastic_recovery,
    hertz_contact_time,
    hertz_max_compression,
    stage_impulses,
    staged_max_compression,
)
from hsgran.contact.rolling import rolling_couple
from hsgran.contact.tangential import (
    REGIME_NONE,
    REGIME_ROLLING,
    REGIME_SLIDING,
    tangential_impulse,
)
from hsgran.contact.viscous import viscoelastic_restitution
from hsgran.effects import Effects
from hsgran.materials import (
    P_E_FIXED,
    P_E_STAR,
    P_G_RATIO,
    P_MU_R,
    P_MU_S,
    P_VISC,
    P_WP_R3,
    P_WY_R3,
)

#: A slip (or rolling) speed below SLIP_EPS_REL × max(v0, 1 m/s) has no defined direction and
#: gets no impulse: that is round-off of velocities of order v0 (MODEL §2, ε_t).
SLIP_EPS_REL = 1e-12

# ---- the record of one collision (indices into a float64 array of size REC_SIZE) ---------
REC_STAGE = 0  #: stage code (``normal.STAGE_*``)
REC_E_N = 1  #: normal restitution e_n [-]
REC_J_N = 2  #: normal impulse J_n [N s]
REC_J_T = 3  #: tangential impulse J_t [N s]
REC_REGIME = 4  #: regime code (``tangential.REGIME_*``)
REC_CAPTURED = 5  #: 1 if adhesion captured the pair (e_n = 0), else 0
REC_ENERGY_LOST = 6  #: kinetic energy dissipated [J]
REC_V0 = 7  #: normal impact speed v0 [m/s]
REC_H_ROLL = 8  #: rolling-couple angular impulse H [N m s]
# diagnostics (NaN unless the resolver was built with diagnostics=True and the value exists)
REC_DELTA_MAX = 9  #: maximum compression δ_max [m]
REC_DELTA_RES = 10  #: residual plastic deformation δ_res [m]
REC_A_MAX = 11  #: contact radius at δ_max [m]
REC_F_MAX = 12  #: force at δ_max [N]
REC_R_PRIME = 13  #: recovery radius R′ [m]
REC_W_R = 14  #: elastic energy returned in recovery W_r [J]
REC_W_A = 15  #: work of adhesion in recovery W_A [J]
REC_P_E = 16  #: impulse of the elastic compression stage [N s]
REC_P_EP = 17  #: impulse of the elastic–plastic compression stage [N s]
REC_P_PL = 18  #: impulse of the fully plastic compression stage [N s]
REC_T_CONTACT = 19  #: contact duration (elastic stage only, Hertz) [s]
REC_SIZE = 20


# long: one collision in the fixed order of MODEL §6, read top to bottom against the model;
# its steps share the contact velocity, impulses and losses as scalar locals, which helpers of
# this kernel (inlined into the event loop) would pass back and forth as tuples.
@njit(inline="always")
def resolve(v1, w1, v2, w2, nx, ny, nz, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2, curv, row, rec,
            plasticity, friction, rolling, adhesion, rotation, diagnostics, compliance=False,
            viscous=False):
    """Apply one collision to two bodies (velocities and spins updated in place).

    Args:
        v1, v2: Centre velocities [m/s], shape (3,); ``v2`` is only written if ``inv_m2 > 0``.
        w1, w2: Angular velocities [rad/s], shape (3,); ignored without ``rotation``.
        nx, ny, nz: Unit contact normal pointing from body 2 to body 1 [-].
        inv_m1, inv_m2: Inverse masses [1/kg] (0 for a wall).
        inv_i1, inv_i2: Inverse moments of inertia [1/(kg m²)] (0 for a wall).
        r1, r2: Lever arms (sphere radii) [m]; 0 for a wall.
        curv: 1/R* = 1/R1 + 1/R2 [1/m] (a flat wall adds 0).
        row: Pair row (``hsgran.materials.pair_row``).
        rec: Record array of size ``REC_SIZE`` (written), see the ``REC_*`` indices.
        plasticity, friction, rolling, adhesion, rotation, diagnostics: effect flags; use
            :func:`make_resolver` to make them compile-time constants.
        compliance, viscous: the effects beyond the paper, ``tangential_compliance``
            (docs/model.md §4.5) and ``viscoelastic_damping`` (§3.11); off, the result is the
            paper's bit for bit.

    Returns:
        True if the bodies were approaching (a collision was applied), else False.

    References:
        MODEL §6 (order), §2 (kinematics), §3 (normal), §5.2 (rolling), §4 (tangential).
    """
    # 1. relative velocity of the contact points, ΔV = (V1 − V2) − (R1 ω1 + R2 ω2) × n (§2)
    dvx = v1[0] - v2[0]
    dvy = v1[1] - v2[1]
    dvz = v1[2] - v2[2]
    if rotation:
        sx = r1 * w1[0] + r2 * w2[0]
        sy = r1 * w1[1] + r2 * w2[1]
        sz = r1 * w1[2] + r2 * w2[2]
        dvx -= sy * nz - sz * ny
        dvy -= sz * nx - sx * nz
        dvz -= sx * ny - sy * nx
    vn = dvx * nx + dvy * ny + dvz * nz
    if not vn < 0.0:
        return False
    # 3. effective quantities (§2)
    v0 = -vn
    m_eff = 1.0 / (inv_m1 + inv_m2)
    r_eff = 1.0 / curv
    t0 = 0.5 * m_eff * v0 * v0
    e_star = row[P_E_STAR]

    # 4. normal model (§3)
    stage = STAGE_ELASTIC
    captured = False
    e_n = 1.0
    d_max = f_max = a_max = r_prime = d_r = w_r = w_a = math.nan
    e_fixed = row[P_E_FIXED]
    if e_fixed >= 0.0:
        stage = STAGE_FIXED  # §3.9 bypass: §3.1-3.8 skipped, adhesion included
        e_n = e_fixed
    elif plasticity or adhesion or diagnostics:
        if plasticity:
            stage, d_max, f_max, a_max = staged_max_compression(t0, r_eff, row)
        else:
            d_max, f_max, a_max = hertz_max_compression(t0, e_star, r_eff)
        if stage == STAGE_ELASTIC:
            # Hertz unloading retraces loading: R′ = R*, δ_r = δ_max, W_r = T0 exactly (§3.7).
            r_prime = r_eff
            d_r = d_max
            w_r = t0
        else:
            r_prime, d_r, w_r = elastic_recovery(f_max, a_max, e_star)
        w_a = 0.0
        if adhesion:
            w_a = adhesion_work(line_force(row, r_eff), a_max, d_r)
        if w_a >= w_r:
            captured = True  # §3.8: adhesion wins, the pair sticks
            e_n = 0.0
        elif stage != STAGE_ELASTIC or w_a > 0.0:
            e_n = math.sqrt((w_r - w_a) / t0)  # §3.9
    if viscous and e_fixed < 0.0 and row[P_VISC] > 0.0:
        # §3.11: the viscoelastic restitution, times what the staged model returns
        e_n *= viscoelastic_restitution(v0, m_eff, r_eff, e_star, row[P_VISC])
    j_n = (1.0 + e_n) * m_eff * v0  # §3.6

    eps = SLIP_EPS_REL * max(v0, 1.0)
    h = 0.0
    loss_roll = 0.0
    if rotation and rolling:
        # 5. rolling couple against the rolling part of Δω = ω1 − ω2 (§5.1-5.2)
        dwx = w1[0] - w2[0]
        dwy = w1[1] - w2[1]
        dwz = w1[2] - w2[2]
        dwn = dwx * nx + dwy * ny + dwz * nz
        dwx -= dwn * nx
        dwy -= dwn * ny
        dwz -= dwn * nz
        roll = math.sqrt(dwx * dwx + dwy * dwy + dwz * dwz)
        if roll * r_eff > eps:
            inv_i_sum = inv_i1 + inv_i2
            h = rolling_couple(row[P_MU_R], r_eff, j_n, roll, inv_i_sum)
            if h > 0.0:
                ux = dwx / roll
                uy = dwy / roll
                uz = dwz / roll
                w1[0] -= h * inv_i1 * ux
                w1[1] -= h * inv_i1 * uy
                w1[2] -= h * inv_i1 * uz
                if inv_i2 > 0.0:
                    w2[0] += h * inv_i2 * ux
                    w2[1] += h * inv_i2 * uy
                    w2[2] += h * inv_i2 * uz
                loss_roll = h * roll - 0.5 * h * h * inv_i_sum
                # 6. the spins changed: recompute the contact-point velocity (§6 step 6)
                dvx = v1[0] - v2[0]
                dvy = v1[1] - v2[1]
                dvz = v1[2] - v2[2]
                sx = r1 * w1[0] + r2 * w2[0]
                sy = r1 * w1[1] + r2 * w2[1]
                sz = r1 * w1[2] + r2 * w2[2]
                dvx -= sy * nz - sz * ny
                dvy -= sz * nx - sx * nz
                dvz -= sx * ny - sy * nx

    # 7. tangential impulse (§4)
    j_t = 0.0
    regime = REGIME_NONE
    tx = ty = tz = 0.0
    loss_t = 0.0
    if rotation and friction:
        vn2 = dvx * nx + dvy * ny + dvz * nz
        stx = dvx - vn2 * nx
        sty = dvy - vn2 * ny
        stz = dvz - vn2 * nz
        slip = math.sqrt(stx * stx + sty * sty + stz * stz)
        if slip > eps:
            m_t = 1.0 / (inv_m1 + inv_m2 + r1 * r1 * inv_i1 + r2 * r2 * inv_i2)
            if compliance:  # §4.5: the elastic contact's impulse, from the table
                j_t, sliding = compliant_impulse(slip, m_t, row[P_MU_S], j_n, row[P_G_RATIO],
                                                 e_n)
                regime = REGIME_SLIDING if sliding else REGIME_ROLLING
            else:
                j_t, regime = tangential_impulse(slip, m_t, row[P_MU_S], j_n)
            tx = stx / slip
            ty = sty / slip
            tz = stz / slip
            loss_t = j_t * (slip - 0.5 * j_t / m_t)

    # 8. apply J = J_n n − J_t t̂ to body 1 and −J to body 2 (§4.1)
    jx = j_n * nx - j_t * tx
    jy = j_n * ny - j_t * ty
    jz = j_n * nz - j_t * tz
    v1[0] += jx * inv_m1
    v1[1] += jy * inv_m1
    v1[2] += jz * inv_m1
    if inv_m2 > 0.0:
        v2[0] -= jx * inv_m2
        v2[1] -= jy * inv_m2
        v2[2] -= jz * inv_m2
    if rotation and j_t != 0.0:  # (J_t < 0: the tangential recoil of §4.5)
        # ω1 += (R1 J_t/I1)(n × t̂), ω2 += (R2 J_t/I2)(n × t̂)  (§4.1)
        cx = ny * tz - nz * ty
        cy = nz * tx - nx * tz
        cz = nx * ty - ny * tx
        k1 = r1 * j_t * inv_i1
        w1[0] += k1 * cx
        w1[1] += k1 * cy
        w1[2] += k1 * cz
        if inv_i2 > 0.0:
            k2 = r2 * j_t * inv_i2
            w2[0] += k2 * cx
            w2[1] += k2 * cy
            w2[2] += k2 * cz

    # 9. record
    rec[REC_STAGE] = stage
    rec[REC_E_N] = e_n
    rec[REC_J_N] = j_n
    rec[REC_J_T] = j_t
    rec[REC_REGIME] = regime
    rec[REC_CAPTURED] = 1.0 if captured else 0.0
    rec[REC_ENERGY_LOST] = (1.0 - e_n * e_n) * t0 + loss_t + loss_roll  # MODEL §7 item 1
    rec[REC_V0] = v0
    rec[REC_H_ROLL] = h
    if diagnostics:
        rec[REC_DELTA_MAX] = d_max
        rec[REC_DELTA_RES] = d_max - d_r
        rec[REC_A_MAX] = a_max
        rec[REC_F_MAX] = f_max
        rec[REC_R_PRIME] = r_prime
        rec[REC_W_R] = w_r
        rec[REC_W_A] = w_a
        if stage == STAGE_FIXED:
            rec[REC_P_E] = rec[REC_P_EP] = rec[REC_P_PL] = math.nan
        elif plasticity:
            r3 = r_eff * r_eff * r_eff
            p_e, p_ep, p_pl = stage_impulses(v0, m_eff, row[P_WY_R3] * r3, row[P_WP_R3] * r3)
            rec[REC_P_E] = p_e
            rec[REC_P_EP] = p_ep
            rec[REC_P_PL] = p_pl
        else:
            rec[REC_P_E] = m_eff * v0
            rec[REC_P_EP] = 0.0
            rec[REC_P_PL] = 0.0
        if stage == STAGE_ELASTIC:
            rec[REC_T_CONTACT] = hertz_contact_time(v0, m_eff, r_eff, e_star)
        else:
            rec[REC_T_CONTACT] = math.nan
    return True


_RESOLVERS: dict = {}
_BATCHES: dict = {}


def _flags(effects: Effects, diagnostics: bool):
    return (bool(effects.plasticity), bool(effects.friction), bool(effects.rolling_resistance),
            bool(effects.adhesion), bool(effects.rotation), bool(diagnostics),
            bool(effects.tangential_compliance), bool(effects.viscoelastic_damping))


def make_resolver(effects: Effects, diagnostics: bool = False):
    """Compiled collision kernel specialised to an effect set.

    Args:
        effects: The enabled effects (``friction`` and ``rolling_resistance`` act only with
            ``rotation``).
        diagnostics: Also fill the diagnostic record fields (δ_max, F_max, ... ); costs a few
            extra power functions per event.

    Returns:
        ``f(v1, w1, v2, w2, nx, ny, nz, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2, curv, row, rec)
        -> bool`` with the flags of :func:`resolve` fixed. One compiled function per effect set
        (cached in memory and on disk).
    """
    key = _flags(effects, diagnostics)
    if key not in _RESOLVERS:
        PL, FR, RO, AD, ROT, DG, CO, VI = key

        @njit
        def resolver(v1, w1, v2, w2, nx, ny, nz, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2, curv,
                     row, rec):
            return resolve(v1, w1, v2, w2, nx, ny, nz, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2,
                           curv, row, rec, PL, FR, RO, AD, ROT, DG, CO, VI)

        _RESOLVERS[key] = resolver
    return _RESOLVERS[key]


@njit(inline="always")
def _resolve_batch(vel1, omg1, vel2, omg2, normal, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2,
                   curv, rows, pair_index, recs, plasticity, friction, rolling, adhesion,
                   rotation, diagnostics, compliance, viscous):
    hit = np.zeros(vel1.shape[0], dtype=np.bool_)
    for k in range(vel1.shape[0]):
        hit[k] = resolve(vel1[k], omg1[k], vel2[k], omg2[k], normal[k, 0], normal[k, 1],
                         normal[k, 2], inv_m1[k], inv_m2[k], inv_i1[k], inv_i2[k], r1[k], r2[k],
                         curv[k], rows[pair_index[k]], recs[k], plasticity, friction, rolling,
                         adhesion, rotation, diagnostics, compliance, viscous)
    return hit


def make_batch_resolver(effects: Effects, diagnostics: bool = False, switched: bool = False):
    """Compiled loop applying :func:`resolve` to many independent collisions.

    Returns:
        ``f(vel1, omg1, vel2, omg2, normal, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2, curv, rows,
        pair_index, recs) -> hit`` over arrays of length K (vectors of shape (K, 3), ``rows``
        of shape (P, PAIR_ROW_SIZE), ``pair_index`` int64 (K,), ``recs`` (K, REC_SIZE)); the
        state arrays are updated in place. ``omg1``/``omg2`` may be (K, 3) zeros without
        rotation. Used by the benchmark and by validation sweeps.

        With ``switched`` the flags are run-time arguments of one compiled loop, as in the
        event loop, instead of compile-time constants.
    """
    key = _flags(effects, diagnostics)
    if switched:
        return partial(_batch_switched, plasticity=key[0], friction=key[1], rolling=key[2],
                       adhesion=key[3], rotation=key[4], diagnostics=key[5],
                       compliance=key[6], viscous=key[7])
    if key not in _BATCHES:
        PL, FR, RO, AD, ROT, DG, CO, VI = key

        @njit(allocates=True)
        def batch(vel1, omg1, vel2, omg2, normal, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2, curv,
                  rows, pair_index, recs):
            return _resolve_batch(vel1, omg1, vel2, omg2, normal, inv_m1, inv_m2, inv_i1, inv_i2,
                                  r1, r2, curv, rows, pair_index, recs, PL, FR, RO, AD, ROT, DG,
                                  CO, VI)

        _BATCHES[key] = batch
    return _BATCHES[key]


@njit(allocates=True)
def _batch_switched(vel1, omg1, vel2, omg2, normal, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2,
                    curv, rows, pair_index, recs, plasticity, friction, rolling, adhesion,
                    rotation, diagnostics, compliance, viscous):
    return _resolve_batch(vel1, omg1, vel2, omg2, normal, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2,
                          curv, rows, pair_index, recs, plasticity, friction, rolling, adhesion,
                          rotation, diagnostics, compliance, viscous)


def new_record() -> np.ndarray:
    """A record array (NaN-filled) for :func:`resolve`."""
    return np.full(REC_SIZE, np.nan)


__all__ = ["REC_SIZE", "make_batch_resolver", "make_resolver", "new_record", "resolve"]
