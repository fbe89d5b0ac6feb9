"""The results database's tables (SQLAlchemy 2 declarative models).

One schema for a plant: parts and their specifications, scans (by content) and the paths
they were seen at, one result per (scan, specification) with its virtual-gage allowances and
T* (Eqs. 5.4, 5.11), form results (Ch. 6) and inspection results, and per machine its
calibrations and tracking cycles (Sec. 4.3: group values per cycle, Tables 4.4-4.6).
The Alembic migrations under ``migrations/versions`` create exactly these tables; a test
compares the two.
"""

from __future__ import annotations

from datetime import datetime
from typing import Any, Optional

from sqlalchemy import JSON, BigInteger, Boolean, DateTime, Float, ForeignKey, Index, Integer, MetaData, String, Text, UniqueConstraint
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column

NAMING = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}


class Base(DeclarativeBase):
    metadata = MetaData(naming_convention=NAMING)


def _ts() -> Mapped[datetime]:
    return mapped_column(DateTime(timezone=True), nullable=False)


# ------------------------------------------------------------------------- parts and scans


class Part(Base):
    """A part number (a drawing): the specifications checked against it share it."""

    __tablename__ = "parts"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), nullable=False, unique=True)
    created: Mapped[datetime] = _ts()


class Spec(Base):
    """A specification as evaluated: kind (gage, form, inspect), its document and options.

    ``hash`` is the SHA-256 of the canonical JSON of (kind, document, options): a changed
    drawing is a new spec, and every scan is evaluated again against it."""

    __tablename__ = "specs"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    hash: Mapped[str] = mapped_column(String(64), nullable=False, unique=True)
    kind: Mapped[str] = mapped_column(String(16), nullable=False)
    part_id: Mapped[Optional[int]] = mapped_column(ForeignKey("parts.id"), nullable=True)
    source: Mapped[Optional[str]] = mapped_column(Text, nullable=True)
    document: Mapped[Any] = mapped_column(JSON, nullable=False)
    created: Mapped[datetime] = _ts()


class Scan(Base):
    """A scan file's content, identified by the SHA-256 of its bytes."""

    __tablename__ = "scans"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    content_hash: Mapped[str] = mapped_column(String(64), nullable=False, unique=True)
    size_bytes: Mapped[int] = mapped_column(BigInteger, nullable=False)
    #: when the scan was taken: the modification time of the first file it was seen in
    scanned: Mapped[datetime] = _ts()
    created: Mapped[datetime] = _ts()
    #: since revision 0003: when the scanner took it, from the file's header (E57
    #: acquisitionStart, LAS creation date); NULL when the format does not say
    acquired: Mapped[Optional[datetime]] = mapped_column(DateTime(timezone=True), nullable=True)


