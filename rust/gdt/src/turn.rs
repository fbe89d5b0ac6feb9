//! Searches over a turn angle: the degree of freedom a datum system leaves about one
//! direction (ISO 5459:2011 Sec. 6.3: an orientation constraint that leaves one
//! rotation; ISO 1101:2017 Sec. 7: the degrees of freedom the datums do not lock are
//! free and the zone is optimised over them). Each function here is one callout's (or
//! one datum's) whole search, so a callout is one kernel call.
//!
//! Methods, case by case:
//!
//! - [`axis_on_cone`]: a datum axis at a basic angle to a datum plane, free to turn about
//!   the plane's normal (ISO 5459 Sec. B.3 associated cylinder). The radius of the
//!   maximum inscribed (minimum circumscribed) cylinder of a fixed direction is exact
//!   ([`crate::datum::axis_along`]: 2-D Voronoi / Welzl), but as a function of the turn
//!   it is only piecewise smooth and need not be unimodal: a 41-point grid within
//!   [`CONE_TURN`] of the least-squares axis's turn, then golden-section search in the
//!   best cell (each value costs a Voronoi diagram) refined until the bracket stops
//!   shrinking (machine precision of the turn).
//!   Not certified global; the grid cell is the bracket.
//! - [`cylinder_on_cone`]: the smallest cylindrical zone at a basic angle, free to turn
//!   (angularity of a derived axis, ISO 1101 Sec. 18.11): the same structure over a full
//!   turn, a [`TURN_GRID`]-point grid, golden-section refinement of the best local minima.
//! - [`position`]: position of a centre or an axis (ISO 1101 Sec. 18.12) when the datums
//!   leave the rotation about z free. Without free translations and with a point or a
//!   line along z the squared distances are sinusoids of the turn, so the optimum is a
//!   vertex of their upper envelope: **exact** ([`min_max_sinusoids`]). Otherwise the inner
//!   problem (a minimum enclosing circle over the free translations) is exact (Welzl, or a
//!   convex 1-D minimum refined to machine precision) and the turn is searched by grid
//!   and golden section.
//! - [`plane_location`]: position / profile of a plane with a free turn: each signed
//!   distance is a sinusoid of the turn; grid, golden section, then an exact polish with
//!   the active extreme sinusoids fixed (their stationary point, kept when no worse).
//! - [`position_with_shift`]: a position whose datum axis may shift (ISO 2692 MMB): the
//!   inner problem is exact ([`min_in_disk`]), the turn (when free) by grid and golden section.

use crate::datum::{self, Axis, AxisFit};
use crate::vec3::{self, check_points, dot, norm, sub, V3};
use gagekit_core::{GkError, Result};
use rayon::prelude::*;

/// Half width (rad) of the turn searched about a datum plane's normal around the
/// least-squares axis, for a datum axis at a basic angle to the plane (10 degrees).
pub const CONE_TURN: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// Grid of the datum axis search within [`CONE_TURN`] (intervals; points = this + 1).
pub const CONE_GRID: usize = 40;

/// Grid of a full-turn search.
pub const TURN_GRID: usize = 720;

/// Best local minima of a full-turn grid refined by golden section.
pub const TURN_CELLS: usize = 3;

// -- the one-dimensional searches ---------------------------------------------------------

/// (value, x) of the minimum of `f` on [lo, hi] by golden-section search, iterated until
/// the bracket stops shrinking in floating point (at most 200 steps; deterministic).
pub fn golden<F: Fn(f64) -> f64>(f: &F, mut lo: f64, mut hi: f64) -> (f64, f64) {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..200 {
        if !(x1 > lo && x2 > x1 && hi > x2) {
            break;
        }
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = f(x2);
        }
    }
    let x = 0.5 * (lo + hi);
    (f(x), x)
}

