"""Plain-text tables (gagekit.report.text): what the CLI prints."""

from gagekit.report.text import table


def test_numbers_are_right_aligned_with_four_decimals():
    out = table(["name", "value"], [["a", 1.23456], ["long name", -12.5]]).splitlines()
    assert out[0].split() == ["name", "value"]
    assert out[2].endswith("  1.2346") and out[3].endswith("-12.5000")
    assert len(out[2]) == len(out[3])


def test_a_value_that_rounds_to_zero_has_no_minus_sign():
    out = table(["v"], [[-1e-13], [-0.0], [-0.00004], [-0.00005001]]).splitlines()[2:]
    assert [ln.strip() for ln in out] == ["0.0000", "0.0000", "0.0000", "-0.0001"]
