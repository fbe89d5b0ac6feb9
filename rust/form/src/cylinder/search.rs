//! The projection-model search over axis directions (Sec. 6.3, Fig. 6.11) in one
//! region of the sphere of directions: the swarm, the SLP refinement from its best
//! particles, basin hopping, and the exact 2-D fit along the best direction.

use super::mic_search::nelder_mead_search;
use super::projection::{axis, fit2d, frame, in_space, objective, zone_value};
use super::{slp, Criterion, CylinderFit, Options, HOPS, HOP_RADIUS, START_STEP};
use crate::lsq::{self, centroid, orthonormal_basis};
use gagekit_core::{GkError, Result};
use gagekit_pso::{minimize_from, nelder_mead, Outcome, Settings};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// An orthonormal basis (u, v, w): directions are parametrised about w.
pub(super) type Basis = (Vector3<f64>, Vector3<f64>, Vector3<f64>);

/// The directions searched: within `s_max` (rad) of `basis.2`. `s_max = pi/2` with the
/// z basis is the upper half sphere t in [0, pi/2], f in [-pi, pi] of Sec. 6.4;
/// `s_max = 0` fixes the direction.
#[derive(Debug, Clone, Copy)]
pub(super) struct Region {
    pub basis: Basis,
    pub s_max: f64,
    /// The user's free search (`max_tilt` 90): also the deterministic grid search of
    /// [`half_sphere_search`], so that the result does not depend on the seed. The
    /// check for a better optimum outside a cone runs without it.
    pub exhaustive: bool,
}

impl Region {
    /// The whole upper half sphere (Sec. 6.4).
    pub fn half_sphere() -> Self {
        Self { basis: (Vector3::x(), Vector3::y(), Vector3::z()), s_max: FRAC_PI_2, exhaustive: false }
    }

    /// The whole upper half sphere, searched exhaustively (`max_tilt` 90).
    pub fn free() -> Self {
        Self { exhaustive: true, ..Self::half_sphere() }
    }

    /// Directions within `half_angle` of the unit vector `w`.
    pub fn cone(w: Vector3<f64>, half_angle: f64) -> Self {
        let (u, v) = orthonormal_basis(&w);
        Self { basis: (u, v, w), s_max: half_angle.min(FRAC_PI_2), exhaustive: false }
    }

    fn dir(&self, s: f64, g: f64) -> Vector3<f64> {
        let b = &self.basis;
        (b.0 * (s.sin() * g.cos()) + b.1 * (s.sin() * g.sin()) + b.2 * s.cos()).normalize()
    }

    fn contains(&self, a: &Vector3<f64>) -> bool {
        a.dot(&self.basis.2).abs() >= self.s_max.cos() - 1e-12
    }
}

/// The centred points and the scales every step uses.
struct Problem<'a> {
    q: Vec<f64>,
    centroid: Vec<f64>,
    crit: Criterion,
    /// Largest distance of a point from the centroid.
    size: f64,
    /// Half length of the part along the least-squares (or the region's) axis.
    len: f64,
    region: &'a Region,
}

impl Problem<'_> {
    /// The exact projection-model value at a direction and the axis of its 2-D fit.
    fn exact(&self, a: &Vector3<f64>) -> Option<(f64, slp::Axis)> {
        let (theta, phi, zone) = fit2d(&self.q, a, self.crit).ok()?;
        let v = zone_value(&zone, self.crit, self.size);
        v.is_finite().then(|| (v, slp::Axis::new(*a, in_space(theta, phi, zone.center))))
    }

    /// One SLP local search; its end direction is scored by the exact 2-D kernel.
    fn local(&self, start: slp::Axis, delta: f64) -> (f64, slp::Axis, usize) {
        let inside = |a: &Vector3<f64>| self.region.contains(a);
        let local = slp::descend(&self.q, self.crit, start, delta, self.len, self.size, &inside);
        // a start outside the region (a hop from its boundary) that did not move in
        match self.exact(&local.axis.dir).filter(|_| inside(&local.axis.dir)) {
            Some((v, ax)) => (v, ax, local.steps + 1),
            None => (f64::INFINITY, local.axis, local.steps + 1),
        }
    }
}

