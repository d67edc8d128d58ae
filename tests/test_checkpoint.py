"""Nothing lost: checkpoints, resume, interrupts, crash-safe output (issue 8).

The claim under test is strong: a run cut anywhere, by anything, and resumed gives the same
trajectory, bit for bit, as a run never cut. The pile scenes below exercise every motion state
(flight, sliding, rolling, rest, sleepers) and the event log, so every array the engine keeps
has to come back exactly.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

import hsgran
from hsgran.api import resume_run, run_scene
from hsgran.engine import Simulation
from hsgran.io.h5md import read_checkpoint, read_trajectory
from hsgran.materials import P_MU_S
from hsgran.scene import parse_scene
from tests.cli_errors import run_error

NOJIT = os.environ.get("NUMBA_DISABLE_JIT") == "1"

#: Spheres of the pile that a subprocess runs: enough that the run lasts ~10x longer than the
#: test waits before it kills it (the pure-Python engine of NUMBA_DISABLE_JIT=1 is ~100x slower).
PILE_SPHERES = 40 if NOJIT else 400
#: Simulated time between checkpoints of the subprocess runs [s].
CHECKPOINT_EVERY = 0.002
#: Longest wait for a subprocess to store its first checkpoint [s].
FIRST_CHECKPOINT_TIMEOUT = 120.0
#: Random delay before a kill, after the first checkpoint is seen [s].
KILL_DELAY = (0.0, 1.5)
#: Simulated time a resumed run goes past its checkpoint [s] (several checkpoints and frames).
RESUME_SPAN = 0.005


def pile(count: int, duration: float = 2.0, box_mm: float = 10.0) -> str:
    """A pour of ``count`` steel spheres into a glass box, with every mechanical effect."""
    return f"""
[scene]
name = "checkpoint pile"
duration = {duration}
gravity = [0.0, 0.0, -9.81]
effects = ["gravity", "rotation", "friction", "rolling_resistance", "plasticity"]
seed = 11
[output]
frame_interval = 0.0005
[[contacts]]
between = ["steel", "steel"]
sliding_friction = 0.2
rolling_friction = 0.002
[[contacts]]
between = ["steel", "glass"]
sliding_friction = 0.3
rolling_friction = 0.002
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [{box_mm / 1000}, {box_mm / 1000}, 0.04]
material = "glass"
[[fill]]
count = {count}
material = "steel"
radius = [0.0004, 0.0006]
region = {{ lower = [0.0, 0.0, 0.002], upper = [{box_mm / 1000}, {box_mm / 1000}, 0.04] }}
speed = 0.05
"""


def same_file(a, b) -> None:
    """Every frame, energy and logged event of two trajectories is bit for bit the same."""
    ta, tb = read_trajectory(a), read_trajectory(b)
    assert ta.n_frames == tb.n_frames
    for name in ("time", "step", "position", "velocity", "angular_velocity", "motion_state"):
        np.testing.assert_array_equal(getattr(ta, name), getattr(tb, name), err_msg=name)
    assert ta.energies.keys() == tb.energies.keys()
    for name in ta.energies:
        np.testing.assert_array_equal(ta.energies[name], tb.energies[name], err_msg=name)
    assert ta.sums.keys() == tb.sums.keys()
    for name in ta.sums:
        np.testing.assert_array_equal(ta.sums[name], tb.sums[name], err_msg=name)
    assert (ta.events is None) == (tb.events is None)
    for name in ta.events or {}:
        np.testing.assert_array_equal(ta.events[name], tb.events[name], err_msg=name)


class Keep:
    """Observer keeping every frame block and checkpoint in memory."""

    def __init__(self):
        self.positions, self.checkpoints = [], []

    def on_frames(self, block):
        self.positions.append(block.position)

    def on_checkpoint(self, ck):
        self.checkpoints.append(ck)


def test_a_run_cut_at_checkpoints_is_bit_for_bit_the_run_not_cut():
    scene = parse_scene(pile(30, duration=0.06))
    whole, cut = Simulation(scene, log_events=True), Simulation(scene, log_events=True)
    kw, kc = Keep(), Keep()
    whole.run(observers=[kw])
    cut.run(observers=[kc], checkpoint_every=0.0037, checkpoint_wall=0.0)
    assert len(kc.checkpoints) >= 16  # every 3.7 ms, every call, and the end
    np.testing.assert_array_equal(whole.state, cut.state)
    np.testing.assert_array_equal(whole.omg, cut.omg)
    np.testing.assert_array_equal(whole.counts, cut.counts)
    np.testing.assert_array_equal(np.concatenate(kw.positions), np.concatenate(kc.positions))


def test_a_restored_checkpoint_continues_bit_for_bit():
    scene = parse_scene(pile(30, duration=0.06))
    whole, keep = Simulation(scene), Keep()
    whole.run(observers=[keep], checkpoint_every=0.01)
    frames = np.concatenate(keep.positions)
    for ck in keep.checkpoints[1:-1:2]:
        again, k2 = Simulation(scene), Keep()
        again.restore(ck)
        again.run(observers=[k2])
        np.testing.assert_array_equal(whole.state, again.state)
        np.testing.assert_array_equal(whole.mstate, again.mstate)
        np.testing.assert_array_equal(frames[ck.frames:], np.concatenate(k2.positions))


def test_the_observables_continue_bit_for_bit_from_a_checkpoint():
    """The momentum ledgers and the open interval's sums are part of the checkpoint."""
    scene = parse_scene(pile(30, duration=0.06).replace(
        "frame_interval = 0.0005", "frame_interval = 0.0005\nobservables = true"))
    names = ("impulse_moment", "wall_impulse", "unresolved_impulse", "collisions")

    class Sums(Keep):
        def on_frames(self, block):
            self.positions.append([getattr(block, name) for name in names])

    whole, keep = Simulation(scene), Sums()
    whole.run(observers=[keep], checkpoint_every=0.0137)
    ck = keep.checkpoints[2]
    again, k2 = Simulation(scene), Sums()
    again.restore(ck)
    again.run(observers=[k2])
    for k, name in enumerate(names):
        full = np.concatenate([b[k] for b in keep.positions])
        np.testing.assert_array_equal(full[ck.frames:],
                                      np.concatenate([b[k] for b in k2.positions]), name)
    assert np.abs(np.concatenate([b[1] for b in keep.positions])).sum() > 0


