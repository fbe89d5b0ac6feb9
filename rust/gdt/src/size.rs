//! Local sizes of features of size (ISO 14405-1:2016).
//!
//! **Two-point sizes (LP) of a cylinder, circle or cone** ([`two_point_sizes`] with
//! [`Sections::Axial`]): the points are cut into `sections` equal slices across the
//! least-squares axis (each slice's points, projected along the axis, form the section's
//! profile in polar coordinates (theta, rho) about the axis); in each section the profile
//! is sorted by angle and `angles` directions phi_j = j pi / angles (j = 0 .. angles-1)
//! are drawn through the axis. The two opposite points of the real surface on the line
//! of direction phi_j are interpolated on the scan, rho linear in theta between the two
//! profile points that bracket phi_j (and phi_j + pi); the local size is
//! rho(phi_j) + rho(phi_j + pi), ISO 14405-1 Sec. 3.6.1 (two-point size: the distance
//! between two opposite points, on a line through the associated axis). A direction
//! whose bracketing points are more than [`GAP_FACTOR`] times the section's median
//! angular spacing apart has no surface there (an unscanned sector) and gives no size.
//! Linear interpolation in the angle keeps r(t) + r(t + pi) exact for profiles sampled
//! symmetrically under a half turn (a 3-lobed shaft has every two-point size 2R).
//!
//! **Spheres** ([`Sections::GreatCircles`]): `sections` half planes through the centre
//! containing the reference direction, rotated by pi / sections; each point joins the
//! nearest plane; its in-plane angle and its 3-D distance from the centre form the profile.
//!
//! **Widths** ([`width_sizes`]): the two-point size between two opposite planar faces:
//! for every point of the first face, the opposite point on the second face along the
//! median plane's normal, interpolated linearly on the Delaunay triangulation of the
//! second face's points (`spade`); points whose opposite falls outside the second face
//! give no size.
//!
//! **Hull distance** ([`hull_distance`]): the distance between the convex hulls of two
//! point sets (GJK with the exact closest point on each simplex): the maximum inscribed
//! size GX of a width (the largest pair of parallel planes separating the two faces).
//!
//! Every kernel runs in parallel (rayon) and is deterministic (results in section
//! order, directions in angle order).

use crate::vec3::{self, check_points, dot, sub, V3};
use gagekit_core::{GkError, Result};
use rayon::prelude::*;
use spade::{DelaunayTriangulation, FloatTriangulation, HasPosition, Point2, Triangulation};

/// A direction's bracketing profile points farther apart than this many median
/// spacings of its section lie across a gap of the scan: no size there.
pub const GAP_FACTOR: f64 = 10.0;

/// Profile points whose angles differ by at most this (rad) are one direction (the same
/// angle of several rings in a slice, up to rounding).
pub const MERGE_RAD: f64 = 1e-9;

/// How the points are cut into sections.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sections {
    /// Slices across the axis (cylinders, circles, cones).
    Axial,
    /// Half planes through the centre containing the axis (spheres).
    GreatCircles,
}

/// The two-point sizes of a feature: `sizes[k]` in section `section[k]` along the
/// direction `angle[k]` (rad, in the section's (u, v) basis of the axis).
#[derive(Debug, Clone, PartialEq)]
pub struct TwoPoint {
    pub sizes: Vec<f64>,
    pub section: Vec<u32>,
    pub angle: Vec<f64>,
    /// Number of sections holding at least 3 points.
    pub sections_used: usize,
}

