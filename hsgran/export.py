"""A trajectory in the files of ParaView and OVITO (layer 6): ``hsgran export``.

* ``vtk``: a ParaView collection. One VTK XML PolyData file (``.vtp``) per frame, written by
  VTK through pyvista (the ``render`` extra), holds the sphere centres as points with point
  data ``radius`` [m], ``velocity`` [m/s], ``angular_velocity`` [rad/s] (with rotation),
  ``motion_state`` (hsgran.onplane.MS_*), ``material`` (index into the file's material names)
  and ``id`` (``motion_state`` is rebuilt from the event log for files that do not store it, as
  ``hsgran render`` does). ``walls.vtp`` holds the plane walls as finite quadrilaterals (the
  patches ``hsgran render`` draws) with their ``normal`` and ``material`` (with moving planes,
  ``walls_K.vtp`` for every frame K, the planes where they are then). ``NAME.pvd`` lists
  the frames with their times (part 0) and the walls (part 1) for every frame; its few lines of
  XML are written with the standard library's ElementTree. Open the ``.pvd`` in ParaView and
  show the points with the Point Gaussian representation scaled by ``radius``.
* ``xyz``: one extended-XYZ file of all frames, written by ASE (the ``export`` extra), which
  OVITO reads: per particle ``pos`` plus the arrays ``radius``, ``velocity``,
  ``angular_velocity``, ``motion_state``, ``material``, ``id``; per frame ``time`` [s] and
  ``step``, the box as the cell and the periodic axes as ``pbc``. Species are all "X" (ASE's
  dummy element): hsgran spheres are not atoms; the material is a column. Lengths are in
  micrometres (XYZ_LENGTH_UNIT): ASE prints every real with 8 decimals, which in metres would
  keep only 10 nm of a position.

VTK values are in SI units (metres, not ångström); XYZ values in µm, µm/s, rad/s and s. Each
file says so in its ``units`` entry (per frame in XYZ, a field of each frame in VTK).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hsgran.animation import motion_states, scene_extent, wall_patches
from hsgran.errors import InputError, MissingDependency
from hsgran.io.h5md import read_trajectory

FORMATS = ("vtk", "xyz")
#: What the exported values are in, written into the files.
UNITS = "SI: m, m/s, rad/s, s"
#: The length unit of the XYZ files [m]: with ASE's 8 decimals, 1e-14 m of a position, and
#: 11 or more significant digits of any length from 1 µm to 1 km.
XYZ_LENGTH_UNIT = 1e-6
XYZ_UNITS = "micrometre: um, um/s, rad/s, s"
EXPORT_EXTRA = "pip install -e '.[export]' (ASE)"
RENDER_EXTRA = "pip install -e '.[render]' (pyvista, vtk)"


@dataclass(frozen=True)
class ExportResult:
    """What :func:`export` wrote: the main file (``.pvd`` or ``.xyz``), every file, frames."""

    output: Path
    files: list[Path]
    frames: int


def _frames(traj, every: int) -> np.ndarray:
    if not isinstance(every, int) or every < 1:
        raise InputError(f"must be a whole number >= 1, got {every!r}", "--every")
    return np.arange(0, traj.n_frames, every)


def _particle_arrays(traj, states: np.ndarray, f: int) -> dict[str, np.ndarray]:
    """Per-particle values of frame f (see the module), of the particles in the system then
    (those that have left through an outlet are not written; ``id`` names the others)."""
    here = traj.present[f]
    out = {"radius": traj.radius, "velocity": traj.velocity[f],
           "material": traj.material.astype(np.int32),
           "id": np.arange(traj.n_particles, dtype=np.int64),
           "motion_state": states[f].astype(np.int32)}
    if traj.angular_velocity is not None:
        out["angular_velocity"] = traj.angular_velocity[f]
    return {name: values[here] for name, values in out.items()}


def _target(path: Path, force: bool) -> None:
    if path.exists() and not force:
        raise InputError(f"{path} exists (use --force to overwrite)", "--output")


def export(trajectory, fmt: str, output=None, *, every: int = 1,
           force: bool = False) -> ExportResult:
    """Write a trajectory for ParaView (``vtk``) or OVITO (``xyz``), see the module.

    Args:
        trajectory: Path of an hsgran H5MD trajectory.
        fmt: ``"vtk"`` or ``"xyz"``.
        output: For ``vtk`` the directory of the collection (default: the trajectory's name
            with ``_vtk``), for ``xyz`` the file (default: the trajectory's name with .xyz).
        every: Write every ``every``-th frame.
        force: Overwrite existing files.

    Raises:
        InputError: unknown format, existing output without ``force``, bad ``every``.
        MissingDependency: the library of the format is not installed.
    """
    if fmt not in FORMATS:
        raise InputError(f"unknown format {fmt!r}; known: {', '.join(FORMATS)}", "--format")
    path = Path(trajectory)
    traj = read_trajectory(path)
    frames = _frames(traj, every)
    states = motion_states(traj)
    if fmt == "xyz":
        out = Path(output) if output is not None else path.with_suffix(".xyz")
        return _write_xyz(traj, states, frames, out, force)
    out = Path(output) if output is not None else path.with_name(path.stem + "_vtk")
    return _write_vtk(traj, states, frames, out, force, path.stem)


def _write_xyz(traj, states, frames, out: Path, force: bool) -> ExportResult:
    try:
        from ase import Atoms
        from ase.io import write
    except ImportError:
        raise MissingDependency(f"--format xyz needs ASE: {EXPORT_EXTRA}") from None
    _target(out, force)
    unit = XYZ_LENGTH_UNIT
    cell = np.zeros(3) if traj.box_lower is None else traj.box_upper - traj.box_lower
    images = []
    for f in frames:
        here = traj.present[f]
        atoms = Atoms(symbols=["X"] * int(here.sum()), positions=traj.position[f][here] / unit,
                      cell=np.diag(cell / unit), pbc=traj.periodic)
        if traj.box_lower is not None:
            atoms.info["origin"] = np.asarray(traj.box_lower, dtype=float) / unit
        atoms.info["time"] = float(traj.time[f])
        atoms.info["step"] = int(traj.step[f])
        atoms.info["units"] = XYZ_UNITS
        for name, values in _particle_arrays(traj, states, f).items():
            lengths = name in ("radius", "velocity")  # in µm and µm/s; the rest as they are
            atoms.new_array(name, np.asarray(values) / unit if lengths
                            else np.array(values, copy=True))
        images.append(atoms)
    tmp = out.with_name(out.name + ".part")
    write(tmp, images, format="extxyz")
    os.replace(tmp, out)  # no half-written file under the final name
    return ExportResult(out, [out], len(frames))


def _write_vtk(traj, states, frames, out: Path, force: bool, name: str) -> ExportResult:
    try:
        import pyvista as pv
    except ImportError:
        raise MissingDependency(f"--format vtk needs pyvista: {RENDER_EXTRA}") from None
    pvd = out / f"{name}.pvd"
    if out.exists() and not out.is_dir():
        raise InputError(f"{out} is a file; --format vtk writes a directory", "--output")
    _target(pvd, force)
    out.mkdir(parents=True, exist_ok=True)
    files = []
    walls_file = _write_walls(pv, traj, out)
    if walls_file is not None:
        files.append(walls_file)
    moving = walls_file is not None and _any_moving(traj)
    collection = ET.Element("Collection")
    for k, f in enumerate(frames):
        cloud = pv.PolyData(np.ascontiguousarray(traj.position[f][traj.present[f]]))
        for key, values in _particle_arrays(traj, states, f).items():
            cloud.point_data[key] = np.ascontiguousarray(values)
        cloud.field_data["time"] = np.array([traj.time[f]])
        cloud.field_data["units"] = np.array([UNITS])
        file = out / f"frame_{k:06d}.vtp"
        cloud.save(file)
        files.append(file)
        ET.SubElement(collection, "DataSet", timestep=repr(float(traj.time[f])), part="0",
                      file=file.name)
        if moving:  # the walls where they are at this frame
            walls_file = _write_walls(pv, traj, out, traj.time[f], f"walls_{k:06d}.vtp")
            files.append(walls_file)
        if walls_file is not None:
            ET.SubElement(collection, "DataSet", timestep=repr(float(traj.time[f])),
                          part="1", file=walls_file.name)
    root = ET.Element("VTKFile", type="Collection", version="0.1")
    root.append(collection)
    ET.ElementTree(root).write(pvd, xml_declaration=True, encoding="utf-8")
    files.append(pvd)
    return ExportResult(pvd, files, len(frames))


def _any_moving(traj) -> bool:
    from hsgran.render import wall_planes

    return any(p.motion is not None for p in wall_planes(traj)[0])


def _write_walls(pv, traj, out: Path, t: float = 0.0, name: str = "walls.vtp") -> Path | None:
    """The plane walls as quadrilaterals, moving planes where they are at time t [s], the
    cylinders as tubes of quadrilaterals (normals towards the spheres), the faces of finite
    walls as polygons and the fixed spheres as spheres."""
    from hsgran.render import CYLINDER_SEGMENTS, part_meshes, wall_cylinders, wall_planes

    planes, _ = wall_planes(traj)
    meshes = []
    if planes:
        lower, upper = scene_extent(traj)
        patches = wall_patches(planes, lower, upper, traj.box_lower, traj.box_upper)
        points = np.concatenate([p.corners + (plane.point_at(t) - plane.point)
                                 for plane, p in zip(planes, patches, strict=True)])
        faces = np.concatenate([[4, 4 * k, 4 * k + 1, 4 * k + 2, 4 * k + 3]
                                for k in range(len(patches))])
        mesh = pv.PolyData(points, faces=faces)
        mesh.cell_data["normal"] = np.array([p.normal for p in patches])
        mesh.cell_data["material"] = np.array([p.material for p in patches], dtype=np.int32)
        meshes.append(mesh)
    for cyl in wall_cylinders(traj):
        tube = pv.Cylinder(center=cyl.center, direction=cyl.axis, radius=cyl.radius,
                           height=2.0 * cyl.half_length, resolution=CYLINDER_SEGMENTS,
                           capping=False)
        q = np.asarray(tube.cell_centers().points) - cyl.center
        q -= np.outer(q @ cyl.axis, cyl.axis)
        q /= np.linalg.norm(q, axis=1)[:, None]
        tube.cell_data["normal"] = -q if cyl.inside else q
        tube.cell_data["material"] = np.full(tube.n_cells, cyl.material, dtype=np.int32)
        meshes.append(tube)
    meshes += part_meshes(pv, traj)  # the faces of finite walls and the fixed spheres
    if not meshes:
        return None
    mesh = meshes[0] if len(meshes) == 1 else pv.merge(meshes)
    file = out / name
    mesh.save(file)
    return file

