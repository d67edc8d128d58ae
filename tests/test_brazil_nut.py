"""tools/brazil_nut.py: its table and summary on a short run of the shipped vibrated bed, the
convection measure on a hand-made bed, and its refusal of a bad argument."""

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
import brazil_nut as bn


def test_a_short_run_prints_heights_and_a_summary(capsys):
    # 0.02 s: the beads are still falling in (a few thousand events, also in plain Python)
    assert bn.main(["--gamma", "3.5", "--duration", "0.02", "--every", "0.01", "--settle",
                    "0.01", "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if line.strip().startswith("0.")]
    assert [row[0] for row in rows] == ["0.00", "0.01", "0.02"]
    big, surface = float(rows[-1][1]), float(rows[-1][3])
    assert 0.0 < big < surface < 50.0  # [mm]: the large sphere low, beads above it
    assert "Γ = 3.5: completed; rise time" in out


def test_convection_is_the_net_rise_over_one_period():
    """Beads in the middle third rise 1 mm per period and the others sink 0.5 mm, on top of a
    breathing common to all; the measure sees only the net motion."""
    small = np.arange(6)
    obs = bn._Heights(big=6, small=small, settle=0.0, lag=4)
    x = np.array([0.0, 0.01, 0.019, 0.021, 0.03, 0.04])
    middle = np.abs(x - 0.02) <= 0.04 / 6
    for f in range(9):
        breathing = 0.003 * np.sin(2 * np.pi * f / 4)
        z = 0.01 + breathing + np.where(middle, 1e-3, -0.5e-3) * f / 4
        pos = np.zeros((1, 7, 3))
        pos[0, :6, 0] = x
        pos[0, :6, 2] = z
        obs.on_frames(SimpleNamespace(time=np.array([0.01 * f]), position=pos))
    net = obs.dz_sum / obs.dz_n
    np.testing.assert_allclose(net, [1e-3, -0.5e-3], rtol=1e-12)


def test_a_bad_gamma_is_refused(capsys):
    assert bn.main(["--gamma", "two"]) == 2
    assert "--gamma" in capsys.readouterr().err
