"""Elastic hard-sphere gas: the collision rate is Enskog's with the Carnahan–Starling contact value.

Elastic Hertz impacts without friction have e_n = 1 and no tangential impulse, so an elastic
scene (``effects = []``) is a hard-sphere gas. In equilibrium the collision frequency of one
sphere is

    Γ = 4 √π n σ² g(σ) √(kT/m)

(Chapman & Cowling, *The Mathematical Theory of Non-uniform Gases*, §16.5; for hard spheres it
is exact given the true contact value g(σ), because at equilibrium the velocities are Maxwellian
and uncorrelated with the positions), with σ the diameter, n = N/V, kT/m = ⟨|v − v̄|²⟩/3, and
the Carnahan–Starling contact value g(σ) = (1 − φ/2)/(1 − φ)³. A run has N Γ / 2 pair collisions
per unit time.

The [[fill]] gives every sphere the same speed in a random direction, which is not Maxwellian
(equal speeds give a ~2 % larger mean relative speed than a Maxwellian of the same energy), so
the first collisions are discarded.
"""

import math
from dataclasses import dataclass

import numpy as np
import pytest

from hsgran.engine import Simulation
from hsgran.scene import parse_scene

#: Spheres in the periodic box: the microcanonical (fixed N, energy, momentum) corrections to
#: the canonical rate are O(1/N) ~ 0.2 %, and 500 equal spheres at φ = 0.25 fill quickly.
N_SPHERES = 500
#: Packing fraction: g(σ) = 2.22 here, so the test would miss by a factor 2.2 without the
#: Enskog factor, while Carnahan–Starling is still within a few tenths of a percent of the true
#: contact value and random sequential addition places the spheres easily (φ ≤ 0.25, see
#: hsgran.scene).
PACKING = 0.25
RADIUS = 0.01  #: [m]
SPEED = 1.0  #: fill speed [m/s]; kT/m = ⟨|v − v̄|²⟩/3 is measured, not assumed
SEED = 5
#: Scene duration [s]: far longer than the ~1 s of simulated time the counted collisions take,
#: so the runs stop on their collision budget.
DURATION = 1000.0

#: Collisions per sphere discarded before counting (each pair collision counts for two spheres).
#: The speed distribution of the equal-speed fill relaxes to Maxwell–Boltzmann within ~8
#: collisions per sphere (measured, mean of 20 seeds at these settings: the kurtosis ⟨v⁴⟩/⟨v²⟩²
#: is 1.00, 1.35, 1.57, 1.68 ± 0.01, 1.67 ± 0.01 after 0, 2, 5, 8, 15 collisions per sphere).
RELAX_PER_SPHERE = 10
#: Pair collisions counted. The relative statistical error of the measured rate is ≈ 1/√(count)
#: (collisions are nearly a Poisson stream): block averaging gave 0.3–0.4 % for 10⁵ collisions
#: at φ = 0.2 and 0.33–0.64 % for these settings; over 12 seeds the ratio measured/predicted was
#: 0.998–1.013 (mean 1.0035, std 0.45 %). So the 3 % tolerance is ~6 standard errors. Cost:
#: ~0.3 s compiled, ~14 s with NUMBA_DISABLE_JIT=1 (~3×10³ collisions/s in pure Python), so
#: both modes run the same test.
COUNTED = 40_000
#: Blocks of equal collision count for the in-test error estimate (2 000 collisions, i.e. 8 per
#: sphere each, much longer than the ~1 collision-per-sphere correlation time of the rate).
BLOCKS = 20

#: Required agreement of measured and predicted collision rate (the issue's 3 %).
ENSKOG_RTOL = 0.03
#: The block estimate of the statistical error must be below this, so that a pass of the 3 %
#: check means something (≥ 3 standard errors); it guards against a change to the constants
#: above that makes the test too noisy.
MAX_STAT_ERROR = 0.01

#: Frames sampled per mean free time × this (≈ independent snapshots of the speed distribution).
COLLISIONS_PER_FRAME = 4.0
#: Kurtosis ⟨v⁴⟩/⟨v²⟩² of the 3-D Maxwell–Boltzmann speed distribution (15/9).
MAXWELL_KURTOSIS = 5.0 / 3.0
#: Allowed relative deviation of the pooled kurtosis from 5/3. One snapshot of 500 speeds has a
#: relative std of ≈ 6 % (var(v⁴)/⟨v⁴⟩² = 945/225 − 1 for a Maxwellian); the ~40 frames of the
#: counted stretch are nearly independent, and 12 seeds gave 1.648–1.675 (std 0.5 %), so 3 % is
#: ~6 standard deviations, while the fill's equal speeds have kurtosis 1 (40 % off).
KURTOSIS_RTOL = 0.03

#: Relative change of kT/m allowed between the fill and the end of the run: elastic collisions
#: conserve energy to a few ulp each, ~1e-12 after 10⁵ collisions (tests/test_engine.py).
ENERGY_RTOL = 1e-9

GAS = """
[scene]
name = "elastic hard-sphere gas"
duration = {duration}
effects = []
seed = {seed}
periodic = [true, true, true]
[output]
frame_interval = {frame}
[materials.steel]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [{side}, {side}, {side}]
[[fill]]
count = {count}
radius = {radius}
material = "steel"
speed = {speed}
region = {{ lower = [0.0, 0.0, 0.0], upper = [{side}, {side}, {side}] }}
"""


