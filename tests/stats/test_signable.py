"""Issue 22, section 5: statistics a quality engineer can sign.

Results carry a resolution (values within it of a limit are on the limit; no capability
without variation above it), capability only against specification limits and with a
warning below 25 values, trends from the scan's acquisition time and over a day at least,
dates on chart time axes, zero margin after T* flagged, `stats --tolerance` checked."""

import json
import re
import subprocess
import sys
from datetime import datetime, timedelta, timezone

import numpy as np
import pytest

from gagekit.stats import capability, imr_chart, trend_per_day
from gagekit.stats.collect import characteristic

T0 = datetime(2026, 3, 2, 7, 0, tzinfo=timezone.utc)
# after T* the limiting gage sits at zero stock: the LP returns +-1.4e-14 mm, not 0
ZERO_STOCK = [1.4e-14, -1.4e-14, 0.0, 7e-15, -3e-15, 1.1e-14] * 5


def gk(*args, **kw):
    return subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True,
                          timeout=600, **kw)


def one_error_line(proc, *words):
    assert proc.returncode == 2 and proc.stdout == "", (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gagekit: error: "), proc.stderr
    for w in words:
        assert w in lines[0], proc.stderr


def test_values_within_the_resolution_are_on_the_limit():
    from gagekit.stats.spc import on_limits

    c = capability(ZERO_STOCK, lower=0.0, resolution=1e-9, unit="mm")
    assert c.min_margin == 0.0 and c.minimum == 0.0 and c.maximum == 0.0 and c.on_limit == len(ZERO_STOCK)
    assert c.cpk is None and c.ppk is None and c.sd is None and c.sigma_within is None
    assert any("no variation above the resolution (1e-09 mm)" in n for n in c.notes), c.notes
    d = c.to_dict()
    assert d["resolution"] == 1e-9 and "cpk" not in d and "sd" not in d and d["on_limit"] == 30
    # without a resolution (what stats did): a margin below the limit, a Cpk of rounding noise
    raw = capability(ZERO_STOCK, lower=0.0)
    assert raw.min_margin < 0 and raw.cpk is not None
    # a value beyond the resolution stays where it is
    assert capability([-2e-9, 1.0, 2.0], lower=0.0, resolution=1e-9).min_margin == -2e-9
    assert list(on_limits([5.0 + 1e-10, 4.0, -1e-10], 0.0, 5.0, 1e-9)) == [5.0, 4.0, 0.0]
    # no chart of rounding noise
    assert imr_chart(ZERO_STOCK, 1e-9) is None and imr_chart(ZERO_STOCK) is not None


def test_a_characteristic_on_its_limit_has_no_index_no_chart_and_a_zero_margin_flag():
    times = [T0 + timedelta(days=k) for k in range(len(ZERO_STOCK))]
    c = characteristic("allowance after T*: g1", "mm", ZERO_STOCK, times, [f"s{k}" for k in range(30)], lower=0.0)
    assert c["resolution"] == 1e-9 and c["min_margin"] == 0.0 and c["zero_margin"] is True
    assert "cpk" not in c and "ppk" not in c and "chart" not in c and "trend_per_day" not in c
    assert set(c["series"]["value"]) == {0.0}
    assert any("nothing is left for measurement noise or fixturing" in w for w in c["warnings"])
    assert any("no variation above the resolution" in n for n in c["notes"])


def test_capability_only_against_limits_and_warned_below_25_values():
    from gagekit.stats.spc import MIN_CAPABILITY_VALUES, cpk_lower_bound

    rng = np.random.default_rng(1)
    x = rng.normal(1.0, 0.1, 12)
    c = capability(x, lower=0.0, upper=2.0, resolution=1e-9)
    assert c.cpk is not None and c.ppk is not None
    (w,) = c.warnings
    assert "only 12 values" in w and f"at least {MIN_CAPABILITY_VALUES}" in w and "AIAG" in w
    assert f"{cpk_lower_bound(c.cpk, 12):.2f}" in w
    # Bissell's bound by hand: Cpk 1.33, n 10 -> 1.33 - 1.645 sqrt(1/90 + 1.33^2/18) = 0.786
    assert cpk_lower_bound(1.33, 10) == pytest.approx(0.78595, abs=1e-5)
    assert capability(rng.normal(1.0, 0.1, 25), lower=0.0, upper=2.0).warnings == ()
    free = capability(x)  # no limits: no index and no warning about the count
    assert free.cp is free.cpk is free.pp is free.ppk is None and free.warnings == ()
    assert free.notes == ("no specification limits: no capability indices",)


def test_no_trend_over_less_than_a_day():
    # 8 files written within milliseconds gave 792 mm/day
    ms = [k * 0.001 / 86400 for k in range(8)]
    vals = [0.1 * k for k in range(8)]
    assert trend_per_day(ms, vals) is None
    assert trend_per_day([0.0, 0.5, 0.9], [1.0, 2.0, 3.0]) is None
    assert trend_per_day([0.0, 1.0, 2.0], [1.0, 2.0, 3.0]) == pytest.approx(1.0)
    times = [T0 + timedelta(milliseconds=k) for k in range(8)]
    c = characteristic("form error", "mm", vals, times, [f"s{k}" for k in range(8)], upper=2.0)
    assert "trend_per_day" not in c and any("less than 1 day: no trend" in n for n in c["notes"])


def test_chart_time_axes_show_dates_and_times():
    pytest.importorskip("matplotlib")
    from gagekit.report.spc import trend_figure

    times = [T0 + timedelta(seconds=0.1 * k) for k in range(8)]  # within a second: was "53:23.300000"
    c = characteristic("allowance after T*: g1", "mm", [0.1 * k for k in range(8)], times, ["s"] * 8, lower=0.0)
    fig = trend_figure([c], "allowances", "mm")
    fig.canvas.draw()
    labels = [t.get_text() for t in fig.axes[0].get_xticklabels() if t.get_text()]
    assert len(labels) >= 3 and len(set(labels)) == len(labels), labels
    assert all(re.fullmatch(r"2026-03-0[12] (06:59:59|07:00:00)\.\d{6}", lb) for lb in labels), labels
    times = [T0 + timedelta(hours=7 * k) for k in range(8)]  # two days: dates and minutes
    c = characteristic("allowance after T*: g1", "mm", [0.1 * k for k in range(8)], times, ["s"] * 8, lower=0.0)
    fig = trend_figure([c], "allowances", "mm")
    fig.canvas.draw()
    labels = [t.get_text() for t in fig.axes[0].get_xticklabels() if t.get_text()]
    assert labels and all(re.fullmatch(r"2026-03-0\d \d\d:\d\d", lb) for lb in labels), labels


def test_gage_check_flags_zero_margin_in_json_text_and_report(tmp_path):
    from gagekit.samples import data_path

    ply, toml = data_path("casting_ok.ply"), data_path("casting_ok.toml")
    proc = gk("gage", "check", ply, toml, "--no-groups", "--json")
    assert proc.returncode == 0, proc.stderr
    r = json.loads(proc.stdout)
    assert r["status"] == "conforming" and r["resolution_mm"] == 1e-9
    on_limit = [g["name"] for g in r["gages"] if abs(g["allowance_after"]) <= 1e-9]
    assert on_limit and r["zero_margin"] is True and r["zero_margin_gages"] == on_limit
    text = gk("gage", "check", ply, toml, "--no-groups", "--report", tmp_path / "rep")
    assert text.returncode == 0, text.stderr
    assert "zero margin:" in text.stdout and "nothing is left for measurement noise or fixturing" in text.stdout
    html = (tmp_path / "rep" / "report.html").read_text()
    assert "zero margin:" in html and "nothing is left for measurement noise or fixturing" in html


@pytest.mark.parametrize("tol", ["-1", "0", "nan", "inf", "-0.0"])
def test_stats_refuses_a_non_positive_tolerance(tmp_path, tol):
    db = tmp_path / "r.db"
    db.write_bytes(b"")
    one_error_line(gk("stats", "--db", f"sqlite:///{db}", "--tolerance", tol, "--json"), "--tolerance", "positive")


def test_stats_refuses_a_bad_resolution(tmp_path):
    one_error_line(gk("stats", "--db", f"sqlite:///{tmp_path / 'r.db'}", "--resolution", "-1"), "--resolution")


def write_las(path, pts, day):
    import laspy

    header = laspy.LasHeader(point_format=0, version="1.2")
    header.scales = np.array([1e-5, 1e-5, 1e-5])
    header.offsets = np.zeros(3)
    header.creation_date = day
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts[:, 0], pts[:, 1], pts[:, 2]
    las.write(str(path))


def test_trend_from_the_scans_acquisition_time(tmp_path):
    """Four LAS scans of a plate taken on four days, written within milliseconds of each
    other: the trend is per day of acquisition, not per millisecond of writing."""
    pytest.importorskip("laspy")
    import datetime as dt

    from gagekit.cloud.acquisition import acquisition_time

    rng = np.random.default_rng(3)
    days = [dt.date(2026, 3, 2), dt.date(2026, 3, 3), dt.date(2026, 3, 5), dt.date(2026, 3, 6)]
    folder = tmp_path / "scans"
    folder.mkdir()
    xy = rng.uniform(0, 100, (400, 2))
    for k, day in enumerate(days):
        z = rng.uniform(-1, 1, 400) * 0.01 * (1 + k)  # the plate warps a little more each day
        write_las(folder / f"plate{3 - k}.las", np.c_[xy, z], day)  # names in the reverse order of the days
        assert acquisition_time(folder / f"plate{3 - k}.las") == datetime(day.year, day.month, day.day, tzinfo=timezone.utc)
    url = f"sqlite:///{tmp_path / 'r.db'}"
    b = gk("form", "batch", "plane", folder, "-c", "minimum-zone", "--db", url, "--json", "-w", "1", "--units", "mm")
    assert b.returncode == 0, b.stderr
    flat = {json.loads(ln)["scan"]: json.loads(ln)["result"]["form_error"] for ln in b.stdout.splitlines()[:-1]}
    proc = gk("stats", "--db", url, "--tolerance", "0.5", "--json")
    assert proc.returncode == 0, proc.stderr
    (c,) = json.loads(proc.stdout)["specs"][0]["characteristics"]
    want = [flat[str(folder / f"plate{3 - k}.las")] for k in range(4)]
    assert c["series"]["value"] == want and c["series"]["time_source"] == ["acquired"] * 4
    assert [t[:10] for t in c["series"]["time"]] == [d.isoformat() for d in days]
    t = np.array([0.0, 1.0, 3.0, 4.0])
    assert c["trend_per_day"] == pytest.approx(np.polyfit(t, want, 1)[0], rel=1e-9)
    assert c["upper"] == 0.5 and "cpk" in c and any("only 4 values" in w for w in c["warnings"])


def test_e57_acquisition_time_from_its_header():
    from pathlib import Path

    from gagekit.cloud.acquisition import acquisition_time, gps_to_utc

    pye57 = pytest.importorskip("pye57")
    data = Path(__file__).resolve().parents[1] / "data" / "e57"
    f = data / "bunnyDouble.e57"
    e57 = pye57.E57(str(f))
    root = e57.root
    node = root["creationDateTime"]
    gps = node["dateTimeValue"].value()  # each node kept: pye57's nodes hold weak references
    assert acquisition_time(f) == gps_to_utc(gps)
    # GPS time runs 15 s ahead of UTC in 2011, 18 s since 2017
    assert gps_to_utc(0.0) == datetime(1980, 1, 6, tzinfo=timezone.utc)
    assert gps_to_utc(1_000_000_000.0) == datetime(2011, 9, 14, 1, 46, 25, tzinfo=timezone.utc)
    assert acquisition_time(data / "tiny_spherical.e57") is None  # no time recorded
    assert acquisition_time(data / "bad-crc.e57") is None or isinstance(acquisition_time(data / "bad-crc.e57"), datetime)