/// The projection-model fit of all given points within `region`.
pub(super) fn fit_direct(
    pts: &[f64],
    crit: Criterion,
    opts: &Options,
    lsq_axis: Option<Vector3<f64>>,
    region: &Region,
) -> Result<CylinderFit> {
    // centred copy: the projection and the 2-D kernels then work near the origin
    let c = centroid(pts, 3);
    let q: Vec<f64> = pts.chunks_exact(3).flat_map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]]).collect();
    let size = q.chunks_exact(3).map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()).fold(0.0, f64::max);
    let len_axis = lsq_axis.unwrap_or(region.basis.2);
    let len = q.chunks_exact(3).map(|p| Vector3::new(p[0], p[1], p[2]).dot(&len_axis).abs()).fold(1e-3 * size, f64::max);
    let pb = Problem { q, centroid: c, crit, size, len, region };
    if region.s_max == 0.0 {
        return fixed(&pb, pts, &region.basis.2);
    }
    let swarm = swarm(&pb, opts, lsq_axis)?;
    let mut evaluations = swarm.evaluations;
    let mut starts = refine_starts(&pb, &swarm, opts.refine_starts);
    starts.extend(grid_starts(region));
    let first = region.dir(swarm.position[0], swarm.position[1]);
    let mut best = match pb.exact(&first) {
        Some(found) => found,
        None => (f64::INFINITY, slp::Axis::new(first, Vector3::zeros())),
    };
    evaluations += 1;
    evaluations += refine(&pb, &starts, &mut best);
    evaluations += hop(&pb, opts.hop_rounds, &mut best);
    evaluations += along_boundary(&pb, &mut best);
    // MIC of a partial arc: where the inscribed circle touches the circumscribed
    // one (Sec. 6.2.2, Cases I and II), the SLP model (the points only) is not the
    // objective; search the exact values directly
    if crit == Criterion::MaxInscribed && fit2d(&pb.q, &best.1.dir, crit).is_ok_and(|(_, _, z)| z.control_in.len() < 3) {
        let inside = |a: &Vector3<f64>| region.contains(a);
        let (value, a, evals) = nelder_mead_search(&pb.q, size, &starts, (best.0, best.1.dir), opts.hop_rounds, &inside);
        evaluations += evals;
        if value < best.0 {
            best = (value, slp::Axis::new(a, Vector3::zeros()));
        }
    }
    if region.exhaustive {
        evaluations += half_sphere_search(&pb, opts.hop_rounds, &mut best);
    }
    let mut r = result(&pb, pts, &best.1.dir)?;
    r.iterations = swarm.iterations;
    r.evaluations = evaluations;
    Ok(r)
}

/// The warm-started fit of all given points within `region` (see [`super::fit_near`]):
/// the exact 2-D fit along the warm axis's direction and the SLP local search from it,
/// on these points (no basin hopping: see [`super::fit_near`]). `None` when the local method
/// cannot decide the result alone: its axis on the region's boundary (the global search
/// walks the boundary ring), a search that hit its step limit, a maximum inscribed
/// cylinder held by fewer than 3 points (a partial arc: the exact values need the
/// Nelder-Mead search), or no finite value.
pub(super) fn fit_warm(
    pts: &[f64],
    crit: Criterion,
    warm: &slp::Axis,
    region: &Region,
) -> Result<Option<CylinderFit>> {
    let c = centroid(pts, 3);
    let q: Vec<f64> = pts.chunks_exact(3).flat_map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]]).collect();
    let size = q.chunks_exact(3).map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()).fold(0.0, f64::max);
    let len = q.chunks_exact(3).map(|p| Vector3::new(p[0], p[1], p[2]).dot(&warm.dir).abs()).fold(1e-3 * size, f64::max);
    let pb = Problem { q, centroid: c, crit, size, len, region };
    if region.s_max == 0.0 {
        return fixed(&pb, pts, &region.basis.2).map(Some);
    }
    if !region.contains(&warm.dir) {
        return Ok(None);
    }
    let Some(mut best) = pb.exact(&warm.dir) else { return Ok(None) };
    let mut evaluations = 1;
    let (value, ax, steps) = pb.local(best.1, START_STEP * pb.len);
    evaluations += steps;
    if steps > slp::MAX_STEPS {
        return Ok(None);
    }
    if value < best.0 {
        best = (value, ax);
    }
    let on_boundary = region.s_max < FRAC_PI_2 && tilt_from(&best.1.dir, &region.basis.2) >= region.s_max - 1e-9;
    if !best.0.is_finite() || on_boundary {
        return Ok(None);
    }
    if crit == Criterion::MaxInscribed && fit2d(&pb.q, &best.1.dir, crit).is_ok_and(|(_, _, z)| z.control_in.len() < 3) {
        return Ok(None);
    }
    let mut r = result(&pb, pts, &best.1.dir)?;
    r.evaluations = evaluations;
    Ok(Some(r))
}

