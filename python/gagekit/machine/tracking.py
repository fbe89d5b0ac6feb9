"""Thermal error tracking over repeated measurement cycles (Sec. 4.3.2-4.3.4).

The same plan is measured in every cycle. The tracker frame T0 is fitted in cycle 1 (Eq. 4.11;
with the frame correction of ERRATA item 6) and kept; then, per cycle j:

* ``full``: the groups re-identified from cycle j (Eqs. 4.12-4.14, Table 4.4);
* ``static``: cycle 1's groups used unchanged (Eq. 4.15, Table 4.5);
* ``drift_only``: cycle 1's groups plus a fitted translation of the workspace (Eqs. 4.16-4.18,
  Table 4.6);
* ``observed``: the errors left after the tracker placement (the "Observed" columns).

With temperature columns, a linear model from the cycle-mean temperatures to each group
(Sec. 7.2, item 4) and its leave-one-cycle-out prediction residuals. Results can be appended
to a per-machine SQLite history (:class:`History`).
"""

from __future__ import annotations

import json
import math
import sqlite3
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Optional, Sequence, Union

import numpy as np

from .. import _progress

from ..errors import ConfigError, DegenerateGeometryError, FileFormatError, InvalidInputError
from .identify import identify
from .model import Machine, ModelStructure
from .observations import Observations, _read_table, write_csv
from .simulate import TRACKER_SIGMA, Truth, simulate

__all__ = ["Cycles", "TrackResult", "read_cycles", "track", "History", "read_history", "simulate_cycles", "plot_drift", "drift_figure"]

_XYZ = ("x", "y", "z")


@dataclass(frozen=True, eq=False)
class Cycles:
    """Repeated measurements of one plan: commands (n, J), measured (C, n, 3) tracker frame."""

    cycle_ids: tuple
    commands: np.ndarray
    measured: np.ndarray
    joint_names: tuple
    time: Optional[np.ndarray] = None
    temperatures: dict = field(default_factory=dict)  # sensor -> (C,) cycle means
    source: Optional[str] = None


def read_cycles(path: Union[str, Path], machine: Machine) -> Cycles:
    """CSV with ``cycle``, the joint columns, ``x, y, z`` and optional ``time`` and ``temp_*``."""
    header, data = _read_table(path)
    joints = machine.joint_names
    need = ["cycle", *joints, *_XYZ]
    missing = [c for c in need if c not in header]
    if missing:
        raise FileFormatError(f"{path}: missing column(s) {', '.join(missing)} (expected {', '.join(need)}, optional time, temp_*)")
    extra = [c for c in header if c not in need and c != "time" and not c.startswith("temp_")]
    if extra:
        raise FileFormatError(f"{path}: unknown column(s) {', '.join(extra)}")
    if len(data) == 0:
        raise FileFormatError(f"{path}: no data rows")
    col = {c: data[:, header.index(c)] for c in header}
    cyc = col["cycle"]
    if not np.allclose(cyc, np.round(cyc)):
        raise FileFormatError(f"{path}: the cycle column must hold whole numbers")
    ids = sorted({int(round(v)) for v in cyc})
    cmds_all = np.column_stack([col[j] for j in joints])
    xyz = np.column_stack([col[c] for c in _XYZ])
    first = np.round(cyc) == ids[0]
    c0 = cmds_all[first]
    tol = 1e-6 * (np.ptp(machine.ranges, axis=1) + 1.0)
    meas, times, temps = [], [], {s: [] for s in header if s.startswith("temp_")}
    for cid in ids:
        sel = np.round(cyc) == cid
        c = cmds_all[sel]
        if c.shape != c0.shape or not (np.abs(c - c0) <= tol).all():
            raise InvalidInputError(
                f"{path}: cycle {cid} measures different commands from cycle {ids[0]} "
                f"({len(c)} vs {len(c0)} points): every cycle must repeat the same plan in the same order"
            )
        meas.append(xyz[sel])
        if "time" in col:
            times.append(float(col["time"][sel].mean()))
        for s in temps:
            temps[s].append(float(col[s][sel].mean()))
    return Cycles(
        cycle_ids=tuple(ids),
        commands=np.ascontiguousarray(c0),
        measured=np.stack(meas),
        joint_names=tuple(joints),
        time=np.array(times) if times else None,
        temperatures={s: np.array(v) for s, v in temps.items()},
        source=str(path),
    )


