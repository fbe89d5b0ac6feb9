"""Streamed reads and region-first evaluation (issue 29): every format read in chunks gives
the whole read's points bit for bit, and `gage check`, `inspect`, `cloud hull` and
`cloud regions` give the same JSON streamed with a tiny chunk size as reading the whole
file (CI runs these small files only; benches/bench_scale.py runs the large ones)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gagekit
from gagekit.cloud import read_cloud
from gagekit.cloud.stream import READ_AHEAD, chunk_points, memory_budget, open_cloud, should_stream
from gagekit.errors import FileFormatError, InvalidInputError

DATA = Path(gagekit.__file__).parent / "data"
TESTS = Path(__file__).resolve().parents[1] / "data"


def streamed(path, chunk=997, units=None) -> np.ndarray:
    s = open_cloud(path, units, chunk=chunk)
    got = np.vstack(list(s))
    assert s.points_read == len(got)
    return got


def same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("path", [DATA / "casting_ok.ply", DATA / "bracket.ply",
                                  *sorted((TESTS / "e57").glob("bunny*.e57"))[:1],
                                  *sorted((TESTS / "las").glob("*.la[sz]"))[:3]], ids=lambda p: p.name)
def test_bundled_files_stream_as_they_read(path):
    whole = read_cloud(path)
    for chunk in (1, 997, 10**6):
        if chunk == 1 and len(whole.points) > 5000:
            continue
        assert same(streamed(path, chunk), whole.points)
    s = open_cloud(path, chunk=100)
    assert (s.source_unit, s.scale_to_mm, s.format) == (whole.source_unit, whole.scale_to_mm, whole.format)


def test_text_formats_and_units(tmp_path):
    rng = np.random.default_rng(3)
    pts = rng.uniform(-100, 100, (5003, 3)).round(6)
    body = "\n".join(f"{i},{z!r},{y!r},{x!r}" + ("\n# c\n" if i % 500 == 0 else "") for i, (x, y, z) in enumerate(pts.tolist()))
    csv = tmp_path / "a.csv"
    csv.write_text("# scan\nid,Z,Y,X\n" + body + "\n")
    assert same(streamed(csv, 77), read_cloud(csv).points)
    assert same(streamed(csv, 77, units="in"), read_cloud(csv, units="in").points)
    ds = tmp_path / "a.ds"
    ds.write_text(f"{len(pts)}\n" + "\n".join(f"{x!r} {y!r} {z!r}" for x, y, z in pts.tolist()) + "\n")
    assert same(streamed(ds, 100), pts)
    ds.write_text(f"{len(pts) + 1}\n" + "\n".join(f"{x!r} {y!r} {z!r}" for x, y, z in pts.tolist()) + "\n")
    with pytest.raises(FileFormatError, match="announces"):
        streamed(ds, 100)
    for order in ("C", "F"):
        npy = tmp_path / f"a{order}.npy"
        np.save(npy, np.asarray(np.column_stack([pts, pts[:, 0]]), order=order))
        assert same(streamed(npy, 300), read_cloud(npy).points)


def test_errors_name_the_point_in_the_whole_file(tmp_path):
    lines = [f"{i} {i} {i}" for i in range(3000)]
    lines[2500] = "1 oops 3"
    bad = tmp_path / "bad.xyz"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(FileFormatError) as whole:
        read_cloud(bad)
    with pytest.raises(FileFormatError) as part:
        streamed(bad, 10)
    assert str(part.value) == str(whole.value) and "line 2501" in str(part.value)
    arr = np.zeros((1000, 3))
    arr[777, 1] = np.nan
    npy = tmp_path / "nan.npy"
    np.save(npy, arr)
    with pytest.raises(InvalidInputError, match="point 777"):
        streamed(npy, 100)
    empty = tmp_path / "empty.xyz"
    empty.write_text("x y z\n")
    with pytest.raises(FileFormatError):
        streamed(empty)


def test_ascii_ply_streams_by_lines(tmp_path):
    """An ASCII PLY file is read in blocks of vertex lines (bounded memory): an element
    before the vertices, blank lines, faces after them; the same points, the same errors
    (count checks, a bad value naming its line) as the whole read."""
    rng = np.random.default_rng(5)
    pts = rng.uniform(-50, 50, (2500, 3)).round(5)
    head = ("ply\nformat ascii 1.0\ncomment t\nelement camera 2\nproperty float k\nelement vertex {n}\n"
            "property float x\nproperty uchar red\nproperty list uchar int extra\nproperty double y\nproperty double z\n"
            "element face 2\nproperty list uchar int vertex_indices\nend_header\n")
    rows = [f"{x!r} 7 2 1 2 {y!r} {z!r}" + ("\n" if i % 400 == 0 else "") for i, (x, y, z) in enumerate(pts.tolist())]
    body = "1.5\n\n2.5\n" + "\n".join(rows) + "\n3 0 1 2\n3 2 1 0\n"
    good = tmp_path / "a.ply"
    good.write_text(head.format(n=len(pts)) + body)
    assert open_cloud(good, chunk=10).format == read_cloud(good).format == "ply ascii"
    for chunk in (1, 333, 10**6):
        assert same(streamed(good, chunk), pts)
    for n, text in ((len(pts) + 1, body), (len(pts) - 1, body), (len(pts), body.replace(rows[1777], "1 7 2 1 2 x 3"))):
        bad = tmp_path / "bad.ply"
        bad.write_text(head.format(n=n) + text)
        with pytest.raises(FileFormatError) as whole:
            read_cloud(bad)
        with pytest.raises(FileFormatError) as part:
            streamed(bad, 100)
        assert str(part.value) == str(whole.value)


def test_memory_budget():
    assert memory_budget("512M") == 512 << 20 and memory_budget("2G") == 2 << 30
    assert memory_budget(None) >= 64 << 20
    for bad in ("1K", "lots", "-3G"):
        with pytest.raises(InvalidInputError):
            memory_budget(bad)
    assert 1 << 16 <= chunk_points(memory_budget("1G")) <= 1 << 23
    assert not should_stream(DATA / "casting_ok.ply", None)
    assert should_stream(DATA / "casting_ok.ply", 64 << 20) is False  # 3 MB of points


def test_an_e57_is_sized_by_its_records():
    """A scaled-integer E57 holds a point in fewer bytes than the float64 point it reads
    as: the whole read's size comes from the record counts, not the file's size."""
    from gagekit.cloud.stream import whole_read_bytes

    f = TESTS / "e57" / "bunnyInt19.e57"
    assert whole_read_bytes(f) == 24 * len(read_cloud(f).points) > f.stat().st_size


def cli(*args):
    return subprocess.run([sys.executable, "-m", "gagekit", *map(str, args), "--json"], capture_output=True,
                          text=True, timeout=300)


def result(proc) -> dict:
    assert proc.returncode == 0, proc.stderr
    d = json.loads(proc.stdout)
    d.pop("seconds", None)
    return d


@pytest.mark.parametrize("args", [
    ("gage", "check", DATA / "casting_ok.ply", DATA / "casting_ok.toml"),
    ("gage", "check", DATA / "casting_short.ply", DATA / "casting_short.toml"),
    ("inspect", DATA / "bracket.ply", DATA / "bracket.toml"),
    ("cloud", "hull", DATA / "casting_short.ply"),
    ("cloud", "regions", DATA / "casting_ok.ply", DATA / "casting_ok.toml"),
], ids=lambda a: " ".join(str(x) for x in a[:2]) if isinstance(a, tuple) else str(a))
def test_streamed_equals_whole(args):
    """Bit for bit: the JSON of a streamed evaluation (chunks of 997 points: about a
    hundred chunks, so regions and hulls straddle chunk borders) is the whole read's."""
    whole = result(cli(*args))
    assert result(cli(*args, "--chunk-points", 997)) == whole
    small = cli(*args, "--memory", "1G")
    assert result(small) == whole


