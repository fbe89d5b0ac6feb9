//! Cylinders by the projection model (Sec. 6.3): minimum circumscribed (MCC,
//! Eq. 6.13), maximum inscribed (MIC, Eq. 6.15) and minimum zone (MZC, Eq. 6.14).
//!
//! An axis direction a = (sin t cos f, sin t sin f, cos t) (polar angle t,
//! azimuth f) projects the points onto the plane normal to it,
//! q = [I2 0] Ry(-t) Rz(-f) p (Eq. 6.12 as corrected in ERRATA item 1), and
//! the projected 2-D set is fitted exactly by the circle kernels
//! ([`crate::circle`]). The value of a direction is that exact 2-D fit's radius
//! (MCC, MIC) or width (MZC). The search over directions:
//!
//! 1. the seeded parallel PSO ([`gagekit_pso`]) over the directions within
//!    `max_tilt` of a reference axis (the least-squares axis, or a nominal axis),
//!    with the least-squares axis as one particle, on the exact 2-D values;
//! 2. local searches from the best distinct particles by sequential linear
//!    programming with a trust region (`slp`): the same minimax problem
//!    (Eqs. 6.13-6.15) written in the axis tilt, axis offset and radii, with the
//!    point-to-axis distances linearised by their analytic gradients; each step
//!    is a 5- or 6-variable LP (`lp`, a dense dual simplex), and the steps
//!    converge quadratically at the usual vertex solutions;
//! 3. basin hopping: the local search restarted from 8 axes tilted 1e-4 rad
//!    about the best while that finds a lower basin (minimax landscapes have long
//!    narrow valleys with several local minima some 1e-5 rad apart).
//!
//! Every local search's end direction is scored by the exact 2-D kernel, and the
//! reported cylinder is the exact 2-D fit along the best direction. One case keeps
//! the earlier Nelder–Mead search on the exact values (`nelder_mead_search`): the
//! MIC of a partial arc, whose inscribed circle touches the circumscribed one
//! (Sec. 6.2.2, Cases I and II), a constraint the SLP model of the points lacks.
//!
//! The search respects the feature (issue 13): a minimum circumscribed cylinder
//! of a short bore searched over the whole half sphere can lie across the bore.
//! Directions are searched within `max_tilt` (default 10 degrees) of the
//! reference axis; `max_tilt` 0 fixes the direction and pi/2 searches the whole
//! half sphere (Sec. 6.4). A restricted fit is compared with the free search:
//! a better optimum inside the cone replaces the result, one outside it is
//! reported in [`CylinderFit::outside`].
//!
//! Large inputs are fitted on an active subset (see [`fit`]). Every result carries
//! its certificate: min and max distance of the input points to the reported axis,
//! recomputed in 3-D.
//!
//! Modules: `projection` (Eq. 6.12 and the exact 2-D score of a direction),
//! `search` (swarm, SLP refinement and basin hopping in a region), `slp` (the
//! local SLP step), `mic_search` (Nelder–Mead for the MIC of partial arcs),
//! `subset` (active subsets of large inputs).

use crate::lsq::{self, Extent};
use gagekit_core::{check_finite, GkError, Result};
use nalgebra::Vector3;
use std::f64::consts::FRAC_PI_2;

mod least_squares;
mod mic_search;
mod projection;
mod search;
pub(crate) mod slp;
pub(crate) mod subset;
#[cfg(test)]
mod tests;

pub use least_squares::{least_squares, least_squares_near, LeastSquaresCylinder};
pub use projection::{angles, arc, axis, project};
use search::Region;

/// Initial trust region (rad of tilt) of the local searches from the swarm.
const START_STEP: f64 = 1e-3;
/// Basin hopping: restarts per round and their tilt (rad) from the best axis.
const HOPS: usize = 8;
const HOP_RADIUS: f64 = 1e-4;
/// Nelder–Mead on the exact values (see `mic_search`): initial simplex
/// edge and final resolution (rad; 1e-12 rad moves a point 100 mm along the axis
/// by 1e-10 mm), and the resolution of the hops' searches.
const NM_STEP: f64 = 1e-4;
const NM_XTOL: f64 = 1e-12;
const HOP_XTOL: f64 = 1e-9;

