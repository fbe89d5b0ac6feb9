"""Region-first evaluation of a streamed cloud (issue 29, Sec. 5.4.1): each chunk is
classified into the regions (one Rust pass over the chunk), and only the points inside
regions are kept; where the evaluation needs only the convex-hull vertices (the LP of
Eq. 5.11: a linear constraint that holds at the hull vertices holds everywhere), a
region's points are hull-filtered in the chunk's cut when the chunk holds at least
:data:`HULL_IN_CUT` of them, else whenever :data:`REHULL` of them have piled up (with the
vertices kept so far), and at the end. The hull of the union is the hull of the union of
the hulls, and the exact predicates keep the same extreme points (the lowest index among
duplicates), so the vertices kept, and their order (ascending point number), are those of
a whole read.

Memory: a chunk, plus the kept points of each region (every point for ``keep="all"``,
hull vertices and at most :data:`REHULL` pending points for ``keep="hull"``).
"""

from __future__ import annotations

from collections import deque
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Iterable, Optional, Sequence

import numpy as np

from .. import _core
from .._util import as_points
from .hull import convex_hull_indices
from .regions import Box

REHULL = 1 << 20
"""Kept points of a ``keep="hull"`` region above which they are hulled during the pass."""

HULL_IN_CUT = 1 << 18
"""Points of a ``keep="hull"`` region in one chunk from which the chunk's cut hulls them
itself (in its parallel pass, beside the other regions' gathers), rather than piling them
up for a later hull (the pile's joins and hull would run beside the next chunk's cut, one
core's work while that cut waits for it)."""


@dataclass
class StreamedRegion:
    """What a pass kept of one region: ``count`` points inside; ``indices`` (point numbers
    in the file, ascending) and ``points`` of every point (``keep="all"``) or of the hull
    vertices only (``keep="hull"``, after :meth:`finish`); ``sample``: up to ``sample_size``
    points drawn uniformly (seeded bottom-k keys) for pictures."""

    name: str
    keep: str
    count: int = 0
    indices: list = field(default_factory=list)
    points: list = field(default_factory=list)
    all_indices: Optional[list] = None
    sample_keys: Optional[np.ndarray] = None
    sample_idx: Optional[np.ndarray] = None
    sample_pts: Optional[np.ndarray] = None
    moments: Optional[np.ndarray] = None
    """the flat moments of every point inside (``_core.cloud.point_moments``), when asked for"""
    backward: bool = False
    """chunks come from the end of the file back: the lists hold descending blocks, each
    ascending, so they are joined in reverse (ascending point numbers, as forward)"""
    _pending: int = 0

    def add(self, ids: np.ndarray, pts: np.ndarray) -> None:
        """Points inside the region (their numbers ``ids``), hull-filtered here for ``keep="hull"``."""
        if self.keep == "hull" and len(ids):
            h = convex_hull_indices(pts)
            self.add_kept(len(ids), ids, ids[h], pts[h])
        else:
            self.add_kept(len(ids), ids, ids, pts)

    def add_kept(self, count: int, inside: Optional[np.ndarray], ids: np.ndarray, pts: np.ndarray) -> None:
        """What a chunk kept of the region: ``count`` points inside (their numbers
        ``inside``, needed only with ``all_indices``), ``ids`` and ``pts`` already kept
        (every inside point, or the hull vertices of them for ``keep="hull"``)."""
        self.count += count
        if self.all_indices is not None:
            self.all_indices.append(inside)
        self.indices.append(ids)
        self.points.append(pts)
        self._pending += len(ids)
        if self.keep == "hull" and self._pending > REHULL:
            self._rehull()

    def _rehull(self) -> None:
        ids, pts = self.index_array(), self.point_array()
        if len(ids):
            h = convex_hull_indices(pts)
            ids, pts = ids[h], pts[h]
        self.indices, self.points, self._pending = [ids], [pts], len(ids)

    def finish(self) -> "StreamedRegion":
        if self.keep == "hull":
            self._rehull()
        if self.backward:  # one ascending order from here on
            for blocks in (self.indices, self.points, self.all_indices):
                if blocks is not None:
                    blocks.reverse()
            self.backward = False
        return self

    def _in_order(self, blocks: list) -> list:
        return blocks[::-1] if self.backward else blocks

    def index_array(self) -> np.ndarray:
        return np.concatenate(self._in_order(self.indices)) if self.indices else np.zeros(0, dtype=np.int64)

    def point_array(self) -> np.ndarray:
        return np.ascontiguousarray(np.vstack(self._in_order(self.points))) if self.points else np.zeros((0, 3))

    def sample(self, seed: int, ids: np.ndarray, pts: np.ndarray, size: int) -> None:
        """Bottom-k sampling: every point inside (numbers ``ids``, rows of ``pts``) gets a
        seeded key (:func:`sample_keys`, a function of its number: the same sample in any
        chunk order), the ``size`` smallest stay. Once ``size`` are held, a key above the
        largest held cannot enter: only the others are kept."""
        # the keys below the largest held, in Rust (no temporaries the size of ``ids``)
        pos, keys = keys_below(seed, ids, self.sample_bound(size))
        if len(pos) < len(ids):
            ids, pts = ids[pos], pts[pos]
        self.sample_drawn(ids, keys, pts, size)

    def sample_bound(self, size: int) -> float:
        """The key below which a point may still enter a sample of ``size``: the largest
        held once ``size`` are held, else infinity."""
        keys = self.sample_keys
        return float(keys.max()) if keys is not None and len(keys) >= size else np.inf

    def sample_drawn(self, ids: np.ndarray, keys: np.ndarray, pts: np.ndarray, size: int) -> None:
        """Points (numbers ``ids``, keys, rows of ``pts``) that may enter the sample: every
        point inside whose key is below a bound at least :meth:`sample_bound` (the others
        could not enter), merged with those held, the ``size`` smallest keys kept."""
        if self.sample_keys is None:
            self.sample_keys, self.sample_idx, self.sample_pts = keys, ids, pts
        elif len(keys):
            self.sample_keys = np.concatenate([self.sample_keys, keys])
            self.sample_idx = np.concatenate([self.sample_idx, ids])
            self.sample_pts = np.vstack([self.sample_pts, pts])
        if len(self.sample_keys) > size:
            keep = np.sort(np.argpartition(self.sample_keys, size)[:size])
            self.sample_keys, self.sample_idx, self.sample_pts = (self.sample_keys[keep], self.sample_idx[keep],
                                                                  self.sample_pts[keep])

    def sample_points(self) -> np.ndarray:
        """The sampled points in file order."""
        if self.sample_idx is None:
            return np.zeros((0, 3))
        return self.sample_pts[np.argsort(self.sample_idx, kind="stable")]


