//! Maximum inscribed circle (MI) constrained to lie within the minimum circumscribed
//! circle (Eq. 6.2, Sec. 6.2.2).

use super::mi_tiled::exact_tiled;
use super::voronoi::Nearest;
use super::{dist, mc, subset, Centered, Circle};
use gagekit_core::Result;
use rayon::prelude::*;

/// Maximum inscribed circle of `pts` (flat (n, 2), n >= 3, not collinear).
///
/// Maximises `g(c) = min(r_MC - |c - c_MC|, min_i |c - p_i|)` (Eq. 6.2). The optimum is
/// one of the candidates of Sec. 6.2.2:
/// - a nearest-Voronoi vertex inside MC (three control points);
/// - Case I: a point of a nearest-Voronoi edge whose circle through the edge's two
///   sites is internally tangent to MC (two control points);
/// - Case II: a circle through one point, tangent to MC at the far end of the MC
///   diameter through that point (one control point), if no point lies inside it.
///
/// Every candidate is scored by `g`, so a candidate is only accepted as far as it is
/// feasible. The reported radius is recomputed against all points and MC.
///
/// Above a few thousand points the candidates come from a subset that grows by the
/// points falling inside its circle; the subset radius bounds the true one from above,
/// so a subset circle with no input point inside it is the global optimum. When that
/// does not settle (points spread over an area rather than along a curve), the
/// candidates of all points are computed tile by tile ([`super::mi_tiled`]).
pub fn max_inscribed(pts: &[f64]) -> Result<Circle> {
    let data = Centered::new(pts, WHAT, 3)?;
    data.require_not_collinear(WHAT)?;
    let p = &data.pts;
    let (cmc, _) = mc::welzl(p, data.scale);
    let rmc = p.iter().map(|q| dist(*q, cmc)).fold(0.0, f64::max);
    let tol = 1e-13 * data.scale;
    let (c, mut control) = 'fit: {
        if p.len() > subset::SMALL {
            // constraint generation: exact MI of a subset (an upper bound), accepted once
            // no point lies inside it
            let mut s = subset::initial(p, cmc, &[], false, true);
            for _ in 0..subset::MAX_ROUNDS {
                gagekit_core::interrupt::check()?;
                let q: Vec<[f64; 2]> = s.iter().map(|&i| p[i]).collect();
                let (c, r, ctrl) = exact(&q, cmc, rmc, data.scale)?;
                let (add, _, _) = subset::violators(p, c, Some(r), None, tol);
                if add.is_empty() {
                    break 'fit (c, ctrl.into_iter().map(|k| s[k]).collect::<Vec<_>>());
                }
                s.extend(add);
                s.sort_unstable();
                s.dedup();
                if 4 * s.len() > p.len() {
                    break;
                }
            }
        }
        // all points: tile by tile above a few thousand (bounded memory), else at once
        let (c, _, ctrl) = if p.len() > subset::SMALL {
            exact_tiled(p, cmc, rmc, data.scale)?
        } else {
            exact(p, cmc, rmc, data.scale)?
        };
        (c, ctrl)
    };
    let r_near = p
        .par_iter()
        .with_min_len(8192)
        .map(|q| dist(*q, c))
        .reduce(|| f64::INFINITY, f64::min);
    let radius = r_near.min(rmc - dist(c, cmc)).max(0.0);
    control.sort_unstable();
    control.dedup();
    Ok(Circle {
        center: data.uncenter(c),
        radius,
        control,
    })
}

const WHAT: &str = "maximum inscribed circle";

/// Exact MI of centred points `p` inside the circle (`cmc`, `rmc`): centre, radius and
/// control points (indices into `p`).
pub(crate) fn exact(
    p: &[[f64; 2]],
    cmc: [f64; 2],
    rmc: f64,
    scale: f64,
) -> Result<([f64; 2], f64, Vec<usize>)> {
    let r0 = p
        .iter()
        .map(|q| dist(*q, cmc))
        .fold(f64::INFINITY, f64::min);
    // the MC centre is feasible with radius r0: only larger empty circles matter
    exact_in(p, cmc, rmc, scale, r0 - 1e-9 * scale, &|_| true)
}

