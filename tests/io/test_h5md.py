"""Trajectory files (hsgran.io.h5md): round trips, the H5MD 1.1 structure, bad files, interrupted
writers, and MDAnalysis reading what we write (docs/trajectory-format.md)."""

from __future__ import annotations

import gc
import json
import os
import select
import subprocess
import sys
import textwrap

import h5py
import numpy as np
import pytest

from hsgran.errors import InputError
from hsgran.io import Trajectory, TrajectoryWriter, read_trajectory
from hsgran.io.h5md import ENERGY_OBSERVABLES, EVENT_FIELDS, FRAME_FIELDS, Walls

N = 7
BLOCKS = (3, 1, 5)  # frames per appended block: uneven on purpose
SCENE = '[[materials]]\nname = "glass"\n# a scene with unicode: δ_max, µ\n'


def writer_args(*, angular=True, events=True, box=True, periodic=(True, False, False)):
    rng = np.random.default_rng(42)
    return dict(
        radius=rng.uniform(1e-3, 2e-3, N),
        mass=rng.uniform(1e-5, 2e-5, N),
        material=np.array([0, 1, 0, 1, 1, 0, 1]),
        material_names=["glass", "steel"],
        box_lower=np.array([-0.1, -0.2, 0.0]) if box else None,
        box_upper=np.array([0.1, 0.2, 0.5]) if box else None,
        periodic=periodic if box else (False, False, False),
        angular_velocity=angular,
        scene_text=SCENE,
        effects=["gravity", "rotation", "friction"] if angular else ["gravity"],
        seed=2**63 + 5,  # beyond int64: stored unsigned
        version="0.1.0",
        log_events=events,
        creator_args="hsgran run scene.toml -o out.h5",
        motion_state=angular,  # the optional fields come and go together in these tests
    )


def make_blocks(angular=True, seed=0):
    """Blocks of frames with random, full-precision values (bit-for-bit checks need them)."""
    rng = np.random.default_rng(seed)
    blocks, first = [], 0
    for size in BLOCKS:
        step = np.arange(first, first + size, dtype=np.int64)
        first += size
        blocks.append(
            dict(
                step=step,
                time=step * 1e-3 + rng.uniform(0, 1e-4, size),  # increasing: jitter < spacing
                position=rng.normal(size=(size, N, 3)),
                velocity=rng.normal(size=(size, N, 3)),
                angular_velocity=rng.normal(size=(size, N, 3)) if angular else None,
                kinetic_translational=rng.uniform(size=size),
                kinetic_rotational=rng.uniform(size=size) if angular else None,
                potential=rng.normal(size=size),
                dissipated=rng.uniform(size=size),
                motion_state=rng.integers(0, 5, (size, N), dtype=np.int8) if angular else None,
            )
        )
    return blocks


def make_events(size, seed=1, t0=0.0):
    rng = np.random.default_rng(seed)
    return dict(
        time=t0 + np.sort(rng.uniform(0, 1, size)),
        kind=rng.integers(0, 4, size, dtype=np.int8),
        i=rng.integers(0, N, size),
        j=rng.integers(-6, N, size),
        normal_impulse=rng.uniform(size=size),
        tangential_impulse=rng.normal(size=size),
        e_n=rng.uniform(size=size),
        stage=rng.integers(0, 4, size, dtype=np.int8),
        regime=rng.integers(0, 3, size, dtype=np.int8),
        velocity=rng.normal(size=(size, 3)),
    )


def concat(blocks, key):
    return np.concatenate([b[key] for b in blocks])


def write_file(path, *, angular=True, events=True, box=True, periodic=(True, False, False)):
    blocks = make_blocks(angular)
    event_blocks = [make_events(4, seed=1), make_events(6, seed=2, t0=1.0)]
    args = writer_args(angular=angular, events=events, box=box, periodic=periodic)
    with TrajectoryWriter(path, **args) as writer:
        for block in blocks:
            writer.append_frames(block)
        if events:
            for block in event_blocks:
                writer.append_events(block)
        writer.set_summary({"events": np.int64(10), "wall_time": 1.5, "e": np.array([1.0, 2.0])})
    return args, blocks, event_blocks


