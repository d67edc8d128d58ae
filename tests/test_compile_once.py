"""The event loop is compiled twice at most, with gravity and without: the other effect switches
are run-time values and the integer types at every call are fixed, so no other kernel of
hsgran._loop gains a second signature (each one would cost a cold compile of tens of seconds on a
fresh machine)."""

from __future__ import annotations

from pathlib import Path

import numba
import pytest

from hsgran import _loop
from hsgran.engine import Simulation
from hsgran.scene import load_scene

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="needs the compiled kernels")
def test_every_scene_uses_the_same_compiled_loop():
    # four different effect sets, with and without gravity, walls, periodic axes, event log
    for name, log in (("steel_ball_on_glass", True), ("granular_gas", False),
                      ("sphere_on_plate", True), ("falling_box", False)):
        sim = Simulation(load_scene(SCENARIOS / f"{name}.toml"), log_events=log)
        sim.run(until=0.01)
    kernels = {name: obj for name, obj in vars(_loop).items()
               if isinstance(obj, numba.core.registry.CPUDispatcher)
               and obj.py_func.__module__ == _loop.__name__}
    assert {"_run_loop", "run_loop_gravity", "run_loop_free", "init", "_predict_fn",
            "_enter_plane"} <= set(kernels)
    # the loop's gravity switch is a compile-time constant: one compile with, one without (none
    # here when both callers came from the on-disk cache)
    gravity_switch = {str(sig[-1]) for sig in kernels.pop("_run_loop").signatures}
    assert gravity_switch <= {"Literal[bool](False)", "Literal[bool](True)"}
    many = {name: len(d.signatures) for name, d in kernels.items() if len(d.signatures) > 1}
    assert not many, f"kernels compiled more than once: {many}"
