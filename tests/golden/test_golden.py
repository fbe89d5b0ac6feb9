"""Every number the main commands print with ``--json`` is unchanged (issue 23's contract
for reorganising the code): each case of golden_cases.py against its recorded JSON."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from golden_cases import CASES, HERE, differences, run_case  # noqa: E402


@pytest.mark.parametrize("name", sorted(CASES))
def test_json_numbers_unchanged(name, tmp_path):
    want = json.loads((HERE / f"{name}.json").read_text())
    got = run_case(name, tmp_path)
    diff = differences(want, got)
    assert not diff, f"{name}: {len(diff)} differences, first: " + "; ".join(diff[:8])


def test_the_comparison_can_fail():
    want = {"a": 1.0, "b": [1, 2], "c": "x", "seconds": 3}
    assert differences(want, {"a": 1.0, "b": [1, 2], "c": "x", "seconds": 9, "new": 1}) == []
    assert differences(want, {"a": 1.0 + 1e-6, "b": [1, 2], "c": "x"})
    assert differences(want, {"a": 1.0, "b": [1], "c": "x"})
    assert differences(want, {"a": 1.0, "b": [1, 2], "c": "y"})
    assert differences(want, {"b": [1, 2], "c": "x"})