fn profile_size(mut prof: Vec<(f64, f64)>, angles: usize) -> Vec<(f64, f64)> {
    use std::f64::consts::PI;
    let tau = 2.0 * PI;
    if prof.len() < 3 {
        return Vec::new();
    }
    prof.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    // merge points of one direction (angles within MERGE_RAD: the same angle of
    // several rings of a slice, up to rounding): their mean radius
    let mut merged: Vec<(f64, f64)> = Vec::with_capacity(prof.len());
    let mut k = 0;
    while k < prof.len() {
        let mut j = k + 1;
        let mut s = prof[k].1;
        while j < prof.len() && prof[j].0 - prof[k].0 <= MERGE_RAD {
            s += prof[j].1;
            j += 1;
        }
        merged.push((prof[k].0, s / (j - k) as f64));
        k = j;
    }
    let n = merged.len();
    if n < 3 {
        return Vec::new();
    }
    let mut gaps: Vec<f64> = (0..n)
        .map(|i| if i + 1 < n { merged[i + 1].0 - merged[i].0 } else { merged[0].0 + tau - merged[n - 1].0 })
        .collect();
    let max_gap = {
        let m = n / 2;
        gaps.select_nth_unstable_by(m, |a, b| a.total_cmp(b));
        GAP_FACTOR * gaps[m]
    };
    // rho at angle phi in [-pi, pi): the bracketing pair (circularly)
    let rho_at = |phi: f64| -> Option<f64> {
        let i = merged.partition_point(|p| p.0 <= phi); // first index with theta > phi
        let (a, b, ta, tb) = if i == 0 {
            (merged[n - 1], merged[0], merged[n - 1].0 - tau, merged[0].0)
        } else if i == n {
            (merged[n - 1], merged[0], merged[n - 1].0, merged[0].0 + tau)
        } else {
            (merged[i - 1], merged[i], merged[i - 1].0, merged[i].0)
        };
        let gap = tb - ta;
        if gap > max_gap {
            return None;
        }
        if gap <= 0.0 || phi == ta {
            return Some(a.1);
        }
        let w = (phi - ta) / gap;
        Some(a.1 + w * (b.1 - a.1))
    };
    let wrap = |x: f64| if x >= PI { x - tau } else { x };
    let mut out = Vec::with_capacity(angles);
    for j in 0..angles {
        let phi = -PI + PI * j as f64 / angles as f64; // directions in [-pi, 0)
        if let (Some(r1), Some(r2)) = (rho_at(phi), rho_at(wrap(phi + PI))) {
            out.push((phi, r1 + r2));
        }
    }
    out
}

/// The unit `reference` projected normal to the unit `a`, and `a x u`: the section
/// basis that moves with the part (the first direction phi = -pi is -u); `basis(a)` if
/// `reference` is (nearly) along `a`.
fn section_basis(a: V3, reference: V3) -> (V3, V3) {
    let r = sub(reference, vec3::scale(a, dot(reference, a)));
    match vec3::unit(r, "reference") {
        Ok(u) if vec3::norm(r) > 1e-6 * vec3::norm(reference) => (u, vec3::cross(a, u)),
        _ => vec3::basis(a),
    }
}

/// Two-point sizes of the points about the axis (`origin`, unit `axis`): see the module
/// documentation. The directions are measured from `reference` projected normal to the
/// axis (a direction that moves with the part, so the sizes are invariant under rigid
/// motions). `sections >= 1`, `angles >= 1`.
#[allow(clippy::too_many_arguments)]
pub fn two_point_sizes(
    pts: &[f64],
    origin: V3,
    axis: V3,
    reference: V3,
    kind: Sections,
    sections: usize,
    angles: usize,
) -> Result<TwoPoint> {
    use std::f64::consts::PI;
    let n = check_points(pts, 3, "two-point sizes")?;
    gagekit_core::check_finite(&origin, 3, "two-point sizes: the axis point")?;
    let a = vec3::unit(axis, "two-point sizes: the axis")?;
    if sections == 0 || angles == 0 {
        return Err(GkError::invalid("two-point sizes: 'sections' and 'angles' must be positive"));
    }
    gagekit_core::check_finite(&reference, 3, "two-point sizes: the reference direction")?;
    let (u, v) = section_basis(a, reference);
    // per point: (section, theta, rho)
    let coords: Vec<(f64, f64, f64)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let q = sub(vec3::at(pts, i), origin);
            let (x, y, t) = (dot(q, u), dot(q, v), dot(q, a));
            match kind {
                Sections::Axial => (t, y.atan2(x), x.hypot(y)),
                Sections::GreatCircles => (y.atan2(x), 0.0, vec3::norm(q)),
            }
        })
        .collect();
    let keys: Vec<usize> = match kind {
        Sections::Axial => {
            let (lo, hi) = coords.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), c| (l.min(c.0), h.max(c.0)));
            coords
                .iter()
                .map(|c| if hi > lo { (((c.0 - lo) / (hi - lo) * sections as f64) as usize).min(sections - 1) } else { 0 })
                .collect()
        }
        Sections::GreatCircles => coords
            .iter()
            .map(|c| {
                let az = c.0.rem_euclid(PI); // the plane through the axis at azimuth psi holds psi and psi + pi
                ((az / PI * sections as f64).round() as usize) % sections
            })
            .collect(),
    };
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); sections];
    for (i, &k) in keys.iter().enumerate() {
        members[k].push(i);
    }
    let per: Vec<Vec<(f64, f64)>> = members
        .par_iter()
        .enumerate()
        .map(|(k, idx)| {
            let prof: Vec<(f64, f64)> = match kind {
                Sections::Axial => idx.iter().map(|&i| (coords[i].1, coords[i].2)).collect(),
                Sections::GreatCircles => {
                    let psi = PI * k as f64 / sections as f64;
                    let e = [psi.cos() * u[0] + psi.sin() * v[0], psi.cos() * u[1] + psi.sin() * v[1], psi.cos() * u[2] + psi.sin() * v[2]];
                    idx.iter()
                        .map(|&i| {
                            let q = sub(vec3::at(pts, i), origin);
                            (dot(q, a).atan2(dot(q, e)), coords[i].2)
                        })
                        .collect()
                }
            };
            profile_size(prof, angles)
        })
        .collect();
    let mut out = TwoPoint { sizes: Vec::new(), section: Vec::new(), angle: Vec::new(), sections_used: 0 };
    for (k, s) in per.into_iter().enumerate() {
        if members[k].len() >= 3 {
            out.sections_used += 1;
        }
        for (phi, d) in s {
            out.sizes.push(d);
            out.section.push(k as u32);
            out.angle.push(phi);
        }
    }
    Ok(out)
}