# -- round trip ---------------------------------------------------------------------------------


@pytest.mark.parametrize("angular", [True, False], ids=["rotation", "no-rotation"])
def test_round_trip_is_bit_for_bit(tmp_path, angular):
    path = tmp_path / "run.h5"
    args, blocks, event_blocks = write_file(path, angular=angular)
    traj = read_trajectory(path)

    assert isinstance(traj, Trajectory)
    assert traj.n_frames == sum(BLOCKS)
    assert traj.n_particles == N
    for key in ("step", "time", "position", "velocity"):
        np.testing.assert_array_equal(getattr(traj, key), concat(blocks, key), strict=True)
    if angular:
        expected = concat(blocks, "angular_velocity")
        np.testing.assert_array_equal(traj.angular_velocity, expected, strict=True)
        np.testing.assert_array_equal(traj.motion_state, concat(blocks, "motion_state"),
                                      strict=True)
    else:
        assert traj.angular_velocity is None
        assert traj.motion_state is None
    names = set(ENERGY_OBSERVABLES) - {"exited_energy", "entered_energy"} - (
        set() if angular else {"kinetic_energy_rotational"})
    assert set(traj.energies) == names
    for name in names:
        expected = concat(blocks, ENERGY_OBSERVABLES[name])
        np.testing.assert_array_equal(traj.energies[name], expected, strict=True)

    np.testing.assert_array_equal(traj.radius, args["radius"], strict=True)
    np.testing.assert_array_equal(traj.mass, args["mass"], strict=True)
    np.testing.assert_array_equal(traj.material, args["material"])
    assert traj.material_names == ["glass", "steel"]
    np.testing.assert_array_equal(traj.box_lower, args["box_lower"], strict=True)
    np.testing.assert_array_equal(traj.box_upper, args["box_upper"], strict=True)
    assert traj.periodic == (True, False, False)
    assert traj.scene_text == SCENE
    assert traj.effects == args["effects"]
    assert traj.seed == 2**63 + 5
    assert traj.version == "0.1.0"
    assert traj.creator_args == args["creator_args"]
    assert traj.summary == {"events": 10, "wall_time": 1.5, "e": [1.0, 2.0]}
    assert traj.complete is True

    assert set(traj.events) == set(EVENT_FIELDS)
    for name, (dtype, _unit) in EVENT_FIELDS.items():
        expected = concat(event_blocks, name).astype(dtype)
        np.testing.assert_array_equal(traj.events[name], expected, strict=True)


def test_an_event_log_of_format_1_reads_with_nan_velocities(tmp_path):
    """Files written before the event log had ``velocity`` (format_version 1) still read."""
    path = tmp_path / "old.h5"
    _, _, event_blocks = write_file(path)
    with h5py.File(path, "r+") as f:
        del f["hsgran/events/velocity"]
    traj = read_trajectory(path)
    assert traj.events["velocity"].shape == (10, 3)
    assert np.isnan(traj.events["velocity"]).all()
    np.testing.assert_array_equal(traj.events["time"], concat(event_blocks, "time"))


def test_the_id_of_an_open_system_marks_absent_particles(tmp_path):
    """With ``open_system=True`` the frames carry H5MD's ``id`` (fill value −1 for a particle not in
    the system) and the energy carried out."""
    path = tmp_path / "open.h5"
    blocks = make_blocks()
    with TrajectoryWriter(path, **writer_args(), open_system=True) as writer:
        for b in blocks:
            ids = np.broadcast_to(np.arange(N), (b["step"].size, N)).copy()
            ids[b["step"] % 3 == 0, 2] = -1
            writer.append_frames(dict(b, id=ids, exited=np.ones(b["step"].size),
                                      entered=np.zeros(b["step"].size)))
    traj = read_trajectory(path)
    assert np.array_equal(traj.present[:, 2], concat(blocks, "step") % 3 != 0)
    assert traj.present[:, [0, 1, 3]].all()
    np.testing.assert_array_equal(traj.energies["exited_energy"], np.ones(traj.n_frames))
    with h5py.File(path, "r") as f:
        assert f["particles/all/id/value"].fillvalue == -1
    write_file(tmp_path / "closed.h5")
    closed = read_trajectory(tmp_path / "closed.h5")
    assert closed.id is None
    assert closed.present.all()


