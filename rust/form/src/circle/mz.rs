//! Minimum zone circle (MZ, roundness; Eqs. 6.5-6.8, Sec. 6.2.3).

use super::voronoi::{convex_hull, intersect, Farthest, Nearest, VEdge};
use super::{circumcenter, dist, dist2, mc, subset, Centered, Zone};
use gagekit_core::Result;
use rayon::prelude::*;

/// A candidate centre with the width its control points give there.
#[derive(Clone, Debug)]
struct Cand {
    c: [f64; 2],
    w: f64,
    inner: Vec<usize>,
    outer: Vec<usize>,
}

/// How many of the best candidates are verified against all points at the end.
const TOP: usize = 8;

/// Below this many points the solver runs on the calling thread only.
const SEQUENTIAL: usize = 256;

/// Minimum zone circle of `pts` (flat (n, 2), n >= 3, not collinear).
///
/// Minimises `f_r(c) = max_i |c - p_i| - min_j |c - p_j|` (Eq. 6.5) exactly. `f_r` has
/// no local minimum with fewer than four active points (its gradient `u_i - u_j`, with
/// unit vectors `u`, cannot vanish on a convex combination of fewer), so the optimum is
/// - case 1+3: a nearest-Voronoi vertex (Eq. 6.6),
/// - case 3+1: a farthest-Voronoi vertex (Eq. 6.7), or
/// - case 2+2: a crossing of a nearest- and a farthest-Voronoi edge (Eq. 6.8).
///
/// Candidates are pruned by lower bounds against the best width so far (starting from the
/// MC centre): `max_i |c - p_i| >= r_MC`, distances to witness points, and each Voronoi
/// edge is clipped to where a narrower zone is still possible. The best few candidates
/// are polished from their control points (equal-distance equations) and verified
/// against all points; the reported radii are recomputed from the reported centre.
///
/// Above a few thousand points the exact solver runs on a subset (extreme points and
/// points nearest the MC centre by direction) that grows by the points violating its
/// zone. The subset width is a lower bound of the true width, so a subset zone that
/// holds all points (to 1e-13 of the part size) is the global optimum: a certificate.
pub fn min_zone(pts: &[f64]) -> Result<Zone> {
    const WHAT: &str = "minimum zone circle";
    let data = Centered::new(pts, WHAT, 3)?;
    data.require_not_collinear(WHAT)?;
    let p = &data.pts;
    let tol = 1e-13 * data.scale;
    let z = if p.len() <= subset::SMALL {
        exact(p, data.scale)?
    } else {
        // constraint generation: exact MZ of a subset, checked against all points
        let (cmc, mc_ctrl) = mc::welzl(p, data.scale);
        let mut s = subset::initial(p, cmc, &mc_ctrl, true, true);
        let mut found = None;
        for _ in 0..subset::MAX_ROUNDS {
            gagekit_core::interrupt::check()?;
            let q: Vec<[f64; 2]> = s.iter().map(|&i| p[i]).collect();
            let zs = exact(&q, data.scale)?;
            let (add, lo, hi) = subset::violators(p, zs.center, Some(zs.r_in), Some(zs.r_out), tol);
            if add.is_empty() {
                let map = |v: Vec<usize>| v.into_iter().map(|k| s[k]).collect();
                found = Some(Zone {
                    center: zs.center,
                    r_in: lo,
                    r_out: hi,
                    control_in: map(zs.control_in),
                    control_out: map(zs.control_out),
                });
                break;
            }
            s.extend(add);
            s.sort_unstable();
            s.dedup();
            if 4 * s.len() > p.len() {
                break;
            }
        }
        match found {
            Some(z) => z,
            None => exact(p, data.scale)?,
        }
    };
    if z.center[0].hypot(z.center[1]) > STRAIGHT * data.scale {
        return Err(gagekit_core::GkError::degenerate(format!(
            "{WHAT}: the {} points lie almost on a straight line (the narrowest zone's \
             circles would have a radius above 10^4 times the points' extent); no roundness \
             zone is determined; fit a straightness zone (two parallel lines) instead",
            p.len()
        )));
    }
    Ok(Zone {
        center: data.uncenter(z.center),
        ..z
    })
}

