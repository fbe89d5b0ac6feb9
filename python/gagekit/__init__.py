"""gagekit: machining accuracy for multi-axis CNC machine tools and scanned parts.

See README.md for the command line; the public Python API is listed in ``__all__``.
"""

from __future__ import annotations


def _quiet_ctrl_c_while_the_cli_starts() -> None:
    """Run as the `gagekit` command (or ``python -m gagekit``), Ctrl-C during the imports
    that follow ends with the CLI's one line ``gagekit: error: interrupted`` (exit 130)
    instead of a traceback; :func:`gagekit.cli.main` restores Python's handler. A library
    import changes nothing."""
    import os
    import signal
    import sys

    argv = list(getattr(sys, "orig_argv", sys.argv))
    as_cli = (sys.argv and os.path.basename(sys.argv[0]) == "gagekit") or argv[1:3] == ["-m", "gagekit"]
    if not as_cli or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        return

    def _stop(signum, frame):  # pragma: no cover - exercised by the interrupt tests
        os.write(2, b"gagekit: error: interrupted\n")
        os._exit(130)

    try:
        signal.signal(signal.SIGINT, _stop)
    except ValueError:  # pragma: no cover - not the main thread
        pass


_quiet_ctrl_c_while_the_cli_starts()  # first: before any slow import

from importlib.metadata import PackageNotFoundError, version as _version  # noqa: E402

from . import _core, cloud, design, form, gage, inspect, machine
from .cloud import (
    Box,
    Cloud,
    UNIT_NAMES,
    CutResult,
    RegionCut,
    classify,
    convex_hull_indices,
    cut_and_filter,
    load_regions,
    read_cloud,
    read_points,
    regions_from_tables,
    select,
    write_points,
)
from .design import (
    optimal_design,
    DesignResult,
)
from .form import (
    CircleFit,
    fit_circle,
    CIRCLE_CRITERIA,
    Certificate,
    LineFit,
    PlaneFit,
    SphereFit,
    Circle3DFit,
    ConeFit,
    fit_cone,
    fit_line,
    fit_plane,
    fit_sphere,
    fit_circle_3d,
    CylinderFit,
    fit_cylinder,
    axis_angles,
    DEFAULT_MAX_TILT,
    RoundnessParameters,
    StraightnessParameters,
    FlatnessParameters,
    roundness_parameters,
    straightness_parameters,
    flatness_parameters,
    cylindricity_parameters,
    gaussian_filter_closed,
    gaussian_filter_open,
    spline_filter_open,
    gaussian_transmission,
    STANDARD_UPR,
    ROUNDNESS_REFERENCES,
)
from .gage import (
    Alignment,
    AlignmentSpec,
    BoundLimit,
    DatumPlane,
    Gage,
    GageCheckResult,
    GageFileWarning,
    GageOutcome,
    GageProblem,
    GageSpec,
    MotionSet,
    Region,
    Transform,
    build_problem,
    check_gages,
    check_gages_uncertainty,
    corrected_cloud,
    datum_alignment,
    gage_distances,
    region_in_scanner,
    load_gage_spec,
    solve_problem,
)
from .machine import (
    Machine,
    JointSpec,
    ShapeSpec,
    Group,
    ModelStructure,
    load_machine,
    parse_machine,
    halton,
    example_machine_path,
    Observations,
    read_observations,
    read_commands,
    Frame,
    ResidualStats,
    GroupEstimate,
    Calibration,
    identify,
    predict,
    predict_uncertainty,
    predict_covariance,
    compensate,
    load_calibration,
    Truth,
    simulate,
    TRACKER_SIGMA,
    ObserverPlan,
    PlanEvaluation,
    design_observer,
    evaluate_plan,
    History,
    TrackResult,
    read_cycles,
    simulate_cycles,
    track,
)
from .inspect import InspectionResult, PartSpec, load_part_spec
from .inspect import inspect as inspect_scan
from .errors import (
    ClusterError,
    ConfigError,
    DegenerateGeometryError,
    FileAccessError,
    FileFormatError,
    GagekitError,
    InfeasibleError,
    InternalError,
    InvalidInputError,
    NumericalError,
    SchemaVersionError,
    StoreError,
)

try:
    __version__ = _version("gagekit")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = _core.__version__

#: The public API, by name (the subpackages cloud, design, form, gage, inspect and machine
#: hold the rest; ``gagekit.inspect`` is the subpackage, :func:`inspect_scan` the function).
__all__ = [
    "__version__",
    "Box",
    "Cloud",
    "UNIT_NAMES",
    "CutResult",
    "RegionCut",
    "classify",
    "convex_hull_indices",
    "cut_and_filter",
    "load_regions",
    "read_cloud",
    "read_points",
    "regions_from_tables",
    "select",
    "write_points",
    "optimal_design",
    "DesignResult",
    "CircleFit",
    "fit_circle",
    "CIRCLE_CRITERIA",
    "Certificate",
    "LineFit",
    "PlaneFit",
    "SphereFit",
    "Circle3DFit",
    "ConeFit",
    "fit_cone",
    "fit_line",
    "fit_plane",
    "fit_sphere",
    "fit_circle_3d",
    "CylinderFit",
    "fit_cylinder",
    "axis_angles",
    "DEFAULT_MAX_TILT",
    "RoundnessParameters",
    "StraightnessParameters",
    "FlatnessParameters",
    "roundness_parameters",
    "straightness_parameters",
    "flatness_parameters",
    "cylindricity_parameters",
    "gaussian_filter_closed",
    "gaussian_filter_open",
    "spline_filter_open",
    "gaussian_transmission",
    "STANDARD_UPR",
    "ROUNDNESS_REFERENCES",
    "Alignment",
    "AlignmentSpec",
    "BoundLimit",
    "DatumPlane",
    "Gage",
    "GageCheckResult",
    "GageFileWarning",
    "GageOutcome",
    "GageProblem",
    "GageSpec",
    "MotionSet",
    "Region",
    "Transform",
    "build_problem",
    "check_gages",
    "check_gages_uncertainty",
    "corrected_cloud",
    "datum_alignment",
    "gage_distances",
    "region_in_scanner",
    "load_gage_spec",
    "solve_problem",
    "Machine",
    "JointSpec",
    "ShapeSpec",
    "Group",
    "ModelStructure",
    "load_machine",
    "parse_machine",
    "halton",
    "example_machine_path",
    "Observations",
    "read_observations",
    "read_commands",
    "Frame",
    "ResidualStats",
    "GroupEstimate",
    "Calibration",
    "identify",
    "predict",
    "predict_uncertainty",
    "predict_covariance",
    "compensate",
    "load_calibration",
    "Truth",
    "simulate",
    "TRACKER_SIGMA",
    "ObserverPlan",
    "PlanEvaluation",
    "design_observer",
    "evaluate_plan",
    "History",
    "TrackResult",
    "read_cycles",
    "simulate_cycles",
    "track",
    "inspect_scan",
    "load_part_spec",
    "PartSpec",
    "InspectionResult",
    "GagekitError",
    "InvalidInputError",
    "FileFormatError",
    "FileAccessError",
    "DegenerateGeometryError",
    "InfeasibleError",
    "ConfigError",
    "NumericalError",
    "InternalError",
    "StoreError",
    "SchemaVersionError",
    "ClusterError",
]
