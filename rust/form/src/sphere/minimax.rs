//! Maximum inscribed and minimum zone spheres by sequential linear programming.
//!
//! About a centre `c`, the distance of a point moves to first order by `g_i . d` with
//! `g_i = -(p_i - c) / |p_i - c|` when the centre moves by `d`. Each step solves, in
//! the box `|d|_inf <= delta`,
//!
//! - MZ: min a - b subject to rho_i + g_i . d <= hi + a and rho_i + g_i . d >= lo + b
//!   (the 3-D form of Eq. 6.5);
//! - MI: max b subject to rho_i + g_i . d >= t + b and, for the MC constraint of
//!   Eq. 6.2, |c - c_MC| + e . d + t + b <= r_MC (e the unit vector from c_MC),
//!
//! a trust region grows after good steps and shrinks after poor ones; the search stops
//! when the LP predicts no decrease beyond rounding.

use super::global::{self, Goal};
use super::{extremes, min_circumscribed, SphereZone};
use crate::lp;
use crate::lsq;
use gagekit_core::{GkError, Result};
use nalgebra::Vector3;

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    MaxInscribed,
    MinZone,
}

/// Most LPs of one search.
const MAX_STEPS: usize = 300;

struct Problem {
    /// Points centred on their centroid.
    q: Vec<Vector3<f64>>,
    kind: Kind,
    /// The MC (centred) for the MI constraint.
    mc: (Vector3<f64>, f64),
    size: f64,
}

impl Problem {
    /// (value to minimise, lo, hi, the MI's t) about centre `c`.
    fn value(&self, c: &Vector3<f64>) -> (f64, f64, f64, f64) {
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for p in &self.q {
            let d = (p - c).norm();
            lo = lo.min(d);
            hi = hi.max(d);
        }
        match self.kind {
            Kind::MinZone => (hi - lo, lo, hi, lo),
            Kind::MaxInscribed => {
                let t = lo.min(self.mc.1 - (c - self.mc.0).norm());
                (-t, lo, hi, t)
            }
        }
    }

    /// SLP from `start`; returns the centre and the LPs solved.
    fn descend(&self, start: Vector3<f64>) -> (Vector3<f64>, usize) {
        let mut c = start;
        let (mut f, _, _, _) = self.value(&c);
        let mut delta = 1e-2 * self.size;
        let (delta_min, delta_max) = (1e-15 * self.size, self.size);
        let nv = if self.kind == Kind::MinZone { 5 } else { 4 };
        let cost: Vec<f64> =
            if self.kind == Kind::MinZone { vec![0.0, 0.0, 0.0, 1.0, -1.0] } else { vec![0.0, 0.0, 0.0, -1.0] };
        let mut steps = 0;
        while steps < MAX_STEPS {
            let (_, lo, hi, t) = self.value(&c);
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for j in 0..3 {
                for s in [1.0, -1.0] {
                    let mut row = vec![0.0; nv];
                    row[j] = s;
                    a.extend(row);
                    b.push(delta);
                }
            }
            for p in &self.q {
                let w = p - c;
                let rho = w.norm();
                let g = if rho > 0.0 { -w / rho } else { Vector3::zeros() };
                // rows that cannot bind within the box are left out
                let reach = 2.0 * 3f64.sqrt() * delta;
                if self.kind == Kind::MinZone && hi - rho <= reach {
                    a.extend([g[0], g[1], g[2], -1.0, 0.0]);
                    b.push(hi - rho);
                }
                let base = if self.kind == Kind::MinZone { lo } else { t };
                if rho - base <= reach {
                    a.extend([-g[0], -g[1], -g[2]]);
                    if self.kind == Kind::MinZone {
                        a.push(0.0);
                    }
                    a.push(1.0);
                    b.push(rho - base);
                }
            }
            if self.kind == Kind::MaxInscribed {
                let w = c - self.mc.0;
                let dn = w.norm();
                let e = if dn > 0.0 { w / dn } else { Vector3::zeros() };
                a.extend([e[0], e[1], e[2], 1.0]);
                b.push((self.mc.1 - dn - t).max(0.0));
            }
            steps += 1;
            let Some(z) = lp::minimize(&a, &b, &cost) else { break };
            let predicted = -cost.iter().zip(&z).map(|(c, z)| c * z).sum::<f64>();
            if !(predicted > 1e-15 * self.size) {
                break;
            }
            let trial = c + Vector3::new(z[0], z[1], z[2]);
            let (ft, _, _, _) = self.value(&trial);
            let ratio = (f - ft) / predicted;
            if ratio > 1e-4 {
                c = trial;
                f = ft;
            }
            let step = z[..3].iter().fold(0.0f64, |m, v| m.max(v.abs()));
            delta = lp::next_radius(delta, step, ratio, delta_max);
            if delta < delta_min {
                break;
            }
        }
        (c, steps)
    }
}

