"""Outlets (docs/open-systems.md): the entry time against a sampled search and closed forms, the
removal (frames, event log, energy ledger, the spheres it held up), checkpoints, the file and
its readers, and the scene keys."""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest

from hsgran.animation import Playback
from hsgran.api import run_scene
from hsgran.engine import Simulation
from hsgran.errors import InputError
from hsgran.events.kinds import EV_EXIT, EV_PAIR, EV_WALL
from hsgran.fields import profiles
from hsgran.io.h5md import read_trajectory
from hsgran.onplane import MS_ABSENT, MS_ROLLING
from hsgran.outlets import (
    OL_A,
    OL_B,
    OL_KIND,
    OL_SIZE,
    OUT_BELOW,
    OUT_BOX,
    inside_outlet,
    outlet_entry_time,
)
from hsgran.scene import Outlet, parse_scene
from tests.observers import Keep
from tests.test_enduring import CLOSED_FORM_RTOL, incline

G = 9.81  #: [m/s²]
#: A root of a quadratic evaluated without cancellation: a few ulps of the time (relative).
ROOT_RTOL = 1e-12
#: How far the centre at a predicted entry may lie outside the region [m]: the rounding of a
#: root, for coordinates and times of order 1.
ON_BOUNDARY = 1e-12
#: Times from the cluster treatment's constrained motion, whose accelerations come from a
#: Gauss–Seidel solve to its tolerance (docs/enduring-contact.md) [-].
CLUSTER_RTOL = 1e-6


def outlet_row(kind, a, b):
    row = np.zeros(OL_SIZE)
    row[OL_KIND] = kind
    row[OL_A:OL_A + 3] = a
    row[OL_B:OL_B + 3] = b
    return row


# ---- the entry time ----------------------------------------------------------------------

@pytest.mark.parametrize("kind", [OUT_BELOW, OUT_BOX])
@pytest.mark.parametrize("gravity", [False, True], ids=["line", "parabola"])
def test_the_entry_time_is_the_first_instant_inside(kind, gravity):
    """Random lines and parabolas against random half-spaces and boxes: the centre is inside
    (on the boundary) at the predicted instant, and no sampled instant before it is inside;
    a path that a sample finds inside has a predicted entry no later than that sample."""
    rng = np.random.default_rng(27 + kind + 2 * gravity)
    ts = np.linspace(0.0, 3.0, 30001)
    entered = drawn = 0
    for _ in range(300):
        if kind == OUT_BOX:
            lo = rng.uniform(-1.0, 0.0, 3)
            hi = lo + rng.uniform(0.05, 1.0, 3)
            row = outlet_row(OUT_BOX, lo, hi)
            aim = rng.uniform(lo, hi)
        else:
            n = rng.normal(size=3)
            n /= np.linalg.norm(n)
            row = outlet_row(OUT_BELOW, rng.uniform(-1.0, 1.0, 3), n)
            aim = row[OL_A:OL_A + 3] - 0.3 * n
        # aimed at the region, more or less: most paths enter it, some graze or miss
        x = rng.uniform(-2.0, 2.0, 3)
        g = rng.uniform(-3.0, 3.0, 3) if gravity else np.zeros(3)
        arrival = rng.uniform(0.3, 2.5)
        u = (aim - x) / arrival - 0.5 * g * arrival + rng.normal(0.0, 0.1, 3)
        if inside_outlet(row, x):
            continue
        drawn += 1
        tau = outlet_entry_time(*x, *u, *g, row[None], 0)
        path = x + np.outer(ts, u) + 0.5 * np.outer(ts**2, g)
        inside = inside_outlet(row, path)
        if math.isfinite(tau):
            at = x + tau * u + 0.5 * tau**2 * g
            lo, hi = (row[OL_A:OL_A + 3], row[OL_B:OL_B + 3])
            if kind == OUT_BOX:
                assert np.all(at >= lo - ON_BOUNDARY)
                assert np.all(at <= hi + ON_BOUNDARY)
            else:
                assert abs((at - lo) @ hi) <= ON_BOUNDARY
            assert not inside[ts < tau * (1.0 - 1e-9)].any()
            entered += tau <= ts[-1]
        if inside.any():
            assert tau <= ts[np.argmax(inside)]
    assert entered >= drawn / 3  # the draws do reach the outlets


