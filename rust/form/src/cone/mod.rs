//! Cones (the dissertation's Sec. 7.2 item 6, "conicity"; issue 25 §3): least squares,
//! minimum circumscribed (MC), maximum inscribed (MI) and minimum zone (MZ), with the half
//! angle free or fixed.
//!
//! A cone is an axis (point `p`, unit direction `a`, the radius growing along `a`) and a
//! half angle psi in (0, pi/2). A point at axial coordinate z = (x - p) . a and axis
//! distance rho lies at the signed **normal** distance
//!
//!   d = rho cos psi - z sin psi - D
//!
//! from the cone whose surface passes at normal distance D from `p` (positive outside the
//! material of a shaft: farther from the axis). This is the deviation measure of every
//! result here: the distance normal to the cone surface, in the point's axial half plane
//! (exact while the foot lies on the surface's generator, i.e. for every point on the
//! apex's side of the plane normal to the generator through the apex -- every point of
//! a scan near the surface).
//!
//! - **Least squares**: min sum d_i^2 ([`crate::lsq::cone_with`], Forbes'
//!   parametrisation).
//! - **Minimum zone** (conicity; ISO 1101 profile of a surface without datums, the
//!   nominal being a cone): two coaxial cones of the same half angle enclosing the points
//!   with the least normal separation, min over (axis, psi) of max d_i - min d_i.
//! - **Minimum circumscribed / maximum inscribed**: the cone containing every point
//!   (rho_i <= R + z_i tan psi) of least radius R / the cone containing no point of
//!   greatest R, where R is the radius at the **reference section**: the plane normal to
//!   the axis through the foot of the points' centroid (the section where a free half
//!   angle has no lever; with the angle fixed every section gives the same cone).
//!
//! The Chebyshev cones reuse the cylinders' local search (Sec. 6.3): sequential linear
//! programming with a trust region ([`crate::cylinder::slp`]) on the same minimax
//! problem in the axis offset (2), tilt (2), the half angle (when free) and the zone's
//! radii, the residuals linearised by their analytic gradients (each step a 6- or
//! 7-variable LP, `lp`), from the least-squares cone and from basin hops (8 axes tilted
//! 1e-4 and 1e-2 rad about the best, repeated while they find a lower basin), all
//! deterministic. The certificate of every result is recomputed from the reported
//! parameters: the min / max normal deviation of the input points; `gap` is the
//! first-order optimality gap -- the decrease the LP predicts within a box of 1e-7 of
//! the part's size about the result (0 at a vertex optimum: no feasible first-order
//! descent), in mm. Above 2000 points the search runs on an active subset, as the
//! cylinders' does (`cylinder::subset`): the extreme residuals of the least-squares cone,
//! grown by every point outside the fitted zone until none is -- then the subset's optimum
//! is the optimum of all points (the reference section stays that of all points).

use crate::criterion::FitCriterion;
use crate::cylinder::slp::{self, Axis, Taper};
use crate::cylinder::subset::{settle, SUBSET_ABOVE, SUBSET_EXTREMES};
use crate::cylinder::Criterion;
use crate::lsq::{self, orthonormal_basis, Extent};
use gagekit_core::{check_finite, GkError, Result};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

#[cfg(test)]
mod tests;

/// Fewest points of a cone fit (axis 4, half angle, size).
pub const MIN_POINTS: usize = 6;
/// A free fit whose half angle is below this (rad) is a cylinder: refused. Over a part
/// of length L the radius changes by L * 1e-7 -- 0.01 um over 100 mm.
pub const MIN_HALF_ANGLE: f64 = 1e-7;
/// Basin hopping: restarts per round, their tilts (rad) and the most rounds.
const HOPS: usize = 8;
const HOP_RADII: [f64; 2] = [1e-4, 1e-2];
const HOP_ROUNDS: usize = 4;

/// Settings of a cone fit.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Options {
    /// The half angle (rad, in (0, pi/2)) when fixed; `None`: a free angle.
    pub half_angle: Option<f64>,
}

/// A fitted cone.
#[derive(Debug, Clone)]
pub struct ConeFit {
    pub criterion: FitCriterion,
    /// The axis point of the reference section: the foot of the points' centroid.
    pub point: [f64; 3],
    /// Unit axis direction; the radius grows along it.
    pub direction: [f64; 3],
    /// The apex: `point - direction * radius / tan(half_angle)`.
    pub apex: [f64; 3],
    /// Half apex angle (rad), and whether it was fixed.
    pub half_angle: f64,
    pub fixed_angle: bool,
    /// Radius at the reference section: least squares, MC, MI; the mean of the zone's two
    /// cones for MZ.
    pub radius: f64,
    /// Radii of the inner and outer cone of the zone at the reference section (MZ); both
    /// equal `radius` otherwise.
    pub r_in: f64,
    pub r_out: f64,
    /// Normal distance from `point` to the cone of radius `radius` (radius cos psi).
    pub distance: f64,
    /// Points fixing the inner / outer cone (indices into the input; empty for least squares).
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Certificate: min and max signed normal deviation of the points from the cone of
    /// radius `radius` (positive away from the axis).
    pub extent: Extent,
    /// First-order optimality gap (mm; 0 for least squares, see the module).
    pub gap: f64,
    /// Linear programs solved.
    pub evaluations: usize,
}