def test_resume_from_the_api_writes_the_file_of_an_uninterrupted_run(tmp_path):
    scene = tmp_path / "pile.toml"
    scene.write_text(pile(30, duration=0.03))
    run_scene(scene, tmp_path / "whole.h5", log_events=True)
    calls = iter(range(1000))
    summary = run_scene(scene, tmp_path / "cut.h5", log_events=True, checkpoint_every=0.004,
                        stop=lambda: next(calls) == 3)
    assert summary.interrupted
    assert not read_trajectory(tmp_path / "cut.h5").complete
    resumed = resume_run(tmp_path / "cut.h5")
    assert not resumed.interrupted
    assert read_trajectory(tmp_path / "cut.h5").complete
    same_file(tmp_path / "whole.h5", tmp_path / "cut.h5")
    # a complete file is extended with a later end time, still bit for bit
    run_scene(scene, tmp_path / "longer.h5", log_events=True, until=0.04)
    resume_run(tmp_path / "cut.h5", until=0.04)
    same_file(tmp_path / "longer.h5", tmp_path / "cut.h5")


def test_a_run_with_overrides_resumes_with_them(tmp_path):
    scene = tmp_path / "pile.toml"
    scene.write_text(pile(20, duration=0.02))
    changes = {"contacts[0].sliding_friction": 0.6, "fill[0].speed": 0.3}
    run_scene(scene, tmp_path / "whole.h5", overrides=changes)
    calls = iter(range(1000))
    run_scene(scene, tmp_path / "cut.h5", overrides=changes, checkpoint_every=0.003,
              stop=lambda: next(calls) == 2)
    resume_run(tmp_path / "cut.h5")
    same_file(tmp_path / "whole.h5", tmp_path / "cut.h5")
    assert read_trajectory(tmp_path / "cut.h5").scene_text.count("# override:") == 2


