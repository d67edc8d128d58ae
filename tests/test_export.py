"""``hsgran export``: the files read back by the outside readers (ParaView's, through
pyvista/VTK, and ASE's extended-XYZ reader) with every field equal to the trajectory's."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from hsgran.animation import motion_states
from hsgran.api import run_scene
from hsgran.cli import main
from hsgran.export import XYZ_LENGTH_UNIT
from hsgran.io.h5md import read_trajectory

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
#: ASE writes every real of an extended-XYZ file with 8 decimals (fixed): half a unit of the
#: last one, plus the round-off of the value itself.
PRINTED = 5.000001e-9


@pytest.fixture(scope="module")
def trajectory(tmp_path_factory):
    """The falling box (walls, a box, rotation, motion states), a few frames."""
    path = tmp_path_factory.mktemp("export") / "box.h5"
    run_scene(SCENARIOS / "falling_box.toml", path, overrides={"scene.duration": 0.02,
                                                              "fill[0].count": 60})
    return path


def test_vtk_collection_reads_back_in_paraviews_reader(trajectory, tmp_path):
    pv = pytest.importorskip("pyvista")
    out = tmp_path / "vtk"
    assert main(["export", str(trajectory), "--format", "vtk", "-o", str(out)]) == 0
    traj = read_trajectory(trajectory)
    reader = pv.PVDReader(out / "box.pvd")
    assert np.allclose(reader.time_values, traj.time, rtol=0, atol=0)
    states = motion_states(traj)
    for f, t in enumerate(traj.time):
        reader.set_active_time_value(t)
        data = reader.read()
        spheres, walls = data[0], data[1]
        assert np.array_equal(spheres.points, traj.position[f])
        assert np.array_equal(spheres.point_data["velocity"], traj.velocity[f])
        assert np.array_equal(spheres.point_data["angular_velocity"], traj.angular_velocity[f])
        assert np.array_equal(spheres.point_data["radius"], traj.radius)
        assert np.array_equal(spheres.point_data["material"], traj.material)
        assert np.array_equal(spheres.point_data["motion_state"], states[f])
        assert np.array_equal(spheres.point_data["id"], np.arange(traj.n_particles))
        assert walls.n_cells == len(traj.walls)
        assert np.array_equal(walls.cell_data["normal"], traj.walls.normal)


def test_extended_xyz_reads_back_in_ase(trajectory, tmp_path):
    ase_io = pytest.importorskip("ase.io")
    out = tmp_path / "box.xyz"
    assert main(["export", str(trajectory), "--format", "xyz", "-o", str(out),
                 "--every", "2"]) == 0
    traj = read_trajectory(trajectory)
    images = ase_io.read(out, index=":", format="extxyz")
    frames = range(0, traj.n_frames, 2)
    assert len(images) == len(frames)
    states = motion_states(traj)
    um = XYZ_LENGTH_UNIT
    for atoms, f in zip(images, frames, strict=True):
        assert atoms.info["time"] == traj.time[f]
        assert atoms.info["step"] == traj.step[f]
        # ASE prints reals with 8 decimals: half a unit of the last one
        for got, want in ((atoms.positions, traj.position[f] / um),
                          (atoms.arrays["velocity"], traj.velocity[f] / um),
                          (atoms.arrays["angular_velocity"], traj.angular_velocity[f]),
                          (atoms.arrays["radius"], traj.radius / um),
                          (np.diag(atoms.cell), (traj.box_upper - traj.box_lower) / um)):
            assert np.allclose(got, want, rtol=0, atol=PRINTED)
        assert np.array_equal(atoms.arrays["material"], traj.material)
        assert np.array_equal(atoms.arrays["motion_state"], states[f])
        assert np.array_equal(atoms.arrays["id"], np.arange(traj.n_particles))
        assert tuple(atoms.pbc) == tuple(traj.periodic)


@pytest.fixture(scope="module")
def draining(tmp_path_factory):
    """An elastic gas that drains through an outlet (docs/open-systems.md)."""
    from hsgran.scene import parse_scene
    from tests.test_outlets import GAS

    path = tmp_path_factory.mktemp("export") / "gas.h5"
    run_scene(parse_scene(GAS.format(duration=0.2)), path)
    return path


def test_particles_that_left_are_not_exported(draining, tmp_path):
    """Each frame holds the particles in the system then, named by their id."""
    traj = read_trajectory(draining)
    here = traj.present
    assert not here[-1].all()
    if importlib.util.find_spec("pyvista") is not None:
        import pyvista as pv

        assert main(["export", str(draining), "--format", "vtk", "-o", str(tmp_path / "v")]) == 0
        reader = pv.PVDReader(tmp_path / "v" / "gas.pvd")
        for f, t in enumerate(traj.time):
            reader.set_active_time_value(t)
            spheres = reader.read()[0]
            assert np.array_equal(spheres.point_data["id"], np.flatnonzero(here[f]))
            assert np.array_equal(spheres.points, traj.position[f][here[f]])
    if importlib.util.find_spec("ase") is not None:
        import ase.io

        assert main(["export", str(draining), "--format", "xyz", "-o",
                     str(tmp_path / "g.xyz")]) == 0
        images = ase.io.read(tmp_path / "g.xyz", index=":", format="extxyz")
        for atoms, f in zip(images, range(traj.n_frames), strict=True):
            assert np.array_equal(atoms.arrays["id"], np.flatnonzero(here[f]))


def test_existing_output_bad_format_and_every_are_refused(trajectory, tmp_path, capsys):
    out = tmp_path / "a.xyz"
    out.write_text("keep me")
    assert main(["export", str(trajectory), "--format", "xyz", "-o", str(out)]) == 2
    assert out.read_text() == "keep me"
    assert "--force" in capsys.readouterr().err
    assert main(["export", str(trajectory), "--format", "xyz", "-o", str(out),
                 "--every", "0"]) == 2
    assert "--every" in capsys.readouterr().err
    assert main(["export", str(trajectory), "--format", "pdb"]) == 2
    assert "--format" in capsys.readouterr().err