/// Minimum of `f` over `n + 1` grid points `lo + k (hi - lo) / n` (`cyclic`: `n` points
/// of a full turn), then golden-section search in the two cells around each of the best
/// `cells` local minima of the grid; a refined value is kept only when it is no worse
/// than the grid's best. Returns (value, x). Grid values in parallel, deterministic.
pub fn min_on_grid<F: Fn(f64) -> f64 + Sync>(f: &F, lo: f64, hi: f64, n: usize, cyclic: bool, cells: usize) -> (f64, f64) {
    let step = (hi - lo) / n as f64;
    let m = if cyclic { n } else { n + 1 };
    let vals: Vec<f64> = (0..m).into_par_iter().map(|k| f(lo + k as f64 * step)).collect();
    let left = |k: usize| if cyclic { Some((k + m - 1) % m) } else { k.checked_sub(1) };
    let right = |k: usize| if cyclic { Some((k + 1) % m) } else { (k + 1 < m).then_some(k + 1) };
    let want = cells.max(1);
    let mut cells: Vec<usize> = (0..m)
        .filter(|&k| left(k).is_none_or(|j| vals[k] <= vals[j]) && right(k).is_none_or(|j| vals[k] <= vals[j]))
        .collect();
    cells.sort_by(|&i, &j| vals[i].total_cmp(&vals[j]).then(i.cmp(&j)));
    cells.truncate(want);
    let k0 = cells[0];
    let mut best = (vals[k0], lo + k0 as f64 * step);
    // the cells refined in parallel, compared in their fixed order (deterministic)
    let refined: Vec<(f64, f64)> = cells
        .par_iter()
        .map(|&k| {
            let a = if cyclic || k > 0 { lo + (k as f64 - 1.0) * step } else { lo };
            let b = if cyclic || k + 1 < m { lo + (k as f64 + 1.0) * step } else { hi };
            golden(f, a, b)
        })
        .collect();
    for (fx, x) in refined {
        if fx < best.0 {
            best = (fx, x);
        }
    }
    best
}

/// Exact (value, psi) of min over psi of max_i f_i(psi), f_i = a_i - b_i cos(psi - phi_i):
/// the minimum of the upper envelope lies at the minimum of one sinusoid or where two
/// cross, (a_i - a_j) = r cos(psi - d); every candidate is scored on every f_i, ties to
/// the first candidate (the sinusoids' own minima, then the crossings pair by pair).
pub fn min_max_sinusoids(a: &[f64], b: &[f64], phi: &[f64]) -> (f64, f64) {
    let n = a.len();
    let mut cand: Vec<f64> = phi.to_vec();
    let (mut plus, mut minus) = (Vec::new(), Vec::new());
    for i in 0..n {
        for j in i + 1..n {
            let c1 = b[i] * phi[i].cos() - b[j] * phi[j].cos();
            let s1 = b[i] * phi[i].sin() - b[j] * phi[j].sin();
            let (r, d, rhs) = (c1.hypot(s1), s1.atan2(c1), a[i] - a[j]);
            if r > 0.0 && rhs.abs() <= r {
                let t = (rhs / r).clamp(-1.0, 1.0).acos();
                plus.push(d + t);
                minus.push(d - t);
            }
        }
    }
    cand.extend(plus);
    cand.extend(minus);
    let env = |psi: f64| (0..n).map(|i| a[i] - b[i] * (psi - phi[i]).cos()).fold(f64::NEG_INFINITY, f64::max);
    let vals: Vec<f64> = cand.par_iter().map(|&p| env(p)).collect();
    let mut k = 0;
    for (i, v) in vals.iter().enumerate() {
        if *v < vals[k] {
            k = i;
        }
    }
    (vals[k], cand[k])
}

/// The largest and smallest of g_i(psi) = k_i + c_i cos psi + s_i sin psi over the rows
/// `[k_i, c_i, s_i]` of `coef`, each with its (first) index: the extremes of a linear
/// function whose direction turns about an axis.
pub(crate) fn extremes(coef: &[[f64; 3]], psi: f64) -> ((f64, usize), (f64, usize)) {
    let (c, s) = (psi.cos(), psi.sin());
    let (mut hi, mut lo) = ((f64::NEG_INFINITY, 0usize), (f64::INFINITY, 0usize));
    for (i, g) in coef.iter().enumerate() {
        let h = g[0] + c * g[1] + s * g[2];
        if h > hi.0 {
            hi = (h, i);
        }
        if h < lo.0 {
            lo = (h, i);
        }
    }
    (hi, lo)
}

