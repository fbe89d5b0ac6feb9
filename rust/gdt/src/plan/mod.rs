//! A whole inspection compiled into a plan, evaluated on many simulated measurements in one
//! call (issue 26: the Monte Carlo uncertainty of every callout, JCGM 101:2008).
//!
//! `gagekit.uncertainty.plan` compiles a drawing (features, datums, callouts) once; a
//! trial is then one pass of [`evaluate`] over a perturbed copy of the active points (the
//! union of the feature regions, [`perturb::perturb`]; [`run`] draws them straight into
//! each feature's buffer, [`perturb::perturb_features`]: the same values, no copy of the
//! active set), and [`run`] evaluates a block of
//! trials in parallel (rayon), trial `i` seeded by (seed, i) alone, so any thread count
//! gives the same values. Each step is the kernel the Python evaluation
//! (`gagekit.inspect.zones`, `gagekit.inspect.datums`) calls, with the same inputs, started
//! from the measured evaluation as there: minimax cylinders by the exact local method from
//! the measured axis (`gagekit_form::cylinder::fit_near_zone`), least-squares cylinders from
//! the measured direction, the flatness slab, the minimum-zone sphere and each roundness
//! section's zone on active sets verified on every point ([`active`]).
//!
//! Supported (the compiler falls back to the Python evaluation otherwise): planes, lines,
//! circles, spheres and cylinders with the least-squares derived axis; Chebyshev datum
//! planes and axes (ISO 5459) behind planes and axes; flatness, straightness of a line in
//! the plane of its outward normal, roundness (no filter), cylindricity, sphericity,
//! parallelism, perpendicularity, angularity, position (in a datum frame), coaxiality,
//! profile of a plane, circular and total run-out; no material modifiers.

pub mod active;
mod frame;
pub mod perturb;
pub mod sparse;
#[cfg(test)]
mod tests;
mod ziggurat;

use crate::datum::{self, AxisFit, Orientation, PlaneFit};
use crate::turn::{self, Frame};
use crate::vec3::{self, basis, cross, dot, norm, scale, sub, V3};
use crate::width2;
use gagekit_core::{GkError, Result};
use gagekit_form::cylinder::{self, Criterion, CylinderFit, Options, Search, Warm};
use gagekit_form::{lsq, sphere};
use rayon::prelude::*;

pub use frame::build_frame;

/// A feature's shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    Plane,
    Line,
    Circle,
    Sphere,
    Cylinder,
}

/// A feature: its rows in the active points and what its evaluation needs.
#[derive(Debug, Clone)]
pub struct Feature {
    pub shape: Shape,
    pub rows: Vec<usize>,
    /// Out of the material (planes; a line's surface normal).
    pub outward: Option<V3>,
    /// The direction that signs an axis (the feature's `direction`, else its box's z).
    pub sign_hint: V3,
    /// The region box's axes (rows): a free turn's x.
    pub box_axes: [V3; 3],
    /// A hole (a datum axis is its maximum inscribed cylinder), else a shaft.
    pub hole: bool,
    /// The measured least-squares cylinder or sphere (the trial's start).
    pub warm_lsq: Option<LsqStart>,
    /// The measured minimax cylinders' axes (point, direction): minimum zone,
    /// min-circumscribed, max-inscribed.
    pub warm_cylinder: [Option<(V3, V3)>; 3],
    /// The measured flatness zone's normal.
    pub warm_slab: Option<V3>,
    /// The measured minimum-zone sphere's centre.
    pub warm_sphere: Option<V3>,
}

/// The measured least-squares fit a trial's fit starts from (`lsq::cylinder_warm`,
/// `lsq::sphere_warm`: Gauss-Newton to a stated step tolerance, the complete fit where it
/// cannot converge).
#[derive(Debug, Clone, PartialEq)]
pub enum LsqStart {
    Cylinder(lsq::Cylinder),
    Sphere { center: V3, radius: f64 },
}

/// A datum simulated behind the datums `prior` (indices of earlier entries, in the
/// order of the feature control frame) at the basic `angle` (degrees) to them.
#[derive(Debug, Clone)]
pub struct Datum {
    pub feature: usize,
    pub prior: Vec<usize>,
    pub angle: f64,
}

/// A characteristic (ISO 1101).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Characteristic {
    Flatness,
    Straightness,
    Roundness,
    Cylindricity,
    Sphericity,
    Parallelism,
    Perpendicularity,
    Angularity,
    Position,
    Coaxiality,
    Profile,
    CircularRunout,
    TotalRunout,
}

