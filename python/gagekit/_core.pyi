"""Type stubs of the Rust extension ``gagekit._core`` (rust/py).

Arrays are float64 numpy arrays unless said otherwise; every function raises the classes of
:mod:`gagekit.errors` (a kernel panic arrives as ``InternalError``). The ``form_*`` part is
maintained with rust/py/src/form.rs.
"""

import types
from typing import Any, Optional, Sequence

import numpy as np
import numpy.typing as npt

_F64 = npt.NDArray[np.float64]
_I64 = npt.NDArray[np.int64]
_Arr = npt.ArrayLike

__version__: str
#: Test-only bindings (panic_in_kernel, gage_lp, gage_lp_solve); not part of the API.
_testing: types.ModuleType

# ----------------------------------------------------------------------------- cloudio
class AsciiCloud:
    @property
    def points(self) -> _F64: ...
    @property
    def header_lines(self) -> int: ...
    @property
    def columns(self) -> list[int]: ...

def cloud_read_ascii(path: str, dim: int = 3, skip_lines: int = 0) -> AsciiCloud: ...
def cloud_ascii_columns(head: bytes) -> int: ...
def cloud_scale_in_place(points: _F64, scale: list[float], what: str) -> None: ...
def cloud_write_ascii(path: str, points: _F64, sep: str = ",", header: Optional[str] = None) -> None: ...

class PlyCloud:
    @property
    def points(self) -> _F64: ...
    @property
    def format(self) -> str: ...

class PlyLayout:
    @property
    def vertices(self) -> int: ...
    @property
    def direct_offset(self) -> Optional[int]: ...

class E57Cloud:
    @property
    def points(self) -> _F64: ...
    @property
    def scans(self) -> int: ...
    @property
    def invalid_dropped(self) -> int: ...

def cloud_read_ply(path: str) -> PlyCloud: ...
def cloud_ply_layout(path: str) -> PlyLayout: ...
def cloud_read_e57(path: str) -> E57Cloud: ...
class AsciiChunks:
    @property
    def header_lines(self) -> int: ...
    def next_chunk(self) -> Optional[_F64]: ...
def cloud_ascii_chunks(path: str, dim: int = 3, skip_lines: int = 0, block: int = ...) -> AsciiChunks: ...
class PlyChunks:
    @property
    def count(self) -> int: ...
    def next_chunk(self, max_points: int) -> Optional[_F64]: ...
def cloud_ply_chunks(path: str) -> Optional[PlyChunks]: ...

# ---------------------------------------------------------------------------- geometry
def classify_boxes(points: _F64, boxes: _F64) -> list[_I64]: ...
def hull_indices(points: _F64) -> _I64: ...
class PointGrid:
    """A cell grid over a cloud (``grid_build``); ``select``/``count`` take a box row."""

    def select(self, row: _F64) -> _I64: ...
    def count(self, row: _F64) -> int: ...
    def __len__(self) -> int: ...
    @property
    def dims(self) -> tuple[int, int, int]: ...
    @property
    def cell_size(self) -> float: ...
    @property
    def bounds(self) -> tuple[list[float], list[float]]: ...

def grid_build(points: _F64, per_cell: int) -> PointGrid: ...
def validate_box(name: str, center: Sequence[float], size: Sequence[float], rotation: Sequence[float]) -> None: ...

class PointGrid:
    """A cell grid over a cloud (built by grid_build); keeps a reference to the cloud."""

    def select(self, row: _F64) -> _I64: ...
    def count(self, row: _F64) -> int: ...
    def __len__(self) -> int: ...
    @property
    def dims(self) -> tuple[int, int, int]: ...
    @property
    def cell_size(self) -> float: ...
    @property
    def bounds(self) -> tuple[list[float], list[float]]: ...

def grid_build(points: _F64, per_cell: int) -> PointGrid: ...