// -- small exact pieces -------------------------------------------------------------------

/// Minimum enclosing circle of 2-D points (Welzl, exact): (radius recomputed as the
/// largest distance to the centre, centre).
pub fn mec(xy: &[[f64; 2]]) -> Result<(f64, [f64; 2])> {
    match xy.len() {
        0 => Err(GkError::invalid("minimum enclosing circle: no points")),
        1 => Ok((0.0, xy[0])),
        2 => Ok((0.5 * (xy[1][0] - xy[0][0]).hypot(xy[1][1] - xy[0][1]), [0.5 * (xy[0][0] + xy[1][0]), 0.5 * (xy[0][1] + xy[1][1])])),
        _ => {
            if xy.iter().all(|p| *p == xy[0]) {
                return Ok((0.0, xy[0]));
            }
            let flat: Vec<f64> = xy.iter().flatten().copied().collect();
            let c = gagekit_form::circle::min_circumscribed(&flat)?.center;
            let r = xy.iter().map(|p| (p[0] - c[0]).hypot(p[1] - c[1])).fold(0.0, f64::max);
            Ok((r, c))
        }
    }
}

/// Exact min over |s| <= rho of max_i |w_i - s| for 2-D points `w` (the datum shift of
/// ISO 2692 MMB / LMB): the minimum enclosing circle when its centre lies in the disk,
/// otherwise a point of the rim, the minimum of the upper envelope of the sinusoids
/// |w_i|^2 + rho^2 - 2 rho |w_i| cos(phi - arg w_i). Returns (value, s).
pub fn min_in_disk(w: &[[f64; 2]], rho: f64) -> Result<(f64, [f64; 2])> {
    let (r, c) = mec(w)?;
    if c[0].hypot(c[1]) <= rho {
        return Ok((r, c));
    }
    if rho <= 0.0 {
        return Ok((w.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max), [0.0, 0.0]));
    }
    let a: Vec<f64> = w.iter().map(|p| p[0] * p[0] + p[1] * p[1] + rho * rho).collect();
    let b: Vec<f64> = w.iter().map(|p| 2.0 * rho * p[0].hypot(p[1])).collect();
    let phi: Vec<f64> = w.iter().map(|p| p[1].atan2(p[0])).collect();
    let (_, psi) = min_max_sinusoids(&a, &b, &phi);
    let s = [rho * psi.cos(), rho * psi.sin()];
    Ok((w.iter().map(|p| (p[0] - s[0]).hypot(p[1] - s[1])).fold(0.0, f64::max), s))
}

/// min over s in span(F) of max_i |w_i - s| for 3-D `w` (the free translations of a
/// datum system, orthonormal rows `F`): no freedom -- the largest |w_i|; a plane -- the
/// minimum enclosing circle (exact); a line -- max_i sqrt((a_i - s)^2 + b_i^2) is convex
/// in s, golden section on [min a, max a] until the bracket stops shrinking.
pub fn radius_free(w: &[V3], f: &[V3]) -> Result<f64> {
    if f.is_empty() {
        return Ok(w.iter().map(|p| norm(*p)).fold(0.0, f64::max));
    }
    if f.len() >= 2 {
        let xy: Vec<[f64; 2]> = w.iter().map(|p| [dot(*p, f[0]), dot(*p, f[1])]).collect();
        return Ok(mec(&xy)?.0);
    }
    let a: Vec<f64> = w.iter().map(|p| dot(*p, f[0])).collect();
    let b2: Vec<f64> = w.iter().zip(&a).map(|(p, ai)| (dot(*p, *p) - ai * ai).max(0.0)).collect();
    let (lo, hi) = a.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
    let g = |s: f64| a.iter().zip(&b2).map(|(ai, bi)| ((ai - s) * (ai - s) + bi).sqrt()).fold(0.0, f64::max);
    Ok(golden(&g, lo, hi).0)
}

