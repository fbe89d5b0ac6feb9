"""`sections` has an upper bound (issue 22 section 3): a drawing asking for 10^9 or 2^63-1
sections is refused at once in one line, on [part], a feature or a tolerance."""

import subprocess
import sys

import pytest

from gagekit.samples import data_path
from gagekit.inspect.spec import MAX_SECTIONS


def _drawing(tmp_path, where: str, value: int):
    text = data_path("bracket.toml").read_text(encoding="utf-8")
    if where == "part":
        text = text.replace('name = "bracket"', f'name = "bracket"\nsections = {value}', 1)
    elif where == "feature":
        text = text.replace('shape = "cylinder"', f'shape = "cylinder"\nsections = {value}', 1)
    else:
        text = text.replace('[[tolerance]]\n', f'[[tolerance]]\nsections = {value}\n', 1)
    assert f"sections = {value}" in text
    p = tmp_path / "PART.toml"
    p.write_text(text, encoding="utf-8")
    return p


@pytest.mark.parametrize("where", ["part", "feature", "tolerance"])
@pytest.mark.parametrize("value", [10**9, 2**63 - 1, MAX_SECTIONS + 1])
def test_too_many_sections_are_refused_in_one_line(tmp_path, where, value):
    part = _drawing(tmp_path, where, value)
    p = subprocess.run([sys.executable, "-m", "gagekit", "inspect", str(data_path("bracket.ply")), str(part), "--json"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and p.stdout == "", p.stderr
    err = p.stderr.splitlines()
    assert len(err) == 1 and err[0].startswith("gagekit: error: ") and f"'sections' = {value} is more than {MAX_SECTIONS}" in err[0]


def test_the_bound_itself_is_accepted(tmp_path):
    from gagekit.inspect import load_part_spec

    spec = load_part_spec(_drawing(tmp_path, "part", MAX_SECTIONS))
    assert spec.features["bore"].sections == MAX_SECTIONS
