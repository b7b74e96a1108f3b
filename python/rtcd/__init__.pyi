# Type stubs of the rtcd package (the extension module rtcd._rtcd). The
# docstrings of the module itself (help(rtcd.NarrowPhase)) say the rest.
from os import PathLike
from typing import Any, Iterable, Literal, Mapping, Protocol, Sequence, TypedDict, Union, overload

import numpy as np
import numpy.typing as npt

from . import gen as gen
from . import oracle as oracle

__version__: str

# Errors: one class per kind, all derived from Error (itself a RuntimeError);
# the ones that blame the input are ValueErrors too. Messages are the CLI's.
class Error(RuntimeError): ...
class MeshError(Error, ValueError):
    kind: str  # "empty", "non_finite_coordinate", ..., "file" (rtcd::MeshErrorKind)
    vertex: int | None
    triangle: int | None
class ConfigError(Error, ValueError): ...
class UsageError(Error, ValueError): ...
class BackendError(Error): ...
class SimulationError(Error): ...
class SceneError(Error, ValueError): ...
class RecordingError(Error, ValueError): ...

ArrayLike = npt.ArrayLike
PathType = Union[str, PathLike[str]]
# [tx, ty, tz, qw, qx, qy, qz], the CLI's order; the quaternion is normalised.
PoseLike = npt.ArrayLike

class _HasVerticesAndFaces(Protocol):
    vertices: Any
    faces: Any

class Mesh:
    """A validated triangle mesh (ids as given), with its normals and adjacency."""
    @overload
    def __init__(self, vertices: ArrayLike, triangles: ArrayLike, *, weld: bool = False,
                 allow_zero_area: bool = False) -> None: ...
    @overload
    def __init__(self, mesh: _HasVerticesAndFaces, *, weld: bool = False, allow_zero_area: bool = False) -> None: ...
    @staticmethod
    def load(path: PathType, weld: bool = False, allow_zero_area: bool = False) -> Mesh: ...
    # Read-only views into the mesh (no copy; they keep the mesh alive).
    @property
    def vertices(self) -> npt.NDArray[np.float32]: ...          # (n, 3)
    @property
    def triangles(self) -> npt.NDArray[np.uint32]: ...          # (m, 3)
    @property
    def vertex_normals(self) -> npt.NDArray[np.float32]: ...    # (n, 3)
    @property
    def triangle_normals(self) -> npt.NDArray[np.float32]: ...  # (m, 3)
    @property
    def neighbors(self) -> npt.NDArray[np.int32]: ...           # (m, 3), -1: none
    @property
    def bounds(self) -> npt.NDArray[np.float64]: ...            # (2, 3): min, max
    @property
    def radius(self) -> float: ...
    @property
    def convex(self) -> bool: ...
    @property
    def report(self) -> dict[str, int]: ...
    def check(self) -> dict[str, Any]: ...  # as `rtcd check --json` prints one file
    def save_obj(self, path: PathType) -> None: ...
    def __len__(self) -> int: ...  # triangles

def check_mesh(vertices: ArrayLike, triangles: ArrayLike) -> dict[str, Any]: ...
def check_file(path: PathType, weld: bool = False) -> dict[str, Any]: ...

class Shape:
    """What a body is made of: a mesh, a sphere, a box or a half-space."""
    def __init__(self, mesh: Mesh) -> None: ...
    @staticmethod
    def sphere(radius: float, sampling_density: float = 0.0) -> Shape: ...
    @staticmethod
    def box(half_extents: ArrayLike, sampling_density: float = 0.0) -> Shape: ...
    @staticmethod
    def half_space() -> Shape: ...
    @property
    def kind(self) -> Literal["mesh", "sphere", "box", "half_space"]: ...
    @property
    def mesh(self) -> Mesh | None: ...
    @property
    def radius(self) -> float: ...
    @property
    def bounds(self) -> npt.NDArray[np.float64]: ...
    @property
    def origins(self) -> npt.NDArray[np.float32]: ...     # (n, 3) view: the ray origins
    @property
    def directions(self) -> npt.NDArray[np.float32]: ...  # (n, 3) view
    @property
    def edges(self) -> npt.NDArray[np.uint32]: ...        # (e, 2) view

ShapeLike = Union[Shape, Mesh]

class Rays:
    """Contacts and predictive rays of a step, one row each (copies)."""
    def __len__(self) -> int: ...
    def keys(self) -> list[str]: ...
    def __getitem__(self, column: str) -> np.ndarray: ...
    pair: npt.NDArray[np.int64]          # index into the step's pairs
    source: npt.NDArray[np.uint8]        # 0: a's ray into b, 1: b's into a
    source_body: npt.NDArray[np.uint32]
    target_body: npt.NDArray[np.uint32]
    kind: npt.NDArray[np.uint8]          # 0 vertex, 1 edge, 2 sphere
    vertex: npt.NDArray[np.uint32]
    edge: npt.NDArray[np.uint32]         # (n, 2): edge contacts' two vertex ids, else (vertex, vertex)
    triangle: npt.NDArray[np.int32]
    origin: npt.NDArray[np.float64]      # (n, 3)
    direction: npt.NDArray[np.float64]   # (n, 3)
    normal: npt.NDArray[np.float64]      # (n, 3)
    depth: npt.NDArray[np.float64]       # 0 for predictive rays
    projected_depth: npt.NDArray[np.float64]
    push: npt.NDArray[np.float64]        # (n, 3)
    distance: npt.NDArray[np.float64]    # predictive rays: the gap; 0 for contacts
    predictive: npt.NDArray[np.bool_]