/// Exact MZ of centred points (all of them), in centred coordinates.
pub(crate) fn exact(p: &[[f64; 2]], scale: f64) -> Result<Zone> {
    const WHAT: &str = "minimum zone circle";
    // MC and the farthest diagram on one core while the other triangulates (small
    // sets in sequence: a task hand-off costs more than either half)
    let side = || {
        let (cmc, mc_ctrl) = mc::welzl(p, scale);
        let (r0, rmc) = radii(p, cmc);
        (cmc, mc_ctrl, r0, rmc, Farthest::new(p, &convex_hull(p)))
    };
    let (side, nvd) = if p.len() < SEQUENTIAL {
        (side(), Nearest::build(p, WHAT))
    } else {
        rayon::join(side, || Nearest::build(p, WHAT))
    };
    let (cmc, mc_ctrl, r0, rmc, fvd) = side;
    let mut nvd = nvd?;
    // the MC centre bounds the width: w <= rmc - r0, so only empty circles of radius
    // >= r0 can be inner circles of a better zone
    nvd.extract(p, r0 - 1e-9 * scale);
    let top = solve(p, &nvd, &fvd, scale, (cmc, mc_ctrl, rmc));
    // verify: exact width over all points at each candidate and at its polished centre
    let checked: Vec<(f64, [f64; 2], f64, f64, usize)> = top
        .par_iter()
        .with_min_len(if p.len() > 20_000 { 1 } else { TOP })
        .enumerate()
        .flat_map_iter(|(k, cand)| {
            std::iter::once(cand.c)
                .chain(polish(p, cand))
                .map(move |c| {
                    let (a, b, w) = spread(p, c);
                    (w, c, a, b, k)
                })
        })
        .collect();
    let (w, c, r_in, r_out, k) = checked
        .into_iter()
        .reduce(|x, y| if y.0 < x.0 { y } else { x })
        .expect("at least the MC centre is a candidate");
    let (mut control_in, mut control_out) = (top[k].inner.clone(), top[k].outer.clone());
    let (mut c, mut r_in, mut r_out) = (c, r_in, r_out);
    if let Some(b) = local_polish(p, c) {
        if b.w < w {
            (c, control_in, control_out) = (b.c, b.inner, b.outer);
            (r_in, r_out) = radii(p, c);
        }
    }
    for v in [&mut control_in, &mut control_out] {
        v.sort_unstable();
        v.dedup();
    }
    Ok(Zone {
        center: c,
        r_in,
        r_out,
        control_in,
        control_out,
    })
}

type Mc = ([f64; 2], Vec<usize>, f64);

/// Keep the `TOP` narrowest candidates (stable: deterministic under parallel merging).
fn merge(mut a: Vec<Cand>, b: Vec<Cand>) -> Vec<Cand> {
    a.extend(b);
    a.sort_by(|x, y| x.w.total_cmp(&y.w));
    a.truncate(TOP);
    a
}

/// Width at `c` claimed by its control points (exact if they are the nearest/farthest).
fn claimed(p: &[[f64; 2]], c: [f64; 2], inner: &[usize], outer: &[usize]) -> f64 {
    let size = inner.iter().chain(outer).map(|&k| p[k][0].abs().max(p[k][1].abs())).fold(0.0, f64::max);
    if !is_far(c, size) {
        let r = inner.iter().map(|&j| dist(p[j], c)).fold(f64::INFINITY, f64::min);
        let big_r = outer.iter().map(|&i| dist(p[i], c)).fold(0.0, f64::max);
        return big_r - r;
    }
    // far centre: distance differences from the difference of squares (see `offset`)
    let k = inner.first().or(outer.first()).map_or(p[0], |&k| p[k]);
    let dk = dist(k, c);
    let lo = inner.iter().map(|&j| offset(p[j], k, c, dk)).fold(f64::INFINITY, f64::min);
    let hi = outer.iter().map(|&i| offset(p[i], k, c, dk)).fold(f64::NEG_INFINITY, f64::max);
    hi - lo
}

/// Centres farther than this many times the points' extent from them are "far": there
/// |c - p_i| - |c - p_j| loses digits to rounding (about 1e-16 |c|) and is computed
/// from the difference of squares instead.
const FAR: f64 = 1e3;

/// A zone whose centre lies farther than this many times the points' extent is no
/// circle for metrology: the points are all but straight, the zone tends to two
/// parallel lines (a straightness zone), and radii of 1e4 extents keep only about
/// 1e-12 of the extent in their difference.
const STRAIGHT: f64 = 1e4;

