//! Least-squares cylinder and sphere of points near those of a known fit (a Monte Carlo
//! trial of the measured points, issue 26): Gauss-Newton on the orthogonal distances from
//! that fit, in one pass over the points an iteration, instead of the complete fits'
//! starts, subsample iterations, input checks and centred copies.
//!
//! A trial's optimum is the measured one moved by the noise (a few sigma / sqrt(n) away),
//! where Gauss-Newton converges linearly at a small rate rho (the residuals are small
//! against the radius). Each pass sums, at the current parameters, J^T r and the cost (sum
//! of squared residuals), checks every coordinate (finite, within [`MAX_COORD`]) and the
//! height of the points along the axis; the first pass also sums J^T J, which the later
//! steps keep (the simplified Gauss-Newton, or chord, method: its rate is Gauss-Newton's
//! plus the relative change of J^T J over the steps, about the first step over the
//! radius, 1e-7 on the bracket; the stopping rule below measures the rate it gets). The
//! iteration stops when
//! the step's size in mm (the largest change of the axis position or the radius, the
//! direction change times the largest height of a point along the axis) is at most
//! [`TOL`], or when the contraction estimate says the rest is: with rho estimated by the
//! ratio of the last two steps (at most 1/2), the distance of the stationary point from
//! the iterate after the step is at most rho / (1 - rho) times the step (the a posteriori
//! bound of a contraction), and that bound is at most [`TOL`]; the last step is applied
//! (a step of at most 1e-8 mm). Each iteration's cost must not exceed the previous one
//! beyond rounding (1e-12 relative): a step that raises it, a singular or ill-conditioned
//! J^T J, a non-finite or out-of-range coordinate, too few points or no convergence in
//! [`MAX_PASSES`] passes fall back to the complete fit ([`cylinder_near`] from the known
//! direction, [`sphere`]), which also raises the typed error of bad input.
//!
//! On the bracket's 2 M-point bore (378 k points) a trial takes two passes where the
//! complete fit took about seven and a subsample's iterations; the result is the complete
//! fit's stationary point to about 1e-14 mm (tests below: 1e-10 mm on random perturbed
//! cylinders and spheres).

use super::cylinder::{cylinder_near, Cylinder};
use super::frame::{arr, orthonormal_basis, upper, MAX_COORD};
use super::sphere::{sphere, Sphere};
use super::Vector3;
use gagekit_core::Result;
use nalgebra::{SMatrix, SVector};

/// Stopping tolerance of the step (mm, or mm-equivalent for a direction change).
pub const TOL: f64 = 1e-12;
/// Passes over the points before the complete fit is run instead.
pub const MAX_PASSES: usize = 8;
/// Points a chunk of the sums (the chunks' sums are added in order).
const CHUNK: usize = 4096;

/// Sums of one pass: J^T J (upper), J^T r, the cost, the sum of the offsets from the
/// origin (cylinder: for the centroid), the largest |height| along the axis, and whether
/// every coordinate was finite and within MAX_COORD.
struct Sums<const P: usize> {
    jtj: [[f64; P]; P],
    jtr: [f64; P],
    cost: f64,
    off: [f64; 3],
    hmax: f64,
    ok: bool,
}

impl<const P: usize> Sums<P> {
    fn zero() -> Self {
        Sums { jtj: [[0.0; P]; P], jtr: [0.0; P], cost: 0.0, off: [0.0; 3], hmax: 0.0, ok: true }
    }

    fn add(&mut self, o: &Sums<P>) {
        for a in 0..P {
            self.jtr[a] += o.jtr[a];
            for b in a..P {
                self.jtj[a][b] += o.jtj[a][b];
            }
        }
        self.cost += o.cost;
        for k in 0..3 {
            self.off[k] += o.off[k];
        }
        self.hmax = self.hmax.max(o.hmax);
        self.ok &= o.ok;
    }

