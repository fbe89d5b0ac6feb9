//! Convex-hull filter of Sec. 5.4.1: the vertices `S'` of the hull of a point
//! set `S`, with `CH(S) = CH(S')` (Eq. 5.21).
//!
//! Exactness: every orientation decision uses Shewchuk's adaptive exact
//! predicates, so the returned set satisfies Eq. 5.21 exactly (no tolerance),
//! and contains no point lying inside the hull or in the relative interior of a
//! hull edge or face. Among duplicate points the lowest index is reported.
//!
//! Pipeline: for large inputs an Akl–Toussaint prefilter ([`prefilter`])
//! discards in parallel every point strictly inside a polytope spanned by input
//! points; the survivors are de-duplicated and hulled by an exact quickhull
//! ([`quickhull`]). Collinear and coplanar sets fall back to 1-D and 2-D hulls.

mod chain;
mod exact;
mod inner;
mod planar;
mod prefilter;
mod quickhull;

pub use chain::hull_2d;
use exact::{collinear, cross, dot, orient2d, orient3d, project, pt, sub, P3};
use gagekit_core::{check_finite, GkError, Result};
use rayon::prelude::*;

/// Inputs at least this large go through the parallel prefilter first.
const PREFILTER_MIN: usize = 4096;

/// Ascending indices of the extreme vertices of the convex hull of `points`
/// (row-major, `n x 3`), the set `S'` of Eq. 5.21.
///
/// Degenerate input: no points gives no indices; exactly collinear points give
/// the two end points; exactly coplanar points give the vertices of their 2-D
/// hull. NaN or infinite coordinates, and magnitudes beyond 1e100 or below
/// 1e-60 (other than 0), are an `InvalidInput` error naming the point.
pub fn convex_hull_indices(points: &[f64]) -> Result<Vec<usize>> {
    validate(points)?;
    let n = points.len() / 3;
    if n == 0 {
        return Ok(Vec::new());
    }
    let candidates: Vec<usize> = if n >= PREFILTER_MIN {
        prefilter::survivors(points)
    } else {
        (0..n).collect()
    };
    let mut out = hull_of(points, candidates)?;
    out.sort_unstable();
    Ok(out)
}

/// The triangulated hull of a solid point set: `triangles` (original indices,
/// counter-clockwise seen from outside) and `neighbors[f][i]`, the triangle across the
/// edge `(triangles[f][i], triangles[f][(i + 1) % 3])`. Coplanar triangles of one facet
/// are kept apart (their shared edges lie inside the facet).
#[derive(Debug, Clone)]
pub struct HullMesh {
    pub triangles: Vec<[usize; 3]>,
    pub neighbors: Vec<[usize; 3]>,
}

/// The triangulated convex hull of `points` (row-major, `n x 3`), or `None` when the
/// points are exactly coplanar or collinear (no solid hull). Same checks, prefilter and
/// exact quickhull as [`convex_hull_indices`].
pub fn convex_hull_mesh(points: &[f64]) -> Result<Option<HullMesh>> {
    validate(points)?;
    let n = points.len() / 3;
    if n < 4 {
        return Ok(None);
    }
    let candidates: Vec<usize> = if n >= PREFILTER_MIN { prefilter::survivors(points) } else { (0..n).collect() };
    let ids = distinct(points, candidates);
    if ids.len() < 4 {
        return Ok(None);
    }
    let p: Vec<P3> = ids.iter().map(|&i| pt(points, i)).collect();
    let Simplex::Solid(init) = simplex(&p) else { return Ok(None) };
    let h = quickhull::hull3d(&p, init)?;
    let triangles = h.faces.iter().map(|f| f.map(|k| ids[k as usize])).collect();
    let neighbors = h.nbrs.iter().map(|g| g.map(|k| k as usize)).collect();
    Ok(Some(HullMesh { triangles, neighbors }))
}

/// Largest and smallest non-zero coordinate magnitude for which the
/// predicates' floating-point filters cannot overflow or underflow.
const MAX_COORD: f64 = 1e100;
const MIN_COORD: f64 = 1e-60;