/// Is `c` far (see [`FAR`]) from centred points whose coordinates are at most `size`?
#[inline]
fn is_far(c: [f64; 2], size: f64) -> bool {
    c[0].abs().max(c[1].abs()) > FAR * size.max(f64::MIN_POSITIVE)
}

/// `|c - q| - |c - k|` accurate to rounding of the points' coordinates even for a
/// centre `c` far away: `(|q|^2 - |k|^2 - 2 c . (q - k)) / (|c - q| + |c - k|)`;
/// `dk = |c - k|`.
#[inline]
fn offset(q: [f64; 2], k: [f64; 2], c: [f64; 2], dk: f64) -> f64 {
    let dq = dist(q, c);
    let (d0, d1) = (q[0] - k[0], q[1] - k[1]);
    let num = (q[0] + k[0]) * d0 + (q[1] + k[1]) * d1 - 2.0 * (c[0] * d0 + c[1] * d1);
    let den = dq + dk;
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// The Sec. 6.2.3 candidates, best first: the MC centre, then the three cases of
/// Eq. 6.6-6.8 ([`case_13`], [`case_31`], [`case_22`]), each pruned by the best zone so far.
fn solve(
    p: &[[f64; 2]],
    nvd: &Nearest,
    fvd: &Farthest,
    scale: f64,
    (cmc, mc_ctrl, rmc): Mc,
) -> Vec<Cand> {
    let tol = 1e-12 * scale;
    let (j0, r0) = nvd.nearest(p, cmc);
    let w0 = rmc - r0;
    let top = vec![Cand {
        c: cmc,
        w: w0,
        inner: vec![j0],
        outer: mc_ctrl.clone(),
    }];
    let top = merge(top, case_13(p, nvd, fvd, tol, &mc_ctrl, rmc, w0));
    let top = case_31(p, nvd, fvd, tol, cmc, j0, top);
    let c22 = case_22(p, nvd, fvd, scale, tol, (cmc, mc_ctrl, rmc), &top[0]);
    merge(top, c22)
}

/// Case 1+3 (Eq. 6.6): nearest-Voronoi vertices whose zone can still beat `w`.
fn case_13(
    p: &[[f64; 2]],
    nvd: &Nearest,
    fvd: &Farthest,
    tol: f64,
    mc_ctrl: &[usize],
    rmc: f64,
    w: f64,
) -> Vec<Cand> {
    // lower bound of max_i |c - p_i|
    let r_lb = |c: [f64; 2]| mc_ctrl.iter().map(|&k| dist(p[k], c)).fold(rmc, f64::max);
    nvd.verts
        .par_iter()
        .with_min_len(512)
        .filter(|v| r_lb(v.c) - v.rad < w + tol)
        .map(|v| {
            let (i, _) = fvd.farthest(p, v.c);
            let (inner, outer) = (v.sites.to_vec(), vec![i]);
            vec![Cand {
                c: v.c,
                w: claimed(p, v.c, &inner, &outer),
                inner,
                outer,
            }]
        })
        .reduce_with(merge)
        .unwrap_or_default()
}

/// Case 3+1 (Eq. 6.7): farthest-Voronoi vertices, visited around the MC centre so that
/// the previous nearest point is both a close start for the walk and a witness
/// (r(u) <= |u - p_prev|) that rules most vertices out without any walk.
fn case_31(
    p: &[[f64; 2]],
    nvd: &Nearest,
    fvd: &Farthest,
    tol: f64,
    cmc: [f64; 2],
    j0: usize,
    mut top: Vec<Cand>,
) -> Vec<Cand> {
    let mut order: Vec<usize> = (0..fvd.verts.len()).collect();
    let ang = |k: &usize| {
        let c = fvd.verts[*k].c;
        (c[1] - cmc[1]).atan2(c[0] - cmc[0])
    };
    let keys: Vec<f64> = order.iter().map(ang).collect();
    order.sort_by(|a, b| keys[*a].total_cmp(&keys[*b]));
    let mut prev = j0;
    for k in order {
        let u = &fvd.verts[k];
        let bound = top.last().map_or(f64::INFINITY, |c| c.w);
        if top.len() == TOP && u.rad - dist(p[prev], u.c) >= bound + tol {
            continue;
        }
        let (j, _) = nvd.walk(p, prev, u.c);
        prev = j;
        let (inner, outer) = (vec![j], u.sites.to_vec());
        let cand = Cand {
            c: u.c,
            w: claimed(p, u.c, &inner, &outer),
            inner,
            outer,
        };
        top = merge(top, vec![cand]);
    }
    top
}

/// Case 2+2 (Eq. 6.8): crossings of nearest and farthest Voronoi edges. Each edge is
/// first clipped to where a zone narrower than `best` is still possible, judged against
/// witness points (f_r >= |c - p_k| - |c - p_j| for any k, j).
fn case_22(
    p: &[[f64; 2]],
    nvd: &Nearest,
    fvd: &Farthest,
    scale: f64,
    tol: f64,
    (cmc, mc_ctrl, rmc): Mc,
    best: &Cand,
) -> Vec<Cand> {
    let w = best.w + tol;
    let margin = 1e-9 * scale;
    let (outer_w, inner_w) = witnesses(p, cmc, &mc_ctrl, best);
    let mut fe: Vec<VEdge> = fvd
        .edges
        .par_iter()
        .with_min_len(512)
        .filter_map(|f0| {
            let mut f = *f0;
            inner_w
                .iter()
                .all(|&j| f.clip_farthest(p[j], w, margin))
                .then_some(f)
        })
        .collect();
    fe.sort_by(|a, b| a.rad_min().total_cmp(&b.rad_min()));
    let fe_rmin: Vec<f64> = fe.iter().map(|f| f.rad_min()).collect();
    nvd.edges
        .par_iter()
        .with_min_len(512)
        .filter_map(|e0| {
            let mut e = *e0;
            if !outer_w.iter().all(|&k| e.clip_nearest(p[k], w, margin)) {
                return None;
            }
            let rmax = e.rad_max();
            if rmax <= rmc - w {
                return None;
            }
            let mut local = Vec::new();
            for (f, &rmin) in fe.iter().zip(&fe_rmin) {
                if rmin - rmax >= w {
                    break;
                }
                let Some((t, s)) = intersect(&e, f) else {
                    continue;
                };
                if !e.contains(t, tol) || !f.contains(s, tol) || f.rad(s) - e.rad(t) >= w {
                    continue;
                }
                let c = e.at(t);
                let (inner, outer) = (vec![e.a, e.b], vec![f.a, f.b]);
                local.push(Cand {
                    c,
                    w: claimed(p, c, &inner, &outer),
                    inner,
                    outer,
                });
            }
            (!local.is_empty()).then(|| merge(Vec::new(), local))
        })
        .reduce_with(merge)
        .unwrap_or_default()
}

/// Witness points for clipping: outer ones (far from the centre: the MC control points,
/// the best zone's outer points and the extreme points in 16 directions) and inner ones
/// (the best zone's inner points and the points nearest to the MC centre in 16 sectors).
fn witnesses(
    p: &[[f64; 2]],
    cmc: [f64; 2],
    mc_ctrl: &[usize],
    best: &Cand,
) -> (Vec<usize>, Vec<usize>) {
    const K: usize = 16;
    let dirs: Vec<[f64; 2]> = (0..K)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / K as f64;
            [a.cos(), a.sin()]
        })
        .collect();
    let mut ext = [(f64::NEG_INFINITY, 0usize); K];
    let mut near = [(f64::INFINITY, usize::MAX); K];
    for (i, q) in p.iter().enumerate() {
        let d = [q[0] - cmc[0], q[1] - cmc[1]];
        for (k, u) in dirs.iter().enumerate() {
            let x = d[0] * u[0] + d[1] * u[1];
            if x > ext[k].0 {
                ext[k] = (x, i);
            }
        }
        let a = d[1].atan2(d[0]).rem_euclid(std::f64::consts::TAU);
        let k = ((a / std::f64::consts::TAU * K as f64) as usize).min(K - 1);
        let r = (d[0] * d[0] + d[1] * d[1]).sqrt();
        if r < near[k].0 {
            near[k] = (r, i);
        }
    }
    let mut outer: Vec<usize> = mc_ctrl
        .iter()
        .chain(&best.outer)
        .copied()
        .chain(ext.iter().map(|e| e.1))
        .collect();
    let mut inner: Vec<usize> = best
        .inner
        .iter()
        .copied()
        .chain(near.iter().filter(|e| e.1 != usize::MAX).map(|e| e.1))
        .collect();
    for v in [&mut outer, &mut inner] {
        v.sort_unstable();
        v.dedup();
    }
    (outer, inner)
}

