"""Point clouds read in chunks of bounded size (issue 29): the cost of a check grows with
the points inside its regions, not with the file.

:func:`open_cloud` returns a :class:`CloudStream`: iterating it reads the file once, in
order, as (m, 3) float64 arrays in millimetres, each exactly the rows :func:`read_cloud`
returns for those points (the same parser, the same unit factor applied the same way, the
same error for a bad point, naming its line, vertex or row in the whole file). Iterating
again reads the file again (a second pass).

========================  =====================================================================
format                    how it streams
========================  =====================================================================
XYZ/CSV/TXT/ASC/PTS/.ds   Rust ``AsciiStream``: blocks cut after a line break, each parsed in
                          parallel; the layout (separators, header columns) read once from the
                          top. ``.ds``: the count line is checked at the end.
PLY binary                Rust ``PlyStream``: ranges of vertex records by positioned reads,
                          decoded in parallel (every element of fixed-size records: the
                          header's sizes are checked first, as a whole read checks them).
                          A float64 file larger than half the memory is read past the page
                          cache (O_DIRECT) straight into the chunk's buffer.
PLY ASCII                 Rust ``PlyAsciiStream``: a first pass counts the body's lines against
                          the header (the whole read's check), then blocks of vertex lines,
                          each parsed in parallel (faces after the vertices are not read).
.npy                      ``numpy.fromfile`` of row ranges (C order); Fortran order by slices
                          of a memory map.
LAS/LAZ                   ``laspy``'s chunk iterator (LAZ decompressed chunk by chunk).
E57                       Rust ``E57Stream``: data packet by data packet, the coordinate fields'
                          bit streams decoded a chunk at a time (positioned reads through an
                          8 MB window, page CRCs checked); files it does not handle (a scan
                          without a coordinate triple...) are read whole.
binary PLY with faces     read whole, then handed out in chunks: memory is that of a whole read.
========================  =====================================================================

Memory: :func:`memory_budget` (``--memory``; default :data:`DEFAULT_MEMORY_FRACTION` of the
machine's RAM) and :func:`whole_read_bytes` decide whether a command reads the whole file or
streams it (:func:`should_stream`), and how many points a chunk holds (:func:`chunk_points`).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterator, Optional, Union

import numpy as np

from .. import _core
from .._util import check_finite
from ..errors import FileFormatError, InvalidInputError
from . import units as _units
from .formats import Raw

PathLike = Union[str, os.PathLike]

DEFAULT_MEMORY_FRACTION = 0.125
"""Share of the machine's RAM a command may use for points when ``--memory`` is not given."""

BYTES_PER_POINT = 24
"""float64 x, y, z"""

__all__ = ["CloudStream", "open_cloud", "memory_budget", "whole_read_bytes", "should_stream", "chunk_points",
           "DEFAULT_MEMORY_FRACTION"]


