"""Generate the bundled inspection sample: a machined bracket with known deviations.

    python make_bracket.py            # writes bracket.ply and bracket.toml beside this file

The part (mm): a block 120 x 80 x 40 with a 45-degree chamfer along its top right edge,
a bore (hole, radius 10) at (30, 40), a stepped boss (radius 12, then 8) at (70, 40)
topped by a ball (radius 8), a pin hole (radius 3, one scanned circle) at (30, 15) and a
scanned line on the back face. Every surface is sampled exactly (no noise) on a grid
that includes its edges, with deviations whose inspection values follow analytically
from the construction (``EXPECTED``):

The scanner stops 1 mm short of every edge of the block's faces (the bottom face A around
the bore's opening, the front and back faces below the chamfer), so no point lies in the air.

- A (bottom, z = 0): perfect -> flatness 0.
- B (front, z in [1, 39]): leans by S_B (y = S_B (z - 1)) -> perpendicularity to A =
  38 S_B; its datum (perpendicular to A, on the air side) is y = 0.
- C (left end, y in [1, 79]): twisted about z (x = S_C (y - 1)) -> perpendicularity to A
  alone = 0 (the zone turns about A's normal), to A and B = 78 S_C; its datum is x = 0.
- top: z = 40 + OFF + T (x - 50), x in [1, 99] -> parallelism to A = 98 T, flatness 0,
  profile (basic z = 40, datum A) = 2 (OFF + 49 T).
- chamfer: at 45 deg + DELTA, scanned over the slant s in [1, L - 1] -> angularity to A
  (45 deg) = (L - 2) sin(DELTA).
- bore: axis through (30 + DX, 40 + DY, 20), tilted by ALPHA about y, 30 mm long, three
  lobes of amplitude A3 -> position (A|B|C) = 2 sqrt((DX + 15 sin ALPHA)^2 + DY^2),
  perpendicularity to A = 30 sin ALPHA, cylindricity = roundness = 2 A3.
- boss: lower step (datum D, shaft) on the axis (70, 40); upper step offset by E ->
  coaxiality = circular run-out = total run-out = 2 E.
- ball: centre offset (BX, 0, BZ) from (70, 40, 75), perfect -> position S-diameter =
  2 sqrt(BX^2 + BZ^2), sphericity 0.
- rib line on the back face, x in [10, 110]: bowed by B_RIB (half sine) -> straightness = B_RIB.
- pin circle: four lobes of amplitude A4, centre offset PX -> roundness = 2 A4,
  position = 2 PX.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

S_B, S_C, T, OFF, DELTA = 1e-3, 5e-4, 6e-4, 0.01, 1e-3
DX, DY, ALPHA, A3 = 0.02, -0.01, 5e-4, 0.004
E, BX, BZ, B_RIB, A4, PX = 0.015, 0.015, 0.01, 0.012, 0.003, 0.01
L_CHAMFER = 20.0 * math.sqrt(2.0)

EXPECTED = {
    "flatness of A": 0.0,
    "perpendicularity of B": 38 * S_B,
    "perpendicularity of C to A|B": 78 * S_C,
    "perpendicularity of C to A": 0.0,
    "parallelism of top": 98 * T,
    "flatness of top": 0.0,
    "profile of top": 2 * (OFF + 49 * T),
    "angularity of chamfer": (L_CHAMFER - 2) * math.sin(DELTA),
    "position of bore": 2 * math.hypot(DX + 15 * math.sin(ALPHA), DY),
    "perpendicularity of bore": 30 * math.sin(ALPHA),
    "cylindricity of bore": 2 * A3,
    "roundness of bore": 2 * A3,
    "coaxiality of boss-top": 2 * E,
    "circular-runout of boss-top": 2 * E,
    "total-runout of boss-top": 2 * E,
    "position of ball": 2 * math.hypot(BX, BZ),
    "sphericity of ball": 0.0,
    "straightness of rib": B_RIB,
    "roundness of pin": 2 * A4,
    "position of pin": 2 * PX,
}

#: bracket_sizes.toml's callouts beyond bracket.toml's (by name): sizes, distances, angles,
#: material conditions. The bore's three lobes keep every two-point size 2 R = 20 while its
#: maximum inscribed cylinder is 2 (R - A3); the pin's four lobes give two-point sizes
#: 6 +- 2 A4 and a maximum inscribed circle of 2 (3 - A4).
BORE_GX = 2 * (10 - A3)
PIN_GX = 2 * (3 - A4)
EXPECTED_SIZES = {
    "size of bore": 20.0,                       # LP (every two-point size 20), envelope GX = BORE_GX
    "size of boss": 24.0,                       # 24 js6, LP of a perfect cylinder
    "GN of boss-top": 16.0,
    "GG of ball": 16.0,
    "size of pin": 6 + 2 * A4,                  # LP: the local size nearest a limit, the largest
    "distance of ball from A": 75 + BZ,         # the ball's centre above A
    "distance of bore from boss": math.hypot(40 - DX, DY),  # the bore's mid-point from the boss axis
    "angle of chamfer": 45 + math.degrees(DELTA),
    "angle of bore to A": 90 - math.degrees(ALPHA),
    "position of bore at MMC": 2 * math.hypot(DX + 15 * math.sin(ALPHA), DY),
    "position of pin 0 at MMC": 2 * PX,
    # A|D(M): the turn about D is free, so only the pin's distance from D's axis is located;
    # the boss (perfect, 24.000) may shift on its 24 js6 MMB gauge (24.0065) by 0.00325
    "position of pin to A|D(M)": 2 * (abs(math.hypot(40 - PX, 25) - math.hypot(40, 25)) - 0.0065 / 2),
}
#: the bonuses: the bore's GX over its MMC size 19.988, the pin's GX over 5.97
BONUS = {"position of bore at MMC": BORE_GX - 19.988, "position of pin 0 at MMC": PIN_GX - 5.97}


def _grid(a0, a1, b0, b1, step):
    na = max(2, int(round((a1 - a0) / step)) + 1)
    nb = max(2, int(round((b1 - b0) / step)) + 1)
    a, b = np.meshgrid(np.linspace(a0, a1, na), np.linspace(b0, b1, nb), indexing="ij")
    return a.ravel(), b.ravel()


def _ring(n_theta):
    return np.linspace(0.0, 2 * math.pi, n_theta, endpoint=False)


def make_bracket(density: float = 1.0) -> np.ndarray:
    """The bracket's points (n, 3); ``density`` scales the number of points (1: ~40 000)."""
    h = 2.0 / math.sqrt(density)  # grid step on the faces (mm)
    nt = max(24, int(round(180 * math.sqrt(density))) // 12 * 12)  # points per turn (a multiple of 12)
    parts = []
    a = math.pi / 4 + DELTA

    def below_chamfer(x, z):  # the front and back faces end at the chamfer (1 mm short of it)
        return z <= 40 - np.maximum(x - 100, 0) * math.tan(a) - 1

    # A: bottom, perfect, without the through bore's opening
    x, y = _grid(1, 119, 1, 79, h)
    keep = np.hypot(x - 30, y - 40) > 10.5
    parts.append(np.column_stack([x[keep], y[keep], 0 * x[keep]]))
    # B: front, leaning y = S_B (z - 1)
    x, z = _grid(1, 119, 1, 39, h)
    keep = below_chamfer(x, z)
    x, z = x[keep], z[keep]
    parts.append(np.column_stack([x, S_B * (z - 1), z]))
    # C: left end, twisted x = S_C (y - 1)
    y, z = _grid(1, 79, 1, 39, h)
    parts.append(np.column_stack([S_C * (y - 1), y, z]))
    # top: tilted plane, without the bore, the boss and the pin hole
    x, y = _grid(1, 99, 1, 79, h / 2)
    keep = (np.hypot(x - 30, y - 40) > 10.5) & (np.hypot(x - 70, y - 40) > 12.5) & (np.hypot(x - 30, y - 15) > 3.5)
    x, y = x[keep], y[keep]
    parts.append(np.column_stack([x, y, 40 + OFF + T * (x - 50)]))
    # chamfer from (100, y, 40) down at 45 deg + DELTA, slant length L
    s, y = _grid(1, L_CHAMFER - 1, 1, 79, h)
    parts.append(np.column_stack([100 + s * math.cos(a), y, 40 - s * math.sin(a)]))
    # right face below the chamfer, back face (without the rib line's band)
    y, z = _grid(1, 79, 1, 40 - L_CHAMFER * math.sin(a) - 1, h)
    parts.append(np.column_stack([0 * y + 120, y, z]))
    x, z = _grid(1, 119, 1, 39, h)
    band = (np.abs(z - 20) > 1.0) & below_chamfer(x, z)
    parts.append(np.column_stack([x[band], 0 * x[band] + 80, z[band]]))
    # rib: a bowed line on the back face at z = 20
    x = np.linspace(10, 110, 2 * int(round(50 / h * 2)) + 1)  # odd: the crest x = 60 is sampled
    parts.append(np.column_stack([x, 80 + B_RIB * np.sin(math.pi * (x - 10) / 100), 0 * x + 20]))
    # bore: tilted, three lobes; axis parameter t in [-15, 15] about (30 + DX, 40 + DY, 20)
    th = _ring(nt)
    t = np.linspace(-15, 15, int(round(30 / h * 2)) + 1)
    T_, TH = np.meshgrid(t, th, indexing="ij")
    r = 10 + A3 * np.cos(3 * TH)
    d = np.array([math.sin(ALPHA), 0.0, math.cos(ALPHA)])
    u = np.array([math.cos(ALPHA), 0.0, -math.sin(ALPHA)])
    v = np.array([0.0, 1.0, 0.0])
    c = np.array([30 + DX, 40 + DY, 20.0])
    bore = c + T_.ravel()[:, None] * d + (r * np.cos(TH)).ravel()[:, None] * u + (r * np.sin(TH)).ravel()[:, None] * v
    parts.append(bore)
    # boss: lower step r = 12 on (70, 40), z in [42, 58]; upper step r = 8 on (70 + E, 40), z in [61, 74]
    for (cx, r0, z0, z1) in ((70.0, 12.0, 42.0, 58.0), (70.0 + E, 8.0, 61.0, 74.0)):
        zz = np.linspace(z0, z1, int(round((z1 - z0) / h * 2)) + 1)
        Z, TH = np.meshgrid(zz, th, indexing="ij")
        parts.append(np.column_stack([(cx + r0 * np.cos(TH)).ravel(), (40 + r0 * np.sin(TH)).ravel(), Z.ravel()]))
    # ball: the upper hemisphere of radius 8 about (70 + BX, 40, 75 + BZ)
    n_lat = max(6, nt // 8)
    lat = np.linspace(0, math.pi / 2, n_lat + 1)[1:]
    LAT, TH = np.meshgrid(lat, th, indexing="ij")
    bc = np.array([70 + BX, 40.0, 75 + BZ])
    parts.append(bc + 8 * np.column_stack([(np.cos(LAT) * np.cos(TH)).ravel(), (np.cos(LAT) * np.sin(TH)).ravel(), np.sin(LAT).ravel()]))
    # pin hole: one scanned circle at z = 38, four lobes, centre offset PX
    th2 = _ring(2 * nt)
    r = 3 + A4 * np.cos(4 * th2)
    parts.append(np.column_stack([30 + PX + r * np.cos(th2), 15 + r * np.sin(th2), 0 * th2 + 38]))
    return np.ascontiguousarray(np.concatenate(parts))


#: Names of the nominal bracket's STEP faces, by a point inside each face (make_bracket_step).
FACE_NAMES = {
    "A": (60.0, 40.0, 0.0), "B": (60.0, 0.0, 20.0), "C": (0.0, 40.0, 20.0), "top": (50.0, 60.0, 40.0),
    "chamfer": (110.0, 40.0, 30.0), "right": (120.0, 40.0, 10.0), "back": (60.0, 80.0, 20.0),
    "bore": (20.0, 40.0, 20.0), "boss": (58.0, 40.0, 50.0), "boss-shoulder": (65.0, 50.0, 60.0),
    "boss-top": (62.0, 40.0, 67.0), "ball": (70.0, 40.0, 83.0), "pin": (27.0, 15.0, 35.0), "pin-bottom": (30.0, 15.0, 30.0),
}


def make_bracket_step(path) -> None:  # pragma: no cover - regenerates the bundled STEP model (needs gagekit[cad])
    """The nominal bracket as a STEP solid (OpenCASCADE): the block with its chamfer, the
    through bore, the blind pin hole (10 deep), the stepped boss and the ball, every face
    named (FACE_NAMES) so that a drawing can call it by name or by its STEP id."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakePrism, BRepPrimAPI_MakeSphere
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.ShapeUpgrade import ShapeUpgrade_UnifySameDomain
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Vec

    poly = BRepBuilderAPI_MakePolygon()
    for x, z in ((0, 0), (120, 0), (120, 20), (100, 40), (0, 40)):
        poly.Add(gp_Pnt(x, 0, z))
    poly.Close()
    block = BRepPrimAPI_MakePrism(BRepBuilderAPI_MakeFace(poly.Wire()).Face(), gp_Vec(0, 80, 0)).Shape()
    up = gp_Dir(0, 0, 1)
    shape = BRepAlgoAPI_Cut(block, BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(30, 40, -1), up), 10.0, 42.0).Shape()).Shape()
    shape = BRepAlgoAPI_Cut(shape, BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(30, 15, 30), up), 3.0, 11.0).Shape()).Shape()
    shape = BRepAlgoAPI_Fuse(shape, BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(70, 40, 39), up), 12.0, 21.0).Shape()).Shape()
    shape = BRepAlgoAPI_Fuse(shape, BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(70, 40, 59), up), 8.0, 16.0).Shape()).Shape()
    shape = BRepAlgoAPI_Fuse(shape, BRepPrimAPI_MakeSphere(gp_Pnt(70, 40, 75), 8.0).Shape()).Shape()
    unify = ShapeUpgrade_UnifySameDomain(shape, True, True, True)
    unify.Build()
    shape = unify.Shape()
    names = []
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        face = ex.Current()
        dists = {n: BRepExtrema_DistShapeShape(face, BRepBuilderAPI_MakeVertex(gp_Pnt(*q)).Vertex()).Value()
                 for n, q in FACE_NAMES.items()}
        name = min(dists, key=dists.get)
        names.append(name if dists[name] < 1e-6 else "")
        ex.Next()
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    writer = STEPControl_Writer()
    writer.Transfer(shape, STEPControl_AsIs)
    tmp = Path(str(path) + ".tmp")
    if writer.Write(str(tmp)) != IFSelect_RetDone:
        raise RuntimeError(f"cannot write {path}")
    # the faces' names: the shell lists the faces in the order OpenCASCADE explored them
    text = tmp.read_text()
    tmp.unlink()
    shell = re.search(r"CLOSED_SHELL\s*\(\s*'[^']*'\s*,\s*\(([^)]*)\)", text)
    ids = [int(x) for x in re.findall(r"#(\d+)", shell.group(1))]
    assert len(ids) == len(names), (len(ids), len(names))
    for fid, name in zip(ids, names):
        text = re.sub(rf"(#{fid}\s*=\s*ADVANCED_FACE\s*\(\s*)''", rf"\g<1>'{name}'", text, count=1)
    text = re.sub(r"FILE_NAME\('[^']*','[^']*'", "FILE_NAME('bracket.step','2026-01-01T00:00:00'", text, count=1)
    Path(path).write_text(text)


def make_bracket_obj(step_path, path) -> None:  # pragma: no cover - regenerates the bundled mesh (needs gagekit[cad])
    """The nominal bracket's tessellation (read_cad's chord tolerance, 0.5 um) as an OBJ
    mesh, one ``g`` group per STEP face named as in the STEP file, so that a bare install
    (no OpenCASCADE) can still compare the scan with the model face by face."""
    from gagekit.cad import read_cad

    m = read_cad(step_path)
    lines = [f"# bracket.obj: tessellation of bracket.step (make_bracket.py), mm, {len(m.faces)} named faces"]
    lines += [f"v {x:.7f} {y:.7f} {z:.7f}" for x, y, z in m.vertices]
    for f in m.faces:
        lines.append(f"g {f.label}")
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in m.triangles[m.triangle_face == f.index]]
    Path(path).write_text("\n".join(lines) + "\n")


def main() -> None:  # pragma: no cover - regenerates the bundled files
    from gagekit.cloud import write_points

    here = Path(__file__).resolve().parent
    write_points(here / "bracket.ply", make_bracket())
    print(f"wrote {here / 'bracket.ply'}")
    try:
        make_bracket_step(here / "bracket.step")
        print(f"wrote {here / 'bracket.step'}")
        make_bracket_obj(here / "bracket.step", here / "bracket.obj")
        print(f"wrote {here / 'bracket.obj'}")
    except ImportError:
        print("bracket.step not written: install gagekit[cad] (OpenCASCADE)")


if __name__ == "__main__":  # pragma: no cover
    main()
