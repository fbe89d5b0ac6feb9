//! Certificates: the minimum and maximum distance of the points to a reported feature,
//! recomputed from its parameters.

use super::frame::vec3;
use super::{Cone, Vector3};

/// Minimum and maximum of a set of distances (the certificate of a fit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extent {
    pub min: f64,
    pub max: f64,
}

impl Extent {
    /// `max - min`: the form error about a feature whose certificate holds signed
    /// distances (planes, 2-D lines, cones) or distances to a centre or an axis (circles,
    /// spheres, cylinders).
    pub fn spread(&self) -> f64 {
        self.max - self.min
    }

    /// The straightness of a line: the spread of the signed distances in 2-D, the
    /// diameter of the enclosing cylinder about the line (twice the largest distance) in 3-D.
    pub fn line_form_error(&self, dim: usize) -> f64 {
        if dim == 2 {
            self.spread()
        } else {
            2.0 * self.max
        }
    }

    pub(crate) fn of(it: impl Iterator<Item = f64>) -> Extent {
        it.fold(Extent { min: f64::INFINITY, max: f64::NEG_INFINITY }, |e, d| Extent {
            min: e.min.min(d),
            max: e.max.max(d),
        })
    }
}

/// Distances of 3-D points to the line through `point` along unit `direction`.
pub fn axis_distances<'a>(
    pts: &'a [f64],
    point: &'a [f64; 3],
    direction: &'a [f64; 3],
) -> impl Iterator<Item = f64> + 'a {
    let (l, a) = (vec3(point), vec3(direction).normalize());
    pts.chunks_exact(3).map(move |p| (vec3(p) - l).cross(&a).norm())
}

/// Min and max distance of the points to an axis (cylinder certificate).
pub fn axis_extent(pts: &[f64], point: &[f64; 3], direction: &[f64; 3]) -> Extent {
    Extent::of(axis_distances(pts, point, direction))
}

/// Min and max signed distance of 3-D points to a plane.
pub fn plane_extent(pts: &[f64], point: &[f64; 3], normal: &[f64; 3]) -> Extent {
    let (o, nv) = (vec3(point), vec3(normal).normalize());
    Extent::of(pts.chunks_exact(3).map(|p| (vec3(p) - o).dot(&nv)))
}

/// Min and max distance of points (2-D or 3-D) to a centre.
pub fn center_extent(pts: &[f64], dim: usize, center: &[f64]) -> Extent {
    let c = vec3(center);
    Extent::of(pts.chunks_exact(dim).map(|p| (vec3(p) - c).norm()))
}

/// For a line: min and max of the signed distances (2-D) or of the distances (3-D).
pub fn line_extent(pts: &[f64], dim: usize, point: &[f64], direction: &[f64]) -> Extent {
    let (o, a) = (vec3(point), vec3(direction).normalize());
    if dim == 2 {
        let nrm = Vector3::new(-a[1], a[0], 0.0);
        Extent::of(pts.chunks_exact(2).map(|p| (vec3(p) - o).dot(&nrm)))
    } else {
        Extent::of(pts.chunks_exact(3).map(|p| (vec3(p) - o).cross(&a).norm()))
    }
}

/// Min and max in-plane radial distance of 3-D points from a circle's centre
/// (the points projected onto the circle's plane).
pub fn circle3_extent(pts: &[f64], center: &[f64; 3], normal: &[f64; 3]) -> Extent {
    let (c, nv) = (vec3(center), vec3(normal).normalize());
    Extent::of(pts.chunks_exact(3).map(|p| (vec3(p) - c).cross(&nv).norm()))
}

/// Min and max signed orthogonal distance of 3-D points to a cone (positive outside).
pub fn cone_extent(pts: &[f64], c: &Cone) -> Extent {
    let (l, a) = (vec3(&c.point), vec3(&c.direction).normalize());
    let (cp, sp) = (c.half_angle.cos(), c.half_angle.sin());
    Extent::of(pts.chunks_exact(3).map(|p| {
        let d = vec3(p) - l;
        let z = d.dot(&a);
        (d - a * z).norm() * cp - z * sp - c.distance
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extents_of_simple_features() {
        let pts = [0.0, 0.0, 1.0, 2.0, 0.0, -1.0, 0.0, 3.0, 0.5];
        let e = plane_extent(&pts, &[0.0, 0.0, 0.0], &[0.0, 0.0, 2.0]);
        assert_eq!((e.min, e.max), (-1.0, 1.0));
        let e = axis_extent(&pts, &[0.0, 0.0, 0.0], &[0.0, 0.0, 1.0]);
        assert_eq!((e.min, e.max), (0.0, 3.0));
        let e = center_extent(&[3.0, 4.0, 0.0, 1.0], 2, &[0.0, 0.0]);
        assert_eq!((e.min, e.max), (1.0, 5.0));
        let e = line_extent(&[0.0, 1.0, 5.0, -2.0], 2, &[0.0, 0.0], &[1.0, 0.0]);
        assert_eq!((e.min, e.max), (-2.0, 1.0));
    }
}
