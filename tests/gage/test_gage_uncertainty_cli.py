"""`gagekit gage check --uncertainty N --noise SIGMA --decision-rule RULE` (issue 26 Sec. 2) on
the bundled castings: JSON keys, seeded and thread-independent, streamed = whole read, bad
input one line and exit 2."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

DATA = Path(__file__).resolve().parents[2] / "python" / "gagekit" / "data"
OK = (DATA / "casting_ok.ply", DATA / "casting_ok.toml")
SHORT = (DATA / "casting_short.ply", DATA / "casting_short.toml")


def gk(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", "gage", "check", *map(str, args)], capture_output=True,
                          text=True, timeout=600)


def _json(proc) -> dict:
    assert proc.returncode == 0, proc.stderr
    d = json.loads(proc.stdout)
    d["monte_carlo"].pop("seconds", None)
    d["monte_carlo"].pop("threads", None)
    return d


def test_json_keys_seed_threads_and_stream():
    args = (*OK, "--uncertainty", 20, "--noise", 0.01, "--seed", 4, "--json")
    d = _json(gk(*args, "--threads", 1))
    assert d["decision_rule"]["name"] == "iso14253" and d["decision"] in ("conforming", "not-proven", "nonconforming")
    for g in d["gages"]:
        u = g["uncertainty"]
        assert set(u) == {"u", "U", "k", "coverage", "interval", "bias", "method", "trials"} and u["trials"] == 20
        assert u["U"] > 0 and g["decision"] in ("conforming", "not-proven", "nonconforming")
    assert d["monte_carlo"]["method"] == "JCGM 101:2008 Monte Carlo" and d["monte_carlo"]["seed"] == 4
    assert set(d["transform_uncertainty"]) == {"beta", "dx", "dy", "dz"}  # the free motions of casting_ok.toml
    assert d["guard_band"]["fraction_of_U"] == 1.0
    # three faces sit on their limit at T*, but dz and dx leave room: proven at the guard-banded transform
    assert d["zero_margin"] and d["decision"] == "conforming" and d["guard_band"]["guarded"]["status"] == "conforming"
    assert _json(gk(*args, "--threads", 2)) == d
    assert _json(gk(*args, "--threads", 1, "--chunk-points", 997)) == d  # streamed: the same active set and trials


def test_short_casting_is_proven_nonconforming():
    d = _json(gk(*SHORT, "--uncertainty", 20, "--noise", 0.005, "--json"))
    assert d["status"] == "nonconforming" and d["decision"] == "nonconforming"
    short = [g for g in d["gages"] if g["slack"] > 0]
    assert short and all(g["decision"] == "nonconforming" for g in short)
    assert d["guard_band"]["relaxed"]["status"] == "nonconforming"
    text = gk(*SHORT, "--uncertainty", 20, "--noise", 0.005)
    assert text.returncode == 0 and "decision: nonconforming" in text.stdout and "U (95 %)" in text.stdout


def test_a_decision_rule_alone_states_the_rule():
    d = json.loads(gk(*OK, "--decision-rule", "simple", "--json").stdout)
    assert d["decision"] == "conforming" and d["decision_rule"]["name"] == "simple"
    assert all(g["decision"] == "conforming" and "uncertainty" not in g for g in d["gages"])
    plain = json.loads(gk(*OK, "--json").stdout)
    assert "decision" not in plain and all("decision" not in g for g in plain["gages"])
    assert np.allclose([g["allowance_after"] for g in plain["gages"]], [g["allowance_after"] for g in d["gages"]])


@pytest.mark.parametrize("extra, words", [
    (("--uncertainty", 5, "--noise", 0.01), "at least 10"),
    (("--uncertainty", "many", "--noise", 0.01), "number of trials"),
    (("--uncertainty", 20, "--noise", "loud"), "--noise"),
    (("--uncertainty", 20), "--noise SIGMA|auto or --measurement"),
    (("--noise", 0.01), "--uncertainty"),
    (("--decision-rule", "strict"), "decision rule"),
    (("--uncertainty", 20, "--noise", 0.01, "--decision-rule", "guard-band=-1"), "FRACTION"),
])
def test_bad_options_are_one_line(extra, words):
    p = gk(*OK, *extra)
    assert p.returncode == 2 and p.stdout == "" and p.stderr.startswith("gagekit: error: ")
    assert len(p.stderr.strip().splitlines()) == 1 and words in p.stderr, p.stderr