def test_without_box_or_events(tmp_path):
    path = tmp_path / "free.h5"
    write_file(path, box=False, events=False)
    traj = read_trajectory(path)
    assert traj.box_lower is None
    assert traj.box_upper is None
    assert traj.periodic == (False, False, False)
    assert traj.events is None
    with h5py.File(path, "r") as f:
        assert "edges" not in f["particles/all/box"]
        assert "hsgran" not in f  # no event log group at all


def test_empty_blocks_and_zero_frames(tmp_path):
    path = tmp_path / "empty.h5"
    args = writer_args(angular=False)
    with TrajectoryWriter(path, **args) as writer:
        writer.append_frames(dict(
            step=np.empty(0, np.int64),
            time=np.empty(0),
            position=np.empty((0, N, 3)),
            velocity=np.empty((0, N, 3)),
            angular_velocity=None,
            kinetic_translational=np.empty(0),
            kinetic_rotational=None,
            potential=np.empty(0),
            dissipated=np.empty(0),
        ))
        writer.append_events(make_events(0))
        assert writer.n_frames == 0
    traj = read_trajectory(path)
    assert traj.position.shape == (0, N, 3)
    assert traj.events["time"].shape == (0,)
    assert traj.summary == {}
    assert traj.complete


# -- H5MD structure -----------------------------------------------------------------------------


def test_file_has_the_h5md_1_1_structure(tmp_path):
    path = tmp_path / "run.h5"
    write_file(path, angular=True)
    with h5py.File(path, "r") as f:
        np.testing.assert_array_equal(f["h5md"].attrs["version"], [1, 1])
        assert f["h5md/author"].attrs["name"] == b"hsgran user"
        assert f["h5md/creator"].attrs["name"] == b"hsgran"
        assert f["h5md/creator"].attrs["version"] == b"0.1.0"
        assert f["h5md/modules/units"].attrs["system"] == "SI"

        particles = f["particles/all"]
        position = particles["position"]
        elements = {
            "particles/all/position": "m",
            "particles/all/velocity": "m s-1",
            "particles/all/angular_velocity": "rad s-1",
            "particles/all/box/edges": "m",
        }
        elements.update({f"observables/{name}": "J" for name, field in ENERGY_OBSERVABLES.items()
                         if FRAME_FIELDS[field].switch != "open_system"})
        assert f["particles/all/velocity/value"] != position["value"]  # the == below means it
        for name, unit in elements.items():
            element = f[name]
            assert set(element) == {"step", "time", "value"}, name
            # step and time are hard links to one pair of datasets, not copies
            assert element["step"] == position["step"], name
            assert element["time"] == position["time"], name
            value = element["value"]
            assert value.attrs["unit"] == unit, name
            assert value.shape[0] == sum(BLOCKS)
            assert value.maxshape[0] is None
            assert value.chunks is not None
            assert value.compression == "lzf"
            assert value.shuffle
        assert position["time"].attrs["unit"] == "s"
        assert position["step"].dtype == np.int64
        assert position["value"].shape == (sum(BLOCKS), N, 3)
        assert f["observables/potential_energy/value"].shape == (sum(BLOCKS),)
        assert particles["box/edges/value"].shape == (sum(BLOCKS), 3)
        np.testing.assert_array_equal(particles["box/edges/value"][0], [0.2, 0.4, 0.5])

        box = particles["box"]
        assert box.attrs["dimension"] == 3
        boundary = box.attrs["boundary"]
        assert boundary.dtype.kind == "S"  # fixed-length strings, as H5MD asks
        assert list(boundary) == [b"periodic", b"none", b"none"]

        for name, unit in (("radius", "m"), ("mass", "kg"), ("species", None)):
            dset = particles[name]
            assert isinstance(dset, h5py.Dataset)
            assert dset.shape == (N,)
            assert dset.attrs.get("unit") == unit
        assert np.issubdtype(particles["species"].dtype, np.integer)

        params = f["parameters/hsgran"].attrs
        assert bool(params["complete"]) is True
        assert params["scene_text"] == SCENE
        assert list(params["effects"]) == ["gravity", "rotation", "friction"]
        assert list(params["material_names"]) == ["glass", "steel"]
        assert json.loads(params["summary"])["events"] == 10

        events = f["hsgran/events"]
        assert set(events) == set(EVENT_FIELDS)
        assert events["time"].attrs["unit"] == "s"
        assert events["normal_impulse"].attrs["unit"] == "kg m s-1"
        assert all(events[name].maxshape[0] is None for name in EVENT_FIELDS)
        assert events["velocity"].shape[1:] == (3,)