def total_ram() -> int:
    """Bytes of physical memory (8 GiB when the system does not tell)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 8 << 30


_SIZE = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*([kmgt]?)i?b?\s*$", re.IGNORECASE)


def memory_budget(memory: Union[str, int, float, None] = None) -> int:
    """Bytes a command may hold in points: ``memory`` as a number of bytes or a size such as
    ``"4G"``, ``"512M"``, ``"1.5GB"`` (powers of 1024), or by default
    :data:`DEFAULT_MEMORY_FRACTION` of the RAM. At least 64 MiB."""
    if memory is None:
        return max(64 << 20, int(total_ram() * DEFAULT_MEMORY_FRACTION))
    if isinstance(memory, (int, float)) and not isinstance(memory, bool):
        value = float(memory)
    else:
        m = _SIZE.match(str(memory))
        if not m:
            raise InvalidInputError(f"memory: expected a size such as 4G, 512M or 2000000000, got {memory!r}")
        value = float(m.group(1)) * 1024 ** "kmgt".find(m.group(2).lower()) * (1024 if m.group(2) else 1) \
            if m.group(2) else float(m.group(1))
    if not np.isfinite(value) or value < (64 << 20):
        raise InvalidInputError(f"memory: {memory!r} is less than 64M; give at least 64M")
    return int(value)


def chunk_points(memory: int) -> int:
    """Points per chunk for a budget of ``memory`` bytes: a sixteenth of it in float64
    points (the chunk, its unit conversion and the region copies stay well inside), between
    2^16 and 2^23."""
    return int(min(1 << 23, max(1 << 16, memory // (16 * BYTES_PER_POINT))))


def whole_read_bytes(path: PathLike) -> int:
    """What reading the whole file would hold in points (bytes), from its header where the
    format has a count (PLY, .npy, E57 records, LAS), else its size (text: about one byte
    of file per byte of float64)."""
    p = Path(path)
    try:
        size = p.stat().st_size
    except OSError:
        return 0  # the reader words the error (missing, no permission...)
    suffix = p.suffix.lower()
    try:
        if suffix == ".ply":
            return _ply_head(p)[0] * BYTES_PER_POINT
        if suffix == ".npy":
            shape, _, _, _ = _npy_header(p)
            return BYTES_PER_POINT * int(shape[0]) if shape else size
        if suffix == ".e57":  # records from the XML: scaled integers take a third of float64's bytes
            s = _core.cloud.e57_chunks(str(p))
            return BYTES_PER_POINT * int(s.records) if s is not None else size
    except (FileFormatError, InvalidInputError, OSError, ValueError):
        return size
    return size


def should_stream(path: PathLike, memory: Optional[int]) -> bool:
    """Whether a command should stream ``path`` rather than read it whole: when the whole
    read would take more than half the budget (the other half is for the work on it)."""
    budget = memory_budget(memory)
    return whole_read_bytes(path) > budget // 2


def _ply_head(p: Path) -> tuple[int, str]:
    """The vertex count and the format word of a PLY header (a guess for sizing only;
    the Rust reader checks the header)."""
    with open(p, "rb") as fh:
        head = fh.read(1 << 16)
    m = re.search(rb"element\s+vertex\s+([0-9]+)", head)
    f = re.search(rb"format\s+(\S+)", head)
    return (int(m.group(1)) if m else p.stat().st_size // BYTES_PER_POINT,
            f.group(1).decode("ascii", "replace") if f else "binary")


@dataclass
class CloudStream:
    """A point-cloud file read chunk by chunk, in millimetres (see the module docstring).

    ``count`` is the number of points when the header tells it before reading (PLY, .npy,
    LAS), else None; :attr:`points_read` counts what the last full pass read."""

    path: str
    format: str
    source_unit: str
    scale_to_mm: float
    unit_basis: str
    z_scale_to_mm: float
    count: Optional[int]
    chunk_points: int
    warnings: tuple = ()
    _raw_chunks: Callable[[], Iterator[np.ndarray]] = field(repr=False, default=None)  # type: ignore[assignment]
    _finite_checked: bool = field(repr=False, default=True)
    _at_end: Optional[Callable[[int], None]] = field(repr=False, default=None)
    _reuse: bool = field(repr=False, default=False)
    points_read: Optional[int] = None

    def reusing(self) -> "CloudStream":
        """The same stream, whose chunks may share one buffer: each chunk is valid until
        the next is read (no fresh memory a chunk; for consumers that copy what they keep,
        as :func:`~gagekit.cloud.streamed.cut_stream` does)."""
        return replace(self, _reuse=True)

    def _ready(self, raw: np.ndarray, start: int) -> np.ndarray:
        """A raw chunk whose first point is number ``start``, checked finite (where the
        reader did not) and scaled to millimetres in place."""
        pts = np.require(raw, np.float64, ["C_CONTIGUOUS", "WRITEABLE"])
        if not self._finite_checked:
            _check_finite_from(pts, start, self.path)
        scale = [self.scale_to_mm, self.scale_to_mm, self.z_scale_to_mm]
        if scale != [1.0, 1.0, 1.0] and len(pts):
            _scale_from(pts, scale, start, self.path)
        return pts

    def __iter__(self) -> Iterator[np.ndarray]:
        n = 0
        source = self._raw_chunks
        if self._reuse:
            source = getattr(source, "reusing", source)
        for raw in source():
            pts = self._ready(raw, n)
            n += len(pts)
            if len(pts):
                yield pts
        if n == 0:
            raise FileFormatError(f"{self.path}: the file holds no points")
        if self._at_end is not None:
            self._at_end(n)
        self.points_read = n

    def backward(self) -> Optional[Iterator[tuple[int, np.ndarray]]]:
        """The chunks from the end of the file back, as (number of the chunk's first point,
        chunk), in one reused buffer like :meth:`reusing`'s, or None when the format reads
        only forward (binary PLY reads any range). A second pass over a file larger than
        the page cache finds the end of the file, read last by the pass before, still
        cached. The same rows as a forward pass, unit factor and checks applied alike."""
        source = getattr(self._raw_chunks, "backward", None)
        if source is None:
            return None

        def chunks() -> Iterator[tuple[int, np.ndarray]]:
            for start, raw in source():
                pts = self._ready(raw, start)
                if len(pts):
                    yield start, pts

        return chunks()


def _check_finite_from(pts: np.ndarray, offset: int, what: str) -> None:
    try:
        check_finite(pts, what)
    except InvalidInputError:
        bad = ~np.isfinite(pts)
        row = int(np.argmax(bad.any(axis=1)))
        raise InvalidInputError(f"{what}: point {offset + row} has a non-finite coordinate {pts[row].tolist()} "
                                "(NaN or inf)") from None


def _scale_from(pts: np.ndarray, scale: list, offset: int, what: str) -> None:
    try:
        _core.cloud.scale_in_place(pts, scale, what)
    except InvalidInputError as exc:
        m = re.search(r"point ([0-9]+) overflows", str(exc))
        if m is None:
            raise
        raise InvalidInputError(str(exc).replace(m.group(0), f"point {offset + int(m.group(1))} overflows")) from None


def open_cloud(path: PathLike, units: Optional[str] = None, *, chunk: Optional[int] = None,
               memory: Union[str, int, None] = None) -> CloudStream:
    """Open a point-cloud file for reading in chunks of ``chunk`` points (default from the
    ``memory`` budget, :func:`chunk_points`). Same formats, units and errors as
    :func:`~gagekit.cloud.read_cloud`; 3-D points only."""
    from .._files import input_file
    from .io import ASCII_SUFFIXES, _BINARY, _sniff, _unit_of

    override = _units.check_units(units)
    p = input_file(path, "point cloud file")
    suffix = p.suffix.lower()
    if suffix not in ASCII_SUFFIXES and suffix not in _BINARY:
        suffix = _sniff(p)
    m = int(chunk) if chunk is not None else chunk_points(memory_budget(memory))
    if m < 1:
        raise InvalidInputError(f"chunk: expected a positive number of points, got {chunk}")
    info, chunks, count, finite, at_end = _open_format(p, suffix, m)
    unit, z_unit, basis, warns = _unit_of(info, p, override)
    return CloudStream(str(p), info.format, unit, _units.scale_to_mm(unit), basis, _units.scale_to_mm(z_unit),
                       count, m, tuple(warns), chunks, finite, at_end)


def _open_format(p: Path, suffix: str, m: int):
    """(Raw without points: format and unit; chunk generator factory; count or None;
    finite already checked; check at the end of a pass or None)."""
    from .io import ASCII_SUFFIXES
    from .formats import e57, las, ply

    empty = np.empty((0, 3))
    if suffix in ASCII_SUFFIXES:
        nist = suffix == ".ds"
        block = max(1 << 16, m * 32)  # about one point per 32 bytes of text

        def text_chunks() -> Iterator[np.ndarray]:
            s = _core.cloud.ascii_chunks(str(p), 3, 1 if nist else 0, block)
            while (c := s.next_chunk()) is not None:
                yield c

        return (Raw(empty, "nist-ds" if nist else "ascii"), text_chunks, None, True,
                (lambda n: _nist_count(p, n)) if nist else None)
    if suffix == ".ply":
        s0 = _core.cloud.ply_chunks(str(p))
        if s0 is not None:
            def ply_chunks() -> Iterator[np.ndarray]:
                s = _core.cloud.ply_chunks(str(p))
                while s is not None and (c := s.next_chunk(m)) is not None:
                    yield c

            count = int(s0.count)
            held: list = []

            def buffers() -> tuple:
                # READ_AHEAD + 1 byte buffers in turn, made once and kept for every pass
                # (fresh pages cost more than the copy into them): the next chunks are
                # read (in a thread, no GIL held) while the consumer uses this one, which
                # stays valid until it asks for the next. Room for whole aligned blocks around
                # the points: a file larger than the page cache is read past it
                # (O_DIRECT, PlyStream.next_direct), straight into the buffer
                if not held:
                    size = min(m, max(1, count))
                    held.extend(np.empty(_core.cloud.direct_buffer_len(size), dtype=np.uint8) for _ in range(READ_AHEAD + 1))
                return tuple(held)

            def points_at(buf: np.ndarray, got: tuple) -> np.ndarray:
                at, k = got
                return buf[at:at + 24 * k].view(np.float64).reshape(k, 3)

            def ply_chunks_reused() -> Iterator[np.ndarray]:
                s = _core.cloud.ply_chunks(str(p))
                bufs = buffers()
                for i, got in _read_ahead(lambda i: s.next_direct(bufs[i % len(bufs)], m)):
                    yield points_at(bufs[i % len(bufs)], got)

            def ply_chunks_backward() -> Iterator[tuple[int, np.ndarray]]:
                s = _core.cloud.ply_chunks(str(p))
                bufs = buffers()
                starts = list(range(0, count, m))[::-1]

                def read(i: int) -> tuple:
                    if i >= len(starts):
                        return (0, 0)
                    s.seek(starts[i])
                    return s.next_direct(bufs[i % len(bufs)], min(m, count - starts[i]))

                for i, got in _read_ahead(read):
                    yield starts[i], points_at(bufs[i % len(bufs)], got)

            ply_chunks.reusing = ply_chunks_reused  # type: ignore[attr-defined]
            ply_chunks.backward = ply_chunks_backward  # type: ignore[attr-defined]
            return Raw(empty, f"ply {_ply_head(p)[1]}"), ply_chunks, int(s0.count), True, None
        a0 = _core.cloud.ply_ascii_chunks(str(p))
        if a0 is not None:
            def ply_ascii_chunks() -> Iterator[np.ndarray]:
                s = _core.cloud.ply_ascii_chunks(str(p))
                while s is not None and (c := s.next_chunk(m)) is not None:
                    yield c

            return Raw(empty, "ply ascii"), ply_ascii_chunks, int(a0.count), True, None
        raw = ply.read(p, 3)
        return _whole(raw, m)
    if suffix == ".npy":
        return _npy(p, m)
    if suffix in (".las", ".laz"):
        return _las(p, m)
    if suffix == ".e57":
        return _e57(p, m)
    raise FileFormatError(f"{p}: cannot stream '{suffix}' files")  # pragma: no cover - suffixes above are all


READ_AHEAD = 2
"""Chunks of a binary PLY read ahead of the one in use (each in a buffer of its own). With
one, the disk waits whenever a chunk's work takes longer than its read (a hull of the
piled-up points of a region, the other programs on the cores), and the cores wait on the
next slow read: the pass takes the sum of the slower of the two chunk by chunk. With two,
a slow chunk on one side is made up by fast ones on the other."""


def _read_ahead(read: Callable[[int], tuple], ahead: int = READ_AHEAD) -> Iterator[tuple[int, tuple]]:
    """(i, read(i)) for i = 0, 1, ... until read(i) reads no point ((offset, points
    read) pairs, 0 points at the end), with read(i + 1) ... read(i + ahead) running in
    order in a thread while the consumer holds (i, read(i)): the file's reading overlaps
    the work on the chunks before (the disk and the page-cache copies run while the
    cores classify). read(i + ahead) starts once the consumer has asked for chunk i (so
    done with chunk i - 1: its buffer may be reused)."""
    from collections import deque
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(1, thread_name_prefix="gagekit-read-ahead") as ex:
        futs = deque(ex.submit(read, j) for j in range(ahead))
        i = 0
        while (k := futs.popleft().result())[1]:
            futs.append(ex.submit(read, i + ahead))
            yield i, k
            i += 1


def _whole(raw: Raw, m: int):
    """A format read whole, handed out in chunks of ``m`` points."""
    pts = raw.points
    info = Raw(np.empty((0, 3)), raw.format, raw.unit, raw.unit_basis, raw.z_unit, raw.scans, raw.invalid_dropped,
               list(raw.warnings), raw.finite_checked)

    def chunks() -> Iterator[np.ndarray]:
        for i in range(0, len(pts), m):
            yield np.array(pts[i:i + m], dtype=np.float64)  # a copy: the unit factor is applied in place

    return info, chunks, len(pts), raw.finite_checked, None


def _e57(p: Path, m: int):
    """E57 data packet by data packet (Rust ``E57Stream``), with the whole read's checks:
    no scans, a non-finite point, every point at one place (checked on the whole pass)."""
    from .formats import e57

    s0 = _core.cloud.e57_chunks(str(p))
    if s0 is None:
        return _whole(e57.read(p, 3), m)
    if s0.scans == 0:
        raise FileFormatError(f"{p}: the E57 file holds no scans")
    info = Raw(np.empty((0, 3)), "e57", unit="m", unit_basis="E57 standard (ASTM E2807): metres", scans=s0.scans)

    def chunks() -> Iterator[np.ndarray]:
        s = _core.cloud.e57_chunks(str(p))
        first, spread, n = None, False, 0
        while (c := s.next_chunk(m)) is not None:
            if len(c):
                if first is None:
                    first = c[0].copy()
                spread = spread or bool((c != first).any())
                n += len(c)
            yield c
        if n > 1 and not spread:
            raise e57.at_one_place(p, n, first)
        info.invalid_dropped = s.invalid_dropped

    return info, chunks, None, True, None


def _nist_count(p: Path, n: int) -> None:
    with p.open("rb") as fh:
        first = fh.readline().split()
    try:
        count = int(first[0])
    except (IndexError, ValueError):
        raise FileFormatError(f"{p}: line 1: a NIST .ds file starts with the point count") from None
    if count != n:
        raise FileFormatError(f"{p}: line 1 announces {count} points but the file holds {n}")


def _npy_header(p: Path):
    with open(p, "rb") as fh:
        version = np.lib.format.read_magic(fh)
        read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, fortran, dtype = read(fh)
        return shape, fortran, dtype, fh.tell()


def _npy(p: Path, m: int):
    from .formats import npy

    try:
        shape, fortran, dtype, offset = _npy_header(p)
    except Exception:  # the whole reader words the error
        return _whole(npy.read(p, 3), m)
    if fortran or dtype.kind not in "fiu" or len(shape) != 2 or shape[1] < 3 or dtype.hasobject \
            or p.stat().st_size < offset + shape[0] * shape[1] * dtype.itemsize:
        return _whole(npy.read(p, 3), m)
    n, ncols = int(shape[0]), int(shape[1])

    def chunks() -> Iterator[np.ndarray]:
        with open(p, "rb") as fh:
            for i in range(0, n, m):
                k = min(m, n - i)
                fh.seek(offset + i * ncols * dtype.itemsize)
                rows = np.fromfile(fh, dtype=dtype, count=k * ncols).reshape(k, ncols)
                yield np.ascontiguousarray(rows[:, :3], dtype=np.float64)

    return Raw(np.empty((0, 3)), "npy"), chunks, n, False, None


def _las(p: Path, m: int):
    from .formats.las import _check_scales, _crs_unit

    try:
        import laspy
    except ImportError:
        raise FileFormatError(f"{p}: LAS/LAZ needs the optional extra: pip install 'gagekit[las]'") from None

    def bad(exc: Exception) -> FileFormatError:
        msg = str(exc)
        if "LazBackend" in msg:
            msg = "no LAZ decompressor; pip install 'gagekit[las]' (laspy with lazrs)"
        return FileFormatError(f"{p}: not a readable LAS/LAZ file ({msg})")

    try:
        with laspy.open(str(p)) as r:
            header = r.header
            vlrs = list(header.vlrs) + list(getattr(r, "evlrs", None) or getattr(header, "evlrs", None) or [])
            count = int(header.point_count)
    except Exception as exc:  # laspy raises LaspyException, ValueError, OSError... for bad files
        raise bad(exc) from None
    _check_scales(header, p)
    info = Raw(np.empty((0, 3)), "laz" if p.suffix.lower() == ".laz" else "las")
    _crs_unit(vlrs, info, p)

    def chunks() -> Iterator[np.ndarray]:
        try:
            with laspy.open(str(p)) as r:
                for pts in r.chunk_iterator(m):
                    out = np.empty((len(pts), 3))
                    out[:, 0], out[:, 1], out[:, 2] = pts.x, pts.y, pts.z
                    yield out
        except FileFormatError:
            raise
        except Exception as exc:
            raise bad(exc) from None

    return info, chunks, count, False, None