/// A callout: `datums` are the indices of the datum entries of each prefix of its datum
/// letters, `frame` the index of its datum frame (location callouts).
#[derive(Debug, Clone)]
pub struct Callout {
    pub characteristic: Characteristic,
    pub feature: usize,
    pub tolerance: f64,
    pub datums: Vec<usize>,
    pub frame: Option<usize>,
    pub angle: f64,
    pub sections: usize,
    pub nominal_point: Option<V3>,
    pub nominal_direction: Option<V3>,
}

/// The compiled inspection: `frames` lists the datum entries of each frame's letters.
#[derive(Debug, Clone)]
pub struct Plan {
    pub features: Vec<Feature>,
    pub datums: Vec<Datum>,
    pub frames: Vec<Vec<usize>>,
    pub callouts: Vec<Callout>,
}

impl Plan {
    /// Check the plan against the active points (flat (n, 3), finite): every row, datum,
    /// frame and callout index in range, every datum behind earlier ones only.
    pub fn check(&self, pts: &[f64]) -> Result<()> {
        gagekit_core::check_finite(pts, 3, "active points")?;
        let n = pts.len() / 3;
        let bad = |what: &str| Err(GkError::invalid(format!("inspection plan: {what} out of range")));
        for f in &self.features {
            if f.rows.iter().any(|&i| i >= n) {
                return bad("a feature's point row");
            }
            if f.rows.is_empty() {
                return Err(GkError::degenerate("inspection plan: a feature without points"));
            }
        }
        for (k, d) in self.datums.iter().enumerate() {
            if d.feature >= self.features.len() || d.prior.iter().any(|&j| j >= k) {
                return bad("a datum's feature or prior datum");
            }
        }
        if self.frames.iter().any(|f| f.is_empty() || f.iter().any(|&k| k >= self.datums.len())) {
            return bad("a frame's datum");
        }
        for c in &self.callouts {
            if c.feature >= self.features.len()
                || c.datums.iter().any(|&k| k >= self.datums.len())
                || c.frame.is_some_and(|k| k >= self.frames.len())
                || c.sections == 0
            {
                return bad("a callout's feature, datum, frame or section count");
            }
            use Characteristic as C;
            let needs_datum = matches!(
                c.characteristic,
                C::Parallelism | C::Perpendicularity | C::Angularity | C::Coaxiality | C::CircularRunout | C::TotalRunout
            );
            if (needs_datum && c.datums.is_empty()) || (c.characteristic == C::Position && c.frame.is_none()) {
                return Err(GkError::config("inspection plan: an orientation, location or run-out callout needs its datums"));
            }
        }
        Ok(())
    }
}

/// A simulated datum: a plane (`vector` out of the material) or an axis.
#[derive(Debug, Clone, Copy)]
pub struct Simulated {
    pub plane: bool,
    pub point: V3,
    pub vector: V3,
    pub feature: usize,
}

/// The measured values of a trial: (measured, margin) of each callout in order, and
/// (warm-started minimax cylinder fits, of them fallbacks to the global search).
#[derive(Debug, Clone, PartialEq)]
pub struct Values {
    pub values: Vec<f64>,
    pub warm_fits: usize,
    pub fallbacks: usize,
}

enum Lsq {
    Plane { normal: V3 },
    Line { point: V3, direction: V3 },
    Circle { center: V3, normal: V3 },
    Sphere { center: V3 },
    Cylinder { point: V3, direction: V3 },
}

fn v3(v: &[f64]) -> V3 {
    [v[0], v[1], v[2]]
}

fn unit(v: V3) -> V3 {
    scale(v, 1.0 / norm(v))
}

fn sign(x: f64) -> f64 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// The trial's state of a feature: its points and the fits computed once.
struct Feat<'a> {
    spec: &'a Feature,
    pts: Vec<f64>,
    lsq: Option<Lsq>,
    mz: Option<(f64, V3)>,
    cyl: [Option<CylinderFit>; 3],
    axis_pts: Option<Vec<f64>>,
    /// Only the points of some blocks are here ([`sparse`]): every result that reads the
    /// points is a zone recorded in `zones`, and a result that needs every point (a
    /// least-squares fit) is refused (the trial then runs on every point).
    sparse: bool,
    /// The zones (normal, lo, hi: lo <= normal . p <= hi) of the results computed on the
    /// points, which the points not here must lie in ([`sparse`]).
    zones: Vec<(V3, f64, f64)>,
}