def sample_keys(seed: int, ids: np.ndarray) -> np.ndarray:
    """Keys in [0, 1) of the point numbers ``ids`` for ``seed``: the SplitMix64 finalizer of
    the number mixed with the seed (53 bits), one key per point whatever the order the
    points come in (``_core.cloud.sample_keys_below``)."""
    return keys_below(seed, ids, np.inf)[1]


def keys_below(seed: int, ids: np.ndarray, below: float) -> tuple[np.ndarray, np.ndarray]:
    """(positions, keys) of the points ``ids`` whose :func:`sample_keys` key is below
    ``below``, in one pass in Rust (no temporaries the size of ``ids``)."""
    return _core.cloud.sample_keys_below(np.ascontiguousarray(ids, dtype=np.int64), seed % (1 << 64), below)


@dataclass
class Pass:
    """One pass over a stream: the number of points and what each region kept."""

    count: int
    regions: list

    def __getitem__(self, name: str) -> StreamedRegion:
        for r in self.regions:
            if r.name == name:
                return r
        raise KeyError(name)


def _reused(chunks: Iterable[np.ndarray]) -> Iterable[np.ndarray]:
    """A :class:`~gagekit.cloud.stream.CloudStream` read into one reused buffer: the
    passes here copy what they keep of a chunk before the next is read."""
    reusing = getattr(chunks, "reusing", None)
    return reusing() if callable(reusing) else chunks


def _numbered(chunks: Iterable[np.ndarray], backward: bool) -> tuple[Iterable[tuple[int, np.ndarray]], bool]:
    """(number of the first point, chunk) pairs of ``chunks``, from the end back when
    ``backward`` is asked for and the stream reads backward (``CloudStream.backward``);
    and whether they come backward."""
    back = getattr(chunks, "backward", None) if backward else None
    source = back() if callable(back) else None
    if source is not None:
        return source, True

    def forward() -> Iterable[tuple[int, np.ndarray]]:
        n = 0
        for pts in _reused(chunks):
            yield n, pts
            n += len(pts)

    return forward(), False


