//! Shared steps of the least-squares fits: input checks, the two-pass centroid, centred
//! copies and principal axes of the scatter matrix, the upper-half-sphere sign convention
//! of axes and orthonormal bases.

use super::Vector3;
use gagekit_core::{check_finite, GkError, Result};
use nalgebra::{Matrix3, SymmetricEigen};

/// Singular values below this fraction of the largest count as zero
/// (degenerate spreads: coincident, collinear, coplanar points).
pub(crate) const DEGENERATE: f64 = 1e-10;

pub(crate) fn check_points(pts: &[f64], dim: usize, min_n: usize, shape: &str) -> Result<usize> {
    if dim != 2 && dim != 3 {
        return Err(GkError::invalid(format!("{shape}: points must be 2-D or 3-D, got {dim}-D")));
    }
    // one vectorised pass for the common case (every coordinate finite and within
    // MAX_COORD: NaN fails the comparison); the two checks name a bad point otherwise
    if pts.len() % dim != 0 || !pts.iter().fold(true, |ok, v| ok & (v.abs() <= MAX_COORD)) {
        check_finite(pts, dim, "points")?;
        check_magnitude(pts, dim)?;
    }
    let n = pts.len() / dim;
    if n < min_n {
        return Err(GkError::invalid(format!(
            "{shape}: needs at least {min_n} points, got {n}"
        )));
    }
    Ok(n)
}

/// Largest accepted coordinate magnitude (mm): squared distances and scatter sums of
/// larger coordinates overflow (a plane fit at 1e155 mm would return NaN normals).
pub const MAX_COORD: f64 = 1e150;

/// An InvalidInput error naming the first point with a coordinate beyond [`MAX_COORD`].
pub fn check_magnitude(pts: &[f64], dim: usize) -> Result<()> {
    match pts.iter().position(|v| v.abs() > MAX_COORD) {
        None => Ok(()),
        Some(pos) => Err(GkError::invalid(format!(
            "points: point {} has a coordinate beyond 1e150 mm ({:e}); check the units",
            pos / dim,
            pts[pos]
        ))),
    }
}

/// Centroid, computed in two passes (mean, then mean of the deviations).
pub fn centroid(pts: &[f64], dim: usize) -> Vec<f64> {
    let n = (pts.len() / dim) as f64;
    let mut c = vec![0.0; dim];
    for p in pts.chunks_exact(dim) {
        for d in 0..dim {
            c[d] += p[d];
        }
    }
    c.iter_mut().for_each(|v| *v /= n);
    let mut corr = vec![0.0; dim];
    for p in pts.chunks_exact(dim) {
        for d in 0..dim {
            corr[d] += p[d] - c[d];
        }
    }
    for d in 0..dim {
        c[d] += corr[d] / n;
    }
    c
}

/// Centred copy of the points, always as 3-D (z = 0 for 2-D input).
pub(crate) fn centred3(pts: &[f64], dim: usize, c: &[f64]) -> Vec<[f64; 3]> {
    pts.chunks_exact(dim)
        .map(|p| {
            let mut q = [0.0; 3];
            for d in 0..dim {
                q[d] = p[d] - c[d];
            }
            q
        })
        .collect()
}

/// [`centred3`] of 3-D points with their scatter matrix summed in the same pass.
pub(crate) fn centred3_scatter(pts: &[f64], c: &[f64]) -> (Vec<[f64; 3]>, Matrix3<f64>) {
    let mut s = [0.0; 6];
    let q = pts
        .chunks_exact(3)
        .map(|p| {
            let q = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            add_outer(&mut s, q);
            q
        })
        .collect();
    (q, Matrix3::new(s[0], s[1], s[2], s[1], s[3], s[4], s[2], s[4], s[5]))
}

/// Adds q q^T to the upper triangle `s` (xx, xy, xz, yy, yz, zz) of a scatter matrix.
#[inline(always)]
pub(crate) fn add_outer(s: &mut [f64; 6], q: [f64; 3]) {
    s[0] += q[0] * q[0];
    s[1] += q[0] * q[1];
    s[2] += q[0] * q[2];
    s[3] += q[1] * q[1];
    s[4] += q[1] * q[2];
    s[5] += q[2] * q[2];
}