impl ConeFit {
    /// Conicity about this cone: the normal width of the zone (max - min deviation).
    pub fn form_error(&self) -> f64 {
        self.extent.max - self.extent.min
    }

    /// Radius at axial coordinate `z` from the reference section.
    pub fn radius_at(&self, z: f64) -> f64 {
        self.radius + z * self.half_angle.tan()
    }
}

/// A fixed half angle a user gives in degrees, checked (strictly between 0 and 90) and in
/// radians.
pub fn half_angle_from_degrees(deg: f64) -> Result<f64> {
    if deg > 0.0 && deg < 90.0 {
        Ok(deg.to_radians())
    } else {
        Err(GkError::config(format!("cone: the half angle must lie strictly between 0 and 90 degrees, got {deg:?}")))
    }
}

/// Checks a fixed half angle: finite, strictly between 0 and 90 degrees.
pub fn check_half_angle(h: f64) -> Result<f64> {
    if h.is_finite() && h > 0.0 && h < FRAC_PI_2 {
        Ok(h)
    } else {
        Err(GkError::config(format!(
            "cone: the half angle must lie strictly between 0 and 90 degrees, got {} degrees",
            h.to_degrees()
        )))
    }
}

/// Fit a cone of the given criterion to 3-D points (flat, row-major), its half angle free
/// or `opts.half_angle`.
pub fn fit(pts: &[f64], crit: FitCriterion, opts: &Options) -> Result<ConeFit> {
    check_finite(pts, 3, "points")?;
    lsq::check_magnitude(pts, 3)?;
    let fixed = opts.half_angle.map(check_half_angle).transpose()?;
    let n = pts.len() / 3;
    if n < MIN_POINTS {
        return Err(GkError::invalid(format!("cone: needs at least {MIN_POINTS} points, got {n}")));
    }
    let sv = lsq::principal_spread(pts);
    if sv[0] == 0.0 {
        return Err(GkError::degenerate("cone: all points coincide"));
    }
    if lsq::negligible(sv[1], sv[0]) {
        return Err(GkError::degenerate("cone: the points are collinear; no cone is determined"));
    }
    if lsq::negligible(sv[2], sv[0]) {
        return Err(GkError::degenerate("cone: the points are coplanar; no cone is determined"));
    }
    let ls = lsq::cone_with(pts, fixed).map_err(|e| match lsq::cylinder(pts, None) {
        // no cone of either taper fits where a cylinder does: its half angle is 0
        Ok(_) if e.kind == gagekit_core::ErrorKind::DegenerateGeometry => GkError::degenerate(
            "cone: the points lie on a cylinder (no taper of either sign fits); fit a cylinder",
        ),
        _ => e,
    })?;
    if fixed.is_none() {
        if ls.half_angle < MIN_HALF_ANGLE {
            return Err(GkError::degenerate(format!(
                "cone: the points lie on a cylinder (least-squares half angle {:.3e} rad); fit a cylinder",
                ls.half_angle
            )));
        }
        if ls.half_angle > FRAC_PI_2 - MIN_HALF_ANGLE {
            return Err(GkError::degenerate("cone: the points lie in a plane (half angle 90 degrees); fit a plane"));
        }
    }
    let centroid = lsq::centroid(pts, 3);
    let c = Vector3::new(centroid[0], centroid[1], centroid[2]);
    let a = Vector3::from(ls.direction);
    // the least-squares axis point is already the foot of the centroid
    let p = Vector3::from(ls.point);
    let Some(cc) = Criterion::from_fit(crit) else {
        // least squares: the kernel's cone as it is (its axis point is the centroid's foot)
        let radius = ls.distance / ls.half_angle.cos();
        let apex = p - a * (radius / ls.half_angle.tan());
        return Ok(ConeFit {
            criterion: crit,
            point: ls.point,
            direction: ls.direction,
            apex: arr(&apex),
            half_angle: ls.half_angle,
            fixed_angle: fixed.is_some(),
            radius,
            distance: ls.distance,
            r_in: radius,
            r_out: radius,
            control_in: vec![],
            control_out: vec![],
            extent: lsq::cone_extent(pts, &ls),
            gap: 0.0,
            evaluations: 0,
        });
    };
    let q: Vec<f64> = pts.chunks_exact(3).flat_map(|x| [x[0] - c[0], x[1] - c[1], x[2] - c[2]]).collect();
    let size = q.chunks_exact(3).map(|x| Vector3::new(x[0], x[1], x[2]).norm()).fold(0.0, f64::max);
    let len = q.chunks_exact(3).map(|x| Vector3::new(x[0], x[1], x[2]).dot(&a).abs()).fold(1e-3 * size, f64::max);
    let free = fixed.is_none();
    let pb = Problem { q, crit: cc, size, len, free };
    // the search on (a subset of) the centred points, warm-started from the last one
    let first = (Axis::new(a, p - c), ls.half_angle);
    let mut start = first;
    let mut evaluations = 0;
    let solve = |sub: &[f64]| -> Result<(Found, f64, f64)> {
        let sp = Problem { q: sub.to_vec(), crit: cc, size, len, free };
        let mut best = sp.local(start, 1e-3 * len);
        evaluations += best.3;
        for radius in HOP_RADII {
            evaluations += sp.hop(&mut best, radius);
        }
        start = (best.1, best.2);
        let (lo, hi, _, _) = sp.contacts(&best.1, best.2);
        Ok((best, lo, hi))
    };
    let n = pts.len() / 3;
    let (ax, psi) = if n > SUBSET_ABOVE {
        // large inputs: an active subset (as the cylinders'), from the extreme residuals
        // of the least-squares cone, grown by the points outside the zone until none is
        let e = pb.residuals(&first.0, first.1);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&i, &j| e[i].total_cmp(&e[j]).then(i.cmp(&j)));
        let k = SUBSET_EXTREMES;
        let subset: Vec<usize> = match cc {
            Criterion::MinCircumscribed => order[n - 2 * k..].to_vec(),
            Criterion::MaxInscribed => order[..2 * k].to_vec(),
            Criterion::MinZone => order[..k].iter().chain(&order[n - k..]).copied().collect(),
        };
        let violations = |(b, lo, hi): &(Found, f64, f64)| -> Vec<f64> {
            let tol = 1e-12 * size;
            pb.residuals(&b.1, b.2)
                .into_iter()
                .map(|e| {
                    let over = if cc == Criterion::MaxInscribed { f64::NEG_INFINITY } else { e - hi };
                    let under = if cc == Criterion::MinCircumscribed { f64::NEG_INFINITY } else { lo - e };
                    over.max(under) - tol
                })
                .collect()
        };
        let ((b, _, _), _) = settle(&pb.q, subset, "cone", solve, violations)?;
        (b.1, b.2)
    } else {
        let mut solve = solve;
        let (b, _, _) = solve(&pb.q)?;
        (b.1, b.2)
    };
    let (lo, hi, ctl_in, ctl_out) = pb.contacts(&ax, psi);
    let gap = pb.gap(&ax, psi);
    // the zone's radii at the reference section (residuals are radial for MC / MI, normal for MZ)
    let (r_in, r_out) = match cc {
        Criterion::MinZone => (lo / psi.cos(), hi / psi.cos()),
        Criterion::MinCircumscribed => (hi, hi),
        Criterion::MaxInscribed => (lo, lo),
    };
    let (ctl_in, ctl_out) = match cc {
        Criterion::MinZone => (ctl_in, ctl_out),
        Criterion::MinCircumscribed => (vec![], ctl_out),
        Criterion::MaxInscribed => (ctl_in, vec![]),
    };
    finish(pts, crit, fixed.is_some(), ax.point + c, ax.dir, psi, (r_in, r_out), (ctl_in, ctl_out), gap, evaluations)
}