/// A fixed direction (`max_tilt` 0): the exact 2-D fit along it.
fn fixed(pb: &Problem<'_>, pts: &[f64], a: &Vector3<f64>) -> Result<CylinderFit> {
    let (_, _, zone) = fit2d(&pb.q, a, pb.crit)?;
    if !zone_value(&zone, pb.crit, pb.size).is_finite() {
        return Err(GkError::degenerate(
            "cylinder: the projection along the given axis does not determine a circle",
        ));
    }
    let mut r = result(pb, pts, a)?;
    r.evaluations = 1;
    Ok(r)
}

/// The seeded swarm over the region, on the exact 2-D values (its particles jump too
/// far for warm starts); the least-squares axis joins it as the first particle.
fn swarm(pb: &Problem<'_>, opts: &Options, lsq_axis: Option<Vector3<f64>>) -> Result<Outcome> {
    let (basis, s_max) = (&pb.region.basis, pb.region.s_max);
    // the swarm stops after `stall_iterations` without a gain of 1e-10 of the part's size
    let settings = Settings {
        particles: opts.particles,
        max_iterations: opts.max_iterations,
        stall_iterations: opts.stall_iterations,
        seed: opts.seed,
        tolerance: 1e-10 * pb.size,
        ..Settings::default()
    };
    let mut seeds = Vec::new();
    if let Some(a) = lsq_axis {
        let a = if a.dot(&basis.2) < 0.0 { -a } else { a };
        let s = a.dot(&basis.2).clamp(-1.0, 1.0).acos();
        if s <= s_max {
            seeds.push(vec![s, a.dot(&basis.1).atan2(a.dot(&basis.0))]);
        }
    }
    let swarm = minimize_from(
        |x: &[f64]| objective(&pb.q, &pb.region.dir(x[0], x[1]), pb.crit, pb.size),
        &[0.0, -PI],
        &[s_max, PI],
        &settings,
        &seeds,
    )?;
    if !swarm.value.is_finite() {
        return Err(GkError::degenerate(
            "cylinder: the points do not determine a cylinder (every projection is degenerate)",
        ));
    }
    Ok(swarm)
}

/// The swarm's best distinct particles (at most `count`), best first.
fn refine_starts(pb: &Problem<'_>, swarm: &Outcome, count: usize) -> Vec<Vector3<f64>> {
    let mut cands: Vec<(f64, Vector3<f64>)> = swarm
        .personal_best
        .iter()
        .filter(|(_, v)| v.is_finite())
        .map(|(x, v)| (*v, pb.region.dir(x[0], x[1])))
        .collect();
    cands.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut starts: Vec<Vector3<f64>> = Vec::new();
    for (_, a) in cands {
        if starts.len() >= count.max(1) {
            break;
        }
        if starts.iter().all(|b| a.cross(b).norm() > 1e-6) {
            starts.push(a);
        }
    }
    starts
}

/// Rings of the cone (not for the half sphere) at 1/3, 2/3 and 3/3 of its half angle
/// with 6, 12, 18 directions, and its axis: deterministic starts for the local
/// searches, so that the best of several local minima in the cone does not hang on the
/// swarm's seed.
fn grid_starts(region: &Region) -> Vec<Vector3<f64>> {
    if region.s_max >= FRAC_PI_2 || region.s_max == 0.0 {
        return Vec::new();
    }
    let mut out = vec![region.basis.2];
    for ring in 1..=GRID_RINGS {
        let s = region.s_max * ring as f64 / GRID_RINGS as f64;
        for k in 0..6 * ring {
            out.push(region.dir(s, 2.0 * PI * k as f64 / (6 * ring) as f64));
        }
    }
    out
}