# -------------------------------------------------------------------------- kinematics
class KinematicChain:
    """A validated chain (Eq. 3.1), built once per machine file."""

    def __init__(self, spec: Sequence[tuple[str, Sequence[float], int]], tool: Sequence[float]) -> None: ...
    @property
    def parameter_labels(self) -> list[tuple[int, str, int]]: ...
    @property
    def n_joints(self) -> int: ...
    @property
    def n_parameters(self) -> int: ...
    def nominal(self, commands: _F64) -> _F64: ...
    def exact(self, commands: _F64, params: _F64) -> _F64: ...
    def design_matrix(self, commands: _F64) -> _F64: ...
    def command_jacobian(self, commands: _F64) -> _F64: ...

def machine_compensate(chain: KinematicChain, commands: _F64, params: _F64, joints: Sequence[int], iterations: int) -> tuple[_F64, _F64]: ...
def tracking_loo_errors(temperatures: _F64, groups: _F64, residuals: _F64, design: _F64, lambdas: Sequence[float]) -> list[float]: ...
def nc_compensate(
    chain: KinematicChain,
    params: _F64,
    text: bytes,
    letters: str,
    unit: Sequence[float],
    start: Sequence[Optional[float]],
    joints: Sequence[int],
    max_step: float,
    decimals: int,
    header: str,
    arc_tolerance: Optional[float] = None,
    iterations: int = 4,
    ranges: Sequence[tuple[float, float]] = ...,
) -> tuple[bytes, dict[str, Any]]: ...

class Identifiability:
    @property
    def rank(self) -> int: ...
    @property
    def singular_values(self) -> _F64: ...
    @property
    def no_effect(self) -> list[int]: ...
    @property
    def leaders(self) -> list[int]: ...
    @property
    def coefficients(self) -> _F64: ...
    @property
    def reconstruction_error(self) -> float: ...

class LeastSquares:
    @property
    def x(self) -> _F64: ...
    @property
    def cov_unscaled(self) -> _F64: ...
    @property
    def rss(self) -> float: ...
    @property
    def singular_values(self) -> _F64: ...
    @property
    def condition_number(self) -> float: ...
    @property
    def weakest(self) -> _F64: ...

class RigidTransform:
    @property
    def rotation(self) -> _F64: ...
    @property
    def translation(self) -> _F64: ...
    @property
    def rms(self) -> float: ...

def machine_identifiability(
    design: _F64, length_scale: float, length_power: Sequence[int], rtol: float = 1e-9, no_effect_tol: float = 1e-12
) -> Identifiability: ...
def machine_lstsq(a: _F64, b: _F64) -> LeastSquares: ...
def machine_rigid_fit(src: _F64, dst: _F64) -> RigidTransform: ...

# -------------------------------------------------------------------------------- ballbar
class BallbarCircle:
    @property
    def centre(self) -> tuple[float, float]: ...
    @property
    def radius_deviation(self) -> float: ...
    @property
    def g(self) -> float: ...
    @property
    def n(self) -> int: ...

class BallbarAnalysis:
    """ISO 230-4 figures and diagnostics (mm, rad, s)."""
    @property
    def both(self) -> BallbarCircle: ...
    @property
    def ccw(self) -> BallbarCircle | None: ...
    @property
    def cw(self) -> BallbarCircle | None: ...
    @property
    def f_max(self) -> float: ...
    @property
    def f_min(self) -> float: ...
    @property
    def hysteresis(self) -> float | None: ...
    @property
    def radius_term(self) -> float: ...
    @property
    def squareness(self) -> float: ...
    @property
    def squareness_fraction(self) -> float: ...
    @property
    def scale_mismatch(self) -> float: ...
    @property
    def scale_fraction(self) -> float: ...
    @property
    def servo_lag(self) -> float | None: ...
    @property
    def servo_mismatch(self) -> float | None: ...
    @property
    def servo_fraction(self) -> float | None: ...
    @property
    def backlash(self) -> list[list[float | None]]: ...
    @property
    def backlash_fraction(self) -> list[float]: ...
    @property
    def centre_fraction(self) -> float: ...
    @property
    def cyclic(self) -> list[float] | None: ...
    @property
    def cyclic_fraction(self) -> list[float] | None: ...
    @property
    def pitch(self) -> float | None: ...
    @property
    def spikes(self) -> list[list[float]]: ...
    @property
    def residual_rms(self) -> float: ...