    /// The Gauss-Newton step -(J^T J)^-1 J^T r, or None when J^T J is singular or
    /// ill-conditioned (a Cholesky pivot below 1e-7 of the square root of its diagonal).
    fn step(&self) -> Option<SVector<f64, P>> {
        let mut m = SMatrix::<f64, P, P>::zeros();
        let mut dmax = 0.0f64;
        for a in 0..P {
            dmax = dmax.max(self.jtj[a][a]);
            for b in a..P {
                m[(a, b)] = self.jtj[a][b];
                m[(b, a)] = self.jtj[a][b];
            }
        }
        let ch = m.cholesky()?;
        let l = ch.l_dirty();
        if !(0..P).all(|k| l[(k, k)] > 1e-7 * dmax.sqrt()) {
            return None;
        }
        let s = ch.solve(&-SVector::<f64, P>::from_column_slice(&self.jtr));
        s.iter().all(|v| v.is_finite()).then_some(s)
    }
}

/// The sums of one pass over `pts` (flat (n, 3)) with rows `row(x) -> (r, J_row, height)`
/// of the point's offset `x` from `origin`, in fixed chunks added in order (deterministic);
/// J^T J only when `full` (else zero: the caller keeps an earlier one).
fn pass<const P: usize>(pts: &[f64], origin: [f64; 3], full: bool, row: impl Fn([f64; 3]) -> (f64, [f64; P], f64)) -> Sums<P> {
    if full {
        pass_with::<P, true>(pts, origin, row)
    } else {
        pass_with::<P, false>(pts, origin, row)
    }
}

#[inline(always)]
fn pass_with<const P: usize, const FULL: bool>(
    pts: &[f64],
    origin: [f64; 3],
    row: impl Fn([f64; 3]) -> (f64, [f64; P], f64),
) -> Sums<P> {
    let mut total = Sums::zero();
    for c in pts.chunks(3 * CHUNK) {
        let mut s = Sums::<P>::zero();
        let mut ok = true;
        for p in c.chunks_exact(3) {
            ok &= (p[0].abs() <= MAX_COORD) & (p[1].abs() <= MAX_COORD) & (p[2].abs() <= MAX_COORD);
            let x = [p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]];
            let (r, j, h) = row(x);
            s.cost += r * r;
            for k in 0..3 {
                s.off[k] += x[k];
            }
            s.hmax = s.hmax.max(h.abs());
            for a in 0..P {
                s.jtr[a] += j[a] * r;
                if FULL {
                    for b in a..P {
                        s.jtj[a][b] += j[a] * j[b];
                    }
                }
            }
        }
        s.ok = ok;
        total.add(&s);
    }
    total
}

/// The iteration of the module docs: `eval(params)` the sums at `params`, `size(step,
/// sums)` the step's size in mm, `apply(params, step)` the next parameters. None: fall
/// back to the complete fit.
fn gauss_newton<S: Clone, const P: usize>(
    start: S,
    eval: impl Fn(&S, bool) -> Sums<P>,
    size: impl Fn(&SVector<f64, P>, &Sums<P>) -> f64,
    apply: impl Fn(&S, &SVector<f64, P>) -> S,
) -> Option<(S, Sums<P>)> {
    let mut s = start;
    let mut prev_cost = f64::INFINITY;
    let mut prev_size = f64::INFINITY;
    let mut jtj = None;
    for _ in 0..MAX_PASSES {
        let mut sums = eval(&s, jtj.is_none());
        // the J^T J of the first pass is kept (simplified Gauss-Newton, module docs)
        let first = *jtj.get_or_insert(sums.jtj);
        sums.jtj = first;
        if !sums.ok || !sums.cost.is_finite() || sums.cost > prev_cost * (1.0 + 1e-12) {
            return None;
        }
        let step = sums.step()?;
        let h = size(&step, &sums);
        let rho = h / prev_size;
        let next = apply(&s, &step);
        if h <= TOL || (h <= 1e-8 && rho <= 0.5 && h * rho / (1.0 - rho) <= TOL) {
            return Some((next, sums));
        }
        (s, prev_cost, prev_size) = (next, sums.cost, h);
    }
    None
}

/// The least-squares cylinder of `pts` (flat (n, 3)) from the cylinder `start` of points
/// near them (module docs): the stationary point [`cylinder_near`] from `start.direction`
/// converges to, the same kind of result (the point the foot of the centroid on the axis,
/// the direction in the upper half sphere).
pub fn cylinder_warm(pts: &[f64], start: &Cylinder) -> Result<Cylinder> {
    match cylinder_gn(pts, start) {
        Some(c) => Ok(c),
        None => cylinder_near(pts, start.direction),
    }
}

