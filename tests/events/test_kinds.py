"""The event kinds are defined once (hsgran.events.kinds): the module constants, the name tuple,
the compiled loop's re-exports and the table of docs/trajectory-format.md all follow that table,
and reading a trajectory or plotting it does not import numba."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from hsgran.events import kinds
from hsgran.events.kinds import EVENT_NAMES, KINDS

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "trajectory-format.md"

#: The codes that files, tools and the run summary already use: they must never move.
KNOWN_CODES = {"none": 0, "pair": 1, "wall": 2, "cell": 3, "frame": 4, "stale": 5, "miss": 6,
               "state": 7, "land": 8, "tc": 9, "hop": 10, "wedge": 11, "cluster": 12,
               "exit": 13}


def test_codes_are_positions_in_the_table_and_never_move():
    assert [k.code for k in KINDS] == list(range(len(KINDS)))
    assert {k.name: k.code for k in KINDS} == KNOWN_CODES


def test_every_kind_has_a_plain_int_constant_and_a_name():
    assert EVENT_NAMES == tuple(k.name for k in KINDS)
    for k in KINDS:
        value = getattr(kinds, f"EV_{k.name.upper()}")
        assert type(value) is int  # numba folds plain module-level ints only
        assert value == k.code
        assert k.description
        assert "\n" not in k.description


def test_the_compiled_loop_uses_the_same_constants():
    from hsgran import _loop, _predict, _settling

    assert _loop.EVENT_NAMES == EVENT_NAMES
    for module in (_loop, _predict, _settling):
        for k in KINDS:
            name = f"EV_{k.name.upper()}"
            assert getattr(module, name, k.code) == k.code, (module.__name__, name)


def doc_kind_rows():
    """(code, name, logged) of every row of the "Event kinds" table of the trajectory docs."""
    text = DOC.read_text()
    section = text.split("#### Event kinds", 1)[1]
    rows = []
    for line in section.splitlines():
        if not line.startswith("|"):
            if rows:
                break
            continue
        cells = [c.strip() for c in line.strip("|").split("|")]
        if re.fullmatch(r"\d+", cells[0]):
            rows.append((int(cells[0]), cells[1].strip("`"), cells[2]))
    return rows


def test_the_docs_table_lists_every_kind_with_its_code_name_and_logging():
    rows = doc_kind_rows()
    assert rows == [(k.code, k.name, "yes" if k.logged else "no") for k in KINDS]


@pytest.mark.parametrize("module", ["hsgran.plot", "hsgran.io", "hsgran.events.kinds"])
def test_reading_and_plotting_do_not_import_numba(module):
    code = f"import sys, {module}; assert 'numba' not in sys.modules, sorted(sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT)
    assert out.returncode == 0, out.stderr[-2000:]
