"""tools/settle_report.py and tools/settle_variants.py run and report how far settling scenes get
(smoke tests)."""

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


def test_settle_variants_runs_a_case_of_the_grid(capsys, load_tool):
    tool = load_tool("settle_variants")
    # one case: 20 spheres of the small pour for 10 ms (they are still falling)
    assert tool.main(["--until", "0.01", "--restitution", "0.5", "--count", "20",
                      "--width", "0.015", "--effects", "rolling", "--seeds", "4"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"^0\.5 20 rolling 0\.015 4 ok, wedge stops 0; at rest 0/20; wall ",
                     out, re.MULTILINE)
    assert out.rstrip().endswith("0 of 1 cases reached the collapse guard")
