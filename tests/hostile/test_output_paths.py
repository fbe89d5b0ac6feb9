"""Every command that writes, with every kind of bad output path: one error line, exit 2,
and nothing written anywhere (checked before the computation starts); an existing
writable file is replaced atomically (a correct result, no temporary left)."""

from __future__ import annotations

import pytest

from .conftest import CASTING_PLY, CASTING_TOML, EXAMPLE_MACHINE, assert_clean_error, assert_ok, gk, leftovers


def writers(sim):
    """(name, args with OUT as the output path, is-a-folder output)"""
    m = EXAMPLE_MACHINE
    return [
        ("simulate --out", ["machine", "simulate", m, "--points", 30, "--out", "OUT"], False),
        ("simulate --truth", ["machine", "simulate", m, "--points", 30, "--out", sim / "o2.csv", "--truth", "OUT"], False),
        ("design --out", ["machine", "design", m, "--points", 40, "--candidates", 400, "--starts", 1, "--out", "OUT"], False),
        ("predict --out", ["machine", "predict", m, sim / "cal.json", sim / "obs.csv", "--out", "OUT"], False),
        ("compensate --out", ["machine", "compensate", m, sim / "cal.json", sim / "obs.csv", "--out", "OUT"], False),
        ("identify --out", ["machine", "identify", m, sim / "obs.csv", "--out", "OUT"], False),
        ("identify --residuals", ["machine", "identify", m, sim / "obs.csv", "--residuals", "OUT"], False),
        ("gage --out-cloud", ["gage", "check", CASTING_PLY, CASTING_TOML, "--no-groups", "--out-cloud", "OUT.ply"], False),
        ("gage --report", ["gage", "check", CASTING_PLY, CASTING_TOML, "--no-groups", "--report", "OUT"], True),
        ("cloud hull --out", ["cloud", "hull", CASTING_PLY, "--out", "OUT.ply"], False),
        ("demo --out", ["demo", "--quick", "--out", "OUT"], True),
    ]


def _args(args, out):
    return [out if isinstance(a, str) and a.startswith("OUT") else a for a in args]


def _suffix(args, is_dir):
    tag = next(a for a in args if isinstance(a, str) and a.startswith("OUT"))
    return "" if is_dir else (tag[3:] or ".csv")


KINDS = ["missing-folder", "a-folder", "read-only-folder", "read-only-file"]


@pytest.mark.parametrize("kind", KINDS)
def test_bad_output_paths(sim, tmp_path, kind):
    for name, args, is_dir in writers(sim):
        if name == "demo --out" and kind != "missing-folder":
            continue  # the demo is slow; its path checks are the same output_dir as gage --report
        base = tmp_path / name.replace(" ", "_").replace("-", "")
        base.mkdir()
        sfx = _suffix(args, is_dir)
        if kind == "missing-folder":
            out = base / "no" / "such" / f"x{sfx}"
        elif kind == "a-folder":
            out = base / f"folder{sfx}"
            out.mkdir()
            (out / "keep.txt").write_text("mine")
        elif kind == "read-only-folder":
            ro = base / "ro"
            ro.mkdir()
            out = ro / f"x{sfx}"
            ro.chmod(0o555)
        else:
            out = base / f"x{sfx}"
            out.write_text("old")
            out.chmod(0o444)
        proc = gk(*_args(args, out), timeout=300)
        try:
            line = assert_clean_error(proc)
        except AssertionError as exc:
            raise AssertionError(f"{name} / {kind}: {exc}") from None
        assert "cannot write" in line or "holds other files" in line or "a file of that name" in line, (name, line)
        if kind == "read-only-file":
            assert out.read_text() == "old"
        if kind == "a-folder" and (out / "keep.txt").exists():
            assert (out / "keep.txt").read_text() == "mine"
        if kind == "read-only-folder":
            out.parent.chmod(0o755)
            assert list(out.parent.iterdir()) == []


def test_existing_outputs_are_replaced_atomically(sim, tmp_path):
    for name, args, is_dir in writers(sim):
        if name == "demo --out":
            continue
        base = tmp_path / name.replace(" ", "_").replace("-", "")
        base.mkdir()
        out = base / f"x{_suffix(args, is_dir)}"
        if is_dir:
            out.mkdir()  # an empty folder is filled
        else:
            out.write_text("old")  # an existing file is replaced
        assert_ok(gk(*_args(args, out), timeout=300))
        assert leftovers(base) == [], name
        assert (out / ".gagekit-report").exists() if is_dir else out.read_bytes() != b"old", name