struct Vert {
    pos: Point2<f64>,
    h: f64,
}

impl HasPosition for Vert {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

/// Two-point sizes of a width: for each point of `face_a`, the height (along the unit
/// `normal`, from `face_a` towards `face_b`) of the opposite point of `face_b`, linearly
/// interpolated on the Delaunay triangulation of `face_b` in the plane normal to
/// `normal`, minus its own height. Returns the sizes of the points whose opposite point
/// lies on `face_b`.
pub fn width_sizes(face_a: &[f64], face_b: &[f64], normal: V3) -> Result<Vec<f64>> {
    check_points(face_a, 1, "width sizes: first face")?;
    check_points(face_b, 3, "width sizes: second face")?;
    let nrm = vec3::unit(normal, "width sizes: the normal")?;
    let (u, v) = vec3::basis(nrm);
    let verts: Vec<Vert> = face_b
        .chunks_exact(3)
        .map(|p| {
            let p = [p[0], p[1], p[2]];
            Vert { pos: Point2::new(dot(p, u), dot(p, v)), h: dot(p, nrm) }
        })
        .collect();
    let dt = DelaunayTriangulation::<Vert>::bulk_load(verts)
        .map_err(|e| GkError::invalid(format!("width sizes: cannot triangulate the second face ({e:?})")))?;
    if dt.num_inner_faces() == 0 {
        return Err(GkError::degenerate("width sizes: the second face's points are collinear"));
    }
    let sizes: Vec<Option<f64>> = face_a
        .par_chunks(3 * 4096)
        .flat_map_iter(|chunk| {
            let bary = dt.barycentric();
            chunk
                .chunks_exact(3)
                .map(|p| {
                    let p = [p[0], p[1], p[2]];
                    bary.interpolate(|w| w.data().h, Point2::new(dot(p, u), dot(p, v))).map(|h| h - dot(p, nrm))
                })
                .collect::<Vec<_>>()
        })
        .collect();
    Ok(sizes.into_iter().flatten().collect())
}

fn support(pts: &[f64], d: V3) -> V3 {
    pts.par_chunks(3 * 8192)
        .map(|c| {
            let mut best = (f64::NEG_INFINITY, [0.0; 3]);
            for p in c.chunks_exact(3) {
                let p = [p[0], p[1], p[2]];
                let s = dot(p, d);
                if s > best.0 {
                    best = (s, p);
                }
            }
            best
        })
        .reduce(|| (f64::NEG_INFINITY, [0.0; 3]), |a, b| if b.0 > a.0 { b } else { a })
        .1
}

/// The point of the affine hull of `s` nearest the origin, as barycentric weights, when
/// it lies inside the simplex (all weights > 0); `None` otherwise or if degenerate.
fn affine_closest(s: &[V3]) -> Option<Vec<f64>> {
    let m = s.len();
    if m == 1 {
        return Some(vec![1.0]);
    }
    // minimise |s0 + sum_k l_k (s_k - s0)|^2: normal equations G l = -E^T s0
    let e: Vec<V3> = (1..m).map(|k| sub(s[k], s[0])).collect();
    let k = m - 1;
    let mut g = [[0.0f64; 4]; 3];
    for i in 0..k {
        for j in 0..k {
            g[i][j] = dot(e[i], e[j]);
        }
        g[i][k] = -dot(e[i], s[0]);
    }
    // Gaussian elimination with partial pivoting
    for c in 0..k {
        let p = (c..k).max_by(|&a, &b| g[a][c].abs().total_cmp(&g[b][c].abs()))?;
        g.swap(c, p);
        let scale = (0..k).map(|j| g[c][j].abs()).fold(0.0, f64::max);
        if g[c][c].abs() <= 1e-14 * scale.max(f64::MIN_POSITIVE) {
            return None;
        }
        for r in 0..k {
            if r != c {
                let f = g[r][c] / g[c][c];
                for j in c..=k {
                    g[r][j] -= f * g[c][j];
                }
            }
        }
    }
    let l: Vec<f64> = (0..k).map(|i| g[i][k] / g[i][i]).collect();
    let l0 = 1.0 - l.iter().sum::<f64>();
    let mut w = vec![l0];
    w.extend(l);
    if w.iter().all(|&x| x > 0.0) {
        Some(w)
    } else {
        None
    }
}

/// The point of the simplex `s` (1-4 points) nearest the origin: (point, the
/// vertices that carry it). Every face of the simplex is tried (at most 15).
fn closest_on_simplex(s: &[V3]) -> (V3, Vec<V3>) {
    let m = s.len();
    let mut best: Option<(f64, V3, Vec<V3>)> = None;
    for mask in 1u32..(1 << m) {
        let sub_s: Vec<V3> = (0..m).filter(|i| mask & (1 << i) != 0).map(|i| s[i]).collect();
        if let Some(w) = affine_closest(&sub_s) {
            let mut p = [0.0; 3];
            for (x, q) in w.iter().zip(&sub_s) {
                for c in 0..3 {
                    p[c] += x * q[c];
                }
            }
            let d = dot(p, p);
            if best.as_ref().is_none_or(|b| d < b.0) {
                best = Some((d, p, sub_s));
            }
        }
    }
    let (_, p, keep) = best.expect("a single vertex is always a candidate");
    (p, keep)
}

/// Distance between the convex hulls of two point sets (flat (n, 3) buffers), and the
/// unit direction from the first hull to the second (GJK, Gilbert-Johnson-Keerthi 1988;
/// support points over every input point, the closest point of each simplex exact).
/// Zero (with a zero direction) when the hulls intersect.
pub fn hull_distance(a: &[f64], b: &[f64]) -> Result<(f64, V3)> {
    check_points(a, 1, "hull distance: first set")?;
    check_points(b, 1, "hull distance: second set")?;
    // Minkowski difference B - A: its support in d is s_B(d) - s_A(-d)
    let sup = |d: V3| sub(support(b, d), support(a, [-d[0], -d[1], -d[2]]));
    let mut simplex = vec![sub(vec3::at(b, 0), vec3::at(a, 0))];
    let mut v = simplex[0];
    for _ in 0..200 {
        let vv = dot(v, v);
        if vv == 0.0 {
            return Ok((0.0, [0.0; 3]));
        }
        let w = sup([-v[0], -v[1], -v[2]]);
        // stop when the support point does not bring the origin closer (exact at a vertex)
        if vv - dot(v, w) <= 1e-13 * vv || simplex.iter().any(|s| *s == w) {
            break;
        }
        simplex.push(w);
        let (p, keep) = closest_on_simplex(&simplex);
        if dot(p, p) >= vv {
            break;
        }
        v = p;
        simplex = keep;
        if simplex.len() == 4 {
            return Ok((0.0, [0.0; 3]));
        }
    }
    let d = vec3::norm(v);
    Ok((d, vec3::scale(v, 1.0 / d)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn lobed(r: f64, a: f64, k: f64, n_theta: usize, heights: &[f64]) -> Vec<f64> {
        let mut out = Vec::new();
        for &z in heights {
            for i in 0..n_theta {
                let t = 2.0 * PI * i as f64 / n_theta as f64;
                let rho = r + a * (k * t).cos();
                out.extend([rho * t.cos(), rho * t.sin(), z]);
            }
        }
        out
    }

    #[test]
    fn three_lobes_have_constant_two_point_size() {
        let pts = lobed(10.0, 0.05, 3.0, 360, &[0.0, 1.0, 2.0, 3.0]);
        let tp = two_point_sizes(&pts, [0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], Sections::Axial, 4, 90).unwrap();
        assert_eq!(tp.sizes.len(), 4 * 90);
        for s in &tp.sizes {
            assert!((s - 20.0).abs() < 1e-12, "{s}");
        }
    }

    #[test]
    fn oval_two_point_range() {
        let pts = lobed(10.0, 0.05, 2.0, 720, &[0.0]);
        let tp = two_point_sizes(&pts, [0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], Sections::Axial, 1, 180).unwrap();
        let lo = tp.sizes.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = tp.sizes.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        assert!((lo - 19.9).abs() < 1e-12 && (hi - 20.1).abs() < 1e-12, "{lo} {hi}");
    }

    #[test]
    fn a_gap_gives_no_size() {
        // half a circle: no direction has both opposite points
        let mut pts = Vec::new();
        for i in 0..=180 {
            let t = PI * i as f64 / 180.0;
            pts.extend([5.0 * t.cos(), 5.0 * t.sin(), 0.0]);
        }
        let tp = two_point_sizes(&pts, [0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], Sections::Axial, 1, 36).unwrap();
        assert!(tp.sizes.len() <= 1, "{:?}", tp.sizes);
    }

    #[test]
    fn sphere_great_circles() {
        let mut pts = Vec::new();
        for i in 1..60 {
            let lat = -PI / 2.0 + PI * i as f64 / 60.0;
            for j in 0..120 {
                let lon = 2.0 * PI * j as f64 / 120.0;
                pts.extend([4.0 * lat.cos() * lon.cos() + 1.0, 4.0 * lat.cos() * lon.sin(), 4.0 * lat.sin() - 2.0]);
            }
        }
        let tp = two_point_sizes(&pts, [1.0, 0.0, -2.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], Sections::GreatCircles, 6, 36).unwrap();
        assert!(!tp.sizes.is_empty());
        for s in &tp.sizes {
            assert!((s - 8.0).abs() < 1e-9, "{s}");
        }
    }

    #[test]
    fn width_between_tilted_faces() {
        let mut a = Vec::new();
        let mut b = Vec::new();
        for i in 0..30 {
            for j in 0..20 {
                let (x, y) = (i as f64, j as f64);
                a.extend([x, y, 0.0]);
                b.extend([x + 0.5, y + 0.5, 10.0 + 0.01 * x]);
            }
        }
        let s = width_sizes(&a, &b, [0.0, 0.0, 1.0]).unwrap();
        assert!(!s.is_empty());
        // the interpolated opposite height of a plane is exact: 10 + 0.01 (x - 0.5)
        let mut k = 0;
        for i in 0..30 {
            for j in 0..20 {
                let (x, y) = (i as f64, j as f64);
                if x >= 0.5 && y >= 0.5 && x <= 29.5 && y <= 19.5 {
                    assert!((s[k] - (10.0 + 0.01 * (x - 0.5))).abs() < 1e-9);
                    k += 1;
                }
            }
        }
        assert_eq!(k, s.len());
    }

    #[test]
    fn hull_distance_of_two_slabs() {
        let mut a = Vec::new();
        let mut b = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                a.extend([i as f64, j as f64, 0.0 + 0.001 * ((i * 7 + j * 3) % 5) as f64]);
                b.extend([i as f64, j as f64, 5.0 + 0.001 * ((i * 3 + j) % 4) as f64]);
            }
        }
        let (d, n) = hull_distance(&a, &b).unwrap();
        // the lowest point of b is 5.0, the highest of a is 0.004: the planes z = 0.004 and z = 5
        assert!((d - (5.0 - 0.004)).abs() < 1e-12, "{d}");
        assert!((n[2] - 1.0).abs() < 1e-12);
        let (d0, _) = hull_distance(&a, &a).unwrap();
        assert_eq!(d0, 0.0);
    }
}