impl<'a> Feat<'a> {
    fn new(spec: &'a Feature, pts: Vec<f64>, sparse: bool) -> Self {
        Feat { spec, pts, lsq: None, mz: None, cyl: [None, None, None], axis_pts: None, sparse, zones: Vec::new() }
    }

    fn lsq(&mut self) -> Result<&Lsq> {
        if self.sparse {
            return Err(GkError::numerical(sparse::NEEDS_ALL));
        }
        if self.lsq.is_none() {
            let p = &self.pts;
            self.lsq = Some(match self.spec.shape {
                Shape::Plane => Lsq::Plane { normal: lsq::plane(p)?.normal },
                Shape::Line => {
                    let l = lsq::line(p, 3)?;
                    Lsq::Line { point: v3(&l.point), direction: v3(&l.direction) }
                }
                Shape::Circle => {
                    let c = lsq::circle3(p)?;
                    Lsq::Circle { center: c.center, normal: c.normal }
                }
                Shape::Sphere => {
                    let s = match &self.spec.warm_lsq {
                        Some(LsqStart::Sphere { center, radius }) => lsq::sphere_warm(p, *center, *radius)?,
                        _ => lsq::sphere(p, 3)?,
                    };
                    Lsq::Sphere { center: v3(&s.center) }
                }
                Shape::Cylinder => {
                    // the axis alone (the complete fit's extent and arc are not needed),
                    // by Gauss-Newton from the measured fit
                    let c = match &self.spec.warm_lsq {
                        Some(LsqStart::Cylinder(m)) => lsq::cylinder_warm(p, m)?,
                        _ => lsq::cylinder(p, None)?,
                    };
                    Lsq::Cylinder { point: c.point, direction: c.direction }
                }
            });
        }
        Ok(self.lsq.as_ref().unwrap())
    }

    /// (point, unit direction) of the least-squares axis, signed by the sign hint.
    fn axis_line(&mut self) -> Result<(V3, V3)> {
        let hint = self.spec.sign_hint;
        let (p, d) = match self.lsq()? {
            Lsq::Cylinder { point, direction } | Lsq::Line { point, direction } => (*point, unit(*direction)),
            Lsq::Circle { center, normal } => (*center, unit(*normal)),
            _ => return Err(GkError::degenerate("the feature has no axis")),
        };
        Ok(if dot(d, hint) < 0.0 { (p, scale(d, -1.0)) } else { (p, d) })
    }

    /// The reference axis of the feature's minimax cylinders (the axis of their search
    /// cone, and what signs a datum axis): the measured least-squares axis, signed by the
    /// sign hint as [`Feat::axis_line`] signs the trial's. A trial's least-squares axis
    /// lies within a few noise sigmas / sqrt(n) of it (microradians) against a cone of 10
    /// degrees, so the warm fit ([`cylinder::fit_near_zone`]) reads the same answer from
    /// either (the cone only decides a fallback, when the axis ends on its boundary), and a
    /// feature read by no callout but its datum's (the bracket's boss, datum D) needs no
    /// least-squares fit of its own in a trial: one Gauss-Newton fit of 202 k points less
    /// a trial at 2 M points. Without a measured fit: the trial's.
    fn reference_axis(&mut self) -> Result<V3> {
        if let Some(LsqStart::Cylinder(m)) = &self.spec.warm_lsq {
            let d = unit(m.direction);
            if d.iter().all(|x| x.is_finite()) {
                return Ok(if dot(d, self.spec.sign_hint) < 0.0 { scale(d, -1.0) } else { d });
            }
        }
        Ok(self.axis_line()?.1)
    }

    fn center(&mut self) -> Result<V3> {
        match self.lsq()? {
            Lsq::Sphere { center } | Lsq::Circle { center, .. } => Ok(*center),
            _ => Err(GkError::degenerate("the feature has no centre")),
        }
    }

    fn plane_normal_out(&mut self) -> Result<V3> {
        let out = self.spec.outward.unwrap_or([0.0, 0.0, 1.0]);
        match self.lsq()? {
            Lsq::Plane { normal } => {
                let n = unit(*normal);
                Ok(if dot(n, out) >= 0.0 { n } else { scale(n, -1.0) })
            }
            _ => Err(GkError::degenerate("the feature is no plane")),
        }
    }

    /// (width, normal) of the flatness zone, the normal into the material.
    fn min_zone(&mut self) -> Result<(f64, V3)> {
        if self.mz.is_none() {
            let s = match self.spec.warm_slab {
                Some(n) => active::slab_near(&self.pts, n)?,
                None => datum::slab(&self.pts, Orientation::Free)?,
            };
            self.zones.push((s.normal, s.lo, s.hi));
            let mut n = s.normal;
            if let Some(o) = self.spec.outward {
                if dot(n, o) > 0.0 {
                    n = scale(n, -1.0);
                }
            }
            self.mz = Some((s.width, n));
        }
        Ok(self.mz.unwrap())
    }

