"""Facts about the machine a run is on (layer 0: imports nothing from hsgran)."""

from __future__ import annotations

import os


def available_memory() -> int | None:
    """Memory the machine can give a new allocation now [bytes], or ``None`` if unknown.

    Linux's ``MemAvailable`` (free memory plus the caches it can drop); elsewhere, free pages.
    Used to refuse, before allocating, scenes and files that cannot fit.
    """
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None
