"""Bad QIF input is one clear error line, exit status 2: not XML, another QIF version,
references to ids the file does not hold, units gagekit does not know."""

from __future__ import annotations

import gzip
import subprocess
import sys

import pytest

from conftest import CTC01

CTC01_TEXT = gzip.decompress(CTC01.read_bytes()).decode()


def _import(tmp_path, text: str, name="m.qif"):
    f = tmp_path / name
    f.write_text(text)
    return subprocess.run([sys.executable, "-m", "gagekit", "qif", "import", str(f), "--out", str(tmp_path / "p.toml")],
                          capture_output=True, text=True, timeout=300)


CASES = {
    "not-xml": ("this is not XML <QIFDocument", "the XML is malformed"),
    "truncated": (CTC01_TEXT[: len(CTC01_TEXT) // 2], "the XML is malformed"),
    "qif2": (CTC01_TEXT.replace("http://qifstandards.org/xsd/qif3", "http://qifstandards.org/xsd/qif2")
             .replace('versionQIF="3.0.0"', 'versionQIF="2.1"'), "QIF version 2.1 is not supported"),
    "no-version": (CTC01_TEXT.replace(' versionQIF="3.0.0"', "", 1), "has no versionQIF attribute"),
    "other-root": ('<?xml version="1.0"?><svg xmlns="http://www.w3.org/2000/svg"/>', "not a QIF document"),
    "missing-definition": (CTC01_TEXT.replace("<CharacteristicDefinitionId>1469</CharacteristicDefinitionId>",
                                              "<CharacteristicDefinitionId>99999</CharacteristicDefinitionId>"),
                           "CharacteristicDefinitionId '99999' names no characteristic definition"),
    "missing-feature": (CTC01_TEXT.replace('<PerpendicularityCharacteristicNominal id="1467">\n        <CharacteristicDefinitionId>'
                                           '1466</CharacteristicDefinitionId>\n        <FeatureNominalIds n="1">\n          <Id>2162',
                                           '<PerpendicularityCharacteristicNominal id="1467">\n        <CharacteristicDefinitionId>'
                                           '1466</CharacteristicDefinitionId>\n        <FeatureNominalIds n="1">\n          <Id>88888'),
                        "FeatureNominalIds names 88888, which is no feature nominal"),
    "missing-drf": (CTC01_TEXT.replace("<DatumReferenceFrameId>1459</DatumReferenceFrameId>",
                                       "<DatumReferenceFrameId>77777</DatumReferenceFrameId>"),
                    "DatumReferenceFrameId 77777 names no DatumReferenceFrame"),
    "unknown-units": (CTC01_TEXT.replace("<UnitName>mm</UnitName>\n        <UnitConversion>\n          <Factor>0.001</Factor>\n"
                                         "        </UnitConversion>", "<UnitName>furlong</UnitName>", 1),
                      "unknown unit 'furlong'"),
    "no-units": (CTC01_TEXT[: CTC01_TEXT.index("<FileUnits>")] + CTC01_TEXT[CTC01_TEXT.index("</FileUnits>") + 12:],
                 "no FileUnits"),
    "unknown-value-unit": (CTC01_TEXT.replace('linearUnit="mm">0.2</ToleranceValue>', 'linearUnit="cubit">0.2</ToleranceValue>'),
                           "unknown linear unit 'cubit'"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_qif_is_one_error_line(case, tmp_path):
    text, message = CASES[case]
    assert text != CTC01_TEXT
    proc = _import(tmp_path, text)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gagekit: error: "), proc.stderr
    assert message in lines[0], lines[0]
    assert "m.qif" in lines[0]
    assert not (tmp_path / "p.toml").exists() and not proc.stdout


def test_missing_file_and_binary_garbage(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "gagekit", "qif", "import", str(tmp_path / "none.qif"), "--out",
                           str(tmp_path / "p.toml")], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and proc.stderr.startswith("gagekit: error: ") and len(proc.stderr.splitlines()) == 1
    (tmp_path / "g.qif").write_bytes(b"\x1f\x8b\x08garbage")
    proc = subprocess.run([sys.executable, "-m", "gagekit", "qif", "import", str(tmp_path / "g.qif"), "--out",
                           str(tmp_path / "p.toml")], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and "gzip" in proc.stderr and len(proc.stderr.splitlines()) == 1


def test_missing_extra_is_one_line_naming_it(tmp_path):
    code = ("import sys; sys.modules['lxml'] = None\n"
            "from gagekit.cli import main\n"
            f"main(['qif', 'import', {str(CTC01)!r}, '--out', {str(tmp_path / 'p.toml')!r}])")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2
    assert proc.stderr.strip() == "gagekit: error: QIF import/export needs lxml: pip install 'gagekit[qif]'"