def carnahan_starling_contact(phi):
    """Pair correlation at contact g(σ) of the Carnahan–Starling equation of state [-]."""
    return (1.0 - 0.5 * phi) / (1.0 - phi) ** 3


def enskog_frequency(density, sigma, phi, kt_over_m):
    """Collisions per sphere per second, Γ = 4 √π n σ² g(σ) √(kT/m) [1/s]."""
    return (4.0 * math.sqrt(math.pi) * density * sigma**2 * carnahan_starling_contact(phi)
            * math.sqrt(kt_over_m))


def temperature(velocity):
    """kT/m = ⟨|v − v̄|²⟩/3 [m²/s²] of velocities (N, 3)."""
    v = velocity - velocity.mean(axis=0)
    return float(np.mean(np.sum(v * v, axis=1)) / 3.0)


class Frames:
    """Observer keeping the sampled times and velocities."""

    def __init__(self):
        self.time = []
        self.velocity = []

    def on_frames(self, block):
        self.time.append(block.time)
        self.velocity.append(block.velocity)


@dataclass
class GasRun:
    """What :func:`run_gas` measured."""

    measured: float  #: pair collisions per second over the counted stretch [1/s]
    predicted: float  #: N Γ / 2 from Enskog with Carnahan–Starling [1/s]
    stat_error: float  #: relative standard error of ``measured`` from block averaging [-]
    kt_start: float  #: kT/m of the fill [m²/s²]
    kt_end: float  #: kT/m at the end of the run [m²/s²]
    velocity: np.ndarray  #: frames sampled during the counted stretch (F, N, 3) [m/s]

    @property
    def ratio(self) -> float:
        return self.measured / self.predicted


def run_gas(seed=SEED, count=N_SPHERES, phi=PACKING, counted=COUNTED, blocks=BLOCKS,
            relax_per_sphere=RELAX_PER_SPHERE) -> GasRun:
    """Relax an elastic gas, then time ``counted`` pair collisions in ``blocks`` equal blocks."""
    side = (count * 4.0 / 3.0 * math.pi * RADIUS**3 / phi) ** (1.0 / 3.0)
    sigma = 2.0 * RADIUS
    density = count / side**3
    # the prediction for the fill's speeds only sets the frame spacing
    gamma_fill = enskog_frequency(density, sigma, phi, SPEED**2 / 3.0)
    scene = parse_scene(GAS.format(duration=DURATION, seed=seed, side=side, count=count,
                                   frame=COLLISIONS_PER_FRAME / gamma_fill, radius=RADIUS,
                                   speed=SPEED))
    frames = Frames()
    sim = Simulation(scene)
    relax = relax_per_sphere * count // 2
    sim.run(until=DURATION, max_collisions=relax)
    per_block = counted // blocks
    t = [sim.time]
    for _ in range(blocks):
        sim.run(until=DURATION, max_collisions=per_block, observers=[frames])
        t.append(sim.time)
    assert sim.collisions == relax + per_block * blocks

    kt = temperature(sim.vel)
    predicted = count * enskog_frequency(density, sigma, phi, kt) / 2.0
    measured = per_block * blocks / (t[-1] - t[0])
    block_rates = per_block / np.diff(t)
    stat_error = float(np.std(block_rates, ddof=1) / math.sqrt(blocks) / np.mean(block_rates))
    times = np.concatenate(frames.time)
    velocity = np.concatenate(frames.velocity)[times >= t[0]]
    return GasRun(measured, predicted, stat_error, temperature(scene.velocity), kt, velocity)


def speed_kurtosis(velocity):
    """⟨v⁴⟩/⟨v²⟩² of the peculiar speeds pooled over frames (F, N, 3) [-]."""
    v = velocity - velocity.mean(axis=1, keepdims=True)
    v2 = np.sum(v * v, axis=2)
    return float(np.mean(v2 * v2) / np.mean(v2) ** 2)


@pytest.fixture(scope="module")
def gas_run():
    """One run serves both tests (it is the costly part under NUMBA_DISABLE_JIT=1)."""
    return run_gas()


def test_elastic_gas_collision_rate_matches_enskog_with_carnahan_starling(gas_run):
    run = gas_run
    # elastic collisions conserve kT/m (to rounding), so the end state's value holds throughout
    assert run.kt_end == pytest.approx(run.kt_start, rel=ENERGY_RTOL)
    assert run.stat_error < MAX_STAT_ERROR
    assert abs(run.ratio - 1.0) < ENSKOG_RTOL, (
        f"measured {run.measured:.6g}/s, Enskog–CS {run.predicted:.6g}/s, ratio "
        f"{run.ratio:.4f} (statistical error {run.stat_error:.2%})")


def test_elastic_gas_speeds_relax_to_maxwell_boltzmann(gas_run):
    run = gas_run
    assert run.velocity.shape[0] >= BLOCKS  # enough frames in the counted stretch to mean much
    assert abs(speed_kurtosis(run.velocity) / MAXWELL_KURTOSIS - 1.0) < KURTOSIS_RTOL
