# Type stubs of the torsion package. Units are SI throughout: m, s, kg, N, N m, Pa, rad.
# Arrays are numpy float64 unless said otherwise; "view" means a read-only array over the
# solver's own storage that changes as the world steps (copy() it to keep a moment).
import os
import pathlib
from typing import Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from . import viewer as viewer  # launch_passive: a window on a world the script steps (viewer.py, typed)

__version__: str
bullet_precision: str  # "double" or "float": the btScalar of the Bullet the module links

def data_path() -> pathlib.Path: ...  # demos/scenes and assets: torsion/data when pip installed it

ArrayLike = npt.ArrayLike
FrameLike = Union["Frame", npt.ArrayLike]  # a Frame or a 4x4 homogeneous matrix

class Error(RuntimeError):
    message: str

class SceneError(Error):
    """A scene file that cannot be read, parsed or built (the CLI's message)."""
    file: Optional[str]
    key: Optional[str]
    line: Optional[int]  # a JSON syntax error's line

class MeshError(Error):
    """A mesh file or nodes/tets arrays that are not a valid tet mesh."""
    file: Optional[str]
    line: Optional[int]  # 1-based

class UnstableError(Error):
    """A failed step; the world is back at the end of the last good step."""
    body: Optional[str]
    step: Optional[int]  # 1-based index of the failed step

class Frame:
    """Origin (m) and rotation (unit quaternion x, y, z, w): world p = R p_local + origin."""
    def __init__(self, position: ArrayLike = (0, 0, 0), quaternion: ArrayLike = (0, 0, 0, 1)) -> None: ...
    @staticmethod
    def from_matrix(matrix: ArrayLike) -> Frame: ...
    @staticmethod
    def from_axis_angle(position: ArrayLike, axis: ArrayLike, angle: float) -> Frame: ...
    @property
    def position(self) -> npt.NDArray[np.float64]: ...  # (3,) m, a copy
    @property
    def quaternion(self) -> npt.NDArray[np.float64]: ...  # (4,) x, y, z, w
    def matrix(self) -> npt.NDArray[np.float64]: ...  # (4, 4)
    def __eq__(self, other: object) -> bool: ...  # the same doubles
    def __hash__(self) -> int: ...
    def __getstate__(self) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]: ...
    def __setstate__(self, state: tuple[tuple[float, float, float], tuple[float, float, float, float]]) -> None: ...

class Material:
    """Linear elastic material: E (Pa), nu, rho (kg/m^3), mass_damping (1/s),
    stiffness_damping (s), volumetric_strain "element" | "nodal_average", and the volume
    barrier against inverted tets: barrier_threshold (J below which it acts, 0: off),
    barrier_stiffness (its pressure at J = 0, in bulk moduli); law "corotated" |
    "stable_neo_hookean" | "mooney_rivlin" (hyperelastic: tet4, no contact) and
    mooney_rivlin_c2_fraction (C2 / (C1 + C2))."""
    def __init__(self, E: float = 1e5, nu: float = 0.3, rho: float = 1000.0,
                 mass_damping: float = 0.0, stiffness_damping: float = 0.01,
                 volumetric_strain: str = "element", barrier_threshold: float = 0.3,
                 barrier_stiffness: float = 30.0, law: str = "corotated",
                 mooney_rivlin_c2_fraction: float = 0.5) -> None: ...
    E: float
    nu: float
    rho: float
    mass_damping: float
    stiffness_damping: float
    volumetric_strain: str
    barrier_threshold: float
    barrier_stiffness: float
    law: str
    mooney_rivlin_c2_fraction: float
    shear_modulus: float  # Pa
    def __eq__(self, other: object) -> bool: ...  # the same values
    def __hash__(self) -> int: ...
    # the constructor's arguments in order
    def __getstate__(self) -> tuple[float, float, float, float, float, str, float, float]: ...
    def __setstate__(self, state: tuple[float, float, float, float, float, str, float, float]) -> None: ...

class State:
    """A world at a moment (World.save_state); picklable (versioned checkpoint bytes)."""
    time: float  # s
    def to_bytes(self) -> bytes: ...  # what pickle stores: "TRSNCKPT", version, length, hash, data
    @staticmethod
    def from_bytes(data: bytes) -> State: ...  # ValueError: truncated, corrupted, not a checkpoint
    def __getstate__(self) -> bytes: ...
    def __setstate__(self, data: bytes) -> None: ...

