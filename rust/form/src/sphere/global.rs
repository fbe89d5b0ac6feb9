//! Certified global search over the sphere's centre (branch and bound) for the maximum
//! inscribed and the minimum-zone sphere.
//!
//! Both objectives are functions of the centre `c` alone:
//!
//! - MZ (sphericity, 3-D Eq. 6.5): `f(c) = max_i |p_i - c| - min_j |p_j - c|`, to minimise;
//! - MI within the MC sphere (3-D Eq. 6.2): `g(c) = min(min_j |p_j - c|, r_MC - |c - c_MC|)`,
//!   to maximise.
//!
//! Cubes of centres are split in eight, the cube with the best bound first. On a cube
//! `B` every distance `|p_i - c|` lies between the distance of `p_i` to the cube and to
//! its farthest corner (exact interval bounds), so
//! `f >= max_i dmin_i(B) - min_j dmax_j(B)` and
//! `g <= min(min_j dmax_j(B), r_MC - dist(c_MC, B))` on `B`. A point whose interval lies
//! wholly below another's lower end cannot be the farthest anywhere in `B` (or wholly
//! above another's upper end, the nearest); each cube keeps only the points that can
//! still be extreme in it, so deep cubes test a handful of points. Where that bound
//! does not settle a cube of few points, a second one is tried: about the cube's centre
//! `m`, with `u_i` the unit vector from `m` to `p_i` and `s = c - m`,
//! `|p_i - c| >= |p_i - m| - u_i . s` (convexity) and
//! `|p_i - c| <= |p_i - m| - u_i . s + |s|^2 / (2 |p_i - m|)`, so the linear program of
//! the sequential-LP step over the cube, less `3 h^2 / (2 min_j |p_j - m|)`, bounds the
//! objective too: its gap shrinks as `h^2`, which settles flat optima (a spherical cap's
//! centre is loosely held along the cap's axis). The value at each
//! cube's centre is an achieved value. The search stops when the best achieved value is
//! within [`tolerance`] of the smallest bound of the cubes left: that bound is the
//! certificate (no centre in the searched cube does better).
//!
//! The searched cube: for MI the MC sphere's bounding cube (every centre with
//! `g >= 0` lies in the MC ball, so the MI is global); for MZ the cube of half side
//! `r_LS` (the least-squares radius) about the least-squares centre: a zone whose
//! centre moved by more than the feature's radius describes another feature.

use crate::lp;
use nalgebra::Vector3;
use rayon::prelude::*;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Stop splitting after this many cubes; the certificate then reports the bound reached.
const MAX_CUBES: usize = 3_000_000;

/// The linear-programming bound uses at most this many points (the most extreme ones at
/// the cube's centre: a subset of the constraints still bounds the objective).
const LP_POINTS: usize = 128;

/// The certified tolerance on the objective: 1e-9 mm, or 1e-13 of the part's size when
/// that is larger (the rounding of coordinates far from the origin).
pub(super) fn tolerance(size: f64) -> f64 {
    1e-9f64.max(1e-13 * size)
}

/// Which objective.
#[derive(Clone, Copy, PartialEq, Debug)]
pub(super) enum Goal {
    /// Minimise the zone width.
    MinZone,
    /// Maximise the inscribed radius within the MC sphere (centre, radius).
    MaxInscribed { mc: Vector3<f64>, r_mc: f64 },
}

/// What the search proved: the best centre found and the certified bound on the optimum (MZ: no centre gives a narrower zone;
/// MI: no centre gives a larger sphere).
#[derive(Debug, Clone, Copy)]
pub(super) struct Certified {
    pub center: Vector3<f64>,
    pub bound: f64,
    pub cubes: usize,
}

struct Cube {
    m: Vector3<f64>,
    h: f64,
    /// Lower bound of the objective to minimise (MZ: width; MI: minus the radius).
    lower: f64,
    far: Vec<u32>,
    near: Vec<u32>,
}