def _stats(res: np.ndarray, observed: dict) -> dict:
    """mean/max of per-point residual norms (mm) and % decrease against the observed errors."""
    n = np.linalg.norm(res, axis=1)
    d = {"mean": float(n.mean()), "max": float(n.max())}
    if observed:
        d["decrease_mean_pct"] = 100.0 * (1 - d["mean"] / observed["mean"]) if observed["mean"] > 0 else 0.0
        d["decrease_max_pct"] = 100.0 * (1 - d["max"] / observed["max"]) if observed["max"] > 0 else 0.0
    return d


@dataclass(frozen=True, eq=False)
class TrackResult:
    """Per-cycle statistics (mm) of Tables 4.4-4.6, group values per cycle, temperature model."""

    machine: str
    cycles: list
    groups: dict
    group_units: dict
    temperature_model: Optional[dict]
    residuals: dict = field(repr=False)  # mode -> (C, n) residual norms, mm
    frame: dict = field(default_factory=dict)
    #: RMS over the plan's points of |d(error)/d(group)|, mm per group unit (for the drift plot)
    group_effect: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        d = {"machine": self.machine, "cycles": self.cycles, "groups": self.groups, "group_units": self.group_units,
             "frame": self.frame}
        if self.temperature_model is not None:
            d["temperature_model"] = self.temperature_model
        return d


def track(machine: Machine, cycles: Cycles, structure: Optional[ModelStructure] = None) -> TrackResult:
    """Track the error model over the cycles (Eqs. 4.11-4.18)."""
    st = structure if structure is not None else machine.structure()
    cmds = cycles.commands
    n = len(cmds)
    if n < st.rank:
        raise DegenerateGeometryError(
            f"the plan has {n} points; re-identifying the {st.rank} groups each cycle needs at least {st.rank}"
        )
    p_nom = machine.nominal(cmds)
    m = st.reduce(machine.design_matrix(cmds))
    sv = np.linalg.svd(m, compute_uv=False)
    if sv[-1] <= 1e-10 * sv[0]:
        raise DegenerateGeometryError("the plan cannot identify all groups (its design matrix is rank deficient): design it with `machine design`")
    cal1 = identify(machine, Observations(cmds, cycles.measured[0], cycles.joint_names), structure=st)
    frame = cal1.frame  # Eq. 4.11, kept for all cycles
    resid = [frame.to_table(q) - p_nom for q in cycles.measured]  # observed errors, table frame
    pinv = np.linalg.pinv(m)
    params = [pinv @ r.reshape(-1) for r in resid]  # Eqs. 4.12, 4.13
    p1 = params[0]
    rows, modes = [], {"full": [], "static": [], "drift_only": []}
    for j, (cid, r) in enumerate(_progress.track(list(zip(cycles.cycle_ids, resid)), "tracking cycles")):
        obs = _stats(r, {})
        full = r - (m @ params[j]).reshape(-1, 3)  # Eq. 4.14
        static = r - (m @ p1).reshape(-1, 3)  # Eq. 4.15
        drift = static - static.mean(axis=0)  # Eqs. 4.16-4.18: best translation of the workspace
        row = {"cycle": cid, "observed": obs, "full": _stats(full, obs), "static": _stats(static, obs),
               "drift_only": _stats(drift, obs), "drift_translation_mm": static.mean(axis=0).tolist()}
        if cycles.time is not None:
            row["time"] = float(cycles.time[j])
        if cycles.temperatures:
            row["temperatures"] = {s: float(v[j]) for s, v in cycles.temperatures.items()}
        rows.append(row)
        for key, arr in (("full", full), ("static", static), ("drift_only", drift)):
            modes[key].append(np.linalg.norm(arr, axis=1))
    names = [g.name for g in st.groups]
    units = machine.parameter_units()
    groups = {name: [float(p[i]) for p in params] for i, name in enumerate(names)}
    temp_model = _temperature_model(cycles, params, names, m, resid) if cycles.temperatures else None
    effect = np.sqrt((m.reshape(n, 3, -1) ** 2).sum(axis=1).mean(axis=0))  # RMS |column| over the plan
    return TrackResult(
        machine=machine.name,
        cycles=rows,
        groups=groups,
        group_units={name: units[st.leaders[i]] for i, name in enumerate(names)},
        temperature_model=temp_model,
        residuals={k: np.array(v) for k, v in modes.items()},
        frame=frame.to_dict(),
        group_effect={name: float(effect[i]) for i, name in enumerate(names)},
    )