/// Default largest tilt of the axis from the reference axis: 10 degrees (rad).
pub const DEFAULT_MAX_TILT: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// Which cylinder to fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Criterion {
    /// Minimum circumscribed cylinder (Eq. 6.13).
    MinCircumscribed,
    /// Maximum inscribed cylinder (Eq. 6.15).
    MaxInscribed,
    /// Minimum zone: two coaxial cylinders of least radial separation (Eq. 6.14).
    MinZone,
}

impl Criterion {
    /// The cylinder criterion of a fit criterion of the package's table (least squares
    /// is no minimax cylinder: `None`).
    pub fn from_fit(c: crate::criterion::FitCriterion) -> Option<Self> {
        use crate::criterion::FitCriterion as F;
        match c {
            F::MinCircumscribed => Some(Self::MinCircumscribed),
            F::MaxInscribed => Some(Self::MaxInscribed),
            F::MinZone => Some(Self::MinZone),
            F::LeastSquares => None,
        }
    }

    /// Its entry of the package's criterion table.
    pub fn fit_criterion(self) -> crate::criterion::FitCriterion {
        use crate::criterion::FitCriterion as F;
        match self {
            Self::MinCircumscribed => F::MinCircumscribed,
            Self::MaxInscribed => F::MaxInscribed,
            Self::MinZone => F::MinZone,
        }
    }
}

/// Where the axis direction is searched: within `max_tilt` (rad, in [0, pi/2]) of
/// `axis`, or of the least-squares axis when `axis` is `None`. `max_tilt` 0 fixes the
/// direction; pi/2 is the whole upper half sphere of Sec. 6.4.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Search {
    pub axis: Option<[f64; 3]>,
    pub max_tilt: f64,
}

impl Default for Search {
    fn default() -> Self {
        Self { axis: None, max_tilt: DEFAULT_MAX_TILT }
    }
}

impl Search {
    /// The whole upper half sphere (the dissertation's search, Sec. 6.4).
    pub fn half_sphere() -> Self {
        Self { axis: None, max_tilt: FRAC_PI_2 }
    }

    /// The search a user asks for: `max_tilt_deg` degrees (in [0, 90]; 90 is exactly the
    /// half sphere) about the nominal `axis`, checked; errors name `shape`.
    pub fn from_degrees(axis: Option<[f64; 3]>, max_tilt_deg: f64, shape: &str) -> Result<Self> {
        if !(0.0..=90.0).contains(&max_tilt_deg) {
            return Err(GkError::config(format!(
                "{shape}: max_tilt must be between 0 and 90 degrees, got {max_tilt_deg:?}"
            )));
        }
        if let Some(a) = axis {
            if !a.iter().all(|x| x.is_finite()) {
                return Err(GkError::config(format!(
                    "{shape}: axis must be three finite numbers (x, y, z), got ({:?}, {:?}, {:?})",
                    a[0], a[1], a[2]
                )));
            }
            if a.iter().all(|x| *x == 0.0) {
                return Err(GkError::config(format!(
                    "{shape}: the axis ({:?}, {:?}, {:?}) has zero length; give a direction such as (0, 0, 1)",
                    a[0], a[1], a[2]
                )));
            }
        }
        let max_tilt = if max_tilt_deg == 90.0 { FRAC_PI_2 } else { max_tilt_deg.to_radians() };
        Ok(Self { axis, max_tilt })
    }

    /// Checks the settings: `max_tilt` in [0, pi/2], `axis` finite and non-zero.
    pub fn validate(&self) -> Result<Option<Vector3<f64>>> {
        if !(0.0..=FRAC_PI_2 * (1.0 + 1e-15)).contains(&self.max_tilt) {
            return Err(GkError::config(format!(
                "max_tilt must be between 0 and 90 degrees, got {} degrees",
                self.max_tilt.to_degrees()
            )));
        }
        match self.axis {
            None => Ok(None),
            Some(a) => {
                let v = Vector3::from(a);
                if !v.iter().all(|x| x.is_finite()) {
                    return Err(GkError::config(format!("axis: the components must be finite numbers, got {a:?}")));
                }
                let norm = v.norm();
                if !(norm > 0.0 && norm.is_finite()) {
                    return Err(GkError::config("axis: the axis has zero length; give a direction such as (0, 0, 1)"));
                }
                Ok(Some(v / norm))
            }
        }
    }
}

