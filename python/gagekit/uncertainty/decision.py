"""Decision rules for proving conformity or nonconformity (ISO 14253-1:2017; ASME
B89.7.3.1-2001 for guard bands).

A callout's measured value y, its expanded uncertainty U and its limits decide it:

``simple``
    Shared-risk acceptance: ``conforming`` inside the limits (limits included), else
    ``nonconforming``; U is ignored (the rule when no uncertainty is computed).
``iso14253`` (ISO 14253-1 Sec. 5, guard band g = U)
    ``conforming`` when y +- U lies within the limits (conformity proven, Sec. 5.2),
    ``nonconforming`` when y +- U lies beyond a limit (nonconformity proven, Sec. 5.3),
    ``not-proven`` in between -- so a value exactly at its limit with U > 0 is not-proven.
``guard-band=FRACTION``
    The same with the guard band g = FRACTION x U (ASME B89.7.3.1 states guard bands as a
    percentage of U: ``guard-band=1`` is ``iso14253``, ``guard-band=0`` accepts on the limit
    and rejects beyond it, with no not-proven zone).

The part takes its worst callout's decision (nonconforming > not-proven > conforming).
The exit status of the commands does not change with the decision.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Optional

from ..errors import InvalidInputError

__all__ = ["DecisionRule", "parse_decision_rule", "decide", "decide_margin", "worst_decision", "DECISIONS", "RULES"]

#: The decisions, best first.
DECISIONS = ("conforming", "not-proven", "nonconforming")
#: The rule names the option takes.
RULES = ("simple", "iso14253", "guard-band=FRACTION")


@dataclass(frozen=True)
class DecisionRule:
    """A decision rule: ``name`` is ``simple``, ``iso14253`` or ``guard-band``; ``fraction``
    the guard band as a fraction of U (1 for iso14253, 0 for simple)."""

    name: str
    fraction: float = 1.0

    @property
    def label(self) -> str:
        """The rule as the option spells it (``guard-band=0.5``), for reports and JSON."""
        return f"guard-band={self.fraction:g}" if self.name == "guard-band" else self.name

    def describe(self) -> str:
        if self.name == "simple":
            return "simple acceptance (the measured value against the limits; uncertainty not applied)"
        if self.name == "iso14253":
            return "ISO 14253-1:2017 (conformity proven when value +- U is within the limits, nonconformity when beyond)"
        return f"guard band of {self.fraction:g} x U (ASME B89.7.3.1)"

    def to_dict(self) -> dict:
        return {"name": self.label, "guard_band_fraction_of_U": 0.0 if self.name == "simple" else self.fraction,
                "description": self.describe()}


def parse_decision_rule(text: Optional[str], uncertainty: bool = False) -> DecisionRule:
    """``simple``, ``iso14253`` or ``guard-band=FRACTION`` (FRACTION >= 0, a finite number);
    ``None``: ``iso14253`` when an uncertainty is computed, ``simple`` otherwise.
    Anything else raises :class:`InvalidInputError` naming the accepted forms."""
    if text is None:
        return DecisionRule("iso14253", 1.0) if uncertainty else DecisionRule("simple", 0.0)
    if not isinstance(text, str):
        raise InvalidInputError(f"decision rule: expected one of {', '.join(RULES)}, got {text!r}")
    t = text.strip().lower()
    if t == "simple":
        return DecisionRule("simple", 0.0)
    if t in ("iso14253", "iso-14253", "iso14253-1"):
        return DecisionRule("iso14253", 1.0)
    if t.startswith("guard-band="):
        raw = t.split("=", 1)[1]
        try:
            f = float(raw)
        except ValueError:
            f = float("nan")
        if not math.isfinite(f) or f < 0:
            raise InvalidInputError(f"decision rule {text!r}: FRACTION must be a finite number >= 0 (the guard band as a "
                                    "fraction of U, e.g. guard-band=0.5)")
        return DecisionRule("guard-band", f)
    raise InvalidInputError(f"decision rule {text!r}: expected one of {', '.join(RULES)}")


def _check(value: float, what: str) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise InvalidInputError(f"decide: {what} must be a finite number, got {value!r}")
    return v


def decide_margin(margin: float, U: float, rule: DecisionRule) -> str:
    """The decision for a callout whose value lies ``margin`` inside its nearest limit
    (negative: beyond it), with the expanded uncertainty ``U`` (>= 0) of that margin."""
    m = _check(margin, "margin")
    u = _check(U, "U")
    if u < 0:
        raise InvalidInputError(f"decide: U must be >= 0, got {U!r}")
    if rule.name == "simple":
        return "conforming" if m >= 0 else "nonconforming"
    g = rule.fraction * u
    if m >= g:
        return "conforming"
    if m < -g:
        return "nonconforming"
    return "not-proven"


def decide(value: float, U: float, *, upper: Optional[float] = None, lower: Optional[float] = None,
           rule: DecisionRule = DecisionRule("iso14253", 1.0)) -> str:
    """The decision for a measured ``value`` with expanded uncertainty ``U`` against an
    ``upper`` and / or ``lower`` limit (ISO 14253-1; see the module docstring). For a
    virtual gage's allowance, ``lower=0``; for a form or location zone, ``upper=tolerance``."""
    if upper is None and lower is None:
        raise InvalidInputError("decide: give an upper or a lower limit (or both)")
    v = _check(value, "value")
    margins = []
    if upper is not None:
        margins.append(_check(upper, "upper") - v)
    if lower is not None:
        margins.append(v - _check(lower, "lower"))
    if upper is not None and lower is not None and float(upper) < float(lower):
        raise InvalidInputError(f"decide: upper limit {upper} below lower limit {lower}")
    return decide_margin(min(margins), U, rule)


def worst_decision(decisions: Iterable[str]) -> str:
    """The part's decision: its worst callout's (``conforming`` when there are none)."""
    worst = 0
    for d in decisions:
        if d not in DECISIONS:
            raise InvalidInputError(f"worst_decision: unknown decision {d!r} (one of {', '.join(DECISIONS)})")
        worst = max(worst, DECISIONS.index(d))
    return DECISIONS[worst]
