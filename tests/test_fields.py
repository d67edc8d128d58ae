"""Slab profiles (hsgran.fields): exact volumes, the mass they hold, flat fields of a uniform
gas within their statistical error, and ``hsgran fields``."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from hsgran.api import run_scene
from hsgran.cli import main
from hsgran.errors import InputError
from hsgran.fields import profiles, slab_fractions, volume_below

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
RHO = 2500.0


def synthetic(position, velocity, radius, periodic=(False, False, False), box=1.0):
    """A trajectory-like object of F frames (position, velocity: (F, N, 3))."""
    f = position.shape[0]
    return SimpleNamespace(time=np.arange(f, dtype=float), position=position, velocity=velocity,
                           radius=radius, mass=RHO * 4.0 / 3.0 * math.pi * radius**3,
                           box_lower=np.zeros(3), box_upper=np.full(3, box),
                           periodic=periodic)


def test_cap_volumes_split_a_sphere_exactly():
    r = np.array([0.1])
    assert volume_below(np.array([0.5]), np.array([0.5]), r)[0] == pytest.approx(
        2.0 / 3.0 * math.pi * 0.1**3, rel=1e-15)
    w = slab_fractions(np.array([0.0, 0.45, 0.5, 1.0]), np.array([0.5]), r)
    assert w.sum() == pytest.approx(1.0, rel=1e-14)
    assert w[0, 2] == pytest.approx(0.5, rel=1e-14)
    # a cap of height h = R/2: (π h²(3R − h)/3)/(4πR³/3) = 5/32
    assert w[0, 0] == pytest.approx(5.0 / 32.0, rel=1e-14)
    # across a periodic boundary the sphere is split between the two ends
    wp = slab_fractions(np.linspace(0.0, 1.0, 11), np.array([0.02]), r, period=1.0)
    assert wp.sum() == pytest.approx(1.0, rel=1e-14)
    assert wp[0, -1] > 0.0


@pytest.mark.parametrize("periodic", [(False, False, False), (True, True, True)])
def test_profiles_hold_the_mass_and_the_identities(periodic):
    rng = np.random.default_rng(3)
    n, frames = 400, 5
    radius = rng.uniform(0.01, 0.03, n)
    lo = 0.0 if any(periodic) else 0.03
    pos = rng.uniform(lo, 1.0 - lo, (frames, n, 3))
    vel = rng.normal(0.0, 0.2, (frames, n, 3)) + np.array([0.0, 0.0, 0.5])
    traj = synthetic(pos, vel, radius, periodic)
    p = profiles(traj, "z", 13)
    assert p.mass.sum() == pytest.approx(traj.mass.sum(), rel=1e-12)
    vol = 4.0 / 3.0 * math.pi * (radius**3).sum()
    assert (p.packing_fraction * np.diff(p.edges)).sum() == pytest.approx(vol, rel=1e-12)
    # tr σ = −3 T × (slab mass)/V_s per frame; the means keep it where the slab mass is steady
    one = profiles(synthetic(pos[:1], vel[:1], radius, periodic), "z", 13)
    slab_v = np.diff(one.edges)
    np.testing.assert_allclose(-np.trace(one.kinetic_stress, axis1=1, axis2=2) * slab_v,
                               3.0 * one.temperature * one.mass, rtol=1e-10)
    # a uniform velocity has no temperature and no stress
    still = profiles(synthetic(pos[:1], np.ones_like(vel[:1]), radius, periodic), "z", 13)
    np.testing.assert_allclose(still.velocity, 1.0, rtol=1e-13)
    np.testing.assert_allclose(still.temperature, 0.0, atol=1e-25)


def test_a_uniform_gas_is_flat_within_its_statistical_error():
    """Independent uniform frames: every slab's φ and T within 4 standard errors of the
    whole box's values (13 slabs × 2 fields: a false alarm has odds below 1 in 600)."""
    rng = np.random.default_rng(7)
    n, frames = 1500, 60
    radius = np.full(n, 0.02)
    pos = rng.uniform(0.0, 1.0, (frames, n, 3))
    vel = rng.normal(0.0, 0.3, (frames, n, 3))
    p = profiles(synthetic(pos, vel, radius, (True, True, True)), "x", 13)
    phi = n * 4.0 / 3.0 * math.pi * 0.02**3
    assert np.all(np.abs(p.packing_fraction - phi) < 4.0 * p.packing_fraction_error)
    # + 0.09/n: an allowance for the variance about the slab's own mean velocity, biased low
    # by a factor (1 − 1/N_slab) with N_slab ≈ n/13 (0.09 × 13/n ≈ 8e-4); the four standard
    # errors (4 × 7e-4 to 4 × 1e-3 here) cover the rest of that bias
    assert np.all(np.abs(p.temperature - 0.09) < 4.0 * p.temperature_error + 0.09 / n)


def test_bad_input_is_refused():
    traj = synthetic(np.full((1, 1, 3), 0.5), np.zeros((1, 1, 3)), np.array([0.1]))
    with pytest.raises(InputError, match="--axis"):
        profiles(traj, "w")
    with pytest.raises(InputError, match="--from"):
        profiles(traj, start=5.0)
    traj.box_lower = None
    with pytest.raises(InputError, match="no box"):
        profiles(traj)


def test_cli_on_a_run(tmp_path, capsys):
    path = tmp_path / "gas.h5"
    run_scene(SCENARIOS / "granular_gas.toml", path, overrides={"scene.duration": 0.01})
    assert main(["fields", str(path), "--axis", "y", "--bins", "5"]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 2 + 5
    csv = tmp_path / "f.csv"
    assert main(["fields", str(path), "--bins", "4", "--from", "0.004", "--csv", str(csv)]) == 0
    rows = csv.read_text().splitlines()
    assert len(rows) == 5
    assert rows[0].startswith("centre_m")
    assert main(["fields", str(path), "--axis", "q"]) == 2
    assert "--axis" in capsys.readouterr().err
