//! Least-squares sphere: Levenberg-Marquardt on the orthogonal distances from the
//! algebraic (Kasa) start; 2-D points go to the circle kernel ([`crate::circle::least_squares`]).

use super::frame::{centred3, centroid, check_points, principal_axes, vec3, DEGENERATE};
use super::lm::{levenberg_marquardt_fused, normal_equations};
use super::Vector3;
use gagekit_core::{GkError, Result};
use nalgebra::{DVector, Matrix3, Matrix4, Vector4};

/// A circle in 2-D or a sphere in 3-D (`center.len()` = dimension).
#[derive(Debug, Clone, PartialEq)]
pub struct Sphere {
    pub center: Vec<f64>,
    pub radius: f64,
}

/// Algebraic (Kåsa) fit of centred points: centre offset and radius, from the normal
/// equations of |x|^2 = 2 c . x + k (rows (2 x_1 .. 2 x_dim, 1)), with `dim` 2 (a circle: the
/// third coordinate is ignored) or 3. One pass over the iterator into fixed 3 x 3 or 4 x 4
/// normal equations, no allocation: the start of every sphere and circle fit, and the score
/// of each direction of the cylinder's start grid (`cylinder::circle_score`).
pub(crate) fn algebraic_sphere(q: impl IntoIterator<Item = [f64; 3]>, dim: usize) -> Option<(Vector3<f64>, f64)> {
    let p = dim + 1;
    let mut a = [[0.0; 4]; 4];
    let mut b = [0.0; 4];
    let mut row = [0.0; 4];
    for x in q {
        for d in 0..dim {
            row[d] = 2.0 * x[d];
        }
        row[dim] = 1.0;
        let rhs: f64 = (0..dim).map(|d| x[d] * x[d]).sum();
        for i in 0..p {
            b[i] += row[i] * rhs;
            for j in 0..p {
                a[i][j] += row[i] * row[j];
            }
        }
    }
    // the same LU with partial pivoting as a dynamic matrix, on the stack
    let sol: [f64; 4] = if dim == 2 {
        let s = Matrix3::from_fn(|i, j| a[i][j]).lu().solve(&Vector3::new(b[0], b[1], b[2]))?;
        [s[0], s[1], s[2], 0.0]
    } else {
        let s = Matrix4::from_fn(|i, j| a[i][j]).lu().solve(&Vector4::new(b[0], b[1], b[2], b[3]))?;
        [s[0], s[1], s[2], s[3]]
    };
    let mut c = Vector3::zeros();
    for d in 0..dim {
        c[d] = sol[d];
    }
    let r2 = sol[dim] + c.norm_squared();
    (r2 > 0.0 && sol.iter().all(|v| v.is_finite())).then(|| (c, r2.sqrt()))
}

/// Geometric least-squares sphere of centred 3-D points.
fn geometric_sphere(q: &[[f64; 3]]) -> Result<(Vector3<f64>, f64)> {
    let start = algebraic_sphere(q.iter().copied(), 3).ok_or_else(|| GkError::degenerate("sphere: the points do not determine a sphere"))?;
    // a trial step is judged by the residuals' sum of the normal equations' pass (the
    // same sum, bit for bit, as a separate cost pass: one pass an accepted step)
    let eval = |s: &(Vector3<f64>, f64)| {
        let e = normal_equations::<4>(q, |x: &[f64; 3]| {
            let dv = vec3(x) - s.0;
            let rho = dv.norm();
            let g = |d: usize| if rho > 0.0 { -dv[d] / rho } else { 0.0 };
            (rho - s.1, [g(0), g(1), g(2), -1.0])
        });
        (e.0, e)
    };
    let apply = |s: &(Vector3<f64>, f64), st: &DVector<f64>| (s.0 + Vector3::new(st[0], st[1], st[2]), s.1 + st[3]);
    let (s, _, _) = levenberg_marquardt_fused(start, 4, start.1, 500, eval, apply, "sphere")?;
    Ok((s.0, s.1.abs()))
}

