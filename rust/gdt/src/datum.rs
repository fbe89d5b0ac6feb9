//! Datum simulation (ISO 5459:2011, Sec. 6 and Annex B).
//!
//! **Planes.** The simulated datum of a nominally flat feature is the associated
//! plane on the air side, tangent to the feature, that minimises the largest distance
//! of the feature's points from it (constrained Chebyshev, "L-infinity with material
//! constraint"). For a fixed orientation n (n pointing out of the material) that plane
//! is n.p = max_i n.p_i and its largest distance is the width of the set along n; so
//! the optimal orientation is the one of least width among the allowed ones:
//!
//! - primary (free): the minimum-width normal ([`crate::min_width3`], exact: the
//!   flatness zone; the datum is its outer plane; dissertation Eq. 5.13);
//! - secondary, perpendicular to the primary direction: the least width of the set
//!   projected along it ([`crate::width3::perpendicular_to`], Eq. 5.14);
//! - secondary at a basic angle to the primary ([`crate::width3::on_cone`]);
//! - tertiary, orientation fixed by the first two: only the offset (Eq. 5.15).
//!
//! The least-squares option fits the plane through the centroid instead, with the
//! normal of least second moment among the allowed orientations.
//!
//! **Axes of a fixed direction.** A hole (shaft) whose datum axis must be
//! perpendicular to the primary plane is simulated by the maximum inscribed (minimum
//! circumscribed) cylinder of that direction: the 2-D maximum inscribed (minimum
//! circumscribed) circle of the points projected along it (`gagekit_form::circle`,
//! Eqs. 6.1-6.2). The same kernel gives the smallest cylindrical tolerance zone of a
//! fixed direction (perpendicularity of an axis to a datum plane, parallelism of an
//! axis to a datum axis).

use crate::min_width3;
use crate::vec3::{self, check_points, dot, V3};
use crate::width3::{self, Slab};
use gagekit_core::{GkError, Result};

/// How the orientation of a datum plane is constrained by the datums before it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    /// No constraint (a primary datum).
    Free,
    /// Normal perpendicular to the given direction (secondary, perpendicular to the primary).
    PerpendicularTo(V3),
    /// Normal at `angle` rad from the given direction, free to turn about it.
    AtAngle(V3, f64),
    /// Normal fixed (tertiary; or a plane perpendicular to a datum axis).
    Fixed(V3),
}

/// Which association criterion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlaneFit {
    /// Constrained Chebyshev tangent plane on the air side (ISO 5459 default).
    Chebyshev,
    /// Least squares through the centroid.
    LeastSquares,
}

/// A datum plane n.p = offset, `normal` pointing out of the material (along `outward`).
/// `deviation`: the largest distance of the feature's points into the material from
/// the plane (Chebyshev), or the largest absolute distance (least squares).
#[derive(Debug, Clone, PartialEq)]
pub struct DatumPlane {
    pub point: V3,
    pub normal: V3,
    pub offset: f64,
    pub deviation: f64,
}

