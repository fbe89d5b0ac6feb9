//! The fits' entry points (Ch. 6): each takes the points and the user's settings, calls the
//! kernel and returns the public result of `gagekit_form::result` as its pyclass
//! (results.rs); the Python facades in `gagekit.form` only read the arguments in.

use super::*;

use super::results::{Circle3DFit, CircleFit, ConeFit, CylinderFit, LineFit, PlaneFit, SphereFit};
use crate::errors::invalid;
use gagekit_core::GkError;
use gagekit_form::criterion::FitCriterion;
use gagekit_form::lsq;
use gagekit_form::result::{self as res, count};
use numpy::PyUntypedArrayMethods;

/// Points as a flat slice of an (n, 2) or (n, 3) array, with its dimension.
fn rows23<'a>(py: Python<'_>, points: &'a PyReadonlyArray2<'_, f64>) -> PyResult<(&'a [f64], usize)> {
    let dim = points.shape()[1];
    if dim != 2 && dim != 3 {
        return Err(invalid(format!("points: expected an (n, 2) or (n, 3) array, got shape {:?}", points.shape())));
    }
    Ok((rows(py, points, dim, "points")?, dim))
}

/// Circle of (n, 2) points, or of (n, 3) points in any pose (fitted in their least-squares
/// plane): `criterion` any name of the criterion table (least squares, MC Eq. 6.1, MI
/// Eq. 6.2, MZ Eqs. 6.5-6.8); `method` "exact" (the computational-geometry kernels) or
/// "pso" (2-D, MC / MI / MZ: the seeded swarm over the centre, Eqs. 6.1, 6.4, 6.5, a
/// cross-check).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(signature = (points, criterion, method="exact", seed=0, particles=20, iterations=2000, stall_iterations=100))]
#[allow(clippy::too_many_arguments)]
fn fit_circle(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    criterion: &str,
    method: &str,
    seed: u64,
    particles: usize,
    iterations: usize,
    stall_iterations: usize,
) -> PyResult<CircleFit> {
    use gagekit_form::circle;
    use gagekit_form::circle_pso::Kind;
    let (pts, dim) = rows23(py, &points)?;
    let n = pts.len() / dim;
    run(py, || {
        let crit = FitCriterion::parse_for(criterion, &FitCriterion::ALL, "circle")?;
        match (method, dim) {
            ("exact", 3) => Ok(res::CircleResult::in_plane(circle::in_plane::fit(pts, crit)?, crit, n)),
            ("exact", _) => Ok(res::CircleResult::planar(circle::fit(pts, crit)?, "exact", n)),
            ("pso", 3) => Err(GkError::config("method 'pso' fits 2-D points; fit points in space with method 'exact'")),
            ("pso", _) => {
                let kind = match crit {
                    FitCriterion::MinCircumscribed => Kind::MinCircumscribed,
                    FitCriterion::MaxInscribed => Kind::MaxInscribed,
                    FitCriterion::MinZone => Kind::MinZone,
                    FitCriterion::LeastSquares => {
                        return Err(GkError::config("method 'pso' fits mc, mi and mz"));
                    }
                };
                let settings = gagekit_pso::Settings { seed, particles, max_iterations: iterations, stall_iterations, ..Default::default() };
                let zone = gagekit_form::circle_pso::fit(pts, kind, &settings)?.zone;
                Ok(res::CircleResult::planar(circle::from_zone(pts, crit, zone)?, "pso", n))
            }
            _ => Err(GkError::config(format!("unknown circle fit method '{method}'; available: 'exact', 'pso'"))),
        }
    })
    .map(CircleFit)
}