class Body:
    name: str
    node_count: int
    element_count: int
    element: str  # "tet4" | "tet10"
    renumbered: bool  # numbered inside otherwise than its mesh (add_body's node_order)
    positions: npt.NDArray[np.float64]  # (n, 3) m, view
    velocities: npt.NDArray[np.float64]  # (n, 3) m/s, view
    rest_positions: npt.NDArray[np.float64]  # (n, 3) m, view (constant)
    masses: npt.NDArray[np.float64]  # (n,) kg, copy
    tets: npt.NDArray[np.int32]  # (m, 4) or (m, 10), read-only (constant)
    surface_triangles: npt.NDArray[np.int32]  # (k, 3), view (constant)
    material: Material
    external_forces: npt.NDArray[np.float64]  # (n, 3) N, copy
    kinetic_energy: float  # J, end of the last step
    solver_iterations: int  # CG iterations of the last step
    newton_iterations: int  # Newton iterations of the last step (0: corotated, one solve)
    def set_material(self, material: Material) -> None: ...
    def set_external_forces(self, forces: ArrayLike) -> None: ...  # (n, 3) N, kept every step
    def set_velocity(self, velocity: ArrayLike) -> None: ...  # (3,) m/s, every node
    def anchor(self, nodes: ArrayLike, rigid_body: RigidBody) -> int: ...  # an id
    def remove_anchor(self, anchor: int) -> None: ...
    self_contact: bool
    def enable_self_contact(self, *, friction: float = 0.3, gap_tolerance: float = 0.0,
                            thickness_factor: float = 2.0, margin: float = 0.25) -> None: ...
    def disable_self_contact(self) -> None: ...
    def von_mises_stress(self) -> npt.NDArray[np.float64]: ...  # per tet, Pa
    def von_mises_strain(self) -> npt.NDArray[np.float64]: ...  # per tet, dimensionless

class NodeSet:
    name: str
    body: Body
    nodes: npt.NDArray[np.int32]
    wrench: npt.NDArray[np.float64]  # (6,) N, N m about wrench_about: what the body exerts
    scripted: bool  # a scene's set with a motion (move_to refuses it)
    frame: Frame  # at the end of the next step; starts at wrench_about, world axes
    def move_to(self, frame: FrameLike) -> None: ...  # reached at the end of the next step (mocap)
    def release(self) -> None: ...

class Hand:
    name: str
    body: Body
    grabbed: bool
    scripted: bool  # a scene's hand (driven by its script or device at each step)
    goal: Frame
    frame: Frame  # the patch frame of the last step
    wrench: npt.NDArray[np.float64]  # (6,) N, N m about the patch origin
    grabbed_nodes: npt.NDArray[np.int32]
    speed_limit: float  # m/s
    def grab(self, frame: FrameLike) -> int: ...
    def move_to(self, frame: FrameLike) -> None: ...
    def release(self) -> None: ...
    def stiffness(self, tolerance: float = 1e-6) -> npt.NDArray[np.float64]: ...  # (6, 6) K_h; 0 < tolerance < 1

class RigidBody:
    name: str
    position: npt.NDArray[np.float64]  # (3,) m
    quaternion: npt.NDArray[np.float64]  # (4,) x, y, z, w
    linear_velocity: npt.NDArray[np.float64]  # (3,) m/s
    angular_velocity: npt.NDArray[np.float64]  # (3,) rad/s
    mass: float  # kg, 0 when static or kinematic
    kind: str  # "dynamic" (mass > 0), "static" (mass 0) or "kinematic" (scripted or targeted)
    applied_force: npt.NDArray[np.float64]  # (3,) N queued for the next step, a copy
    applied_torque: npt.NDArray[np.float64]  # (3,) N m about the centre of mass, queued, a copy
    # Steering between steps; a bad argument raises ValueError/TypeError and changes nothing.
    def set_pose(self, position: ArrayLike, quaternion: ArrayLike = (0, 0, 0, 1)) -> None: ...
    def set_velocity(self, linear: Optional[ArrayLike] = None,
                     angular: Optional[ArrayLike] = None) -> None: ...  # dynamic bodies; m/s, rad/s
    def apply_force(self, force: ArrayLike, point: Optional[ArrayLike] = None) -> None: ...  # N, next step
    def apply_torque(self, torque: ArrayLike) -> None: ...  # N m, next step only
    def set_kinematic_target(self, position: ArrayLike,
                             quaternion: ArrayLike = (0, 0, 0, 1)) -> None: ...  # mass-0 bodies

class Contacts:
    """The contacts of a world's last step (World.contacts()); row k is one contact of
    body_a[k] with body_b[k]. FEM-rigid (A the FEM body) and rigid-rigid; not FEM-FEM."""
    body_a: list[str]
    body_b: list[str]  # a rigid body's name, "ground" for the ground plane
    points: npt.NDArray[np.float64]  # (k, 3) m, on A at the end of the step
    normals: npt.NDArray[np.float64]  # (k, 3) unit, from B towards A
    impulses: npt.NDArray[np.float64]  # (k, 3) N s, what B gave A over the step
    normal_impulses: npt.NDArray[np.float64]  # (k,) N s, impulses . normals
    def __len__(self) -> int: ...
    # (body_a, body_b, points, normals, impulses), the arrays flattened to lists of floats
    def __getstate__(self) -> tuple[list[str], list[str], list[float], list[float], list[float]]: ...
    def __setstate__(self, state: tuple[list[str], list[str], list[float], list[float], list[float]]) -> None: ...