def machine_ballbar(
    radius: float, angles: _F64, deviations: _F64, directions: npt.NDArray[np.int8],
    pitch: float | None = None, feed: float | None = None,
) -> BallbarAnalysis: ...

# -------------------------------------------------------------------------------- gage
class GageSolution:
    @property
    def params(self) -> list[float]: ...
    @property
    def matrix(self) -> list[list[float]]: ...
    @property
    def allowance_before(self) -> list[float]: ...
    @property
    def allowance_after(self) -> list[float]: ...
    @property
    def q(self) -> list[float]: ...
    @property
    def s(self) -> list[float]: ...
    @property
    def u(self) -> float: ...
    @property
    def objective(self) -> float: ...
    @property
    def lp_objective(self) -> float: ...
    @property
    def iterations(self) -> int: ...
    @property
    def last_step(self) -> float: ...
    @property
    def lp_status(self) -> str: ...
    @property
    def active_bounds(self) -> list[tuple[str, str, float]]: ...
    @property
    def groups(self) -> list[list[int]]: ...

def gage_solve(
    points: _F64, offsets: Sequence[int], planes: _F64, f: _F64, g: _F64, free: Sequence[bool],
    max_angle: float, max_shift: float, tol: float = 1e-10, slack_tol: float = 1e-7, groups: bool = True,
) -> GageSolution: ...

# ------------------------------------------------------------------------------ design
class DesignMetrics:
    @property
    def trace(self) -> float: ...
    @property
    def log_det(self) -> float: ...
    @property
    def condition_number(self) -> float: ...
    @property
    def lambda_min(self) -> float: ...
    @property
    def lambda_max(self) -> float: ...
    @property
    def i_value(self) -> Optional[float]: ...
    @property
    def rank(self) -> int: ...
    def objective(self, criterion_name: str) -> float: ...

class DesignSearch:
    @property
    def design(self) -> _I64: ...
    @property
    def objective(self) -> float: ...
    @property
    def start_objectives(self) -> list[float]: ...
    @property
    def exchanges(self) -> int: ...
    @property
    def metrics(self) -> DesignMetrics: ...

def design_search(
    blocks: _F64, r: int, groups: Sequence[_I64], point_group: Sequence[int], criterion_name: str,
    weights: Optional[_F64] = None, starts: int = 8, max_sweeps: int = 50, seed: int = 0,
    initial: Optional[Sequence[int]] = None,
) -> DesignSearch: ...
def design_metrics(blocks: _F64, weights: Optional[_F64] = None) -> DesignMetrics: ...
def design_halton(n: int, d: int, seed: int = 0) -> _F64: ...

# -------------------------------------------------------------------------------- form
class CircleResult:
    """A complete 2-D circle fit (Sec. 6.2); arc in rad, lengths mm."""
    criterion: str
    center: list[float]
    radius: float
    r_in: float
    r_out: float
    form_error: float
    control: list[int]
    control_in: list[int]
    control_out: list[int]
    arc: float
    arc_center: list[float]
    ill_posed: bool

def form_circle_fit(points: _F64, criterion: str) -> CircleResult: ...
def form_circle_pso(
    points: _F64, criterion: str, seed: int = 0, particles: int = 20, max_iterations: int = 2000,
    stall_iterations: int = 100,
) -> CircleResult: ...
class LineResult:
    """A least-squares line with its certificate."""
    point: list[float]
    direction: list[float]
    min_distance: float
    max_distance: float
    form_error: float

