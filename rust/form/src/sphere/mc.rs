//! Minimum circumscribed sphere by Welzl's algorithm in 3-D (move-to-front form of
//! the nested loops; exact, expected linear time).

use super::{dist, extremes, SphereZone};
use crate::lsq;
use gagekit_core::{check_finite, GkError, Result};
use nalgebra::{Matrix3, Vector3};
use rand::seq::SliceRandom;
use rand::SeedableRng;

/// Seed of the fixed shuffle: the result never depends on the run.
const SEED: u64 = 0x6d63_7370;

#[derive(Clone, Copy)]
struct Ball {
    c: Vector3<f64>,
    r: f64,
}

fn v(p: &[[f64; 3]], i: usize) -> Vector3<f64> {
    Vector3::from(p[i])
}

fn diametral(a: Vector3<f64>, b: Vector3<f64>) -> Ball {
    let c = (a + b) * 0.5;
    Ball { c, r: (a - c).norm().max((b - c).norm()) }
}

/// Smallest ball through three points (their circumcircle in their plane; the
/// diametral ball of the farthest pair when collinear).
fn through3(a: Vector3<f64>, b: Vector3<f64>, c: Vector3<f64>) -> Ball {
    let (ab, ac) = (b - a, c - a);
    let n = ab.cross(&ac);
    let n2 = n.norm_squared();
    if n2 > 0.0 && n2.is_finite() {
        let o = a + (n.cross(&ab) * ac.norm_squared() + ac.cross(&n) * ab.norm_squared()) / (2.0 * n2);
        if o.iter().all(|x| x.is_finite()) {
            let r = (a - o).norm().max((b - o).norm()).max((c - o).norm());
            return Ball { c: o, r };
        }
    }
    [diametral(a, b), diametral(a, c), diametral(b, c)].into_iter().max_by(|x, y| x.r.total_cmp(&y.r)).unwrap_or(Ball { c: a, r: 0.0 })
}

/// Ball through four points (their circumsphere), or the smallest of the balls
/// through three of them that contains the fourth when they are coplanar.
fn through4(a: Vector3<f64>, b: Vector3<f64>, c: Vector3<f64>, d: Vector3<f64>, tol: f64) -> Ball {
    let m = Matrix3::from_rows(&[(b - a).transpose(), (c - a).transpose(), (d - a).transpose()]) * 2.0;
    let rhs = Vector3::new((b - a).norm_squared(), (c - a).norm_squared(), (d - a).norm_squared());
    if let Some(x) = m.lu().solve(&rhs).filter(|x| x.iter().all(|v| v.is_finite())) {
        let o = a + x;
        let r = [a, b, c, d].iter().map(|p| (p - o).norm()).fold(0.0, f64::max);
        return Ball { c: o, r };
    }
    let pts = [a, b, c, d];
    let mut best: Option<Ball> = None;
    for skip in 0..4 {
        let q: Vec<Vector3<f64>> = (0..4).filter(|&k| k != skip).map(|k| pts[k]).collect();
        let ball = through3(q[0], q[1], q[2]);
        if (pts[skip] - ball.c).norm() <= ball.r + tol && best.is_none_or(|b| ball.r < b.r) {
            best = Some(ball);
        }
    }
    best.unwrap_or_else(|| through3(a, b, c))
}

/// Minimum circumscribed sphere of 3-D points (flat, row-major, at least 1 point).
/// `control_out` holds the 1 to 4 points that fix it; the radius is recomputed as the
/// largest distance of any point to the centre, so the sphere contains every point.
pub fn min_circumscribed(pts: &[f64]) -> Result<SphereZone> {
    check_finite(pts, 3, "points")?;
    lsq::check_magnitude(pts, 3)?;
    let n = pts.len() / 3;
    if n == 0 {
        return Err(GkError::invalid("minimum circumscribed sphere: need at least 1 point, got 0"));
    }
    // centred on the bounding box: accuracy does not depend on the distance to the origin
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in pts.chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let mid = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
    let scale = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let p: Vec<[f64; 3]> = pts.chunks_exact(3).map(|q| [q[0] - mid[0], q[1] - mid[1], q[2] - mid[2]]).collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(SEED));
    let tol = 1e-14 * scale;
    let out = |b: &Ball, i: usize| (v(&p, i) - b.c).norm() > b.r + tol;
    let mut ball = Ball { c: v(&p, order[0]), r: 0.0 };
    let mut ctrl = vec![order[0]];
    for i in 1..n {
        let a = order[i];
        if !out(&ball, a) {
            continue;
        }
        ball = Ball { c: v(&p, a), r: 0.0 };
        ctrl = vec![a];
        for j in 0..i {
            let b = order[j];
            if !out(&ball, b) {
                continue;
            }
            ball = diametral(v(&p, a), v(&p, b));
            ctrl = vec![a, b];
            for k in 0..j {
                let c = order[k];
                if !out(&ball, c) {
                    continue;
                }
                ball = through3(v(&p, a), v(&p, b), v(&p, c));
                ctrl = vec![a, b, c];
                for l in 0..k {
                    let d = order[l];
                    if !out(&ball, d) {
                        continue;
                    }
                    ball = through4(v(&p, a), v(&p, b), v(&p, c), v(&p, d), tol);
                    ctrl = vec![a, b, c, d];
                }
            }
        }
    }
    let center = [ball.c[0] + mid[0], ball.c[1] + mid[1], ball.c[2] + mid[2]];
    let r = pts.chunks_exact(3).map(|q| dist(q, &center)).fold(0.0, f64::max);
    ctrl.sort_unstable();
    let _ = extremes;
    Ok(SphereZone { center, r_in: r, r_out: r, control_in: ctrl.clone(), control_out: ctrl, iterations: 0, bound: r, cubes: 0 })
}