def _temperature_model(cycles: Cycles, params, names, m, resid) -> dict:
    """Linear model group = a + b . (T - T_mean) over cycle-mean temperatures, minimum-norm
    least squares (more sensors than cycles is common), with leave-one-cycle-out residuals."""
    sensors = list(cycles.temperatures)
    T = np.column_stack([cycles.temperatures[s] for s in sensors])  # (C, S)
    P = np.array(params)  # (C, G)
    C = len(P)
    if C < 3:
        return {"sensors": sensors, "fitted": False, "reason": "a temperature model needs at least 3 cycles"}

    def fit(idx):
        Tm, Pm = T[idx].mean(axis=0), P[idx].mean(axis=0)
        B = np.linalg.pinv(T[idx] - Tm) @ (P[idx] - Pm)  # (S, G)
        return Tm, Pm, B

    Tm, Pm, B = fit(np.arange(C))
    loo = []
    for c in range(C):
        keep = np.array([i for i in range(C) if i != c])
        tm, pm, b = fit(keep)
        g = pm + (T[c] - tm) @ b
        res = np.linalg.norm(resid[c] - (m @ g).reshape(-1, 3), axis=1)
        loo.append({"cycle": cycles.cycle_ids[c], "mean": float(res.mean()), "max": float(res.max())})
    return {
        "fitted": True,
        "sensors": sensors,
        "coefficients": {name: {s: float(B[k, i]) for k, s in enumerate(sensors)} for i, name in enumerate(names)},
        "reference_temperatures": {s: float(v) for s, v in zip(sensors, Tm)},
        "leave_one_cycle_out": loo,
        "leave_one_cycle_out_mean": float(np.mean([x["mean"] for x in loo])),
    }


def plot_drift(result: TrackResult, path: Union[str, Path], top: int = 8) -> None:
    """Write :func:`drift_figure` as a PNG."""
    import matplotlib.pyplot as plt

    from .._files import atomic_path

    fig = drift_figure(result, top)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=120)
    finally:
        plt.close(fig)


