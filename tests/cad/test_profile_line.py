"""The profile of a line (ISO 1101 Sec. 18.6) on a surface feature located by CAD faces:
sections across a direction, in each the deviations from the CAD surface, the zone per
section (fixed by the datums, or floating in the section's plane), the worst section the
callout's value. Analytic: a box whose top carries parabolas of known height per section."""

from __future__ import annotations

import numpy as np
import pytest

from gagekit.errors import ConfigError
from gagekit.inspect import inspect as inspect_scan, load_part_spec

from cad_models import box

H = (50.0, 20.0, 10.0)
YS = (-16.0, -8.0, 0.0, 8.0, 16.0)
CURV = (0.002, 0.004, 0.006, 0.008, 0.010)  # mm: the parabola's rise over each section
SLOPE = 0.001                               # mm over the half length: a tilt


def write_obj(path):
    """The box with its top face (z = +10) as the group "top", the bottom as "bottom"."""
    v, t = box(H)
    lines = [f"v {a!r} {b!r} {c!r}" for a, b, c in v.tolist()]
    z = v[t][:, :, 2]
    for name, sel in (("top", (z > 0).all(axis=1)), ("bottom", (z < 0).all(axis=1)),
                      ("sides", ~((z > 0).all(axis=1) | (z < 0).all(axis=1)))):
        lines.append(f"g {name}")
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in t[sel].tolist()]
    path.write_text("\n".join(lines) + "\n")


def scan():
    """Per section y_k: the top at z = 10 + c_k xi^2 + s xi (xi = x / 40), and the flat bottom."""
    x = np.linspace(-40.0, 40.0, 81)
    xi = x / 40.0
    top = [np.column_stack([x, np.full_like(x, y), H[2] + c * xi ** 2 + SLOPE * xi]) for y, c in zip(YS, CURV)]
    g = np.linspace(-40.0, 40.0, 9)
    bottom = np.array([[a, b, -H[2]] for a in g for b in (-15.0, 0.0, 15.0)])
    return np.vstack(top + [bottom])


def drawing(path, tolerance: str) -> None:
    path.write_text(f"""[part]
name = "block"
cad = "block.obj"

[[feature]]
name = "A"
shape = "plane"
faces = ["bottom"]
outward = [0, 0, -1]
band = 1.0

[[feature]]
name = "top"
shape = "surface"
faces = ["top"]
band = 1.0

[datums]
A = "A"

[[tolerance]]
feature = "top"
characteristic = "profile-line"
{tolerance}
""")


@pytest.fixture()
def folder(tmp_path):
    write_obj(tmp_path / "block.obj")
    return tmp_path


def measure(folder, tolerance: str):
    drawing(folder / "part.toml", tolerance)
    result = inspect_scan(scan(), load_part_spec(folder / "part.toml"))
    (t,) = result.tolerances
    return t


def sampled(c: float) -> np.ndarray:
    xi = np.linspace(-1.0, 1.0, 81)
    return c * xi ** 2 + SLOPE * xi


def test_floating_sections_each_take_their_own_minimax_in_their_plane(folder):
    """No datums: each section's zone floats (shift and tilt in the x-z plane): the tilt is
    taken out, the parabola c xi^2 on [-1, 1] needs a zone of width c (Chebyshev: the line
    c/2 leaves +-c/2); the worst section is the largest c."""
    t = measure(folder, 'tolerance = 0.02\ndirection = [0, 1, 0]\nsections = 5')
    rows = t.details["sections"]
    assert len(rows) == 5 and [r["n"] for r in rows] == [81] * 5
    assert [r["position"] for r in rows] == pytest.approx(YS)
    assert [r["width"] for r in rows] == pytest.approx(CURV, abs=2e-7)
    assert t.measured == pytest.approx(max(CURV), abs=2e-7) and t.details["worst_section"] == 4
    for r in rows:
        c = r["certificate"]
        assert c["max_abs_deviation"] == pytest.approx(c["lp_optimum"], abs=1e-7)
    assert t.measured <= t.tolerance and "floats in its plane" in t.element