/// Re-solve the equal-distance equations for every 1+3, 3+1 and 2+2 choice among the
/// few points nearest to the inner and outer circle at `c`, and return the narrowest
/// zone found (exact width over all points). Repairs the last digits when rounding in
/// the Voronoi geometry picked a neighbouring combination (points within ~1e-11 of a
/// perfect circle).
fn local_polish(p: &[[f64; 2]], c: [f64; 2]) -> Option<Cand> {
    local_choices::<6>(p, c)
}

/// [`local_polish`] among the `K` points nearest to and farthest from `c`.
fn local_choices<const K: usize>(p: &[[f64; 2]], c: [f64; 2]) -> Option<Cand> {
    let mut order: Vec<(f64, usize)> = p
        .iter()
        .enumerate()
        .map(|(i, q)| (dist(*q, c), i))
        .collect();
    if order.len() < 2 * K {
        return None;
    }
    order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let inner: Vec<usize> = order[..K].iter().map(|e| e.1).collect();
    let outer: Vec<usize> = order[order.len() - K..].iter().map(|e| e.1).collect();
    // (centre, inner controls, outer controls), without allocating per choice
    type Ids = ([usize; 3], usize);
    type Choice = (Option<[f64; 2]>, Ids, Ids);
    const NONE: Ids = ([0; 3], 0);
    let mut cands: Vec<Choice> = Vec::with_capacity(2 * K * K * K + K * K * K * K);
    for a in 0..K {
        for b in a + 1..K {
            for d in b + 1..K {
                let (i3, o3) = (
                    [inner[a], inner[b], inner[d]],
                    [outer[a], outer[b], outer[d]],
                );
                cands.push((circumcenter(p[i3[0]], p[i3[1]], p[i3[2]]), (i3, 3), NONE));
                cands.push((circumcenter(p[o3[0]], p[o3[1]], p[o3[2]]), NONE, (o3, 3)));
            }
            for x in 0..K {
                for y in x + 1..K {
                    let (ia, ib, oa, ob) = (inner[a], inner[b], outer[x], outer[y]);
                    cands.push((
                        bisector_crossing(p[ia], p[ib], p[oa], p[ob]),
                        ([ia, ib, 0], 2),
                        ([oa, ob, 0], 2),
                    ));
                }
            }
        }
    }
    // rank the choices by their width over the near-active points, then check the best
    // few against all points
    let near: Vec<[f64; 2]> = inner.iter().chain(&outer).map(|&i| p[i]).collect();
    let near_size = extent(&near);
    let mut ranked: Vec<(f64, usize)> = cands
        .iter()
        .enumerate()
        .filter_map(|(k, (c, _, _))| c.map(|c| (spread_in(&near, c, near_size).2, k)))
        .collect();
    // the four best in order (the key is total: same as sorting all of them)
    let key = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    if ranked.len() > 4 {
        ranked.select_nth_unstable_by(3, key);
        ranked.truncate(4);
    }
    ranked.sort_by(key);
    ranked
        .iter()
        .take(4)
        .filter_map(|&(_, k)| {
            let (c, (ia, ni), (oa, no)) = cands[k];
            let (mut inn, mut out) = (ia[..ni].to_vec(), oa[..no].to_vec());
            let c = c?;
            let (lo, hi, w) = spread(p, c);
            // the controls of a 1+3 / 3+1 choice: complete with the extreme point
            let extreme = |want: f64| p.iter().position(|q| dist(*q, c) == want);
            if inn.is_empty() {
                inn = extreme(lo).into_iter().collect();
            }
            if out.is_empty() {
                out = extreme(hi).into_iter().collect();
            }
            Some(Cand {
                c,
                w,
                inner: inn,
                outer: out,
            })
        })
        .reduce(|x, y| if y.w < x.w { y } else { x })
}