def test_bad_memory_option_is_one_line():
    proc = cli("cloud", "hull", DATA / "bracket.ply", "--memory", "12 apples")
    assert proc.returncode == 2 and proc.stderr.startswith("gagekit: error: memory:") and proc.stderr.count("\n") == 1


E57_FILES = [TESTS / "e57" / f"{n}.e57" for n in ("bunnyDouble", "bunnyInt19", "tiny_spherical",
                                                   "cartesian_invalid_state_single", "translationWithoutRotation")]


@pytest.mark.parametrize("path", E57_FILES, ids=lambda p: p.name)
def test_e57_streams_packet_by_packet_as_it_reads(path):
    """Every sample E57 (Cartesian double, 19-bit scaled integers, spherical floats with
    invalid states, a pose) is read data packet by data packet, not whole, and any chunk
    size gives the whole read's points bit for bit."""
    from gagekit import _core

    s = _core.cloud.e57_chunks(str(path))
    assert s is not None and s.scans >= 1
    whole = read_cloud(path)
    for chunk in (1, 97, 10**6):
        if chunk == 1 and len(whole.points) > 5000:
            continue
        assert same(streamed(path, chunk), whole.points)


def test_e57_stream_errors_are_the_whole_reads(tmp_path):
    """A corrupt page, and a scan whose points are all at one place, give the whole read's
    error when streamed."""
    for bad in (TESTS / "e57" / "corrupt_crc.e57", TESTS / "e57" / "bad-crc.e57"):
        with pytest.raises(FileFormatError) as whole:
            read_cloud(bad)
        with pytest.raises(FileFormatError) as part:
            streamed(bad, 50)
        assert "E57" in str(part.value) and str(whole.value).split(" (")[0] == str(part.value).split(" (")[0]
    pye57 = pytest.importorskip("pye57")
    n = 2651
    f = tmp_path / "zero.e57"
    w = pye57.E57(str(f), mode="w")
    zero = np.zeros(n)
    w.write_scan_raw({"cartesianX": zero + 1, "cartesianY": zero, "cartesianZ": zero})
    w.close()
    with pytest.raises(FileFormatError) as whole:
        read_cloud(f)
    with pytest.raises(FileFormatError) as part:
        streamed(f, 100)
    assert str(part.value) == str(whole.value) and f"all {n} points are at one place" in str(part.value)


