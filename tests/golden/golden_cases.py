"""The commands whose ``--json`` numbers must not change when the code is reorganised
(issue 23: "every number every command prints stays the same"). Each case is a name and
the arguments after ``gagekit``; ``{sample}`` fields are bundled samples, ``{tmp}`` a
scratch folder, ``{golden}`` this folder. ``python tests/golden/regenerate.py`` records them after an intended
change of behaviour (say which in the commit)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: keys whose values are timings, paths or versions: not compared
VOLATILE = {"seconds", "elapsed", "elapsed_s", "time", "created", "version", "path", "file", "source", "out", "report",
            "scan", "spec", "cad", "machine_file", "calibration", "observations", "report_dir", "db", "url", "threads"}

CASES: dict[str, list[str]] = {
    "cloud_info_bracket": ["cloud", "info", "{bracket}", "--json"],
    "gage_check_ok": ["gage", "check", "{casting}", "{casting-gages}", "--json"],
    "gage_check_short": ["gage", "check", "{casting-short}", "{casting-short-gages}", "--json"],
    "inspect_bracket": ["inspect", "{bracket}", "{bracket-part}", "--json"],
    "inspect_bracket_turns": ["inspect", "{bracket}", "{golden}/bracket_turns.toml", "--json"],
    "form_cylinder_set1_mz": ["form", "fit", "cylinder", "{cylinder-set1}", "-c", "minimum-zone", "--seed", "0", "--json"],
    "form_cylinder_set3_lsq": ["form", "fit", "cylinder", "{cylinder-set3}", "-c", "least-squares", "--json"],
    "form_circle_all": ["form", "circle", "{round}", "-c", "all", "--json"],
    "form_sphere_mz": ["form", "fit", "sphere", "{ball}", "-c", "mz", "--json"],
    "machine_check": ["machine", "check", "{machine}", "--json"],
    "machine_identify": ["machine", "identify", "{machine}", "{tmp}/obs.csv", "--json"],
    "iso230_2": ["machine", "iso230-2", "{iso230-2}", "--json"],
}

#: commands run before a case (their output is its input)
SETUP: dict[str, list[list[str]]] = {
    "machine_identify": [["machine", "simulate", "{machine}", "--points", "60", "--seed", "3", "--out", "{tmp}/obs.csv"]],
}


def _fill(args: list[str], tmp: Path) -> list[str]:
    from gagekit.samples import SAMPLES, sample_path

    out = []
    for a in args:
        if a.startswith("{") and a.endswith("}") and a[1:-1] in SAMPLES:
            a = str(sample_path(a[1:-1]))
        out.append(a.replace("{tmp}", str(tmp)).replace("{golden}", str(HERE)))
    return out


def run_case(name: str, tmp: Path) -> dict:
    """The parsed ``--json`` output of case ``name`` (its set-up commands first)."""
    env = dict(os.environ)
    for pre in SETUP.get(name, []):
        subprocess.run([sys.executable, "-m", "gagekit", *_fill(pre, tmp)], check=True, capture_output=True, env=env)
    p = subprocess.run([sys.executable, "-m", "gagekit", *_fill(CASES[name], tmp)], capture_output=True, text=True, env=env)
    if p.returncode != 0:
        raise AssertionError(f"{name}: exit {p.returncode}: {p.stderr[-2000:]}")
    return json.loads(p.stdout)


def differences(want, got, where: str = "$", rel: float = 1e-9, abs_: float = 1e-12) -> list[str]:
    """Where ``got`` departs from ``want``: every number within ``rel`` (relative) or
    ``abs_``; strings and booleans equal; keys of ``want`` present in ``got`` (new keys
    are allowed); lists of the same length. Volatile keys are skipped."""
    out: list[str] = []
    if isinstance(want, dict):
        if not isinstance(got, dict):
            return [f"{where}: an object became {type(got).__name__}"]
        for k, v in want.items():
            if k in VOLATILE:
                continue
            if k not in got:
                out.append(f"{where}.{k}: missing")
            else:
                out += differences(v, got[k], f"{where}.{k}", rel, abs_)
    elif isinstance(want, list):
        if not isinstance(got, list) or len(got) != len(want):
            return [f"{where}: a list of {len(want)} became {len(got) if isinstance(got, list) else type(got).__name__}"]
        for i, (a, b) in enumerate(zip(want, got)):
            out += differences(a, b, f"{where}[{i}]", rel, abs_)
    elif isinstance(want, bool) or want is None:
        if want != got:
            out.append(f"{where}: {want!r} became {got!r}")
    elif isinstance(want, (int, float)):
        if not isinstance(got, (int, float)) or isinstance(got, bool) or abs(got - want) > max(abs_, rel * abs(want)):
            out.append(f"{where}: {want!r} became {got!r}")
    elif isinstance(want, str):
        if "/" not in want and want != got:
            out.append(f"{where}: {want!r} became {got!r}")
    return out
