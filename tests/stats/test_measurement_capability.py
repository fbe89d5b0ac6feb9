"""Issue 26 §3: capability with the measurement's variance (ISO 22514-7: observed variance =
process variance + measurement variance), by hand, on a simulated process with known
components, and through `gagekit stats --measurement-uncertainty` on a results database."""

import json
import math
import subprocess
import sys
from datetime import datetime, timedelta, timezone

import numpy as np
import pytest

from gagekit.errors import InvalidInputError
from gagekit.stats import capability


def gk(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True)


def test_split_by_hand():
    # x = 10 12 11 13 12: sigma_within = 1.5 / 1.128, s = sqrt(1.3); u = 0.5
    x = [10, 12, 11, 13, 12]
    c = capability(x, lower=8, upper=16, measurement_u=0.5)
    m = c.measurement
    sigma = 1.5 / 1.128
    sp, sdp = math.sqrt(sigma**2 - 0.25), math.sqrt(1.3 - 0.25)
    assert m["observed"]["cp"] == c.cp == pytest.approx(8 / (6 * sigma))
    assert m["process"]["sigma_within"] == pytest.approx(sp) and m["process"]["sd"] == pytest.approx(sdp)
    assert m["process"]["cp"] == pytest.approx(8 / (6 * sp)) and m["process"]["cpk"] == pytest.approx(3.6 / (3 * sp))
    assert m["process"]["pp"] == pytest.approx(8 / (6 * sdp)) and m["process"]["ppk"] == pytest.approx(3.6 / (3 * sdp))
    assert m["q_mp_pct"] == pytest.approx(100 * 2 * 2 * 0.5 / 8)  # 2U/T with U = 2u: 25 %
    assert m["share_of_observed_variance"] == pytest.approx(0.25 / 1.3)
    assert "ISO 22514-7" in m["model"] and c.to_dict()["measurement"] == m
    # removing the measurement variance only raises the indices
    assert all(m["process"][k] > m["observed"][k] for k in ("cp", "cpk", "pp", "ppk"))
    # u = 0: the process is what was observed; no u: no split at all
    z = capability(x, lower=8, upper=16, measurement_u=0.0).measurement
    assert z["process"] == z["observed"]
    assert capability(x, lower=8, upper=16).measurement is None and "measurement" not in capability(x, 8, 16).to_dict()


def test_a_measurement_as_noisy_as_the_process_gives_no_process_index():
    x = [10, 12, 11, 13, 12]
    m = capability(x, lower=8, upper=16, measurement_u=1.2).measurement  # sigma_within 1.33 > u > s = 1.14
    assert "cp" in m["process"] and "pp" not in m["process"] and "sd" not in m["process"]
    assert any("does not resolve the process" in n for n in m["notes"])
    m = capability(x, lower=8, upper=16, measurement_u=2.0).measurement
    assert m["process"] == {} and m["share_of_observed_variance"] == 1.0
    assert any("Q_MP" in n and "30 %" in n for n in m["notes"])  # 2U/T = 100 %
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(InvalidInputError):
            capability(x, lower=8, upper=16, measurement_u=bad)


def test_simulated_process_with_known_components():
    """Process sd 0.010, measurement sd 0.006 (independent): the observed Pp is that of
    sqrt(0.010^2 + 0.006^2); the split gives back the process's Pp = T / (6 * 0.010)."""
    rng = np.random.default_rng(7)
    n = 40_000
    x = 5.0 + rng.normal(0, 0.010, n) + rng.normal(0, 0.006, n)
    c = capability(x, lower=4.94, upper=5.06, measurement_u=0.006)
    m = c.measurement
    assert c.pp == pytest.approx(0.12 / (6 * math.hypot(0.010, 0.006)), rel=0.01)
    assert m["process"]["pp"] == pytest.approx(0.12 / (6 * 0.010), rel=0.01)
    assert m["process"]["cp"] == pytest.approx(0.12 / (6 * 0.010), rel=0.02)  # MRbar / d2 is noisier
    assert m["q_mp_pct"] == pytest.approx(20.0)


@pytest.fixture()
def database(tmp_path):
    """30 inspections of a flatness (tolerance 0.05) stored in a results database."""
    from gagekit._util import load_toml
    from gagekit.batch.tasks import Outcome
    from gagekit.store import ResultStore

    part_toml = tmp_path / "part.toml"
    part_toml.write_text('name = "plate"\n[[tolerance]]\ncharacteristic = "flatness"\n')
    url = f"sqlite:///{tmp_path / 'r.db'}"
    store = ResultStore(url)
    sid = store.ensure_spec("inspect", "a" * 64, {"part": load_toml(part_toml)})
    values = 0.02 + np.random.default_rng(3).normal(0, 0.004, 30)
    t0 = datetime(2026, 3, 2, tzinfo=timezone.utc)
    for i, v in enumerate(values):
        res = {"tolerances": [{"characteristic": "flatness", "feature": "top", "measured": float(v),
                               "tolerance": 0.05, "pass": True}]}
        t = t0 + timedelta(hours=i)
        store.record("inspect", sid, f"{i:04d}".ljust(64, "0"), 10, t, [f"/scans/p{i:02d}.ply"], Outcome("ok", res, None, t, t, 0.1))
    store.close()
    return url, part_toml, values


def test_cli_stats_measurement_uncertainty(database):
    url, part_toml, values = database
    r = gk("stats", "--db", url, "--spec", part_toml, "--measurement-uncertainty", "0.002", "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["measurement"]["u"] == 0.002 and "ISO 22514-7" in s["measurement"]["model"]
    (c,) = s["specs"][0]["characteristics"]
    want = capability(values, upper=0.05, resolution=1e-9, measurement_u=0.002)
    m = c["measurement"]
    assert c["ppk"] == pytest.approx(want.ppk, rel=1e-12) and m["observed"]["ppk"] == c["ppk"]
    sd_p = math.sqrt(np.std(values, ddof=1) ** 2 - 0.002**2)
    assert m["process"]["ppk"] == pytest.approx((0.05 - np.mean(values)) / (3 * sd_p), rel=1e-12)
    text = gk("stats", "--db", url, "--spec", part_toml, "--measurement-uncertainty", "0.002")
    assert text.returncode == 0 and "measurement: tolerance: flatness of top: u = 0.002" in text.stdout
    assert "process" in text.stdout
    plain = json.loads(gk("stats", "--db", url, "--json").stdout)
    assert "measurement" not in plain and "measurement" not in plain["specs"][0]["characteristics"][0]
    for bad in ("-0.001", "nan", "inf"):
        p = gk("stats", "--db", url, "--measurement-uncertainty", bad)
        assert p.returncode == 2 and p.stdout == "" and p.stderr.startswith("gagekit: error: ")
        assert len(p.stderr.strip().splitlines()) == 1 and "measurement-uncertainty" in p.stderr