@pytest.mark.parametrize("chunk", [1, 13, 997, 10**6])
def test_datum_moments_stream_to_the_whole_reads_bits(chunk):
    """The 3-2-1 datums keep their regions' hull vertices and moments, not their points:
    the moments summed chunk by chunk are the whole region's bits, and the centroid,
    scatter and axes they give match numpy's of all the points."""
    from gagekit import _core
    from gagekit.cloud.regions import Box
    from gagekit.cloud.streamed import cut_stream
    from gagekit.gage.align import DatumStats

    rng = np.random.default_rng(3)
    pts = rng.normal([500.0, -200.0, 70.0], [3.0, 1.0, 0.01], (5000, 3))
    box = Box((500.0, -200.0, 70.0), (8.0, 4.0, 1.0), name="d")
    inside = pts[np.all(np.abs(pts - [500.0, -200.0, 70.0]) <= [4.0, 2.0, 0.5], axis=1)]
    whole = _core.cloud.point_moments(inside)
    p = cut_stream([pts[i:i + chunk] for i in range(0, len(pts), chunk)], [box], ["hull"], moments=[True])
    assert p["d"].moments.tobytes() == whole.tobytes()
    st = DatumStats.of_moments([whole])
    assert st.n == len(inside)
    assert np.allclose(st.mean, inside.mean(axis=0), rtol=0, atol=1e-11)
    q = inside - inside.mean(axis=0)
    assert np.allclose(st.scatter, q.T @ q, rtol=1e-10, atol=1e-9)
    sv, vt = st.axes()
    _, sv_np, vt_np = np.linalg.svd(q, full_matrices=False)
    assert np.allclose(sv, sv_np, rtol=1e-9)
    assert np.allclose(np.abs(vt @ vt_np.T), np.eye(3), atol=1e-9)


@pytest.mark.parametrize("in_cut", [1 << 18, 200, 1])
def test_hull_regions_rehulled_midway_equal_the_whole_read(monkeypatch, in_cut):
    """A hull region's points are hulled whenever REHULL of them pile up (with the vertices
    kept so far), and in the chunk's cut when it holds HULL_IN_CUT of them: with REHULL at
    64 points, many such rounds in each pass, and every region, some or none hulled in
    the cut, the streamed gage check is still the whole read's, bit for bit."""
    from gagekit.cloud import streamed
    from gagekit.gage.analysis import check_gages, check_gages_stream

    monkeypatch.setattr(streamed, "REHULL", 64)
    monkeypatch.setattr(streamed, "HULL_IN_CUT", in_cut)
    path, spec = DATA / "casting_ok.ply", DATA / "casting_ok.toml"
    whole = check_gages(read_cloud(path).points, spec).to_dict()
    assert check_gages_stream(open_cloud(path, chunk=4999), spec).to_dict() == whole