    fn chebyshev(&mut self, crit: Criterion, counts: &mut (usize, usize)) -> Result<&CylinderFit> {
        let k = match crit {
            Criterion::MinZone => 0,
            Criterion::MinCircumscribed => 1,
            Criterion::MaxInscribed => 2,
        };
        if self.cyl[k].is_none() {
            let d = self.reference_axis()?;
            let opts = Options { search: Search { axis: Some(d), max_tilt: 10f64.to_radians() }, ..Options::default() };
            let fit = match self.spec.warm_cylinder[k] {
                Some((point, direction)) => {
                    let (f, fell) = cylinder::fit_near_zone(&self.pts, crit, &opts, &Warm { point, direction })?;
                    counts.0 += 1;
                    counts.1 += fell as usize;
                    f
                }
                None => cylinder::fit(&self.pts, crit, &opts)?,
            };
            self.cyl[k] = Some(fit);
        }
        Ok(self.cyl[k].as_ref().unwrap())
    }

    /// The derived axis as points: a circle's centre, else the two ends of the
    /// least-squares axis limited to the span of the points (flat (m, 3)).
    fn axis_points(&mut self) -> Result<Vec<f64>> {
        if self.axis_pts.is_none() {
            let (p0, d) = self.axis_line()?;
            let v = if self.spec.shape == Shape::Circle {
                p0.to_vec()
            } else {
                let (lo, hi) = self.heights(p0, d);
                [vec3::add(p0, scale(d, lo)), vec3::add(p0, scale(d, hi))].concat()
            };
            self.axis_pts = Some(v);
        }
        Ok(self.axis_pts.clone().unwrap())
    }

    fn heights(&self, p0: V3, d: V3) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for p in self.pts.chunks_exact(3) {
            let t = dot(sub(v3(p), p0), d);
            lo = lo.min(t);
            hi = hi.max(t);
        }
        (lo, hi)
    }

    /// The element of an orientation or location callout: the surface of a plane, else
    /// the derived axis.
    fn element(&mut self) -> Result<Vec<f64>> {
        if self.spec.shape == Shape::Plane {
            Ok(self.pts.clone())
        } else {
            self.axis_points()
        }
    }
}

/// Indices of the values in `key` falling in `count` equal slices of their span (empty
/// slices skipped; a zero span: one slice), each slice in input order.
fn slices(key: &[f64], count: usize) -> Vec<Vec<usize>> {
    let lo = key.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = key.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    if hi <= lo {
        return vec![(0..key.len()).collect()];
    }
    // each value's slice, then every slice allocated at its size and filled in input order
    let which: Vec<usize> = key.iter().map(|&t| (((t - lo) / (hi - lo) * count as f64) as usize).min(count - 1)).collect();
    let mut sizes = vec![0usize; count];
    for &k in &which {
        sizes[k] += 1;
    }
    let mut out: Vec<Vec<usize>> = sizes.iter().map(|&m| Vec::with_capacity(m)).collect();
    for (i, &k) in which.iter().enumerate() {
        out[k].push(i);
    }
    out.into_iter().filter(|s| !s.is_empty()).collect()
}

fn plane_2d(pts: &[f64], idx: &[usize], origin: V3, u: V3, v: V3) -> Vec<f64> {
    let mut xy = Vec::with_capacity(2 * idx.len());
    for &i in idx {
        let q = sub(vec3::at(pts, i), origin);
        xy.push(dot(q, u));
        xy.push(dot(q, v));
    }
    xy
}

fn cylinder_zone(pts: &[f64], d: V3) -> Result<f64> {
    Ok(2.0 * datum::axis_along(pts, d, AxisFit::Circumscribed)?.radius)
}

fn slab_width(pts: &[f64], o: Orientation) -> Result<f64> {
    Ok(datum::slab(pts, o)?.width)
}

struct Trial<'a> {
    plan: &'a Plan,
    feats: Vec<Feat<'a>>,
    sims: Vec<Simulated>,
    frames: Vec<Frame>,
    counts: (usize, usize),
    reuse: Vec<Option<f64>>,
}

