"""tools/bench_engine.py runs and prints its figures (smoke test; speeds are never asserted)."""

import re

#: A number as the script prints it (3.36e+03, 193, 5.57e+05, 0.44).
NUMBER = r"[0-9][0-9.,]*(?:e[+-][0-9]+)?"


def test_bench_engine_quick_run_prints_speed_memory_and_targets(capsys, load_tool):
    bench = load_tool("bench_engine")
    assert bench.main(["--quick", "--sizes", "1e3"]) == 0
    out = capsys.readouterr().out
    # speed row of N = 1000: setup, warm-up and timed collisions, wall, events/s, collisions/s
    assert re.search(rf"^\s+1,000(\s+{NUMBER}){{6}}\s*$", out, re.MULTILINE), out
    # memory row: state, state + frames, peak RSS (bytes per particle; RSS may be 0 or negative
    # when freed memory is reused, so only its presence is checked)
    assert re.search(rf"^\s+1,000(\s+{NUMBER}){{2}}\s+-?{NUMBER}\s*$", out, re.MULTILINE), out
    assert re.search(rf"^granular: {NUMBER} events/s, {NUMBER} collisions/s", out,
                     re.MULTILINE), out
    assert re.search(rf"^pile: {NUMBER} events/particle/s over the run, ", out, re.MULTILINE), out
    assert "targets:" in out
    assert "B/particle" in out