/// Least-squares circle of 2-D points (dim 2) or sphere of 3-D points (dim 3),
/// minimising the sum of squared orthogonal distances. The circle is the one 2-D
/// least-squares circle of the package, [`crate::circle::least_squares`].
pub fn sphere(pts: &[f64], dim: usize) -> Result<Sphere> {
    let what = if dim == 2 { "circle" } else { "sphere" };
    check_points(pts, dim, dim + 1, what)?;
    let c = centroid(pts, dim);
    let q = centred3(pts, dim, &c);
    let (sv, _) = principal_axes(&q);
    if sv[0] == 0.0 {
        return Err(GkError::degenerate(format!("{what}: all points coincide")));
    }
    if sv[dim - 1] <= DEGENERATE * sv[0] {
        let shape = if dim == 2 { "collinear" } else { "coplanar" };
        return Err(GkError::degenerate(format!(
            "{what}: the points are {shape}; a {what} through them is not determined"
        )));
    }
    if dim == 2 {
        let circle = crate::circle::least_squares(pts)?;
        return Ok(Sphere { center: circle.center.to_vec(), radius: circle.radius });
    }
    let (off, r) = geometric_sphere(&q)?;
    Ok(Sphere { center: (0..3).map(|d| c[d] + off[d]).collect(), radius: r })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_and_sphere() {
        let pts: Vec<f64> = (0..7)
            .flat_map(|i| {
                let t = i as f64;
                [3.0 + 2.0 * t.cos(), -1.0 + 2.0 * t.sin()]
            })
            .collect();
        let s = sphere(&pts, 2).unwrap();
        assert!((s.radius - 2.0).abs() < 1e-12 && (s.center[0] - 3.0).abs() < 1e-12);
        assert!(sphere(&[0.0, 0.0, 1.0, 1.0, 2.0, 2.0], 2).is_err());
        let flat = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0];
        assert!(sphere(&flat, 3).is_err());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// On spherical caps of half angle 0.05 rad to a whole sphere (radii 2 to 80 mm, far
        /// from the origin, noise along the normal), the fit from the algebraic start is found
        /// and its cost is at most that of the generating sphere: the global basin, as the
        /// cylinder's and cone's start tests ask of theirs.
        #[test]
        fn the_fit_is_no_worse_than_the_generating_sphere(
            seed in 0u64..1000, r in 2.0f64..80.0, cap in 0.05f64..std::f64::consts::PI, noise in 1e-4f64..0.01,
            tilt in -1.0f64..1.0, far in 0.0f64..1e4,
        ) {
            use rand::{Rng, SeedableRng};
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let a = Vector3::new(tilt, 0.4, 1.0).normalize();
            let (u, v) = super::super::frame::orthonormal_basis(&a);
            let o = Vector3::new(far, -0.5 * far, 0.3 * far);
            let (mut pts, mut generating) = (Vec::new(), 0.0);
            for _ in 0..2000 {
                // uniform on the cap: cos of the polar angle uniform on [cos cap, 1]
                let ct = 1.0 - rng.random::<f64>() * (1.0 - cap.cos());
                let g = rng.random::<f64>() * std::f64::consts::TAU;
                let n = a * ct + (u * g.cos() + v * g.sin()) * (1.0 - ct * ct).max(0.0).sqrt();
                let e: f64 = (0..4).map(|_| rng.random::<f64>() - 0.5).sum::<f64>() * noise * 1.7;
                let q = o + n * (r + e);
                generating += e * e;
                pts.extend_from_slice(&[q[0], q[1], q[2]]);
            }
            let s = sphere(&pts, 3).unwrap();
            let c = Vector3::new(s.center[0], s.center[1], s.center[2]);
            let f: f64 = pts.chunks(3).map(|x| ((vec3(x) - c).norm() - s.radius).powi(2)).sum();
            proptest::prop_assert!(f <= generating * (1.0 + 1e-9) + 1e-20, "{f:e} > {generating:e}: {s:?}");
        }
    }
}