impl<'a> Trial<'a> {
    fn simulate(&mut self, k: usize) -> Result<Simulated> {
        let spec = &self.plan.datums[k];
        let prior: Vec<Simulated> = spec.prior.iter().map(|&j| self.sims[j]).collect();
        let fi = spec.feature;
        let counts = &mut self.counts;
        let f = &mut self.feats[fi];
        if f.spec.shape == Shape::Plane {
            let out = unit(f.spec.outward.ok_or_else(|| GkError::config("a datum plane needs 'outward'"))?);
            let orient = match prior.as_slice() {
                [] => Orientation::Fixed(f.min_zone()?.1),
                [a] if a.plane => {
                    if spec.angle == 90.0 {
                        Orientation::PerpendicularTo(a.vector)
                    } else {
                        // the least-squares normal only signs the datum's direction here
                        let n_ls = f.plane_normal_out()?;
                        Orientation::AtAngle(scale(a.vector, sign(dot(n_ls, a.vector))), spec.angle.to_radians())
                    }
                }
                [a] => Orientation::Fixed(a.vector),
                [a, b] if a.plane && b.plane => Orientation::Fixed(unit(cross(a.vector, b.vector))),
                [a, b] if a.plane || b.plane => Orientation::PerpendicularTo(a.vector),
                _ => return Err(GkError::config("a tertiary plane after two datum axes is not supported")),
            };
            let d = datum::plane(&f.pts, out, orient, PlaneFit::Chebyshev)?;
            f.zones.push((d.normal, d.offset - d.deviation, d.offset));
            return Ok(Simulated { plane: true, point: d.point, vector: d.normal, feature: fi });
        }
        let fit = if f.spec.hole { AxisFit::Inscribed } else { AxisFit::Circumscribed };
        if f.spec.shape == Shape::Cylinder && !prior.iter().any(|p| p.plane) {
            // a minimax cylinder, signed by its reference axis: no least-squares fit needed
            let d_ref = f.reference_axis()?;
            let crit = if f.spec.hole { Criterion::MaxInscribed } else { Criterion::MinCircumscribed };
            let cyl = f.chebyshev(crit, counts)?;
            let d = unit(cyl.direction);
            let d = if dot(d, d_ref) >= 0.0 { d } else { scale(d, -1.0) };
            return Ok(Simulated { plane: false, point: cyl.point, vector: d, feature: fi });
        }
        let (_, d_ls) = f.axis_line()?;
        if let Some(a) = prior.iter().find(|p| p.plane) {
            let d0 = if dot(a.vector, d_ls) >= 0.0 { a.vector } else { scale(a.vector, -1.0) };
            let ax = if spec.angle == 90.0 {
                datum::axis_along(&f.pts, d0, fit)?
            } else {
                turn::axis_on_cone(&f.pts, d0, (90.0 - spec.angle).to_radians(), d_ls, fit)?
            };
            return Ok(Simulated { plane: false, point: ax.point, vector: ax.direction, feature: fi });
        }
        if f.spec.shape == Shape::Circle {
            let ax = datum::axis_along(&f.pts, d_ls, fit)?;
            return Ok(Simulated { plane: false, point: ax.point, vector: ax.direction, feature: fi });
        }
        let crit = if f.spec.hole { Criterion::MaxInscribed } else { Criterion::MinCircumscribed };
        let cyl = f.chebyshev(crit, counts)?;
        let d = unit(cyl.direction);
        let d = if dot(d, d_ls) >= 0.0 { d } else { scale(d, -1.0) };
        Ok(Simulated { plane: false, point: cyl.point, vector: d, feature: fi })
    }

