"""torsion: corotational FEM soft bodies, hand planes and rigid bodies in Bullet, from Python.

    import torsion
    world = torsion.World.from_scene("twist_cylinder_2430")
    world.step(100)                      # without the GIL
    x = world.body("cylinder").positions # (n, 3) float64, read-only view, m
    w = world.hand("hand").wrench        # (6,) force N, torque N m

See docs/python.md for the API by example, views vs copies and threading; torsion.viewer
(launch_passive) shows a world the script steps in a window.
"""

import pathlib

from . import _torsion, viewer
from .errors import Error, MeshError, SceneError, UnstableError
from ._torsion import (
    Body,
    Contacts,
    Frame,
    Hand,
    Material,
    NodeSet,
    RigidBody,
    State,
    World,
    __version__,
    bullet_precision,
)

__all__ = [
    "Body", "Contacts", "Error", "Frame", "Hand", "Material", "MeshError", "NodeSet", "RigidBody",
    "SceneError", "State", "UnstableError", "World", "__version__", "bullet_precision",
    "data_path",
]


def data_path() -> pathlib.Path:
    """The folder of the data the package comes with: demos/scenes/*.json (the scenes that
    World.from_scene finds by name) and assets/ (the meshes, trajectories and .bullet files
    they refer to).

    Installed by pip: torsion/data inside the package. Installed by `cmake --install`:
    <prefix>/share/torsion. In a build tree: <build>/share/torsion, links into the source tree.
    FileNotFoundError when the module has none of these beside it.
    """
    found = _torsion._data_directory()
    if found is None:
        raise FileNotFoundError(
            "torsion.data_path: no data folder beside the module " + _torsion.__file__ +
            " (torsion/data, or share/torsion above it)")
    return pathlib.Path(found)