/// [`exact`] over the candidates whose centre satisfies `inside` and whose empty circle is
/// at least `floor` (a lower bound of the optimum); the centre `cmc` with no control point
/// when no candidate qualifies.
pub(crate) fn exact_in(
    p: &[[f64; 2]],
    cmc: [f64; 2],
    rmc: f64,
    scale: f64,
    floor: f64,
    inside: &dyn Fn([f64; 2]) -> bool,
) -> Result<([f64; 2], f64, Vec<usize>)> {
    let mut nvd = Nearest::build(p, WHAT)?;
    nvd.extract(p, floor);
    let tol = 1e-12 * scale;
    let g_mc = |c: [f64; 2]| rmc - dist(c, cmc);

    let mut best_r = f64::NEG_INFINITY;
    let mut best_c = cmc;
    let mut best_ctrl = Vec::new();

    // three points: nearest-Voronoi vertices inside MC
    for v in &nvd.verts {
        if v.rad > best_r && v.rad <= g_mc(v.c) + tol && inside(v.c) {
            best_r = v.rad;
            best_c = v.c;
            best_ctrl = v.sites.to_vec();
        }
    }
    // Case I: two points and internal tangency with MC, on a nearest-Voronoi edge
    for e in &nvd.edges {
        if e.rad_max() <= best_r {
            continue;
        }
        // |c(t) - p_a| = s, |c(t) - c_MC| = R - s with c(t) = m + t n:
        // s = alpha + beta t and (1 - beta^2) t^2 - 2 alpha beta t + h^2 - alpha^2 = 0
        let q = [e.m[0] - cmc[0], e.m[1] - cmc[1]];
        let qq = q[0] * q[0] + q[1] * q[1];
        let qn = q[0] * e.n[0] + q[1] * e.n[1];
        let alpha = (rmc * rmc + e.h * e.h - qq) / (2.0 * rmc);
        let beta = -qn / rmc;
        let (a2, b2, c2) = (
            1.0 - beta * beta,
            -2.0 * alpha * beta,
            e.h * e.h - alpha * alpha,
        );
        for t in quadratic_roots(a2, b2, c2) {
            let s = alpha + beta * t;
            if s <= best_r || s > rmc || !e.contains(t, tol) {
                continue;
            }
            let c = e.at(t);
            let g = g_mc(c).min(e.rad(t));
            if g > best_r && inside(c) {
                best_r = g;
                best_c = c;
                best_ctrl = vec![e.a, e.b];
            }
        }
    }
    // Case II: one point; the circle with diameter from the point to the far end of the
    // MC diameter through it
    // a few recent "witness" points that put a candidate's circle over a point reject
    // most candidates without a nearest-neighbour query
    let mut witness: Vec<usize> = best_ctrl.clone();
    for (i, pi) in p.iter().enumerate() {
        let d = dist(*pi, cmc);
        let r = 0.5 * (rmc + d);
        if d == 0.0 || r <= best_r {
            continue;
        }
        let c = [
            pi[0] + (cmc[0] - pi[0]) / d * r,
            pi[1] + (cmc[1] - pi[1]) / d * r,
        ];
        if !inside(c) {
            continue;
        }
        if witness.iter().any(|&k| dist(p[k], c) < r - tol) {
            continue;
        }
        let (k, dn) = nvd.nearest(p, c);
        if dn < r - tol {
            if witness.len() >= 8 {
                witness.remove(0);
            }
            witness.push(k);
            continue;
        }
        let g = g_mc(c).min(dn);
        if g > best_r {
            best_r = g;
            best_c = c;
            best_ctrl = vec![i];
        }
    }
    let r = p
        .iter()
        .map(|q| dist(*q, best_c))
        .fold(f64::INFINITY, f64::min)
        .min(g_mc(best_c));
    Ok((best_c, r, best_ctrl))
}

/// Real roots of a t^2 + b t + c = 0 (a may be ~0).
pub(crate) fn quadratic_roots(a: f64, b: f64, c: f64) -> Vec<f64> {
    if a.abs() < 1e-15 * (b.abs() + c.abs()).max(f64::MIN_POSITIVE) {
        return if b != 0.0 { vec![-c / b] } else { vec![] };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return vec![];
    }
    let sq = disc.sqrt();
    let qv = -0.5 * (b + b.signum() * sq);
    if qv == 0.0 {
        return vec![0.0];
    }
    vec![qv / a, c / qv]
}