def drift_figure(result: TrackResult, top: int = 8):
    """Fig. 4.8: how much each group's change since the first cycle moves the target, RMS
    over the plan's points (um), for the ``top`` groups that move it most."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(result.groups)
    vals = np.array([result.groups[n] for n in names]) * np.array([result.group_effect[n] for n in names])[:, None] * 1000.0
    change = vals - vals[:, :1]
    order = np.argsort(-np.abs(change).max(axis=1))[:top]
    x = [c["cycle"] for c in result.cycles]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for i in order:
        ax.plot(x, change[i], marker="o", label=names[i] if len(names[i]) < 40 else names[i][:37] + "...")
    ax.set_xlabel("cycle")
    ax.set_ylabel(f"effect of the change since cycle {x[0]} (um RMS)")
    ax.set_title("Parameter drift over cycles (Fig. 4.8)")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------------- history

class History:
    """An embedded SQLite store of one machine's tracking history (writes are transactional)."""

    SCHEMA = """
    CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
    CREATE TABLE IF NOT EXISTS runs (id INTEGER PRIMARY KEY, created TEXT, source TEXT, n_points INTEGER);
    CREATE TABLE IF NOT EXISTS cycles (run INTEGER, cycle INTEGER, time REAL, stats TEXT, PRIMARY KEY (run, cycle));
    CREATE TABLE IF NOT EXISTS observations (run INTEGER, cycle INTEGER, idx INTEGER, commands TEXT, x REAL, y REAL, z REAL);
    CREATE TABLE IF NOT EXISTS groups (run INTEGER, cycle INTEGER, name TEXT, value REAL);
    CREATE TABLE IF NOT EXISTS residuals (run INTEGER, cycle INTEGER, idx INTEGER, full REAL, static REAL, drift_only REAL);
    CREATE TABLE IF NOT EXISTS temperatures (run INTEGER, cycle INTEGER, sensor TEXT, value REAL);
    """

    def __init__(self, path: Union[str, Path], machine: Machine, create: bool = True):
        self.path = Path(path)
        if not create and not self.path.exists():
            raise FileFormatError(f"{self.path}: history file not found")
        if not self.path.parent.is_dir():
            raise FileFormatError(f"{self.path}: the folder {self.path.parent} does not exist")
        try:
            self.conn = sqlite3.connect(self.path)
            with self.conn:
                self.conn.executescript(self.SCHEMA)
                rows = dict(self.conn.execute("SELECT key, value FROM meta").fetchall())
        except sqlite3.DatabaseError as exc:
            raise FileFormatError(f"{self.path}: not a gagekit history file ({exc})") from None
        sig = "|".join(g.name for g in machine.structure().groups)
        if rows:
            if rows.get("machine") != machine.name or rows.get("groups") != sig:
                raise ConfigError(
                    f"{self.path}: this history belongs to machine '{rows.get('machine')}', not '{machine.name}' "
                    "(or the machine file changed its error model): use another --history file"
                )
        elif create:
            with self.conn:
                self.conn.executemany("INSERT INTO meta VALUES (?, ?)", [("machine", machine.name), ("groups", sig),
                                      ("created", datetime.now(timezone.utc).isoformat())])

    def close(self) -> None:
        self.conn.close()

    def append(self, cycles: Cycles, result: TrackResult) -> int:
        """Store one tracking run in a single transaction; returns its run id."""
        with self.conn:
            cur = self.conn.execute("INSERT INTO runs (created, source, n_points) VALUES (?, ?, ?)",
                                    (datetime.now(timezone.utc).isoformat(), cycles.source, len(cycles.commands)))
            run = int(cur.lastrowid)
            for j, row in enumerate(result.cycles):
                cid = row["cycle"]
                self.conn.execute("INSERT INTO cycles VALUES (?, ?, ?, ?)", (run, cid, row.get("time"), json.dumps(row)))
                self.conn.executemany(
                    "INSERT INTO observations VALUES (?, ?, ?, ?, ?, ?, ?)",
                    [(run, cid, i, json.dumps(cycles.commands[i].tolist()), *map(float, cycles.measured[j, i]))
                     for i in range(len(cycles.commands))],
                )
                self.conn.executemany("INSERT INTO groups VALUES (?, ?, ?, ?)",
                                      [(run, cid, name, v[j]) for name, v in result.groups.items()])
                r = result.residuals
                self.conn.executemany(
                    "INSERT INTO residuals VALUES (?, ?, ?, ?, ?, ?)",
                    [(run, cid, i, float(r["full"][j, i]), float(r["static"][j, i]), float(r["drift_only"][j, i]))
                     for i in range(r["full"].shape[1])],
                )
                self.conn.executemany("INSERT INTO temperatures VALUES (?, ?, ?, ?)",
                                      [(run, cid, s, float(v[j])) for s, v in cycles.temperatures.items()])
        return run

    def summary(self) -> dict:
        meta = dict(self.conn.execute("SELECT key, value FROM meta").fetchall())
        runs = []
        for run, created, source, npts in self.conn.execute("SELECT id, created, source, n_points FROM runs ORDER BY id"):
            cyc = [json.loads(s) for (s,) in self.conn.execute("SELECT stats FROM cycles WHERE run = ? ORDER BY cycle", (run,))]
            runs.append({"run": run, "created": created, "source": source, "points": npts,
                         "cycles": [{"cycle": c["cycle"], "observed_mean": c["observed"]["mean"],
                                     "full_mean": c["full"]["mean"], "static_mean": c["static"]["mean"],
                                     "drift_only_mean": c["drift_only"]["mean"]} for c in cyc]})
        return {"machine": meta.get("machine"), "created": meta.get("created"), "runs": runs}


