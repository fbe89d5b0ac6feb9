"""Simulated scans of a raw casting on a 3-2-1 fixture, after Secs. 5.3-5.4.

The part (mm, part frame = locator frame): a base block whose top is the
machined flange face (z = 110.4 raw) and whose +y side is the flange side
(y = 147.8 raw); two walls on the flange (x = 10.42..25.48 and 73.62..89.43,
y = 20..60, up to z = 135) and a tower (x = 35..65, y = 100..135, top z = 126.2
raw). The gage planes are those of Table 5.1 (2 mm machining allowance on every
face of the nominal casting, the flange top within its +-1.1 mm band).

What is simulated, honestly and deterministically from the seed:

* raw-casting form error on every casting face: an offset of up to +-0.25 mm,
  a waviness of 0.05-0.2 mm and a tilt of up to 1 mrad, along the face normal;
* scanner noise: Gaussian, ``noise`` mm (default 0.03) along the surface normal;
* the fixture error of Sec. 5.3: the casting sits on spacers (a shift ``shift``
  in x and y and a rotation ``tilt`` about y), while the locators (Z1-Z3 pads,
  Y1-Y2, X1 faces, scanned before the part was loaded) are where they belong;
* the scanner frame: the whole scene is seen in an arbitrary rigid frame.

``casting_ok``: conforming only after the correction T*.
``casting_short``: wall 1 is cast 4.8 mm thin, 2.4 mm off each face (11.01 mm
thick where its gages need 11.81 mm), so it is short of material for its
minimum thickness: outer wall 1 and inner wall 1 conflict, nothing else does.

Run ``python -m gagekit.data.make_castings`` to rewrite the bundled files.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import numpy as np

from .._rotation import rotation_from_vector

# Table 5.1: a x + b y + c z + d >= 0 on the material side
TABLE_5_1 = [
    ("top of flange min", "flange_top", (0, 0, 1, -109.30)),
    ("top of flange max", "flange_top", (0, 0, -1, 111.50)),
    ("side of flange", "flange_side", (0, 1, 0, -145.80)),
    ("outer wall 1", "outer_wall_1", (1, 0, 0, -87.43)),
    ("outer wall 2", "outer_wall_2", (-1, 0, 0, 12.42)),
    ("inner wall 1", "inner_wall_1", (-1, 0, 0, 75.62)),
    ("inner wall 2", "inner_wall_2", (1, 0, 0, -23.48)),
    ("top of tower", "tower_top", (0, 0, 1, -124.20)),
]

# part-frame sampling volumes: (center, size)
PART_REGIONS = {
    "flange_top": ((50.0, 80.0, 110.4), (80.0, 24.0, 12.0)),
    "flange_side": ((50.0, 147.8, 55.0), (80.0, 14.0, 90.0)),
    "outer_wall_1": ((91.75, 40.0, 124.0), (15.5, 30.0, 14.0)),
    "outer_wall_2": ((13.0, 40.0, 124.0), (14.0, 30.0, 14.0)),
    "inner_wall_1": ((76.5, 40.0, 124.0), (14.0, 30.0, 14.0)),
    "inner_wall_2": ((28.5, 40.0, 124.0), (14.0, 30.0, 14.0)),
    "tower_top": ((52.5, 117.5, 126.2), (15.0, 19.0, 10.0)),
}

# locators, part frame: name -> (face center, u, v, normal) and their sampling volumes
LOCATORS = {
    "Z1": ((15.0, 20.0, 0.0), (12, 0, 0), (0, 12, 0), (0, 0, 1)),
    "Z2": ((15.0, 130.0, 0.0), (12, 0, 0), (0, 12, 0), (0, 0, 1)),
    "Z3": ((90.0, 75.0, 0.0), (12, 0, 0), (0, 12, 0), (0, 0, 1)),
    "Y1": ((20.0, 0.0, 8.0), (12, 0, 0), (0, 0, 10), (0, 1, 0)),
    "Y2": ((80.0, 0.0, 8.0), (12, 0, 0), (0, 0, 10), (0, 1, 0)),
    "X1": ((0.0, 75.0, 8.0), (0, 12, 0), (0, 0, 10), (1, 0, 0)),
}
LOCATOR_REGIONS = {
    "Z1": ((15.0, 20.0, 0.0), (14.0, 14.0, 3.0)),
    "Z2": ((15.0, 130.0, 0.0), (14.0, 14.0, 3.0)),
    "Z3": ((90.0, 75.0, 0.0), (14.0, 14.0, 3.0)),
    "Y1": ((20.0, 0.0, 8.0), (14.0, 2.0, 12.0)),
    "Y2": ((80.0, 0.0, 8.0), (14.0, 2.0, 12.0)),
    "X1": ((0.0, 75.0, 8.0), (2.0, 14.0, 12.0)),
}

CASES = {
    # name: (seed, shift (x, y), tilt about y (rad), wall 1 thinning (mm), scanner pose)
    "casting_ok": dict(seed=51, shift=(3.0, 3.0), tilt=math.radians(1.3), thin=0.0,
                       pose=((0.03, -0.02, 0.55), (412.0, -230.0, 65.0))),
    "casting_short": dict(seed=54, shift=(1.5, 2.0), tilt=math.radians(-0.3), thin=4.8,
                          pose=((-0.02, 0.04, -0.9), (-120.0, 310.0, 48.0))),
}


def _faces(thin: float):
    """Casting faces: (name, origin corner, u, v, outward normal, holes [(x0, x1, y0, y1)])."""
    walls = [(10.42, 25.48), (73.62 + thin / 2, 89.43 - thin / 2)]
    tower = (35.0, 65.0, 100.0, 135.0)
    F = []
    holes = [(a, b, 20.0, 60.0) for a, b in walls] + [tower]
    F.append(("flange_top", (0, 0, 110.4), (100, 0, 0), (0, 147.8, 0), (0, 0, 1), holes))
    F.append(("flange_side", (0, 147.8, 0), (100, 0, 0), (0, 0, 110.4), (0, 1, 0), []))
    F.append(("flange_front", (0, 0, 0), (100, 0, 0), (0, 0, 110.4), (0, -1, 0), []))
    F.append(("flange_left", (0, 0, 0), (0, 147.8, 0), (0, 0, 110.4), (-1, 0, 0), []))
    F.append(("flange_right", (100, 0, 0), (0, 147.8, 0), (0, 0, 110.4), (1, 0, 0), []))
    h = 135.0 - 110.4
    # wall 2 at x = 10.42..25.48 (outer face -x, inner face +x), wall 1 at 73.62..89.43
    for k, (a, b), lo, hi in ((2, walls[0], "outer_wall_2", "inner_wall_2"), (1, walls[1], "inner_wall_1", "outer_wall_1")):
        F.append((lo, (a, 20, 110.4), (0, 40, 0), (0, 0, h), (-1, 0, 0), []))
        F.append((hi, (b, 20, 110.4), (0, 40, 0), (0, 0, h), (1, 0, 0), []))
        F.append((f"wall{k}_top", (a, 20, 135.0), (b - a, 0, 0), (0, 40, 0), (0, 0, 1), []))
        F.append((f"wall{k}_front", (a, 20, 110.4), (b - a, 0, 0), (0, 0, h), (0, -1, 0), []))
        F.append((f"wall{k}_back", (a, 60, 110.4), (b - a, 0, 0), (0, 0, h), (0, 1, 0), []))
    x0, x1, y0, y1 = tower
    th = 126.2 - 110.4
    F.append(("tower_top", (x0, y0, 126.2), (x1 - x0, 0, 0), (0, y1 - y0, 0), (0, 0, 1), []))
    F.append(("tower_xmin", (x0, y0, 110.4), (0, y1 - y0, 0), (0, 0, th), (-1, 0, 0), []))
    F.append(("tower_xmax", (x1, y0, 110.4), (0, y1 - y0, 0), (0, 0, th), (1, 0, 0), []))
    F.append(("tower_front", (x0, y0, 110.4), (x1 - x0, 0, 0), (0, 0, th), (0, -1, 0), []))
    F.append(("tower_back", (x0, y1, 110.4), (x1 - x0, 0, 0), (0, 0, th), (0, 1, 0), []))
    return F


def _sample_face(rng, origin, u, v, normal, holes, density, noise, form: bool):
    o, u, v, n = (np.asarray(a, dtype=float) for a in (origin, u, v, normal))
    lu, lv = np.linalg.norm(u), np.linalg.norm(v)
    count = rng.poisson(density * lu * lv)
    s, t = rng.random(count), rng.random(count)
    p = o + np.outer(s, u) + np.outer(t, v)
    keep = np.ones(count, dtype=bool)
    for x0, x1, y0, y1 in holes:
        keep &= ~((p[:, 0] > x0) & (p[:, 0] < x1) & (p[:, 1] > y0) & (p[:, 1] < y1))
    p, s, t = p[keep], s[keep], t[keep]
    dev = np.zeros(len(p))
    if form:
        off = rng.uniform(-0.25, 0.25)
        amp = rng.uniform(0.05, 0.2)
        lam_u, lam_v = rng.uniform(40, 120, size=2)
        ph = rng.uniform(0, 2 * np.pi, size=2)
        tu, tv = rng.uniform(-1e-3, 1e-3, size=2)
        dev = (off + amp * np.sin(2 * np.pi * s * lu / lam_u + ph[0]) * np.sin(2 * np.pi * t * lv / lam_v + ph[1])
               + tu * (s - 0.5) * lu + tv * (t - 0.5) * lv)
    dev = dev + rng.normal(0.0, noise, size=len(p))
    return p + np.outer(dev, n)


def make_casting(name: str = "casting_ok", density: float = 1.5, noise: float = 0.03,
                 seed: Optional[int] = None, shift: Optional[tuple] = None,
                 tilt: Optional[float] = None) -> tuple[np.ndarray, dict]:
    """Simulate the scan of a case of :data:`CASES`; returns (points in the scanner
    frame, the gage-file document as a dict). ``density`` in points per mm^2.

    ``seed``, ``shift`` (x, y mm) and ``tilt`` (rad about y) override the case's: another
    casting of the same pattern sitting differently on its spacers, seen by the same
    scanner over the same fixture (so the case's gage file applies to it)."""
    case = dict(CASES[name])
    if shift is not None:
        case["shift"] = tuple(shift)
    if tilt is not None:
        case["tilt"] = float(tilt)
    rng = np.random.default_rng(case["seed"] if seed is None else seed)
    beta = case["tilt"]
    Rp = rotation_from_vector((0.0, beta, 0.0))
    # lift so the lowest bottom corner stays on the pads
    tp = np.array([case["shift"][0], case["shift"][1], max(0.0, 100.0 * math.sin(beta))])
    parts, labels = [], []
    for label, origin, u, v, normal, holes in _faces(case["thin"]):
        p = _sample_face(rng, origin, u, v, normal, holes, density, noise, form=True)
        parts.append(p @ Rp.T + tp)
        labels += [label] * len(p)
    for label, (c, u, v, n) in LOCATORS.items():
        corner = np.asarray(c) - 0.5 * np.asarray(u) - 0.5 * np.asarray(v)
        parts.append(_sample_face(rng, corner, u, v, n, [], 4.0 * density, noise, form=False))
        labels += [label] * len(parts[-1])
    pts = np.vstack(parts)
    _check_regions(pts, np.array(labels))
    rv, ts = case["pose"]
    Rs = rotation_from_vector(rv)
    pts = pts @ Rs.T + np.asarray(ts)
    perm = rng.permutation(len(pts))
    return np.ascontiguousarray(pts[perm]), gage_document(Rs, np.asarray(ts))


def _check_regions(pts: np.ndarray, labels: np.ndarray) -> None:
    """Every sampling volume catches points of its own face only (part frame)."""
    for name, (c, sz) in {**PART_REGIONS, **LOCATOR_REGIONS}.items():
        inside = np.all(np.abs(pts - np.asarray(c)) <= 0.5 * np.asarray(sz), axis=1)
        found = set(labels[inside])
        if found != {name}:
            raise AssertionError(f"region {name} catches faces {sorted(found)}")


def gage_document(Rs: np.ndarray, ts: np.ndarray) -> dict:
    """The gage file: Table 5.1 gages, part-frame regions, scanner-frame locator regions."""
    from ..cloud.regions import Box
    from ..gage.analysis import box_in_scanner

    C = np.eye(4)
    C[:3, :3], C[:3, 3] = Rs, ts
    regions = []
    for name, (c, s) in LOCATOR_REGIONS.items():
        b = box_in_scanner(Box(c, s, name=name), C)
        regions.append({"name": name, "frame": "scanner", "center": [round(x, 6) for x in b.center],
                        "size": list(b.size), "rotation": [round(x, 9) for x in b.rotation]})
    for name, (c, s) in PART_REGIONS.items():
        regions.append({"name": name, "frame": "part", "center": list(c), "size": list(s)})
    gages = [{"name": n, "region": r, "plane": [float(x) for x in p], "weight": 1.0, "slack_weight": 10.0}
             for n, r, p in TABLE_5_1]
    return {
        "length_unit": "mm",
        "motion": {"free": ["beta", "dx", "dy", "dz"], "max_angle": 0.05, "max_shift": 20.0},
        "alignment": {"primary": ["Z1", "Z2", "Z3"], "secondary": ["Y1", "Y2"], "tertiary": ["X1"]},
        "region": regions,
        "gage": gages,
    }


def _toml_value(v) -> str:
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(float(v)) if isinstance(v, float) else str(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(type(v))


def to_toml(doc: dict, header: str = "") -> str:
    """TOML text of a gage document (scalars, [tables] of scalars, [[arrays of tables]])."""
    lines = [f"# {line}" for line in header.splitlines()]
    for k, v in doc.items():
        if not isinstance(v, (dict, list)) or (isinstance(v, list) and not (v and isinstance(v[0], dict))):
            lines.append(f"{k} = {_toml_value(v)}")
    for k, v in doc.items():
        if isinstance(v, dict):
            lines += ["", f"[{k}]"] + [f"{kk} = {_toml_value(vv)}" for kk, vv in v.items()]
    for k, v in doc.items():
        if isinstance(v, list) and v and isinstance(v[0], dict):
            for t in v:
                lines += ["", f"[[{k}]]"] + [f"{kk} = {_toml_value(vv)}" for kk, vv in t.items()]
    return "\n".join(lines) + "\n"


def write_ply(path: Path, pts: np.ndarray) -> None:
    """Binary little-endian PLY, float32 x y z (scanner resolution is far coarser)."""
    from plyfile import PlyData, PlyElement

    v = np.empty(len(pts), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
    v["x"], v["y"], v["z"] = pts[:, 0], pts[:, 1], pts[:, 2]
    PlyData([PlyElement.describe(v, "vertex")], text=False).write(str(path))


def main(out: Optional[Path] = None) -> None:
    out = Path(out) if out else Path(__file__).parent
    for name in CASES:
        pts, doc = make_casting(name)
        write_ply(out / f"{name}.ply", pts)
        header = (f"{name}: virtual gages of Table 5.1 on a simulated casting scan ({name}.ply),\n"
                  "written by gagekit/data/make_castings.py. Locator regions are in the scanner frame.")
        (out / f"{name}.toml").write_text(to_toml(doc, header))
        print(f"{name}: {len(pts)} points")


if __name__ == "__main__":
    main()
