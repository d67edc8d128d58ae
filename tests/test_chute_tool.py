"""tools/chute.py: how a run's flow is called, and a run stopped by its wall-time limit."""

import math

import numba
import pytest


def test_a_run_is_called_by_its_late_windows_or_by_where_it_stopped(load_tool):
    """Steady, stopped, accelerating, slowing from the mean velocity's rate of change over the
    last half of the windows, against g sin θ; a guard stop or a timeout wins over them (a
    timed-out run's last windows are empty: NaN)."""
    chute = load_tool("chute")
    g = 9.81 * math.sin(math.radians(30.0))  # 4.9 m/s²: 1 % of it is 0.049 m/s²
    win = 0.25
    # the 30° chute of docs/open-systems.md over 1.5 s and over 3 s (its last six windows)
    assert chute.classify([0.16, 0.23, 0.27, 0.29, 0.31, 0.31], None, None, 0.01, win, g) \
        == "steady"
    assert chute.classify([0.16, 0.23, 0.27, 0.29, 0.33, 0.37], None, None, 0.01, win, g) \
        == "accelerating"
    # gaining 0.1 m/s a window at 1.6 m/s: the 10 % test of the last two windows called
    # this steady; it is an accelerating flow (0.4 m/s², 8 % of g sin θ)
    assert chute.classify([1.2, 1.3, 1.4, 1.5, 1.6, 1.7], None, None, 0.01, win, g) \
        == "accelerating"
    assert chute.classify([0.05, 0.02, 0.002, 0.0004], None, None, 0.01, win, g) \
        == "stopped"
    assert chute.classify([0.20, 0.15, 0.10, 0.05], None, None, 0.01, win, g) == "slowing"
    assert math.isclose(chute.late_acceleration([0.0, 0.0, 1.0, 2.0, 3.0], 0.5), 2.0)
    assert chute.classify([0.05, math.nan, math.nan], None, 0.4, 0.01, win, g) == \
        "timed out at 0.4000 s"
    assert chute.classify([0.05, math.nan, math.nan], 0.25, None, 0.01, win, g) == \
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