def _start(args, tmp_path):
    return subprocess.Popen([sys.executable, "-m", "hsgran", *args], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _first_checkpoint(proc, out):
    """Wait until the running ``proc`` has stored a checkpoint in ``out``."""
    deadline = time.monotonic() + FIRST_CHECKPOINT_TIMEOUT
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        if out.exists():
            try:
                return read_checkpoint(out)
            except Exception:
                pass
        time.sleep(0.05)
    proc.kill()
    raise AssertionError("no checkpoint within the timeout")


@pytest.mark.parametrize("how", ["SIGKILL", "SIGINT", "SIGTERM"])
def test_a_run_stopped_by_a_signal_resumes_to_the_same_file(tmp_path, how):
    scene = tmp_path / "pile.toml"
    scene.write_text(pile(PILE_SPHERES))
    out = tmp_path / "cut.h5"
    proc = _start(["run", "pile.toml", "-o", "cut.h5", "--events", "--no-progress",
                   "--checkpoint-every", str(CHECKPOINT_EVERY)], tmp_path)
    _first_checkpoint(proc, out)
    delay = random.uniform(*KILL_DELAY)
    time.sleep(delay)
    assert proc.poll() is None, f"the run ended before the {how} ({delay:.2f} s)"
    proc.send_signal(getattr(signal, how))
    _, err = proc.communicate(timeout=120)
    if how == "SIGKILL":
        assert proc.returncode == -signal.SIGKILL
    else:
        assert proc.returncode == 128 + getattr(signal, how)
        assert f"interrupted by {how}" in err
        assert "hsgran run --resume cut.h5" in err
        assert "Traceback" not in err
    traj = read_trajectory(out)  # the file still opens
    assert not traj.complete
    ck = read_checkpoint(out)
    assert ck.frames <= traj.n_frames
    until = ck.time + RESUME_SPAN
    rc = subprocess.run([sys.executable, "-m", "hsgran", "run", "--resume", "cut.h5",
                         "--until", repr(until), "--no-progress"], cwd=tmp_path,
                        capture_output=True, text=True, timeout=600)
    assert rc.returncode == 0, rc.stderr
    rc = subprocess.run([sys.executable, "-m", "hsgran", "run", "pile.toml", "-o", "whole.h5",
                         "--events", "--until", repr(until), "--no-progress"], cwd=tmp_path,
                        capture_output=True, text=True, timeout=600)
    assert rc.returncode == 0, rc.stderr
    same_file(tmp_path / "whole.h5", out)
    resumed = read_trajectory(out)
    assert resumed.complete
    with h5py.File(out, "r") as f:  # written anew: plain HDF5 readers open it again
        assert f["particles/all/position/value"].shape[0] == resumed.n_frames


def test_an_existing_output_is_not_overwritten_without_force(tmp_path, capsys):
    scene = tmp_path / "pile.toml"
    scene.write_text(pile(5, duration=0.002))
    out = tmp_path / "out.h5"
    out.write_bytes(b"precious")
    err = run_error(capsys, ["run", str(scene), "-o", str(out), "--no-progress"])
    assert "--force" in err
    assert out.read_bytes() == b"precious"


def test_a_run_that_fails_before_its_first_frame_leaves_no_file(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text(pile(5, duration=0.002).replace("speed = 0.05", "speed = -1.0"))
    run_error(capsys, ["run", str(scene), "-o", str(tmp_path / "out.h5"), "--no-progress"])
    good = tmp_path / "good.toml"
    good.write_text(pile(5, duration=0.002))
    run_error(capsys, ["run", str(good), "-o", str(tmp_path / "nodir" / "out.h5"),
                       "--no-progress"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml", "good.toml"]



def cut_file(tmp_path):
    """A 5-sphere pile run stopped early: a file with a checkpoint to resume from."""
    scene = tmp_path / "pile.toml"
    scene.write_text(pile(5, duration=0.004))
    calls = iter(range(1000))
    out = tmp_path / "cut.h5"
    assert run_scene(scene, out, checkpoint_every=0.001, stop=lambda: next(calls) == 1
                     ).interrupted
    return out


def test_resume_refuses_a_checkpoint_of_another_hsgran_version(tmp_path, capsys):
    out = cut_file(tmp_path)
    with h5py.File(out, "r+") as f:
        f["parameters/hsgran"].attrs["version"] = "0.0.1"
    before = out.read_bytes()
    err = run_error(capsys, ["run", "--resume", str(out), "--no-progress"])
    assert f"checkpoint written by hsgran 0.0.1, this is {hsgran.__version__}" in err
    assert "resume with that version or start again" in err
    assert out.read_bytes() == before  # nothing written
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cut.h5", "pile.toml"]


def test_resume_refuses_a_checkpoint_built_with_other_contact_laws(tmp_path, capsys):
    out = cut_file(tmp_path)
    stored = read_checkpoint(out)
    names = read_trajectory(out).material_names
    steel, glass = names.index("steel"), names.index("glass")
    assert stored.pair_table is not None
    with h5py.File(out, "r+") as f:  # as if written with another friction for steel on glass
        table = f["parameters/hsgran/pair_table"]
        table[glass, steel, P_MU_S] = stored.pair_table[glass, steel, P_MU_S] + 0.1
    before = out.read_bytes()
    err = run_error(capsys, ["run", "--resume", str(out), "--no-progress"])
    assert "contact law glass-steel differs from the checkpoint's (P_MU_S: " in err
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cut.h5", "pile.toml"]
    with h5py.File(out, "r+") as f:  # the table as written: the resume goes ahead
        f["parameters/hsgran/pair_table"][...] = stored.pair_table
    assert not resume_run(out).interrupted


@pytest.mark.parametrize(("args", "needle"), [
    (["--resume", "{out}", "{scene}"], "drop SCENE.toml"),
    (["--resume", "{out}", "-o", "x.h5"], "drop -o"),
    (["--resume", "{out}"], "is complete"),
    (["--resume", "{out}", "--until", "0.001"], "--until: must not be before"),
    (["--resume", "{scene}"], "not an HDF5 file"),
    (["--resume", "{foreign}"], "not an hsgran trajectory"),
    (["--resume", "{missing}"], "not found"),
    ([], "missing SCENE.toml"),
    (["{scene}", "--checkpoint-every", "0"], "--checkpoint-every"),
    (["{scene}", "--checkpoint-wall", "-1"], "--checkpoint-wall"),
])
def test_bad_resumes_are_one_line_errors(tmp_path, capsys, args, needle):
    scene = tmp_path / "pile.toml"
    scene.write_text(pile(5, duration=0.002))
    out = tmp_path / "out.h5"
    run_scene(scene, out)
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["x"] = np.arange(3)
    names = {"out": out, "scene": scene, "foreign": foreign, "missing": tmp_path / "none.h5"}
    argv = ["run", *(a.format(**names) for a in args), "--no-progress"]
    assert needle in run_error(capsys, argv)