impl PartialEq for Cube {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Cube {}
impl PartialOrd for Cube {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Cube {
    /// The heap pops the smallest bound first (ties: the cube's centre, for a
    /// deterministic order).
    fn cmp(&self, o: &Self) -> Ordering {
        o.lower
            .total_cmp(&self.lower)
            .then_with(|| o.m[0].total_cmp(&self.m[0]))
            .then_with(|| o.m[1].total_cmp(&self.m[1]))
            .then_with(|| o.m[2].total_cmp(&self.m[2]))
    }
}

/// Distance from `p` to the cube (centre `m`, half side `h`) and to its farthest corner.
#[inline]
fn interval(p: &Vector3<f64>, m: &Vector3<f64>, h: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (0.0, 0.0);
    for k in 0..3 {
        let a = (p[k] - m[k]).abs();
        let d = (a - h).max(0.0);
        lo += d * d;
        hi += (a + h) * (a + h);
    }
    (lo.sqrt(), hi.sqrt())
}

struct Search<'a> {
    q: &'a [Vector3<f64>],
    goal: Goal,
    /// Rounding slack of the interval tests.
    slack: f64,
    tol: f64,
}

/// A cube's bound, its centre's value and the points kept.
struct Evaluated {
    lower: f64,
    value: f64,
    far: Vec<u32>,
    near: Vec<u32>,
}

impl Search<'_> {
    fn evaluate(&self, m: &Vector3<f64>, h: f64, far: &[u32], near: &[u32], best: f64) -> Evaluated {
        let q = self.q;
        // nearest side: the smallest upper end, then the points whose lower end reaches it
        let iv: Vec<(f64, f64)> = near.iter().map(|&j| interval(&q[j as usize], m, h)).collect();
        let up = iv.iter().fold(f64::INFINITY, |a, v| a.min(v.1));
        let near: Vec<u32> = near.iter().zip(&iv).filter(|(_, v)| v.0 <= up + self.slack).map(|(&j, _)| j).collect();
        let at_m_near = near.iter().map(|&j| (q[j as usize] - m).norm()).fold(f64::INFINITY, f64::min);
        let mut e = match self.goal {
            Goal::MinZone => {
                let iv: Vec<(f64, f64)> = far.iter().map(|&i| interval(&q[i as usize], m, h)).collect();
                let down = iv.iter().fold(0.0f64, |a, v| a.max(v.0));
                let far: Vec<u32> =
                    far.iter().zip(&iv).filter(|(_, v)| v.1 >= down - self.slack).map(|(&i, _)| i).collect();
                let at_m_far = far.iter().map(|&i| (q[i as usize] - m).norm()).fold(0.0, f64::max);
                Evaluated { lower: down - up, value: at_m_far - at_m_near, far, near }
            }
            Goal::MaxInscribed { mc, r_mc } => {
                let (to_mc, _) = interval(&mc, m, h);
                let upper = up.min(r_mc - to_mc);
                let value = at_m_near.min(r_mc - (m - mc).norm());
                Evaluated { lower: -upper, value: -value, far: Vec::new(), near }
            }
        };
        let open = e.lower < best.min(e.value) - self.tol;
        if open && at_m_near > 0.0 {
            // on many points, the LP of the most extreme ones at m (still a bound)
            let far = self.extreme(m, &e.far, true);
            let near = self.extreme(m, &e.near, false);
            let d_near = near.iter().map(|&j| (q[j as usize] - m).norm()).fold(f64::INFINITY, f64::min);
            if let Some(lower) = self.lp_bound(m, h, &far, &near, d_near) {
                e.lower = e.lower.max(lower);
            }
        }
        e
    }

    /// The `LP_POINTS / 2` points of `ids` farthest from (`far`) or nearest to `m`.
    fn extreme(&self, m: &Vector3<f64>, ids: &[u32], far: bool) -> Vec<u32> {
        let k = LP_POINTS / 2;
        if ids.len() <= k {
            return ids.to_vec();
        }
        let mut d: Vec<(f64, u32)> = ids.iter().map(|&i| ((self.q[i as usize] - m).norm_squared(), i)).collect();
        let key = |a: &(f64, u32), b: &(f64, u32)| if far { b.0.total_cmp(&a.0) } else { a.0.total_cmp(&b.0) };
        d.select_nth_unstable_by(k - 1, key);
        d[..k].iter().map(|v| v.1).collect()
    }