/// Recompute the winning centre from its control points (equal-distance equations).
fn polish(p: &[[f64; 2]], b: &Cand) -> Option<[f64; 2]> {
    match (b.inner.len(), b.outer.len()) {
        (3, 1) => circumcenter(p[b.inner[0]], p[b.inner[1]], p[b.inner[2]]),
        (1, 3) => circumcenter(p[b.outer[0]], p[b.outer[1]], p[b.outer[2]]),
        (2, 2) => {
            let (a, bb, i, l) = (p[b.inner[0]], p[b.inner[1]], p[b.outer[0]], p[b.outer[1]]);
            bisector_crossing(a, bb, i, l)
        }
        _ => None,
    }
}

/// Smallest and largest distance of the points from `c` (for a far centre, see [`FAR`],
/// from differences of squares relative to the first point: the width `hi - lo` keeps
/// its digits however far the centre is).
pub(crate) fn radii(p: &[[f64; 2]], c: [f64; 2]) -> (f64, f64) {
    let (lo, hi, _) = spread(p, c);
    (lo, hi)
}

/// Smallest and largest distance of the points from `c` and the width between them,
/// accurate also for a far centre (see [`FAR`]): there the distances are taken relative
/// to the first point from differences of squares.
fn spread(p: &[[f64; 2]], c: [f64; 2]) -> (f64, f64, f64) {
    spread_in(p, c, extent(p))
}