/// Settings of a cylinder fit.
#[derive(Debug, Clone)]
pub struct Options {
    pub seed: u64,
    pub particles: usize,
    pub max_iterations: usize,
    pub stall_iterations: usize,
    pub search: Search,
    /// Local refinements from this many of the swarm's best distinct particles.
    pub refine_starts: usize,
    /// Rounds of basin hopping around the best axis (0: none); a round that
    /// does not improve ends the hopping.
    pub hop_rounds: usize,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            seed: 0,
            particles: 20,
            max_iterations: 300,
            // the local searches from 8 particles and the basin hopping follow, so
            // the swarm only has to find the right valley (6: same results for seeds
            // 0..19 on data sets 1 and 3 and on 120 random cylinders as 25)
            stall_iterations: 6,
            search: Search::default(),
            refine_starts: 8,
            hop_rounds: 3,
        }
    }
}

/// A better optimum that the free search (the whole half sphere) found outside the
/// search cone.
#[derive(Debug, Clone, PartialEq)]
pub struct Outside {
    /// Its radius (MCC, MIC) or zone width (MZC).
    pub value: f64,
    /// Its axis direction and the tilt (rad) of that axis from the reference axis.
    pub direction: [f64; 3],
    pub tilt: f64,
}

/// A fitted cylinder.
#[derive(Debug, Clone)]
pub struct CylinderFit {
    pub criterion: Criterion,
    /// Point on the axis: the foot of the centroid of the points.
    pub point: [f64; 3],
    /// Unit axis direction in the upper half sphere (z >= 0).
    pub direction: [f64; 3],
    /// Polar and azimuthal angle of `direction` (Tables 6.2, 6.4).
    pub theta: f64,
    pub phi: f64,
    /// Radius of the MCC or MIC; for the MZC the mean of `r_in` and `r_out`.
    pub radius: f64,
    /// Inner and outer radius of the zone (MZC); both equal `radius` otherwise.
    pub r_in: f64,
    pub r_out: f64,
    /// Points fixing the inner / outer cylinder (indices into the input).
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Certificate: min and max 3-D distance of the points to the reported axis.
    pub extent: Extent,
    /// PSO iterations run, and the work: exact 2-D fits (the swarm's and those
    /// scoring the local searches) plus the local searches' linear programs.
    pub iterations: usize,
    pub evaluations: usize,
    /// The reference axis of the search (unit, upper half sphere): the nominal axis
    /// given, else the least-squares axis.
    pub reference: [f64; 3],
    /// Angle (rad) between `direction` and `reference`.
    pub tilt: f64,
    /// A better optimum of the free search outside the cone, if any.
    pub outside: Option<Outside>,
    /// Whether the axis lies on the boundary of the search cone (the constraint is
    /// active: the points alone would tilt it further).
    pub at_limit: bool,
    /// Angle (rad) the points cover around the axis (about the least-squares axis
    /// for the MIC, whose own axis can sit anywhere inside a short arc), and whether
    /// the fit is ill-posed (a MIC of less than [`MIN_ARC`]).
    pub arc: f64,
    pub ill_posed: bool,
    /// The least-squares cylinder's axis (point, direction), when it exists.
    pub lsq_axis: Option<([f64; 3], [f64; 3])>,
}

/// Below this arc (rad) around the axis a maximum inscribed cylinder is ill-posed
/// (Sec. 6.2.2) and other fits are poorly determined.
pub const MIN_ARC: f64 = FRAC_PI_2;

impl CylinderFit {
    /// Radial width of the zone about this axis (cylindricity for the MZC).
    pub fn form_error(&self) -> f64 {
        self.extent.max - self.extent.min
    }

    /// The value the criterion minimises: the MCC radius, minus the MIC radius, the
    /// MZC width.
    fn objective(&self) -> f64 {
        match self.criterion {
            Criterion::MinCircumscribed => self.r_out,
            Criterion::MaxInscribed => -self.r_in,
            Criterion::MinZone => self.r_out - self.r_in,
        }
    }