def test_box_edges_only_when_an_axis_is_periodic(tmp_path):
    path = tmp_path / "walls.h5"
    write_file(path, periodic=(False, False, False))
    with h5py.File(path, "r") as f:
        assert "edges" not in f["particles/all/box"]
        assert list(f["particles/all/box"].attrs["boundary"]) == [b"none"] * 3
    traj = read_trajectory(path)
    np.testing.assert_array_equal(traj.box_upper, [0.1, 0.2, 0.5])


# -- bad files ----------------------------------------------------------------------------------


def assert_one_line_input_error(path, fragment):
    with pytest.raises(InputError) as info:
        read_trajectory(path)
    message = str(info.value)
    assert "\n" not in message
    assert fragment in message
    return message


def test_missing_file_is_an_input_error(tmp_path):
    assert_one_line_input_error(tmp_path / "nope.h5", "not found")


def test_directory_is_an_input_error(tmp_path):
    assert_one_line_input_error(tmp_path, "directory")


@pytest.mark.parametrize("content", [b"", b"not hdf5 at all\n" * 100], ids=["empty", "text"])
def test_non_hdf5_file_is_an_input_error(tmp_path, content):
    path = tmp_path / "scene.toml"
    path.write_bytes(content)
    assert_one_line_input_error(path, "not an HDF5 file")


