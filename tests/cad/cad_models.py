"""Analytic test models: convex polytopes as meshes and files, STEP solids made with OCP."""

from __future__ import annotations

import numpy as np


def box(h=(2.0, 1.5, 1.0)):
    """Box [-h, h] as (vertices, triangles), wound outwards."""
    v = np.array([[(-1) ** (1 - (i & 1)) * h[0], (-1) ** (1 - ((i >> 1) & 1)) * h[1], (-1) ** (1 - ((i >> 2) & 1)) * h[2]]
                  for i in range(8)], dtype=float)
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    t = []
    for q in quads:
        t += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    return v, np.array(t, dtype=np.int64)


def octahedron(r=3.0):
    v = np.array([[r, 0, 0], [-r, 0, 0], [0, r, 0], [0, -r, 0], [0, 0, r], [0, 0, -r]], dtype=float)
    t = []
    for sx, a in ((1, 0), (-1, 1)):
        for sy, b in ((1, 2), (-1, 3)):
            for sz, c in ((1, 4), (-1, 5)):
                tri = [a, b, c]
                if sx * sy * sz < 0:
                    tri = [a, c, b]
                t.append(tri)
    return v, np.array(t, dtype=np.int64)


def write_stl(path, v, t, binary=True):
    corners = v[t]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    if binary:
        rec = np.zeros(len(t), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
        rec["n"], rec["v"] = n, corners
        with open(path, "wb") as fh:
            fh.write(b"\0" * 80 + np.uint32(len(t)).tobytes())
            rec.tofile(fh)
    else:
        lines = ["solid test"]
        for nn, c in zip(n, corners):
            lines.append(f"facet normal {nn[0]:.17g} {nn[1]:.17g} {nn[2]:.17g}\n outer loop")
            lines += [f"  vertex {p[0]:.17g} {p[1]:.17g} {p[2]:.17g}" for p in c]
            lines.append(" endloop\nendfacet")
        lines.append("endsolid test")
        with open(path, "w") as fh:
            fh.write("\n".join(lines) + "\n")


def step_solid(path, kind):
    """A STEP box 40 x 30 x 20 at the origin, or a cylinder r = 10, h = 30 on the z axis."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    shape = BRepPrimAPI_MakeBox(40.0, 30.0, 20.0).Shape() if kind == "box" else BRepPrimAPI_MakeCylinder(10.0, 30.0).Shape()
    w = STEPControl_Writer()
    w.Transfer(shape, STEPControl_AsIs)
    w.Write(str(path))