class ScanPath(Base):
    """Every path a scan's content was seen at (two files of the same content: both)."""

    __tablename__ = "scan_paths"
    __table_args__ = (UniqueConstraint("scan_id", "path", name="uq_scan_paths_scan_id_path"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    scan_id: Mapped[int] = mapped_column(ForeignKey("scans.id"), nullable=False)
    path: Mapped[str] = mapped_column(Text, nullable=False)
    seen: Mapped[datetime] = _ts()


class Result(Base):
    """One evaluation of one scan against one spec: ``ok`` with the JSON the single-scan
    command prints, or ``error`` with its message. Unique per (scan, spec): a batch run again
    skips what is here, and concurrent writers cannot store a result twice."""

    __tablename__ = "results"
    __table_args__ = (UniqueConstraint("scan_id", "spec_id", name="uq_results_scan_id_spec_id"),
                      Index("ix_results_spec_id_finished", "spec_id", "finished"))
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    scan_id: Mapped[int] = mapped_column(ForeignKey("scans.id"), nullable=False)
    spec_id: Mapped[int] = mapped_column(ForeignKey("specs.id"), nullable=False)
    path: Mapped[str] = mapped_column(Text, nullable=False)
    status: Mapped[str] = mapped_column(String(8), nullable=False)
    error: Mapped[Optional[str]] = mapped_column(Text, nullable=True)
    result: Mapped[Any] = mapped_column(JSON, nullable=True)
    started: Mapped[datetime] = _ts()
    finished: Mapped[datetime] = _ts()
    seconds: Mapped[float] = mapped_column(Float, nullable=False)
    worker: Mapped[Optional[str]] = mapped_column(String(200), nullable=True)


class GageCheck(Base):
    """The virtual-gage outcome of a result: status, Eq. 5.11's objective, T* (rad, mm)."""

    __tablename__ = "gage_checks"
    result_id: Mapped[int] = mapped_column(ForeignKey("results.id"), primary_key=True)
    status: Mapped[str] = mapped_column(String(16), nullable=False)
    objective: Mapped[float] = mapped_column(Float, nullable=False)
    largest_release: Mapped[float] = mapped_column(Float, nullable=False)
    alpha: Mapped[float] = mapped_column(Float, nullable=False)
    beta: Mapped[float] = mapped_column(Float, nullable=False)
    gamma: Mapped[float] = mapped_column(Float, nullable=False)
    dx: Mapped[float] = mapped_column(Float, nullable=False)
    dy: Mapped[float] = mapped_column(Float, nullable=False)
    dz: Mapped[float] = mapped_column(Float, nullable=False)


class GageAllowance(Base):
    """One gage of a result (mm): allowances before/after T*, q_i and the slack s_i."""

    __tablename__ = "gage_allowances"
    __table_args__ = (UniqueConstraint("result_id", "gage", name="uq_gage_allowances_result_id_gage"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    result_id: Mapped[int] = mapped_column(ForeignKey("results.id"), nullable=False)
    gage: Mapped[str] = mapped_column(String(200), nullable=False)
    region: Mapped[str] = mapped_column(String(200), nullable=False)
    points: Mapped[int] = mapped_column(Integer, nullable=False)
    filtered_points: Mapped[int] = mapped_column(Integer, nullable=False)
    allowance_before: Mapped[float] = mapped_column(Float, nullable=False)
    allowance_after: Mapped[float] = mapped_column(Float, nullable=False)
    q: Mapped[float] = mapped_column(Float, nullable=False)
    slack: Mapped[float] = mapped_column(Float, nullable=False)
    # since revision 0004: the result's uncertainty (JCGM 101) and ISO 14253-1 decision,
    # NULL for a result computed without --uncertainty
    u: Mapped[Optional[float]] = mapped_column(Float, nullable=True)
    """standard uncertainty (k = 1) of the allowance after T*, mm"""
    expanded_u: Mapped[Optional[float]] = mapped_column(Float, nullable=True)
    """expanded uncertainty U (half the 95 % coverage interval), mm"""
    decision: Mapped[Optional[str]] = mapped_column(String(16), nullable=True)
    """``conforming``, ``not-proven`` or ``nonconforming``"""
    decision_rule: Mapped[Optional[str]] = mapped_column(String(64), nullable=True)


class FormResult(Base):
    """A form fit of a result (Ch. 6): shape, criterion, form error (mm), size when it has one."""

    __tablename__ = "form_results"
    result_id: Mapped[int] = mapped_column(ForeignKey("results.id"), primary_key=True)
    shape: Mapped[str] = mapped_column(String(32), nullable=False)
    criterion: Mapped[str] = mapped_column(String(32), nullable=False)
    n_points: Mapped[int] = mapped_column(Integer, nullable=False)
    form_error: Mapped[float] = mapped_column(Float, nullable=False)
    radius: Mapped[Optional[float]] = mapped_column(Float, nullable=True)


class InspectionResult(Base):
    """One tolerance of an inspection result (GD&T): the measured value against its limits."""

    __tablename__ = "inspection_results"
    __table_args__ = (UniqueConstraint("result_id", "tolerance", name="uq_inspection_results_result_id_tolerance"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    result_id: Mapped[int] = mapped_column(ForeignKey("results.id"), nullable=False)
    tolerance: Mapped[str] = mapped_column(String(200), nullable=False)
    characteristic: Mapped[str] = mapped_column(String(64), nullable=False)
    value: Mapped[float] = mapped_column(Float, nullable=False)
    lower: Mapped[Optional[float]] = mapped_column(Float, nullable=True)
    upper: Mapped[Optional[float]] = mapped_column(Float, nullable=True)
    conforming: Mapped[bool] = mapped_column(Boolean, nullable=False)
    # since revision 0002: what the callout is, beyond its name (NULL only where a result's
    # JSON could not say, which no result written by gagekit is)
    feature: Mapped[Optional[str]] = mapped_column(String(200), nullable=True)
    datums: Mapped[Optional[str]] = mapped_column(String(64), nullable=True)
    """the datum reference frame as written in a feature control frame, e.g. ``A|B|C``"""
    zone: Mapped[Optional[str]] = mapped_column(String(32), nullable=True)
    """``width``, ``diameter`` or ``spherical diameter``: what ``value`` and ``upper`` are"""
    n_points: Mapped[Optional[int]] = mapped_column(Integer, nullable=True)
    # since revision 0004: the result's uncertainty (JCGM 101) and ISO 14253-1 decision,
    # NULL for a result computed without --uncertainty
    u: Mapped[Optional[float]] = mapped_column(Float, nullable=True)
    """standard uncertainty (k = 1) of the value, mm"""
    expanded_u: Mapped[Optional[float]] = mapped_column(Float, nullable=True)
    """expanded uncertainty U (half the 95 % coverage interval), mm"""
    decision: Mapped[Optional[str]] = mapped_column(String(16), nullable=True)
    """``conforming``, ``not-proven`` or ``nonconforming``"""
    decision_rule: Mapped[Optional[str]] = mapped_column(String(64), nullable=True)


# ----------------------------------------------------------------------------- machines


class MachineRow(Base):
    """A machine tool, with the signature of its error model (the group names, in order)."""

    __tablename__ = "machines"
    __table_args__ = (UniqueConstraint("name", "signature", name="uq_machines_name_signature"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), nullable=False)
    signature: Mapped[str] = mapped_column(Text, nullable=False)
    created: Mapped[datetime] = _ts()


class Calibration(Base):
    """One calibration session of a machine: a tracking run over measurement cycles
    (``kind = 'track'``, Sec. 4.3) with its tracker frame (Eq. 4.11)."""

    __tablename__ = "calibrations"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    machine_id: Mapped[int] = mapped_column(ForeignKey("machines.id"), nullable=False)
    kind: Mapped[str] = mapped_column(String(16), nullable=False)
    created: Mapped[datetime] = _ts()
    source: Mapped[Optional[str]] = mapped_column(Text, nullable=True)
    n_points: Mapped[int] = mapped_column(Integer, nullable=False)
    frame: Mapped[Any] = mapped_column(JSON, nullable=True)


class TrackingCycle(Base):
    """A measurement cycle of a calibration: time (min) and the Table 4.4-4.6 statistics."""

    __tablename__ = "tracking_cycles"
    __table_args__ = (UniqueConstraint("calibration_id", "cycle", name="uq_tracking_cycles_calibration_id_cycle"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    calibration_id: Mapped[int] = mapped_column(ForeignKey("calibrations.id"), nullable=False)
    cycle: Mapped[int] = mapped_column(Integer, nullable=False)
    time: Mapped[Optional[float]] = mapped_column(Float, nullable=True)
    stats: Mapped[Any] = mapped_column(JSON, nullable=False)


class GroupValue(Base):
    """An identified parameter group's value in a cycle (Eqs. 4.12-4.13; Fig. 4.8)."""

    __tablename__ = "group_values"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    calibration_id: Mapped[int] = mapped_column(ForeignKey("calibrations.id"), nullable=False)
    cycle: Mapped[int] = mapped_column(Integer, nullable=False)
    name: Mapped[str] = mapped_column(Text, nullable=False)
    value: Mapped[float] = mapped_column(Float, nullable=False)
    unit: Mapped[Optional[str]] = mapped_column(String(32), nullable=True)
    effect_mm: Mapped[Optional[float]] = mapped_column(Float, nullable=True)


class CycleObservation(Base):
    """A tracker reading of a cycle: the commanded joints (JSON list) and x, y, z (mm)."""

    __tablename__ = "cycle_observations"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    calibration_id: Mapped[int] = mapped_column(ForeignKey("calibrations.id"), nullable=False)
    cycle: Mapped[int] = mapped_column(Integer, nullable=False)
    idx: Mapped[int] = mapped_column(Integer, nullable=False)
    commands: Mapped[Any] = mapped_column(JSON, nullable=False)
    x: Mapped[float] = mapped_column(Float, nullable=False)
    y: Mapped[float] = mapped_column(Float, nullable=False)
    z: Mapped[float] = mapped_column(Float, nullable=False)


class CycleResidual(Base):
    """Residual norms (mm) at an observation: full, static and drift-only (Eqs. 4.14-4.18)."""

    __tablename__ = "cycle_residuals"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    calibration_id: Mapped[int] = mapped_column(ForeignKey("calibrations.id"), nullable=False)
    cycle: Mapped[int] = mapped_column(Integer, nullable=False)
    idx: Mapped[int] = mapped_column(Integer, nullable=False)
    full: Mapped[float] = mapped_column(Float, nullable=False)
    static: Mapped[float] = mapped_column(Float, nullable=False)
    drift_only: Mapped[float] = mapped_column(Float, nullable=False)


class CycleTemperature(Base):
    """A sensor's cycle-mean temperature (deg C, Fig. 4.7)."""

    __tablename__ = "cycle_temperatures"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    calibration_id: Mapped[int] = mapped_column(ForeignKey("calibrations.id"), nullable=False)
    cycle: Mapped[int] = mapped_column(Integer, nullable=False)
    sensor: Mapped[str] = mapped_column(String(64), nullable=False)
    value: Mapped[float] = mapped_column(Float, nullable=False)


TABLES = [t.name for t in Base.metadata.sorted_tables]
