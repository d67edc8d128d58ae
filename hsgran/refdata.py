"""Reference data shipped with hsgran (layer 1: imports only numpy and ``hsgran.errors``).

The CSV tables in the ``hsgran.data`` package are benchmark digitisations and closed-form
oracles used by the tests and by ``hsgran validate``; ``hsgran/data/README.md`` says where each
file comes from, what its columns mean and how accurate it is. Every table has one header row;
units are part of the column names (``overlap_um``, ``normal_force_kN``, ...).

Example:
    >>> from hsgran import refdata
    >>> table = refdata.read_csv("chung_ooi_2011_test7_reference.csv")
    >>> float(table["final_angular_velocity_rad_s"][8])
    2.0
"""

from __future__ import annotations

import atexit
import contextlib
import csv
import io
import math
from importlib import resources
from pathlib import Path

import numpy as np

from hsgran.errors import InputError, did_you_mean

#: The package that holds the data files.
DATA_PACKAGE = "hsgran.data"
#: File types that count as reference data (``__init__.py`` and the like are not data).
DATA_SUFFIXES = (".csv", ".md", ".toml", ".npz")

# Keeps files extracted from a zipped installation alive until the interpreter exits.
_EXTRACTED = contextlib.ExitStack()
atexit.register(_EXTRACTED.close)


def available() -> list[str]:
    """Names of the reference-data files shipped with hsgran, sorted.

    Returns:
        File names (no directories), e.g. ``"derived_hertz_chung_ooi_tests1_2.csv"``.
    """
    root = resources.files(DATA_PACKAGE)
    return sorted(p.name for p in root.iterdir()
                  if p.is_file() and p.name.endswith(DATA_SUFFIXES))


def _resource(name: str):
    """The traversable of data file ``name``, after checking the name."""
    if not isinstance(name, str) or not name or "/" in name or "\\" in name or name in (".", ".."):
        raise InputError(f"must be the name of a file in {DATA_PACKAGE}, got {name!r}",
                         "data file")
    known = available()
    if name not in known:
        raise InputError(f"no reference data file '{name}'{did_you_mean(name, known)}; "
                         f"known: {', '.join(known)}", "data file")
    return resources.files(DATA_PACKAGE).joinpath(name)


def data_path(name: str) -> Path:
    """File-system path of a reference-data file.

    Args:
        name: File name inside ``hsgran/data`` (e.g. ``"material_parameters.csv"``).

    Returns:
        Path of the file. For a normal (or editable) installation this is the file in the
        package directory; from a zipped installation the file is extracted to a temporary
        location that lasts until the interpreter exits.

    Raises:
        InputError: ``name`` is not a data file shipped with hsgran (with a "did you mean"
            hint), or contains a directory part.
    """
    res = _resource(name)
    if isinstance(res, Path):
        return res
    return Path(_EXTRACTED.enter_context(resources.as_file(res)))


def _as_float(text: str) -> float | None:
    """``float(text)`` for a numeric cell, NaN for an empty cell, ``None`` for text."""
    s = text.strip()
    if not s:
        return math.nan
    try:
        return float(s)
    except ValueError:
        return None


def read_csv(name: str) -> dict[str, np.ndarray | list[str]]:
    """Read a reference-data CSV table (one header row) into columns.

    A column whose cells all parse as numbers becomes a ``float64`` array (empty cells become
    NaN); any other column stays a list of strings (cells stripped of surrounding blanks).
    Quoted cells may contain commas (standard CSV quoting).

    Args:
        name: File name inside ``hsgran/data``, e.g. ``"chung_ooi_2011_test4_dem_reference.csv"``.

    Returns:
        Column name → values, in the order of the header.

    Raises:
        InputError: unknown file name, empty file, repeated or empty column names, or a row
            whose number of cells differs from the header (the message names the line).
    """
    text = _resource(name).read_text(encoding="utf-8")
    rows = list(csv.reader(io.StringIO(text)))
    while rows and not any(cell.strip() for cell in rows[-1]):
        rows.pop()  # trailing blank lines
    if not rows:
        raise InputError("empty file (a header row is required)", name)
    header = [h.strip() for h in rows[0]]
    if any(not h for h in header):
        raise InputError(f"empty column name in header {header!r}", name)
    if len(set(header)) != len(header):
        raise InputError(f"repeated column name in header {header!r}", name)
    body = rows[1:]
    for lineno, row in enumerate(body, start=2):
        if len(row) != len(header):
            raise InputError(f"line {lineno} has {len(row)} cells, the header has {len(header)}",
                             name)
    out: dict[str, np.ndarray | list[str]] = {}
    for j, col in enumerate(header):
        cells = [row[j] for row in body]
        numbers = [_as_float(c) for c in cells]
        numeric = all(x is not None for x in numbers) and any(c.strip() for c in cells)
        if numeric:
            out[col] = np.array(numbers, dtype=np.float64)
        else:
            out[col] = [c.strip() for c in cells]
    return out


__all__ = ["available", "data_path", "read_csv"]
