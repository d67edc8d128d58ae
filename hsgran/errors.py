"""Errors that hsgran reports to users (layer 0: imports nothing from hsgran).

Every error raised for bad input is an :class:`InputError`: the command line turns it into
one line on stderr and exit code 2, so a typo never shows a traceback.
"""

from __future__ import annotations

import difflib
import math
import numbers

#: Exit code for bad input (command-line usage errors, as argparse does).
EXIT_BAD_INPUT = 2


class HsgranError(Exception):
    """Base class of the errors hsgran raises on purpose."""


class InputError(HsgranError, ValueError):
    """Bad user input: a one-line message that names the offending key or value.

    Args:
        message: What is wrong and, where possible, how to fix it.
        key: Key path of the offending value (``particles[3].radius``), or ``None``.
    """

    def __init__(self, message: str, key: str | None = None):
        self.key = key
        super().__init__(f"{key}: {message}" if key else message)


class MissingDependency(HsgranError, ImportError):
    """An optional dependency (an 'extra') is not installed."""


def did_you_mean(word: str, choices) -> str:
    """Return a ``" (did you mean 'x'?)"`` hint for a misspelt ``word``, or ``""``."""
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


def short_repr(value, limit: int = 60) -> str:
    """``repr(value)``, cut to ``limit`` characters for one-line messages."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def check_number(value, key: str, *, allow_inf: bool = False) -> float:
    """A real number from user input (not a bool, not NaN; ``inf`` only if allowed).

    Raises:
        InputError: naming ``key``.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"must be a number, got {short_repr(value)}", key)
    x = float(value)
    if math.isnan(x) or (math.isinf(x) and not allow_inf):
        raise InputError(f"must be a finite number, got {value!r}", key)
    return x


def check_positive(value, key: str, unit: str = "") -> float:
    """A finite number > 0 from user input; ``unit`` is shown in the message.

    Raises:
        InputError: naming ``key``.
    """
    x = check_number(value, key)
    if x <= 0.0:
        raise InputError(f"must be > 0{' ' + unit if unit else ''}, got {value!r}", key)
    return x