/// Whether the points of scatter matrix `s` certainly pass the spread checks of
/// [`principal_axes`]' singular values (`sv[0] > 0` and `sv[1] > DEGENERATE * sv[0]`): the
/// second eigenvalue at least 1e-6 of the first (sv[1]^2 / sv[0]^2 is then about 1e-6,
/// fourteen orders of magnitude above DEGENERATE^2 = 1e-20, far beyond the rounding of the
/// sums and of the eigenvalues, about 1e-16 of the first). `false`: recompute the spreads.
pub(crate) fn clearly_spread(s: &Matrix3<f64>) -> bool {
    if !s.iter().all(|v| v.is_finite()) {
        return false;
    }
    let mut e: Vec<f64> = SymmetricEigen::new(*s).eigenvalues.iter().copied().collect();
    e.sort_by(|a, b| b.total_cmp(a));
    e[0] > 0.0 && e[1] >= 1e-6 * e[0]
}

/// Principal axes of centred points: singular values (descending) and the
/// matching unit vectors (columns).
pub(crate) fn principal_axes(q: &[[f64; 3]]) -> ([f64; 3], [Vector3<f64>; 3]) {
    let mut s = Matrix3::zeros();
    for p in q {
        let v = Vector3::new(p[0], p[1], p[2]);
        s += v * v.transpose();
    }
    let eig = SymmetricEigen::new(s);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let vecs = order.map(|k| eig.eigenvectors.column(k).into_owned().normalize());
    // spreads recomputed from the data (eigenvalues of the scatter matrix only
    // resolve them to sqrt(eps) relative, too coarse to detect degeneracy)
    let sv = vecs.map(|e| q.iter().map(|p| (p[0] * e[0] + p[1] * e[1] + p[2] * e[2]).powi(2)).sum::<f64>().sqrt());
    (sv, vecs)
}

/// The sign of an axis direction in the upper half sphere (z > 0, or z = 0 and
/// y > 0, or z = y = 0 and x > 0), the convention of the angles (theta, phi).
pub fn upper(a: [f64; 3]) -> [f64; 3] {
    if a[2] < 0.0 || (a[2] == 0.0 && (a[1] < 0.0 || (a[1] == 0.0 && a[0] < 0.0))) {
        [-a[0], -a[1], -a[2]]
    } else {
        a
    }
}

pub(crate) fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v[0], v[1], v[2]]
}

pub(crate) fn vec3(a: &[f64]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a.get(2).copied().unwrap_or(0.0))
}

/// A unit vector orthogonal to `a` (unit) and a third completing a right-handed basis.
pub fn orthonormal_basis(a: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let t = if a[0].abs() <= a[1].abs() && a[0].abs() <= a[2].abs() {
        Vector3::x()
    } else if a[1].abs() <= a[2].abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let u = a.cross(&t).normalize();
    let v = a.cross(&u);
    (u, v)
}

/// Rings of the start grid over the half sphere (tilt every 90 / [`GRID_RINGS`] degrees
/// from the first principal axis, 6 k directions on ring k: 127 directions).
const GRID_RINGS: usize = 6;
/// Grid directions kept as starts (the lowest scores, pairwise more than
/// [`GRID_APART`] rad apart).
const GRID_STARTS: usize = 3;
const GRID_APART: f64 = 0.35;
/// Points the grid judges a direction on (every k-th point of the centred points).
const GRID_POINTS: usize = 256;