def form_line_lsq(points: _F64) -> LineResult: ...

class PlaneResult:
    """A least-squares plane with its certificate."""
    point: list[float]
    normal: list[float]
    min_distance: float
    max_distance: float
    form_error: float

def form_plane_lsq(points: _F64) -> PlaneResult: ...

class LeastSquaresSphereResult:
    """A least-squares circle (2-D) or sphere (3-D) with its certificate."""
    center: list[float]
    radius: float
    min_distance: float
    max_distance: float
    form_error: float

def form_sphere_lsq(points: _F64) -> LeastSquaresSphereResult: ...

class LeastSquaresCircle3Result:
    """A least-squares circle in space with its certificate."""
    center: list[float]
    normal: list[float]
    radius: float
    min_distance: float
    max_distance: float
    form_error: float

def form_circle3d_lsq(points: _F64) -> LeastSquaresCircle3Result: ...

class LeastSquaresCylinderResult:
    """A least-squares cylinder with its certificate and arc (rad)."""
    point: list[float]
    direction: list[float]
    radius: float
    min_distance: float
    max_distance: float
    form_error: float
    arc: float

def form_cylinder_lsq(points: _F64, start_axis: Optional[Sequence[float]] = None) -> LeastSquaresCylinderResult: ...

class MinZoneFlatResult:
    """A minimum-zone plane (flatness) or 2-D line (straightness) with its certificate."""
    point: list[float]
    normal: list[float]
    direction: list[float]
    form_error: float
    control: list[int]
    min_distance: float
    max_distance: float
    iterations: int

def form_min_zone_flat(points: _F64) -> MinZoneFlatResult: ...
class OutsideResult:
    """A better optimum of the free search outside the search cone (radius or width, mm)."""
    value: float
    direction: tuple[float, float, float]
    tilt: float

class CylinderResult:
    """A minimax cylinder (Sec. 6.3); angles rad, lengths mm."""
    criterion: str
    point: tuple[float, float, float]
    direction: tuple[float, float, float]
    theta: float
    phi: float
    radius: float
    r_in: float
    r_out: float
    control_in: list[int]
    control_out: list[int]
    min_distance: float
    max_distance: float
    iterations: int
    evaluations: int
    reference: tuple[float, float, float]
    tilt: float
    outside: Optional[OutsideResult]
    at_limit: bool
    arc: float
    ill_posed: bool
    lsq_axis: Optional[tuple[tuple[float, float, float], tuple[float, float, float]]]

def form_cylinder_fit(
    points: _F64, criterion: str, seed: int = 0, particles: int = 20, max_iterations: int = 300,
    stall_iterations: int = 6, axis: Optional[Sequence[float]] = None, max_tilt: float = ...,
    refine_starts: int = 8, hop_rounds: int = 3,
) -> CylinderResult: ...

class Line3Result:
    """A minimum-zone line in space (straightness)."""
    point: tuple[float, float, float]
    direction: tuple[float, float, float]
    min_distance: float
    max_distance: float
    form_error: float
    control: list[int]
    reference: tuple[float, float, float]
    tilt: float
    outside: Optional[OutsideResult]

def form_line3_min_zone(
    points: _F64, seed: int = 0, axis: Optional[Sequence[float]] = None, max_tilt: float = ...,
) -> Line3Result: ...
def form_criterion(name: str, allowed: Sequence[str] = ..., shape: str = "fit") -> str: ...
def form_criteria() -> list[tuple[str, str, str]]: ...

class Circle3Result:
    """A circle in any pose, fitted in the least-squares plane."""
    center: tuple[float, float, float]
    normal: tuple[float, float, float]
    radius: float
    r_in: float
    r_out: float
    control_in: list[int]
    control_out: list[int]
    min_distance: float
    max_distance: float
    out_of_plane: float
    control: list[int]
    arc: float
    ill_posed: bool

