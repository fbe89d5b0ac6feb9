"""`gagekit qif import`: the NIST CTC QIF models become PART.toml files that account for every
characteristic of the model (evaluated, written as a comment, or listed with the reason)."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest

from gagekit.inspect import part_spec_from_dict
from gagekit.qif import part_from_model, read_model

from conftest import CTC01, CTC03, CTC05, FTC09

try:
    import tomllib
except ImportError:  # pragma: no cover - Python < 3.11
    import tomli as tomllib


def _char_ids(path) -> list[str]:
    """Every characteristic nominal id of the file, read with a bare regular expression
    (independent of the reader under test)."""
    import gzip

    text = gzip.decompress(path.read_bytes()).decode()
    return re.findall(r"<(\w+)CharacteristicNominal id=\"(\d+)\"", text)


@pytest.mark.parametrize("path, n", [(CTC01, 14), (CTC03, 22), (CTC05, 16), (FTC09, 53)])
def test_every_characteristic_accounted_for(path, n):
    expected = _char_ids(path)
    assert len(expected) == n
    draft = part_from_model(read_model(path))
    s = draft.summary
    got = [e["qif_id"] for e in s["evaluated"]] + [e["qif_id"] for e in s["unsupported"]]
    assert sorted(got) == sorted(i for _, i in expected)  # each once, none dropped
    assert s["characteristics"] == n
    doc = tomllib.loads(draft.toml)
    spec = part_spec_from_dict(doc, "imported")  # the TOML reads as a drawing
    assert [t.qif_id for t in spec.tolerances] == [s["evaluated"][j]["qif_id"] for j, e in enumerate(s["evaluated"])
                                                   for _ in e["callouts"]]
    assert all(t.qpid == s["qpid"] and t.qpid for t in spec.tolerances)
    for e in s["unsupported"]:  # every one is in the TOML as a comment naming its id
        assert re.search(rf"^# .*CharacteristicNominal {e['qif_id']}\b", draft.toml, re.M), e
        assert e["reason"]
        if e["toml"] == "comment":
            assert re.search(rf'^# qif_id = "{e["qif_id"]}"$', draft.toml, re.M)


def test_ctc01_mapping():
    s = part_from_model(read_model(CTC01)).summary
    ev = {e["qif_id"]: e for e in s["evaluated"]}
    un = {e["qif_id"]: e for e in s["unsupported"]}
    assert s["units"] == {"file": "mm", "mm_per_unit": 1.0}
    assert ev["1470"]["characteristic"] == "flatness" and ev["1470"]["features"] == ["plane-2154"]
    assert ev["1467"]["characteristic"] == "perpendicularity"
    # the seven diameters are sizes (issue 25 keys), evaluated since gagekit reads sizes
    sizes = [e for e in s["unsupported"] + s["evaluated"] if e.get("type") == "Diameter" or
             (e.get("characteristic") == "size" and e in s["evaluated"])]
    assert len(sizes) == 7 and all(e.get("characteristic") == "size" for e in sizes)
    # positions of the centre planes of slots: no such derived feature yet
    assert un["1443"]["toml"] == "listed" and ("OppositeParallelPlanes" in un["1443"]["reason"]
                                               or "position of a slot is not evaluated" in un["1443"]["reason"])
    # profiles of surfaces with no nominal geometry
    assert "OtherNonShape" in un["1457"]["reason"]
    assert s["datums"] == {"A": "plane-2154", "B": "cylinder-2156", "C": "cylinder-2157"}


def test_ctc05_inch_model_in_mm():
    m = read_model(CTC05)
    assert m.units.linear == 25.4
    s = part_from_model(m).summary
    kinds = {e["characteristic"] for e in s["evaluated"]}
    assert {"total-runout", "roundness", "coaxiality"} <= kinds
    doc = tomllib.loads(part_from_model(m).toml)
    tol = {t["qif_id"]: t for t in doc["tolerance"]}
    circ = next(e for e in s["evaluated"] if e["type"] == "Circularity")
    # the file's 0.002 in circularity is 0.0508 mm
    assert abs(tol[circ["qif_id"]]["tolerance"] - 0.002 * 25.4) < 1e-12


def test_material_modifiers_written_for_issue_25(tmp_path):
    """CTC 3's MMC pattern positions 2068, 2077 (datums B(M), C(M)) and the single-hole
    position 2055 made MMC are written with issue 25's keys, as comments while this
    gagekit lacks them."""
    import gzip

    from gagekit.schema.part import ToleranceTable

    _TOL_KEYS = set(ToleranceTable.model_fields)

    draft = part_from_model(read_model(CTC03))
    if "material" not in _TOL_KEYS:
        un = {e["qif_id"]: e for e in draft.summary["unsupported"]}
        for q in ("2068", "2077"):
            assert un[q]["toml"] == "comment" and "material condition MMC" in un[q]["reason"]
        assert draft.toml.count('# material = "MMC"') >= 6  # 2 + 4 pattern members
        assert '# datums = ["A", "B(M)", "C(M)"]' in draft.toml
    text = gzip.decompress(CTC03.read_bytes()).decode()
    head, tail = text.split('<PositionCharacteristicDefinition id="2054">', 1)
    tail = tail.replace("<MaterialCondition>NONE</MaterialCondition>", "<MaterialCondition>MAXIMUM</MaterialCondition>", 1)
    f = tmp_path / "mmc.qif"
    f.write_text(head + '<PositionCharacteristicDefinition id="2054">' + tail)
    draft = part_from_model(read_model(f))
    entry = next(e for e in draft.summary["evaluated"] + draft.summary["unsupported"] if e["qif_id"] == "2055")
    if "material" in _TOL_KEYS:
        assert entry in draft.summary["evaluated"]
    else:
        assert entry["toml"] == "comment" and "material condition MMC" in entry["reason"]
        assert '# material = "MMC"' in draft.toml


def test_position_nominal_in_the_datum_frame():
    """CTC 1's frame A|B|C: z out of plane A (into the material), origin on bore B's axis;
    a position nominal from the model lands where the datum frame puts it."""
    draft = part_from_model(read_model(CTC05))
    doc = tomllib.loads(draft.toml)
    for t in doc["tolerance"]:
        if t["characteristic"] in ("position", "profile") and t.get("datums"):
            assert len(t["nominal"]["point"]) == 3


def test_cli_import_json(tmp_path):
    out = tmp_path / "ctc01.toml"
    proc = subprocess.run([sys.executable, "-m", "gagekit", "qif", "import", str(CTC01), "--out", str(out), "--json"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    s = json.loads(proc.stdout)
    assert s["characteristics"] == 14 and len(s["evaluated"]) + len(s["unsupported"]) == 14
    doc = tomllib.loads(out.read_text())
    assert doc["qif"]["qpid"] == s["qpid"]
    # the model path is recorded relative to the PART.toml
    assert (out.parent / doc["qif"]["model"]).resolve() == CTC01.resolve()


def test_pmi_linear_unit_applies_to_tolerances_not_geometry(tmp_path):
    """FileUnits may give the PMI a unit of its own (NIST FTC 6: geometry mm, PMI inch): a
    tolerance without a linearUnit is in the PMI unit, the geometry in the linear unit."""
    import gzip

    text = gzip.decompress(CTC01.read_bytes()).decode()
    old = "</LinearUnit>\n      <MassUnit>"
    assert old in text
    text = text.replace(old, "</LinearUnit>\n      <PMILinearUnit>\n        <SIUnitName>meter</SIUnitName>\n"
                        "        <UnitName>inch</UnitName>\n        <UnitConversion>\n          <Factor>0.0254</Factor>\n"
                        "        </UnitConversion>\n      </PMILinearUnit>\n      <MassUnit>", 1)
    text = text.replace('<ToleranceValue linearUnit="mm">0.2</ToleranceValue>', "<ToleranceValue>0.2</ToleranceValue>", 1)
    f = tmp_path / "pmi.qif"
    f.write_text(text)
    m = read_model(f)
    assert m.units.linear == 1.0 and m.units.pmi_linear == 25.4
    flat = next(c for c in m.characteristics if c.id == "1470")
    assert abs(flat.tolerance - 0.2 * 25.4) < 1e-12
    assert m.features["2156"].geometry["point"].tolist() == [-325.0, -175.0, 0.0]  # mm, as the file says


def test_pattern_gives_one_callout_per_member():
    """FTC 9: position 2186 applies to four holes in a frame that locks every motion: four
    callouts sharing the qif_id; patterns whose frame leaves motion free are listed."""
    draft = part_from_model(read_model(FTC09))
    ev = {e["qif_id"]: e for e in draft.summary["evaluated"]}
    assert len(ev["2186"]["callouts"]) == 4 and len(ev["2186"]["features"]) == 4
    doc = tomllib.loads(draft.toml)
    members = [t for t in doc["tolerance"] if t["qif_id"] == "2186"]
    assert sorted(t["feature"] for t in members) == sorted(ev["2186"]["features"])
    assert all(t["name"].endswith(f"({k + 1}/4)") for k, t in enumerate(members))
