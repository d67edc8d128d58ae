"""Every citation of the model specification in the code resolves to a heading of docs/model.md.

The code cites the specification as ``MODEL §3.8`` (older spelling ``MODEL §3.8``), also as
lists and ranges (``MODEL §5.1, §5.3``, ``MODEL §3.2–3.4``, ``MODEL §3–§5``); a citation
may break across a docstring or comment line. docs/model.md carries the numbers in its headings
(``### §3.8 Adhesion during recovery ...``).
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODEL_PAGE = ROOT / "docs" / "model.md"
CITING_DIRS = ("hsgran", "tests", "tools")

#: Every section of the specification, in its numbering, and hsgran's own sections on physics
#: beyond the paper appended to theirs (§3.11 viscoelastic damping, §4.5 tangential compliance).
SECTIONS = (
    ["0", "1", "2", "3"]
    + [f"3.{k}" for k in range(1, 12)]
    + ["4"] + [f"4.{k}" for k in range(1, 6)]
    + ["5"] + [f"5.{k}" for k in range(1, 4)]
    + ["6", "7", "7.1", "8", "9", "10"]
)

_NUM = r"\d+(?:\.\d+)?"
#: "MODEL" or "MODEL.md", perhaps a closing parenthesis, colon or comma, white space that may
#: cross a line (and a comment's "#"), then "§N[.M]" and any further numbers joined to it by a
#: range dash ("–3.4", "-§5") or by ", §" / " and §".
CITATION = re.compile(
    r"\bMODEL(?:\.md)?\)?[:,]?[ \t]*(?:\n[ \t]*(?:#[ \t]*)?)?§[ \t]?(" + _NUM + r")"
    r"((?:[ \t]*[–-][ \t]*§?" + _NUM + r"|,[ \t]*§" + _NUM + r"|[ \t]+and[ \t]+§" + _NUM + r")*)"
)
HEADING = re.compile(r"^#{1,6}[ \t]+§(" + _NUM + r")(?=[ \t]|$)", re.MULTILINE)


def citations():
    """(file, line, section) of every citation in the .py files of the citing directories."""
    found = []
    for top in CITING_DIRS:
        for path in sorted((ROOT / top).rglob("*.py")):
            text = path.read_text(encoding="utf-8")
            for m in CITATION.finditer(text):
                line = text.count("\n", 0, m.start()) + 1
                rel = path.relative_to(ROOT).as_posix()
                found.append((rel, line, m.group(1)))
                for extra in re.findall(_NUM, m.group(2)):
                    found.append((rel, line, extra))
    return found


def headings():
    """Section numbers of the headings of docs/model.md."""
    return HEADING.findall(MODEL_PAGE.read_text(encoding="utf-8"))


def test_citation_pattern_reads_the_forms_in_use():
    text = ("MODEL §3.2–3.4 and MODEL §5.3: x; (MODEL.md\n    §5.3) MODEL §5.1, §5.3. "
            "MODEL §3–§5, MODEL.md): §3.3-3.4 plastic; MODEL §2, 3 spheres; MODEL §3.10")
    got = []
    for m in CITATION.finditer(text):
        got.append(m.group(1))
        got.extend(re.findall(_NUM, m.group(2)))
    assert got == ["3.2", "3.4", "5.3", "5.3", "5.1", "5.3", "3", "5", "3.3", "3.4", "2", "3.10"]


def test_the_code_cites_the_specification():
    # guards the pattern: if it stopped matching, the next test would pass vacuously
    assert len(citations()) > 150


def test_every_citation_resolves_to_a_heading_of_docs_model():
    known = set(headings())
    unresolved = [f"{f}:{line}: §{sec}" for f, line, sec in citations() if sec not in known]
    assert not unresolved, ("citations with no heading in docs/model.md:\n"
                            + "\n".join(unresolved))


def test_docs_model_has_every_section_once_and_in_order():
    found = headings()
    assert found == SECTIONS, f"docs/model.md numbered headings: {found}"


def test_docs_model_says_what_the_citations_mean():
    text = MODEL_PAGE.read_text(encoding="utf-8")
    intro = text.split("\n## ", 1)[0]
    assert "`MODEL §x.y`" in intro
    assert "`MODEL §x.y`" in intro
    assert "(enduring-contact.md)" in text