/// The Gauss-Newton iteration of [`cylinder_warm`]; None: run the complete fit.
fn cylinder_gn(pts: &[f64], start: &Cylinder) -> Option<Cylinder> {
    let o = start.point;
    let a0 = Vector3::from(start.direction);
    if pts.len() < 15 || pts.len() % 3 != 0 || !(a0.norm() > 0.0) || !o.iter().all(|x| x.is_finite()) || !start.radius.is_finite() {
        return None;
    }
    // parameters: the axis point l (offset from o, kept in the plane through o normal to
    // the axis), the unit direction a, the radius; a step (x0, y0, alpha, beta, dr) in the
    // frame (u, v, a): l += x0 u + y0 v, a = normalize(a + alpha u + beta v) (Forbes 1989)
    type S = (Vector3<f64>, Vector3<f64>, f64);
    let eval = |s: &S, full: bool| {
        let (u, w) = orthonormal_basis(&s.1);
        let (l, a, r) = (s.0, s.1, s.2);
        pass::<5>(pts, o, full, |x| {
            let d = [x[0] - l[0], x[1] - l[1], x[2] - l[2]];
            let xu = d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
            let yv = d[0] * w[0] + d[1] * w[1] + d[2] * w[2];
            let z = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
            // sqrt, not hypot: |xu|, |yv| <= 2 * MAX_COORD * sqrt(3), their squares finite
            let rho = (xu * xu + yv * yv).sqrt();
            let inv = if rho > 0.0 { 1.0 / rho } else { 0.0 };
            let (cx, cy) = (xu * inv, yv * inv);
            (rho - r, [-cx, -cy, -cx * z, -cy * z, -1.0], z)
        })
    };
    let size = |st: &SVector<f64, 5>, s: &Sums<5>| {
        st[0].abs().max(st[1].abs()).max(st[4].abs()).max(st[2].abs().max(st[3].abs()) * s.hmax)
    };
    let apply = |s: &S, st: &SVector<f64, 5>| {
        let (u, w) = orthonormal_basis(&s.1);
        let l = s.0 + u * st[0] + w * st[1];
        let a = (s.1 + u * st[2] + w * st[3]).normalize();
        (l - a * l.dot(&a), a, s.2 + st[4])
    };
    let ((l, a, r), sums) = gauss_newton((Vector3::zeros(), a0.normalize(), start.radius), eval, size, apply)?;
    // the foot of the centroid (the offsets' mean from o) on the axis
    let c = Vector3::from(sums.off) / (pts.len() / 3) as f64;
    let p = Vector3::from(o) + l + a * (c - l).dot(&a);
    (p.iter().all(|x| x.is_finite()) && a.iter().all(|x| x.is_finite()) && r.is_finite())
        .then(|| Cylinder { point: arr(&p), direction: upper(arr(&a)), radius: r.abs() })
}

/// The least-squares sphere of 3-D `pts` (flat (n, 3)) from the centre and radius of a
/// sphere of points near them (module docs): the stationary point of [`sphere`].
pub fn sphere_warm(pts: &[f64], center: [f64; 3], radius: f64) -> Result<Sphere> {
    match sphere_gn(pts, center, radius) {
        Some(s) => Ok(s),
        None => sphere(pts, 3),
    }
}