/// Largest coordinate magnitude of centred points.
fn extent(p: &[[f64; 2]]) -> f64 {
    p.iter().map(|q| q[0].abs().max(q[1].abs())).fold(0.0, f64::max)
}

/// [`spread`] of points of the given [`extent`].
fn spread_in(p: &[[f64; 2]], c: [f64; 2], size: f64) -> (f64, f64, f64) {
    if is_far(c, size) {
        let k = p[0];
        let dk = dist(k, c);
        let (lo, hi) = p.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| {
            let e = offset(*q, k, c, dk);
            (lo.min(e), hi.max(e))
        });
        return (dk + lo, dk + hi, hi - lo);
    }
    let (lo, hi) = near_radii(p, c);
    (lo, hi, hi - lo)
}

fn near_radii(p: &[[f64; 2]], c: [f64; 2]) -> (f64, f64) {
    // extremes of the squared distances, then two roots: sqrt is monotone and
    // correctly rounded, so this equals the extremes of `dist`
    let fold = |(lo, hi): (f64, f64), q: &[f64; 2]| {
        let d = dist2(*q, c);
        (lo.min(d), hi.max(d))
    };
    let (lo, hi) = if p.len() < 50_000 {
        p.iter().fold((f64::INFINITY, 0.0f64), fold)
    } else {
        p.par_iter().fold(|| (f64::INFINITY, 0.0f64), fold).reduce(
            || (f64::INFINITY, 0.0f64),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        )
    };
    (lo.sqrt(), hi.sqrt())
}

/// Point equidistant from a and b and from i and l (two linear equations), solved
/// relative to the centroid of the four points.
fn bisector_crossing(a: [f64; 2], b: [f64; 2], i: [f64; 2], l: [f64; 2]) -> Option<[f64; 2]> {
    let o = [
        (a[0] + b[0] + i[0] + l[0]) / 4.0,
        (a[1] + b[1] + i[1] + l[1]) / 4.0,
    ];
    let sh = |q: [f64; 2]| [q[0] - o[0], q[1] - o[1]];
    let (a, b, i, l) = (sh(a), sh(b), sh(i), sh(l));
    // 2 (b - a) . c = |b|^2 - |a|^2
    let r1 = [2.0 * (b[0] - a[0]), 2.0 * (b[1] - a[1])];
    let r2 = [2.0 * (l[0] - i[0]), 2.0 * (l[1] - i[1])];
    let v1 = (b[0] * b[0] + b[1] * b[1]) - (a[0] * a[0] + a[1] * a[1]);
    let v2 = (l[0] * l[0] + l[1] * l[1]) - (i[0] * i[0] + i[1] * i[1]);
    let det = r1[0] * r2[1] - r1[1] * r2[0];
    if det == 0.0 {
        return None;
    }
    let x = (v1 * r2[1] - r1[1] * v2) / det;
    let y = (r1[0] * v2 - v1 * r2[0]) / det;
    (x.is_finite() && y.is_finite()).then_some([x + o[0], y + o[1]])
}
