"""`--qif-results`: QIF 3.0 MeasurementsResults that validate against the official XSDs,
one actual per callout with the value `--json` prints; results of a part imported from a
QIF model point at the model's own ids."""

from __future__ import annotations

import gzip
import json
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

import gagekit
from gagekit.samples import data_path
from gagekit.inspect import part_spec_from_dict
from gagekit.qif import part_from_model, read_model, write_inspection_results
from gagekit.qif.nominal import sample_feature

from conftest import CTC01, CTC05, FTC09, assert_valid

try:
    import tomllib
except ImportError:  # pragma: no cover
    import tomli as tomllib

NS = {"q": "http://qifstandards.org/xsd/qif3"}


def _gagekit(*args, check=True):
    proc = subprocess.run([sys.executable, "-m", "gagekit", *map(str, args)], capture_output=True, text=True, timeout=600)
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def _measurements(tree):
    return tree.xpath("//q:MeasuredCharacteristics/q:CharacteristicMeasurements/*", namespaces=NS)


def test_bracket_results_validate_and_match_json(tmp_path, qif_schema):
    out = tmp_path / "bracket.qif"
    proc = _gagekit("inspect", data_path("bracket.ply"), data_path("bracket.toml"), "--json", "--qif-results", out,
                    "--instrument", "structured-light scanner")
    res = json.loads(proc.stdout)
    tree = assert_valid(qif_schema, out)
    ms = _measurements(tree)
    assert len(ms) == len(res["tolerances"]) == 20  # one actual per callout
    for m, t in zip(ms, res["tolerances"]):
        assert float(m.findtext("q:Value", namespaces=NS)) == t["measured"]  # the same number, to the bit
        assert m.findtext("q:Status/q:CharacteristicStatusEnum", namespaces=NS) == ("PASS" if t["pass"] else "FAIL")
    # self-contained: its own definitions, nominals and items, each measurement pointing at an item
    items = {el.get("id") for el in tree.xpath("//q:CharacteristicItems/*", namespaces=NS)}
    assert len(items) == 20 and {m.findtext("q:CharacteristicItemId", namespaces=NS) for m in ms} == items
    assert tree.xpath("//q:MeasurementDevice/q:Name/text()", namespaces=NS) == ["structured-light scanner"]
    assert tree.xpath("//q:ExternalFileReference/q:URI/text()", namespaces=NS)[0].endswith("bracket.ply")
    assert tree.xpath("//q:Header/q:Application/q:Name/text()", namespaces=NS) == ["gagekit"]
    assert len(tree.xpath("//q:ActualTransforms/q:Transform", namespaces=NS)) >= 1
    status = tree.xpath("//q:MeasurementResults/q:InspectionStatus/q:InspectionStatusEnum/text()", namespaces=NS)
    assert status == ["PASS" if res["status"] == "conforming" else "FAIL"]


def _synthetic_scan(model, spec, seed=0, noise=0.002):
    """A scan made from the nominals of every feature of the drawing, with Gaussian noise
    along random directions (seeded)."""
    rng = np.random.default_rng(seed)
    parts = [sample_feature(model.features[f.qif_id], 3000) for f in spec.features.values()]
    pts = np.vstack(parts)
    d = rng.normal(size=pts.shape)
    d /= np.linalg.norm(d, axis=1)[:, None]
    return pts + noise * rng.normal(size=(len(pts), 1)) * d


