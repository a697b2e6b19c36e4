"""The ParaView series of `torsion run --vtk-every N`, read back by two independent readers
(meshio, and VTK's own XML reader as ParaView uses it) and compared with the run's state.

    vtk_series_check.py CASE TORSION SCENES_DIR ASSETS_DIR

Each case runs the tool in a temporary directory and asserts facts that hold for any correct
writer: positions equal to those of a separate run stopped at that step (1e-12 relative of the
body's size; the runs are deterministic, so in practice exactly), displacement = position - rest,
velocity = (x_k - x_{k-1}) / dt (the backward Euler position update), tet10 mid-edge nodes in
VTK's order, wrenches equal to wrench.csv, rigid surfaces centred on rigid.csv's positions.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import meshio
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

CASE, TORSION, SCENES, ASSETS = sys.argv[1:5]


def scene(work, name, edit=None):
    text = open(os.path.join(SCENES, name + ".json")).read().replace("../../assets/meshes", ASSETS)
    path = os.path.join(work, name + ".json")
    open(path, "w").write(edit(text) if edit else text)
    return path


def run(work, scene_path, out, *args):
    result = subprocess.run([TORSION, "run", scene_path, "--out", os.path.join(work, out),
                             "--threads", "1", *args], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return os.path.join(work, out), result.stderr


def pvd_entries(out):
    text = open(os.path.join(out, "series.pvd")).read()
    return [(float(t), int(p), f) for t, p, f in
            re.findall(r'<DataSet timestep="([^"]+)" part="(\d+)" file="([^"]+)"/>', text)]


def read_vtk(path):
    """VTK's reader: points and the named point array, as ParaView gets them."""
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    assert grid.GetNumberOfPoints() > 0, path
    return grid


def close(a, b, scale, rel=1e-12):
    worst = float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
    assert worst <= rel * scale, f"difference {worst} > {rel} * {scale}"


def size_of(points):
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def twist_series(work):
    path = scene(work, "twist_cylinder_2430")
    out, err = run(work, path, "a", "--steps", "10", "--vtk-every", "3")
    assert "series: " in err and "series.pvd (5 steps" in err, err
    entries = pvd_entries(out)
    steps = [int(re.search(r"_(\d+)\.vtu", f).group(1)) for _, _, f in entries]
    assert steps == [0, 3, 6, 9, 10], steps
    times = [t for t, _, _ in entries]
    # Bullet's clock sums dt in btScalar: on float Bullet 0.01f is 2e-10 s short, 2e-9 s in 10 steps.
    assert np.allclose(times, [0, 0.03, 0.06, 0.09, 0.10], rtol=0, atol=1e-8), times
    return path, out


def case_positions_match_the_state():
    with tempfile.TemporaryDirectory() as work:
        path, out = twist_series(work)
        rest = meshio.read(os.path.join(out, "series", "cylinder_000000.vtu"))
        scale = size_of(rest.points)
        for step in (3, 6):
            # A run stopped at that step wrote its final state to cylinder.vtk (%.17g: exact).
            stopped, _ = run(work, path, f"stop{step}", "--steps", str(step))
            final = meshio.read(os.path.join(stopped, "cylinder.vtk"))
            m = meshio.read(os.path.join(out, "series", f"cylinder_{step:06d}.vtu"))
            close(m.points, final.points, scale)
            close(m.point_data["displacement"], m.points - rest.points, scale)
            g = read_vtk(os.path.join(out, "series", f"cylinder_{step:06d}.vtu"))
            close(vtk_to_numpy(g.GetPoints().GetData()), m.points, scale, rel=0)
        last = meshio.read(os.path.join(out, "series", "cylinder_000010.vtu"))
        close(last.points, meshio.read(os.path.join(out, "cylinder.vtk")).points, scale)
        # Cells: the 2408 tets of the mesh, stress and strain of a twisted, upright cylinder.
        assert [c.type for c in last.cells] == ["tetra"] and len(last.cells[0].data) == 2408
        vm = last.cell_data["von_mises"][0]
        assert vm.min() >= 0 and vm.max() > 0, (vm.min(), vm.max())
        assert 0 < last.cell_data["strain"][0].max() < 0.1
        assert not last.cell_data["inverted"][0].any()


def case_velocity_is_the_position_update():
    with tempfile.TemporaryDirectory() as work:
        path = scene(work, "twist_cylinder_2430")
        out, _ = run(work, path, "a", "--steps", "4", "--vtk-every", "1")
        dt = json.load(open(os.path.join(out, "summary.json")))["dt"]
        x = [meshio.read(os.path.join(out, "series", f"cylinder_{k:06d}.vtu")) for k in range(5)]
        assert not x[0].point_data["velocity"].any(), "the cylinder starts at rest"
        for k in range(1, 5):
            v = x[k].point_data["velocity"]
            speed = float(np.abs(v).max())
            assert speed > 0
            # 1e-7: on float Bullet the step's dt is 0.01f, 2e-8 relative off the summary's dt.
            close(v, (x[k].points - x[k - 1].points) / dt, speed, rel=1e-7)