class Pairs:
    """One row per input pair, in input order (copies)."""
    def __len__(self) -> int: ...
    def keys(self) -> list[str]: ...
    def __getitem__(self, column: str) -> np.ndarray: ...
    a: npt.NDArray[np.uint32]
    b: npt.NDArray[np.uint32]
    colliding: npt.NDArray[np.bool_]
    mode: npt.NDArray[np.uint8]          # 0 full, 1 iterative, 2 certified
    max_depth: npt.NDArray[np.float64]
    first_contact: npt.NDArray[np.int64]
    contact_count: npt.NDArray[np.int64]
    first_predictive: npt.NDArray[np.int64]
    predictive_count: npt.NDArray[np.int64]
    device: npt.NDArray[np.int32]        # OpenCL: the device the pair ran on; -1 the CPU

class StepResult:
    """What one detect() returned. Arrays are built on first access."""
    @property
    def pairs(self) -> Pairs: ...
    @property
    def contacts(self) -> Rays: ...
    @property
    def predictive(self) -> Rays: ...
    @property
    def rays(self) -> Rays: ...   # contacts, then predictive rays
    @property
    def stats(self) -> dict[str, Any]: ...
    def to_json(self, pair: int = 0) -> dict[str, Any]: ...  # as `rtcd query --json` prints it

class NarrowPhase:
    def __init__(self, backend: str = "auto", *, threads: int = 0, mode: str = "auto",
                 max_walk_steps: int | None = None, displacement_threshold: float | None = None,
                 distance_extension: float | None = None, predictive: bool = True,
                 verify_walks: bool = True, edge_contacts: bool = True, edges_beside_contacts: bool = True,
                 edges_both_sides: bool = True,
                 edge_retest_motion: float | None = None, trace_separated_pairs: bool = True,
                 nearest_surface: bool = True,
                 projected: bool = True) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def devices(self) -> list[str]: ...
    @property
    def config(self) -> dict[str, Any]: ...
    def add_shape(self, shape: ShapeLike) -> int: ...
    def add_body(self, shape: int, pose: PoseLike | None = None) -> int: ...
    def add_bodies(self, shape: int, poses: ArrayLike) -> npt.NDArray[np.uint32]: ...
    def remove_body(self, body: int) -> None: ...
    def set_pose(self, body: int, pose: PoseLike) -> None: ...
    def set_poses(self, bodies: ArrayLike, poses: ArrayLike) -> None: ...
    def detect(self, pairs: ArrayLike) -> StepResult: ...
    def detect_begin(self, pairs: ArrayLike) -> None: ...   # the step runs while Python does
    def detect_done(self) -> bool: ...                     # never waits
    def detect_end(self) -> StepResult: ...

def query(a: ShapeLike, b: ShapeLike, pose_a: PoseLike | None = None, pose_b: PoseLike | None = None, *,
          backend: str = "auto", mode: str = "auto", **knobs: Any) -> StepResult: ...

class BackendInfo(TypedDict):
    name: str
    usable: bool
    devices: str

def backends() -> list[BackendInfo]: ...
def knobs() -> list[dict[str, Any]]: ...

def validate(family: str | None = None, backend: str | None = None, *, mode: str = "full", pairs: int = 1000,
             seed: int = 1, oracles: bool = True, **knobs: Any) -> list[dict[str, Any]]: ...
def families() -> list[str]: ...

class Simulation:
    GROUND: int  # the ground's number in contacts and pairs; body k is poses[k], labels[k]
    def __init__(self, scene: PathType | Mapping[str, Any], backend: str = "", threads: int = 0) -> None: ...
    def step(self, steps: int = 1) -> dict[str, Any]: ...
    @property
    def steps_done(self) -> int: ...
    @property
    def record(self) -> dict[str, Any]: ...
    @property
    def backend(self) -> str: ...
    @property
    def devices(self) -> list[str]: ...
    @property
    def labels(self) -> list[str]: ...
    @property
    def poses(self) -> npt.NDArray[np.float64]: ...          # (k, 7)
    @property
    def velocities(self) -> npt.NDArray[np.float64]: ...     # (k, 6): linear, angular
    @property
    def masses(self) -> npt.NDArray[np.float64]: ...
    @property
    def contacts(self) -> StepResult: ...                    # bodies numbered as poses
    @property
    def pairs(self) -> npt.NDArray[np.uint32]: ...           # (k, 2), numbered as poses
    @property
    def counters(self) -> dict[str, int]: ...
    @property
    def warnings(self) -> list[str]: ...
    def measure_interpenetration(self) -> dict[str, Any]: ...
    def state_hash(self) -> int: ...

def run(scene: PathType | None = None, *, backend: str = "", steps: int | None = None, threads: int = 0,
        out: PathType | None = None, record: PathType | None = None, plots: bool = True,
        full_rays: bool = False) -> dict[str, Any]: ...
