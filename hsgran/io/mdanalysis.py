"""An hsgran trajectory as an MDAnalysis Universe in one call (layer 5).

MDAnalysis (2.x) reads H5MD files, but its unit tables know no "m" (its lengths are Å, nm,
pm, fm) and its H5MD reader refuses a unit it does not know even with
``convert_units=False``. The H5MD standard leaves units free and hsgran's files are SI, so
rather than write a unit MDAnalysis knows, :func:`universe` teaches MDAnalysis metres
(1 m = 10¹⁰ Å; three table entries, added once per process, which change nothing else it
reads) and loads the file into an empty universe of the right size (the file has no
topology). See docs/trajectory-format.md, "MDAnalysis".
"""

from __future__ import annotations

import os

import h5py

from hsgran.errors import InputError, MissingDependency

#: Å per metre, as MDAnalysis's length factors count (a length in m is the length in Å × 1e-10).
METRE_FACTOR = 1e-10


def register_metres() -> None:
    """Teach MDAnalysis the length unit "m" (idempotent)."""
    from MDAnalysis import units
    from MDAnalysis.coordinates.H5MD import H5MDReader

    H5MDReader._unit_translation["length"].setdefault("m", "m")
    units.lengthUnit_factor.setdefault("m", METRE_FACTOR)
    units.unit_types.setdefault("m", "length")


def universe(path: str | os.PathLike, *, convert_units: bool = True):
    """An MDAnalysis Universe of an hsgran trajectory.

    Args:
        path: The H5MD file of ``hsgran run``.
        convert_units: As MDAnalysis's own option: ``True`` gives its units (Å, ps, Å/ps),
            ``False`` keeps the file's SI units (m, s, m/s).

    Returns:
        ``MDAnalysis.Universe`` with one atom per sphere, the frames as its trajectory and the
        energies in ``ts.data``. Radii, spins, materials and events are not read by
        MDAnalysis: use :func:`hsgran.io.read_trajectory` for those.

    Raises:
        MissingDependency: MDAnalysis is not installed.
        InputError: the file has no particles.
    """
    try:
        from MDAnalysis import Universe
    except ImportError:
        raise MissingDependency("MDAnalysis is not installed: pip install MDAnalysis") from None
    with h5py.File(path, "r") as f:
        if "particles/all/radius" not in f:
            raise InputError(f"{path}: not an hsgran trajectory (no particles/all/radius)",
                             "path")
        n = int(f["particles/all/radius"].shape[0])
    register_metres()
    u = Universe.empty(n, trajectory=True)
    u.load_new(os.fspath(path), format="H5MD", convert_units=convert_units)
    return u