/// Cylinder of (n, 3) points (Sec. 6.3): least squares (Levenberg-Marquardt; `warm`: from
/// the direction of a nearby fit alone) or a Chebyshev cylinder (MCC Eq. 6.13, MIC Eq.
/// 6.15, MZC Eq. 6.14) by the projection model + seeded PSO, its axis searched within
/// `max_tilt` degrees ([0, 90]) of `axis` (default: the least-squares axis); `warm`:
/// (point, direction) of a nearby fit's axis to start the exact local method from
/// ([`gagekit_form::cylinder::fit_near`]).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(signature = (points, criterion, seed=0, particles=20, iterations=300, stall_iterations=6, axis=None, max_tilt=gagekit_form::cylinder::DEFAULT_MAX_TILT.to_degrees(), refine_starts=8, hop_rounds=3, warm=None))]
#[allow(clippy::too_many_arguments)]
fn fit_cylinder(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    criterion: &str,
    seed: i64,
    particles: i64,
    iterations: i64,
    stall_iterations: i64,
    axis: Option<[f64; 3]>,
    max_tilt: f64,
    refine_starts: i64,
    hop_rounds: i64,
    warm: Option<([f64; 3], [f64; 3])>,
) -> PyResult<CylinderFit> {
    use gagekit_form::cylinder::{fit, fit_near, least_squares, least_squares_near, Criterion, Options, Search, Warm};
    let pts = rows(py, &points, 3, "points")?;
    let n = pts.len() / 3;
    run(py, || {
        let crit = FitCriterion::parse_for(criterion, &FitCriterion::ALL, "cylinder")?;
        let search = Search::from_degrees(axis, max_tilt, "cylinder")?;
        let Some(kind) = Criterion::from_fit(crit) else {
            let c = match warm {
                Some((_, direction)) => least_squares_near(pts, direction),
                None => least_squares(pts, None),
            }?;
            return Ok(res::cylinder_least_squares(c, n));
        };
        let opts = Options {
            particles: count("cylinder", "particles", particles, 1)?,
            max_iterations: count("cylinder", "iterations", iterations, 0)?,
            stall_iterations: count("cylinder", "stall_iterations", stall_iterations, 0)?,
            refine_starts: count("cylinder", "refine_starts", refine_starts, 0)?,
            hop_rounds: count("cylinder", "hop_rounds", hop_rounds, 0)?,
            seed: u64::try_from(seed)
                .map_err(|_| GkError::config(format!("cylinder: seed must be a non-negative integer, got {seed}")))?,
            search,
        };
        match warm {
            None => fit(pts, kind, &opts).map(|r| res::cylinder_minimax(r, max_tilt, None, n)),
            Some((point, direction)) => fit_near(pts, kind, &opts, &Warm { point, direction })
                .map(|(r, fell_back)| res::cylinder_minimax(r, max_tilt, Some(fell_back), n)),
        }
    })
    .map(CylinderFit)
}

/// (theta, phi) of an axis direction, flipped into the upper half sphere (theta <= pi/2;
/// Tables 6.2, 6.4).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
fn axis_angles(direction: [f64; 3]) -> (f64, f64) {
    res::axis_angles(direction)
}

/// Line of (n, 2) or (n, 3) points: least squares (the principal axis through the
/// centroid) or minimum zone (2-D: two parallel lines of least separation, LP then the
/// exact active-set solve; 3-D: the thinnest enclosing cylinder, Eq. 6.13, searched
/// within `max_tilt` degrees of `axis`, default the least-squares direction).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(signature = (points, criterion, seed=0, axis=None, max_tilt=gagekit_form::cylinder::DEFAULT_MAX_TILT.to_degrees()))]
fn fit_line(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    criterion: &str,
    seed: u64,
    axis: Option<[f64; 3]>,
    max_tilt: f64,
) -> PyResult<LineFit> {
    use gagekit_form::cylinder::{Options, Search};
    let (pts, dim) = rows23(py, &points)?;
    let n = pts.len() / dim;
    run(py, || {
        let crit = FitCriterion::parse_for(criterion, &[FitCriterion::LeastSquares, FitCriterion::MinZone], "line")?;
        match (crit, dim) {
            (FitCriterion::MinZone, 3) => {
                let search = Search::from_degrees(axis, max_tilt, "line")?;
                let opts = Options { seed, stall_iterations: 50, refine_starts: 4, search, ..Options::default() };
                Ok(res::LineResult::min_zone_3d(gagekit_form::straightness::line3(pts, &opts)?, max_tilt, n))
            }
            (FitCriterion::MinZone, _) => Ok(res::LineResult::min_zone_2d(gagekit_form::minzone::line2(pts)?, n)),
            _ => {
                let l = lsq::line(pts, dim)?;
                let e = lsq::line_extent(pts, dim, &l.point, &l.direction);
                Ok(res::LineResult::least_squares(l, e, dim, n))
            }
        }
    })
    .map(LineFit)
}

