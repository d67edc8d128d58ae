"""Kernels compiled without reference counting (hsgran._jit.njit) keep memory sound.

Most kernels run without numba's reference counting of arrays; the few that create arrays
(``allocates=True``) keep it. What must hold: a run leaves the reference count of every array
the engine holds as it found it (nothing released once too often, nothing kept alive), and
every array a kernel creates during a run is freed again (numba's allocation statistics, in a
subprocess because they must be switched on before numba starts).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from hsgran._jit import JIT_OPTIONS, njit
from hsgran.engine import Simulation
from hsgran.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
GAS = ROOT / "scenarios" / "granular_gas.toml"
#: 200 spheres poured into a box: landings, motion-state changes, sleepers, hops and wedge
#: stops, and many quartic contact times (spheres on the floor met by falling ones).
POUR = ROOT / "tools" / "scenes" / "small_pour.toml"
#: How far the pour is run [s]: past the first landings (≈ 0.1 s) while the pile forms.
POUR_UNTIL = 0.25

needs_jit = pytest.mark.skipif(numba.config.DISABLE_JIT, reason="needs the compiled kernels")


def _arrays(sim) -> dict[str, np.ndarray]:
    """Every numpy array the Simulation holds, by attribute path (tuples walked)."""
    found: dict[str, np.ndarray] = {}

    def visit(path, obj):
        if isinstance(obj, np.ndarray):
            found[path] = obj
        elif isinstance(obj, tuple | list):
            for k, item in enumerate(obj):
                visit(f"{path}[{k}]", item)

    for name, value in vars(sim).items():
        if name != "scene":
            visit(name, value)
    return found


def _refcounts(arrays: dict[str, np.ndarray]) -> dict[str, int]:
    return {path: sys.getrefcount(a) for path, a in arrays.items()}


def test_kernels_count_references_only_when_they_allocate():
    assert JIT_OPTIONS["_nrt"] is False

    @njit
    def plain(a):
        return a[0]

    @njit(allocates=True)
    def making(n):
        return np.zeros(n).sum()

    if not numba.config.DISABLE_JIT:
        assert plain.targetoptions["_nrt"] is False
        assert making.targetoptions["_nrt"] is True
    assert plain(np.ones(2)) == 1.0
    assert making(3) == 0.0


@needs_jit
@pytest.mark.parametrize(("scene", "until", "large"), [
    (GAS, 0.05, False),
    (POUR, POUR_UNTIL, False),
    (POUR, POUR_UNTIL, True),  # the layout of large systems: records, calendar with buckets
], ids=["gas", "pour", "pour-large-layout"])
def test_runs_leave_every_engine_array_reference_count_unchanged(scene, until, large):
    sim = Simulation(load_scene(scene), log_events=True, large=large)
    arrays = _arrays(sim)
    sim.run(until=until / 2)  # (the first run also loads the compiled loop)
    before = _refcounts(arrays)
    summary = sim.run(until=until)
    after = _refcounts(arrays)
    assert summary.collisions > 100
    changed = {p: (before[p], after[p]) for p in before if before[p] != after[p]}
    assert not changed, f"reference counts changed by a run: {changed}"


ALLOCATION_PROBE = """
import json, sys
from numba.core.runtime import rtsys
from hsgran.engine import Simulation
from hsgran.scene import load_scene
out = {}
for name, path, until, large in json.loads(sys.argv[1]):
    sim = Simulation(load_scene(path), log_events=True, large=large)
    sim.run(until=until / 10)  # loads the compiled loop (and whatever it allocates once)
    a0 = rtsys.get_allocation_stats()
    s = sim.run(until=until)
    a1 = rtsys.get_allocation_stats()
    out[name] = dict(alloc=a1.alloc - a0.alloc, free=a1.free - a0.free,
                     mi_alloc=a1.mi_alloc - a0.mi_alloc, mi_free=a1.mi_free - a0.mi_free,
                     collisions=s.collisions)
print(json.dumps(out))
"""


@needs_jit
def test_every_array_a_run_creates_is_freed():
    cases = [("pour", str(POUR), POUR_UNTIL, False), ("pour-large", str(POUR), POUR_UNTIL, True)]
    env = {**os.environ, "NUMBA_NRT_STATS": "1"}
    proc = subprocess.run([sys.executable, "-c", ALLOCATION_PROBE, json.dumps(cases)],
                          capture_output=True, text=True, env=env, cwd=ROOT, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    stats = json.loads(proc.stdout.strip().splitlines()[-1])
    for name, s in stats.items():
        assert s["collisions"] > 100, name
        assert s["alloc"] == s["free"], (name, s)
        assert s["mi_alloc"] == s["mi_free"], (name, s)
