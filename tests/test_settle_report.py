"""tools/settle_report.py runs and reports how far a settling scene gets (smoke test)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_settle_report_prints_rates_and_where_the_run_ended(capsys, load_tool):
    tool = load_tool("settle_report")
    # the paper's sphere sliding on a plate (one sphere), reported in two intervals
    scene = ROOT / "scenarios" / "sphere_on_plate.toml"
    assert tool.main([str(scene), "--duration", "0.2", "--interval", "0.1"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"^# sphere_on_plate\.toml: 1 spheres to t = 0\.2 s$", out, re.MULTILINE)
    assert len(re.findall(r"^\s+0\.[12]00\s+[0-9.]+\s+[01]\s+[0-9.]+$", out, re.MULTILINE)) == 2
    assert out.rstrip().endswith("finished at t = 0.2 s")


def test_settle_report_default_scenes_exist(load_tool):
    tool = load_tool("settle_report")
    for path in tool.DEFAULT_SCENES:
        assert path.is_file(), path
