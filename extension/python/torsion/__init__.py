"""torsion: corotational FEM soft bodies, hand planes and rigid bodies in Bullet, from Python.

    import torsion
    world = torsion.World.from_scene("twist_cylinder_2430")
    world.step(100)                      # without the GIL
    x = world.body("cylinder").positions # (n, 3) float64, read-only view, m
    w = world.hand("hand").wrench        # (6,) force N, torque N m

See docs/python.md for the API by example, views vs copies and threading.
"""

from .errors import Error, MeshError, SceneError, UnstableError
from ._torsion import (
    Body,
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
    "Body", "Error", "Frame", "Hand", "Material", "MeshError", "NodeSet", "RigidBody",
    "SceneError", "State", "UnstableError", "World", "__version__", "bullet_precision",
]
