"""CI smoke test of the accuracy–cost study: ``tools/accuracy_cost.py --quick`` runs every
section and writes a report with numbers and figures (the figures are not judged here)."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

TOOL = Path(__file__).resolve().parents[1] / "tools" / "accuracy_cost.py"
SECTIONS = ("## 1. One impact", "## 2. Fidelity levels", "## 3. The engine's accuracy knobs",
            "## 4. Many spheres", "## 5. The price of each effect")
FIGURES = ("impact.png", "fidelity.png", "knobs.png", "many.png", "price.png")


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("accuracy_cost")
    subprocess.run([sys.executable, str(TOOL), "--quick", "--out", str(out)], check=True,
                   capture_output=True, text=True, timeout=600)
    return out


def test_quick_study_writes_every_section_with_numbers(report):
    text = (report / "accuracy-cost.md").read_text()
    for title in SECTIONS:
        assert title in text
        body = text.split(title, 1)[1].split("\n## ", 1)[0]
        assert re.search(r"\|\s*[-+]?\d", body), f"no numbers in the table of {title}"
    assert "Machine:" in text
    assert "tools/accuracy_cost.py --quick" in text


def test_quick_study_writes_the_figures(report):
    for name in FIGURES:
        path = report / "img" / "accuracy-cost" / name
        assert path.exists()
        assert path.stat().st_size > 1000
