"""The collision kernel gives bit-identical results with the effect flags compiled in
(specialised, as ``make_resolver``) and passed as run-time switches (as the event loop calls it)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from hsgran.contact.model import REC_SIZE, make_batch_resolver
from hsgran.effects import Effects

_BENCH = Path(__file__).resolve().parents[2] / "tools" / "bench_contact.py"
_spec = importlib.util.spec_from_file_location("bench_contact", _BENCH)
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)

KEYS = ("vel1", "omg1", "vel2", "omg2", "normal", "inv_m1", "inv_m2", "inv_i1", "inv_i2", "r1",
        "r2", "curv")


@pytest.mark.parametrize(("label", "names"), bench.EFFECT_SETS)
def test_switched_equals_specialised(label, names):
    events = bench.make_events(300, seed=7)
    fixed = "fixed" in names
    effects = Effects(**{n: True for n in names if n != "fixed"})
    rows = bench.rows_for(fixed)
    idx = np.zeros(300, dtype=np.int64)
    out = []
    for switched in (False, True):
        args = [events[k].copy() for k in KEYS]
        recs = np.full((300, REC_SIZE), np.nan)
        hit = make_batch_resolver(effects, switched=switched)(*args, rows, idx, recs)
        assert hit.all()
        out.append((args, recs))
    (a0, r0), (a1, r1) = out
    for x, y in zip(a0, a1, strict=True):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(r0, r1)