def case_wrenches_are_field_data():
    with tempfile.TemporaryDirectory() as work:
        _, out = twist_series(work)
        rows = np.loadtxt(os.path.join(out, "wrench.csv"), delimiter=",", skiprows=1)
        header = open(os.path.join(out, "wrench.csv")).readline().strip().split(",")
        g = read_vtk(os.path.join(out, "series", "cylinder_000006.vtu"))
        fields = g.GetFieldData()
        # 1e-8 s: the clocks agree to the bit on double Bullet; float Bullet's sums dt in float.
        assert abs(vtk_to_numpy(fields.GetArray("TimeValue"))[0] - rows[5, 1]) < 1e-8
        for name in ("base", "hand"):
            w = vtk_to_numpy(fields.GetArray("wrench_" + name)).ravel()
            cols = [header.index(f"{name}.{c}") for c in ("fx", "fy", "fz", "tx", "ty", "tz")]
            for part in (slice(0, 3), slice(3, 6)):  # forces, then torques, each to its size
                scale = np.abs(rows[:, cols[part]]).max()
                close(w[part], rows[5, cols[part]], max(scale, 1e-300), rel=1e-9)


def rotation(q):
    """Rotation matrix of the quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def case_hand_patch_and_frame():
    # The grabbed nodes are carried rigidly by the hand's frame: their coordinates in that frame
    # are the same at every written step, while the frame itself turns; they lie near its plane
    # (the plane cuts their triangles: within one element of it).
    with tempfile.TemporaryDirectory() as work:
        _, out = twist_series(work)
        local, angles = [], []
        for step in (3, 6, 9):
            g = read_vtk(os.path.join(out, "series", f"cylinder_{step:06d}.vtu"))
            flags = vtk_to_numpy(g.GetPointData().GetArray("grabbed_hand"))
            grabbed = np.flatnonzero(flags == 1)
            assert len(grabbed) > 0 and set(np.unique(flags)) <= {0.0, 1.0}
            frame = vtk_to_numpy(g.GetFieldData().GetArray("hand_frame_hand")).ravel()
            origin, q = frame[:3], frame[3:]
            assert abs(np.linalg.norm(q) - 1) < 1e-12
            R = rotation(q)
            x = vtk_to_numpy(g.GetPoints().GetData())[grabbed]
            p_hat = (x - origin) @ R  # R^T (x - O), row by row
            local.append(p_hat)
            angles.append(np.arctan2(R[1, 0], R[0, 0]))
            size = size_of(vtk_to_numpy(g.GetPoints().GetData()))
            assert np.abs(p_hat[:, 2]).max() < 0.1 * size, np.abs(p_hat[:, 2]).max()
        for p_hat in local[1:]:
            close(p_hat, local[0], np.abs(local[0]).max(), rel=1e-9)
        assert abs(angles[2] - angles[0]) > 1e-3, angles  # the hand turned in between


def case_tet10_cells_in_vtk_order():
    with tempfile.TemporaryDirectory() as work:
        path = scene(work, "twist_cylinder_2430_tet10")
        out, _ = run(work, path, "a", "--steps", "2", "--vtk-every", "1")
        summary = json.load(open(os.path.join(out, "summary.json")))
        body = summary["bodies"][0]
        m = meshio.read(os.path.join(out, "series", "cylinder_000000.vtu"))
        assert [c.type for c in m.cells] == ["tetra10"], [c.type for c in m.cells]
        cells = m.cells[0].data
        assert len(cells) == body["tets"] and len(m.points) == body["nodes"]
        # VTK_QUADRATIC_TETRA: nodes 4..9 at the middles of edges 01, 12, 02, 03, 13, 23.
        p = m.points
        scale = size_of(p)
        for k, (a, b) in enumerate([(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]):
            close(p[cells[:, 4 + k]], 0.5 * (p[cells[:, a]] + p[cells[:, b]]), scale)
        g = read_vtk(os.path.join(out, "series", "cylinder_000002.vtu"))
        assert g.GetCellType(0) == vtk.VTK_QUADRATIC_TETRA
        close(vtk_to_numpy(g.GetPoints().GetData()),
              meshio.read(os.path.join(out, "cylinder.vtk")).points, scale)


def case_rigid_bodies_in_their_poses():
    with tempfile.TemporaryDirectory() as work:
        path = scene(work, "rigid_mix")
        out, _ = run(work, path, "a", "--steps", "5", "--vtk-every", "5")
        header = open(os.path.join(out, "rigid.csv")).readline().strip().split(",")
        row = np.loadtxt(os.path.join(out, "rigid.csv"), delimiter=",", skiprows=1)[-1]
        checked = 0
        for name in ("slab_crate", "slab_ball", "rod_crate", "rod_pin"):  # centred shapes
            vtu = os.path.join(out, "series", f"rigid_{name}_000005.vtu")
            g = read_vtk(vtu)
            position = vtk_to_numpy(g.GetFieldData().GetArray("position")).ravel()
            csv = row[[header.index(f"{name}.{c}") for c in "xyz"]]
            close(position, csv, np.abs(csv).max(), rel=1e-9)  # the CSV holds 10 digits
            points = meshio.read(vtu).points
            # Box corners and a tessellated sphere or capsule are symmetric about the centre.
            close(points.mean(axis=0), position, size_of(points) + np.abs(position).max())
            checked += 1
        assert checked == 4


def case_compressed_when_zlib_is_there():
    with tempfile.TemporaryDirectory() as work:
        _, out = twist_series(work)
        head = open(os.path.join(out, "series", "cylinder_000003.vtu"), "rb").read(400)
        assert b'compressor="vtkZLibDataCompressor"' in head, head


globals()["case_" + CASE]()
print("PASS:", CASE)
