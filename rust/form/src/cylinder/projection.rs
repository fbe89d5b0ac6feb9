//! The projection model (Eq. 6.12, ERRATA item 1): axis angles, the projection of
//! the points along an axis, and the exact 2-D fit of a projection that scores it.

use super::Criterion;
use crate::circle;
use crate::lsq;
use gagekit_core::Result;
use nalgebra::Vector3;
use std::f64::consts::PI;

/// Axis direction of the polar angle `theta` and azimuth `phi`.
pub fn axis(theta: f64, phi: f64) -> [f64; 3] {
    [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]
}

/// (theta, phi) of a direction, flipped into the upper half sphere.
pub fn angles(direction: &[f64; 3]) -> (f64, f64) {
    let a = Vector3::from(lsq::upper(*direction)).normalize();
    (a[2].clamp(-1.0, 1.0).acos(), a[1].atan2(a[0]))
}

/// The two rows of [I2 0] Ry(-t) Rz(-f) (Eq. 6.12, ERRATA item 1).
pub(super) fn frame(theta: f64, phi: f64) -> ([f64; 3], [f64; 3]) {
    let (st, ct, sf, cf) = (theta.sin(), theta.cos(), phi.sin(), phi.cos());
    ([ct * cf, ct * sf, -st], [-sf, cf, 0.0])
}

/// The 3-D point (in the projection's origin) of the 2-D point `c` of the plane
/// normal to the axis (theta, phi): the inverse of [`project`] on that plane.
pub(super) fn in_space(theta: f64, phi: f64, c: [f64; 2]) -> Vector3<f64> {
    let (u, w) = frame(theta, phi);
    Vector3::from(u) * c[0] + Vector3::from(w) * c[1]
}

/// Project 3-D points along the axis (theta, phi) to 2-D (Eq. 6.12, corrected).
pub fn project(pts: &[f64], theta: f64, phi: f64) -> Vec<f64> {
    let (u, v) = frame(theta, phi);
    let mut out = Vec::with_capacity(pts.len() / 3 * 2);
    for p in pts.chunks_exact(3) {
        out.push(u[0] * p[0] + u[1] * p[1] + u[2] * p[2]);
        out.push(v[0] * p[0] + v[1] * p[1] + v[2] * p[2]);
    }
    out
}

/// Angle (rad) the points cover around an axis: 2 pi minus the largest
/// angular gap of their projections seen from the axis. Below pi/2 a maximum
/// inscribed cylinder is ill-posed (Sec. 6.2.2).
pub fn arc(pts: &[f64], point: &[f64; 3], direction: &[f64; 3]) -> f64 {
    let (t, f) = angles(direction);
    let rel: Vec<f64> = pts.chunks_exact(3).flat_map(|p| [p[0] - point[0], p[1] - point[1], p[2] - point[2]]).collect();
    2.0 * PI - circle::max_angular_gap(&project(&rel, t, f), [0.0, 0.0])
}

/// The exact 2-D fit of the projection along `a`, as a zone (MC and MI give
/// r_in = r_out). Also returns the angles used.
pub(super) fn fit2d(q: &[f64], a: &Vector3<f64>, crit: Criterion) -> Result<(f64, f64, circle::Zone)> {
    let (t, f) = angles(&[a[0], a[1], a[2]]);
    let proj = project(q, t, f);
    let zone = match crit {
        Criterion::MinZone => circle::min_zone(&proj)?,
        Criterion::MinCircumscribed | Criterion::MaxInscribed => {
            let c = if crit == Criterion::MinCircumscribed {
                circle::min_circumscribed(&proj)?
            } else {
                circle::max_inscribed(&proj)?
            };
            circle::Zone {
                center: c.center,
                r_in: c.radius,
                r_out: c.radius,
                control_in: c.control.clone(),
                control_out: c.control,
            }
        }
    };
    Ok((t, f, zone))
}

/// The value minimised: MCC radius, minus the MIC radius, MZC width. A
/// projection whose fitted centre lies farther than 100 part sizes from the
/// points is no cylinder section (a strip: the zone degenerates to parallel
/// lines) and is rejected.
pub(super) fn objective(q: &[f64], a: &Vector3<f64>, crit: Criterion, size: f64) -> f64 {
    fit2d(q, a, crit).map_or(f64::INFINITY, |(_, _, z)| zone_value(&z, crit, size))
}

/// The value of a 2-D fit for [`objective`].
pub(super) fn zone_value(z: &circle::Zone, crit: Criterion, size: f64) -> f64 {
    if !(z.center[0].hypot(z.center[1]) <= 100.0 * size && z.r_out.is_finite()) {
        return f64::INFINITY;
    }
    match crit {
        Criterion::MinCircumscribed => z.r_out,
        Criterion::MaxInscribed => -z.r_in,
        Criterion::MinZone => z.r_out - z.r_in,
    }
}

/// A single circle as a zone of width 0.
pub(super) fn zone_of(c: circle::Circle) -> circle::Zone {
    circle::Zone { center: c.center, r_in: c.radius, r_out: c.radius, control_in: c.control.clone(), control_out: c.control }
}