    /// The radius (MCC, MIC) or the zone width (MZC) the criterion optimises.
    pub fn size(&self) -> f64 {
        match self.criterion {
            Criterion::MinCircumscribed => self.r_out,
            Criterion::MaxInscribed => self.r_in,
            Criterion::MinZone => self.r_out - self.r_in,
        }
    }
}

/// Angle (rad) between two axes (unsigned directions), in [0, pi/2].
pub fn tilt(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let (a, b) = (Vector3::from(*a), Vector3::from(*b));
    a.cross(&b).norm().atan2(a.dot(&b).abs())
}

/// Fit a cylinder of the given criterion to 3-D points (flat, row-major).
///
/// The axis is searched within `opts.search.max_tilt` of the reference axis (the given
/// nominal axis, else the least-squares axis). Unless that is the whole half sphere,
/// the free search runs too: a better optimum inside the cone replaces the result (the
/// cone's own search missed it), one outside is reported in `outside`.
///
/// Large inputs (more than 2000 points) are fitted on an active subset (`subset`).
pub fn fit(pts: &[f64], crit: Criterion, opts: &Options) -> Result<CylinderFit> {
    let (nominal, spread) = checked(pts, opts)?;
    fit_spread(pts, crit, opts, nominal, spread)
}

/// The checks of [`fit`] and [`fit_near`]: finite points of sane magnitude, at least 5,
/// neither coincident nor collinear, valid search settings. Returns the validated nominal
/// axis and the largest principal spread of the points.
fn checked(pts: &[f64], opts: &Options) -> Result<(Option<Vector3<f64>>, f64)> {
    check_finite(pts, 3, "points")?;
    lsq::check_magnitude(pts, 3)?;
    let nominal = opts.search.validate()?;
    let n = pts.len() / 3;
    let min_n = 5;
    if n < min_n {
        return Err(GkError::invalid(format!("cylinder: needs at least {min_n} points, got {n}")));
    }
    let sv = lsq::principal_spread(pts);
    if sv[0] == 0.0 {
        return Err(GkError::degenerate("cylinder: all points coincide"));
    }
    if lsq::negligible(sv[1], sv[0]) {
        return Err(GkError::degenerate("cylinder: the points are collinear; no cylinder is determined"));
    }
    Ok((nominal, sv[0]))
}

/// [`checked`] in one pass over the points where it can decide (a Monte Carlo trial's
/// points, [`fit_near`]): every coordinate within [`lsq::MAX_COORD`] (NaN fails), at least
/// 5 points, and the scatter matrix about the first point, corrected to the centroid,
/// clearly spread (second eigenvalue at least 1e-6 of the first, fourteen orders of
/// magnitude above the collinearity test's 1e-20); the largest spread is then the square
/// root of the largest eigenvalue (the same quantity as [`checked`]'s, to rounding; it only
/// scales the verification's 1e-12 tolerance). Anything else: [`checked`] itself (its
/// typed errors, its spreads).
#[cfg(test)]
fn checked_near(pts: &[f64], opts: &Options) -> Result<(Option<Vector3<f64>>, f64)> {
    checked_near_sum(pts, opts).map(|(a, s, _)| (a, s))
}

