"""The root of the package is an explicit public API (issue 23 §7): imported by name, an
explicit ``__all__``, no star import, and ``gagekit.inspect`` is the subpackage while
:func:`gagekit.inspect_scan` is the function."""

from __future__ import annotations

import ast
import types
from pathlib import Path

import gagekit

INIT = Path(gagekit.__file__)


def test_every_public_name_exists_and_is_listed_once():
    assert len(gagekit.__all__) == len(set(gagekit.__all__))
    missing = [n for n in gagekit.__all__ if not hasattr(gagekit, n)]
    assert not missing, missing


def test_no_star_import_at_the_root():
    tree = ast.parse(INIT.read_text())
    stars = [n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and any(a.name == "*" for a in n.names)]
    assert not stars, stars


def test_subpackage_public_names_reach_the_root():
    """Each subpackage's ``__all__`` is re-exported by name (a name added to a subpackage
    and forgotten at the root fails here)."""
    for sub in (gagekit.cloud, gagekit.design, gagekit.form, gagekit.gage, gagekit.machine):
        forgotten = [n for n in sub.__all__ if n not in gagekit.__all__]
        assert not forgotten, (sub.__name__, forgotten)


def test_inspect_is_the_subpackage_and_inspect_scan_the_function():
    assert isinstance(gagekit.inspect, types.ModuleType)
    assert gagekit.inspect.__name__ == "gagekit.inspect"
    assert gagekit.inspect_scan is gagekit.inspect.inspect