def test_a_centre_inside_enters_now():
    row = outlet_row(OUT_BOX, (0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    assert outlet_entry_time(0.5, 0.5, 0.5, 9.0, 0.0, 0.0, 0.0, 0.0, -9.81, row[None], 0) == 0.0
    below = outlet_row(OUT_BELOW, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    assert outlet_entry_time(0.0, 0.0, -1e-3, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, below[None], 0) == 0.0


def test_a_path_through_a_box_edge_enters_it():
    """Entering exactly through an edge: the two faces' roots agree only to rounding."""
    row = outlet_row(OUT_BOX, (1.0, 1.0, -1.0), (2.0, 2.0, 1.0))
    tau = outlet_entry_time(0.0, 0.0, 0.0, 0.1, 0.1, 0.0, 0.0, 0.0, 0.0, row[None], 0)
    assert tau == pytest.approx(10.0, rel=ROOT_RTOL)


# ---- runs --------------------------------------------------------------------------------

DROP = """
[scene]
name = "drop through an outlet"
duration = {duration}
effects = ["gravity"]
[output]
frame_interval = 0.01
[[particles]]
material = "steel"
radius = 0.002
position = [0.0, 0.0, {z0}]
velocity = [{vx}, 0.0, 0.0]
[[particles]]
material = "steel"
radius = 0.002
position = [0.05, 0.0, 0.3]
[[outlets]]
kind = "below"
point = [0.0, 0.0, {h}]
normal = [0.0, 0.0, 1.0]
"""


def run(scene, **kw):
    sim = Simulation(scene, log_events=True)
    keep = Keep()
    sim.run(observers=[keep], **kw)
    return sim, keep


def test_a_falling_sphere_leaves_at_the_closed_form_time_with_its_velocity():
    z0, h, vx = 0.1, 0.05, 0.3
    sim, keep = run(parse_scene(DROP.format(duration=0.3, z0=z0, h=h, vx=vx)))
    kind, i = keep.log("kind"), keep.log("i")
    exits = kind == EV_EXIT
    assert i[exits].tolist() == [0, 1]
    t_exit = math.sqrt(2.0 * (z0 - h) / G)
    assert keep.log("time")[exits][0] == pytest.approx(t_exit, rel=ROOT_RTOL)
    assert keep.log("time")[exits][1] == pytest.approx(math.sqrt(2.0 * (0.3 - h) / G),
                                                       rel=ROOT_RTOL)
    np.testing.assert_allclose(keep.log("velocity")[exits][0], (vx, 0.0, -G * t_exit),
                               rtol=ROOT_RTOL)
    assert keep.log("j")[exits].tolist() == [0, 0]
    # frames after the exit: NaN, id −1, motion state absent
    time, ids = keep.cat("time"), keep.cat("id")
    after = time > t_exit
    assert np.all(ids[~after, 0] == 0)
    assert np.all(ids[after, 0] == -1)
    assert np.isnan(keep.cat("position")[after, 0]).all()
    assert np.all(keep.cat("motion_state")[after, 0] == MS_ABSENT)
    assert sim.present.tolist() == [0, 0]
    # energy: nothing dissipated, all of it carried out
    m = sim.mass
    e0 = float(m[0] * G * z0 + m[1] * G * 0.3 + 0.5 * m[0] * vx**2)
    assert sim.exited_energy == pytest.approx(e0, rel=1e-12)
    assert abs(sim.dissipated_energy()) <= 1e-12 * e0
    assert np.all(np.abs(keep.cat("dissipated")) <= 1e-12 * e0)
    assert sim.counts[EV_EXIT] == 2


def test_a_sphere_rolling_down_an_incline_leaves_at_the_rolling_time():
    """From an on-plane motion state: rolling at a = 5/7 g sin θ, the centre reaches the box
    a distance L down the fall line at √(2L/a)."""
    scene, th = incline(20.0, 0.3, 0.0)
    length = 0.02
    x0 = scene.position[0]
    scene.outlets = (Outlet(outlet_row(OUT_BOX, (x0[0] + length * math.cos(th), -1.0, -1.0),
                                       (1.0, 1.0, 1.0)), "outlets[0]"),)
    _sim, keep = run(scene, until=0.5)
    assert keep.log("stage")[keep.log("kind") == EV_EXIT].tolist() == [MS_ROLLING]
    a = 5.0 / 7.0 * G * math.sin(th)
    t = keep.log("time")[keep.log("kind") == EV_EXIT][0]
    assert t == pytest.approx(math.sqrt(2.0 * length / a), rel=CLOSED_FORM_RTOL)


PAIR_ON_INCLINE = """
[scene]
name = "two spheres roll into an outlet"
duration = 0.6
effects = ["gravity", "rotation", "friction"]
[output]
frame_interval = 0.05
[enduring_contact]
treatment = "{treatment}"
[materials.m]
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3
[[contacts]]
between = ["m", "m"]
sliding_friction = 0.3
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [{nx}, 0.0, {nz}]
material = "m"
[[particles]]
material = "m"
radius = {r}
position = [{x0}, 0.0, {z0}]
[[particles]]
material = "m"
radius = {r}
position = [{x1}, 0.0, {z1}]
[[outlets]]
kind = "box"
lower = [{edge}, -1.0, -1.0]
upper = [1.0, 1.0, 1.0]
"""


@pytest.mark.parametrize("treatment", ["pairwise", "clusters"])
def test_two_touching_spheres_roll_into_an_outlet_one_after_the_other(treatment):
    """Two spheres touching along the fall line roll together at 5/7 g sin θ (no force between
    them); the lower one leaves a distance L down, the upper one 2R later, and its motion does
    not change when its neighbour leaves (with clusters it is solved again, alone)."""
    th, r, length = math.radians(15.0), 0.005, 0.03
    n = np.array([math.sin(th), 0.0, math.cos(th)])  # downhill is +x
    uphill = np.array([-math.cos(th), 0.0, math.sin(th)])
    c0 = r * n
    c1 = c0 + 2.0 * r * uphill
    scene = parse_scene(PAIR_ON_INCLINE.format(
        treatment=treatment, nx=n[0], nz=n[2], r=r, x0=c0[0], z0=c0[2], x1=c1[0], z1=c1[2],
        edge=c0[0] + length * math.cos(th)))
    _, keep = run(scene)
    exits = keep.log("kind") == EV_EXIT
    assert keep.log("i")[exits].tolist() == [0, 1]
    a = 5.0 / 7.0 * G * math.sin(th)
    # the clusters' constrained motion comes from an iterative solve (its tolerance)
    rtol = CLOSED_FORM_RTOL if treatment == "pairwise" else CLUSTER_RTOL
    np.testing.assert_allclose(keep.log("time")[exits],
                               [math.sqrt(2.0 * length / a),
                                math.sqrt(2.0 * (length + 2.0 * r) / a)], rtol=rtol)


GAS = """
[scene]
name = "an elastic gas drains"
duration = {duration}
effects = []
seed = 5
[output]
frame_interval = 0.005
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.02, 0.02, 0.02]
material = "steel"
[[fill]]
count = 150
material = "glass"
radius = 0.0006
region = {{ lower = [0.0, 0.0, 0.006], upper = [0.02, 0.02, 0.02] }}
speed = 0.5
[[outlets]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.006, 0.006, 0.004]
"""


def test_an_elastic_gas_drains_and_the_spheres_that_left_never_meet_anything():
    sim, keep = run(parse_scene(GAS.format(duration=0.3)))
    kind, i, j, t = keep.log("kind"), keep.log("i"), keep.log("j"), keep.log("time")
    exit_time = dict(zip(i[kind == EV_EXIT].tolist(), t[kind == EV_EXIT].tolist(), strict=True))
    assert 20 <= len(exit_time) < 150
    assert len(set(i[kind == EV_EXIT].tolist())) == len(exit_time)  # each leaves once
    for row in np.flatnonzero((kind == EV_PAIR) | (kind == EV_WALL)):
        for s in (i[row], j[row] if kind[row] == EV_PAIR else -1):
            assert s not in exit_time or t[row] <= exit_time[s]
    # the count in the system never grows; the frames agree with the log
    present = keep.cat("id") >= 0
    assert np.all(keep.cat("motion_state")[~present] == MS_ABSENT)
    counts = present.sum(axis=1)
    assert np.all(np.diff(counts) <= 0)
    for f, tf in enumerate(keep.cat("time")):
        gone = {s for s, te in exit_time.items() if te <= tf}
        assert set(np.flatnonzero(~present[f]).tolist()) == gone
    # every sphere that left stays where it left: on the outlet box's boundary (to rounding)
    row = sim.scene.outlets[0].row
    left = sim.pos[i[kind == EV_EXIT]]
    outside = np.maximum(row[OL_A:OL_A + 3] - left, left - row[OL_B:OL_B + 3]).max(axis=1)
    assert np.all(np.abs(outside) <= 1e-12)
    # elastic collisions: nothing dissipated, the energy that left is booked apart
    e0 = sim.energy0
    assert sim.exited_energy > 0.05 * e0
    assert np.all(np.abs(keep.cat("dissipated")) <= 1e-9 * e0)


def test_a_run_with_exits_continues_bit_for_bit_from_a_checkpoint():
    scene = parse_scene(GAS.format(duration=0.2))
    whole, keep = Simulation(scene), Keep()
    keep.checkpoints = []
    keep.on_checkpoint = keep.checkpoints.append
    whole.run(observers=[keep], checkpoint_every=0.05)
    ids = keep.cat("id")
    ck = keep.checkpoints[2]
    again, k2 = Simulation(scene), Keep()
    again.restore(ck)
    again.run(observers=[k2])
    np.testing.assert_array_equal(whole.state, again.state)
    np.testing.assert_array_equal(whole.present, again.present)
    np.testing.assert_array_equal(ids[ck.frames:], k2.cat("id"))
    assert again.exited_energy == whole.exited_energy
    assert (ids < 0).any()


def test_the_file_marks_absent_particles_and_every_reader_leaves_them_out(tmp_path):
    path = tmp_path / "gas.h5"
    run_scene(parse_scene(GAS.format(duration=0.2)), path, log_events=True)
    with h5py.File(path, "r") as f:
        assert f["particles/all/id/value"].fillvalue == -1
        assert f["hsgran/events/velocity"].shape[1:] == (3,)
    traj = read_trajectory(path)
    present = traj.present
    assert present[0].all()
    assert not present[-1].all()
    assert np.isnan(traj.position[~present]).all()
    assert "exited_energy" in traj.energies
    exits = traj.events["kind"] == EV_EXIT
    assert exits.sum() == (~present[-1]).sum()
    # the movie's playback hides them and keeps every drawn coordinate finite
    play = Playback(traj, color_by="speed")
    state = play.frame(float(traj.time[-1]))
    assert state.shown.tolist() == present[-1].tolist()
    assert np.isfinite(state.position).all()
    assert np.isfinite(state.values).all()
    # slab profiles count only the particles in the system
    prof = profiles(traj, axis="z", bins=4, start=float(traj.time[-1]))
    assert prof.mass.sum() == pytest.approx(traj.mass[present[-1]].sum(), rel=1e-12)


def test_scenes_without_outlets_write_no_id():
    sim, keep = run(parse_scene(DROP.format(duration=0.05, z0=0.1, h=0.05, vx=0.0).split(
        "[[outlets]]")[0]))
    assert keep.frames[0].id is None
    assert keep.frames[0].exited is None
    assert sim.present.shape == (0,)


# ---- the scene keys ----------------------------------------------------------------------

BASE = DROP.format(duration=0.1, z0=0.1, h=0.05, vx=0.0).split("[[outlets]]")[0]


@pytest.mark.parametrize(("table", "key", "needle"), [
    ('kind = "hole"', "outlets[0].kind", "unknown outlet kind 'hole'"),
    ('kind = "below"\npoint = [0, 0, 0]', "outlets[0].normal", "missing"),
    ('kind = "below"\npoint = [0, 0, 0]\nnormal = [0, 0, 0]', "outlets[0].normal", "non-zero"),
    ('kind = "box"\nlower = [0, 0, 0]\nupper = [1, 1, 0]', "outlets[0].upper", "must exceed"),
    ('kind = "box"\nlower = [0, 0, 0]\nupper = [1, 1, 1]\nnormal = [0, 0, 1]',
     "outlets[0].normal", "unknown key"),
    ('kind = "below"\npoint = [0, 0, 0.2]\nnormal = [0, 0, 1]', "particles[0].position",
     "starts inside outlet outlets[0]"),
])
def test_bad_outlets_are_refused_naming_the_key(table, key, needle):
    with pytest.raises(InputError) as err:
        parse_scene(BASE + "[[outlets]]\n" + table + "\n")
    assert err.value.key == key
    assert needle in str(err.value)


# ---- inflow ------------------------------------------------------------------------------

POURED = """
[scene]
name = "an inflow into an elastic gas"
duration = {duration}
effects = []
seed = 11
[output]
frame_interval = 0.01
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.03, 0.03, 0.03]
material = "steel"
[[fill]]
count = 30
material = "glass"
radius = 0.0008
region = {{ lower = [0.0, 0.0, 0.0], upper = [0.03, 0.03, 0.015] }}
speed = 0.3
[[inflow]]
count = {count}
material = "steel"
radius = [0.0005, 0.001]
region = {{ lower = [0.0, 0.0, 0.02], upper = [0.03, 0.03, 0.03] }}
rate = {rate}
interval = {interval}
start = 0.005
velocity = [0.0, 0.0, -0.2]
speed = 0.1
{extra}
"""


def poured(duration=0.2, count=60, rate=500.0, interval=0.01, extra=""):
    return parse_scene(POURED.format(duration=duration, count=count, rate=rate,
                                     interval=interval, extra=extra))


def test_an_inflow_inserts_its_spheres_at_its_rate_clear_of_the_others():
    scene = poured()
    assert scene.n == 90
    assert not scene.present[30:].any()
    assert np.isnan(scene.position[30:]).all()
    sim, keep = run(scene)
    time, ids, pos = keep.cat("time"), keep.cat("id"), keep.cat("position")
    # batch k at 0.005 + 0.01 k brings the count up to round(500 × 0.01 × (k + 1)) = 5 (k + 1)
    inserted = (ids[:, 30:] >= 0).sum(axis=1)
    expect = np.minimum(60, 5 * np.floor((time - 0.005) / 0.01 + 1).clip(0))
    np.testing.assert_array_equal(inserted, expect)
    # once in, a sphere of the inflow stays (no outlet here)
    assert np.all(np.diff((ids[:, 30:] >= 0).astype(int), axis=0) >= 0)
    # no overlap in any frame among the spheres in the system
    radius = sim.radius
    for f in range(len(time)):
        here = np.flatnonzero(ids[f] >= 0)
        p = pos[f, here]
        d = np.linalg.norm(p[:, None] - p[None], axis=-1)
        sigma = radius[here, None] + radius[None, here]
        np.fill_diagonal(d, np.inf)
        assert np.all(d >= sigma * (1.0 - 1e-9))
    # elastic: the energy they brought in is kept, nothing is dissipated
    assert sim.entered_energy > 0.0
    assert np.all(np.abs(keep.cat("dissipated")) <= 1e-9 * (sim.energy0 + sim.entered_energy))


def test_an_inserted_sphere_flies_from_its_batch_on_a_straight_line():
    """The first frame after its batch shows a sphere where its velocity took it (no
    gravity; the 5 ms between the batch and the frame are too short to reach anything)."""
    scene = poured(duration=0.02, extra="")
    sim, keep = run(scene)
    time, ids, pos, vel = (keep.cat(n) for n in ("time", "id", "position", "velocity"))
    f = int(np.flatnonzero(time > 0.005)[0])  # the frame at 0.01 s
    new = np.flatnonzero(ids[f, 30:] >= 0) + 30
    assert new.size == 5
    start = pos[f, new] - vel[f, new] * (time[f] - 0.005)
    lo, hi = np.array([0.0, 0.0, 0.02]), np.array([0.03, 0.03, 0.03])
    r = sim.radius[new, None]
    assert np.all(start >= lo + r - 1e-12)
    assert np.all(start <= hi - r + 1e-12)
    np.testing.assert_allclose(np.linalg.norm(vel[f, new] - (0.0, 0.0, -0.2), axis=1), 0.1,
                               rtol=1e-12)


def test_a_crowded_inflow_waits_for_room():
    """A region with room for a few spheres at a time: the batches insert what fits and the
    rest waits; never an overlap, and all go in eventually."""
    scene = parse_scene(POURED.format(duration=0.3, count=30, rate=3000.0, interval=0.01,
                                      extra="").replace(
        "upper = [0.03, 0.03, 0.03] }\nrate", "upper = [0.003, 0.003, 0.03] }\nrate"))
    _sim, keep = run(scene)
    ids = keep.cat("id")
    inserted = (ids[:, 30:] >= 0).sum(axis=1)
    assert inserted[1] < 30  # the first batch did not fit them all
    assert inserted[-1] == 30
    assert np.all(np.diff(inserted) >= 0)


RECIRCULATED = """
[scene]
name = "a gas that leaves through an outlet and comes back"
duration = {duration}
effects = []
seed = 3
[output]
frame_interval = 0.01
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.02, 0.02, 0.04]
material = "steel"
[[fill]]
count = 40
material = "glass"
radius = 0.0007
region = {{ lower = [0.0, 0.0, 0.01], upper = [0.02, 0.02, 0.03] }}
speed = 0.5
[[outlets]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.02, 0.02, 0.004]
[[inflow]]
recirculate = true
region = {{ lower = [0.0, 0.0, 0.034], upper = [0.02, 0.02, 0.04] }}
rate = 2000.0
interval = 0.01
velocity = [0.0, 0.0, -0.3]
"""


def test_recirculation_brings_the_spheres_that_left_back_and_the_table_stays_the_same():
    scene = parse_scene(RECIRCULATED.format(duration=0.4))
    assert scene.n == 40
    sim, keep = run(scene)
    ids = keep.cat("id")
    kind, i = keep.log("kind"), keep.log("i")
    left = i[kind == EV_EXIT]
    assert left.size > 40  # more exits than spheres: they came back and left again
    back = [s for s in set(left.tolist()) if ids[-1, s] >= 0 or (left == s).sum() > 1]
    assert back
    # a sphere is out of the system from its exit until the next batch at most
    gone = (ids < 0).sum(axis=1)
    assert gone.max() < 40
    e_in, e_out = sim.entered_energy, sim.exited_energy
    assert e_in > 0.0
    assert e_out > 0.0
    assert np.all(np.abs(keep.cat("dissipated")) <= 1e-9 * (sim.energy0 + e_in))


def test_an_inflow_continues_bit_for_bit_from_a_checkpoint():
    scene = poured(duration=0.12)
    whole, keep = Simulation(scene), Keep()
    keep.checkpoints = []
    keep.on_checkpoint = keep.checkpoints.append
    whole.run(observers=[keep], checkpoint_every=0.031)
    ck = keep.checkpoints[1]
    again, k2 = Simulation(scene), Keep()
    again.restore(ck)
    again.run(observers=[k2])
    np.testing.assert_array_equal(whole.state, again.state)
    np.testing.assert_array_equal(whole.inflow_state, again.inflow_state)
    np.testing.assert_array_equal(keep.cat("id")[ck.frames:], k2.cat("id"))


@pytest.mark.parametrize(("extra", "key", "needle"), [
    ("recirculate = true", "inflow[0].count", "remove 'count'"),
    ("recirculate = 1", "inflow[0].recirculate", "true or false"),
    ('[[outlets]]\nkind = "below"\npoint = [0, 0, 0.025]\nnormal = [0, 0, -1]',
     "inflow[0].region", "reaches into outlet outlets[0]"),
])
def test_bad_inflows_are_refused_naming_the_key(extra, key, needle):
    with pytest.raises(InputError) as err:
        poured(extra=extra)
    assert err.value.key == key
    assert needle in str(err.value)


def test_observables_and_periodic_boxes_of_open_systems_are_refused():
    with pytest.raises(InputError) as err:
        parse_scene(GAS.format(duration=0.1).replace("frame_interval = 0.005",
                                                      "frame_interval = 0.005\nobservables = true"))
    assert err.value.key == "output.observables"
    periodic = GAS.format(duration=0.1).replace("seed = 5", "seed = 5\nperiodic = [true, false, "
                                                "false]").replace(
        "lower = [0.0, 0.0, 0.0]\nupper = [0.006, 0.006, 0.004]",
        "lower = [-0.001, 0.0, 0.0]\nupper = [0.006, 0.006, 0.004]")
    with pytest.raises(InputError) as err:
        parse_scene(periodic)
    assert err.value.key == "outlets[0].upper"


def test_an_inflow_needs_a_rate():
    with pytest.raises(InputError) as err:
        parse_scene(POURED.format(duration=0.1, count=5, rate=1.0, interval=0.01, extra="")
                    .replace("rate = 1.0\n", ""))
    assert err.value.key == "inflow[0].rate"