def test_a_reused_ply_chunk_is_valid_until_the_next_is_read():
    """The reusing PLY stream's contract (READ_AHEAD + 1 buffers in turn, the next ones
    filled in a thread while the consumer holds this one): each chunk holds its own points as long as the
    consumer holds it, and a chunk held past the next one's read is overwritten by a
    later chunk (so a consumer that keeps points must copy them, as ``cut_stream`` does)."""
    whole = read_cloud(DATA / "bracket.ply").points
    s = open_cloud(DATA / "bracket.ply", chunk=997).reusing()
    chunks, copies = [], []
    for c in s:
        # this chunk is intact while it is held, though the next is being read meanwhile
        assert same(c, whole[997 * len(copies):997 * len(copies) + len(c)])
        chunks.append(c)
        copies.append(c.copy())
    assert len(chunks) > 3 and same(np.vstack(copies), whole)
    # chunk i and chunk i + READ_AHEAD + 1 share a buffer: the held chunk 0 now shows a later chunk
    assert READ_AHEAD == 2 and len(chunks) > READ_AHEAD + 1
    assert np.shares_memory(chunks[0], chunks[3])
    assert not any(np.shares_memory(chunks[0], chunks[j]) for j in (1, 2))
    assert not same(chunks[0], copies[0])


@pytest.mark.parametrize("ahead", [1, 2])
def test_read_ahead_reads_the_next_chunks_while_this_one_is_held(ahead):
    """``_read_ahead`` yields (i, read(i)) in order until read(i) reads no point (its
    (offset, points) pair has 0 points), and has already started read(i + 1) ...
    read(i + ahead), in order, when it hands out i (not read(i + ahead + 1), whose buffer
    is chunk i's)."""
    import threading

    from gagekit.cloud.stream import _read_ahead

    started, sizes = [], [5, 3, 2, 0, 7, 1]
    reading = [threading.Event() for _ in sizes]

    def read(i):
        started.append(i)
        reading[i].set()
        return 8 * i, sizes[i]

    got = []
    for i, k in _read_ahead(read, ahead):
        assert reading[i + ahead].wait(5), f"read({i + ahead}) did not start while chunk {i} was held"
        assert not reading[i + ahead + 1].is_set()
        got.append((i, k))
    assert got == [(0, (0, 5)), (1, (8, 3)), (2, (16, 2))] and started == list(range(3 + ahead))


@pytest.mark.parametrize("chunk", [1, 97, 4999])
def test_a_backward_pass_keeps_what_a_forward_pass_keeps(tmp_path, chunk, monkeypatch):
    """A pass from the end of the file back (binary PLY; the gage check's second pass)
    keeps the same hull vertices and points, in the same ascending order, the same counts
    and inside numbers and the same picture sample as a forward pass, at any chunk size,
    with hulls re-made midway; exact duplicate points keep their lowest number (the
    cloud is written twice over, so every point has a twin)."""
    from gagekit.cloud import streamed
    from gagekit.cloud.regions import Box
    from gagekit.cloud.streamed import cut_stream

    monkeypatch.setattr(streamed, "REHULL", 300)
    pts = np.ascontiguousarray(read_cloud(DATA / "casting_ok.ply").points[::40])
    pts = np.vstack([pts, pts[::-1]])
    path = tmp_path / "twice.ply"
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(pts)}\nproperty double x\n"
              "property double y\nproperty double z\nend_header\n")
    path.write_bytes(header.encode() + pts.astype("<f8").tobytes())
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    mid = (lo + hi) / 2
    boxes = [Box(tuple(mid), tuple((hi - lo) * 0.6), name="a"),
             Box(tuple(lo + (hi - lo) * 0.3), tuple((hi - lo) * 0.5), rotation=(0.1, 0.2, 0.3), name="b")]
    s = open_cloud(path, chunk=chunk)
    assert s.backward() is not None
    args = dict(all_indices=True, sample=50, seed=4)
    fwd = cut_stream(s, boxes, ["hull", "all"], **args)
    back = cut_stream(s, boxes, ["hull", "all"], backward=True, **args)
    assert back.count == fwd.count == len(pts)
    for f, b in zip(fwd.regions, back.regions):
        assert b.count == f.count > 0
        assert np.array_equal(b.index_array(), f.index_array())
        assert np.all(np.diff(b.index_array()) > 0)
        assert b.point_array().tobytes() == f.point_array().tobytes()
        assert np.array_equal(np.concatenate(b.all_indices), np.concatenate(f.all_indices))
        assert b.sample_points().tobytes() == f.sample_points().tobytes()
    # every chunk's hull made in its cut (no inside numbers asked for): the same vertices,
    # duplicates' lowest numbers, samples, both ways
    monkeypatch.setattr(streamed, "HULL_IN_CUT", 1)
    for way in (False, True):
        got = cut_stream(s, boxes, ["hull", "all"], sample=50, seed=4, backward=way)
        for f, g in zip(fwd.regions, got.regions):
            assert g.count == f.count
            assert np.array_equal(g.index_array(), f.index_array())
            assert g.point_array().tobytes() == f.point_array().tobytes()
            assert g.sample_points().tobytes() == f.sample_points().tobytes()
    # the moments need file order: a pass summing them reads forward
    assert cut_stream(s, boxes[:1], ["hull"], moments=[True], backward=True)["a"].moments.tobytes() == \
        cut_stream(s, boxes[:1], ["hull"], moments=[True])["a"].moments.tobytes()