/// The simulated datum plane of the points (flat (n, 3)); `outward` roughly points
/// from the material into the air and fixes the side.
pub fn plane(pts: &[f64], outward: V3, orientation: Orientation, fit: PlaneFit) -> Result<DatumPlane> {
    const WHAT: &str = "datum plane";
    check_points(pts, 3, WHAT)?;
    let out = vec3::unit(outward, "datum plane: outward")?;
    let normal = match (fit, orientation) {
        (_, Orientation::Fixed(n)) => vec3::unit(n, WHAT)?,
        (PlaneFit::Chebyshev, Orientation::Free) => min_width3::min_width(pts)?.normal,
        (PlaneFit::Chebyshev, Orientation::PerpendicularTo(a)) => width3::perpendicular_to(pts, a)?.normal,
        (PlaneFit::Chebyshev, Orientation::AtAngle(a, t)) => width3::on_cone(pts, a, t)?.normal,
        (PlaneFit::LeastSquares, Orientation::Free) => {
            let p = gagekit_form::lsq::plane(pts)?;
            [p.normal[0], p.normal[1], p.normal[2]]
        }
        (PlaneFit::LeastSquares, Orientation::PerpendicularTo(a)) => {
            let a = vec3::unit(a, WHAT)?;
            let (q, u, v) = vec3::project(pts, a, vec3::centroid(pts));
            let l = gagekit_form::lsq::line(&q, 2)?;
            // normal of the 2-D line, back in 3-D
            let n2 = [-l.direction[1], l.direction[0]];
            vec3::add(vec3::scale(u, n2[0]), vec3::scale(v, n2[1]))
        }
        (PlaneFit::LeastSquares, Orientation::AtAngle(..)) => {
            return Err(GkError::config("datum plane: a least-squares datum at a basic angle is not supported; use the default (Chebyshev) fit"))
        }
    };
    let normal = if dot(normal, out) < 0.0 { vec3::scale(normal, -1.0) } else { normal };
    let c = vec3::centroid(pts);
    let (lo, hi) = width3::extent(pts, normal);
    let offset = match fit {
        PlaneFit::Chebyshev => hi,
        PlaneFit::LeastSquares => dot(c, normal),
    };
    let deviation = match fit {
        PlaneFit::Chebyshev => hi - lo,
        PlaneFit::LeastSquares => (hi - offset).max(offset - lo),
    };
    let point = vec3::add(c, vec3::scale(normal, offset - dot(c, normal)));
    Ok(DatumPlane { point, normal, offset, deviation })
}

/// Which cylinder of a fixed axis direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisFit {
    /// Maximum inscribed (a hole's datum, ISO 5459).
    Inscribed,
    /// Minimum circumscribed (a shaft's datum; the smallest cylindrical zone).
    Circumscribed,
    /// Geometric least squares.
    LeastSquares,
}

/// An axis of fixed direction: `point` (the foot of the centroid of the points),
/// `direction`, and `radius` of the fitted cylinder; `r_min`, `r_max`: the smallest
/// and largest distance of the points to the axis, recomputed in 3-D.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    pub point: V3,
    pub direction: V3,
    pub radius: f64,
    pub r_min: f64,
    pub r_max: f64,
}

/// The cylinder of the given axis direction fitted to the points (flat (n, 3)).
pub fn axis_along(pts: &[f64], direction: V3, fit: AxisFit) -> Result<Axis> {
    const WHAT: &str = "axis of a fixed direction";
    check_points(pts, if fit == AxisFit::Circumscribed { 1 } else { 3 }, WHAT)?;
    let d = vec3::unit(direction, WHAT)?;
    let c = vec3::centroid(pts);
    let (q, u, v) = vec3::project(pts, d, c);
    let circ = match fit {
        AxisFit::Circumscribed => gagekit_form::circle::min_circumscribed(&q)?,
        AxisFit::Inscribed => gagekit_form::circle::max_inscribed(&q)?,
        AxisFit::LeastSquares => gagekit_form::circle::least_squares(&q)?,
    };
    let point = vec3::add(c, vec3::add(vec3::scale(u, circ.center[0]), vec3::scale(v, circ.center[1])));
    let (mut r_min, mut r_max) = (f64::INFINITY, 0.0f64);
    for p in pts.chunks_exact(3) {
        let e = vec3::sub([p[0], p[1], p[2]], point);
        let r = vec3::norm(vec3::sub(e, vec3::scale(d, dot(e, d))));
        r_min = r_min.min(r);
        r_max = r_max.max(r);
    }
    Ok(Axis { point, direction: d, radius: circ.radius, r_min, r_max })
}

/// The thinnest slab of the points with its orientation constrained (see [`width3`]).
pub fn slab(pts: &[f64], orientation: Orientation) -> Result<Slab> {
    match orientation {
        Orientation::Free => min_width3::min_width(pts),
        Orientation::PerpendicularTo(a) => width3::perpendicular_to(pts, a),
        Orientation::AtAngle(a, t) => width3::on_cone(pts, a, t),
        Orientation::Fixed(n) => width3::along(pts, n),
    }
}
