"""Spheres riding moving planes (hsgran._riding): a ball below take-off comes to rest on a
vibrating plate and moves with it; a completely inelastic ball takes off where the plate's
downward acceleration reaches g (against an exact map); friction under the varying load of a
vibrating plate; a ball rolling on a plate shaken sideways; a ball lifted by a piston."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from hsgran._riding import END_TAKEOFF, RIDE_STEP
from hsgran.engine import Simulation
from hsgran.events.kinds import EV_LAND, EV_STATE, EV_WALL
from hsgran.onplane import END_SLIP, MS_FLIGHT, MS_ROLLING
from hsgran.scene import parse_scene
from tests.observers import Keep

G = 9.81  #: [m/s²]
RADIUS = 0.005  #: [m]
FREQ = 20.0  #: [Hz]
OMEGA = 2 * math.pi * FREQ  #: [rad/s]
#: Rounding of a position of a few millimetres after thousands of segments [m]
ROUND_POS = 1e-15

PLATE = """
[scene]
name = "ball on a plate"
duration = {duration}
gravity = [0.0, 0.0, -9.81]
effects = {effects}
[output]
frame_interval = {frame}
[[contacts]]
between = ["steel", "steel"]
restitution = {e}
{friction}
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "steel"
[walls.motion]
kind = "oscillation"
amplitude = {amp!r}
frequency = {freq}
phase = {phase!r}
direction = {direction}
[[particles]]
material = "steel"
radius = {radius}
position = [0.0, 0.0, {z0!r}]
velocity = [{u!r}, 0.0, {w!r}]
"""


def plate_scene(*, amp, phase, z0, duration, e=0.5, u=0.0, w=0.0, effects='["gravity"]',
                friction="", direction="[0.0, 0.0, 1.0]", frame=0.001):
    return PLATE.format(duration=duration, effects=effects, frame=frame, e=e, friction=friction,
                        amp=amp, freq=FREQ, phase=phase, direction=direction, radius=RADIUS,
                        z0=z0, u=u, w=w)


def run(text):
    """Run a scene; its frames (time, position, velocity, motion_state) and event log."""
    sim = Simulation(parse_scene(text), log_events=True)
    keep = Keep()
    summary = sim.run(observers=[keep])
    frames = {name: keep.cat(name) for name in ("time", "position", "velocity", "motion_state")}
    log = {name: keep.log(name) for name in ("time", "kind", "regime")}
    return summary, frames, log


def plate_height(t, amp, phase):
    return amp * (np.sin(OMEGA * t + phase) - math.sin(phase))


def plate_speed(t, amp, phase):
    return amp * OMEGA * np.cos(OMEGA * t + phase)


@pytest.mark.parametrize("gamma", [0.5, 0.9])
def test_below_takeoff_a_ball_comes_to_rest_and_moves_with_the_plate(gamma):
    """Γ < 1, e = 0.5: the bounces relative to the plate die out, the ball lands, and from
    then on it sits on the plate: its height is the plate's plus r, above it by at most the
    hover ½ A RIDE_STEP³ of a segment, and never below; its speed is the plate's within
    A ω RIDE_STEP²; the plate never hits it again."""
    amp = gamma * G / OMEGA**2
    summary, frames, log = run(plate_scene(amp=amp, phase=0.3, z0=RADIUS + 0.002,
                                           duration=1.0))
    lands = log["time"][log["kind"] == EV_LAND]
    assert lands.shape == (1,)
    assert summary.events["wall"] >= 3  # it bounced first
    assert np.all(log["time"][log["kind"] == EV_WALL] <= lands[0])  # the last one lands it
    after = frames["time"] > lands[0]
    assert after.sum() > 500
    t = frames["time"][after]
    gap = frames["position"][after, 0, 2] - RADIUS - plate_height(t, amp, 0.3)
    assert gap.min() >= -ROUND_POS
    assert gap.max() <= 0.5 * amp * RIDE_STEP**3
    np.testing.assert_allclose(frames["velocity"][after, 0, 2], plate_speed(t, amp, 0.3),
                               rtol=0, atol=amp * OMEGA * RIDE_STEP**2)
    assert np.all(frames["motion_state"][after, 0] == MS_ROLLING)  # carried: it moves
    # a segment per RIDE_STEP of phase, and nothing else
    per_second = summary.events["state"] / (1.0 - lands[0])
    assert per_second == pytest.approx(OMEGA / RIDE_STEP, rel=0.01)


def inelastic_map(amp, phase, t_end):
    """Impacts and take-offs of a completely inelastic ball (e = 0) that starts on the plate
    z = A [sin(ω t + φ) − sin φ] at t = 0: it rides while the load g − A ω² sin θ is positive,
    takes off where sin θ reaches 1/Γ, flies on a parabola (the impact is the first root of
    ball − plate on a grid of 1/4000 period, polished by Brent's method to 1e-15 s), and at
    impact takes the plate's speed: it rides if the load is positive then, else flies on.
    An oracle independent of hsgran's segments and contact search."""
    gamma = amp * OMEGA**2 / G
    rise = math.asin(1.0 / gamma)
    takeoffs, impacts = [], []
    t = 0.0
    riding = G - amp * OMEGA**2 * math.sin(phase) > 0.0
    while t < t_end:
        if riding:
            theta = OMEGA * t + phase
            m = (theta - rise) % (2 * math.pi)
            if m > math.pi - 2 * rise:
                t += (2 * math.pi - m) / OMEGA  # the next window where the plate pulls away
            takeoffs.append(t)
        t0 = t
        z0 = float(plate_height(t0, amp, phase))
        v0 = float(plate_speed(t0, amp, phase))

        def gap(s, t0=t0, z0=z0, v0=v0):
            tau = s - t0
            return z0 + v0 * tau - 0.5 * G * tau * tau - plate_height(s, amp, phase)

        step = 1.0 / FREQ / 4000
        a = t0 + 1e-7
        while gap(a + step) > 0.0:
            a += step
        t = brentq(gap, a, a + step, xtol=1e-15, rtol=1e-15)
        impacts.append(t)
        riding = G - amp * OMEGA**2 * math.sin(OMEGA * t + phase) > 0.0
    return np.array(takeoffs), np.array(impacts)


@pytest.mark.parametrize(("gamma", "phase"), [(1.5, 0.3), (2.0, 1.0), (3.0, 2.0)])
def test_a_completely_inelastic_ball_takes_off_where_the_plate_outruns_gravity(gamma, phase):
    """e = 0: each impact ends the bounce, and the ball leaves the plate exactly where the
    plate's downward acceleration reaches g (sin θ = 1/Γ). Take-off and impact times follow
    the exact map to 1e-13 s (measured: 1.3e-16 s)."""
    amp = gamma * G / OMEGA**2
    duration = 0.6
    _, _, log = run(plate_scene(amp=amp, phase=phase, z0=RADIUS, duration=duration, e=0.0,
                                w=float(plate_speed(0.0, amp, phase))))
    takeoffs, impacts = inelastic_map(amp, phase, duration)
    got_off = log["time"][(log["kind"] == EV_STATE) & (log["regime"] == END_TAKEOFF)]
    got_hit = log["time"][log["kind"] == EV_WALL]
    n = min(len(got_hit), len(impacts[impacts < duration]))
    assert n >= 5
    np.testing.assert_allclose(got_hit[:n], impacts[:n], rtol=0, atol=1e-13)
    m = min(len(got_off), len(takeoffs[takeoffs < duration]))
    assert m >= 5
    np.testing.assert_allclose(got_off[:m], takeoffs[:m], rtol=0, atol=1e-13)
    # every take-off at the phase where the plate pulls away at g
    np.testing.assert_allclose(np.sin(OMEGA * got_off + phase), 1.0 / gamma, atol=1e-9)


def test_friction_under_the_load_of_a_vibrating_plate():
    """A ball sliding on a plate vibrating along its normal (Γ = 0.8) is slowed by μ λ(t),
    λ = g + s̈ the load in the plate's frame: with no spin at first, its slip falls as
    u = v₀ − (1 + 1/k) μ J(t) with J(t) = ∫ λ dt = g t + ṡ(t) − ṡ(0), and it rolls from
    J = v₀/(3.5 μ) on at 5/7 v₀ (k = 2/5)."""
    amp, phase, mu, v0 = 0.8 * G / OMEGA**2, 0.7, 0.05, 0.05
    _, frames, log = run(plate_scene(
        amp=amp, phase=phase, z0=RADIUS, duration=0.4, e=0.0, u=v0,
        w=float(plate_speed(0.0, amp, phase)), effects='["gravity", "rotation", "friction"]',
        friction=f"sliding_friction = {mu}"))

    def impulse(t):
        return G * t + plate_speed(t, amp, phase) - plate_speed(0.0, amp, phase)

    t_roll = brentq(lambda t: impulse(t) - v0 / (3.5 * mu), 1e-6, 1.0, xtol=1e-15)
    rolls = log["time"][(log["kind"] == EV_STATE) & (log["regime"] == END_SLIP)]
    assert rolls.shape == (1,)
    assert rolls[0] == pytest.approx(t_roll, rel=1e-6)
    t = frames["time"]
    sliding = t < t_roll
    np.testing.assert_allclose(frames["velocity"][sliding, 0, 0],
                               v0 - mu * impulse(t[sliding]), rtol=0, atol=1e-6 * v0)
    np.testing.assert_allclose(frames["velocity"][~sliding, 0, 0], 5 / 7 * v0, rtol=1e-6)
    assert np.all(frames["motion_state"][:, 0] != MS_FLIGHT)


def test_a_ball_on_a_plate_shaken_sideways_rolls_at_two_sevenths_of_its_speed():
    """A plate shaken along itself (d ⟂ n) drags a ball resting on it by friction; rolling
    without slip, the ball's centre moves at k/(1 + k) = 2/7 of the plate's speed (its
    relative acceleration is −s̈/(1 + k)). Started at rest with the plate at rest (φ = π/2):
    x = 2/7 s(t), within the bound of the segments' mean frame acceleration."""
    amp = 5.0 / OMEGA**2  # A ω² = 5 m/s², 2/7 of it well within μ g
    phase = math.pi / 2
    _, frames, _ = run(plate_scene(
        amp=amp, phase=phase, z0=RADIUS, duration=0.5, e=0.0,
        effects='["gravity", "rotation", "friction"]', friction="sliding_friction = 0.5",
        direction="[1.0, 0.0, 0.0]"))
    t = frames["time"]
    x = frames["position"][:, 0, 0]
    np.testing.assert_allclose(x, 2 / 7 * plate_height(t, amp, phase), rtol=0,
                               atol=amp * RIDE_STEP**2)
    np.testing.assert_allclose(frames["velocity"][:, 0, 0],
                               2 / 7 * plate_speed(t, amp, phase), rtol=0,
                               atol=amp * OMEGA * RIDE_STEP**2)
    np.testing.assert_allclose(frames["position"][:, 0, 2], RADIUS, rtol=0, atol=ROUND_POS)


PISTON = """
[scene]
name = "ball on a lift"
duration = 0.5
gravity = [0.0, 0.0, -9.81]
effects = ["gravity"]
[output]
frame_interval = 0.002
[[contacts]]
between = ["steel", "steel"]
restitution = 0.0
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "steel"
motion = { kind = "velocity", velocity = [0.0, 0.0, 0.1], travel = 0.01, start = 0.05 }
[[particles]]
material = "steel"
radius = 0.005
position = [0.0, 0.0, 0.005]
velocity = [0.0, 0.0, 0.0]
"""


def test_a_piston_lifts_a_ball_and_throws_it():
    """A ball resting on a piston (e = 0) is hit when it starts at V = 0.1 m/s, rides it up
    for 0.1 s, flies on when it stops (apex V²/2g higher), and lands back on it to rest."""
    _, frames, log = run(PISTON)
    start, stop, speed = 0.05, 0.15, 0.1
    t = frames["time"]
    z = frames["position"][:, 0, 2] - RADIUS
    lifted = (t > start) & (t <= stop)
    np.testing.assert_allclose(z[t <= start], 0.0, atol=ROUND_POS)
    np.testing.assert_allclose(z[lifted], speed * (t[lifted] - start), rtol=0, atol=ROUND_POS)
    fall = stop + 2 * speed / G
    flying = (t > stop) & (t < fall)
    tau = t[flying] - stop
    np.testing.assert_allclose(z[flying], 0.01 + speed * tau - 0.5 * G * tau**2, rtol=0,
                               atol=1e-14)
    np.testing.assert_allclose(z[t > fall + 1e-9], 0.01, atol=ROUND_POS)
    hits = log["time"][log["kind"] == EV_WALL]
    np.testing.assert_allclose(hits, [start, fall], rtol=0, atol=1e-12)
