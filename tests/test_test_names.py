"""Test modules in folders without ``__init__.py`` are imported by their base name (pytest's
rootdir-relative import mode): two with the same name break the collection of the whole
suite. Each such name is unique."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def test_test_module_names_are_unique():
    names = Counter(p.name for p in TESTS.rglob("test_*.py") if not (p.parent / "__init__.py").exists())
    assert [n for n, k in names.items() if k > 1] == []
