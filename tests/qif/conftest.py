"""QIF test data: NIST CTC models (QIF MBD, from the QIF community repository; see
tests/data/qif/README.md) and the official QIF 3.0 XSDs, compiled once per session."""

from __future__ import annotations

from pathlib import Path

import pytest

from gagekit.samples import data_path

QIF_DATA = Path(__file__).resolve().parents[1] / "data" / "qif"
CTC01 = data_path("nist_ctc_01_asme1_ap242.qif.gz")
CTC03 = QIF_DATA / "nist_ctc_03_asme1_ap242.qif.gz"
CTC05 = QIF_DATA / "nist_ctc_05_asme1_ap242.qif.gz"
FTC09 = QIF_DATA / "nist_ftc_09_asme1_ap242.qif.gz"
XSD = QIF_DATA / "xsd" / "QIFApplications" / "QIFDocument.xsd"


@pytest.fixture(scope="session")
def qif_schema():
    from lxml import etree

    return etree.XMLSchema(etree.parse(str(XSD)))


def assert_valid(schema, path_or_tree):
    """Validate a QIF document against the official QIF 3.0 XSDs (every key/keyref too)."""
    from lxml import etree

    tree = etree.parse(str(path_or_tree)) if isinstance(path_or_tree, (str, Path)) else path_or_tree
    ok = schema.validate(tree)
    assert ok, "\n".join(str(e) for e in list(schema.error_log)[:10])
    return tree