// -- the datum frame's free turn ----------------------------------------------------------

/// A datum reference frame as the zones see it: `origin`, `axes` (rows x, y, z),
/// `free` (orthonormal free translations) and whether the rotation about z is free.
#[derive(Debug, Clone)]
pub struct Frame {
    pub origin: V3,
    pub axes: [V3; 3],
    pub free: Vec<V3>,
    pub free_rotation: bool,
}

impl Frame {
    /// Check the frame: finite, unit orthogonal axes, at most 3 free translations.
    pub fn checked(origin: V3, axes: [V3; 3], free: Vec<V3>, free_rotation: bool) -> Result<Self> {
        let finite = |v: &V3| v.iter().all(|x| x.is_finite());
        if !finite(&origin) || !axes.iter().all(finite) || !free.iter().all(finite) || free.len() > 3 {
            return Err(GkError::invalid("datum frame: needs a finite origin, axes and at most 3 free translations"));
        }
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                if (dot(axes[i], axes[j]) - want).abs() > 1e-9 {
                    return Err(GkError::invalid("datum frame: the axes must be unit and orthogonal"));
                }
            }
        }
        Ok(Self { origin, axes, free, free_rotation })
    }

    /// The rotation by `psi` about z (Rodrigues), as a 3x3 matrix (rows).
    fn rot(&self, psi: f64) -> [V3; 3] {
        let z = self.axes[2];
        let (c, s) = (psi.cos(), psi.sin());
        let k = [[0.0, -z[2], z[1]], [z[2], 0.0, -z[0]], [-z[1], z[0], 0.0]];
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let kk: f64 = (0..3).map(|m| k[i][m] * k[m][j]).sum();
                r[i][j] = if i == j { 1.0 } else { 0.0 } + s * k[i][j] + (1.0 - c) * kk;
            }
        }
        r
    }

    /// A nominal point turned by `psi` about z through the origin.
    fn point(&self, r: &[V3; 3], p: V3) -> V3 {
        vec3::add(self.origin, mat(r, sub(p, self.origin)))
    }

    /// Orthonormal basis of the free translations without their part along `d`.
    fn free_perp(&self, d: Option<V3>) -> Vec<V3> {
        let mut out: Vec<V3> = Vec::new();
        for t in &self.free {
            let mut t = *t;
            if let Some(d) = d {
                t = sub(t, vec3::scale(d, dot(t, d)));
            }
            for q in &out {
                t = sub(t, vec3::scale(*q, dot(t, *q)));
            }
            let l = norm(t);
            if l > 1e-9 {
                out.push(vec3::scale(t, 1.0 / l));
            }
        }
        out
    }
}

fn mat(r: &[V3; 3], v: V3) -> V3 {
    [dot(r[0], v), dot(r[1], v), dot(r[2], v)]
}

fn points(pts: &[f64]) -> Vec<V3> {
    pts.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect()
}

/// The position zone's radius of the points `pts` (flat (n, 3): a centre, or the points
/// of a derived axis) about the nominal point `p0` (`d0` None: a spherical zone) or the
/// nominal line through `p0` along `d0` (a cylindrical zone), optimised over the free
/// translations and, when the frame leaves it free, the turn about z (module docs).
/// Returns (radius, turn).
pub fn position(pts: &[f64], frame: &Frame, p0: V3, d0: Option<V3>) -> Result<(f64, f64)> {
    check_points(pts, 1, "position zone")?;
    let d0 = d0.map(|d| vec3::unit(d, "position zone: nominal direction")).transpose()?;
    let q = points(pts);
    if frame.free_rotation {
        if let Some(e) = exact_turn(&q, frame, p0, d0) {
            return Ok(e);
        }
    }
    let fail = std::sync::Mutex::new(None);
    let value = |psi: f64| -> f64 {
        let r = frame.rot(psi);
        let p = frame.point(&r, p0);
        let d = d0.map(|d| mat(&r, d));
        let w: Vec<V3> = q
            .iter()
            .map(|x| {
                let e = sub(*x, p);
                match d {
                    Some(d) => sub(e, vec3::scale(d, dot(e, d))),
                    None => e,
                }
            })
            .collect();
        radius_free(&w, &frame.free_perp(d)).unwrap_or_else(|e| {
            fail.lock().unwrap().get_or_insert(e);
            f64::INFINITY
        })
    };
    let out = if frame.free_rotation { min_on_grid(&value, 0.0, std::f64::consts::TAU, TURN_GRID, true, TURN_CELLS) } else { (value(0.0), 0.0) };
    match fail.into_inner().unwrap() {
        Some(e) => Err(e),
        None => Ok(out),
    }
}