/// The reported cone: the axis point moved to the foot of the centroid, the direction
/// along which the radius grows, the certificate recomputed on `pts`.
#[allow(clippy::too_many_arguments)]
fn finish(
    pts: &[f64],
    crit: FitCriterion,
    fixed_angle: bool,
    p: Vector3<f64>,
    a: Vector3<f64>,
    psi: f64,
    (r_in, r_out): (f64, f64),
    (control_in, control_out): (Vec<usize>, Vec<usize>),
    gap: f64,
    evaluations: usize,
) -> Result<ConeFit> {
    let a = a.normalize();
    let c = lsq::centroid(pts, 3);
    let p = p + a * (Vector3::new(c[0], c[1], c[2]) - p).dot(&a);
    let radius = 0.5 * (r_in + r_out);
    if !(radius > 0.0 && radius.is_finite() && psi > 0.0 && psi < FRAC_PI_2) {
        return Err(GkError::degenerate(format!(
            "cone: the points do not determine a cone of this kind (radius {radius:.6e} at the reference section, half angle {:.6} degrees)",
            psi.to_degrees()
        )));
    }
    let apex = p - a * (radius / psi.tan());
    let cone = lsq::Cone { point: arr(&p), direction: arr(&a), distance: radius * psi.cos(), half_angle: psi };
    let extent = lsq::cone_extent(pts, &cone);
    Ok(ConeFit {
        criterion: crit,
        point: arr(&p),
        direction: arr(&a),
        apex: arr(&apex),
        half_angle: psi,
        fixed_angle,
        radius,
        distance: cone.distance,
        r_in,
        r_out,
        control_in,
        control_out,
        extent,
        gap,
        evaluations,
    })
}

fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v[0], v[1], v[2]]
}

/// The centred points and the scales of the local searches.
struct Problem {
    q: Vec<f64>,
    crit: Criterion,
    /// Largest distance of a point from the centroid.
    size: f64,
    /// Half length of the part along the least-squares axis.
    len: f64,
    free: bool,
}

/// (value, axis, half angle, linear programs) of a local search.
type Found = (f64, Axis, f64, usize);

impl Problem {
    /// The residual model at a half angle: normal distances for the zone, radial ones
    /// (the radius at the reference section) for MC / MI.
    fn taper(&self, psi: f64) -> Taper {
        Taper { psi, free: self.free, normal: self.crit == Criterion::MinZone }
    }

    /// One SLP local search from `(axis, psi)` with the initial box `delta` (mm).
    fn local(&self, (ax, psi): (Axis, f64), delta: f64) -> Found {
        let inside = |_: &Vector3<f64>, psi: f64| psi > 0.0 && psi < FRAC_PI_2;
        let (local, psi) = slp::descend_tapered(&self.q, self.crit, ax, Some(self.taper(psi)), delta, self.len, self.size, &inside);
        let v = slp::tapered_value(&self.q, self.crit, &local.axis, Some(&self.taper(psi)));
        (v, local.axis, psi, local.steps)
    }

    /// Rounds of basin hopping at tilt `radius` about the best axis, while they find a
    /// lower basin (gains at the rounding level do not count). Returns the LPs solved.
    fn hop(&self, best: &mut Found, radius: f64) -> usize {
        let mut evaluations = 0;
        for _ in 0..HOP_ROUNDS {
            let (u, v) = orthonormal_basis(&best.1.dir);
            let (a0, psi0) = (best.1, best.2);
            let hops: Vec<Found> = (0..HOPS)
                .into_par_iter()
                .map(|k| {
                    let th = 0.3 + 2.0 * PI * k as f64 / HOPS as f64;
                    let dir = a0.dir + (u * th.cos() + v * th.sin()) * radius;
                    self.local((Axis::new(dir, a0.point), psi0), radius * self.len)
                })
                .collect();
            let before = best.0;
            for h in hops {
                evaluations += h.3;
                if h.0 < best.0 {
                    *best = (h.0, h.1, h.2, best.3);
                }
            }
            if best.0 >= before - 1e-12 * self.size {
                break;
            }
        }
        evaluations
    }

    /// The residual of every point about the cone (`ax`, `psi`): normal (MZ) or radial.
    fn residuals(&self, ax: &Axis, psi: f64) -> Vec<f64> {
        let t = self.taper(psi);
        self
            .q
            .chunks_exact(3)
            .map(|x| {
                let w = Vector3::new(x[0], x[1], x[2]) - ax.point;
                let z = w.dot(&ax.dir);
                let rho = (w - ax.dir * z).norm();
                t.residual(rho, z)
            })
            .collect()
    }

    /// Smallest and largest residual and the points within 1e-9 of the size of each.
    fn contacts(&self, ax: &Axis, psi: f64) -> (f64, f64, Vec<usize>, Vec<usize>) {
        let e = self.residuals(ax, psi);
        let lo = e.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = e.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let tol = 1e-9 * self.size;
        let pick = |target: f64| (0..e.len()).filter(|&i| (e[i] - target).abs() <= tol).collect::<Vec<_>>();
        (lo, hi, pick(lo), pick(hi))
    }

    /// The first-order optimality gap at the result: the decrease one LP step predicts in
    /// a box of 1e-7 of the part's size (its value; the step is not taken).
    fn gap(&self, ax: &Axis, psi: f64) -> f64 {
        slp::predicted_decrease(&self.q, self.crit, *ax, Some(self.taper(psi)), 1e-7 * self.size, self.len)
            .map_or(0.0, |g| g.max(0.0))
    }
}
