//! Least-squares cone (Forbes' parametrisation), from algebraic starts about each
//! principal axis ([`algebraic_cone`]). Unlike the cylinder's, these starts need no grid
//! of directions: on 1,000 random partial cones whose axial spread is near the depth or
//! chord spread (the test below), the principal axes alone reached the global basin.

use super::frame::{arr, centred3, centroid, check_points, orthonormal_basis, principal_axes, vec3, DEGENERATE};
use super::lm::{det_sum, levenberg_marquardt, normal_equations};
use super::Vector3;
use gagekit_core::{GkError, Result};
use nalgebra::{DMatrix, DVector};
use std::f64::consts::{FRAC_PI_2, PI};

/// A cone: a point on the axis, the unit axis direction, the signed
/// orthogonal distance from that point to the surface (positive inside) and
/// the half apex angle (rad; the radius grows along `direction`).
#[derive(Debug, Clone, PartialEq)]
pub struct Cone {
    pub point: [f64; 3],
    pub direction: [f64; 3],
    pub distance: f64,
    pub half_angle: f64,
}

/// Algebraic cone for a known axis direction `a` (centred points): with
/// rho = s + t z about the axis through (x0, y0), x^2 + y^2 is linear in
/// (1, z, z^2, x, y): (x - x0)^2 + (y - y0)^2 = c0 + x0^2 + y0^2 + c1 z + c2 z^2 =
/// s^2 + 2 s t z + t^2 z^2. Returns the axis point offset, s and t: s the radius at the
/// centroid's plane, sqrt(c0 + x0^2 + y0^2), and t = c1 / (2 s); t = sqrt(c2) only when
/// that radius is not positive (the apex near the centroid). The slope from c2 alone
/// (as before) is the square root of a small, noisy number for a narrow cone: about an
/// axis 0.04 rad off a cone of half angle 3 degrees, c2 came out negative, and with every
/// start refused the fit failed.
fn algebraic_cone(q: &[[f64; 3]], a: &Vector3<f64>) -> Option<(Vector3<f64>, f64, f64)> {
    let (u, v) = orthonormal_basis(a);
    let mut m = DMatrix::<f64>::zeros(5, 5);
    let mut b = DVector::<f64>::zeros(5);
    for p in q {
        let pv = vec3(p);
        let (x, y, z) = (pv.dot(&u), pv.dot(&v), pv.dot(a));
        let row = [1.0, z, z * z, x, y];
        let rhs = x * x + y * y;
        for i in 0..5 {
            b[i] += row[i] * rhs;
            for j in 0..5 {
                m[(i, j)] += row[i] * row[j];
            }
        }
    }
    let c = m.lu().solve(&b)?;
    let (x0, y0) = (0.5 * c[3], 0.5 * c[4]);
    let r0 = c[0] + x0 * x0 + y0 * y0;
    let (s, t) = if r0 > 0.0 {
        let s = r0.sqrt();
        (s, c[1] / (2.0 * s))
    } else if c[2] > 0.0 {
        let t = c[2].sqrt();
        (c[1] / (2.0 * t), t)
    } else {
        return None;
    };
    (s.is_finite() && t.is_finite()).then(|| (u * x0 + v * y0, s, t))
}

/// Least-squares cone, minimising the squared orthogonal distances
/// d = rho cos(psi) - z sin(psi) - D (Forbes' parametrisation), from
/// algebraic starts about each principal axis.
pub fn cone(pts: &[f64]) -> Result<Cone> {
    cone_with(pts, None)
}

