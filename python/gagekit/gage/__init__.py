"""Virtual gages for scanned castings (Ch. 5): gage files, 3-2-1 alignment, the LP
of Eq. 5.11 with slacks, infeasible groups and reports."""

from .align import Alignment, DatumPlane
from .analysis import (
    BoundLimit,
    GageCheckResult,
    GageOutcome,
    GageProblem,
    Transform,
    build_problem,
    check_gages,
    corrected_cloud,
    datum_alignment,
    gage_distances,
    region_in_scanner,
    solve_problem,
)
from .uncertainty import check_gages_uncertainty
from .spec import AlignmentSpec, Gage, GageFileWarning, GageSpec, MotionSet, Region, load_gage_spec

__all__ = [
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
]