/// When the best axis lies on the boundary of a cone, the constrained optimum is on
/// the boundary ring: Nelder–Mead in the ring's angle from the best axis and from the
/// outer grid ring's directions (deterministic, so the optimum does not hang on the
/// swarm's seed). Returns the evaluations spent.
fn along_boundary(pb: &Problem<'_>, best: &mut (f64, slp::Axis)) -> usize {
    let region = pb.region;
    let (basis, s_max) = (&region.basis, region.s_max);
    if s_max >= FRAC_PI_2 || s_max == 0.0 || tilt_from(&best.1.dir, &basis.2) < s_max - 1e-9 {
        return 0;
    }
    let d = if best.1.dir.dot(&basis.2) < 0.0 { -best.1.dir } else { best.1.dir };
    let g0 = d.dot(&basis.1).atan2(d.dot(&basis.0));
    let ring = 6 * GRID_RINGS;
    let starts: Vec<f64> =
        std::iter::once(g0).chain((0..ring).map(|k| 2.0 * PI * k as f64 / ring as f64)).collect();
    let found: Vec<(f64, f64, usize)> = starts
        .par_iter()
        .map(|&g| {
            let nm = nelder_mead(|x: &[f64]| objective(&pb.q, &region.dir(s_max, x[0]), pb.crit, pb.size), &[g], PI / ring as f64, 1e-12);
            (nm.value, nm.position[0], nm.evaluations)
        })
        .collect();
    let mut evaluations = 0;
    for (value, g, evals) in found {
        evaluations += evals;
        if value < best.0 {
            if let Some(found) = pb.exact(&region.dir(s_max, g)) {
                *best = found;
            }
        }
    }
    evaluations
}

/// The angle (rad, [0, pi/2]) between the axes of unit vectors `a` and `w` (a and -a
/// alike). Clamped: an axis on the cone's own axis can give |a . w| = 1 + 1 ulp, whose
/// acos is NaN, and a NaN tilt counted as "on the boundary" (the boundary walk then ran
/// for seconds on the bracket's bore, whose least-squares axis is its exact axis).
pub(super) fn tilt_from(a: &Vector3<f64>, w: &Vector3<f64>) -> f64 {
    a.dot(w).abs().min(1.0).acos()
}

/// Rings of the exhaustive grid over the half sphere ([`half_sphere_search`]).
const HALF_SPHERE_RINGS: usize = 12;
/// Local searches started from the best directions of that grid.
const HALF_SPHERE_STARTS: usize = 12;

/// The free search (`max_tilt` 90, the whole half sphere; issue 12: a 120-degree arc's
/// MCC hung on the swarm's seed): the exact objective on a deterministic grid of
/// directions (rings every 7.5 degrees of tilt, 6 k directions on ring k), local
/// searches and basin hopping from its best distinct directions, all independent of the
/// seed. The seeded swarm's optimum (`best`) is kept only when it is lower by more than
/// 1e-9 of the part's size, so that a seed can only improve a result, not perturb it at
/// the rounding level. Returns the evaluations spent.
fn half_sphere_search(pb: &Problem<'_>, rounds: usize, best: &mut (f64, slp::Axis)) -> usize {
    let region = pb.region;
    let mut grid = vec![region.basis.2];
    for ring in 1..=HALF_SPHERE_RINGS {
        let s = region.s_max * ring as f64 / HALF_SPHERE_RINGS as f64;
        for k in 0..6 * ring {
            grid.push(region.dir(s, 2.0 * PI * k as f64 / (6 * ring) as f64));
        }
    }
    let values: Vec<f64> = grid.par_iter().map(|a| objective(&pb.q, a, pb.crit, pb.size)).collect();
    let mut order: Vec<usize> = (0..grid.len()).filter(|&i| values[i].is_finite()).collect();
    order.sort_by(|&i, &j| values[i].total_cmp(&values[j]).then(i.cmp(&j)));
    // distinct: at least one grid step (7.5 degrees) apart, as axes (a and -a alike)
    let step = (region.s_max / HALF_SPHERE_RINGS as f64).cos();
    let mut starts: Vec<Vector3<f64>> = Vec::new();
    for i in order {
        if starts.len() >= HALF_SPHERE_STARTS {
            break;
        }
        if starts.iter().all(|b| grid[i].dot(b).abs() < step) {
            starts.push(grid[i]);
        }
    }
    let mut evaluations = grid.len();
    let Some(&first) = starts.first() else { return evaluations };
    let mut det = match pb.exact(&first) {
        Some(found) => found,
        None => (f64::INFINITY, slp::Axis::new(first, Vector3::zeros())),
    };
    evaluations += refine(pb, &starts, &mut det);
    evaluations += hop(pb, rounds, &mut det);
    if pb.crit == Criterion::MaxInscribed && fit2d(&pb.q, &det.1.dir, pb.crit).is_ok_and(|(_, _, z)| z.control_in.len() < 3) {
        // as in fit_direct: a partial arc's MIC, searched on the exact values
        let inside = |a: &Vector3<f64>| region.contains(a);
        let (value, a, evals) = nelder_mead_search(&pb.q, pb.size, &starts, (det.0, det.1.dir), rounds, &inside);
        evaluations += evals;
        if value < det.0 {
            det = (value, slp::Axis::new(a, Vector3::zeros()));
        }
    }
    if !(best.0 < det.0 - 1e-9 * pb.size) {
        *best = det;
    }
    evaluations
}