/// Exact minimum over the free turn psi about z of the largest distance of `q` to the
/// nominal point (`d0` None) or to the nominal line (`d0` along z) when no translation
/// is free: each squared distance is a sinusoid in psi, so the optimum is an envelope
/// vertex ([`min_max_sinusoids`]). `None` where that does not hold (free translations:
/// the inner minimum enclosing circle is not a sinusoid; a line not along z: quartic).
fn exact_turn(q: &[V3], frame: &Frame, p0: V3, d0: Option<V3>) -> Option<(f64, f64)> {
    let (u, z) = (frame.axes[0], frame.axes[2]);
    let v = vec3::cross(z, u); // the turn is counter-clockwise about z: R u = cos u + sin v
    if !frame.free.is_empty() {
        return None;
    }
    if let Some(d) = d0 {
        if (dot(d, z).abs() - 1.0).abs() > 1e-12 {
            return None;
        }
    }
    let o = frame.origin;
    let perp = |x: V3| if d0.is_some() { sub(x, vec3::scale(z, dot(x, z))) } else { x };
    let b0 = perp(sub(p0, o));
    let (bz, bu, bv) = (dot(b0, z), dot(b0, u), dot(b0, v));
    let (mut a, mut b, mut phi) = (Vec::new(), Vec::new(), Vec::new());
    for x in q {
        let e = perp(sub(*x, o));
        let (qz, qu, qv) = (dot(e, z), dot(e, u), dot(e, v));
        a.push(dot(e, e) + dot(b0, b0) - 2.0 * qz * bz);
        let (cc, ss) = (qu * bu + qv * bv, qv * bu - qu * bv);
        b.push(2.0 * cc.hypot(ss));
        phi.push(ss.atan2(cc));
    }
    let (value, psi) = min_max_sinusoids(&a, &b, &phi);
    Some((value.max(0.0).sqrt(), psi))
}