def test_foreign_hdf5_file_is_an_input_error(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f["data"] = np.arange(3)
    assert_one_line_input_error(path, "not an hsgran trajectory")


def test_damaged_trajectory_is_an_input_error(tmp_path):
    path = tmp_path / "run.h5"
    write_file(path)
    with h5py.File(path, "a") as f:
        del f["particles/all/velocity"]
    assert_one_line_input_error(path, "velocity")


# -- interrupted writers ------------------------------------------------------------------------


def test_writer_dropped_without_close_still_reads(tmp_path):
    path = tmp_path / "dropped.h5"
    writer = TrajectoryWriter(path, **writer_args())
    blocks = make_blocks()
    for block in blocks[:2]:
        writer.append_frames(block)
    del writer
    gc.collect()
    traj = read_trajectory(path)
    assert traj.complete is False
    assert traj.summary == {}
    np.testing.assert_array_equal(traj.position, concat(blocks[:2], "position"))


def test_writer_killed_with_sigkill_leaves_a_readable_file(tmp_path):
    path = tmp_path / "killed.h5"
    child = textwrap.dedent(
        f"""
        import sys, time
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        from test_h5md import make_blocks, make_events, writer_args
        from hsgran.io import TrajectoryWriter
        writer = TrajectoryWriter({str(path)!r}, **writer_args())
        for block in make_blocks()[:2]:
            writer.append_frames(block)
        writer.append_events(make_events(4))
        print("appended", flush=True)
        time.sleep(60)
        """
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", child], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        ready, _, _ = select.select([proc.stdout], [], [], 60)
        assert ready, "the writing process never reported its appends"
        line = proc.stdout.readline()
        assert line.strip() == "appended", proc.stderr.read()
        # a running simulation's file can be read while its writer holds it open
        np.testing.assert_array_equal(read_trajectory(path).step, np.arange(sum(BLOCKS[:2])))
    finally:
        proc.kill()  # SIGKILL: no clean-up of any kind runs
        proc.wait(timeout=10)
    traj = read_trajectory(path)
    blocks = make_blocks()
    assert traj.complete is False
    np.testing.assert_array_equal(traj.position, concat(blocks[:2], "position"), strict=True)
    np.testing.assert_array_equal(traj.time, concat(blocks[:2], "time"), strict=True)
    np.testing.assert_array_equal(traj.events["i"], make_events(4)["i"])


def test_half_written_block_is_dropped_whole(tmp_path):
    # A writer killed inside append_frames has written some values but not step/time.
    path = tmp_path / "cut.h5"
    write_file(path)
    with h5py.File(path, "a") as f:
        f["particles/all/position/step"].resize(4, axis=0)
        f["hsgran/events/time"].resize(3, axis=0)
    traj = read_trajectory(path)
    assert traj.n_frames == 4
    assert traj.velocity.shape == (4, N, 3)
    assert traj.energies["potential_energy"].shape == (4,)
    assert all(values.shape[0] == 3 for values in traj.events.values())


def test_exception_in_with_block_leaves_file_incomplete(tmp_path):
    path = tmp_path / "failed.h5"
    blocks = make_blocks()

    def failing_run():
        with TrajectoryWriter(path, **writer_args()) as writer:
            writer.append_frames(blocks[0])
            raise RuntimeError("engine failed")

    with pytest.raises(RuntimeError, match="engine failed"):
        failing_run()
    traj = read_trajectory(path)
    assert traj.complete is False
    assert traj.n_frames == BLOCKS[0]


# -- writer checks ------------------------------------------------------------------------------


def test_writer_rejects_mismatched_arrays(tmp_path):
    blocks = make_blocks()
    with TrajectoryWriter(tmp_path / "w.h5", **writer_args(events=False)) as writer:
        bad = dict(blocks[0], position=blocks[0]["position"][:, :-1])
        with pytest.raises(ValueError, match="position"):
            writer.append_frames(bad)
        with pytest.raises(ValueError, match="angular_velocity"):
            writer.append_frames(dict(blocks[0], angular_velocity=None))
        with pytest.raises(ValueError, match="motion_state=True"):
            writer.append_frames(dict(blocks[0], motion_state=None))
        with pytest.raises(ValueError, match="motion_state"):
            writer.append_frames(dict(blocks[0], motion_state=blocks[0]["motion_state"][:1]))
        with pytest.raises(ValueError, match="log_events=False"):
            writer.append_events(make_events(2))
        writer.append_frames(blocks[1])
        with pytest.raises(ValueError, match="non-decreasing"):
            writer.append_frames(blocks[0])
        assert writer.n_frames == BLOCKS[1]
    with pytest.raises(ValueError, match="closed"):
        writer.append_frames(blocks[2])
    writer.close()  # a second close does nothing


def test_writer_rejects_bad_setup(tmp_path):
    with pytest.raises(InputError, match="periodic axis needs a box"):
        TrajectoryWriter(tmp_path / "a.h5", **dict(writer_args(box=False), periodic=(1, 0, 0)))
    with pytest.raises(ValueError, match="material"):
        TrajectoryWriter(tmp_path / "b.h5", **dict(writer_args(), material_names=["glass"]))
    with pytest.raises(InputError, match="cannot create"):
        TrajectoryWriter(tmp_path / "no" / "such" / "dir.h5", **writer_args())



def test_the_frame_table_lists_every_field_of_the_engines_blocks():
    # a field added to a block but not to the table (or the reverse) is caught here
    from dataclasses import fields

    from hsgran.engine import EventBlock, FrameBlock

    assert {f.name for f in fields(FrameBlock)} == {"step", "time", *FRAME_FIELDS}
    assert {f.name for f in fields(EventBlock)} == set(EVENT_FIELDS)
    trajectory_fields = {f.name for f in fields(Trajectory)}
    for name, spec in FRAME_FIELDS.items():
        if spec.path.startswith("particles/all/"):
            assert name in trajectory_fields, name


def test_the_writer_takes_the_engines_blocks(tmp_path):
    from hsgran.engine import EventBlock, FrameBlock

    path = tmp_path / "blocks.h5"
    blocks = make_blocks()
    events = make_events(5)
    with TrajectoryWriter(path, **writer_args()) as writer:
        for block in blocks:
            writer.append_frames(FrameBlock(**block))
        writer.append_events(EventBlock(**events))
    traj = read_trajectory(path)
    for name in ("position", "velocity", "angular_velocity", "motion_state"):
        np.testing.assert_array_equal(getattr(traj, name), concat(blocks, name), strict=True)
    for observable, name in ENERGY_OBSERVABLES.items():
        if FRAME_FIELDS[name].switch != "open_system":  # (a closed system's blocks)
            np.testing.assert_array_equal(traj.energies[observable], concat(blocks, name))
    for name, (dtype, _unit) in EVENT_FIELDS.items():
        np.testing.assert_array_equal(traj.events[name], events[name].astype(dtype))


def test_a_mapping_with_an_unknown_or_missing_field_is_refused(tmp_path):
    block = make_blocks()[0]
    with TrajectoryWriter(tmp_path / "w.h5", **writer_args()) as writer:
        with pytest.raises(ValueError, match="unknown field 'positon'"):
            writer.append_frames(dict(block, positon=block["position"]))
        without = {k: v for k, v in block.items() if k != "dissipated"}
        with pytest.raises(ValueError, match="dissipated: required"):
            writer.append_frames(without)
        events = make_events(3)
        del events["regime"]
        with pytest.raises(ValueError, match="regime: required"):
            writer.append_events(events)
        assert writer.n_frames == 0
        assert writer.n_events == 0


def floor_and_ramp():
    """Two walls: a floor of material 0 and a tilted ramp of material 1."""
    return Walls(point=np.array([[0.0, 0.0, 0.0], [0.05, 0.0, 0.01]]),
                 normal=np.array([[0.0, 0.0, 1.0], [-0.6, 0.0, 0.8]]),
                 material=np.array([0, 1]), key=["walls[0]", "walls[1]"])


def test_walls_pair_table_and_scene_name_round_trip(tmp_path):
    path = tmp_path / "walls.h5"
    walls = floor_and_ramp()
    table = np.random.default_rng(3).normal(size=(2, 2, 14))
    table[1, 1] = np.nan  # two rigid walls: no contact law
    with TrajectoryWriter(path, **writer_args(), walls=walls, pair_table=table,
                          scene_name="ramp", overrides={"walls[1].normal": [-0.6, 0.0, 0.8]}):
        pass
    traj = read_trajectory(path)
    np.testing.assert_array_equal(traj.walls.point, walls.point, strict=True)
    np.testing.assert_array_equal(traj.walls.normal, walls.normal, strict=True)
    np.testing.assert_array_equal(traj.walls.material, [0, 1])
    assert traj.walls.key == ["walls[0]", "walls[1]"]
    assert traj.scene_name == "ramp"
    assert traj.overrides == {"walls[1].normal": [-0.6, 0.0, 0.8]}
    np.testing.assert_array_equal(traj.pair_table, table, strict=True)
    with h5py.File(path, "r") as f:
        group = f["parameters/hsgran/walls"]
        assert set(group) == {"point", "normal", "material", "key"}
        assert group["point"].attrs["unit"] == "m"
        assert f["parameters/hsgran/pair_table"].shape == (2, 2, 14)


def test_no_walls_differs_from_walls_not_stored(tmp_path):
    with TrajectoryWriter(tmp_path / "none.h5", **writer_args(), walls=Walls.of([])):
        pass
    with TrajectoryWriter(tmp_path / "old.h5", **writer_args()):
        pass
    empty = read_trajectory(tmp_path / "none.h5").walls
    assert len(empty) == 0
    assert empty.point.shape == (0, 3)
    old = read_trajectory(tmp_path / "old.h5")
    assert old.walls is None
    assert old.pair_table is None
    assert old.scene_name == ""


def test_bad_walls_and_pair_table_are_refused(tmp_path):
    walls = floor_and_ramp()
    walls.material[1] = 2  # only two material names
    with pytest.raises(ValueError, match=r"walls\.material"):
        TrajectoryWriter(tmp_path / "a.h5", **writer_args(), walls=walls)
    with pytest.raises(ValueError, match="pair_table"):
        TrajectoryWriter(tmp_path / "b.h5", **writer_args(), pair_table=np.zeros((3, 3, 14)))
    assert not list(tmp_path.iterdir())  # refused before any file was made


# -- MDAnalysis ---------------------------------------------------------------------------------


@pytest.fixture
def mdanalysis_reads_metres(monkeypatch):
    """MDAnalysis (2.x) knows no length unit "m": register it, as docs/trajectory-format.md says.

    Its H5MD reader raises RuntimeError for a unit missing from its table even with
    ``convert_units=False``; the three entries below teach it metres (1 m = 1e10 Å).
    """
    mda = pytest.importorskip("MDAnalysis")
    from MDAnalysis import units
    from MDAnalysis.coordinates.H5MD import H5MDReader

    monkeypatch.setitem(H5MDReader._unit_translation["length"], "m", "m")
    monkeypatch.setitem(units.lengthUnit_factor, "m", 1e-10)
    monkeypatch.setitem(units.unit_types, "m", "length")
    return mda


@pytest.mark.parametrize("convert_units", [False, True], ids=["SI", "angstrom"])
def test_mdanalysis_reads_the_trajectory(tmp_path, mdanalysis_reads_metres, convert_units):
    mda = mdanalysis_reads_metres
    path = tmp_path / "run.h5"
    write_file(path)
    traj = read_trajectory(path)

    universe = mda.Universe.empty(N, trajectory=True)
    universe.load_new(str(path), format="H5MD", convert_units=convert_units)
    assert universe.trajectory.n_frames == traj.n_frames
    positions = np.array([ts.positions.copy() for ts in universe.trajectory])
    times = np.array([ts.time for ts in universe.trajectory])
    box = universe.trajectory[0].dimensions
    energy = universe.trajectory[2].data["potential_energy"]
    scale_length, scale_time = (1e10, 1e12) if convert_units else (1.0, 1.0)  # Å, ps

    # MDAnalysis holds positions in float32
    if convert_units:
        np.testing.assert_allclose(positions, traj.position * scale_length, rtol=1e-6)
    else:
        np.testing.assert_array_equal(positions, traj.position.astype(np.float32))
    np.testing.assert_allclose(times, traj.time * scale_time, rtol=1e-12)
    np.testing.assert_allclose(box[:3], (traj.box_upper - traj.box_lower) * scale_length)
    np.testing.assert_array_equal(box[3:], [90, 90, 90])
    assert energy == traj.energies["potential_energy"][2]


@pytest.mark.parametrize("convert_units", [False, True], ids=["SI", "angstrom"])
def test_one_call_helper_gives_the_same_universe(tmp_path, mdanalysis_reads_metres,
                                                 convert_units):
    from hsgran.io.mdanalysis import universe

    path = tmp_path / "run.h5"
    write_file(path)
    mine = universe(path, convert_units=convert_units)
    by_hand = mdanalysis_reads_metres.Universe.empty(N, trajectory=True)
    by_hand.load_new(str(path), format="H5MD", convert_units=convert_units)
    assert mine.trajectory.n_frames == by_hand.trajectory.n_frames
    for a, b in zip(mine.trajectory, by_hand.trajectory, strict=True):
        np.testing.assert_array_equal(a.positions, b.positions)
        assert a.time == b.time


def test_mdanalysis_sees_no_cell_in_a_walled_box(tmp_path, mdanalysis_reads_metres):
    path = tmp_path / "walls.h5"
    write_file(path, periodic=(False, False, False))
    universe = mdanalysis_reads_metres.Universe.empty(N, trajectory=True)
    universe.load_new(str(path), format="H5MD")
    assert universe.dimensions is None
