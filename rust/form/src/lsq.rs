//! Least-squares (geometric, orthogonal-distance) fits of lines, planes,
//! circles, spheres, 3-D circles and cylinders, as ASME B89.4.10 / the NIST
//! Algorithm Testing System define them.
//!
//! All fits work on centred data (the centroid is subtracted first, in two
//! passes), so coordinates far from the origin (1e6 mm) lose no accuracy.
//! Lines and planes are exact (principal axes of the scatter matrix); circles,
//! spheres and cylinders use Levenberg–Marquardt on the orthogonal distances
//! from algebraic / principal-axis starts and iterate to full double precision.
//!
//! Points are flat row-major buffers: `(n, dim)` with `dim` 2 or 3.

use gagekit_core::{check_finite, GkError, Result};
use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// Singular values below this fraction of the largest count as zero
/// (degenerate spreads: coincident, collinear, coplanar points).
const DEGENERATE: f64 = 1e-10;

/// A line: a point on it (the centroid of the data) and a unit direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    pub point: Vec<f64>,
    pub direction: Vec<f64>,
}

/// A plane: a point on it (the centroid of the data) and a unit normal.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    pub point: [f64; 3],
    pub normal: [f64; 3],
}

/// A circle in 2-D or a sphere in 3-D (`center.len()` = dimension).
#[derive(Debug, Clone, PartialEq)]
pub struct Sphere {
    pub center: Vec<f64>,
    pub radius: f64,
}

/// A circle in 3-D space: centre, unit normal of its plane, radius.
#[derive(Debug, Clone, PartialEq)]
pub struct Circle3 {
    pub center: [f64; 3],
    pub normal: [f64; 3],
    pub radius: f64,
}

/// A cylinder: a point on the axis (the foot of the data centroid), unit axis
/// direction, radius.
#[derive(Debug, Clone, PartialEq)]
pub struct Cylinder {
    pub point: [f64; 3],
    pub direction: [f64; 3],
    pub radius: f64,
}

/// Minimum and maximum of a set of distances (the certificate of a fit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extent {
    pub min: f64,
    pub max: f64,
}

impl Extent {
    fn of(it: impl Iterator<Item = f64>) -> Extent {
        it.fold(Extent { min: f64::INFINITY, max: f64::NEG_INFINITY }, |e, d| Extent {
            min: e.min.min(d),
            max: e.max.max(d),
        })
    }
}

// ---------------------------------------------------------------- helpers

