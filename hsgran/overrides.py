"""Overrides of a parsed scene file: ``contacts[0].sliding_friction = 0.2`` (layer 4).

A sweep (``hsgran sweep``) or a user's own script runs one base scene many times with a few
values changed. Each change is an *override*: a key path in the notation every scene error
message uses, and a TOML value::

    {"contacts[0].sliding_friction": 0.2,
     "particles[0].velocity": [1.0, 0.0, -3.0],
     "particles[0].velocity[2]": -3.0,
     "materials.steel.yield_stress": 2e9,
     "scene.seed": 7}

:func:`apply_overrides` writes them into a copy of the dictionary :mod:`tomllib` made of the
scene file, before the scene is validated, so a value set by an override is checked exactly like
one written in the file. The path must lead through tables and arrays that exist, except that
missing tables are created (``enduring_contact.tc_time`` in a scene without that table); the last
key may be new, and the scene's own validation then refuses it if it is not a scene key (with its
"did you mean" hint). A bad path is an :class:`~hsgran.errors.InputError` naming the override.

Layer 4: pure functions on dictionaries; imports ``errors`` only.
"""

from __future__ import annotations

import copy
import re
from collections.abc import Mapping

from hsgran.errors import InputError, short_repr

#: One step of a key path: a bare TOML key (letters, digits, ``_`` and ``-``), then any number
#: of ``[index]``.
_STEP = re.compile(r"([A-Za-z0-9_-]+)((?:\[\d+\])*)")
_INDEX = re.compile(r"\[(\d+)\]")


def parse_key_path(path: str) -> list[str | int]:
    """Split a key path into table keys (str) and array indices (int).

    ``"contacts[0].sliding_friction"`` → ``["contacts", 0, "sliding_friction"]``.

    Args:
        path: Dotted key path; each step a bare key optionally followed by ``[i]`` indices.

    Raises:
        InputError: malformed path, naming it.
    """
    if not isinstance(path, str) or not path:
        raise InputError(f"a key path must be a non-empty string, got {short_repr(path)}")
    parts: list[str | int] = []
    for step in path.split("."):
        match = _STEP.fullmatch(step)
        if match is None:
            raise InputError(f"malformed key path: {step!r} is not a key like 'radius' or "
                             "'particles[0]'", path)
        parts.append(match.group(1))
        parts.extend(int(i) for i in _INDEX.findall(match.group(2)))
    return parts


def format_key_path(parts) -> str:
    """Inverse of :func:`parse_key_path`."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def set_value(doc: dict, path: str, value) -> None:
    """Set one override in ``doc`` in place (see the module notes for what a path may do).

    Args:
        doc: Parsed TOML document (nested dicts and lists).
        path: Key path.
        value: The new value (any TOML value).

    Raises:
        InputError: the path is malformed, indexes past the end of an array, or goes through
            something that is not a table or an array; the key is the override's path.
    """
    parts = parse_key_path(path)
    node = doc
    for depth, part in enumerate(parts[:-1]):
        here = format_key_path(parts[:depth + 1])
        nxt = parts[depth + 1]
        node = _step(node, part, here, path, create=not isinstance(nxt, int))
    last = parts[-1]
    where = format_key_path(parts[:-1]) or "the top level"
    if isinstance(last, int):
        if not isinstance(node, list):
            raise InputError(f"{where} is not an array, so it has no [{last}]", path)
        if last >= len(node):
            raise InputError(f"index {last} out of range: {where} has {len(node)} entries", path)
        node[last] = copy.deepcopy(value)
    else:
        if not isinstance(node, dict):
            raise InputError(f"{where} is not a table, so it has no key '{last}'", path)
        node[last] = copy.deepcopy(value)


def _step(node, part, here: str, path: str, create: bool):
    """The child ``part`` of ``node``; a missing table key becomes an empty table if ``create``."""
    if isinstance(part, int):
        parent = here.rsplit("[", 1)[0]
        if not isinstance(node, list):
            raise InputError(f"{parent} is not an array, so it has no [{part}]", path)
        if part >= len(node):
            raise InputError(f"index {part} out of range: {parent} has {len(node)} entries",
                             path)
        return node[part]
    if not isinstance(node, dict):
        raise InputError(f"cannot go into '{part}': its parent is not a table", path)
    if part not in node:
        if not create:
            raise InputError(f"{here} does not exist, so it cannot be indexed", path)
        node[part] = {}
    return node[part]


def apply_overrides(doc: Mapping, overrides: Mapping[str, object] | None) -> dict:
    """A deep copy of a parsed scene document with the overrides written in.

    Overrides are applied in their order, so ``{"particles[0].velocity": [...],
    "particles[0].velocity[2]": -1.0}`` sets the vector then changes one of its components.

    Args:
        doc: Parsed TOML document (left unchanged).
        overrides: Key path → value, or ``None``.

    Returns:
        The new document.

    Raises:
        InputError: a bad key path (see :func:`set_value`), naming the override.
    """
    out = copy.deepcopy(dict(doc))
    for path, value in (overrides or {}).items():
        set_value(out, path, value)
    return out


def names_override(key: str | None, overrides: Mapping[str, object] | None) -> str | None:
    """The override whose path is ``key`` or contains it (``particles[0].velocity`` for
    ``particles[0].velocity[2]`` and the other way round), or ``None``."""
    if not key or not overrides:
        return None
    for path in overrides:
        if key == path or key.startswith((path + ".", path + "[")) \
                or path.startswith((key + ".", key + "[")):
            return path
    return None