/// Largest circle among the Sec. 6.2.2 candidates built from the five points nearest to
/// `center` (input coordinates): circles through three of them, circles through two
/// internally tangent to MC (Case I) and circles through one tangent to MC at the far
/// end of its diameter (Case II), each scored by `g` (Eq. 6.2) over all points. A local
/// maximum near `center`, cheap (no Voronoi diagram), for warm starts of a search in
/// which the points move little between calls; not a global optimum. `None` for fewer
/// than 5 points.
pub fn max_inscribed_near(pts: &[f64], center: [f64; 2]) -> Result<Option<Circle>> {
    const K: usize = 5;
    let data = Centered::new(pts, WHAT, 3)?;
    let p = &data.pts;
    if p.len() < K {
        return Ok(None);
    }
    let (cmc, _) = mc::welzl(p, data.scale);
    let rmc = p.iter().map(|q| dist(*q, cmc)).fold(0.0, f64::max);
    let c0 = [center[0] - data.shift[0], center[1] - data.shift[1]];
    let mut order: Vec<(f64, usize)> = p.iter().enumerate().map(|(i, q)| (super::dist2(*q, c0), i)).collect();
    order.select_nth_unstable_by(K - 1, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut near: Vec<usize> = order[..K].iter().map(|e| e.1).collect();
    near.sort_unstable();
    // g over all points (Eq. 6.2); a candidate stops as soon as a point rules it out
    // (g, centre, (control points, how many))
    type Best = (f64, [f64; 2], ([usize; 3], usize));
    let mut best: Option<Best> = None;
    let mut consider = |c: [f64; 2], ctrl: ([usize; 3], usize)| {
        let floor = best.as_ref().map_or(f64::NEG_INFINITY, |b| b.0);
        let g_mc = rmc - dist(c, cmc);
        if g_mc.is_nan() || g_mc <= floor {
            return;
        }
        let floor2 = if floor > 0.0 { floor * floor } else { 0.0 };
        let mut d2 = f64::INFINITY;
        for q in p {
            d2 = d2.min(super::dist2(*q, c));
            if d2 <= floor2 {
                return;
            }
        }
        let v = d2.sqrt().min(g_mc);
        if v.is_finite() && v > floor {
            best = Some((v, c, ctrl));
        }
    };
    for a in 0..K {
        let pa = p[near[a]];
        // Case II
        let d = dist(pa, cmc);
        if d > 0.0 {
            let r = 0.5 * (rmc + d);
            consider([pa[0] + (cmc[0] - pa[0]) / d * r, pa[1] + (cmc[1] - pa[1]) / d * r], ([near[a], 0, 0], 1));
        }
        for b in a + 1..K {
            let pb = p[near[b]];
            // Case I: on the bisector c(t) = m + t n, |c - pa| = s, |c - cMC| = R - s
            let m = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])];
            let len = dist(pa, pb);
            if len > 0.0 {
                let n = [-(pb[1] - pa[1]) / len, (pb[0] - pa[0]) / len];
                let h = 0.5 * len;
                let q = [m[0] - cmc[0], m[1] - cmc[1]];
                let qq = q[0] * q[0] + q[1] * q[1];
                let qn = q[0] * n[0] + q[1] * n[1];
                let alpha = (rmc * rmc + h * h - qq) / (2.0 * rmc);
                let beta = -qn / rmc;
                for t in quadratic_roots(1.0 - beta * beta, -2.0 * alpha * beta, h * h - alpha * alpha) {
                    if alpha + beta * t > 0.0 {
                        consider([m[0] + t * n[0], m[1] + t * n[1]], ([near[a], near[b], 0], 2));
                    }
                }
            }
            for e in b + 1..K {
                if let Some(c) = super::circumcenter(pa, pb, p[near[e]]) {
                    consider(c, ([near[a], near[b], near[e]], 3));
                }
            }
        }
    }
    let Some((_, c, (ids, k))) = best else {
        return Ok(None);
    };
    let control = ids[..k].to_vec();
    let r_near = p.iter().map(|q| dist(*q, c)).fold(f64::INFINITY, f64::min);
    let radius = r_near.min(rmc - dist(c, cmc)).max(0.0);
    Ok(Some(Circle { center: data.uncenter(c), radius, control }))
}
