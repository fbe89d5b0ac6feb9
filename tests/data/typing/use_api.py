"""A small client of gagekit's public API, type-checked with ``mypy --strict`` by
tests/test_typing.py (it is never run there; it only has to type-check)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

import gagekit
from gagekit import _core
from gagekit.errors import GagekitError


def circle_form_error(points: npt.NDArray[np.float64]) -> float:
    fit = gagekit.fit_circle(points, "minimum-zone")
    return fit.r_out - fit.r_in


def machine_rank(path: str) -> int:
    m = gagekit.load_machine(path)
    commands = m.sample_commands(100, seed=1)
    design: npt.NDArray[np.float64] = m.design_matrix(commands)
    st = m.structure()
    names: list[str] = m.parameter_names
    rank: int = st.rank
    return rank if design.shape[1] == len(names) else -1


def hull_size(points: npt.NDArray[np.float64]) -> int:
    idx: npt.NDArray[np.int64] = _core.geometry.hull_indices(points)
    return int(idx.shape[0])


def design_trace(rows: npt.NDArray[np.float64]) -> float:
    met: _core.design.DesignMetrics = _core.design.metrics(rows)
    return met.trace + met.objective("A")


def rigid_rms(src: npt.NDArray[np.float64], dst: npt.NDArray[np.float64]) -> float:
    fit: _core.kinematics.RigidTransform = _core.kinematics.rigid_fit(src, dst)
    return fit.rms


def safe_check(path: str) -> str:
    try:
        return gagekit.machine.load_machine(path).name
    except GagekitError as exc:
        return str(exc)