/// Rings of deterministic starts in a cone (see [`grid_starts`]).
const GRID_RINGS: usize = 3;

/// SLP local searches from `starts`, in parallel; each is deterministic and the best
/// is taken in start order, so the thread count never changes the result. Each starts
/// at the axis of the projection's circumscribed circle (a cheap fit near the centre of
/// every criterion's circles). Returns the evaluations spent.
fn refine(pb: &Problem<'_>, starts: &[Vector3<f64>], best: &mut (f64, slp::Axis)) -> usize {
    let mc_axis = |a: &Vector3<f64>| -> Option<slp::Axis> {
        let (theta, phi, zone) = fit2d(&pb.q, a, Criterion::MinCircumscribed).ok()?;
        Some(slp::Axis::new(*a, in_space(theta, phi, zone.center)))
    };
    let refined: Vec<(f64, slp::Axis, usize)> = starts
        .par_iter()
        .map(|a0| match mc_axis(a0) {
            Some(ax) => {
                let (v, ax, e) = pb.local(ax, START_STEP * pb.len);
                (v, ax, e + 1)
            }
            None => (f64::INFINITY, slp::Axis::new(*a0, Vector3::zeros()), 1),
        })
        .collect();
    let mut evaluations = 0;
    for (value, ax, evals) in refined {
        evaluations += evals;
        if value < best.0 {
            *best = (value, ax);
        }
    }
    evaluations
}

/// Basin hopping: minimax landscapes have long narrow valleys holding several local
/// minima some 1e-5 rad apart (set 3: two minima 4.6e-5 rad and 6e-9 mm apart);
/// restart the search from HOPS axes tilted HOP_RADIUS about the best, for at most
/// `rounds` rounds while that finds a lower basin. Returns the evaluations spent.
fn hop(pb: &Problem<'_>, rounds: usize, best: &mut (f64, slp::Axis)) -> usize {
    let mut evaluations = 0;
    for _ in 0..rounds {
        let (u, v) = orthonormal_basis(&best.1.dir);
        let a0 = best.1;
        let hops: Vec<(f64, slp::Axis, usize)> = (0..HOPS)
            .into_par_iter()
            .map(|k| {
                let th = 0.3 + 2.0 * PI * k as f64 / HOPS as f64;
                let dir = a0.dir + (u * th.cos() + v * th.sin()) * HOP_RADIUS;
                pb.local(slp::Axis::new(dir, a0.point), HOP_RADIUS * pb.len)
            })
            .collect();
        let before = best.0;
        for (value, ax, evals) in hops {
            evaluations += evals;
            if value < best.0 {
                *best = (value, ax);
            }
        }
        if best.0 >= before - 1e-9 * before.abs() {
            break; // no new basin (gains at rounding level do not count)
        }
    }
    evaluations
}

/// The reported cylinder: the exact 2-D fit along `a`, mapped back to 3-D, with its
/// certificate recomputed on `pts`.
fn result(pb: &Problem<'_>, pts: &[f64], a: &Vector3<f64>) -> Result<CylinderFit> {
    let (theta, phi, zone) = fit2d(&pb.q, a, pb.crit)?;
    let dir = axis(theta, phi);
    let (u, v) = frame(theta, phi);
    let c = &pb.centroid;
    let point = [
        c[0] + u[0] * zone.center[0] + v[0] * zone.center[1],
        c[1] + u[1] * zone.center[0] + v[1] * zone.center[1],
        c[2] + u[2] * zone.center[0] + v[2] * zone.center[1],
    ];
    let extent = lsq::axis_extent(pts, &point, &dir);
    Ok(CylinderFit {
        criterion: pb.crit,
        point,
        direction: dir,
        theta,
        phi,
        radius: 0.5 * (zone.r_in + zone.r_out),
        r_in: zone.r_in,
        r_out: zone.r_out,
        control_in: zone.control_in,
        control_out: zone.control_out,
        extent,
        iterations: 0,
        evaluations: 0,
        reference: dir,
        tilt: 0.0,
        outside: None,
        at_limit: false,
        arc: 0.0,
        ill_posed: false,
        lsq_axis: None,
    })
}