    fn callout(&mut self, c: &Callout) -> Result<f64> {
        use Characteristic as C;
        let sims: Vec<Simulated> = c.datums.iter().map(|&k| self.sims[k]).collect();
        let counts = &mut self.counts;
        let f = &mut self.feats[c.feature];
        Ok(match c.characteristic {
            C::Flatness => f.min_zone()?.0,
            C::Profile if c.frame.is_none() => f.min_zone()?.0,
            C::Straightness => {
                let (p0, d) = f.axis_line()?;
                let o = f.spec.outward.ok_or_else(|| GkError::config("straightness: the line needs 'outward'"))?;
                let w = unit(sub(o, scale(d, dot(o, d))));
                let idx: Vec<usize> = (0..f.pts.len() / 3).collect();
                width2::min_width(&plane_2d(&f.pts, &idx, p0, d, w))?.width
            }
            C::Roundness if f.spec.shape == Shape::Circle => {
                let (center, normal) = match f.lsq()? {
                    Lsq::Circle { center, normal } => (*center, unit(*normal)),
                    _ => unreachable!(),
                };
                let (u, v) = basis(normal);
                let idx: Vec<usize> = (0..f.pts.len() / 3).collect();
                // the zone on an active set from the least-squares centre, verified on every
                // point: the zone of circle::fit's minimum zone without its complete fit
                active::circle_zone_near(&plane_2d(&f.pts, &idx, center, u, v), [0.0, 0.0])?.form_error()
            }
            C::Roundness => {
                let (p0, d) = f.axis_line()?;
                let (u, v) = basis(d);
                let t: Vec<f64> = f.pts.chunks_exact(3).map(|p| dot(sub(v3(p), p0), d)).collect();
                let mut worst = 0.0f64;
                let mut used = 0;
                for idx in slices(&t, c.sections) {
                    if idx.len() < 3 {
                        continue;
                    }
                    // the section's zone from the trial's least-squares axis, (0, 0) in the
                    // section's plane (exact by verification: the start only chooses the first
                    // active set, the zone is that of every point of the section; a
                    // least-squares circle a section, as the Python evaluation starts from,
                    // cost about ten times the zone's CPU and gives the same zone to rounding)
                    let xy = plane_2d(&f.pts, &idx, p0, u, v);
                    worst = worst.max(active::circle_zone_near(&xy, [0.0, 0.0])?.form_error());
                    used += 1;
                }
                if used < 2 {
                    return Err(GkError::degenerate("fewer than 2 sections hold 3 points"));
                }
                worst
            }
            C::Cylindricity => {
                let z = f.chebyshev(Criterion::MinZone, counts)?;
                z.r_out - z.r_in
            }
            C::Sphericity => {
                let z = match f.spec.warm_sphere {
                    Some(c) => active::sphere_near(&f.pts, c)?,
                    None => sphere::min_zone(&f.pts)?,
                };
                z.r_out - z.r_in
            }
            C::Parallelism | C::Perpendicularity | C::Angularity => {
                let a = sims[0].vector;
                let plane_datum = sims[0].plane;
                let pts = f.element()?;
                let ch = c.characteristic;
                if f.spec.shape == Shape::Plane {
                    let o = match ch {
                        C::Parallelism if plane_datum => Orientation::Fixed(a),
                        C::Parallelism => Orientation::PerpendicularTo(a),
                        C::Perpendicularity if plane_datum && sims.len() > 1 && sims[1].plane => {
                            Orientation::Fixed(unit(cross(a, sims[1].vector)))
                        }
                        C::Perpendicularity if plane_datum => Orientation::PerpendicularTo(a),
                        C::Perpendicularity => Orientation::Fixed(a),
                        _ => {
                            let s = sign(dot(f.plane_normal_out()?, a));
                            let th = c.angle.to_radians();
                            Orientation::AtAngle(scale(a, s), if plane_datum { th } else { std::f64::consts::FRAC_PI_2 - th })
                        }
                    };
                    let s = datum::slab(&pts, o)?;
                    f.zones.push((s.normal, s.lo, s.hi));
                    s.width
                } else {
                    match ch {
                        C::Parallelism if plane_datum => slab_width(&pts, Orientation::Fixed(a))?,
                        C::Parallelism => cylinder_zone(&pts, a)?,
                        C::Perpendicularity if plane_datum => cylinder_zone(&pts, a)?,
                        C::Perpendicularity => slab_width(&pts, Orientation::Fixed(a))?,
                        _ => {
                            let th = c.angle.to_radians();
                            let (_, d_ls) = f.axis_line()?;
                            let s = sign(dot(d_ls, a));
                            let cone = if plane_datum { std::f64::consts::FRAC_PI_2 - th } else { th };
                            turn::cylinder_on_cone(&pts, scale(a, s), cone)?.0
                        }
                    }
                }
            }
            C::Position | C::Profile => {
                let frame = c.frame.map(|k| &self.frames[k]).ok_or_else(|| GkError::config("the callout needs a datum frame"))?;
                let to_scan = |p: V3| {
                    let mut o = frame.origin;
                    for k in 0..3 {
                        o = vec3::add(o, scale(frame.axes[k], p[k]));
                    }
                    o
                };
                let dir_scan = |d: V3| unit(sub(to_scan(d), frame.origin));
                let p0 = to_scan(c.nominal_point.ok_or_else(|| GkError::config("the callout needs a nominal point"))?);
                let nd = c.nominal_direction.map(dir_scan);
                match f.spec.shape {
                    Shape::Plane => {
                        let n0 = nd.ok_or_else(|| GkError::config("the callout needs a nominal direction"))?;
                        let w = turn::plane_location(&f.pts, frame, p0, n0)?.0;
                        if f.sparse {
                            // without a turn searched the zone is that of n0 . p (turn::plane_location)
                            let nz = dot(n0, frame.axes[2]);
                            if frame.free_rotation && nz.abs() < 1.0 - 1e-12 {
                                return Err(GkError::numerical(sparse::NEEDS_ALL));
                            }
                            let (lo, hi) = crate::width3::extent(&f.pts, n0);
                            f.zones.push((n0, lo, hi));
                        }
                        w
                    }
                    Shape::Sphere => 2.0 * turn::position(&f.center()?, frame, p0, None)?.0,
                    Shape::Circle => {
                        let d0 = match nd {
                            Some(d) => d,
                            None => match f.lsq()? {
                                Lsq::Circle { normal, .. } => unit(*normal),
                                _ => unreachable!(),
                            },
                        };
                        2.0 * turn::position(&f.center()?, frame, p0, Some(d0))?.0
                    }
                    _ => {
                        let d0 = nd.ok_or_else(|| GkError::config("the callout needs a nominal direction"))?;
                        2.0 * turn::position(&f.axis_points()?, frame, p0, Some(d0))?.0
                    }
                }
            }
            C::Coaxiality => {
                let d = sims[0];
                let pts = match f.spec.shape {
                    Shape::Circle | Shape::Sphere => f.center()?.to_vec(),
                    _ => f.axis_points()?,
                };
                let mut worst = 0.0f64;
                for p in pts.chunks_exact(3) {
                    let q = sub(v3(p), d.point);
                    worst = worst.max(norm(sub(q, scale(d.vector, dot(q, d.vector)))));
                }
                2.0 * worst
            }
            C::CircularRunout | C::TotalRunout => {
                let d = sims[0];
                let (o, a) = (d.point, d.vector);
                let mut dist = Vec::with_capacity(f.pts.len() / 3);
                let mut key = Vec::with_capacity(f.pts.len() / 3);
                for p in f.pts.chunks_exact(3) {
                    let q = sub(v3(p), o);
                    let t = dot(q, a);
                    let r = norm(sub(q, scale(a, t)));
                    if f.spec.shape == Shape::Plane {
                        dist.push(t);
                        key.push(r);
                    } else {
                        dist.push(r);
                        key.push(t);
                    }
                }
                let ptp = |v: &[f64]| {
                    v.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - v.iter().cloned().fold(f64::INFINITY, f64::min)
                };
                if c.characteristic == C::TotalRunout || f.spec.shape == Shape::Circle {
                    ptp(&dist)
                } else {
                    let mut worst = 0.0f64;
                    let mut used = 0;
                    for idx in slices(&key, c.sections) {
                        if idx.len() >= 2 {
                            let seg: Vec<f64> = idx.iter().map(|&i| dist[i]).collect();
                            worst = worst.max(ptp(&seg));
                            used += 1;
                        }
                    }
                    if used == 0 {
                        return Err(GkError::degenerate("no section holds 2 points"));
                    }
                    worst
                }
            }
        })
    }
}