fn check_points(pts: &[f64], dim: usize, min_n: usize, shape: &str) -> Result<usize> {
    if dim != 2 && dim != 3 {
        return Err(GkError::invalid(format!("{shape}: points must be 2-D or 3-D, got {dim}-D")));
    }
    check_finite(pts, dim, "points")?;
    check_magnitude(pts, dim)?;
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
fn centred3(pts: &[f64], dim: usize, c: &[f64]) -> Vec<[f64; 3]> {
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

/// Principal axes of centred points: singular values (descending) and the
/// matching unit vectors (columns).
fn principal_axes(q: &[[f64; 3]]) -> ([f64; 3], [Vector3<f64>; 3]) {
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

fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v[0], v[1], v[2]]
}

fn vec3(a: &[f64]) -> Vector3<f64> {
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

/// Levenberg–Marquardt on a small parameter vector. `eval(params)` returns
/// the sum of squared residuals, J^T J and J^T r (J = d residual / d step,
/// the step applied by `apply`). `scale` is the length scale of the data.
///
/// The cost cannot resolve the last digits of a flat minimum, so once steps
/// are tiny the plain Gauss–Newton step is taken as long as the cost does not
/// grow beyond rounding, until the step itself is at rounding level: the
/// result is then the stationary point to full double precision.
#[allow(clippy::too_many_arguments)]
fn levenberg_marquardt<P: Clone>(
    mut params: P,
    p: usize,
    scale: f64,
    max_iter: usize,
    eval: impl Fn(&P) -> (f64, DMatrix<f64>, DVector<f64>),
    cost: impl Fn(&P) -> f64,
    apply: impl Fn(&P, &DVector<f64>) -> P,
    what: &str,
) -> Result<(P, usize)> {
    let (mut f, mut jtj, mut jtr) = eval(&params);
    let scale = scale.max(1e-300);
    let mut lambda = 1e-6;
    let mut iters = 0;
    let mut polish = 0;
    while iters < max_iter {
        iters += 1;
        let mut a = jtj.clone();
        for k in 0..p {
            a[(k, k)] += lambda * jtj[(k, k)].max(1e-300);
        }
        let step = match a.cholesky() {
            Some(ch) => ch.solve(&(-&jtr)),
            None => {
                lambda = (lambda * 10.0).max(1e-12);
                if lambda > 1e16 {
                    return Err(GkError::degenerate(format!(
                        "{what}: the fit is not determined by these points (singular Jacobian)"
                    )));
                }
                continue;
            }
        };
        if !step.iter().all(|v| v.is_finite()) {
            return Err(GkError::numerical(format!("{what}: the iteration diverged")));
        }
        let size = step.amax();
        if size <= 1e-15 * scale {
            break;
        }
        let trial = apply(&params, &step);
        let ft = cost(&trial);
        let tiny = size <= 1e-8 * scale;
        if ft < f || (tiny && ft <= f * (1.0 + 1e-12) + f64::MIN_POSITIVE && polish < 8) {
            if tiny {
                polish += 1;
            }
            params = trial;
            (f, jtj, jtr) = eval(&params);
            lambda = if tiny { 0.0 } else { (lambda / 10.0).max(1e-12) };
        } else {
            if tiny && polish > 0 {
                break; // a rejected step at rounding level after polishing: done
            }
            lambda = if lambda == 0.0 { 1e-12 } else { lambda * 10.0 };
            if lambda > 1e12 {
                break; // no descent direction left: at the minimum to rounding
            }
        }
    }
    Ok((params, iters))
}


/// Points per chunk of the parallel sums: the chunks are fixed, and their
/// partial sums are added in order, so the thread count never changes a result.
const CHUNK: usize = 8192;

/// Sum of `f` over the points, deterministic (fixed chunks, ordered reduction).
fn det_sum(q: &[[f64; 3]], f: impl Fn(&[f64; 3]) -> f64 + Sync) -> f64 {
    if q.len() <= CHUNK {
        return q.iter().map(&f).sum();
    }
    let parts: Vec<f64> = q.par_chunks(CHUNK).map(|c| c.iter().map(&f).sum::<f64>()).collect();
    parts.iter().sum()
}

/// Sum of squared residuals, J^T J and J^T r for residual rows `row(x) -> (r, J_row)`.
fn normal_equations<const P: usize>(
    q: &[[f64; 3]],
    row: impl Fn(&[f64; 3]) -> (f64, [f64; P]) + Sync,
) -> (f64, DMatrix<f64>, DVector<f64>) {
    type Acc<const P: usize> = (f64, [[f64; P]; P], [f64; P]);
    let part = |c: &[[f64; 3]]| -> Acc<P> {
        let mut acc = (0.0, [[0.0; P]; P], [0.0; P]);
        for x in c {
            let (r, j) = row(x);
            acc.0 += r * r;
            for a in 0..P {
                acc.2[a] += j[a] * r;
                for b in a..P {
                    acc.1[a][b] += j[a] * j[b];
                }
            }
        }
        acc
    };
    let parts: Vec<Acc<P>> =
        if q.len() <= CHUNK { vec![part(q)] } else { q.par_chunks(CHUNK).map(part).collect() };
    let mut jtj = DMatrix::zeros(P, P);
    let mut jtr = DVector::zeros(P);
    let mut f = 0.0;
    for (pf, pm, pv) in &parts {
        f += pf;
        for a in 0..P {
            jtr[a] += pv[a];
            for b in a..P {
                jtj[(a, b)] += pm[a][b];
            }
        }
    }
    for a in 0..P {
        for b in 0..a {
            jtj[(a, b)] = jtj[(b, a)];
        }
    }
    (f, jtj, jtr)
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

// ---------------------------------------------------------------- lines and planes

/// Least-squares line through 2-D or 3-D points (total least squares: the
/// principal axis through the centroid).
pub fn line(pts: &[f64], dim: usize) -> Result<Line> {
    let n = check_points(pts, dim, 2, "line")?;
    let c = centroid(pts, dim);
    let q = centred3(pts, dim, &c);
    let (sv, axes) = principal_axes(&q);
    if sv[0] <= f64::MIN_POSITIVE * n as f64 || sv[0] == 0.0 {
        return Err(GkError::degenerate("line: all points coincide"));
    }
    let mut dir: Vec<f64> = arr(&axes[0])[..dim].to_vec();
    let norm = dir.iter().map(|v| v * v).sum::<f64>().sqrt();
    dir.iter_mut().for_each(|v| *v /= norm);
    Ok(Line { point: c, direction: dir })
}

/// Least-squares plane: centroid and the direction of least spread.
pub fn plane(pts: &[f64]) -> Result<Plane> {
    check_points(pts, 3, 3, "plane")?;
    let c = centroid(pts, 3);
    let q = centred3(pts, 3, &c);
    let (sv, axes) = principal_axes(&q);
    if sv[0] == 0.0 {
        return Err(GkError::degenerate("plane: all points coincide"));
    }
    if sv[1] <= DEGENERATE * sv[0] {
        return Err(GkError::degenerate("plane: the points are collinear; a plane through them is not determined"));
    }
    Ok(Plane { point: [c[0], c[1], c[2]], normal: arr(&axes[2]) })
}

// ---------------------------------------------------------------- circles and spheres

/// Algebraic (Kåsa) fit of centred points: centre offset and radius.
fn algebraic_sphere(q: &[[f64; 3]], dim: usize) -> Option<(Vector3<f64>, f64)> {
    let p = dim + 1;
    let mut a = DMatrix::<f64>::zeros(p, p);
    let mut b = DVector::<f64>::zeros(p);
    for x in q {
        let row: Vec<f64> = (0..dim).map(|d| 2.0 * x[d]).chain([1.0]).collect();
        let rhs: f64 = (0..dim).map(|d| x[d] * x[d]).sum();
        for i in 0..p {
            b[i] += row[i] * rhs;
            for j in 0..p {
                a[(i, j)] += row[i] * row[j];
            }
        }
    }
    let sol = a.lu().solve(&b)?;
    let mut c = Vector3::zeros();
    for d in 0..dim {
        c[d] = sol[d];
    }
    let r2 = sol[dim] + c.norm_squared();
    (r2 > 0.0 && sol.iter().all(|v| v.is_finite())).then(|| (c, r2.sqrt()))
}

/// Geometric least-squares circle (dim 2) or sphere (dim 3) of centred points.
fn geometric_sphere(q: &[[f64; 3]], dim: usize, what: &str) -> Result<(Vector3<f64>, f64)> {
    let start = algebraic_sphere(q, dim).ok_or_else(|| {
        GkError::degenerate(format!("{what}: the points do not determine a {what}"))
    })?;
    let p = dim + 1;
    let cost = |s: &(Vector3<f64>, f64)| det_sum(q, |x| ((vec3(x) - s.0).norm() - s.1).powi(2));
    let eval = |s: &(Vector3<f64>, f64)| {
        let row = |x: &[f64; 3]| {
            let dv = vec3(x) - s.0;
            let rho = dv.norm();
            let g = |d: usize| if rho > 0.0 && d < dim { -dv[d] / rho } else { 0.0 };
            (rho - s.1, [g(0), g(1), g(2), -1.0])
        };
        let (f, jtj, jtr) = normal_equations::<4>(q, row);
        if dim == 2 {
            // drop the z column: parameters (cx, cy, r)
            let keep = [0usize, 1, 3];
            let m = DMatrix::from_fn(3, 3, |i, j| jtj[(keep[i], keep[j])]);
            let v = DVector::from_fn(3, |i, _| jtr[keep[i]]);
            (f, m, v)
        } else {
            (f, jtj, jtr)
        }
    };
    let apply = |s: &(Vector3<f64>, f64), st: &DVector<f64>| {
        let mut c = s.0;
        for d in 0..dim {
            c[d] += st[d];
        }
        (c, s.1 + st[dim])
    };
    let (s, _) = levenberg_marquardt(start, p, start.1, 500, eval, cost, apply, what)?;
    Ok((s.0, s.1.abs()))
}

/// Least-squares circle of 2-D points (dim 2) or sphere of 3-D points (dim 3),
/// minimising the sum of squared orthogonal distances.
pub fn sphere(pts: &[f64], dim: usize) -> Result<Sphere> {
    let what = if dim == 2 { "circle" } else { "sphere" };
    let n = check_points(pts, dim, dim + 1, what)?;
    let _ = n;
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
    let (off, r) = geometric_sphere(&q, dim, what)?;
    Ok(Sphere { center: (0..dim).map(|d| c[d] + off[d]).collect(), radius: r })
}

/// Least-squares circle in 3-D (the NIST convention): least-squares plane,
/// projection of the points onto it, least-squares circle in that plane
/// ([`crate::circle::in_plane`]).
pub fn circle3(pts: &[f64]) -> Result<Circle3> {
    let c = crate::circle::in_plane::fit(pts, crate::criterion::FitCriterion::LeastSquares)?;
    Ok(Circle3 { center: c.center, normal: c.normal, radius: c.radius })
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

// ---------------------------------------------------------------- cylinders

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

/// Levenberg–Marquardt refinement of a cylinder from a starting axis, on
/// centred points. Returns the cylinder (in centred coordinates) and its cost.
fn refine_cylinder(
    q: &[[f64; 3]],
    l0: Vector3<f64>,
    a0: Vector3<f64>,
    r0: f64,
    max_iter: usize,
) -> Result<(Cylinder, f64)> {
    type S = (Vector3<f64>, Vector3<f64>, f64);
    let cost = |s: &S| det_sum(q, |x| ((vec3(x) - s.0).cross(&s.1).norm() - s.2).powi(2));
    // Step (x0, y0, alpha, beta, dr) in the frame (u, v, a) of the current axis:
    // point += x0 u + y0 v, direction = normalize(a + alpha u + beta v) (Forbes 1989).
    let eval = |s: &S| {
        let (u, v) = orthonormal_basis(&s.1);
        normal_equations::<5>(q, |x| {
            let d = vec3(x) - s.0;
            let (xu, yv, z) = (d.dot(&u), d.dot(&v), d.dot(&s.1));
            let rho = xu.hypot(yv);
            let (cx, cy) = if rho > 0.0 { (xu / rho, yv / rho) } else { (0.0, 0.0) };
            (rho - s.2, [-cx, -cy, -cx * z, -cy * z, -1.0])
        })
    };
    let apply = |s: &S, st: &DVector<f64>| {
        let (u, v) = orthonormal_basis(&s.1);
        let l = s.0 + u * st[0] + v * st[1];
        let a = (s.1 + u * st[2] + v * st[3]).normalize();
        // keep the axis point at the foot of the centroid (origin of the centred data)
        let l = l - a * l.dot(&a);
        (l, a, s.2 + st[4])
    };
    let l0 = l0 - a0 * l0.dot(&a0);
    let (s, _) = levenberg_marquardt((l0, a0, r0), 5, r0, max_iter, eval, cost, apply, "cylinder")?;
    let f = cost(&s);
    Ok((Cylinder { point: arr(&s.0), direction: arr(&s.1), radius: s.2.abs() }, f))
}

/// Least-squares cylinder, minimising the sum of squared orthogonal distances.
///
/// Starts from each principal axis of the data (and from `start_axis` when
/// given): the projected points' least-squares circle gives the start
/// position and radius; the lowest-cost refinement wins.
pub fn cylinder(pts: &[f64], start_axis: Option<[f64; 3]>) -> Result<Cylinder> {
    check_points(pts, 3, 5, "cylinder")?;
    let c = centroid(pts, 3);
    let q = centred3(pts, 3, &c);
    let (sv, axes) = principal_axes(&q);
    if sv[0] == 0.0 {
        return Err(GkError::degenerate("cylinder: all points coincide"));
    }
    if sv[1] <= DEGENERATE * sv[0] {
        return Err(GkError::degenerate("cylinder: the points are collinear; no cylinder is determined"));
    }
    let mut starts: Vec<Vector3<f64>> = axes.to_vec();
    if let Some(a) = start_axis {
        let a = vec3(&a);
        if a.norm() > 0.0 && a.iter().all(|v| v.is_finite()) {
            starts.insert(0, a.normalize());
        }
    }
    // Phase 1: a few iterations from every start; phase 2: the best to convergence.
    let mut best: Option<(Cylinder, f64)> = None;
    let mut last_err = None;
    for a in starts {
        let (u, v) = orthonormal_basis(&a);
        let q2: Vec<[f64; 3]> = q.iter().map(|x| [vec3(x).dot(&u), vec3(x).dot(&v), 0.0]).collect();
        let Some((off, r)) = algebraic_sphere(&q2, 2) else { continue };
        let l0 = u * off[0] + v * off[1];
        match refine_cylinder(&q, l0, a, r, 6) {
            Ok((cyl, f)) => {
                if best.as_ref().is_none_or(|b| f < b.1) {
                    best = Some((cyl, f));
                }
            }
            Err(e) => last_err = Some(e),
        }
    }
    if let Some((b, _)) = &best {
        let (l, a) = (vec3(&b.point), vec3(&b.direction));
        best = Some(refine_cylinder(&q, l, a, b.radius, 500)?);
    }
    let (cyl, _) = best.ok_or_else(|| {
        last_err.unwrap_or_else(|| GkError::degenerate("cylinder: the points do not determine a cylinder"))
    })?;
    let p = vec3(&cyl.point) + vec3(&c);
    Ok(Cylinder { point: arr(&p), direction: upper(cyl.direction), ..cyl })
}

// ---------------------------------------------------------------- cones

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

/// Algebraic cone for a known axis direction `a` (centred points): with
/// rho = s + t z about the axis through (x0, y0), x^2 + y^2 is linear in
/// (1, z, z^2, x, y). Returns the axis point offset, s and t.
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
    if !(c[2] > 0.0) {
        return None;
    }
    let (x0, y0) = (0.5 * c[3], 0.5 * c[4]);
    let t = c[2].sqrt();
    let s = c[1] / (2.0 * t);
    (s.is_finite() && t.is_finite()).then(|| (u * x0 + v * y0, s, t))
}

/// Least-squares cone, minimising the squared orthogonal distances
/// d = rho cos(psi) - z sin(psi) - D (Forbes' parametrisation), from
/// algebraic starts about each principal axis.
pub fn cone(pts: &[f64]) -> Result<Cone> {
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
        normal_equations::<6>(&q, |x| {
            let d = vec3(x) - s.0;
            let (xu, yv, z) = (d.dot(&u), d.dot(&v), d.dot(&s.1));
            let rho = xu.hypot(yv);
            let (cx, cy) = if rho > 0.0 { (xu / rho, yv / rho) } else { (0.0, 0.0) };
            let r = rho * cp - z * sp - s.2;
            // step (x0, y0, alpha, beta, dD, dpsi); a' = a + alpha u + beta v
            (r, [-cp * cx, -cp * cy, -cp * cx * z - sp * xu, -cp * cy * z - sp * yv, -1.0, -rho * sp - z * cp])
        })
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
            let psi = (sign * t0).atan();
            let start: S = (l0, a, s0 * psi.cos(), psi);
            if let Ok((sol, _)) = levenberg_marquardt(start, 6, sv[0] / (q.len() as f64).sqrt(), 500, eval, cost, apply, "cone") {
                let f = cost(&sol);
                if f.is_finite() && best.as_ref().is_none_or(|b| f < b.1) {
                    best = Some((sol, f));
                }
            }
        }
    }
    let ((l, a, mut dd, mut psi), _) =
        best.ok_or_else(|| GkError::degenerate("cone: the points do not determine a cone"))?;
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
    Ok(Cone { point: arr(&(l + vec3(&c))), direction: arr(&a), distance: dd, half_angle: psi })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cyl_points(n: usize, l: [f64; 3], a: [f64; 3], r: f64, noise: f64) -> Vec<f64> {
        let a = vec3(&a).normalize();
        let (u, v) = orthonormal_basis(&a);
        let mut out = Vec::new();
        for i in 0..n {
            let t = i as f64 * 2.399963;
            let z = (i as f64 * 0.618034).fract() * 40.0 - 20.0;
            let rr = r + noise * ((i * 7919 % 13) as f64 / 6.0 - 1.0);
            let p = vec3(&l) + a * z + (u * t.cos() + v * t.sin()) * rr;
            out.extend_from_slice(&[p[0], p[1], p[2]]);
        }
        out
    }

    #[test]
    fn exact_cylinder_far_from_origin() {
        let l = [1e6, -2e6, 5e5];
        let a = [0.3, -0.2, 0.9];
        let pts = cyl_points(50, l, a, 12.5, 0.0);
        let c = cylinder(&pts, None).unwrap();
        assert!((c.radius - 12.5).abs() < 1e-8, "{}", c.radius);
        let an = vec3(&a).normalize();
        assert!(vec3(&c.direction).cross(&an).norm() < 1e-10);
        let e = axis_extent(&pts, &c.point, &c.direction);
        assert!(e.max - e.min < 1e-7);
    }

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

    #[test]
    fn degenerate_inputs() {
        assert!(line(&[1.0, 1.0, 1.0, 1.0], 2).is_err());
        assert!(plane(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0]).is_err());
        assert!(plane(&[0.0, f64::NAN, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 3.0]).is_err());
        assert!(cylinder(&[0.0; 15], None).is_err());
    }
}