def test_datums_fix_every_section_zone_symmetric_about_the_cad(folder):
    """Datum A (the flat bottom, on the CAD's): nothing floats that changes a distance to
    the top, each section's width is 2 max |c xi^2 + s xi| over its points."""
    t = measure(folder, 'tolerance = 0.05\ndatums = ["A"]\ndirection = [0, 1, 0]\nsections = 5')
    want = [2.0 * np.abs(sampled(c)).max() for c in CURV]
    assert [r["width"] for r in t.details["sections"]] == pytest.approx(want, abs=1e-9)
    assert t.measured == pytest.approx(2.0 * (max(CURV) + SLOPE), abs=1e-9)
    # an offset zone (ISO 1101 UZ): 2 max |d - offset|
    t = measure(folder, 'tolerance = 0.05\ndatums = ["A"]\ndirection = [0, 1, 0]\nsections = 5\noffset = 0.004')
    want = [2.0 * np.abs(sampled(c) - 0.004).max() for c in CURV]
    assert [r["width"] for r in t.details["sections"]] == pytest.approx(want, abs=1e-9)


def test_spacing_and_a_turned_direction(folder):
    """Sections 6.4 mm apart over the 32 mm span: the same five; a direction of -y gives
    the same sections (their order reversed along the direction)."""
    t = measure(folder, 'tolerance = 0.05\ndirection = [0, 1, 0]\nspacing = 6.4')
    assert len(t.details["sections"]) == 5 and t.measured == pytest.approx(max(CURV), abs=2e-7)
    t = measure(folder, 'tolerance = 0.05\ndirection = [0, -2, 0]\nsections = 5')
    assert [r["width"] for r in t.details["sections"]] == pytest.approx(CURV[::-1], abs=2e-7)
    assert t.details["direction"] == pytest.approx([0, -1, 0])


@pytest.mark.parametrize("tolerance, words", [
    ("tolerance = 0.1", "'direction' is missing"),
    ("tolerance = 0.1\ndirection = [0, 0, 0]", "direction"),
    ("tolerance = 0.1\ndirection = [0, 1, 0]\nsections = 5\nspacing = 2.0", "not both"),
    ("tolerance = 0.1\ndirection = [0, 1, 0]\nspacing = -1.0", "spacing"),
])
def test_bad_line_profile_callouts_name_the_key(folder, tolerance, words):
    drawing(folder / "part.toml", tolerance)
    with pytest.raises(ConfigError, match=words):
        load_part_spec(folder / "part.toml")


def test_direction_on_another_characteristic_and_profile_line_on_a_plane_are_refused(folder):
    drawing(folder / "part.toml", "tolerance = 0.1\ndirection = [0, 1, 0]")
    text = (folder / "part.toml").read_text().replace('characteristic = "profile-line"', 'characteristic = "profile"')
    (folder / "part.toml").write_text(text)
    with pytest.raises(ConfigError, match="applies to profile-line"):
        load_part_spec(folder / "part.toml")
    text = text.replace('feature = "top"\ncharacteristic = "profile"', 'feature = "A"\ncharacteristic = "profile-line"')
    (folder / "part.toml").write_text(text)
    with pytest.raises(ConfigError, match="does not apply to a plane"):
        load_part_spec(folder / "part.toml")


def test_sections_across_the_lines_and_empty_ones_skipped(folder):
    """Sections across x: 81 slices each hold one point of every line (5 points); asked for
    200, the slices that fall between the points' x are empty and skipped, not zero."""
    t = measure(folder, 'tolerance = 0.05\ndatums = ["A"]\ndirection = [1, 0, 0]\nsections = 81')
    assert len(t.details["sections"]) == 81 and all(r["n"] == 5 for r in t.details["sections"])
    t200 = measure(folder, 'tolerance = 0.05\ndatums = ["A"]\ndirection = [1, 0, 0]\nsections = 200')
    assert len(t200.details["sections"]) == 81 and t200.measured == pytest.approx(t.measured, abs=1e-12)
    # the ends (xi = +-1) carry the largest deviation, c_max + s
    assert t.measured == pytest.approx(2.0 * (max(CURV) + SLOPE), abs=1e-9)
