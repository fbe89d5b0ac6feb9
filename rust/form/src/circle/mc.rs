//! Minimum circumscribed circle (MC, Eq. 6.1) by Welzl's randomized incremental
//! algorithm (move-to-front form), exact, expected linear time.

use super::{circumcenter, dist, dist2, Centered, Circle};
use gagekit_core::Result;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rayon::prelude::*;

/// Seed of the fixed shuffle: the result never depends on the run.
const SEED: u64 = 0x6a6b_636d;

#[derive(Clone, Copy)]
struct Disk {
    c: [f64; 2],
    r2: f64,
}

/// Minimum circumscribed circle of `pts` (flat (n, 2), n >= 1).
///
/// Welzl's algorithm: the points are visited in a fixed pseudo-random order and the
/// circle grows only when a point falls outside it (Sec. 6.2.1, Fig. 6.1). `control`
/// holds the 1, 2 or 3 points that fix the circle (cases 1-3 of Sec. 6.2.1; with
/// 4 or more cocircular points, three of them). The radius is recomputed as the
/// largest distance of any input point to the centre, so the circle contains every
/// point exactly.
pub fn min_circumscribed(pts: &[f64]) -> Result<Circle> {
    let data = Centered::new(pts, "minimum circumscribed circle", 1)?;
    let (c, control) = welzl(&data.pts, data.scale);
    let r = data
        .pts
        .par_iter()
        .with_min_len(8192)
        .map(|p| dist(*p, c))
        .reduce(|| 0.0, f64::max);
    Ok(Circle {
        center: data.uncenter(c),
        radius: r,
        control,
    })
}

/// Welzl on centred points; returns the centre (centred coordinates) and the control
/// indices.
pub(crate) fn welzl(p: &[[f64; 2]], scale: f64) -> ([f64; 2], Vec<usize>) {
    let n = p.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(SEED));
    // a point is outside when beyond the circle by more than rounding noise
    let tol = 1e-14 * scale.max(f64::MIN_POSITIVE);
    let outside = |d: &Disk, q: [f64; 2]| {
        let dd = dist2(q, d.c);
        dd > d.r2 && dd.sqrt() > d.r2.sqrt() + tol
    };
    let mut disk = Disk {
        c: p[order[0]],
        r2: 0.0,
    };
    let mut ctrl = vec![order[0]];
    for i in 1..n {
        let pi = p[order[i]];
        if !outside(&disk, pi) {
            continue;
        }
        // circle through pi containing order[..i]
        disk = Disk { c: pi, r2: 0.0 };
        ctrl = vec![order[i]];
        for j in 0..i {
            let pj = p[order[j]];
            if !outside(&disk, pj) {
                continue;
            }
            disk = diametral(pi, pj);
            ctrl = vec![order[i], order[j]];
            for k in 0..j {
                let pk = p[order[k]];
                if !outside(&disk, pk) {
                    continue;
                }
                let (d, c) = through3([order[i], order[j], order[k]], p);
                disk = d;
                ctrl = c;
            }
        }
    }
    ctrl.sort_unstable();
    (disk.c, ctrl)
}

fn diametral(a: [f64; 2], b: [f64; 2]) -> Disk {
    let c = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    Disk {
        c,
        r2: dist2(a, c).max(dist2(b, c)),
    }
}

/// Circle through three points (the smallest one containing them if they are
/// numerically collinear: the diametral circle of the farthest pair).
fn through3(idx: [usize; 3], p: &[[f64; 2]]) -> (Disk, Vec<usize>) {
    let [a, b, c] = idx.map(|i| p[i]);
    if let Some(u) = circumcenter(a, b, c) {
        let r2 = dist2(a, u).max(dist2(b, u)).max(dist2(c, u));
        return (Disk { c: u, r2 }, idx.to_vec());
    }
    // the longest of the three pairs (the last of equals, as `Iterator::max_by`)
    let len2 = |(i, j): (usize, usize)| dist2(p[idx[i]], p[idx[j]]);
    let (i, j) = [(0, 2), (1, 2)]
        .into_iter()
        .fold((0, 1), |best, x| if len2(x).total_cmp(&len2(best)).is_ge() { x } else { best });
    (diametral(p[idx[i]], p[idx[j]]), vec![idx[i], idx[j]])
}
