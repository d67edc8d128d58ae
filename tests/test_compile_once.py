"""The event loop is compiled twice at most per layout, with gravity and without (two loops,
run_loop_gravity and run_loop_free): the other effect switches are run-time values and the
integer types at every call are fixed, so no kernel gains a second signature (each one would cost
a cold compile of tens of seconds on a fresh machine). The layout for large systems
(engine.LARGE_FROM: strided record fields, a calendar with buckets) has versions of its own,
which other tests may have compiled."""

from __future__ import annotations

from pathlib import Path

import numba
import pytest

from hsgran import _flight, _loop, _predict, _settling
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
    kernels = {name: obj for module in (_loop, _predict, _flight, _settling)
               for name, obj in vars(module).items()
               if isinstance(obj, numba.core.registry.CPUDispatcher)
               and obj.py_func.__module__ == module.__name__}
    assert {"run_loop_gravity", "run_loop_free", "init", "predict_fn", "enter_plane", "settle",
            "wake_sleepers"} <= set(kernels)
    # the loop's gravity switch is a constant of each of the two loops (hsgran._loop._loop_of),
    # so each is compiled once per layout, like every other kernel (none here when both came
    # from the on-disk cache)
    many = {name: n for name, d in kernels.items()
            if (n := sum(not large_layout(sig) for sig in d.signatures)) > 1}
    assert not many, f"kernels compiled more than once: {many}"


def large_layout(signature) -> bool:
    """A signature of the layout for large systems: strided ("A") arrays of record fields,
    anywhere in the argument types (the state groups are named tuples of arrays)."""
    stack = list(signature)
    while stack:
        t = stack.pop()
        if isinstance(t, numba.types.Array) and t.layout == "A":
            return True
        stack.extend(getattr(t, "types", ()))
    return False
