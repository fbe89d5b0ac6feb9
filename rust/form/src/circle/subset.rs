//! Constraint generation for the Voronoi fits (MI, MZ) on large point sets.
//!
//! Solve the fit exactly on a small subset S, then check it against all points. For MZ
//! the subset width is a lower bound of the true one (fewer constraints), for MI the
//! subset radius an upper bound; if the subset optimum is also feasible for all points
//! (nothing inside the inner circle or outside the outer one, up to rounding), it is the
//! global optimum for all points. Otherwise the most violating points join S and the
//! subset fit is repeated. Sparse subsets also keep the Voronoi geometry well
//! conditioned when the points lie very close to a circle.

use rayon::prelude::*;

/// Number of angular sectors / directions of the starting subset.
pub(crate) const SECTORS: usize = 64;
/// Most violating points added per side and round.
pub(crate) const ADD: usize = 48;
/// Rounds before giving up and solving on all points.
pub(crate) const MAX_ROUNDS: usize = 40;
/// Below this many points the fit runs on all points directly.
pub(crate) const SMALL: usize = 3000;

/// Starting subset: the given points, the extreme points in `SECTORS` directions and the
/// points nearest to `o` in `SECTORS` angular sectors around it.
pub(crate) fn initial(
    p: &[[f64; 2]],
    o: [f64; 2],
    seed: &[usize],
    outer: bool,
    inner: bool,
) -> Vec<usize> {
    const K: usize = SECTORS;
    let dirs: Vec<[f64; 2]> = (0..K)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / K as f64;
            [a.cos(), a.sin()]
        })
        .collect();
    type Acc = (Vec<(f64, usize)>, Vec<(f64, usize)>);
    let empty = || -> Acc {
        (
            vec![(f64::NEG_INFINITY, usize::MAX); K],
            vec![(f64::INFINITY, usize::MAX); K],
        )
    };
    let (ext, near) = p
        .par_iter()
        .enumerate()
        .with_min_len(8192)
        .fold(empty, |(mut ext, mut near), (i, q)| {
            let d = [q[0] - o[0], q[1] - o[1]];
            if outer {
                for (k, u) in dirs.iter().enumerate() {
                    let x = d[0] * u[0] + d[1] * u[1];
                    if x > ext[k].0 {
                        ext[k] = (x, i);
                    }
                }
            }
            if inner {
                let a = d[1].atan2(d[0]).rem_euclid(std::f64::consts::TAU);
                let k = ((a / std::f64::consts::TAU * K as f64) as usize).min(K - 1);
                let r = (d[0] * d[0] + d[1] * d[1]).sqrt();
                if r < near[k].0 {
                    near[k] = (r, i);
                }
            }
            (ext, near)
        })
        .reduce(empty, |(mut e1, mut n1), (e2, n2)| {
            for k in 0..K {
                // ties to the lower index: deterministic for any thread count
                if e2[k].0 > e1[k].0 || (e2[k].0 == e1[k].0 && e2[k].1 < e1[k].1) {
                    e1[k] = e2[k];
                }
                if n2[k].0 < n1[k].0 || (n2[k].0 == n1[k].0 && n2[k].1 < n1[k].1) {
                    n1[k] = n2[k];
                }
            }
            (e1, n1)
        });
    let mut s: Vec<usize> = seed
        .iter()
        .copied()
        .chain(
            ext.iter()
                .chain(&near)
                .map(|e| e.1)
                .filter(|&i| i != usize::MAX),
        )
        .collect();
    s.sort_unstable();
    s.dedup();
    s
}

/// Points violating `lo <= |p - c| <= hi` by more than `tol`: up to `ADD` most violating
/// below `lo` and `ADD` above `hi` (None for an unused side), plus the min and max
/// distance over all points.
pub(crate) fn violators(
    p: &[[f64; 2]],
    c: [f64; 2],
    lo: Option<f64>,
    hi: Option<f64>,
    tol: f64,
) -> (Vec<usize>, f64, f64) {
    let d: Vec<f64> = p
        .par_iter()
        .with_min_len(8192)
        .map(|q| super::dist(*q, c))
        .collect();
    let dmin = d.par_iter().copied().reduce(|| f64::INFINITY, f64::min);
    let dmax = d.par_iter().copied().reduce(|| 0.0, f64::max);
    let mut out = Vec::new();
    if let Some(lo) = lo {
        if dmin < lo - tol {
            out.extend(worst(&d, |x| lo - x, tol));
        }
    }
    if let Some(hi) = hi {
        if dmax > hi + tol {
            out.extend(worst(&d, |x| x - hi, tol));
        }
    }
    (out, dmin, dmax)
}

fn worst(d: &[f64], viol: impl Fn(f64) -> f64 + Sync, tol: f64) -> Vec<usize> {
    let mut v: Vec<(f64, usize)> = d
        .par_iter()
        .enumerate()
        .filter_map(|(i, &x)| {
            let e = viol(x);
            (e > tol).then_some((e, i))
        })
        .collect();
    if v.len() > ADD {
        v.select_nth_unstable_by(ADD, |a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        v.truncate(ADD);
    }
    v.into_iter().map(|e| e.1).collect()
}