/// Above this many points the global search runs on an active subset.
const ACTIVE_ABOVE: usize = 4096;
/// Points added per side (nearest, farthest) to the active subset in each round.
const ACTIVE: usize = 512;

/// The certified global search ([`global::search`]) over the cube (centre `m0`, half side
/// `h0`). On many points it runs on an active subset: the points nearest to (and for MZ
/// farthest from) the local optimum `start`. A subset's bound holds for all points (fewer
/// constraints: the MZ width can only shrink, the MI radius only grow), so the subset's
/// best centre is certified when its value on all points is within the tolerance of that
/// bound; otherwise the points beyond the subset's extremes at that centre join it and
/// the search runs again.
fn certify(pb: &Problem, goal: Goal, m0: Vector3<f64>, h0: f64, start: Vector3<f64>) -> global::Certified {
    let n = pb.q.len();
    if n <= ACTIVE_ABOVE {
        return global::search(&pb.q, goal, m0, h0, pb.size, start);
    }
    let tol = global::tolerance(pb.size);
    let mz = goal == Goal::MinZone;
    let mut active: Vec<usize> = Vec::new();
    let mut centre = start;
    let mut cubes = 0;
    for _round in 0..20 {
        // the points beyond the active subset's extremes at `centre` (all of them at first)
        let d: Vec<f64> = pb.q.iter().map(|p| (p - centre).norm()).collect();
        let (lo, hi) = active.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &i| (l.min(d[i]), h.max(d[i])));
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&i, &j| d[i].total_cmp(&d[j]).then(i.cmp(&j)));
        let before = active.len();
        active.extend(order.iter().take(ACTIVE).filter(|&&i| d[i] < lo));
        if mz {
            active.extend(order.iter().rev().take(ACTIVE).filter(|&&i| d[i] > hi));
        }
        active.sort_unstable();
        active.dedup();
        if active.len() == before {
            break; // nothing beyond: the last subset's answer stands (checked below)
        }
        let sub: Vec<Vector3<f64>> = active.iter().map(|&i| pb.q[i]).collect();
        let cert = global::search(&sub, goal, m0, h0, pb.size, centre);
        cubes += cert.cubes;
        centre = cert.center;
        // minimisation form: MZ the width, MI minus the radius
        let bound = if mz { cert.bound } else { -cert.bound };
        if pb.value(&centre).0 <= bound + tol {
            return global::Certified { center: centre, bound: cert.bound, cubes };
        }
    }
    let mut all = global::search(&pb.q, goal, m0, h0, pb.size, centre);
    all.cubes += cubes;
    all
}

