"""3MF meshes (3D Manufacturing Format core 1.3): a zip with one XML <model>; its unit, its
build items' transforms and component objects; distances against the exact box; bad files
are one FileFormatError naming the file."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

from gagekit.cad import read_cad
from gagekit.errors import FileFormatError

from cad_models import box

NS = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
RELS = ('<?xml version="1.0" encoding="UTF-8"?>\n<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/'
        'relationships"><Relationship Target="/3D/3dmodel.model" Id="rel0" '
        'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>')


def mesh_xml(v, t) -> str:
    vs = "".join(f'<vertex x="{a!r}" y="{b!r}" z="{c!r}"/>' for a, b, c in v.tolist())
    ts = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in t.tolist())
    return f"<mesh><vertices>{vs}</vertices><triangles>{ts}</triangles></mesh>"


def write_3mf(path, model_xml: str, rels: str = RELS, part: str = "3D/3dmodel.model") -> None:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("[Content_Types].xml", '<?xml version="1.0"?><Types xmlns="http://schemas.openxmlformats.org/'
                   'package/2006/content-types"><Default Extension="model" ContentType="application/'
                   'vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>')
        if rels is not None:
            z.writestr("_rels/.rels", rels)
        z.writestr(part, model_xml)


def model_xml(body: str, build: str, unit: str = "millimeter") -> str:
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<model unit="{unit}" xml:lang="en-US" xmlns="{NS}">'
            f"<resources>{body}</resources><build>{build}</build></model>")


def _box_sdf(p, h):
    q = np.abs(p) - np.asarray(h)
    return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)


def test_a_box_in_3mf_reads_with_exact_signed_distances(tmp_path):
    h = (2.0, 1.5, 1.0)
    v, t = box(h)
    path = tmp_path / "box.3mf"
    write_3mf(path, model_xml(f'<object id="1" name="block" type="model">{mesh_xml(v, t)}</object>', '<item objectid="1"/>'))
    model = read_cad(path)
    assert model.format == "3mf" and model.unit == "mm" and model.signed
    assert len(model.triangles) == 12 and [f.name for f in model.faces] == ["block"] and model.faces[0].id == 1
    pts = np.random.default_rng(0).uniform(-4, 4, (5000, 3))
    assert np.abs(model.distances(pts).distance - _box_sdf(pts, h)).max() < 1e-9


def test_the_unit_transforms_and_components_of_a_3mf_model(tmp_path):
    """Two build items: the box in inches, moved by 10 in along x by its item's transform,
    and a component object holding the box turned 90 degrees about z; each item one face."""
    v, t = box((1.0, 1.0, 1.0))
    body = (f'<object id="1" name="cube" type="model">{mesh_xml(v * [2.0, 1.0, 1.0], t)}</object>'
            '<object id="2" name="assembly" type="model"><components>'
            '<component objectid="1" transform="0 1 0 -1 0 0 0 0 1 0 0 5"/></components></object>')
    build = '<item objectid="1" transform="1 0 0 0 1 0 0 0 1 10 0 0"/><item objectid="2"/>'
    path = tmp_path / "parts.3mf"
    write_3mf(path, model_xml(body, build, unit="inch"))
    model = read_cad(path, units="mm")
    assert model.unit == "in" and any("declares its unit" in w for w in model.warnings)
    assert [f.name for f in model.faces] == ["cube", "assembly"]
    first = model.triangle_face == 0
    a = model.vertices[np.unique(model.triangles[first])] / 25.4
    b = model.vertices[np.unique(model.triangles[~first])] / 25.4
    np.testing.assert_allclose(a.min(axis=0), [8, -1, -1]) and np.testing.assert_allclose(a.max(axis=0), [12, 1, 1])
    # [x y z 1] M with M's rows (0 1 0), (-1 0 0), (0 0 1), (0 0 5): (x, y, z) -> (-y, x, z + 5)
    np.testing.assert_allclose(b.min(axis=0), [-1, -2, 4], atol=1e-12)
    np.testing.assert_allclose(b.max(axis=0), [1, 2, 6], atol=1e-12)
    # a point 0.1 in above the turned box's top: 2.54 mm outside
    assert model.distances(np.array([[0.0, 0.0, 6.1 * 25.4]])).distance[0] == pytest.approx(2.54, abs=1e-9)


def test_a_3mf_without_rels_finds_its_model_part(tmp_path):
    v, t = box((1.0, 1.0, 1.0))
    path = tmp_path / "plain.3mf"
    write_3mf(path, model_xml(f'<object id="3">{mesh_xml(v, t)}</object>', '<item objectid="3"/>', unit="micron"),
              rels=None)
    model = read_cad(path)
    assert model.unit == "um" and np.allclose(np.abs(model.vertices), 1e-3) and model.faces[0].name == "object 3"


@pytest.mark.parametrize("case, words", [
    ("notzip", "zip archive"),
    ("nomodel", "no 3D model part"),
    ("badxml", "not valid XML"),
    ("root", "not a 3MF core <model>"),
    ("unit", "unknown 3MF unit"),
    ("nobuild", "no <build><item>"),
    ("object", "not defined"),
    ("index", "does not exist"),
    ("number", "not a number"),
    ("int", "integer v1"),
    ("transform", "12 numbers"),
    ("cycle", "contains itself"),
    ("empty", "no triangles"),
])
def test_bad_3mf_files_are_one_clear_error(tmp_path, case, words):
    v, t = box((1.0, 1.0, 1.0))
    good = f'<object id="1">{mesh_xml(v, t)}</object>'
    path = tmp_path / f"{case}.3mf"
    if case == "notzip":
        path.write_text("solid x\n")
    elif case == "nomodel":
        with zipfile.ZipFile(path, "w") as z:
            z.writestr("readme.txt", "x")
    else:
        xml = {
            "badxml": model_xml(good, '<item objectid="1"/>').replace("</model>", ""),
            "root": f'<?xml version="1.0"?><mesh xmlns="{NS}"/>',
            "unit": model_xml(good, '<item objectid="1"/>', unit="parsec"),
            "nobuild": model_xml(good, ""),
            "object": model_xml(good, '<item objectid="9"/>'),
            "index": model_xml(f'<object id="1">{mesh_xml(v, t + 5)}</object>', '<item objectid="1"/>'),
            "number": model_xml(good.replace('x="-1.0"', 'x="abc"', 1), '<item objectid="1"/>'),
            "int": model_xml(good.replace('v1="0"', 'v1="x"', 1), '<item objectid="1"/>'),
            "transform": model_xml(good, '<item objectid="1" transform="1 0 0"/>'),
            "cycle": model_xml('<object id="1"><components><component objectid="1"/></components></object>',
                               '<item objectid="1"/>'),
            "empty": model_xml('<object id="1"><mesh><vertices/><triangles/></mesh></object>', '<item objectid="1"/>'),
        }[case]
        write_3mf(path, xml)
    with pytest.raises(FileFormatError, match=words) as err:
        read_cad(path)
    assert str(path) in str(err.value)
