//! Minimum zone circle (MZ, roundness; Eqs. 6.5-6.8, Sec. 6.2.3).

use super::voronoi::{intersect, Farthest, Nearest};
use super::{circumcenter, dist, mc, Centered, Zone};
use gagekit_core::Result;

#[derive(Clone, Debug)]
struct Cand {
    c: [f64; 2],
    w: f64,
    inner: Vec<usize>,
    outer: Vec<usize>,
}

/// Minimum zone circle of `pts` (flat (n, 2), n >= 3, not collinear).
///
/// Minimises `f_r(c) = max_i |c - p_i| - min_j |c - p_j|` (Eq. 6.5) exactly. `f_r` has
/// no local minimum with fewer than four active points, so the optimum is one of
/// - case 1+3: a nearest-Voronoi vertex (Eq. 6.6),
/// - case 3+1: a farthest-Voronoi vertex (Eq. 6.7),
/// - case 2+2: a crossing of a nearest- and a farthest-Voronoi edge (Eq. 6.8).
///
/// Candidates are pruned by lower bounds (`max_i |c - p_i| >= r_MC`, the site distance
/// along an edge) against the best width so far, starting from the MC centre; only
/// survivors need a nearest/farthest query. The winner's width is recomputed against all
/// points.
pub fn min_zone(pts: &[f64]) -> Result<Zone> {
    const WHAT: &str = "minimum zone circle";
    let data = Centered::new(pts, WHAT, 3)?;
    data.require_not_collinear(WHAT)?;
    let p = &data.pts;
    let (cmc, mc_ctrl) = mc::welzl(p, data.scale);
    let (r0, rmc) = radii(p, cmc);
    // the MC centre bounds the width: w <= rmc - r0, so only empty circles of radius
    // >= r0 can be inner circles of a better zone
    let nvd = Nearest::new(p, WHAT, r0 - 1e-9 * data.scale)?;
    let fvd = Farthest::new(p, &nvd.hull());
    let best = solve(p, &nvd, &fvd, data.scale, (cmc, mc_ctrl, rmc));
    // polish from the control points; keep it only if it is no worse over all points
    let (mut c, (mut r_in, mut r_out)) = (best.c, radii(p, best.c));
    if let Some(c2) = polish(p, &best) {
        let (a, b) = radii(p, c2);
        if b - a <= r_out - r_in {
            (c, r_in, r_out) = (c2, a, b);
        }
    }
    let (mut control_in, mut control_out) = (best.inner, best.outer);
    for v in [&mut control_in, &mut control_out] {
        v.sort_unstable();
        v.dedup();
    }
    Ok(Zone { center: data.uncenter(c), r_in, r_out, control_in, control_out })
}

type Mc = ([f64; 2], Vec<usize>, f64);

fn solve(p: &[[f64; 2]], nvd: &Nearest, fvd: &Farthest, scale: f64, (cmc, mc_ctrl, rmc): Mc) -> Cand {
    let tol = 1e-12 * scale;
    // lower bound of max_i |c - p_i|
    let r_lb = |c: [f64; 2]| mc_ctrl.iter().map(|&k| dist(p[k], c)).fold(rmc, f64::max);

    let (j0, r0) = nvd.nearest(p, cmc);
    let mut best = Cand { c: cmc, w: rmc - r0, inner: vec![j0], outer: mc_ctrl.clone() };

    // case 1+3 (Eq. 6.6): nearest-Voronoi vertices
    for v in &nvd.verts {
        if r_lb(v.c) - v.rad >= best.w - tol {
            continue;
        }
        let (i, r) = fvd.farthest(p, v.c);
        if r - v.rad < best.w {
            best = Cand { c: v.c, w: r - v.rad, inner: v.sites.to_vec(), outer: vec![i] };
        }
    }
    // case 3+1 (Eq. 6.7): farthest-Voronoi vertices
    for u in &fvd.verts {
        let (j, r) = nvd.nearest(p, u.c);
        if u.rad - r < best.w {
            best = Cand { c: u.c, w: u.rad - r, inner: vec![j], outer: u.sites.to_vec() };
        }
    }
    // case 2+2 (Eq. 6.8): crossings of nearest and farthest Voronoi edges
    let mut fe: Vec<(f64, usize)> = fvd.edges.iter().enumerate().map(|(k, e)| (e.rad_min(), k)).collect();
    fe.sort_by(|a, b| a.0.total_cmp(&b.0));
    for e0 in &nvd.edges {
        let mut e = *e0;
        if !e.tlo.is_finite() || !e.thi.is_finite() {
            // a ray beyond the hull edge (a, b): for c there, max |c - p| >= s + W and
            // |c - p_a| <= s + h (s = distance beyond the edge, W = depth of the set
            // behind the edge), so f_r >= W - h. Drop that part when it cannot win.
            let out = if e.thi.is_finite() { -1.0 } else { 1.0 };
            let depth = mc_ctrl
                .iter()
                .map(|&k| out * ((e.m[0] - p[k][0]) * e.n[0] + (e.m[1] - p[k][1]) * e.n[1]))
                .fold(0.0, f64::max);
            if depth - e.h >= best.w - tol {
                if out > 0.0 {
                    e.thi = 0.0;
                } else {
                    e.tlo = 0.0;
                }
                if e.tlo > e.thi {
                    continue;
                }
            }
        }
        let rmax = e.rad_max();
        if rmax <= rmc - best.w + tol {
            continue;
        }
        for &(rmin, k) in &fe {
            if rmin - rmax >= best.w - tol {
                break;
            }
            let f = &fvd.edges[k];
            let Some((t, s)) = intersect(&e, f) else { continue };
            if !e.contains(t, tol) || !f.contains(s, tol) {
                continue;
            }
            let w = f.rad(s) - e.rad(t);
            if w < best.w {
                let c = e.at(t);
                best = Cand { c, w, inner: vec![e.a, e.b], outer: vec![f.a, f.b] };
            }
        }
    }
    best
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
