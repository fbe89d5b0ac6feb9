"""The point files of `gagekit form fit`: how many values a text line holds decides 2-D or
3-D, read as the cloud readers read the file (decimal commas included)."""

from __future__ import annotations

import numpy as np
import pytest

from gagekit.form.files import read_xy, text_columns


@pytest.mark.parametrize(
    "text, columns",
    [
        ("1,5;2,5\n3,5;4,25\n", 2),  # decimal commas, semicolons: 2 values (was 3)
        ("1,5 2,5\n", 2),
        ("1,5,2\n", 3),
        ("\ufeffx;y\n1,5;2,5\n", 2),  # Excel's BOM and a header
        ("# comment\n1 2 3 4\n", 4),
        ("x y\nfoo bar\n", 0),
    ],
)
def test_text_columns(tmp_path, text, columns):
    f = tmp_path / "p.csv"
    f.write_text(text, encoding="utf-8")
    assert text_columns(f) == columns


def test_a_two_column_decimal_comma_file_is_read_as_2d_points(tmp_path):
    f = tmp_path / "circle.csv"
    a = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    f.write_text("".join(f"{10 + 5 * np.cos(t):.6f};{-3 + 5 * np.sin(t):.6f}\n".replace(".", ",") for t in a))
    p = read_xy(f)
    assert p.shape == (12, 2)
    np.testing.assert_allclose(p[:, 0], 10 + 5 * np.cos(a), atol=1e-6)