/// One parallel pass over the coordinates; the detailed (serial) checks that
/// name the offending point run only when something is wrong.
fn validate(points: &[f64]) -> Result<()> {
    let fine = |v: &f64| {
        let a = v.abs();
        a <= MAX_COORD && (a >= MIN_COORD || a == 0.0)
    };
    let all_fine = points.par_chunks(1 << 16).all(|c| c.iter().all(fine));
    if points.len() % 3 != 0 || !all_fine {
        check_finite(points, 3, "points")?;
        check_range(points)?;
    }
    Ok(())
}

/// Exactness of the predicates needs products of coordinate differences to
/// stay in the normal floating-point range.
fn check_range(points: &[f64]) -> Result<()> {
    let bad = |v: &f64| v.abs() > MAX_COORD || (*v != 0.0 && v.abs() < MIN_COORD);
    match points.iter().position(bad) {
        None => Ok(()),
        Some(pos) => Err(GkError::invalid(format!(
            "points: point {} has coordinate {:e}; the hull filter supports magnitudes \
             between 1e-60 and 1e100 mm (or exactly 0)",
            pos / 3,
            points[pos]
        ))),
    }
}

/// Candidates sorted lexicographically by coordinates, one per distinct point
/// (the lowest index of each group of duplicates).
fn distinct(points: &[f64], mut ids: Vec<usize>) -> Vec<usize> {
    ids.sort_unstable_by(|&i, &j| {
        pt(points, i)
            .partial_cmp(&pt(points, j))
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(i.cmp(&j))
    });
    ids.dedup_by(|later, first| pt(points, *later) == pt(points, *first));
    ids
}

/// Extreme vertices (original indices, unordered) of the hull of `ids`.
fn hull_of(points: &[f64], ids: Vec<usize>) -> Result<Vec<usize>> {
    let ids = distinct(points, ids);
    if ids.len() <= 2 {
        return Ok(ids);
    }
    let p: Vec<P3> = ids.iter().map(|&i| pt(points, i)).collect();
    let local = extreme_local(&p)?;
    Ok(local.into_iter().map(|k| ids[k]).collect())
}

/// Extreme points of distinct, lexicographically sorted points `p` (>= 3),
/// as indices into `p`.
pub(crate) fn extreme_local(p: &[P3]) -> Result<Vec<usize>> {
    match simplex(p) {
        Simplex::Segment(a, b) => Ok(vec![a, b]),
        Simplex::Plane(axis) => Ok(planar::hull2d(p, &(0..p.len()).collect::<Vec<_>>(), axis)),
        Simplex::Solid(init) => Ok(quickhull::hull3d(p, init)?.extreme_vertices(p)),
    }
}

pub(crate) enum Simplex {
    /// All points on the segment between these two (exactly collinear).
    Segment(usize, usize),
    /// Exactly coplanar; dropping this coordinate maps the plane one-to-one.
    Plane(usize),
    /// A non-degenerate tetrahedron.
    Solid([usize; 4]),
}

/// The largest (in floating point) non-degenerate simplex spanned from the
/// lexicographic extremes of `p`; degeneracy itself is decided exactly.
pub(crate) fn simplex(p: &[P3]) -> Simplex {
    let (a, b) = (0, p.len() - 1);
    let dir = sub(p[b], p[a]);
    let off_line = |i: usize| {
        let c = cross(dir, sub(p[i], p[a]));
        dot(c, c)
    };
    let far = (0..p.len()).max_by(|&i, &j| off_line(i).total_cmp(&off_line(j)));
    let c = match far.filter(|&i| !collinear(p[a], p[b], p[i])) {
        Some(c) => c,
        None => match (0..p.len()).find(|&i| !collinear(p[a], p[b], p[i])) {
            Some(c) => c,
            None => return Simplex::Segment(a, b),
        },
    };
    let height = |i: usize| orient3d(p[a], p[b], p[c], p[i]).abs();
    let d = (0..p.len()).max_by(|&i, &j| height(i).total_cmp(&height(j)));
    match d.filter(|&d| height(d) != 0.0) {
        Some(d) => Simplex::Solid([a, b, c, d]),
        None => {
            let area =
                |ax: usize| orient2d(project(p[a], ax), project(p[b], ax), project(p[c], ax)).abs();
            let axis = (0..3)
                .max_by(|&x, &y| area(x).total_cmp(&area(y)))
                .unwrap_or(2);
            Simplex::Plane(axis)
        }
    }
}

#[cfg(test)]
mod tests;