@pytest.mark.parametrize("path", [CTC01, CTC05, FTC09])
def test_round_trip_references_the_model_ids(path, tmp_path, qif_schema):
    model = read_model(path)
    draft = part_from_model(model, model_ref=str(path))
    part = tmp_path / "part.toml"
    part.write_text(draft.toml)
    spec = gagekit.load_part_spec(part)
    assert spec.tolerances
    scan = tmp_path / "scan.npy"
    np.save(scan, _synthetic_scan(model, spec))
    out = tmp_path / "results.qif"
    proc = _gagekit("inspect", scan, part, "--json", "--qif-results", out)
    res = json.loads(proc.stdout)
    # the nominal part with 2 um of noise passes every callout whose region holds its own
    # surface only (the importer flags the others: a hole piercing a face, coaxial cylinders)
    crowded = {e["qif_id"] for e in draft.summary["evaluated"] if any("also holds" in n for n in e["notes"])}
    assert len(crowded) < len(spec.tolerances)
    for t, r in zip(spec.tolerances, res["tolerances"]):
        # sizes (evaluated since issue 25) are left out here: a size whose nominal is one of its
        # limits (CTC-01 35 -0.2/0) fails its two-point sizes on the nominal part with noise,
        # honestly (half its local sizes lie beyond that limit), and FTC-09 'Linear Size.2'
        # targets 5.9436 on a cylinder of nominal diameter 11.887 (a radius? for the QIF mapping)
        if t.characteristic == "size":
            continue
        assert r["pass"] or t.qif_id in crowded, (t.label, r["measured"], r["tolerance"])
    tree = assert_valid(qif_schema, out)
    # the model's ids are kept: every item points at the model's characteristic nominal,
    # in the same order as the callouts
    by_id = {el.get("id"): el for el in tree.iter() if isinstance(el.tag, str) and el.get("id")}
    ms = _measurements(tree)
    # one measurement per characteristic; a pattern's is its largest member's value
    groups: dict = {}
    for t, r in zip(spec.tolerances, res["tolerances"]):
        groups.setdefault(t.qif_id, []).append(r)
    assert len(ms) == len(groups) == len(draft.summary["evaluated"])
    scale = model.units.pmi_linear or model.units.linear
    for m, (qif_id, rs) in zip(ms, groups.items()):
        item = by_id[m.findtext("q:CharacteristicItemId", namespaces=NS)]
        assert item.findtext("q:CharacteristicNominalId", namespaces=NS) == qif_id
        assert by_id[qif_id].tag.endswith("CharacteristicNominal")
        assert float(m.findtext("q:Value", namespaces=NS)) == pytest.approx(max(r["measured"] for r in rs) / scale, rel=1e-15)
        assert m.findtext("q:Status/q:CharacteristicStatusEnum", namespaces=NS) == ("PASS" if all(r["pass"] for r in rs) else "FAIL")
        # a width (slot / tab, issue 25) has no feature measurement in the export yet
        measured_features = [r for r in rs if spec.features[r["feature"]].shape not in ("slot", "tab")]
        assert len(m.xpath("q:FeatureMeasurementIds/q:Id", namespaces=NS)) == len(measured_features)
    # the original model's ids are untouched; the document has its own QPId and names the model's
    orig = set(re.findall(r' id="(\d+)"', gzip.decompress(path.read_bytes()).decode()))
    assert orig <= set(by_id)
    assert tree.findtext("q:QPId", namespaces=NS) != model.qpid
    assert tree.xpath("//q:ExternalQIFDocument/q:QPId/text()", namespaces=NS) == [model.qpid]
    # feature items point at the model's feature nominals
    for fi in tree.xpath("//q:FeatureItems/*", namespaces=NS):
        assert by_id[fi.findtext("q:FeatureNominalId", namespaces=NS)].tag.endswith("FeatureNominal")


def test_batch_writes_one_results_per_scan(tmp_path, qif_schema):
    scans = tmp_path / "scans"
    scans.mkdir()
    pts = gagekit.read_points(data_path("bracket.ply"))
    np.save(scans / "a.npy", pts)
    R = np.array([[1.0, 0, 0], [0, 1, 0], [0, 0, 1]])
    np.save(scans / "b.npy", pts @ R.T + [0.0, 0.0, 0.003])
    out = tmp_path / "batch.qif"
    proc = _gagekit("inspect", "batch", data_path("bracket.toml"), scans, "--workers", 1, "--db",
                    f"sqlite:///{tmp_path}/b.db", "--json", "--qif-results", out)
    lines = [json.loads(x) for x in proc.stdout.splitlines()]
    ok = [x for x in lines if x.get("status") == "ok"]
    assert len(ok) == 2
    tree = assert_valid(qif_schema, out)
    runs = tree.xpath("//q:MeasurementResults", namespaces=NS)
    assert len(runs) == 2
    for run, line in zip(runs, sorted(ok, key=lambda x: x["scan"])):
        vals = [float(v) for v in run.xpath("q:MeasuredCharacteristics/q:CharacteristicMeasurements/*/q:Value/text()",
                                             namespaces=NS)]
        assert vals == [t["measured"] for t in line["result"]["tolerances"]]