def read_history(path: Union[str, Path]) -> dict:
    """The summary of a history file, opened read-only (no machine file needed)."""
    p = Path(path)
    if not p.exists():
        raise FileFormatError(f"{p}: history file not found")
    h = History.__new__(History)
    h.path = p
    try:
        h.conn = sqlite3.connect(f"file:{p}?mode=ro", uri=True)
        return h.summary()
    except sqlite3.DatabaseError as exc:
        raise FileFormatError(f"{p}: not a gagekit history file ({exc})") from None
    finally:
        if hasattr(h, "conn"):
            h.conn.close()


# ------------------------------------------------------------------------------- simulation

#: Thermal state of the simulated cycles: heating for four cycles, then cooling (Fig. 4.4).
HEAT_PROFILE = (0.0, 1.0, 2.0, 3.0, 4.0, 2.6)


def simulate_cycles(
    machine: Machine,
    truth: Truth,
    commands: Any,
    cycles: int = 6,
    noise: float = TRACKER_SIGMA,
    drift_scale: float = 1.0,
    seed: int = 0,
) -> tuple[list[np.ndarray], dict]:
    """Thermal mode of the simulator: the W- and Y-axis terms drift with a heating and
    cooling profile (Fig. 4.8: only they changed markedly), temperatures follow (W +4.5 C,
    Y +3 C at the end of heating, X and Z under 2 C, Fig. 4.7).

    Returns the rows (cycle, joints, x, y, z, time, temp_X..temp_W) per cycle and the header.
    """
    if cycles < 1:
        raise InvalidInputError("--cycles must be at least 1")
    names = machine.parameter_names
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x7468]))
    drift = np.zeros(len(names))
    per_step = {"W.delta": 2e-5, "W.dbeta": 1.2e-8, "W.dgamma": 1e-8, "Y.delta": 1.2e-5, "Y.dalpha": 8e-9, "Y.dgamma": 6e-9}
    for k, v in per_step.items():
        if k in names:
            drift[names.index(k)] = v * drift_scale * (1 if rng.random() < 0.5 else -1)
    profile = [HEAT_PROFILE[min(j, len(HEAT_PROFILE) - 1)] if j < len(HEAT_PROFILE) else HEAT_PROFILE[-1] * 0.8 ** (j - 5)
               for j in range(cycles)]
    rise = {"X": 0.35, "Z": 0.4, "Y": 0.75, "W": 1.12}
    joints = machine.joint_names
    sensors = [f"temp_{j}" for j in joints if j in rise]
    out = []
    cmds = machine.commands_array(commands)
    for j in range(cycles):
        t = Truth(truth.machine, truth.parameter_names, truth.parameters + profile[j] * drift, truth.frame)
        obs = simulate(machine, t, cmds, noise=noise, seed=seed + 31 * j)
        temps = [20.0 + rise[s[5:]] * profile[j] + rng.normal(scale=0.05) for s in sensors]
        block = np.column_stack([np.full(len(cmds), j + 1), cmds, obs.measured, np.full(len(cmds), 60.0 * j),
                                 np.tile(temps, (len(cmds), 1))])
        out.append(block)
    header = ["cycle", *joints, *_XYZ, "time", *sensors]
    return out, {"header": header, "drift": {k: float(drift[names.index(k)]) for k in per_step if k in names}}