/// The checks (finite, magnitude, at least 4 points, not coplanar), the least-squares
/// and MC spheres, and the problem on the points centred on their centroid `c0`.
fn setup(pts: &[f64], kind: Kind, what: &str) -> Result<(Problem, lsq::Sphere, SphereZone, Vector3<f64>)> {
    let ls = lsq::sphere(pts, 3).map_err(|e| GkError::new(e.kind, e.message.replacen("sphere", what, 1)))?;
    let mc = min_circumscribed(pts)?;
    let c0 = lsq::centroid(pts, 3);
    let c0 = Vector3::new(c0[0], c0[1], c0[2]);
    let q: Vec<Vector3<f64>> = pts.chunks_exact(3).map(|p| Vector3::new(p[0], p[1], p[2]) - c0).collect();
    let size = q.iter().map(|p| p.norm()).fold(0.0, f64::max);
    let mcc = Vector3::from(mc.center) - c0;
    let pb = Problem { q, kind, mc: (mcc, mc.r_out), size };
    Ok((pb, ls, mc, c0))
}

fn fit(pts: &[f64], kind: Kind) -> Result<SphereZone> {
    let what = if kind == Kind::MinZone { "minimum-zone sphere" } else { "maximum inscribed sphere" };
    let (pb, ls, mc, c0) = setup(pts, kind, what)?;
    let (mcc, size) = (pb.mc.0, pb.size);
    // a local optimum first (the exact local step from the least-squares or MC centre),
    // then the certified global search over the centre, then the local step from its best
    let lsc = Vector3::new(ls.center[0], ls.center[1], ls.center[2]) - c0;
    let (local, steps) = pb.descend(if kind == Kind::MinZone { lsc } else { mcc });
    let cert = match kind {
        Kind::MinZone => certify(&pb, Goal::MinZone, lsc, ls.radius.max(1e-9 * size), local),
        Kind::MaxInscribed => certify(&pb, Goal::MaxInscribed { mc: mcc, r_mc: mc.r_out }, mcc, mc.r_out, local),
    };
    let (polished, more) = pb.descend(cert.center);
    let iterations = steps + more;
    let c = [polished, cert.center, local].into_iter().min_by(|a, b| pb.value(a).0.total_cmp(&pb.value(b).0)).unwrap_or(local);
    let center = [c[0] + c0[0], c[1] + c0[1], c[2] + c0[2]];
    let tol = 1e-9 * size;
    let (lo, hi, cin, cout) = extremes(pts, &center, tol);
    let (r_in, r_out) = match kind {
        Kind::MinZone => (lo, hi),
        Kind::MaxInscribed => {
            let off = (Vector3::from(center) - Vector3::from(mc.center)).norm();
            let r = lo.min(mc.r_out - off);
            (r, r)
        }
    };
    if !(r_in.is_finite() && r_out.is_finite()) {
        return Err(GkError::numerical(format!("{what}: the search did not converge")));
    }
    let control_out = if kind == Kind::MinZone { cout } else { cin.clone() };
    Ok(SphereZone { center, r_in, r_out, control_in: cin, control_out, iterations, bound: cert.bound, cubes: cert.cubes })
}

/// Minimum-zone sphere (sphericity) of 3-D points (flat, at least 4, not coplanar).
pub fn min_zone(pts: &[f64]) -> Result<SphereZone> {
    fit(pts, Kind::MinZone)
}

/// Maximum inscribed sphere within the minimum circumscribed one (3-D Eq. 6.2).
pub fn max_inscribed(pts: &[f64]) -> Result<SphereZone> {
    fit(pts, Kind::MaxInscribed)
}

/// The old local-only search (tests): best value from the LS and MC starts.
#[cfg(test)]
pub(super) fn local_only(pts: &[f64], mz: bool) -> f64 {
    let kind = if mz { Kind::MinZone } else { Kind::MaxInscribed };
    let (pb, ls, _, c0) = setup(pts, kind, "sphere").unwrap();
    let starts = [Vector3::new(ls.center[0], ls.center[1], ls.center[2]) - c0, pb.mc.0];
    let v = starts.iter().map(|s| pb.value(&pb.descend(*s).0).0).fold(f64::INFINITY, f64::min);
    if mz { v } else { -v }
}