/// [`checked_near`], and from the same pass the plain sum of the points' coordinates in
/// input order (the first pass of [`lsq::centroid`], the same bits; `None` when the checks
/// ran as [`checked`]): the active-subset fit's centroid takes one pass less (`subset`).
fn checked_near_sum(pts: &[f64], opts: &Options) -> Result<(Option<Vector3<f64>>, f64, Option<[f64; 3]>)> {
    let n = pts.len() / 3;
    let complete = |pts: &[f64]| checked(pts, opts).map(|(a, s)| (a, s, None));
    if n < 5 || pts.len() % 3 != 0 {
        return complete(pts);
    }
    let o = [pts[0], pts[1], pts[2]];
    let mut ok = true;
    let (mut s1, mut s2, mut sum) = ([0.0f64; 3], [0.0f64; 6], [0.0f64; 3]);
    for p in pts.chunks_exact(3) {
        ok &= (p[0].abs() <= lsq::MAX_COORD) & (p[1].abs() <= lsq::MAX_COORD) & (p[2].abs() <= lsq::MAX_COORD);
        let d = [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
        for k in 0..3 {
            s1[k] += d[k];
            sum[k] += p[k];
        }
        lsq::add_outer(&mut s2, d);
    }
    if !ok {
        return complete(pts);
    }
    let nominal = opts.search.validate()?;
    let m = [s1[0] / n as f64, s1[1] / n as f64, s1[2] / n as f64];
    let nf = n as f64;
    let s = nalgebra::Matrix3::new(
        s2[0] - nf * m[0] * m[0],
        s2[1] - nf * m[0] * m[1],
        s2[2] - nf * m[0] * m[2],
        s2[1] - nf * m[0] * m[1],
        s2[3] - nf * m[1] * m[1],
        s2[4] - nf * m[1] * m[2],
        s2[2] - nf * m[0] * m[2],
        s2[4] - nf * m[1] * m[2],
        s2[5] - nf * m[2] * m[2],
    );
    if !s.iter().all(|v| v.is_finite()) {
        return complete(pts);
    }
    let mut e: Vec<f64> = nalgebra::SymmetricEigen::new(s).eigenvalues.iter().copied().collect();
    e.sort_by(|a, b| b.total_cmp(a));
    if !(e[0] > 0.0 && e[1] >= 1e-6 * e[0]) {
        return complete(pts);
    }
    Ok((nominal, e[0].sqrt(), Some(sum)))
}

/// A warm start for [`fit_near`]: the axis (a point on it and its direction) of a fit of
/// nearby points -- a Monte Carlo trial's perturbed points start from the measured fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Warm {
    pub point: [f64; 3],
    pub direction: [f64; 3],
}

/// [`fit`] started from a nearby fit's axis, for points within a few noise sigmas of
/// those of the nearby fit (a Monte Carlo trial of the measured points).
///
/// The optimum of the nearby points lies in the basin the perturbed points' optimum has
/// moved from, so the exact local method of the global search runs from it: the exact
/// 2-D fit along the warm direction and the SLP local search (`slp`) -- without the
/// basin hopping of the global search (`opts.hop_rounds` applies to a fallback only): the
/// trial's optimum is the nearby one moved by the noise, and the hops that ran in the
/// nearby fit's global search are not repeated (on the bracket's bore and datum D, 100
/// trials with and without them differ by at most 3.4e-10 mm) -- above 2000 points on an active subset grown until every point lies inside the fitted
/// cylinder(s) (`subset`; the result is then the fit of all points). When the local
/// method cannot decide alone -- the axis ends on the boundary of the search cone, the
/// search does not converge, a maximum inscribed cylinder of a partial arc -- the global
/// search [`fit`] runs instead, and the second value is `true` (a fallback). The warm
/// result skips the free search outside the cone (`outside` stays `None`: that is a
/// warning the nearby fit already gave) and, without a nominal axis, the least-squares
/// axis is the search cone's reference as in [`fit`].
pub fn fit_near(pts: &[f64], crit: Criterion, opts: &Options, warm: &Warm) -> Result<(CylinderFit, bool)> {
    near(pts, crit, opts, warm, true)
}

/// [`fit_near`] without the fields only a report reads (the least-squares axis, the arc
/// the points cover and `ill_posed` stay unset): the axis, radii and control points of a
/// Monte Carlo trial (`gagekit_gdt::plan`). A fallback to the global search is complete.
pub fn fit_near_zone(pts: &[f64], crit: Criterion, opts: &Options, warm: &Warm) -> Result<(CylinderFit, bool)> {
    near(pts, crit, opts, warm, false)
}