def form_circle_in_plane(points: _F64, criterion: str) -> Circle3Result: ...

class SphereResult:
    """A Chebyshev sphere (MC, MI, MZ)."""
    criterion: str
    center: tuple[float, float, float]
    r_in: float
    r_out: float
    control_in: list[int]
    control_out: list[int]
    min_distance: float
    max_distance: float
    iterations: int
    bound: float

def form_sphere_fit(points: _F64, criterion: str) -> SphereResult: ...
class ConeResult:
    """A cone (issue 25 §3): reference-section axis point, direction, apex, half angle rad."""
    criterion: str
    point: tuple[float, float, float]
    direction: tuple[float, float, float]
    apex: tuple[float, float, float]
    half_angle: float
    fixed_angle: bool
    radius: float
    distance: float
    r_in: float
    r_out: float
    control_in: list[int]
    control_out: list[int]
    gap: float
    evaluations: int
    min_distance: float
    max_distance: float
    form_error: float

def form_cone_fit(points: _F64, criterion: str, half_angle: Optional[float] = None) -> ConeResult: ...

# -------------------------------------------------------------------------------- gdt
_V3 = tuple[float, float, float]

def gdt_min_width_2d(points: _F64) -> tuple[float, tuple[float, float], float, float]: ...
def gdt_slab(points: _F64, mode: str, axis: _V3, angle: float) -> tuple[_V3, float, float, float]: ...
def gdt_datum_plane(points: _F64, outward: _V3, mode: str, axis: _V3, angle: float, fit: str) -> tuple[_V3, _V3, float, float]: ...
def gdt_axis_along(points: _F64, direction: _V3, fit: str) -> tuple[_V3, _V3, float, float, float]: ...
def gdt_two_point_sizes(points: _F64, origin: _V3, axis: _V3, reference: _V3, kind: str, sections: int, angles: int) -> tuple[_F64, _I64, _F64, int]: ...
def gdt_width_sizes(face_a: _F64, face_b: _F64, normal: _V3) -> _F64: ...
def gdt_hull_distance(a: _F64, b: _F64) -> tuple[float, _V3]: ...

# ------------------------------------------------------------------------------- mesh
class MeshBestFit:
    """Robust best fit: `matrix` (4x4 rows) applied to the points."""
    matrix: list[list[float]]
    iterations: int
    rms_before: float
    rms_after: float
    n_used: int
    start: int

class MeshMinimax:
    """Minimax alignment with its certificate (`max_abs` equals `lp_optimum` at the optimum)."""
    matrix: list[list[float]]
    max_abs: float
    lp_optimum: float
    rms: float
    iterations: int
    active: int
    n_used: int

class Mesh:
    """A validated triangle mesh (BVH, topology, pseudonormals), built once."""
    def __init__(self, vertices: _F64, triangles: Any) -> None: ...
    @property
    def n_vertices(self) -> int: ...
    @property
    def n_triangles(self) -> int: ...
    @property
    def signed(self) -> bool: ...
    @property
    def reason(self) -> Optional[str]: ...
    @property
    def flipped(self) -> bool: ...
    @property
    def volume(self) -> float: ...
    @property
    def area(self) -> float: ...
    def face_normals(self) -> _F64: ...
    def distances(self, points: _F64, max_distance: Optional[float] = None, unsigned: bool = False,
                  foot: bool = False) -> tuple[_F64, Any, Optional[_F64], int, bool]: ...
    def best_fit(self, points: _F64, initial: Optional[_F64] = None, free: Sequence[bool] = ...,
                 max_distance: Optional[float] = None, search: bool = True) -> MeshBestFit: ...
    def minimax(self, points: _F64, initial: Optional[_F64] = None, free: Sequence[bool] = ...,
                max_distance: Optional[float] = None, offset: float = 0.0) -> MeshMinimax: ...