/// [`cone`] with the half angle free (`None`) or fixed to `half_angle` (rad, in
/// (0, pi/2); the caller checks it): the fixed angle's step is held at 0.
pub fn cone_with(pts: &[f64], half_angle: Option<f64>) -> Result<Cone> {
    check_points(pts, 3, 6, "cone")?;
    let c = centroid(pts, 3);
    let q = centred3(pts, 3, &c);
    let (sv, axes) = principal_axes(&q);
    if sv[0] == 0.0 || sv[1] <= DEGENERATE * sv[0] {
        return Err(GkError::degenerate("cone: the points are coincident or collinear; no cone is determined"));
    }
    type S = (Vector3<f64>, Vector3<f64>, f64, f64); // point, direction, D, psi
    let cost = |s: &S| {
        let (cp, sp) = (s.3.cos(), s.3.sin());
        det_sum(&q, |x| {
            let d = vec3(x) - s.0;
            let z = d.dot(&s.1);
            ((d - s.1 * z).norm() * cp - z * sp - s.2).powi(2)
        })
    };
    let eval = |s: &S| {
        let (u, v) = orthonormal_basis(&s.1);
        let (cp, sp) = (s.3.cos(), s.3.sin());
        let fixed = half_angle.is_some() as u8 as f64;
        let (f, mut jtj, jtr) = normal_equations::<6>(&q, |x| {
            let d = vec3(x) - s.0;
            let (xu, yv, z) = (d.dot(&u), d.dot(&v), d.dot(&s.1));
            let rho = xu.hypot(yv);
            let (cx, cy) = if rho > 0.0 { (xu / rho, yv / rho) } else { (0.0, 0.0) };
            let r = rho * cp - z * sp - s.2;
            // step (x0, y0, alpha, beta, dD, dpsi); a' = a + alpha u + beta v
            let dpsi = (1.0 - fixed) * (-rho * sp - z * cp);
            (r, [-cp * cx, -cp * cy, -cp * cx * z - sp * xu, -cp * cy * z - sp * yv, -1.0, dpsi])
        });
        if half_angle.is_some() {
            // a fixed angle: zero gradient and a unit curvature keep its step at 0
            jtj[(5, 5)] = 1.0;
        }
        (f, jtj, jtr)
    };
    let apply = |s: &S, st: &DVector<f64>| {
        let (u, v) = orthonormal_basis(&s.1);
        let l = s.0 + u * st[0] + v * st[1];
        let a = (s.1 + u * st[2] + v * st[3]).normalize();
        (l, a, s.2 + st[4], s.3 + st[5])
    };
    let mut best: Option<(S, f64)> = None;
    for a in axes {
        let Some((l0, s0, t0)) = algebraic_cone(&q, &a) else { continue };
        // the algebraic fit gives rho = s0 + t0 z (up to the sign of t0)
        for sign in [1.0, -1.0] {
            let psi = half_angle.map_or((sign * t0).atan(), |h| sign * h);
            let start: S = (l0, a, s0 * psi.cos(), psi);
            if let Ok((sol, _)) = levenberg_marquardt(start, 6, sv[0] / (q.len() as f64).sqrt(), 500, eval, cost, apply, "cone") {
                let f = cost(&sol);
                if f.is_finite() && best.as_ref().is_none_or(|b| f < b.1) {
                    best = Some((sol, f));
                }
            }
        }
    }
    let ((l, a, dd, psi), _) =
        best.ok_or_else(|| GkError::degenerate("cone: the points do not determine a cone"))?;
    Ok(canonical_cone(l, a, dd, psi, &c))
}