@pytest.mark.parametrize("chunk", [333, 4999, 10**7])
def test_reads_past_the_page_cache_equal_the_buffered_reads(tmp_path, chunk, monkeypatch):
    """A float64 PLY read past the page cache (O_DIRECT: what a file larger than half the
    memory gets) gives the buffered read's chunks, forward and from the end back, and the
    same gage check to the bit (the header padded to a multiple of 8 bytes, so the points
    can land in place); also with chunks larger than the file (buffers for its points only).
    A read buffer smaller than ``direct_buffer_len`` of the points read is refused."""
    from gagekit import _core
    from gagekit.gage.analysis import check_gages_stream

    pts = read_cloud(DATA / "casting_ok.ply").points
    header = (f"ply\nformat binary_little_endian 1.0\ncomment c\nelement vertex {len(pts)}\nproperty double x\n"
              "property double y\nproperty double z\nend_header\n")
    header = header.replace("comment c", "comment c" + " " * (-len(header) % 8))
    path = tmp_path / "direct.ply"
    path.write_bytes(header.encode() + pts.astype("<f8").tobytes())
    spec = DATA / "casting_ok.toml"
    buffered = _core.cloud.ply_chunks(str(path), direct=False)
    assert not buffered.direct
    want_chunks = [c.copy() for c in open_cloud(path, chunk=chunk).reusing()]
    want_back = [(k, c.copy()) for k, c in open_cloud(path, chunk=chunk).backward()]
    want = check_gages_stream(open_cloud(path, chunk=chunk), spec).to_dict()

    made = []
    real = _core.cloud.ply_chunks

    def direct(p, direct=None):
        made.append(real(p, direct=True))
        return made[-1]

    monkeypatch.setattr(_core.cloud, "ply_chunks", direct)
    got_chunks = [c.copy() for c in open_cloud(path, chunk=chunk).reusing()]
    assert made and all(s.direct for s in made)  # ext4, the tests' file system, has O_DIRECT
    assert len(got_chunks) == len(want_chunks) and all(same(a, b) for a, b in zip(got_chunks, want_chunks))
    got_back = [(k, c.copy()) for k, c in open_cloud(path, chunk=chunk).backward()]
    assert [k for k, _ in got_back] == [k for k, _ in want_back]
    assert all(same(a, b) for (_, a), (_, b) in zip(got_back, want_back))
    assert check_gages_stream(open_cloud(path, chunk=chunk), spec).to_dict() == want
    s = real(str(path), direct=True)
    with pytest.raises(InvalidInputError, match="expected at least"):
        s.next_direct(np.empty(_core.cloud.direct_buffer_len(100) - 1, dtype=np.uint8), 100)
    at, k = s.next_direct(np.empty(_core.cloud.direct_buffer_len(100), dtype=np.uint8), 100)
    assert k == 100