def test_results_against_a_moved_model_is_one_error(tmp_path):
    shutil.copy(CTC01, tmp_path / "m.qif.gz")
    part = tmp_path / "part.toml"
    _gagekit("qif", "import", tmp_path / "m.qif.gz", "--out", part)
    (tmp_path / "m.qif.gz").unlink()
    spec = gagekit.load_part_spec(part)
    res = {"tolerances": [{"measured": 0.0, "pass": True, "datums": []} for _ in spec.tolerances]}
    with pytest.raises(gagekit.GagekitError, match="QIF model is not at"):
        write_inspection_results(tmp_path / "r.qif", [{"scan": "x", "result": res}], spec, part)


def test_spec_keys_round_trip():
    doc = tomllib.loads(part_from_model(read_model(CTC01)).toml)
    spec = part_spec_from_dict(doc, "x")
    assert spec.qif["qpid"] and all(f.qif_id for f in spec.features.values())


def test_gage_check_results_validate(tmp_path, qif_schema):
    out = tmp_path / "gage.qif"
    proc = _gagekit("gage", "check", data_path("casting_ok.ply"), data_path("casting_ok.toml"), "--no-groups", "--json",
                    "--qif-results", out)
    res = json.loads(proc.stdout)
    tree = assert_valid(qif_schema, out)
    ms = _measurements(tree)
    assert len(ms) == len(res["gages"]) > 0
    for m, g in zip(ms, res["gages"]):
        assert float(m.findtext("q:Value", namespaces=NS)) == g["allowance_after"]
        assert m.findtext("q:Status/q:CharacteristicStatusEnum", namespaces=NS) == ("PASS" if g["slack"] == 0 else "FAIL")
    T = np.array(res["transform"]["matrix"])
    z = [float(v) for v in tree.findtext(".//q:Transform/q:Rotation/q:ZDirection", namespaces=NS).split()]
    assert z == T[:3, 2].tolist()


def test_results_with_their_uncertainty_validate(tmp_path, qif_schema):
    """`--uncertainty` results: each actual's Value carries combinedUncertainty (u) and
    meanError (|bias|), QIF's MeasuredDecimalType; U, k, the coverage interval and the
    decision rule are its Attributes; Status follows the ISO 14253-1 decision (not-proven:
    INDETERMINATE). The document still validates against the QIF 3.0 XSDs."""
    out = tmp_path / "bracket-u.qif"
    proc = _gagekit("inspect", data_path("bracket.ply"), data_path("bracket.toml"), "--json", "--qif-results", out,
                    "--uncertainty", "10", "--noise", "0.001")
    res = json.loads(proc.stdout)
    tree = assert_valid(qif_schema, out)
    ms = _measurements(tree)
    assert len(ms) == len(res["tolerances"]) == 20
    status = {"conforming": "PASS", "nonconforming": "FAIL", "not-proven": "INDETERMINATE"}
    for m, t in zip(ms, res["tolerances"]):
        v = m.find("q:Value", namespaces=NS)
        assert float(v.text) == t["measured"]
        assert float(v.get("combinedUncertainty")) == t["uncertainty"]["u"]
        assert float(v.get("meanError")) == abs(t["uncertainty"]["bias"])
        attrs = {a.get("name"): a.get("value") for a in m.findall("q:Attributes/*", namespaces=NS)}
        assert float(attrs["U"]) == t["uncertainty"]["U"] and attrs["decision_rule"] == "iso14253"
        assert m.findtext("q:Status/q:CharacteristicStatusEnum", namespaces=NS) == status[t["decision"]]
    gout = tmp_path / "gage-u.qif"
    proc = _gagekit("gage", "check", data_path("casting_ok.ply"), data_path("casting_ok.toml"), "--no-groups", "--json",
                    "--qif-results", gout, "--uncertainty", "10", "--noise", "0.01")
    res = json.loads(proc.stdout)
    tree = assert_valid(qif_schema, gout)
    for m, g in zip(_measurements(tree), res["gages"]):
        assert float(m.find("q:Value", namespaces=NS).get("combinedUncertainty")) == g["uncertainty"]["u"]
        assert m.findtext("q:Status/q:CharacteristicStatusEnum", namespaces=NS) == status[g["decision"]]