/// Plane of (n, 3) points: least squares (the centroid and the direction of least spread)
/// or minimum zone (flatness: LP in the least-squares frame, the exact solve of the
/// active constraints, re-linearised until the tilt vanishes).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
fn fit_plane(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<PlaneFit> {
    let pts = rows(py, &points, 3, "points")?;
    let n = pts.len() / 3;
    run(py, || {
        let crit = FitCriterion::parse_for(criterion, &[FitCriterion::LeastSquares, FitCriterion::MinZone], "plane")?;
        if crit == FitCriterion::MinZone {
            return Ok(res::PlaneResult::min_zone(gagekit_form::minzone::plane(pts)?, n));
        }
        let p = lsq::plane(pts)?;
        let e = lsq::plane_extent(pts, &p.point, &p.normal);
        Ok(res::PlaneResult::least_squares(p, e, n))
    })
    .map(PlaneFit)
}

/// Sphere of (n, 3) points (least squares also circle of (n, 2) points): least squares
/// (Levenberg-Marquardt), minimum circumscribed (Welzl), maximum inscribed or minimum zone
/// (certified branch and bound, then the exact local step).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
fn fit_sphere(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<SphereFit> {
    use gagekit_form::sphere;
    use FitCriterion as F;
    let (pts, dim) = rows23(py, &points)?;
    let n = pts.len() / dim;
    run(py, || {
        let crit = F::parse_for(criterion, &F::ALL, "sphere")?;
        if crit == F::LeastSquares {
            let s = lsq::sphere(pts, dim)?;
            let e = lsq::center_extent(pts, dim, &s.center);
            return Ok(res::SphereResult::least_squares(s, e, dim, n));
        }
        if dim != 3 {
            return Err(GkError::config(format!(
                "sphere: {} needs (n, 3) points; for 2-D points use fit_circle",
                crit.name()
            )));
        }
        let z = match crit {
            F::MinCircumscribed => sphere::min_circumscribed(pts),
            F::MaxInscribed => sphere::max_inscribed(pts),
            _ => sphere::min_zone(pts),
        }?;
        let e = lsq::center_extent(pts, 3, &z.center);
        Ok(res::SphereResult::chebyshev(z, crit, e, n))
    })
    .map(SphereFit)
}

/// Minimum-zone sphere of (n, 3) points on an active set started near `center`, exact by
/// verification on every point (`gagekit_gdt::plan::active`; a Monte Carlo trial).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
fn fit_sphere_near(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, center: [f64; 3]) -> PyResult<SphereFit> {
    let pts = rows(py, &points, 3, "points")?;
    let n = pts.len() / 3;
    run(py, || {
        gagekit_core::check_finite(pts, 3, "points")?;
        let z = gagekit_gdt::plan::active::sphere_near(pts, center)?;
        let e = lsq::center_extent(pts, 3, &z.center);
        Ok(res::SphereResult::chebyshev(z, FitCriterion::MinZone, e, n))
    })
    .map(SphereFit)
}

/// Minimum-zone circle of (n, 2) points on an active set started near `center`, exact by
/// verification on every point (`gagekit_gdt::plan::active`; a roundness section of a
/// Monte Carlo trial).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
fn fit_circle_near(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, center: [f64; 2]) -> PyResult<CircleFit> {
    let pts = rows(py, &points, 2, "points")?;
    let n = pts.len() / 2;
    run(py, || {
        gagekit_core::check_finite(pts, 2, "points")?;
        Ok(res::CircleResult::planar(gagekit_gdt::plan::active::circle_near(pts, center)?, "exact", n))
    })
    .map(CircleFit)
}

/// Least-squares circle of (n, 3) points in space (NIST: plane, projection, circle in the
/// plane).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(signature = (points, criterion="least-squares"))]
fn fit_circle_3d(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<Circle3DFit> {
    let pts = rows(py, &points, 3, "points")?;
    let n = pts.len() / 3;
    run(py, || {
        FitCriterion::parse_for(criterion, &[FitCriterion::LeastSquares], "3-D circle")?;
        let c = lsq::circle3(pts)?;
        let e = lsq::circle3_extent(pts, &c.center, &c.normal);
        Ok(res::Circle3Result::least_squares(c, e, n))
    })
    .map(Circle3DFit)
}

/// Cone of (n, 3) points: `criterion` any name of the criterion table; `angle` fixes the
/// half angle (degrees, strictly between 0 and 90).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(signature = (points, criterion, angle=None))]
fn fit_cone(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str, angle: Option<f64>) -> PyResult<ConeFit> {
    use gagekit_form::cone;
    let pts = rows(py, &points, 3, "points")?;
    let n = pts.len() / 3;
    run(py, || {
        let crit = FitCriterion::parse_for(criterion, &FitCriterion::ALL, "cone")?;
        let half_angle = angle.map(cone::half_angle_from_degrees).transpose()?;
        Ok(res::cone(cone::fit(pts, crit, &cone::Options { half_angle })?, n))
    })
    .map(ConeFit)
}

/// The canonical name of a fit criterion (any alias of the package's one table), or a
/// ConfigError listing the names `allowed` (all when empty) for `shape`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "criterion")]
#[pyo3(signature = (name, allowed=Vec::new(), shape="fit"))]
fn form_criterion(py: Python<'_>, name: &str, allowed: Vec<String>, shape: &str) -> PyResult<String> {
    run(py, || {
        let allowed: Vec<FitCriterion> = if allowed.is_empty() {
            FitCriterion::ALL.to_vec()
        } else {
            allowed.iter().map(|a| a.parse::<FitCriterion>()).collect::<Result<_, _>>()?
        };
        FitCriterion::parse_for(name, &allowed, shape).map(|c| c.name().to_string())
    })
}

/// The criterion table: (alias, canonical name, circle code) for every accepted spelling.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "criteria")]
fn form_criteria() -> Vec<(&'static str, &'static str, &'static str)> {
    gagekit_form::criterion::ALIASES.iter().map(|(k, c)| (*k, c.name(), c.code())).collect()
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<super::results::Certificate>()?;
    m.add_class::<CircleFit>()?;
    m.add_class::<CylinderFit>()?;
    m.add_class::<ConeFit>()?;
    m.add_class::<LineFit>()?;
    m.add_class::<PlaneFit>()?;
    m.add_class::<SphereFit>()?;
    m.add_class::<Circle3DFit>()?;
    m.add_function(wrap_pyfunction!(fit_circle, m)?)?;
    m.add_function(wrap_pyfunction!(fit_cylinder, m)?)?;
    m.add_function(wrap_pyfunction!(fit_line, m)?)?;
    m.add_function(wrap_pyfunction!(fit_plane, m)?)?;
    m.add_function(wrap_pyfunction!(fit_sphere, m)?)?;
    m.add_function(wrap_pyfunction!(fit_sphere_near, m)?)?;
    m.add_function(wrap_pyfunction!(fit_circle_near, m)?)?;
    m.add_function(wrap_pyfunction!(fit_circle_3d, m)?)?;
    m.add_function(wrap_pyfunction!(fit_cone, m)?)?;
    m.add_function(wrap_pyfunction!(axis_angles, m)?)?;
    m.add_function(wrap_pyfunction!(form_criterion, m)?)?;
    m.add_function(wrap_pyfunction!(form_criteria, m)?)?;
    Ok(())
}
