"""Reader fuzzing (issue 12): random bytes and mutated real files fed to every reader.
Every outcome is a correct read (finite (n, 3) millimetres) or a typed gagekit error:
never another exception, a crash or a hang (each read runs under an alarm)."""

import signal
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gagekit
from gagekit.cli import main
from gagekit.errors import GagekitError

DATA = Path(__file__).resolve().parents[1] / "data"
SUFFIXES = [".xyz", ".csv", ".txt", ".pts", ".ds", ".ply", ".npy", ".las", ".laz", ".e57", ".dat"]
SEEDS = {
    ".e57": DATA / "e57" / "cartesian_invalid_state_single.e57",
    ".las": DATA / "las" / "simple.las",
    ".laz": DATA / "las" / "simple.laz",
}
FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@contextmanager
def alarm(seconds=20):
    def boom(*_):
        raise AssertionError(f"reader hung for more than {seconds} s")

    old = signal.signal(signal.SIGALRM, boom)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _check(path):
    with alarm():
        try:
            pts = gagekit.read_points(path, units="mm")
        except GagekitError:
            return None
    assert pts.ndim == 2 and pts.shape[1] == 3 and len(pts) > 0 and np.isfinite(pts).all()
    return pts


def _seed_bytes(suffix):
    if suffix in SEEDS:
        return SEEDS[suffix].read_bytes()
    if suffix == ".ply":
        return b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n" + np.arange(6, dtype="<f4").tobytes()
    if suffix == ".npy":
        import io

        buf = io.BytesIO()
        np.save(buf, np.arange(12.0).reshape(4, 3))
        return buf.getvalue()
    return b"x,y,z\n1,2,3\n4.5;5;6\n7 8 9\n"


@FUZZ
@given(suffix=st.sampled_from(SUFFIXES), data=st.binary(max_size=600))
def test_random_bytes(tmp_path, suffix, data):
    f = tmp_path / f"fuzz{suffix}"
    f.write_bytes(data)
    _check(f)


@FUZZ
@given(
    suffix=st.sampled_from([".e57", ".las", ".laz", ".ply", ".npy", ".csv"]),
    cut=st.floats(0, 1),
    flips=st.lists(st.tuples(st.floats(0, 1, exclude_max=True), st.integers(0, 255)), max_size=6),
)
def test_mutated_real_files(tmp_path, suffix, cut, flips):
    b = bytearray(_seed_bytes(suffix))
    for at, val in flips:
        b[int(at * len(b))] = val
    b = b[: max(1, int(cut * len(b))) if cut < 1 else len(b)]
    f = tmp_path / f"mut{suffix}"
    f.write_bytes(bytes(b))
    _check(f)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(suffix=st.sampled_from(SUFFIXES), data=st.binary(max_size=300))
def test_cli_random_point_files(tmp_path, capfd, suffix, data):
    """The CLI on random bytes: exit 0 with a result, or one 'gagekit: error:' line and exit 2."""
    f = tmp_path / f"cli{suffix}"
    f.write_bytes(data)
    capfd.readouterr()
    with alarm(), pytest.raises(SystemExit) as ex:
        main(["cloud", "info", str(f), "--json"])
    out, err = capfd.readouterr()
    assert ex.value.code in (0, 2, None)
    if ex.value.code == 2:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("gagekit: error:"), err
        assert out == ""
    else:
        assert "Traceback" not in err and out.startswith("{")