@pytest.mark.parametrize("shell", [0.1, 1e-9])
def test_a_one_pass_gage_check_equals_the_whole_read(monkeypatch, shell):
    """With a first chunk that holds the datum regions, the streamed gage check reads the
    file once: the part-frame gage regions are cut in the datum pass around the boxes the
    first chunk's alignment puts them at (hull vertices of a shrunk core, every point of a
    shell around it), and joined once the whole file's alignment is known. The result is
    the whole read's, bit for bit; with a shell too thin to hold the fitted boxes it falls
    back to the second pass, with the same result. The guess's chunk is read once: the
    pass goes on from it."""
    from gagekit.cloud import streamed
    from gagekit.gage import analysis
    from gagekit.gage.analysis import check_gages, check_gages_stream

    monkeypatch.setattr(streamed, "REHULL", 500)
    monkeypatch.setattr(analysis, "SHELL_MM", shell)
    passes = []
    cut = streamed.cut_stream
    monkeypatch.setattr(streamed, "cut_stream", lambda c, b, *a, **k: passes.append(len(b)) or cut(c, b, *a, **k))
    path, spec = DATA / "casting_ok.ply", DATA / "casting_ok.toml"
    whole = check_gages(read_cloud(path).points, spec).to_dict()
    n = open_cloud(path).count
    stream = open_cloud(path, chunk=n // 3 + 1)
    reads = []
    reusing, backward = stream.reusing, stream.backward

    def counted(source):
        def chunks():
            for c in source():
                reads.append(1)
                yield c
        return chunks

    monkeypatch.setattr(stream, "reusing", counted(reusing))
    monkeypatch.setattr(stream, "backward", counted(backward))
    assert check_gages_stream(stream, spec).to_dict() == whole
    # the first chunk's guess, then one pass with the datum, core and shell boxes; a second
    # pass over the gage regions only when the shell is too thin
    assert len(passes) == (2 if shell == 0.1 else 3)
    # three chunks a pass; the guess's is not read again
    assert len(reads) == (3 if shell == 0.1 else 6)


@pytest.mark.parametrize("in_cut", [1 << 18, 1])
def test_the_streamed_sample_is_the_bottom_k_of_every_inside_point(monkeypatch, in_cut):
    """A region's picture sample, streamed in chunks with the keys filtered in Rust below
    the largest held (drawn in the chunk's cut, whether the cut hulls the region or not),
    holds the ``sample`` points of the smallest keys among every inside point, as keying
    the whole region at once; the keys are the SplitMix64 numpy form's bits, also for
    numbers above 2^32 and a negative seed."""
    from gagekit.cloud import streamed
    from gagekit.cloud.regions import Box, classify
    from gagekit.cloud.streamed import cut_stream, sample_keys

    monkeypatch.setattr(streamed, "HULL_IN_CUT", in_cut)

    ids = np.array([0, 1, 7, 2**32 + 5, 2**40 + 3, 2**62 + 11], dtype=np.int64)
    for seed in (0, 4, -3, 2**70 + 1):
        with np.errstate(over="ignore"):
            z = ids.astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15) + np.uint64((seed * 0xD1B54A32D192ED03 + 1) % (1 << 64))
            z ^= z >> np.uint64(30)
            z *= np.uint64(0xBF58476D1CE4E5B9)
            z ^= z >> np.uint64(27)
            z *= np.uint64(0x94D049BB133111EB)
            z ^= z >> np.uint64(31)
        assert sample_keys(seed, ids).tobytes() == ((z >> np.uint64(11)).astype(np.float64) * (1.0 / (1 << 53))).tobytes()
    pts = np.ascontiguousarray(read_cloud(DATA / "casting_ok.ply").points[::7])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    box = Box(tuple((lo + hi) / 2), tuple((hi - lo) * 0.7), rotation=(0.1, 0.2, 0.3), name="a")
    inside = classify(pts, [box])[0]
    for size, chunk in [(50, 997), (50, 31), (len(inside) + 5, 4001)]:
        p = cut_stream([pts[i:i + chunk] for i in range(0, len(pts), chunk)], [box], ["hull"], sample=size, seed=9)
        want = np.sort(inside[np.argsort(sample_keys(9, inside), kind="stable")[:size]])
        r = p["a"]
        assert np.array_equal(np.sort(r.sample_idx), want)
        assert r.sample_points().tobytes() == pts[want].tobytes()
