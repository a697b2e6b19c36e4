"""Shared fixtures: where the torsion tool, the assets and the demo scenes are (ctest passes them
in the environment; run by hand: PYTHONPATH=build/python TORSION_EXE=build/demos/torsion
/usr/bin/python3 -m pytest tests/python)."""

import os
import pathlib

import numpy as np
import pytest

import torsion

# Relative round-off of Bullet's clock and rigid bodies: the time step is a btScalar, a float in a
# float-Bullet build (0.01f is 0.0099999998).
BULLET_RTOL = 1e-12 if torsion.bullet_precision == "double" else 1e-6

SOURCE_DIR = pathlib.Path(os.environ.get("TORSION_SOURCE_DIR",
                                         pathlib.Path(__file__).resolve().parents[2]))


@pytest.fixture(scope="session")
def source_dir():
    return SOURCE_DIR


@pytest.fixture(scope="session")
def assets():
    return SOURCE_DIR / "assets" / "meshes"


@pytest.fixture(scope="session")
def scenes():
    return SOURCE_DIR / "demos" / "scenes"


@pytest.fixture(scope="session")
def torsion_exe():
    exe = os.environ.get("TORSION_EXE")
    if not exe or not os.path.exists(exe):
        pytest.skip("TORSION_EXE (the torsion tool) not given")
    return os.path.abspath(exe)


def cube_mesh(cells=2, size=1.0):
    """A cube of cells^3 hexahedra, each cut into 6 tets (positive volume), as numpy arrays."""
    n = cells + 1
    grid = np.stack(np.meshgrid(*[np.linspace(0, size, n)] * 3, indexing="ij"), axis=-1)
    nodes = grid.reshape(-1, 3)
    index = np.arange(n ** 3).reshape(n, n, n)
    tets = []
    for i in range(cells):
        for j in range(cells):
            for k in range(cells):
                c = [index[i + a, j + b, k + d] for a, b, d in
                     [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                      (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]]
                for t in [(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6),
                          (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)]:
                    tets.append([c[v] for v in t])
    tets = np.array(tets, dtype=np.int32)
    # orient every tet positively
    x = nodes[tets]
    vol = np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 3] - x[:, 0])
    tets[vol < 0] = tets[vol < 0][:, [0, 2, 1, 3]]
    return nodes, tets


def read_vtk_points(path):
    """The POINTS of a legacy VTK file torsion wrote (%.17g: bit for bit)."""
    lines = pathlib.Path(path).read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("POINTS"))
    count = int(lines[start].split()[1])
    return np.array([[float(v) for v in line.split()] for line in lines[start + 1:start + 1 + count]])
