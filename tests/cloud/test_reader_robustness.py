"""Issue 12's silently-wrong reads: decimal commas, PLY counts, complex .npy, BOMs."""

import numpy as np
import pytest

import gagekit
from gagekit.errors import FileFormatError


def test_decimal_comma_file_reads_the_numbers_it_means(tmp_path):
    f = tmp_path / "de.csv"
    f.write_text("1,5;2,5;3,5\n-0,25;1e3;4\n")  # was read as (1, 5, 2)
    np.testing.assert_array_equal(gagekit.read_points(f), [[1.5, 2.5, 3.5], [-0.25, 1000, 4]])
    g = tmp_path / "excel_de.csv"  # Excel (German locale) "CSV UTF-8": BOM, header, ; and ,
    g.write_bytes("\ufeffX;Y;Z\n10,125;-3,5;0,0\n".encode("utf-8"))
    np.testing.assert_array_equal(gagekit.read_points(g), [[10.125, -3.5, 0.0]])
    h = tmp_path / "de.txt"
    h.write_text("1,5\t2,5\t3,5\n")
    np.testing.assert_array_equal(gagekit.read_points(h), [[1.5, 2.5, 3.5]])


def test_plain_comma_files_are_unchanged(tmp_path):
    f = tmp_path / "en.csv"
    f.write_text("1,5,2\n3, 4, 5\n")
    np.testing.assert_array_equal(gagekit.read_points(f), [[1, 5, 2], [3, 4, 5]])


def test_bom_csv_header_names_columns(tmp_path):
    f = tmp_path / "bom.csv"
    f.write_bytes("\ufeffz,y,x\n3,2,1\n".encode("utf-8"))
    np.testing.assert_array_equal(gagekit.read_points(f), [[1, 2, 3]])
    u = tmp_path / "utf16.txt"
    u.write_bytes("x\ty\tz\n1\t2\t3\n".encode("utf-16"))
    with pytest.raises(FileFormatError, match="UTF-16"):
        gagekit.read_points(u)


def _ply(tmp_path, declared, n, binary):
    pts = np.arange(3 * n, dtype=float).reshape(n, 3) / 4
    head = (f"ply\nformat {'binary_little_endian' if binary else 'ascii'} 1.0\nelement vertex {declared}\n"
            "property double x\nproperty double y\nproperty double z\nend_header\n").encode()
    body = pts.astype("<f8").tobytes() if binary else "".join(f"{a} {b} {c}\n" for a, b, c in pts).encode()
    f = tmp_path / f"v{declared}_{n}_{binary}.ply"
    f.write_bytes(head + body)
    return f, pts


@pytest.mark.parametrize("binary", [True, False])
def test_ply_count_must_match_the_file(tmp_path, binary):
    f, _ = _ply(tmp_path, 10, 50, binary)  # header says 10, file holds 50: was read as 10 points
    with pytest.raises(FileFormatError, match="holds 50 vertices"):
        gagekit.read_points(f)
    f, _ = _ply(tmp_path, 50, 10, binary)
    with pytest.raises(FileFormatError, match="truncated|shorter"):
        gagekit.read_points(f)
    f, pts = _ply(tmp_path, 50, 50, binary)
    np.testing.assert_array_equal(gagekit.read_points(f), pts)


def test_ply_reader_agrees_with_plyfile(tmp_path):
    """Second reader: plyfile, on files with extra properties, faces and both byte orders."""
    from plyfile import PlyData, PlyElement

    rng = np.random.default_rng(3)
    v = np.empty(200, dtype=[("nx", "<f4"), ("x", "<f4"), ("y", "<f8"), ("red", "u1"), ("z", "<i4")])
    for k in v.dtype.names:
        v[k] = rng.uniform(-1e3, 1e3, 200).astype(v.dtype[k])
    faces = np.empty(3, dtype=[("vertex_indices", "O")])
    faces["vertex_indices"] = [np.array([0, 1, 2], "i4"), np.array([1, 2, 3, 4], "i4"), np.array([5, 6, 7], "i4")]
    for text, byte_order in [(True, "="), (False, "<"), (False, ">")]:
        f = tmp_path / f"p{int(text)}{byte_order}.ply"
        PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(faces, "face")], text=text, byte_order=byte_order).write(str(f))
        ref = PlyData.read(str(f))["vertex"].data
        want = np.column_stack([np.asarray(ref[c], dtype=np.float64) for c in "xyz"])
        np.testing.assert_array_equal(gagekit.read_points(f), want)


def test_complex_npy_is_refused(tmp_path):
    f = tmp_path / "c.npy"
    np.save(f, (np.arange(9.0) + 1j).reshape(3, 3))  # the imaginary part was dropped silently
    with pytest.raises(FileFormatError, match="complex"):
        gagekit.read_points(f)
    g = tmp_path / "i.npy"
    np.save(g, np.arange(9, dtype=np.int16).reshape(3, 3))
    np.testing.assert_array_equal(gagekit.read_points(g), np.arange(9.0).reshape(3, 3))
    for bad in (np.array(["a", "b", "c"]).reshape(1, 3), np.ones((2, 3), dtype=bool)):
        np.save(tmp_path / "b.npy", bad)
        with pytest.raises(FileFormatError):
            gagekit.read_points(tmp_path / "b.npy")


def test_excel_bom_observations_csv(tmp_path, machine):
    """Issue 12: an observations CSV saved by Excel as "CSV UTF-8" (with a BOM) gave
    'missing column(s)': the BOM stuck to the first header name."""
    from gagekit.machine.observations import read_observations

    cols = list(machine.joint_names) + ["x", "y", "z"]
    row = ",".join("0" for _ in cols)
    f = tmp_path / "obs.csv"
    f.write_bytes(("\ufeff" + ",".join(cols) + "\n" + row + "\n" + row + "\n").encode("utf-8"))
    obs = read_observations(f, machine)
    assert obs.commands.shape == (2, len(machine.joint_names))
