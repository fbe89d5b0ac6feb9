"""The command line as people read it (issue 22 section 6): every command's --help prints the
TOML table names of its texts, no `<bool>` after flags, no 20-digit seed bound; `form fit -c`
names the criteria; `stats --spec` takes a drawing too."""

from __future__ import annotations

import subprocess
import sys

import pytest
import typer

from gagekit.cli import app


def _leaves(cmd, prefix=()):
    sub = getattr(cmd, "commands", None)
    if not sub:
        yield prefix
        return
    for name, c in sub.items():
        yield from _leaves(c, (*prefix, name))


COMMANDS = sorted(_leaves(typer.main.get_command(app)))


def _help(*path: str) -> str:
    from typer.testing import CliRunner

    r = CliRunner().invoke(app, [*path, "--help"], terminal_width=400, max_content_width=400)
    assert r.exit_code == 0, r.output
    return r.output


@pytest.fixture(scope="module")
def helps() -> dict:
    return {" ".join(c): _help(*c) for c in COMMANDS}


def test_no_bool_metavar_and_no_seed_range(helps):
    for name, text in helps.items():
        assert "<bool>" not in text, name
        assert "18446744073709551615" not in text, name


def test_toml_table_names_survive(helps):
    assert "[motion], [alignment], [[region]], [[gage]]" in helps["gage check"]
    assert "[[feature]], [datums], [[tolerance]]" in helps["inspect scan"]
    assert "[[region]]" in helps["cloud regions"]


def test_form_fit_lists_its_criteria(helps):
    from gagekit.form.criteria import CIRCLE_CRITERIA

    text = " ".join(helps["form fit"].split())
    for alias, name in CIRCLE_CRITERIA.items():
        assert f"{name} ({alias})" in text, name


def test_stats_spec_takes_gages_or_part(helps):
    text = " ".join(_help("stats").split())  # a group since `stats grr`: its callback's help
    assert "GAGES.toml or PART.toml" in text


@pytest.mark.parametrize("value", ["-1", str(2**64)])
def test_seed_out_of_range_is_one_usage_line(value, tmp_path):
    from gagekit.samples import sample_path

    p = subprocess.run([sys.executable, "-m", "gagekit", "form", "fit", "cylinder", str(sample_path("bore")),
                        "--seed", value], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and p.stdout == "" and p.stderr.count("\n") == 1, p.stderr
    assert p.stderr.startswith("gagekit: error: ") and "2**64 - 1" in p.stderr