def cut_stream(chunks: Iterable[np.ndarray], boxes: Sequence[Box], keep: Sequence[str], *,
               all_indices: bool = False, sample: int = 0, seed: int = 0,
               moments: Optional[Sequence[bool]] = None, backward: bool = False,
               minus: Optional[Sequence[Optional[int]]] = None) -> Pass:
    """One pass over ``chunks`` ((m, 3) arrays in file order): every chunk classified into
    ``boxes``; per box ``keep`` is ``"all"`` (every point inside) or ``"hull"`` (hull
    vertices). ``all_indices`` also keeps every inside point's number (int64, 8 bytes a
    point); ``sample`` > 0 draws that many points per box (seeded) for pictures;
    ``moments`` flags the boxes whose points' moments are summed (``StreamedRegion.moments``,
    the bits of ``_core.cloud.point_moments`` of all of them: they need file order, so
    ``backward`` may not be combined with them). ``backward``: read the chunks from the
    end of the file back where the stream can (a second pass then starts on what the
    page cache holds of the first); the result is the same (the hull of a set, every
    list joined in ascending point number). ``minus[i]`` = k (a ``keep="all"`` box i):
    box i keeps only its points outside box k (a shell around box k)."""
    flags = list(moments) if moments is not None and any(moments) else []
    chunks_at, back = _numbered(chunks, backward and not flags)
    regions = [StreamedRegion(b.name, k, all_indices=[] if all_indices else None, backward=back)
               for b, k in zip(boxes, keep)]
    state = np.zeros((len(boxes), 22)) if flags else None
    rows = np.array([b.row() for b in boxes], dtype=np.float64).reshape(-1, 9)
    # a hull box's points are hulled in the cut when a chunk holds at least HULL_IN_CUT
    # of them (a large region: one parallel pass, no serial stage after it), else they
    # pile up to REHULL points and are hulled then, with the vertices kept so far (the
    # hull of the union is the hull of the union of the hulls, at any batching). A hull
    # of many points costs less a point than many hulls of a chunk's few (the
    # prefilter's fixed cost), and memory stays bounded by REHULL points a region.
    # With ``all_indices`` every inside point's number is needed: nothing is hulled in
    # the cut.
    hull = [k == "hull" and not all_indices for k in keep]

    cut_minus = list(minus) if minus and any(k is not None for k in minus) else []

    def take(start: int, cuts: list) -> None:
        # kept: every inside point, or a large hull box's hull vertices (for a box with
        # ``minus``, the points outside the other box: the cut's own); drawn: the sample
        # candidates the cut drew (keys below the bound the sample had at the cut)
        for r, (count, _, kept, kpts, drawn) in zip(regions, cuts):
            ids = kept + start
            r.add_kept(count, ids, ids, kpts)
            if drawn is not None and len(drawn[0]):
                r.sample_drawn(drawn[0] + start, drawn[1], drawn[2], sample)

    # the regions' share of chunk i (number shifts, samples, hulls of the piled-up points)
    # is taken in a thread while this one cuts chunk i + 1 (the cut holds no GIL) and the
    # read-ahead reads chunk i + 2: at most two chunks' cuts wait, in order. A sample's
    # bound read here may be that of a chunk not yet taken: larger, so the cut draws
    # more candidates, never fewer (the same sample).
    n = 0
    with ThreadPoolExecutor(1, thread_name_prefix="gagekit-regions") as ex:
        waiting: deque = deque()
        for start, pts in chunks_at:
            n += len(pts)
            if boxes:
                # one Rust call: classify, gather (and moments), parallel inside
                below = [r.sample_bound(sample) for r in regions] if sample else []
                cuts = _core.cloud.cut_chunk(as_points(pts), rows, hull, False, state, flags, cut_minus,
                                             HULL_IN_CUT, start, seed % (1 << 64), below)
                while len(waiting) >= 2:
                    waiting.popleft().result()
                waiting.append(ex.submit(take, start, cuts))
        for fut in waiting:
            fut.result()
    for k, r in enumerate(regions):
        if flags and flags[k]:
            r.moments = state[k].copy()
    # the last hulls of the piled-up points, two regions at a time (the hull holds no GIL):
    # nothing else runs after the last chunk
    with ThreadPoolExecutor(2, thread_name_prefix="gagekit-regions") as ex:
        return Pass(n, list(ex.map(StreamedRegion.finish, regions)))


def hull_stream(chunks: Iterable[np.ndarray]) -> tuple[int, np.ndarray, np.ndarray]:
    """(number of points, hull vertex numbers ascending, their points) of a streamed cloud:
    each chunk hull-filtered, then the hull of the kept vertices (Eq. 5.21)."""
    acc = StreamedRegion("cloud", "hull")
    n = 0
    for pts in _reused(chunks):
        acc.add(np.arange(n, n + len(pts), dtype=np.int64), pts)
        n += len(pts)
    acc.finish()
    return n, acc.index_array(), acc.point_array()


__all__ = ["StreamedRegion", "Pass", "cut_stream", "hull_stream", "REHULL", "HULL_IN_CUT"]
