"""Fit criterion names: the package's one table of names and aliases is Rust's
(``gagekit_form::criterion``, read through ``_core.form.criteria``); every part of the
package (form, gage, inspect, the CLI) parses names here, and stores the canonical name
(``least-squares``, ``min-circumscribed``, ``max-inscribed``, ``minimum-zone``).
"""

from __future__ import annotations

from typing import Iterable

from .. import _core

__all__ = ["ALIASES", "CIRCLE_CRITERIA", "CRITERIA", "SHAPE_CRITERIA", "criterion_name"]

_TABLE = _core.form.criteria()

#: Every accepted spelling (lower case, '-' for '_') and the canonical name it stands for.
ALIASES: dict[str, str] = {alias: name for alias, name, _ in _TABLE}

#: The canonical names, in the order of the documentation.
CRITERIA: tuple[str, ...] = tuple(dict.fromkeys(name for _, name, _ in _TABLE))

#: The short codes of the 2-D circle fits (lsq, mc, mi, mz) and their canonical names.
CIRCLE_CRITERIA: dict[str, str] = {code: name for _, name, code in _TABLE}

#: The criteria the fit of each shape accepts (canonical names); the fits and the batches
#: (which check the name before the first scan) read them here.
SHAPE_CRITERIA: dict[str, tuple[str, ...]] = {
    "circle": CRITERIA,
    "line": ("least-squares", "minimum-zone"),
    "plane": ("least-squares", "minimum-zone"),
    "sphere": ("least-squares", "min-circumscribed", "max-inscribed", "minimum-zone"),
    "cylinder": ("least-squares", "min-circumscribed", "max-inscribed", "minimum-zone"),
    "cone": ("least-squares", "min-circumscribed", "max-inscribed", "minimum-zone"),
}


def criterion_name(criterion: object, allowed: Iterable[str] = (), shape: str = "fit") -> str:
    """The canonical name of ``criterion`` (any alias of the table), or a
    :class:`~gagekit.errors.ConfigError` listing the names ``allowed`` (all when empty)
    for ``shape``."""
    return _core.form.criterion(str(criterion), list(allowed), shape)