class World:
    def __init__(self, gravity: ArrayLike = (0, 0, -9.81), dt: float = 0.01,
                 tolerance: float = 1e-4, max_iterations: int = 300,
                 linear_solver: str = "cg", threads: int = 0, max_speed: float = 1e3,
                 newton_tolerance: float = 1e-6, newton_max_iterations: int = 30) -> None: ...
    @staticmethod
    def from_scene(scene: str, threads: int = -1, *,
                   devices: Union[dict[str, str], Sequence[str], None] = None,
                   haptics: str = "", allow_remote_devices: bool = False) -> World: ...
    # A world from a scene pickles as (scene, threads, gravity, dt, state bytes); TypeError for
    # one built, extended or changed in code (rigid bodies removed, node sets driven, FEM
    # contact set), with devices or kinematic targets
    def __getstate__(self) -> tuple[str, int, tuple[float, float, float], float, bytes]: ...
    def __setstate__(self, state: tuple[str, int, tuple[float, float, float], float,
                                        bytes]) -> None: ...
    def step(self, n: int = 1) -> None: ...  # releases the GIL; Ctrl-C stops it between steps
    # ParaView time series (as `torsion run --vtk-every`): directory/series.pvd + series/*.vtu.
    # ValueError: every < 1, already recording, directory cannot be created; OSError: a write.
    def record_series(self, directory: Union[str, os.PathLike[str]], every: int = 1) -> None: ...
    def stop_series(self) -> None: ...  # writes the state now unless already written; OSError
    recording_series: bool
    series_steps_written: int
    time: float  # s
    step_count: int
    dt: float  # s; settable between steps, in [1e-6, 1] (not with device hands)
    @property
    def gravity(self) -> npt.NDArray[np.float64]: ...  # (3,) m/s^2, a copy
    @gravity.setter
    def gravity(self, value: ArrayLike) -> None: ...  # between steps; magnitude <= 1e6 m/s^2
    scene_steps: int
    bodies: list[Body]
    node_sets: list[NodeSet]
    hands: list[Hand]
    rigid_bodies: list[RigidBody]
    def body(self, name: str) -> Body: ...
    def node_set(self, name: str) -> NodeSet: ...
    def hand(self, name: str) -> Hand: ...
    def rigid_body(self, name: str) -> RigidBody: ...
    def device_wrench(self, name: str) -> npt.NDArray[np.float64]: ...  # (6,) N, N m, world
    def remove_rigid_body(self, body: Union[RigidBody, str]) -> None: ...  # its handles raise after
    fem_contact: bool  # whether FEM bodies touch each other (on by default)
    def enable_fem_contact(self, *, friction: float = 0.3, gap_tolerance: float = 0.0,
                           thickness_factor: float = 2.0, margin: float = 0.25) -> None: ...
    def disable_fem_contact(self, *, refuse_touching: bool = False) -> None: ...
    def contacts(self) -> Contacts: ...  # the last step's; empty after restore_state until a step
    def save_state(self) -> State: ...
    def restore_state(self, state: State) -> None: ...
    def add_body(self, name: str, mesh: Optional[str] = None, *, nodes: Optional[ArrayLike] = None,
                 tets: Optional[ArrayLike] = None, material: Material = ...,
                 frame: Optional[FrameLike] = None, element: str = "tet4",
                 node_order: str = "cache_friendly") -> Body: ...
    def add_node_set(self, name: str, body: Union[Body, str], *,
                     plane: Optional[tuple[ArrayLike, ArrayLike]] = None,
                     box: Optional[tuple[ArrayLike, ArrayLike]] = None,
                     sphere: Optional[tuple[ArrayLike, float]] = None,
                     indices: Optional[ArrayLike] = None, tolerance: float = 1e-6,
                     wrench_about: ArrayLike = (0, 0, 0)) -> NodeSet: ...
    def add_hand(self, name: str, body: Union[Body, str], max_drag_strain: float = 0.2) -> Hand: ...
    def add_rigid_body(self, name: str, shape: str = "box", *, half_extents: ArrayLike = (0.5, 0.5, 0.5),
                       radius: float = 0.5, half_height: float = 0.5, mass: float = 1.0,
                       frame: Optional[FrameLike] = None, friction: float = 0.5,
                       linear_velocity: ArrayLike = (0, 0, 0)) -> RigidBody: ...
    # lengths in (0, 1e6] m; mass 0 (static) or in [1e-9, 1e12] kg
    def add_ground(self, height: float = 0.0, friction: float = 0.5) -> None: ...  # |height| <= 1e6 m
    def render(self, width: int = 640, height: int = 480, camera: Optional[dict] = None,
               hud: bool = False) -> npt.NDArray[np.uint8]: ...  # (height, width, 3)
    def write_vtk(self, path: str, body: Union[Body, str, None] = None) -> None: ...