/// The Gauss-Newton iteration of [`sphere_warm`]; None: run the complete fit.
fn sphere_gn(pts: &[f64], center: [f64; 3], radius: f64) -> Option<Sphere> {
    if pts.len() < 12 || pts.len() % 3 != 0 || !center.iter().all(|x| x.is_finite()) || !radius.is_finite() {
        return None;
    }
    type S = (Vector3<f64>, f64);
    let eval = |s: &S, full: bool| {
        let (c, r) = (s.0, s.1);
        pass::<4>(pts, center, full, |x| {
            let d = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
            let rho = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let inv = if rho > 0.0 { 1.0 / rho } else { 0.0 };
            (rho - r, [-d[0] * inv, -d[1] * inv, -d[2] * inv, -1.0], 0.0)
        })
    };
    let size = |st: &SVector<f64, 4>, _: &Sums<4>| st.amax();
    let apply = |s: &S, st: &SVector<f64, 4>| (s.0 + Vector3::new(st[0], st[1], st[2]), s.1 + st[3]);
    let ((c, r), _) = gauss_newton((Vector3::zeros(), radius), eval, size, apply)?;
    let c = Vector3::from(center) + c;
    (c.iter().all(|x| x.is_finite()) && r.is_finite()).then(|| Sphere { center: arr(&c).to_vec(), radius: r.abs() })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::lsq::cylinder;
    use gagekit_core::ErrorKind;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Points on a cylinder (point, unit axis, radius, length; an arc of `arc` rad) with
    /// Gaussian-like noise (sum of uniforms) of size `noise` (also the least-squares
    /// cylinder's tests' partial arcs).
    pub(in crate::lsq) fn cyl(rng: &mut ChaCha8Rng, n: usize, p: [f64; 3], a: [f64; 3], r: f64, len: f64, arc: f64, noise: f64) -> Vec<f64> {
        let a = Vector3::from(a).normalize();
        let (u, w) = orthonormal_basis(&a);
        let mut out = Vec::with_capacity(3 * n);
        for _ in 0..n {
            let t = rng.random::<f64>() * arc;
            let z = (rng.random::<f64>() - 0.5) * len;
            let e: f64 = (0..4).map(|_| rng.random::<f64>() - 0.5).sum::<f64>() * noise * 1.7;
            let q = Vector3::from(p) + a * z + (u * t.cos() + w * t.sin()) * (r + e);
            out.extend_from_slice(&[q[0], q[1], q[2]]);
        }
        out
    }

    /// The length of a partial arc of radius `r` over `arc` rad that makes the spread along
    /// the axis `ratio` times that across the arc's depth (`chord` false) or along its chord
    /// (the variances of r cos s and r sin s, s uniform on the arc; a uniform length `len`
    /// has variance len^2 / 12), at least 0.05 r: where the principal directions mix, the
    /// partial bores and cones of the cylinder's and cone's start tests.
    pub(in crate::lsq) fn mixing_length(r: f64, arc: f64, ratio: f64, chord: bool) -> f64 {
        let h = 0.5 * arc;
        let depth = r * r * (0.5 + arc.sin() / (2.0 * arc) - (h.sin() / h).powi(2));
        let across = r * r * (0.5 - arc.sin() / (2.0 * arc));
        (12.0 * ratio * if chord { across } else { depth }).sqrt().max(0.05 * r)
    }

    fn jitter(rng: &mut ChaCha8Rng, pts: &[f64], sigma: f64) -> Vec<f64> {
        pts.iter().map(|x| x + sigma * ((0..4).map(|_| rng.random::<f64>() - 0.5).sum::<f64>() * 1.7)).collect()
    }

    /// The distance of two axes over a height `h` about `p` (mm): of the points, the
    /// directions' change times `h`.
    fn axis_gap(a: &Cylinder, b: &Cylinder, h: f64) -> f64 {
        let (da, db) = (Vector3::from(a.direction), Vector3::from(b.direction));
        let db = if da.dot(&db) < 0.0 { -db } else { db };
        let q = Vector3::from(a.point) - Vector3::from(b.point);
        let off = (q - db * q.dot(&db)).norm();
        off + (da - db).norm() * h + (a.radius - b.radius).abs()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn the_warm_cylinder_is_the_complete_fit_of_a_perturbed_trial(
            seed in 0u64..1000, far in 0.0f64..1e4, r in 2.0f64..80.0, len in 5.0f64..120.0,
            arc in 1.5f64..6.3, noise in 1e-4f64..0.01, tilt in -1.0f64..1.0,
        ) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let p = [far, -0.5 * far, 0.3 * far];
            let a = [tilt, 0.4, 1.0];
            let measured = cyl(&mut rng, 3000, p, a, r, len, arc, noise);
            let m = cylinder(&measured, None).unwrap();
            let trial = jitter(&mut rng, &measured, noise);
            let full = cylinder_near(&trial, m.direction).unwrap();
            let warm = cylinder_warm(&trial, &m).unwrap();
            prop_assert!(cylinder_gn(&trial, &m).is_some(), "the Gauss-Newton path falls back");
            prop_assert!(axis_gap(&full, &warm, len) <= 1e-10, "{full:?} {warm:?}");
            // the point is the foot of the centroid, as the complete fit's
            prop_assert!((Vector3::from(full.point) - Vector3::from(warm.point)).norm() <= 1e-9 + 1e-15 * far, "{full:?} {warm:?}");
        }

        #[test]
        fn the_warm_sphere_is_the_complete_fit_of_a_perturbed_trial(
            seed in 0u64..1000, far in 0.0f64..1e4, r in 1.0f64..60.0, cap in 0.6f64..3.1, noise in 1e-4f64..0.01,
        ) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let c = [far, 0.7 * far, -far];
            let measured: Vec<f64> = (0..2000)
                .flat_map(|_| {
                    let th = (1.0 - rng.random::<f64>() * (1.0 - cap.cos())).acos();
                    let ph = rng.random::<f64>() * std::f64::consts::TAU;
                    let e = noise * ((0..4).map(|_| rng.random::<f64>() - 0.5).sum::<f64>() * 1.7);
                    let rr = r + e;
                    [c[0] + rr * th.sin() * ph.cos(), c[1] + rr * th.sin() * ph.sin(), c[2] + rr * th.cos()]
                })
                .collect();
            let m = sphere(&measured, 3).unwrap();
            let trial = jitter(&mut rng, &measured, noise);
            let full = sphere(&trial, 3).unwrap();
            let warm = sphere_warm(&trial, [m.center[0], m.center[1], m.center[2]], m.radius).unwrap();
            prop_assert!(sphere_gn(&trial, [m.center[0], m.center[1], m.center[2]], m.radius).is_some());
            let gap = (0..3).map(|k| (full.center[k] - warm.center[k]).abs()).fold(0.0, f64::max);
            prop_assert!(gap <= 1e-10 && (full.radius - warm.radius).abs() <= 1e-10, "{full:?} {warm:?}");
        }
    }

    #[test]
    fn a_far_start_or_bad_input_falls_back_to_the_complete_fit() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let pts = cyl(&mut rng, 4000, [10.0, 20.0, 30.0], [0.1, 0.2, 1.0], 12.0, 40.0, 6.3, 0.002);
        let full = cylinder(&pts, None).unwrap();
        // from the complete fit itself: the Gauss-Newton path, no fallback
        assert!(cylinder_gn(&pts, &full).is_some());
        // starts where Gauss-Newton fails (a step raises the cost, no contraction in the
        // passes, a singular J^T J): the complete fit from that direction, the same cylinder
        let mut fell = 0;
        for (off, tilt, dr) in [(0.5, 0.05, 2.0), (3.0, 0.6, -5.0), (8.0, 2.0, 30.0), (0.0, 40.0, 0.0)] {
            let s = Cylinder { point: [10.0 + off, 20.0, 30.0], direction: [0.1 + tilt, 0.2, 1.0], radius: 12.0 + dr };
            fell += cylinder_gn(&pts, &s).is_none() as usize;
            let warm = cylinder_warm(&pts, &s).unwrap();
            assert!(axis_gap(&full, &warm, 40.0) <= 1e-10, "{off} {tilt} {dr}: {full:?} {warm:?}");
        }
        assert!(fell >= 1, "no start needed the fallback");
        // a NaN and a coordinate beyond 1e150 mm raise the complete fit's typed errors
        let mut nan = pts.clone();
        nan[40] = f64::NAN;
        let mut huge = pts.clone();
        huge[40] = 1e151;
        for bad in [nan, huge] {
            let (e1, e2) = (cylinder_warm(&bad, &full).unwrap_err(), cylinder_near(&bad, full.direction).unwrap_err());
            assert_eq!((e1.kind, e1.message), (e2.kind, e2.message));
            assert_eq!(e1.kind, ErrorKind::InvalidInput);
            let e3 = sphere_warm(&bad, [10.0, 20.0, 30.0], 12.0).unwrap_err();
            assert_eq!(e3.kind, ErrorKind::InvalidInput);
        }
        // too few points, coincident points: the complete fit's errors
        assert!(cylinder_warm(&pts[..12], &full).is_err());
        assert_eq!(cylinder_warm(&[1.0; 30], &full).unwrap_err().kind, ErrorKind::DegenerateGeometry);
        assert_eq!(sphere_warm(&[1.0; 30], [1.0, 1.0, 1.0], 1.0).unwrap_err().kind, ErrorKind::DegenerateGeometry);
    }
}
