"""Virtual-gage analysis of a scanned casting (Secs. 5.2-5.5).

1. optional 3-2-1 alignment of the scanner frame to the part frame (Eqs. 5.13-5.19);
2. the sampling regions cut from the cloud and hull-filtered (Sec. 5.4.1);
3. Eq. 5.11, min sum f_i q_i + sum g_i s_i + u subject to
   -u <= -s_i <= e_ij <= q_i, solved in Rust (clarabel) over the free motions
   within Omega (Eq. 5.2), with the exact transform
   T = [Rz(alpha) Ry(beta) Rx(gamma) | (dx, dy, dz)] and re-linearisation until T
   moves less than 1e-10 mm, so every distance reported holds for T itself;
4. per gage the allowances before and after T*, q_i, s_i; the infeasible groups
   of Eq. 5.10; the motion bounds whose multipliers are non-zero (Sec. 5.2.2).

Where Eq. 5.11 has several optimal transforms (two opposite faces whose q_i
trade one for one, as the walls of Table 5.1 do in x), the optimal transform
nearest the identity is reported (smallest motion, angles weighted by the lever
arm), so the answer is unique and reproducible. Each LP solution is moved to that
exact point of its optimal face, which also makes the re-linearisation converge
to machine precision. LPs of more than 4000 points (unfiltered regions) are
solved by constraint generation, with the same result.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Mapping, Optional, Union

import numpy as np

from .. import _core
from .._core.gage import BoundLimit, GageOutcome, Transform
from .._rotation import rotation_from_vector, rotation_vector
from .._util import LENGTH_RESOLUTION_MM, as_points, check_finite
from ..cloud.regions import Box
from ..errors import ConfigError, InvalidInputError
from .align import Alignment, DatumStats, apply, fit_321
from .spec import GageSpec

SpecLike = Union[GageSpec, str, Path, Mapping[str, Any]]
PLOT_POINTS = 4000


# --------------------------------------------------------------------------- results


@dataclass(frozen=True)
class GageCheckResult:
    """The outcome of a virtual-gage analysis (Eq. 5.11 at T*): the kernel's result
    (``_core.gage.check``: status, objective, T*, the limiting bounds, each gage's
    :class:`GageOutcome`, the infeasible groups, u, the solver's figures, assembled once
    in ``gagekit_gage::result``) with what the analysis adds: the alignment, the motion
    set, the plot data and, with an uncertainty, the decision and the Monte Carlo."""

    status: str
    """``conforming`` when every slack is zero, else ``nonconforming``"""
    objective: float
    """Eq. 5.11 at T*: sum f_i q_i + sum g_i s_i + u"""
    transform: Transform
    limited_by_motion_bounds: bool
    bound_limits: tuple[BoundLimit, ...]
    gages: tuple[GageOutcome, ...]
    infeasible_groups: tuple[tuple[str, ...], ...]
    largest_release: float
    """u of Eq. 5.11"""
    alignment: Optional[Alignment]
    iterations: int
    last_step: float
    lp_status: str
    motion: dict
    plot_data: Optional[dict] = field(default=None, repr=False, compare=False)
    resolution: float = LENGTH_RESOLUTION_MM
    """mm: an allowance within it of zero is on the limit"""
    decision: Optional[str] = None
    """with an uncertainty or a decision rule: the part's decision (its worst gage's)"""
    decision_rule: Optional[dict] = None
    monte_carlo: Optional[dict] = None
    """how the Monte Carlo ran (JCGM 101), with an uncertainty"""
    transform_uncertainty: Optional[dict] = None
    """each free motion of T*: its uncertainty when T* is found again on every simulated measurement"""
    guard_band: Optional[dict] = None
    """the guard-banded problem that proves the decision (:mod:`gagekit.gage.uncertainty`)"""

    @property
    def conforming(self) -> bool:
        return self.status == "conforming"

    @property
    def zero_margin_gages(self) -> tuple[str, ...]:
        """The gages of a conforming part whose allowance after T* is zero (within the
        resolution): the part can be machined to print, with nothing left for measurement
        noise or fixturing - a risk, not a comfortable pass."""
        if not self.conforming:
            return ()
        return tuple(g.name for g in self.gages if abs(g.allowance_after) <= self.resolution)

    def gage(self, name: str) -> GageOutcome:
        for g in self.gages:
            if g.name == name:
                return g
        raise KeyError(name)

    def to_dict(self) -> dict:
        return {
            "status": self.status,
            "objective": self.objective,
            "transform": self.transform.to_dict(),
            "limited_by_motion_bounds": self.limited_by_motion_bounds,
            "bound_limits": [b.to_dict() for b in self.bound_limits],
            "gages": [g.to_dict() for g in self.gages],
            "infeasible_groups": [list(g) for g in self.infeasible_groups],
            "largest_release": self.largest_release,
            "resolution_mm": self.resolution,
            "zero_margin": bool(self.zero_margin_gages),
            "zero_margin_gages": list(self.zero_margin_gages),
            "alignment": None if self.alignment is None else self.alignment.to_dict(),
            "motion": self.motion,
            "solver": {"lp_status": self.lp_status, "relinearisations": self.iterations,
                       "last_step_mm": self.last_step},
            **{k: getattr(self, k) for k in ("decision", "decision_rule", "monte_carlo", "transform_uncertainty",
                                             "guard_band") if getattr(self, k) is not None},
        }


# --------------------------------------------------------------------------- rotations


def box_in_scanner(box: Box, C: np.ndarray) -> Box:
    """A part-frame box expressed in the scanner frame (C = C_L^S, part -> scanner)."""
    R = C[:3, :3] @ rotation_from_vector(box.rotation)
    center = C[:3, :3] @ np.asarray(box.center) + C[:3, 3]
    return Box(tuple(center), box.size, tuple(rotation_vector(R)), name=box.name)


# --------------------------------------------------------------------------- analysis


def _as_spec(spec: SpecLike) -> GageSpec:
    if isinstance(spec, GageSpec):
        return spec
    if isinstance(spec, (str, Path)):
        return GageSpec.load(spec)
    if isinstance(spec, Mapping):
        return GageSpec.from_dict(spec)
    raise InvalidInputError(f"spec: expected a GageSpec, a gage file path or a dict, got {type(spec).__name__}")


def _cut(pts: np.ndarray, boxes: list[Box], frames: list[str], source: str):
    from ..cloud.workflow import cut_and_filter

    cut = cut_and_filter(pts, boxes)
    for r, frame in zip(cut.regions, frames):
        if len(r.indices) == 0:
            raise ConfigError(f"{source}: region '{r.name}' (frame {frame}) catches no points of the cloud; "
                              "check its center and size against the cloud"
                              + (" after alignment" if frame == "part" else ""))
    return cut


@dataclass(frozen=True)
class GageProblem:
    """The data of Eq. 5.11 after alignment, cutting and hull filtering (part frame).

    Gage ``i`` owns ``points[offsets[i]:offsets[i+1]]`` (its region's hull vertices)
    and ``planes[i]``; ``f``, ``g`` are the weights; ``free`` flags the motions
    alpha, beta, gamma, dx, dy, dz of Eq. 5.2.
    """

    spec: GageSpec
    points: np.ndarray
    offsets: list
    planes: np.ndarray
    f: np.ndarray
    g: np.ndarray
    free: list
    max_angle: float
    max_shift: float
    alignment: Optional[Alignment]
    region_counts: dict
    """region name -> (points, hull vertices)"""
    plot_points: dict = field(repr=False, compare=False)

    def args(self) -> tuple:
        """Positional arguments of the ``_core.gage`` kernels."""
        return (self.points, self.offsets, self.planes, self.f, self.g, self.free, self.max_angle, self.max_shift)


def _alignment(pts: np.ndarray, spec: GageSpec) -> Optional[Alignment]:
    if spec.alignment is None:
        return None
    al = spec.alignment
    names = list(dict.fromkeys([*al.primary, *al.secondary, *al.tertiary]))
    cut = _cut(pts, [spec.region(n).box for n in names], ["scanner"] * len(names), spec.source)
    groups_in = {}
    for key, lst in (("primary", al.primary), ("secondary", al.secondary), ("tertiary", al.tertiary)):
        stats = DatumStats.of_moments([_core.cloud.point_moments(pts[cut[n].indices]) for n in lst])
        hull = np.vstack([pts[cut[n].hull] for n in lst])
        groups_in[key] = (lst, stats, hull)
    return fit_321(groups_in)  # the datums' own points, never the whole cloud


def datum_alignment(points, spec: SpecLike) -> Optional[Alignment]:
    """The 3-2-1 frame of the spec's ``[alignment]`` found in the cloud (Eqs. 5.13-5.19),
    or None when the spec has no ``[alignment]``."""
    spec = _as_spec(spec)
    pts = as_points(points, 3, "cloud")
    if len(pts) == 0:
        raise InvalidInputError("cloud: no points")
    check_finite(pts, "cloud")
    return _alignment(pts, spec)


def region_boxes(points, spec: SpecLike) -> list[Box]:
    """Every region of ``spec`` as a box in the scanner frame, as :func:`check_gages` places
    it: part-frame regions carried by the 3-2-1 alignment found in ``points`` (when the spec
    has an ``[alignment]``), scanner-frame regions as they are."""
    spec = _as_spec(spec)
    alignment = datum_alignment(points, spec) if spec.alignment is not None else None
    return [region_in_scanner(r, alignment) for r in spec.regions]


def region_in_scanner(region, alignment: Optional[Alignment]) -> Box:
    """The box of a spec region in the scanner frame: part-frame boxes are carried
    by the alignment's C = C_L^S (Eq. 5.17); scanner-frame boxes and every box of an
    unaligned spec are returned as they are."""
    if region.frame == "part" and alignment is not None:
        return box_in_scanner(region.box, alignment.frame)
    return region.box


def gage_distances(points, spec: SpecLike, result: GageCheckResult) -> list:
    """Per gage, ``(indices, e)``: the points of ``points`` (scanner frame) inside the
    gage's region and their signed distances e_ij = p_i^T T* H [r_ij; 1] from the gage
    plane at T* (Eq. 5.4; negative: short of material). Unlike the allowances of the
    result, every point of the region counts here, not only its hull vertices."""
    from ..cloud.regions import classify

    spec = _as_spec(spec)
    pts = as_points(points, 3, "cloud")
    boxes = [region_in_scanner(spec.region(g.region), result.alignment) for g in spec.gages]
    inside = classify(pts, boxes) if len(pts) else [np.zeros(0, dtype=np.int64) for _ in boxes]
    out = []
    for g, idx in zip(spec.gages, inside):
        moved = corrected_cloud(pts[idx], result) if len(idx) else np.zeros((0, 3))
        e = moved @ np.asarray(g.plane[:3]) + g.plane[3]
        out.append((idx, e))
    return out


def build_problem(points, spec: SpecLike) -> GageProblem:
    """Align (Eqs. 5.13-5.19), cut the regions and hull-filter them (Sec. 5.4.1)."""
    spec = _as_spec(spec)
    pts = as_points(points, 3, "cloud")
    if len(pts) == 0:
        raise InvalidInputError("cloud: no points")
    check_finite(pts, "cloud")
    source = spec.source

    alignment = _alignment(pts, spec)
    H = np.eye(4) if alignment is None else alignment.H

    region_names = list(dict.fromkeys(g.region for g in spec.gages))
    regions = [spec.region(n) for n in region_names]
    boxes = [region_in_scanner(r, alignment) for r in regions]
    cut = _cut(pts, boxes, [r.frame for r in regions], source)
    filtered = {r.name: apply(H, pts[cut[r.name].hull]) for r in regions}
    rng = np.random.default_rng(0)
    plot = {}
    for r in regions:
        idx = cut[r.name].indices
        if len(idx) > PLOT_POINTS:
            idx = np.sort(rng.choice(idx, PLOT_POINTS, replace=False))
        plot[r.name] = apply(H, pts[idx])
    counts = {r.name: (int(len(cut[r.name].indices)), int(len(cut[r.name].hull))) for r in regions}
    return _assemble(spec, alignment, filtered, counts, plot)


def _assemble(spec: GageSpec, alignment: Optional[Alignment], filtered: dict, counts: dict, plot: dict) -> GageProblem:
    """The problem of Eq. 5.11 from each region's hull vertices in the part frame
    (``filtered``), shared by the whole read and the streamed one."""
    gpts, offsets, planes = [], [0], []
    for g in spec.gages:
        gpts.append(filtered[g.region])
        offsets.append(offsets[-1] + len(filtered[g.region]))
        planes.append(g.plane)
    m = spec.motion
    return GageProblem(
        spec=spec,
        points=np.ascontiguousarray(np.vstack(gpts)),
        offsets=offsets,
        planes=np.array(planes, dtype=np.float64),
        f=np.array([g.weight for g in spec.gages], dtype=np.float64),
        g=np.array([g.slack_weight for g in spec.gages], dtype=np.float64),
        free=m.flags(),
        max_angle=m.max_angle,
        max_shift=m.max_shift,
        alignment=alignment,
        region_counts=counts,
        plot_points=plot,
    )


def build_problem_stream(stream, spec: SpecLike) -> GageProblem:
    """:func:`build_problem` of a streamed cloud (:class:`~gagekit.cloud.stream.CloudStream`,
    or any re-iterable of (m, 3) chunks in file order), keeping only region points.

    With an ``[alignment]`` whose gage regions are in the part frame the file is read
    once or twice: the datum pass keeps the hull vertices and the moments of the datum
    regions (what the 3-2-1 fit needs: :class:`~gagekit.gage.align.DatumStats`; memory
    does not grow with the datum regions' points). When the first chunk alone gives a
    3-2-1 frame, the same pass also cuts each part-frame gage region around the box that
    frame puts it at: the hull vertices of the box shrunk by :data:`SHELL_MM` and every
    point of the shell between the shrunk and the grown box; if the whole file's frame
    puts every box between the two, the shell points inside the fitted box join the
    core's vertices (the points of the box, hence the same hull) and the file is read
    once. Otherwise a second pass cuts the
    gage regions, carried into the scanner frame by the fitted C_L^S, reading the file
    from its end back where the format allows (binary PLY), so that it starts on what
    the page cache still holds of the first. Scanner-frame gage
    regions are cut in the first pass. Gage regions keep only their hull vertices, chunk
    by chunk (:mod:`gagekit.cloud.streamed`): the same vertices, in the same order, as a
    whole read, hence the same LP. The region pictures use a seeded uniform sample of each
    region instead of the whole read's draw (the numbers do not depend on it)."""
    from ..cloud.streamed import Pass, cut_stream

    spec = _as_spec(spec)
    source = spec.source
    region_names = list(dict.fromkeys(g.region for g in spec.gages))
    regions = [spec.region(n) for n in region_names]
    al = spec.alignment
    alignment = None
    late = list(regions)
    got: dict = {}
    if al is not None:
        early = [r for r in regions if r.frame != "part"]
        late = [r for r in regions if r.frame == "part"]
        guess, rest = _first_chunk_alignment(stream, spec) if late else (None, None)
        extra, keep, minus = [r.box for r in early], ["hull"] * len(early), [None] * len(early)
        if guess is not None:
            k = len(dict.fromkeys([*al.primary, *al.secondary, *al.tertiary])) + len(early)
            ahead = [region_in_scanner(r, guess) for r in late]
            extra += [_grown(b, -SHELL_MM) for b in ahead] + [_grown(b, SHELL_MM) for b in ahead]
            keep += ["hull"] * len(late) + ["all"] * len(late)
            minus += [None] * len(late) + [k + i for i in range(len(late))]
        # the pass goes on from the guess's chunk (read once) when there is a guess
        alignment, first = _datum_pass(stream if rest is None else rest, spec, extra, keep, minus)
        k0 = len(first.regions) - len(extra)
        _check_caught(first, [r.name for r in early], [r.frame for r in early], source, offset=k0)
        for i, r in enumerate(early):
            got[r.name] = first.regions[k0 + i]
        if guess is not None:
            exact = [region_in_scanner(r, alignment) for r in late]
            c0, s0 = k0 + len(early), k0 + len(early) + len(late)
            if all(_box_within(_grown(a, -SHELL_MM), b) and _box_within(b, _grown(a, SHELL_MM))
                   for a, b in zip(ahead, exact)):
                joined = [_joined(first.regions[c0 + i], first.regions[s0 + i], b) for i, b in enumerate(exact)]
                _check_caught(Pass(0, joined), [r.name for r in late], [r.frame for r in late], source)
                got.update({r.name: j for r, j in zip(late, joined)})
                late = []
    if late:
        boxes = [region_in_scanner(r, alignment) for r in late]
        # from the end of the file back: a file larger than the page cache has its end,
        # read last by the first pass, still cached (the same hulls, in the same order)
        second = cut_stream(stream, boxes, ["hull"] * len(late), sample=PLOT_POINTS, backward=True)
        _check_caught(second, [r.name for r in late], [r.frame for r in late], source)
        for r, sr in zip(late, second.regions):
            got[r.name] = sr
    H = np.eye(4) if alignment is None else alignment.H
    filtered = {r.name: apply(H, got[r.name].point_array()) for r in regions}
    counts = {r.name: (int(got[r.name].count), int(len(got[r.name].index_array()))) for r in regions}
    plot = {r.name: apply(H, got[r.name].sample_points()) for r in regions}
    return _assemble(spec, alignment, filtered, counts, plot)


def _datum_pass(stream, spec: GageSpec, extra: list, keep: Optional[list] = None, minus: Optional[list] = None):
    """One pass: the hull vertices and moments of the datum regions (scanner frame) and
    what ``keep`` says of the ``extra`` boxes (default their hull vertices; ``minus``: see
    :func:`~gagekit.cloud.streamed.cut_stream`); the 3-2-1 frame fitted to the datums as
    :func:`_alignment` fits it (the same hulls, the same moments bit for bit)."""
    from ..cloud.streamed import cut_stream

    al = spec.alignment
    names = list(dict.fromkeys([*al.primary, *al.secondary, *al.tertiary]))
    boxes = [spec.region(n).box for n in names] + list(extra)
    first = cut_stream(stream, boxes, ["hull"] * len(names) + list(keep or ["hull"] * len(extra)),
                       sample=PLOT_POINTS, moments=[True] * len(names) + [False] * len(extra),
                       minus=[None] * len(names) + list(minus) if minus and any(m is not None for m in minus) else None)
    _check_caught(first, names, ["scanner"] * len(names), spec.source)
    groups_in = {}
    for key, lst in (("primary", al.primary), ("secondary", al.secondary), ("tertiary", al.tertiary)):
        stats = DatumStats.of_moments([first[n].moments for n in lst])
        groups_in[key] = (lst, stats, np.vstack([first[n].point_array() for n in lst]))
    return fit_321(groups_in), first  # the datums' own points, as the whole read


SHELL_MM = 0.1
"""Half-thickness (mm) of the shell around each part-frame gage region that a one-pass
streamed check keeps whole (:func:`build_problem_stream`)."""


def _first_chunk_alignment(stream, spec: GageSpec) -> tuple[Optional[Alignment], Optional[Iterator]]:
    """The 3-2-1 frame fitted to the first chunk's datum points alone (a guess of the
    whole file's), and the stream's chunks from that first one on (the chunk not read a
    second time: the file's reading goes on ahead while the guess is fitted); (None,
    None) when that chunk cannot give one."""
    import itertools
    import warnings

    from ..cloud.streamed import _reused

    chunks = iter(_reused(stream))
    guess = None
    try:
        chunk = next(chunks, None)
        if chunk is None:
            return None, None
        with warnings.catch_warnings():  # a guess: what it finds is not the result's to report
            warnings.simplefilter("ignore")
            guess = _datum_pass([chunk], spec, [])[0]  # the chunk stays valid until the next is asked for
        return guess, itertools.chain([chunk], chunks)
    except Exception:  # no datum points in the first chunk, a degenerate fit...: no guess, two passes
        return None, None
    finally:
        close = getattr(chunks, "close", None)
        if guess is None and close is not None:
            close()


def _grown(b: Box, by: float) -> Box:
    """``b`` with every face moved out by ``by`` mm (in, for a negative ``by``)."""
    return Box(b.center, tuple(s + 2 * by for s in b.size), b.rotation, name=b.name)


def _box_within(inner: Box, outer: Box, margin: float = 1e-6) -> bool:
    """Whether every point of ``inner`` (a box with positive sizes) lies in ``outer`` by
    ``margin`` mm plus 1e-9 of the coordinates (far above the rounding of either box's
    membership test): its eight corners do (both are convex)."""
    if min(inner.size) <= 0:
        return False
    Ri, Ro = rotation_from_vector(inner.rotation), rotation_from_vector(outer.rotation)
    signs = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    corners = np.asarray(inner.center) + (signs * np.asarray(inner.size)) @ Ri.T
    local = np.abs((corners - np.asarray(outer.center)) @ Ro)
    pad = margin + 1e-9 * (np.abs(corners).max() + np.abs(outer.center).max() + max(outer.size))
    return bool(np.all(local <= np.asarray(outer.size) / 2 - pad))


def _joined(core, shell, box: Box):
    """A part-frame gage region cut in the datum pass: the hull vertices of its points
    surely inside (``core``, the box guessed from the first chunk, shrunk by
    :data:`SHELL_MM`), and the points of the shell around it (``shell``), of which those
    inside the fitted ``box`` join them. The core lies in the box, the box in the core
    grown by twice the shell, so these are the points of the box: the same hull vertices
    (of the same set), count and picture sample as a second pass over the box."""
    from ..cloud.streamed import StreamedRegion

    sids, spts = shell.index_array(), shell.point_array()
    inside = _core.geometry.classify_boxes(spts, np.array([box.row()], dtype=np.float64))[0] if len(sids) else []
    sids, spts = sids[inside], spts[inside]
    ids = np.concatenate([core.index_array(), sids])
    order = np.argsort(ids, kind="stable")
    r = StreamedRegion(box.name, "hull", count=core.count + len(sids))
    r.indices, r.points = [ids[order]], [np.ascontiguousarray(np.vstack([core.point_array(), spts])[order])]
    r.sample_keys, r.sample_idx, r.sample_pts = core.sample_keys, core.sample_idx, core.sample_pts
    if len(sids):
        r.sample(0, sids, spts, PLOT_POINTS)
    return r.finish()


def region_boxes_stream(stream, spec: SpecLike) -> list[Box]:
    """:func:`region_boxes` of a streamed cloud (a pass over the datum regions first when
    the spec has an ``[alignment]``)."""
    spec = _as_spec(spec)
    alignment = _datum_pass(stream, spec, [])[0] if spec.alignment is not None else None
    return [region_in_scanner(r, alignment) for r in spec.regions]


def _check_caught(p, names: list, frames: list, source: str, offset: int = 0) -> None:
    """The whole read's error for a region that catches no points (:func:`_cut`)."""
    for k, (name, frame) in enumerate(zip(names, frames)):
        if p.regions[offset + k].count == 0:
            raise ConfigError(f"{source}: region '{name}' (frame {frame}) catches no points of the cloud; "
                              "check its center and size against the cloud"
                              + (" after alignment" if frame == "part" else ""))


def check_gages_stream(stream, spec: SpecLike, *, groups: bool = True) -> GageCheckResult:
    """:func:`check_gages` of a streamed cloud (:func:`build_problem_stream`)."""
    return solve_problem(build_problem_stream(stream, spec), groups=groups)


#: the fields of a GageCheckResult that are the kernel's result (``_core.gage.GageCheck``)
_KERNEL_FIELDS = ("status", "objective", "transform", "limited_by_motion_bounds", "bound_limits", "gages",
                  "infeasible_groups", "largest_release", "iterations", "last_step", "lp_status")


def solve_problem(problem: GageProblem, *, groups: bool = True) -> GageCheckResult:
    """Solve Eq. 5.11 for a prepared problem (Rust, clarabel, exact re-linearisation)."""
    spec = problem.spec
    labels = [(g.name, g.region, *problem.region_counts[g.region]) for g in spec.gages]
    r = _core.gage.check(*problem.args(), labels, groups=groups)
    return GageCheckResult(**{k: getattr(r, k) for k in _KERNEL_FIELDS}, alignment=problem.alignment,
                           motion=spec.motion.to_dict(), plot_data={"regions": problem.plot_points, "spec": spec})


def check_gages(points, spec: SpecLike, *, groups: bool = True) -> GageCheckResult:
    """Virtual-gage analysis of a scanned part (Eq. 5.11, Secs. 5.4-5.5).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        The cloud in the scanner frame (mm); the part frame when there is no ``[alignment]``.
    spec : GageSpec, path of a gage file, or the parsed TOML dict
    groups : bool
        Also find the infeasible gage groups of Eq. 5.10 (one more LP per released gage).

    Returns
    -------
    GageCheckResult

    References
    ----------
    Dissertation Eqs. 5.2, 5.4, 5.10, 5.11, 5.13-5.19, Sec. 5.2.2, Tables 5.3-5.4.
    """
    return solve_problem(build_problem(points, spec), groups=groups)


def corrected_cloud(points, result: GageCheckResult) -> np.ndarray:
    """The whole cloud in the part frame with T* applied (H first when aligned)."""
    pts = as_points(points, 3, "cloud")
    if result.alignment is not None:
        pts = result.alignment.to_part(pts)
    return result.transform.apply(pts)


__all__ = ["GageOutcome", "Transform", "BoundLimit", "GageCheckResult", "GageProblem", "build_problem",
           "build_problem_stream", "check_gages_stream",
           "solve_problem", "check_gages", "corrected_cloud", "box_in_scanner", "datum_alignment", "region_boxes",
           "region_in_scanner", "gage_distances"]