fn near(pts: &[f64], crit: Criterion, opts: &Options, warm: &Warm, complete: bool) -> Result<(CylinderFit, bool)> {
    let (wp, wd) = (Vector3::from(warm.point), Vector3::from(warm.direction));
    if !(wp.iter().chain(wd.iter()).all(|x| x.is_finite()) && wd.norm() > 0.0) {
        return Err(GkError::invalid(format!("cylinder: the warm start must be a finite point and a non-zero direction, got {warm:?}")));
    }
    let (nominal, spread, sum) = checked_near_sum(pts, opts)?;
    let lsq_fit = if nominal.is_none() { lsq::cylinder(pts, None).ok() } else { None };
    let reference = match (nominal, &lsq_fit) {
        (Some(a), _) => a,
        (None, Some(c)) => Vector3::from(c.direction),
        (None, None) => return fit_spread(pts, crit, opts, nominal, spread).map(|r| (r, true)),
    };
    let max_tilt = opts.search.max_tilt.min(FRAC_PI_2);
    let free = max_tilt >= FRAC_PI_2 - 1e-12;
    let region = if free { Region::free() } else { Region::cone(reference, max_tilt) };
    let start = slp::Axis::new(wd, wp);
    let Some(mut r) = subset::fit_near_in(pts, crit, &start, &region, spread, sum)? else {
        return fit_spread(pts, crit, opts, nominal, spread).map(|r| (r, true));
    };
    let reference = lsq::upper([reference[0], reference[1], reference[2]]);
    r.tilt = tilt(&r.direction, &reference);
    r.reference = reference;
    r.at_limit = false;
    if complete {
        finish(&mut r, pts, crit, lsq_fit.as_ref());
    }
    Ok((r, false))
}

/// The fields every fit of all the points ends with: the least-squares axis, the arc the
/// points cover about the axis (the least-squares one for a maximum inscribed cylinder) and
/// whether that arc makes the maximum inscribed cylinder ill-posed (< 90 degrees).
fn finish(r: &mut CylinderFit, pts: &[f64], crit: Criterion, lsq_fit: Option<&lsq::Cylinder>) {
    r.lsq_axis = lsq_fit.map(|c| (c.point, c.direction));
    let (point, direction) = match (crit, r.lsq_axis) {
        (Criterion::MaxInscribed, Some(ax)) => ax,
        _ => (r.point, r.direction),
    };
    r.arc = arc(pts, &point, &direction);
    r.ill_posed = crit == Criterion::MaxInscribed && r.arc.to_degrees() < 90.0;
}

/// [`fit`] after its checks: `nominal` is the validated unit axis (if given), `spread`
/// the largest principal spread of the points (> 0). Needs no minimum count of
/// points (the straightness of a 3-D line uses it for 2 points and up).
pub(crate) fn fit_spread(
    pts: &[f64],
    crit: Criterion,
    opts: &Options,
    nominal: Option<Vector3<f64>>,
    spread: f64,
) -> Result<CylinderFit> {
    let lsq_fit = lsq::cylinder(pts, None).ok();
    let reference = match (nominal, &lsq_fit) {
        (Some(a), _) => a,
        (None, Some(c)) => Vector3::from(c.direction),
        (None, None) => {
            return Err(GkError::degenerate(
                "cylinder: no least-squares axis to search around; give a nominal axis",
            ))
        }
    };
    let max_tilt = opts.search.max_tilt.min(FRAC_PI_2);
    let free = max_tilt >= FRAC_PI_2 - 1e-12;
    let region = if free { Region::free() } else { Region::cone(reference, max_tilt) };
    let mut r = subset::fit_in(pts, crit, opts, lsq_fit.as_ref(), &region, spread)?;
    let reference = lsq::upper([reference[0], reference[1], reference[2]]);
    if !free {
        if let Ok(f) = subset::fit_in(pts, crit, opts, lsq_fit.as_ref(), &Region::half_sphere(), spread) {
            r.evaluations += f.evaluations;
            let tol = 1e-9 * r.r_out.max(f.r_out);
            if f.objective() < r.objective() - tol {
                let t = tilt(&f.direction, &reference);
                if t <= max_tilt {
                    // the cone's search missed an optimum inside the cone: take it
                    r = CylinderFit { evaluations: r.evaluations, ..f };
                } else {
                    r.outside = Some(Outside { value: f.size(), direction: f.direction, tilt: t });
                }
            }
        }
    }
    r.tilt = tilt(&r.direction, &reference);
    r.reference = reference;
    r.at_limit = !free && max_tilt > 0.0 && r.tilt >= max_tilt - 1e-9;
    finish(&mut r, pts, crit, lsq_fit.as_ref());
    Ok(r)
}
