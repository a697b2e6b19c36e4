"""World.record_series: the ParaView time series of `torsion run --vtk-every`, written by the same
code from Python. The files are read back here without VTK: the XML header with xml.etree, the
appended arrays (zlib-compressed when the build has zlib) with struct and zlib."""

import struct
import xml.etree.ElementTree as ET
import zlib

import numpy as np
import pytest

import torsion
from conftest import cube_mesh

APPENDED = b'<AppendedData encoding="raw">\n   _'
NUMPY_TYPE = {"Float64": np.float64, "Int64": np.int64, "UInt8": np.uint8}


def falling_cube(rigid=False):
    world = torsion.World(gravity=(0, 0, -9.81), dt=0.01, threads=1)
    nodes, tets = cube_mesh(cells=2)
    cube = world.add_body("cube", nodes=nodes, tets=tets,
                          material=torsion.Material(E=1e5, nu=0.3, rho=100))
    if rigid:
        world.add_rigid_body("plate", "box", half_extents=(0.6, 0.6, 0.1), mass=0.0,
                             frame=torsion.Frame(position=(0.5, 0.5, -1.0)))
    return world, cube


def read_vtu(path):
    """(root element, {array name: numpy array of shape (tuples, components)})."""
    data = path.read_bytes()
    head, tail = data.split(APPENDED)
    root = ET.fromstring(head + b"</VTKFile>")
    compressed = root.get("compressor") == "vtkZLibDataCompressor"
    arrays = {}
    for array in root.iter("DataArray"):
        at = int(array.get("offset"))
        if compressed:
            blocks, raw_size, _, size = struct.unpack_from("<4Q", tail, at)
            assert blocks == 1
            raw = zlib.decompress(tail[at + 32:at + 32 + size])
            assert len(raw) == raw_size
        else:
            (size,) = struct.unpack_from("<Q", tail, at)
            raw = tail[at + 8:at + 8 + size]
        values = np.frombuffer(raw, dtype=NUMPY_TYPE[array.get("type")])
        arrays[array.get("Name")] = values.reshape(-1, int(array.get("NumberOfComponents", "1")))
    return root, arrays


def pvd_entries(directory):
    root = ET.parse(directory / "series.pvd").getroot()
    return [(float(d.get("timestep")), int(d.get("part")), d.get("file"))
            for d in root.iter("DataSet")]


def test_every_fifth_step_of_twenty_is_written_and_reads_back_as_the_world_is(tmp_path):
    world, cube = falling_cube()
    world.record_series(tmp_path, every=5)
    assert world.recording_series
    assert len(pvd_entries(tmp_path)) == 1  # listed from the start, as each step is written
    world.step(7)  # the steps due fall inside step(n): written in its loop
    world.step(13)
    world.stop_series()  # step 20 was written: nothing more
    assert not world.recording_series
    assert world.series_steps_written == 5

    entries = pvd_entries(tmp_path)
    assert [e[2] for e in entries] == [f"series/cube_{s:06d}.vtu" for s in (0, 5, 10, 15, 20)]
    assert all(e[1] == 0 for e in entries)
    times = [e[0] for e in entries]
    assert all(b > a for a, b in zip(times, times[1:]))
    assert times[-1] == pytest.approx(world.time, rel=1e-12)
    for step, (_, _, file) in zip((0, 5, 10, 15, 20), entries):
        root, arrays = read_vtu(tmp_path / file)
        piece = root.find("UnstructuredGrid/Piece")
        assert int(piece.get("NumberOfPoints")) == cube.node_count
        assert int(piece.get("NumberOfCells")) == cube.element_count
        assert arrays["step"][0, 0] == step
    _, arrays = read_vtu(tmp_path / entries[-1][2])
    assert np.abs(arrays["Points"] - cube.positions).max() <= 1e-12
    displacement = cube.positions - cube.rest_positions
    assert np.abs(displacement).max() > 1e-3  # it fell: the comparison below means something
    assert np.abs(arrays["displacement"] - displacement).max() <= 1e-12
    assert np.abs(arrays["displacement"][-1] - displacement[-1]).max() <= 1e-12
    assert np.abs(arrays["velocity"] - cube.velocities).max() <= 1e-12
    assert arrays["TimeValue"][0, 0] == pytest.approx(world.time, rel=1e-12)


def test_stop_series_writes_the_last_state_and_a_new_series_empties_the_old_files(tmp_path):
    world, cube = falling_cube(rigid=True)
    world.step(3)  # a series may start at any step: numbered by the world's step count
    world.record_series(str(tmp_path), every=5)
    world.step(7)
    world.stop_series()
    world.stop_series()  # ended: nothing
    assert world.series_steps_written == 3
    files = [e[2] for e in pvd_entries(tmp_path)]
    assert files == [f"series/{name}_{s:06d}.vtu" for s in (3, 8, 10)
                     for name in ("cube", "rigid_plate")]
    root, arrays = read_vtu(tmp_path / "series/rigid_plate_000010.vtu")
    assert int(root.find("UnstructuredGrid/Piece").get("NumberOfCells")) == 12  # a box
    np.testing.assert_allclose(arrays["position"][0], (0.5, 0.5, -1.0))

    world.record_series(tmp_path, every=1)
    world.step()
    world.stop_series()
    assert sorted(p.name for p in (tmp_path / "series").iterdir()) == [
        "cube_000010.vtu", "cube_000011.vtu", "rigid_plate_000010.vtu", "rigid_plate_000011.vtu"]
    assert world.series_steps_written == 2


@pytest.mark.parametrize("every", [0, -1])
def test_every_below_one_is_a_value_error_that_changes_nothing(tmp_path, every):
    world, _ = falling_cube()
    with pytest.raises(ValueError, match="every must be >= 1"):
        world.record_series(tmp_path / "out", every=every)
    assert not (tmp_path / "out").exists()
    assert not world.recording_series


def test_a_second_series_is_a_value_error(tmp_path):
    world, _ = falling_cube()
    world.record_series(tmp_path / "a")
    with pytest.raises(ValueError, match="a series is being recorded"):
        world.record_series(tmp_path / "b")
    assert not (tmp_path / "b").exists()
    assert world.recording_series


def test_a_directory_that_cannot_be_created_is_a_value_error_naming_it(tmp_path):
    world, _ = falling_cube()
    (tmp_path / "file").write_text("not a directory")
    target = tmp_path / "file" / "out"
    with pytest.raises(ValueError, match=str(target)):
        world.record_series(target)
    assert not world.recording_series
    with pytest.raises(TypeError):
        world.record_series(42)
    with pytest.raises(TypeError):
        world.record_series(bytes(tmp_path))


def test_a_file_that_cannot_be_written_raises_os_error_naming_it_and_ends_the_series(tmp_path):
    world, cube = falling_cube()
    world.record_series(tmp_path, every=5)
    blocked = tmp_path / "series" / "cube_000005.vtu"
    blocked.mkdir()  # a directory where step 5's file goes: written by no one, as root too
    with pytest.raises(OSError, match=str(blocked)):
        world.step(8)
    assert not world.recording_series
    assert world.series_steps_written == 1
    assert world.step_count == 5  # the world is as after the steps done
    world.step(3)  # and goes on without a series
    world.stop_series()
    assert world.step_count == 8
