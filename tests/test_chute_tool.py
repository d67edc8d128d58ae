"""tools/chute.py: how a run's flow is called, and a run stopped by its wall-time limit."""

import math

import numba
import pytest


def test_a_run_is_called_by_its_last_windows_or_by_where_it_stopped(load_tool):
    """Steady, stopped, accelerating, slowing from the last two windows; a guard stop or a
    timeout wins over them (a timed-out run's last windows are empty: NaN)."""
    chute = load_tool("chute")
    assert chute.classify([0.05, 0.040, 0.042], None, None, 0.1) == "steady"
    assert chute.classify([0.05, 0.002, 0.0004], None, None, 0.1) == "stopped"
    assert chute.classify([0.05, 0.10, 0.20], None, None, 0.1) == "accelerating"
    assert chute.classify([0.20, 0.10, 0.05], None, None, 0.1) == "slowing"
    assert chute.classify([0.05, math.nan, math.nan], None, 0.4, 0.1) == \
        "timed out at 0.4000 s"
    assert chute.classify([0.05, math.nan, math.nan], 0.25, None, 0.1) == \
        "guard at 0.2500 s"


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="too slow without the compiler")
@pytest.mark.parametrize("timeout", [None, 1e-6])
def test_a_run_stops_at_its_wall_time_limit_and_says_where(load_tool, timeout):
    """Without a limit the chute runs to its end; with one far below a compiled call's
    length it stops after the first call, before its end, and says at which time."""
    chute = load_tool("chute")
    r = chute.run_one((24.0, 0.15, timeout))
    assert r["guard"] is None
    if timeout is None:
        assert r["timed_out"] is None
        assert r["t"][-1] == pytest.approx(0.15)
    else:
        assert 0.0 < r["timed_out"] < 0.15
        assert r["t"][-1] <= r["timed_out"]