/// The width of the location zone of a plane (position or profile, ISO 1101 Sec. 18.12,
/// ISO 1660): two planes symmetric about the nominal plane through `p0` with normal `n0`
/// (2 max |h_i|), or, when a free translation moves the offset, two parallel planes of
/// the nominal orientation (max h - min h); the turn about z optimised when free and the
/// normal not along z. Returns (width, turn).
pub fn plane_location(pts: &[f64], frame: &Frame, p0: V3, n0: V3) -> Result<(f64, f64)> {
    check_points(pts, 1, "plane location zone")?;
    let n0 = vec3::unit(n0, "plane location zone: nominal normal")?;
    let (u, z) = (frame.axes[0], frame.axes[2]);
    let v = vec3::cross(z, u); // the turn is counter-clockwise about z: R u = cos u + sin v
    // h_i(psi) = (q_i - R b0) . R n0 = R^T q_i . n0 - b0 . n0 = k_i + c_i cos psi + s_i sin psi
    let b0 = sub(p0, frame.origin);
    let (nz, nu, nv) = (dot(n0, z), dot(n0, u), dot(n0, v));
    let k0 = dot(b0, n0);
    let coef: Vec<[f64; 3]> = pts
        .par_chunks_exact(3)
        .map(|p| {
            let e = sub([p[0], p[1], p[2]], frame.origin);
            let (qz, qu, qv) = (dot(e, z), dot(e, u), dot(e, v));
            // R^T q: (qu, qv) turned by -psi about z
            [qz * nz - k0, qu * nu + qv * nv, qv * nu - qu * nv]
        })
        .collect();
    let search = frame.free_rotation && nz.abs() < 1.0 - 1e-12;
    // the offset is free when a free translation has a component along the normal: at
    // the nominal turn, or (turn searched) at some turn -- along z, or in the plane when
    // the normal leans
    let floating = frame.free.iter().any(|t| {
        if search {
            dot(*t, z).abs() * nz.abs() > 1e-9 || dot(*t, u).hypot(dot(*t, v)) * nu.hypot(nv) > 1e-9
        } else {
            dot(*t, n0).abs() > 1e-9
        }
    });
    let eval = |psi: f64| -> (f64, usize, usize) {
        let (hi, lo) = extremes(&coef, psi);
        if floating {
            (hi.0 - lo.0, hi.1, lo.1)
        } else if hi.0 >= -lo.0 {
            (2.0 * hi.0, hi.1, usize::MAX)
        } else {
            (-2.0 * lo.0, usize::MAX, lo.1)
        }
    };
    if !search {
        return Ok((eval(0.0).0, 0.0));
    }
    let (mut w, mut f) = min_on_grid(&|x| eval(x).0, 0.0, std::f64::consts::TAU, TURN_GRID, true, TURN_CELLS);
    // exact polish: with the active extremes fixed the width is one sinusoid
    let (_, i, j) = eval(f);
    let pick = |k: usize, s: f64| if k == usize::MAX { [0.0; 3] } else { [s * coef[k][0], s * coef[k][1], s * coef[k][2]] };
    let g = if floating {
        let (a, b) = (pick(i, 1.0), pick(j, 1.0));
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    } else if i != usize::MAX {
        pick(i, 2.0)
    } else {
        pick(j, -2.0)
    };
    if g[1] != 0.0 || g[2] != 0.0 {
        let fs = (-g[2]).atan2(-g[1]);
        let ws = eval(fs).0;
        if ws <= w {
            (w, f) = (ws, fs);
        }
    }
    Ok((w, f))
}

/// Position of axis points whose datum axis may shift within a disk of radius `rho`
/// normal to it (ISO 2692 MMB / LMB), the nominal line through `p0`, parallel to the
/// datum axis (plane `u`, `v` normal to it), no free translations: (radius, shift used,
/// turn); the turn about z optimised when the frame leaves it free.
pub fn position_with_shift(pts: &[f64], frame: &Frame, p0: V3, u: V3, v: V3, rho: f64) -> Result<(f64, f64, f64)> {
    check_points(pts, 1, "position with a datum shift")?;
    if !(rho.is_finite() && rho >= 0.0) {
        return Err(GkError::invalid(format!("position with a datum shift: the shift radius must be finite and >= 0, got {rho}")));
    }
    let q = points(pts);
    let fail = std::sync::Mutex::new(None);
    let value = |psi: f64| -> (f64, f64) {
        let r = frame.rot(psi);
        let p = frame.point(&r, p0);
        let w: Vec<[f64; 2]> = q.iter().map(|x| [dot(sub(*x, p), u), dot(sub(*x, p), v)]).collect();
        match min_in_disk(&w, rho) {
            Ok((r, s)) => (r, s[0].hypot(s[1])),
            Err(e) => {
                fail.lock().unwrap().get_or_insert(e);
                (f64::INFINITY, 0.0)
            }
        }
    };
    let psi = if frame.free_rotation { min_on_grid(&|x| value(x).0, 0.0, std::f64::consts::TAU, TURN_GRID, true, TURN_CELLS).1 } else { 0.0 };
    let (r, used) = value(psi);
    match fail.into_inner().unwrap() {
        Some(e) => Err(e),
        None => Ok((r, used, psi)),
    }
}

// -- cones of directions ------------------------------------------------------------------

