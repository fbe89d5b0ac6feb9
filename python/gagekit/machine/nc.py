"""NC programs corrected by the inverse error model (issue 15 part 2; Sec. 7.1.1 (3)).

``compensate_nc(machine, calibration, program, out)`` reads a G-code program (ISO 6983 /
RS-274) written with the machine's joint letters and writes it corrected: every programmed
point goes through the inverse of the first-order model (the same Gauss-Newton iteration as
:func:`gagekit.machine.compensate`, minimum-norm parameters of the identified groups), so
that the predicted actual target is the programmed one. The interpreter, corrector and
writer are the Rust kernel ``gagekit-nc`` (throughput: ``benches/bench_nc.py``).

- Supported: G0/G1 (modal), G90 and G91 (converted: the output is absolute, G91 is written
  G90), G17/G18/G19, G21, G40, G49, G80, G94, G61, G64, G4 with P; block numbers; F, S, T and
  M words (not M98/M99); comments ``( )`` and ``;``; ``%`` lines; ``O`` program numbers.
- Arcs (G2/G3), canned cycles, work offsets, macros (``#``, ``[ ]``, GOTO, M98) and words for
  axes the machine does not have are errors naming the line; ``linearize_arcs=TOL`` turns
  arcs into chords within TOL mm first.
- A linear (G1) move whose correction changes by more than ``max_step`` (default 0.001 mm)
  along it, or bends away from the straight line by more (moves with a rotary joint or longer
  than 100 mm are checked at the pieces' midpoints), is subdivided: the inserted points come
  first as blocks without numbers, then the original block, with its number and words, ending
  at the corrected end point. Modal words are not repeated: the first inserted block carries
  ``G1`` only where the mode in force is not already linear, and the block's feed word, which
  the original block then drops (F is modal, in force from the first inserted point). A move
  is split into at most 100,000 points (``MAX_PIECES_PER_MOVE`` of the kernel) and a program
  grows by at most 20 million: a smaller ``max_step`` is refused naming the line, not allocated.
  Rapid (G0) moves are corrected at their end point only (a controller does not move them
  straight).
- Every other byte is copied; joint words of the corrected joints are rewritten with
  ``decimals`` decimals and missing ones appended, in the program's own word order (the order
  in which it first writes each joint; inserted blocks too); a leading comment names the
  machine, the calibration's date and which axes were corrected.
- Corrected axes: by default the first prismatic joint along x, y and z (a redundant axis such
  as W keeps its programmed words; name it in ``axes`` to move it too).
- Programmed or corrected points outside the joint ranges of the machine file are corrected
  all the same, with the warning :func:`gagekit.machine.compensate` gives, naming the first
  line per joint.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Optional, Sequence, Union

import numpy as np

from .. import _core
from ..errors import ConfigError, FileFormatError, InvalidInputError
from ._files import write_files_atomically
from .export import calibration_parameters, default_axes
from .calibration import Calibration
from .model import Machine, warn_outside_ranges

__all__ = ["NcResult", "compensate_nc", "compensate_nc_text"]


@dataclass(frozen=True)
class NcResult:
    """What :func:`compensate_nc` did: counts, the largest correction of a programmed point
    (mm), the largest predicted error left at a written point (um), timing."""

    out: str
    axes: tuple[str, ...]
    max_step: float
    lines: int
    lines_written: int
    moves: int
    inserted: int
    subdivided: int
    max_correction: float
    max_remaining_um: float
    seconds: float

    @property
    def lines_per_second(self) -> float:
        return self.lines / self.seconds if self.seconds > 0 else math.inf

    def to_dict(self) -> dict:
        return {
            "out": self.out,
            "axes": list(self.axes),
            "max_step": self.max_step,
            "lines": self.lines,
            "lines_written": self.lines_written,
            "moves": self.moves,
            "inserted": self.inserted,
            "subdivided": self.subdivided,
            "max_correction": self.max_correction,
            "max_remaining_um": self.max_remaining_um,
            "seconds": self.seconds,
        }


def _letters(machine: Machine) -> str:
    names = machine.joint_names
    bad = [n for n in names if len(n) != 1 or not n.isalpha() or n.upper() in "NGMFSTPOIJKR"]
    if bad:
        raise ConfigError(
            f"machine '{machine.name}': joint '{bad[0]}' cannot be an NC address letter "
            "(joints need single letters other than N, G, M, F, S, T, P, O, I, J, K, R)"
        )
    return "".join(n.upper() for n in names)


def compensate_nc_text(
    machine: Machine,
    calibration: Calibration,
    text: bytes,
    axes: Optional[Sequence[str]] = None,
    max_step: float = 0.001,
    linearize_arcs: Optional[float] = None,
    start: Optional[Mapping[str, float]] = None,
    decimals: int = 4,
    stamp: str = "",
    source: str = "NC program",
) -> tuple[bytes, dict]:
    """The corrected program (bytes) and the kernel's report; see the module docstring.

    ``axes`` default: one prismatic joint per direction x, y, z, the first of the chain
    (a redundant axis such as W keeps its programmed words unless named). Programmed or
    corrected points outside the joint ranges give the warning of :func:`compensate`,
    naming the first line (``source``: the program's name in it)."""
    params = np.ascontiguousarray(calibration_parameters(machine, calibration))  # refuses another machine's
    letters = _letters(machine)
    names = machine.joint_names
    axes = list(axes) if axes else default_axes(machine, "grid-csv")
    unknown = [a for a in axes if a not in names]
    if unknown or not axes:
        raise InvalidInputError(f"compensation axes: unknown joint(s) {', '.join(unknown) or '(none given)'} (machine has {', '.join(names)})")
    if not (isinstance(max_step, (int, float)) and math.isfinite(max_step) and max_step > 0):
        raise InvalidInputError(f"--max-step must be a positive number of mm, got {max_step}")
    if linearize_arcs is not None and not (math.isfinite(linearize_arcs) and linearize_arcs > 0):
        raise InvalidInputError(f"--linearize-arcs must be a positive tolerance in mm, got {linearize_arcs}")
    if not (isinstance(decimals, int) and 0 <= decimals <= 9):
        raise InvalidInputError(f"--decimals must be an integer from 0 to 9, got {decimals}")
    start = dict(start or {})
    for k, v in start.items():
        if k not in names:
            raise InvalidInputError(f"--start: '{k}' is not a joint of machine '{machine.name}' ({', '.join(names)})")
        if not math.isfinite(v):
            raise InvalidInputError(f"--start {k}: not a finite number")
    unit = [float(f) for f in machine._angle_factor()]
    header = (
        f"gagekit compensate-nc: machine {machine.name}, calibration {stamp or 'undated'}; "
        f"points corrected by the inverse error model on {','.join(axes)}; linear moves subdivided "
        f"where the correction changes by more than {max_step:g} mm"
        + (f"; arcs linearised within {linearize_arcs:g} mm" if linearize_arcs else "")
    )
    out, report = _core.nc.compensate_program(
        machine._chain,
        params,
        bytes(text),
        letters,
        unit,
        [start.get(n) for n in names],
        [names.index(a) for a in axes],
        float(max_step),
        int(decimals),
        header,
        arc_tolerance=linearize_arcs,
        ranges=[(float(lo), float(hi)) for lo, hi in machine.ranges],
    )
    order = [names[j] for j in report["order"]]
    if report["outside"]:
        warn_outside_ranges(source, ", ".join(
            f"{names[j]}: {k} at line {first}" if k == 1 else f"{names[j]}: {k}, first at line {first}"
            for j, k, first in report["outside"]), stacklevel=3)
    return bytes(out), {**report, "axes": sorted(axes, key=order.index)}


def compensate_nc(
    machine: Machine,
    calibration: Calibration,
    program: Union[str, Path],
    out: Union[str, Path],
    **kwargs,
) -> NcResult:
    """Read ``program``, correct it (:func:`compensate_nc_text`) and write ``out`` atomically."""
    from .._files import output_file, read_bytes

    p = Path(program)
    text = read_bytes(p, "NC program")
    output_file(out)
    t0 = time.perf_counter()
    try:
        data, report = compensate_nc_text(machine, calibration, text, source=str(p), **kwargs)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{p}, {exc}") from None
    write_files_atomically({Path(out): data})
    seconds = time.perf_counter() - t0
    return NcResult(
        out=str(out),
        axes=tuple(report["axes"]),
        max_step=float(kwargs.get("max_step", 0.001)),
        lines=int(report["lines"]),
        lines_written=int(report["lines_written"]),
        moves=int(report["moves"]),
        inserted=int(report["inserted"]),
        subdivided=int(report["subdivided"]),
        max_correction=float(report["max_correction"]),
        max_remaining_um=float(report["max_remaining"]) * 1000.0,
        seconds=seconds,
    )
