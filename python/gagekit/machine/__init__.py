"""Machine-tool volumetric error models and their identification (Ch. 3).

    m = load_machine("dissertation-5axis.toml")
    m.design_matrix(commands)          # (3n, 52), Eq. 3.13
    s = m.structure()                  # rank 32, groups of Eq. 3.14
    truth = Truth.random(m, seed=1)
    obs = simulate(m, truth, m.sample_commands(290, seed=1), seed=11)
    cal = identify(m, obs)             # joint frame + groups (Sec. 3.1.5, ERRATA 6)
"""

from .identify import (
    Calibration,
    Frame,
    GroupEstimate,
    ResidualStats,
    compensate,
    identify,
    load_calibration,
    predict,
    predict_uncertainty,
)
from .predict import predict_covariance
from .model import (
    Group,
    JointSpec,
    Machine,
    ModelStructure,
    ShapeSpec,
    example_machine_path,
    halton,
    load_machine,
    parse_machine,
)
from .observations import Observations, read_commands, read_observations
from .observer import ObserverPlan, PlanEvaluation, design_observer, evaluate_plan
from .simulate import TRACKER_SIGMA, Truth, simulate
from .tracking import History, TrackResult, read_cycles, simulate_cycles, track

__all__: list[str] = [
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
]