/// The unit direction at `angle` (rad) from the unit `a`, turned by `phi` about it.
pub fn cone_dir(a: V3, angle: f64, phi: f64) -> V3 {
    let (u, v) = vec3::basis(a);
    let (ca, sa) = (angle.cos(), angle.sin());
    vec3::add(vec3::scale(a, ca), vec3::add(vec3::scale(u, sa * phi.cos()), vec3::scale(v, sa * phi.sin())))
}

/// The smallest cylinder containing the points whose axis is at `angle` (rad) from the
/// unit `a`, turned freely about it (angularity of a derived axis): (diameter, axis
/// direction). Each value is the exact fixed-direction cylinder (Welzl).
pub fn cylinder_on_cone(pts: &[f64], a: V3, angle: f64) -> Result<(f64, V3)> {
    check_points(pts, 1, "cylindrical zone at an angle")?;
    let a = vec3::unit(a, "cylindrical zone at an angle")?;
    let c = vec3::centroid(pts);
    let q: Vec<V3> = points(pts).into_iter().map(|p| sub(p, c)).collect();
    let value = |phi: f64| -> f64 {
        let d = cone_dir(a, angle, phi);
        let (u, v) = vec3::basis(d);
        let xy: Vec<[f64; 2]> = q.iter().map(|p| [dot(*p, u), dot(*p, v)]).collect();
        2.0 * mec(&xy).map(|m| m.0).unwrap_or(f64::INFINITY)
    };
    let (w, phi) = min_on_grid(&value, 0.0, std::f64::consts::TAU, TURN_GRID, true, TURN_CELLS);
    Ok((w, cone_dir(a, angle, phi)))
}

/// The datum axis of the points at `tilt` (rad) from the datum plane's unit normal `a`,
/// free to turn about it (ISO 5459: the orientation constraint of a secondary datum, one
/// rotation left): the maximum inscribed (minimum circumscribed) cylinder over the turn
/// within [`CONE_TURN`] of the turn of the least-squares axis `d_ls` (module docs); the
/// least-squares option takes the direction on the cone nearest `d_ls`.
pub fn axis_on_cone(pts: &[f64], a: V3, tilt: f64, d_ls: V3, fit: AxisFit) -> Result<Axis> {
    const WHAT: &str = "datum axis at an angle";
    let n = check_points(pts, if fit == AxisFit::Circumscribed { 1 } else { 3 }, WHAT)?;
    let a = vec3::unit(a, WHAT)?;
    if !tilt.is_finite() {
        return Err(GkError::invalid(format!("{WHAT}: the angle must be finite")));
    }
    let (u, v) = vec3::basis(a);
    let phi0 = dot(d_ls, v).atan2(dot(d_ls, u));
    if fit == AxisFit::LeastSquares {
        return datum::axis_along(pts, cone_dir(a, tilt, phi0), fit);
    }
    // the minimum circumscribed cylinder of a direction depends on the hull's vertices only
    let sub_pts: Vec<f64> = if fit == AxisFit::Circumscribed && n > 64 {
        match gagekit_geometry::convex_hull_indices(pts) {
            Ok(ids) if !ids.is_empty() => ids.iter().flat_map(|&i| vec3::at(pts, i)).collect(),
            _ => pts.to_vec(),
        }
    } else {
        pts.to_vec()
    };
    let sign = if fit == AxisFit::Inscribed { -1.0 } else { 1.0 };
    let fail = std::sync::Mutex::new(None);
    let value = |phi: f64| -> f64 {
        match datum::axis_along(&sub_pts, cone_dir(a, tilt, phi), fit) {
            Ok(ax) => sign * ax.radius,
            Err(e) => {
                fail.lock().unwrap().get_or_insert(e);
                f64::INFINITY
            }
        }
    };
    let (_, phi) = min_on_grid(&value, phi0 - CONE_TURN, phi0 + CONE_TURN, CONE_GRID, false, 1);
    if let Some(e) = fail.into_inner().unwrap() {
        return Err(e);
    }
    datum::axis_along(pts, cone_dir(a, tilt, phi), fit)
}