/// The reported form of a fitted cone (centred solution `l`, `a`, D, psi; centroid `c`):
/// psi in [0, pi/2] with the radius growing along the direction, and the axis point
/// nearest the centroid.
fn canonical_cone(l: Vector3<f64>, a: Vector3<f64>, mut dd: f64, mut psi: f64, c: &[f64]) -> Cone {
    // (psi, D) and (psi - pi, -D) give the same residuals up to sign: bring psi into [-pi/2, pi/2]
    psi = psi.rem_euclid(2.0 * PI);
    if psi > PI {
        psi -= 2.0 * PI;
    }
    if psi > FRAC_PI_2 {
        psi -= PI;
        dd = -dd;
    } else if psi < -FRAC_PI_2 {
        psi += PI;
        dd = -dd;
    }
    // report the point on the axis nearest the centroid; D moves with it
    let z = -l.dot(&a);
    let l = l + a * z;
    let dd = dd + z * psi.sin();
    let (a, psi) = if psi < 0.0 { (-a, -psi) } else { (a, psi) };
    Cone { point: arr(&(l + vec3(c))), direction: arr(&a), distance: dd, half_angle: psi }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lsq::cone_extent;

    #[test]
    fn exact_cone_and_canonical_form() {
        // apex angle 2 * 0.3 rad about the axis (0, 0.6, 0.8) through (5, -2, 1)
        let a = Vector3::new(0.0, 0.6, 0.8);
        let (u, v) = orthonormal_basis(&a);
        let pts: Vec<f64> = (0..60)
            .flat_map(|i| {
                let t = i as f64 * 2.399963;
                let z = (i as f64 * 0.754_877_666).fract() * 10.0;
                let p = Vector3::new(5.0, -2.0, 1.0) + a * z + (u * t.cos() + v * t.sin()) * (4.0 + z * 0.3f64.tan());
                [p[0], p[1], p[2]]
            })
            .collect();
        let c = cone(&pts).unwrap();
        assert!((c.half_angle - 0.3).abs() < 1e-10, "{c:?}");
        assert!((Vector3::from(c.direction) - a).norm() < 1e-10);
        let e = cone_extent(&pts, &c);
        assert!(e.max - e.min < 1e-9, "{e:?}");
        assert!(cone(&[0.0; 18]).is_err());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        /// On partial cones (arcs of 60 to 360 degrees, half angles of 3 to 40 degrees, noise
        /// along the surface normal) whose length puts the spread along the axis near (0.6
        /// to 1.6 times) that across the arc's depth or along its chord, the fit is found
        /// and its cost is at most that of the generating cone: the global basin.
        #[test]
        fn the_fit_is_no_worse_than_the_generating_cone(
            seed in 0u64..1000, r in 2.0f64..80.0, arc in 1.05f64..6.3, chord in proptest::bool::ANY, ratio in 0.6f64..1.6,
            psi in 0.05f64..0.7, noise in 1e-4f64..0.01, tilt in -1.0f64..1.0, far in 0.0f64..1e3,
        ) {
            // the length puts the spread along the axis near that across the arc's depth or
            // along its chord, where the principal directions mix (one nappe: the radius
            // stays above 0.2 r at the narrow end)
            let len_r = (crate::lsq::warm::tests::mixing_length(r, arc, ratio, chord) / r).min(1.6 / psi.tan());
            use rand::{Rng, SeedableRng};
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let a = Vector3::new(tilt, 0.4, 1.0).normalize();
            let (u, v) = orthonormal_basis(&a);
            let o = Vector3::new(far, -0.5 * far, 0.3 * far);
            let (mut pts, mut generating) = (Vec::new(), 0.0);
            for _ in 0..2000 {
                let t = rng.random::<f64>() * arc;
                let z = (rng.random::<f64>() - 0.5) * len_r * r;
                let e: f64 = (0..4).map(|_| rng.random::<f64>() - 0.5).sum::<f64>() * noise * 1.7;
                let radial = u * t.cos() + v * t.sin();
                let q = o + a * z + radial * (r + z * psi.tan()) + (radial * psi.cos() - a * psi.sin()) * e;
                generating += e * e;
                pts.extend_from_slice(&[q[0], q[1], q[2]]);
            }
            let c = cone(&pts).unwrap();
            let (p, d) = (Vector3::from(c.point), Vector3::from(c.direction));
            let (cp, sp) = (c.half_angle.cos(), c.half_angle.sin());
            let f: f64 = pts
                .chunks(3)
                .map(|x| {
                    let w = vec3(x) - p;
                    let z = w.dot(&d);
                    ((w - d * z).norm() * cp - z * sp - c.distance).powi(2)
                })
                .sum();
            proptest::prop_assert!(f <= generating * (1.0 + 1e-6) + 1e-12, "{f:e} > {generating:e}: {c:?}");
        }
    }
}
