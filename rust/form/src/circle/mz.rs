//! Minimum zone circle (MZ, roundness; Eqs. 6.5-6.8, Sec. 6.2.3).

use super::voronoi::{convex_hull, intersect, Farthest, Nearest, VEdge};
use super::{circumcenter, dist, mc, Centered, Zone};
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
pub fn min_zone(pts: &[f64]) -> Result<Zone> {
    const WHAT: &str = "minimum zone circle";
    let data = Centered::new(pts, WHAT, 3)?;
    data.require_not_collinear(WHAT)?;
    let p = &data.pts;
    // MC and the farthest diagram on one core while the other triangulates
    let (side, nvd) = rayon::join(
        || {
            let (cmc, mc_ctrl) = mc::welzl(p, data.scale);
            let (r0, rmc) = radii(p, cmc);
            (cmc, mc_ctrl, r0, rmc, Farthest::new(p, &convex_hull(p)))
        },
        || Nearest::build(p, WHAT),
    );
    let (cmc, mc_ctrl, r0, rmc, fvd) = side;
    let mut nvd = nvd?;
    // the MC centre bounds the width: w <= rmc - r0, so only empty circles of radius
    // >= r0 can be inner circles of a better zone
    nvd.extract(p, r0 - 1e-9 * data.scale);
    let top = solve(p, &nvd, &fvd, data.scale, (cmc, mc_ctrl, rmc));
    // verify: exact width over all points at each candidate and at its polished centre
    let checked: Vec<(f64, [f64; 2], f64, f64, usize)> = top
        .par_iter()
        .enumerate()
        .flat_map_iter(|(k, cand)| {
            std::iter::once(cand.c).chain(polish(p, cand)).map(move |c| {
                let (a, b) = radii(p, c);
                (b - a, c, a, b, k)
            })
        })
        .collect();
    let (_, c, r_in, r_out, k) = checked
        .into_iter()
        .reduce(|x, y| if y.0 < x.0 { y } else { x })
        .expect("at least the MC centre is a candidate");
    let (mut control_in, mut control_out) = (top[k].inner.clone(), top[k].outer.clone());
    for v in [&mut control_in, &mut control_out] {
        v.sort_unstable();
        v.dedup();
    }
    Ok(Zone { center: data.uncenter(c), r_in, r_out, control_in, control_out })
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
    let r = inner.iter().map(|&j| dist(p[j], c)).fold(f64::INFINITY, f64::min);
    let big_r = outer.iter().map(|&i| dist(p[i], c)).fold(0.0, f64::max);
    big_r - r
}

fn solve(p: &[[f64; 2]], nvd: &Nearest, fvd: &Farthest, scale: f64, (cmc, mc_ctrl, rmc): Mc) -> Vec<Cand> {
    let tol = 1e-12 * scale;
    // lower bound of max_i |c - p_i|
    let r_lb = |c: [f64; 2]| mc_ctrl.iter().map(|&k| dist(p[k], c)).fold(rmc, f64::max);

    let (j0, r0) = nvd.nearest(p, cmc);
    let mut top = vec![Cand { c: cmc, w: rmc - r0, inner: vec![j0], outer: mc_ctrl.clone() }];

    // case 1+3 (Eq. 6.6): nearest-Voronoi vertices
    let w = top[0].w;
    let c13 = nvd
        .verts
        .par_iter()
        .filter(|v| r_lb(v.c) - v.rad < w + tol)
        .map(|v| {
            let (i, _) = fvd.farthest(p, v.c);
            let (inner, outer) = (v.sites.to_vec(), vec![i]);
            vec![Cand { c: v.c, w: claimed(p, v.c, &inner, &outer), inner, outer }]
        })
        .reduce_with(merge);
    top = merge(top, c13.unwrap_or_default());

    // case 3+1 (Eq. 6.7): farthest-Voronoi vertices, visited around the MC centre so
    // that the previous nearest point is both a close start for the walk and a witness
    // (r(u) <= |u - p_prev|) that rules most vertices out without any walk
    let mut order: Vec<usize> = (0..fvd.verts.len()).collect();
    let ang = |k: &usize| {
        let c = fvd.verts[*k].c;
        (c[1] - cmc[1]).atan2(c[0] - cmc[0])
    };
    order.sort_by(|a, b| ang(a).total_cmp(&ang(b)));
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
        let cand = Cand { c: u.c, w: claimed(p, u.c, &inner, &outer), inner, outer };
        top = merge(top, vec![cand]);
    }

    // case 2+2 (Eq. 6.8): crossings of nearest and farthest Voronoi edges. Each edge is
    // first clipped to where a zone narrower than the best so far is still possible,
    // judged against witness points (f_r >= |c - p_k| - |c - p_j| for any k, j).
    let w = top[0].w + tol;
    let margin = 1e-9 * scale;
    let (outer_w, inner_w) = witnesses(p, cmc, &mc_ctrl, &top[0]);
    let mut fe: Vec<VEdge> = fvd
        .edges
        .par_iter()
        .filter_map(|f0| {
            let mut f = *f0;
            inner_w.iter().all(|&j| f.clip_farthest(p[j], w, margin)).then_some(f)
        })
        .collect();
    fe.sort_by(|a, b| a.rad_min().total_cmp(&b.rad_min()));
    let fe_rmin: Vec<f64> = fe.iter().map(|f| f.rad_min()).collect();
    let c22 = nvd
        .edges
        .par_iter()
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
                let Some((t, s)) = intersect(&e, f) else { continue };
                if !e.contains(t, tol) || !f.contains(s, tol) || f.rad(s) - e.rad(t) >= w {
                    continue;
                }
                let c = e.at(t);
                let (inner, outer) = (vec![e.a, e.b], vec![f.a, f.b]);
                local.push(Cand { c, w: claimed(p, c, &inner, &outer), inner, outer });
            }
            (!local.is_empty()).then(|| merge(Vec::new(), local))
        })
        .reduce_with(merge);
    merge(top, c22.unwrap_or_default())
}

/// Witness points for clipping: outer ones (far from the centre: the MC control points,
/// the best zone's outer points and the extreme points in 16 directions) and inner ones
/// (the best zone's inner points and the points nearest to the MC centre in 16 sectors).
fn witnesses(p: &[[f64; 2]], cmc: [f64; 2], mc_ctrl: &[usize], best: &Cand) -> (Vec<usize>, Vec<usize>) {
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
        let r = d[0].hypot(d[1]);
        if r < near[k].0 {
            near[k] = (r, i);
        }
    }
    let mut outer: Vec<usize> = mc_ctrl.iter().chain(&best.outer).copied().chain(ext.iter().map(|e| e.1)).collect();
    let mut inner: Vec<usize> = best.inner.iter().copied().chain(near.iter().filter(|e| e.1 != usize::MAX).map(|e| e.1)).collect();
    for v in [&mut outer, &mut inner] {
        v.sort_unstable();
        v.dedup();
    }
    (outer, inner)
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

/// Smallest and largest distance of the points from `c`.
pub(crate) fn radii(p: &[[f64; 2]], c: [f64; 2]) -> (f64, f64) {
    p.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), q| {
        let d = dist(*q, c);
        (lo.min(d), hi.max(d))
    })
}

/// Point equidistant from a and b and from i and l (two linear equations), solved
/// relative to the centroid of the four points.
fn bisector_crossing(a: [f64; 2], b: [f64; 2], i: [f64; 2], l: [f64; 2]) -> Option<[f64; 2]> {
    let o = [(a[0] + b[0] + i[0] + l[0]) / 4.0, (a[1] + b[1] + i[1] + l[1]) / 4.0];
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