/// Start axes of the least-squares cylinder ([`super::cylinder`]) beyond the principal
/// axes `axes` (largest spread first): of a grid over the half sphere about `axes[0]`
/// (rings of [`GRID_RINGS`], the seam of each ring turned by half a step on alternate
/// rings, half of the equator since a and -a are one axis), the at most [`GRID_STARTS`]
/// best directions by `score(sub, a)` (an evenly spaced subsample `sub` of at most
/// [`GRID_POINTS`] of the centred points `q`; None: the direction is refused) that score
/// lower than every principal axis: none when a principal axis is already the best start
/// (a well-spread bore), so that the fit then costs no more local iterations than before.
/// Deterministic: a fixed grid, a fixed subsample, ties to the earlier direction. Why the
/// principal axes alone are not enough (a short partial bore): the module documentation of
/// `lsq/cylinder.rs`.
pub(crate) fn grid_axes(
    q: &[[f64; 3]],
    axes: &[Vector3<f64>],
    score: impl Fn(&[[f64; 3]], &Vector3<f64>) -> Option<f64>,
) -> Vec<Vector3<f64>> {
    let sub: Vec<[f64; 3]> = q.iter().step_by(q.len().div_ceil(GRID_POINTS).max(1)).copied().collect();
    let (w, e0, e1) = (axes[0], axes[1], axes[2]);
    let mut dirs = vec![w];
    for ring in 1..=GRID_RINGS {
        let t = std::f64::consts::FRAC_PI_2 * ring as f64 / GRID_RINGS as f64;
        let n = 6 * ring;
        let count = if ring == GRID_RINGS { n / 2 } else { n };
        for k in 0..count {
            let g = std::f64::consts::TAU * (k as f64 + 0.5 * (ring % 2) as f64) / n as f64;
            dirs.push(w * t.cos() + (e0 * g.cos() + e1 * g.sin()) * t.sin());
        }
    }
    let bar = axes.iter().filter_map(|a| score(&sub, a)).filter(|f| f.is_finite()).fold(f64::INFINITY, f64::min);
    let mut scored: Vec<(f64, Vector3<f64>)> =
        dirs.into_iter().filter_map(|a| score(&sub, &a).filter(|&f| f < bar).map(|f| (f, a))).collect();
    scored.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut out: Vec<Vector3<f64>> = Vec::new();
    for (_, a) in scored {
        if out.len() == GRID_STARTS {
            break;
        }
        if out.iter().all(|b| a.dot(b).abs().min(1.0).acos() > GRID_APART) {
            out.push(a);
        }
    }
    out
}

/// Spread of 3-D points along their principal axes (root sum of squares of the
/// centred coordinates), largest first: zero entries mean coincident,
/// collinear or coplanar points.
pub fn principal_spread(pts: &[f64]) -> [f64; 3] {
    let c = centroid(pts, 3);
    principal_axes(&centred3(pts, 3, &c)).0
}

/// Whether a spread counts as zero relative to the largest one.
pub fn negligible(spread: f64, largest: f64) -> bool {
    spread <= DEGENERATE * largest
}

/// The plane of points in space for a planar feature: the centroid and the principal
/// axes (largest spread first; the third is the least-squares normal). Errors for
/// coincident or collinear points.
pub fn plane_frame(pts: &[f64], what: &str) -> Result<(Vec<f64>, [Vector3<f64>; 3])> {
    check_points(pts, 3, 3, what)?;
    let c = centroid(pts, 3);
    let q = centred3(pts, 3, &c);
    let (sv, axes) = principal_axes(&q);
    if sv[0] == 0.0 {
        return Err(GkError::degenerate(format!("{what}: all points coincide")));
    }
    if sv[1] <= DEGENERATE * sv[0] {
        return Err(GkError::degenerate(format!("{what}: the points are collinear; no circle passes near them")));
    }
    Ok((c, axes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centroid_far_from_origin_and_conventions() {
        let pts = [1e9 + 1.0, 2.0, 1e9 + 3.0, 4.0];
        assert_eq!(centroid(&pts, 2), vec![1e9 + 2.0, 3.0]);
        assert_eq!(upper([0.0, -1.0, 0.0]), [0.0, 1.0, 0.0]);
        assert_eq!(upper([1.0, 0.0, -0.0]), [1.0, 0.0, -0.0]);
        let a = Vector3::new(0.0, 0.6, 0.8);
        let (u, v) = orthonormal_basis(&a);
        assert!(u.dot(&a).abs() < 1e-15 && v.dot(&a).abs() < 1e-15 && (u.cross(&v) - a).norm() < 1e-15);
        assert!(check_magnitude(&[0.0, 2e150], 2).is_err());
        let sv = principal_spread(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0]);
        assert!(negligible(sv[1], sv[0]));
    }
}