/// Trial `trial`'s simulated measurement of the active points `pts` as [`run`] draws it:
/// by blocks ([`sparse`]) where it evaluates a trial that way, else [`perturb::perturb`].
pub fn simulate(plan: &Plan, pts: &[f64], model: &perturb::Model, seed: u64, trial: u64) -> Result<Vec<f64>> {
    plan.check(pts)?;
    match sparse::Layout::new(plan, pts) {
        Some(lay) if sparse::covers(model) => Ok(lay.simulate(pts, model.sigma, seed, trial)),
        _ => perturb::perturb(pts, 3, model, seed, trial),
    }
}

/// One trial: every callout's (measured, margin = tolerance - measured) of the active
/// points `pts` (flat (n, 3)).
pub fn evaluate(plan: &Plan, pts: &[f64]) -> Result<Values> {
    plan.check(pts)?;
    evaluate_checked(plan, gather(plan, pts))
}

/// Each feature's points gathered from the active points (flat (n, 3)).
fn gather(plan: &Plan, pts: &[f64]) -> Vec<Vec<f64>> {
    plan.features
        .iter()
        .map(|spec| {
            let mut p = Vec::with_capacity(3 * spec.rows.len());
            for &i in &spec.rows {
                p.extend_from_slice(&pts[3 * i..3 * i + 3]);
            }
            p
        })
        .collect()
}