    /// The linearised bound of the module doc on the cube (centre `m`, half side `h`),
    /// or `None` when the LP did not solve.
    fn lp_bound(&self, m: &Vector3<f64>, h: f64, far: &[u32], near: &[u32], d_near: f64) -> Option<f64> {
        let q = self.q;
        let curv = 1.5 * h * h / d_near;
        let unit = |i: u32| -> (f64, Vector3<f64>) {
            let w = q[i as usize] - m;
            let d = w.norm();
            (d, if d > 0.0 { w / d } else { Vector3::zeros() })
        };
        let (mut a, mut b) = (Vec::new(), Vec::new());
        let nv = if self.goal == Goal::MinZone { 5 } else { 4 };
        for k in 0..3 {
            for sg in [1.0, -1.0] {
                let mut row = vec![0.0; nv];
                row[k] = sg;
                a.extend(row);
                b.push(h);
            }
        }
        match self.goal {
            Goal::MinZone => {
                // z = (s, a', b'): min a' - b'; d_i - u_i.s <= A0 + a'; d_j - u_j.s >= B0 + b'
                let far_d: Vec<(f64, Vector3<f64>)> = far.iter().map(|&i| unit(i)).collect();
                let near_d: Vec<(f64, Vector3<f64>)> = near.iter().map(|&j| unit(j)).collect();
                let a0 = far_d.iter().fold(0.0f64, |x, v| x.max(v.0));
                let b0 = near_d.iter().fold(f64::INFINITY, |x, v| x.min(v.0));
                for (d, u) in &far_d {
                    a.extend([-u[0], -u[1], -u[2], -1.0, 0.0]);
                    b.push(a0 - d);
                }
                for (d, u) in &near_d {
                    a.extend([u[0], u[1], u[2], 0.0, 1.0]);
                    b.push(d - b0);
                }
                let z = lp::minimize(&a, &b, &[0.0, 0.0, 0.0, 1.0, -1.0])?;
                Some(a0 - b0 + z[3] - z[4] - curv)
            }
            Goal::MaxInscribed { mc, r_mc } => {
                // z = (s, t'): max t'; T0 + t' <= d_j - u_j.s; T0 + t' <= r_mc - |m - mc| - e.s
                let w = m - mc;
                let dm = w.norm();
                let e = if dm > 0.0 { w / dm } else { Vector3::zeros() };
                let near_d: Vec<(f64, Vector3<f64>)> = near.iter().map(|&j| unit(j)).collect();
                let t0 = near_d.iter().fold(r_mc - dm, |x, v| x.min(v.0));
                for (d, u) in &near_d {
                    a.extend([u[0], u[1], u[2], 1.0]);
                    b.push(d - t0);
                }
                a.extend([e[0], e[1], e[2], 1.0]);
                b.push(r_mc - dm - t0);
                let z = lp::minimize(&a, &b, &[0.0, 0.0, 0.0, -1.0])?;
                Some(-(t0 + z[3] + curv))
            }
        }
    }
}

/// Branch and bound over the centres in the cube (centre `m0`, half side `h0`) of the
/// points `q` (centred near the origin; `size` their scale); `start` is a good centre
/// (a local optimum) whose value prunes from the first split.
pub(super) fn search(q: &[Vector3<f64>], goal: Goal, m0: Vector3<f64>, h0: f64, size: f64, start: Vector3<f64>) -> Certified {
    let tol = tolerance(size);
    let s = Search { q, goal, slack: 1e-13 * size, tol };
    let all: Vec<u32> = (0..q.len() as u32).collect();
    let far = if goal == Goal::MinZone { all.clone() } else { Vec::new() };
    let first = s.evaluate(&start, 0.0, &far, &all, f64::NEG_INFINITY);
    let root = s.evaluate(&m0, h0, &far, &all, first.value);
    let mut best = if first.value <= root.value { (first.value, start) } else { (root.value, m0) };
    let mut heap = BinaryHeap::new();
    heap.push(Cube { m: m0, h: h0, lower: root.lower, far: root.far, near: root.near });
    // smallest bound of the cubes dropped without being split
    let mut dropped = f64::INFINITY;
    let mut cubes = 1usize;
    let floor = 1e-15 * size;
    while let Some(cube) = heap.pop() {
        if cube.lower >= best.0 - tol || cubes >= MAX_CUBES || cube.h <= floor {
            dropped = dropped.min(cube.lower);
            if cube.lower >= best.0 - tol || cubes >= MAX_CUBES {
                heap.push(cube);
                break;
            }
            continue;
        }
        let h = 0.5 * cube.h;
        let children: Vec<(Vector3<f64>, Evaluated)> = (0..8u8)
            .into_par_iter()
            .with_min_len(if cube.far.len() + cube.near.len() > 4096 { 1 } else { 8 })
            .map(|k| {
                let sx = |b: u8| if k & b != 0 { h } else { -h };
                let m = cube.m + Vector3::new(sx(1), sx(2), sx(4));
                let e = s.evaluate(&m, h, &cube.far, &cube.near, best.0);
                (m, e)
            })
            .collect();
        cubes += 8;
        for (m, e) in children {
            if e.value < best.0 {
                best = (e.value, m);
            }
            if e.lower < best.0 - tol {
                heap.push(Cube { m, h, lower: e.lower, far: e.far, near: e.near });
            } else {
                dropped = dropped.min(e.lower);
            }
        }
    }
    let left = heap.iter().map(|c| c.lower).fold(f64::INFINITY, f64::min);
    let bound = best.0.min(dropped).min(left);
    match goal {
        Goal::MinZone => Certified { center: best.1, bound, cubes },
        Goal::MaxInscribed { .. } => Certified { center: best.1, bound: -bound, cubes },
    }
}