/// One trial of the plan on each feature's points (`pts[k]`: feature `k`'s, flat (m, 3)).
fn evaluate_checked(plan: &Plan, pts: Vec<Vec<f64>>) -> Result<Values> {
    let feats = plan
        .features
        .iter()
        .zip(pts)
        .map(|(spec, p)| Feat::new(spec, p, false))
        .collect();
    evaluate_feats(plan, feats, Vec::new()).0
}

/// One trial of the plan on its features' states (kept by the caller between rounds of
/// [`sparse::trial`]): the values, and the states back.
/// `reuse[i]`: callout `i`'s value when already known (its inputs unchanged since).
fn evaluate_feats<'a>(plan: &'a Plan, feats: Vec<Feat<'a>>, reuse: Vec<Option<f64>>) -> (Result<Values>, Vec<Feat<'a>>) {
    let mut t = Trial { plan, feats, sims: Vec::with_capacity(plan.datums.len()), frames: Vec::new(), counts: (0, 0), reuse };
    let r = t.all();
    (r, t.feats)
}

impl Trial<'_> {
    fn all(&mut self) -> Result<Values> {
        let plan = self.plan;
        for k in 0..plan.datums.len() {
            let s = self.simulate(k)?;
            self.sims.push(s);
        }
        for letters in &plan.frames {
            let sims: Vec<Simulated> = letters.iter().map(|&k| self.sims[k]).collect();
            let box_axes = plan.features[sims[0].feature].box_axes;
            self.frames.push(build_frame(&sims, box_axes)?);
        }
        let mut values = Vec::with_capacity(2 * plan.callouts.len());
        for (i, c) in plan.callouts.iter().enumerate() {
            let m = match self.reuse.get(i).copied().flatten() {
                Some(m) => m,
                None => self.callout(c)?,
            };
            values.push(m);
            values.push(c.tolerance - m);
        }
        Ok(Values { values, warm_fits: self.counts.0, fallbacks: self.counts.1 })
    }
}

/// Trials `first .. first + count` of the simulation: each perturbs the active points by
/// `model` with the generator of (seed, trial) and evaluates the plan; in parallel, the
/// same values on any number of threads. Returns the values (row-major, trial by trial)
/// and the warm-start counts summed. A failing trial's error names it.
/// `threads` 0: rayon's global pool.
pub fn run(plan: &Plan, pts: &[f64], model: &perturb::Model, seed: u64, first: u64, count: usize, threads: usize) -> Result<Values> {
    run_with(plan, pts, model, seed, first, count, threads, false, &sparse::Cache::default())
}

/// [`run`]; `every_point`: the sparse features' trials evaluated on every point (the
/// reference the certified subsets of [`sparse`] equal; tests); `cache`: the blocks of
/// the last points run.
#[allow(clippy::too_many_arguments)]
pub fn run_with(
    plan: &Plan,
    pts: &[f64],
    model: &perturb::Model,
    seed: u64,
    first: u64,
    count: usize,
    threads: usize,
    every_point: bool,
    cache: &sparse::Cache,
) -> Result<Values> {
    plan.check(pts)?;
    let rows: Vec<&[usize]> = plan.features.iter().map(|f| f.rows.as_slice()).collect();
    let layout = if sparse::covers(model) { cache.layout(plan, pts) } else { None };
    let map = if layout.is_none() { Some(perturb::Scatter::new(pts.len() / 3, &rows)) } else { None };
    let trials = || -> Vec<Result<Values>> {
        (0..count as u64)
            .into_par_iter()
            .map(|k| {
                let trial = first + k;
                gagekit_core::interrupt::check()?;
                match (&layout, &map) {
                    (Some(lay), _) => sparse::trial(plan, pts, lay, model.sigma, seed, trial, every_point),
                    (None, Some(map)) => evaluate_checked(plan, perturb::perturb_features(pts, map, model, seed, trial)?),
                    (None, None) => unreachable!(),
                }
                .map_err(|e| GkError::new(e.kind, format!("Monte Carlo trial {trial} (a simulated measurement): {}", e.message)))
            })
            .collect()
    };
    let rows = if threads == 0 {
        trials()
    } else {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| GkError::numerical(format!("Monte Carlo: cannot start {threads} threads: {e}")))?
            .install(trials)
    };
    let mut out = Values { values: Vec::with_capacity(count * 2 * plan.callouts.len()), warm_fits: 0, fallbacks: 0 };
    for r in rows {
        let v = r?;
        out.values.extend(v.values);
        out.warm_fits += v.warm_fits;
        out.fallbacks += v.fallbacks;
    }
    Ok(out)
}
