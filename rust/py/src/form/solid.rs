//! 3-D fits: lines, planes, spheres, 3-D circles, cylinders, cones (Sec. 6.3-6.5).

use super::*;

use crate::errors::invalid;
use gagekit_form::criterion::FitCriterion;
use gagekit_form::lsq;
use numpy::PyUntypedArrayMethods;

/// Points as a flat slice of an (n, 2) or (n, 3) array, with its dimension.
fn rows23<'a>(py: Python<'_>, points: &'a PyReadonlyArray2<'_, f64>) -> PyResult<(&'a [f64], usize)> {
    let dim = points.shape()[1];
    if dim != 2 && dim != 3 {
        return Err(invalid(format!("points: expected an (n, 2) or (n, 3) array, got shape {:?}", points.shape())));
    }
    Ok((rows(py, points, dim, "points")?, dim))
}

/// A least-squares line (2-D or 3-D) with its certificate: signed distances (2-D) or
/// distances (3-D) to the line; `form_error` the spread (2-D) or twice the largest (3-D).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct LineResult {
    pub point: Vec<f64>,
    pub direction: Vec<f64>,
    pub min_distance: f64,
    pub max_distance: f64,
    pub form_error: f64,
}

/// Least-squares line of (n, 2) or (n, 3) points (the principal axis through the centroid).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "line_lsq")]
fn form_line_lsq(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<LineResult> {
    let (pts, dim) = rows23(py, &points)?;
    let (l, e) = run(py, || {
        let l = lsq::line(pts, dim)?;
        let e = lsq::line_extent(pts, dim, &l.point, &l.direction);
        Ok((l, e))
    })?;
    Ok(LineResult { point: l.point, direction: l.direction, min_distance: e.min, max_distance: e.max, form_error: e.line_form_error(dim) })
}

/// A least-squares plane with its certificate (signed distances) and flatness about it.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct PlaneResult {
    pub point: [f64; 3],
    pub normal: [f64; 3],
    pub min_distance: f64,
    pub max_distance: f64,
    pub form_error: f64,
}

/// Least-squares plane of (n, 3) points: the centroid and the direction of least spread.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "plane_lsq")]
fn form_plane_lsq(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<PlaneResult> {
    let pts = rows(py, &points, 3, "points")?;
    let (p, e) = run(py, || {
        let p = lsq::plane(pts)?;
        let e = lsq::plane_extent(pts, &p.point, &p.normal);
        Ok((p, e))
    })?;
    Ok(PlaneResult { point: p.point, normal: p.normal, min_distance: e.min, max_distance: e.max, form_error: e.spread() })
}

/// A least-squares circle (2-D) or sphere (3-D) with its certificate (distances to the
/// centre) and form error about it.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct LeastSquaresSphereResult {
    pub center: Vec<f64>,
    pub radius: f64,
    pub min_distance: f64,
    pub max_distance: f64,
    pub form_error: f64,
}

/// Least-squares circle of (n, 2) points or sphere of (n, 3) points.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "sphere_lsq")]
fn form_sphere_lsq(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<LeastSquaresSphereResult> {
    let (pts, dim) = rows23(py, &points)?;
    let (s, e) = run(py, || {
        let s = lsq::sphere(pts, dim)?;
        let e = lsq::center_extent(pts, dim, &s.center);
        Ok((s, e))
    })?;
    Ok(LeastSquaresSphereResult { center: s.center, radius: s.radius, min_distance: e.min, max_distance: e.max, form_error: e.spread() })
}

/// A least-squares circle in space with its certificate (in-plane radial distances).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct LeastSquaresCircle3Result {
    pub center: [f64; 3],
    pub normal: [f64; 3],
    pub radius: f64,
    pub min_distance: f64,
    pub max_distance: f64,
    pub form_error: f64,
}

/// Least-squares circle of (n, 3) points (NIST: plane, projection, circle in the plane).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "circle3d_lsq")]
fn form_circle3d_lsq(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<LeastSquaresCircle3Result> {
    let pts = rows(py, &points, 3, "points")?;
    let (c, e) = run(py, || {
        let c = lsq::circle3(pts)?;
        let e = lsq::circle3_extent(pts, &c.center, &c.normal);
        Ok((c, e))
    })?;
    Ok(LeastSquaresCircle3Result {
        center: c.center,
        normal: c.normal,
        radius: c.radius,
        min_distance: e.min,
        max_distance: e.max,
        form_error: e.spread(),
    })
}

/// A least-squares cylinder, complete: axis, angles, radius, certificate, arc covered.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct LeastSquaresCylinderResult {
    pub point: [f64; 3],
    pub direction: [f64; 3],
    pub radius: f64,
    /// Certificate: min and max 3-D distance of the points to the axis.
    pub min_distance: f64,
    pub max_distance: f64,
    pub form_error: f64,
    /// Arc (rad) the points cover around the axis.
    pub arc: f64,
}

/// Least-squares cylinder of (n, 3) points (from the principal axes and `start_axis`;
/// `warm`: from the axis `warm` of a nearby fit alone).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "cylinder_lsq")]
#[pyo3(signature = (points, start_axis=None, warm=None))]
fn form_cylinder_lsq(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    start_axis: Option<[f64; 3]>,
    warm: Option<[f64; 3]>,
) -> PyResult<LeastSquaresCylinderResult> {
    use gagekit_form::cylinder::{least_squares, least_squares_near};
    let pts = rows(py, &points, 3, "points")?;
    let c = run(py, || match warm {
        Some(a) => least_squares_near(pts, a),
        None => least_squares(pts, start_axis),
    })?;
    Ok(LeastSquaresCylinderResult {
        point: c.point,
        direction: c.direction,
        radius: c.radius,
        min_distance: c.extent.min,
        max_distance: c.extent.max,
        form_error: c.form_error(),
        arc: c.arc,
    })
}

/// A minimum-zone plane (flatness) or 2-D line (straightness), with its certificate.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct MinZoneFlatResult {
    /// A point on the mid-plane (mid-line), its unit normal, and a 2-D line's direction
    /// (empty for planes).
    pub point: Vec<f64>,
    pub normal: Vec<f64>,
    pub direction: Vec<f64>,
    /// Separation of the two bounding planes (lines).
    pub form_error: f64,
    /// Points on the upper and lower bound, sorted and merged.
    pub control: Vec<usize>,
    /// Certificate: min and max signed distance of the points to the mid-plane (mid-line).
    pub min_distance: f64,
    pub max_distance: f64,
    /// Linear programs solved.
    pub iterations: usize,
}

/// Minimum-zone plane of (n, 3) points or line of (n, 2) points (LP, then the exact
/// solve of the active constraints).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "min_zone_flat")]
fn form_min_zone_flat(py: Python<'_>, points: PyReadonlyArray2<'_, f64>) -> PyResult<MinZoneFlatResult> {
    let (pts, dim) = rows23(py, &points)?;
    let z = run(py, || if dim == 3 { gagekit_form::minzone::plane(pts) } else { gagekit_form::minzone::line2(pts) })?;
    let mut control: Vec<usize> = z.control_upper.iter().chain(&z.control_lower).copied().collect();
    control.sort_unstable();
    control.dedup();
    Ok(MinZoneFlatResult {
        point: z.point,
        normal: z.normal,
        direction: z.direction,
        form_error: z.form_error,
        control,
        min_distance: z.extent.min,
        max_distance: z.extent.max,
        iterations: z.iterations,
    })
}

/// A better optimum of the free search outside the search cone.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct OutsideResult {
    /// Its radius (MCC, MIC) or zone width (MZC), mm.
    pub value: f64,
    pub direction: [f64; 3],
    /// Tilt (rad) of its axis from the reference axis.
    pub tilt: f64,
}

impl OutsideResult {
    /// The Python object of a kernel's optional better optimum outside the cone.
    fn wrap(py: Python<'_>, o: Option<gagekit_form::cylinder::Outside>) -> PyResult<Option<Py<Self>>> {
        o.map(|o| Py::new(py, Self { value: o.value, direction: o.direction, tilt: o.tilt })).transpose()
    }
}

/// A minimax cylinder (Sec. 6.3): axis, radii, control points, certificate, search
/// diagnostics (angles rad, lengths mm). Its attributes are the kernel's
/// [`gagekit_form::cylinder::CylinderFit`] fields, read through [`mirror!`], plus the
/// criterion's canonical name, the certificate (`min_distance`, `max_distance`) and the
/// optimum outside the cone as an [`OutsideResult`].
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct CylinderResult {
    fit: gagekit_form::cylinder::CylinderFit,
    /// With a warm start: whether the global search had to run (`None` without one).
    warm_fallback: Option<bool>,
}

mirror!(CylinderResult {
    point, direction, theta, phi, radius, r_in, r_out, control_in, control_out, iterations, evaluations,
    reference, tilt, at_limit, arc, ill_posed, lsq_axis
} extra {
    #[getter]
    fn criterion(&self) -> &'static str {
        self.fit.criterion.fit_criterion().name()
    }
    #[getter]
    fn min_distance(&self) -> f64 {
        self.fit.extent.min
    }
    #[getter]
    fn max_distance(&self) -> f64 {
        self.fit.extent.max
    }
    #[getter]
    fn outside(&self, py: Python<'_>) -> PyResult<Option<Py<OutsideResult>>> {
        OutsideResult::wrap(py, self.fit.outside.clone())
    }
    /// With a warm start: `True` when the local method could not decide and the global
    /// search ran; `None` without a warm start.
    #[getter]
    fn warm_fallback(&self) -> Option<bool> {
        self.warm_fallback
    }
});

fn search_of(axis: Option<[f64; 3]>, max_tilt: f64) -> gagekit_form::cylinder::Search {
    gagekit_form::cylinder::Search { axis, max_tilt }
}

/// Minimax cylinder by the projection model + PSO (Sec. 6.3). `criterion`: any name of
/// the criterion table but least squares; the axis is searched within `max_tilt` (rad,
/// [0, pi/2]) of `axis` (default: the least-squares axis). `warm`: (point, direction) of a
/// nearby fit's axis to start the exact local method from
/// ([`gagekit_form::cylinder::fit_near`]; the global search when it cannot decide).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "cylinder_fit")]
#[pyo3(signature = (points, criterion, seed=0, particles=20, max_iterations=300, stall_iterations=6, axis=None, max_tilt=gagekit_form::cylinder::DEFAULT_MAX_TILT, refine_starts=8, hop_rounds=3, warm=None))]
#[allow(clippy::too_many_arguments)]
fn form_cylinder_fit(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    criterion: &str,
    seed: u64,
    particles: usize,
    max_iterations: usize,
    stall_iterations: usize,
    axis: Option<[f64; 3]>,
    max_tilt: f64,
    refine_starts: usize,
    hop_rounds: usize,
    warm: Option<([f64; 3], [f64; 3])>,
) -> PyResult<CylinderResult> {
    use gagekit_form::cylinder::{fit, fit_near, Criterion, Options, Warm};
    let pts = rows(py, &points, 3, "points")?;
    let opts = Options { seed, particles, max_iterations, stall_iterations, search: search_of(axis, max_tilt), refine_starts, hop_rounds };
    let (r, warm_fallback) = run(py, || {
        let allowed = [FitCriterion::MinCircumscribed, FitCriterion::MaxInscribed, FitCriterion::MinZone];
        let crit = Criterion::from_fit(FitCriterion::parse_for(criterion, &allowed, "cylinder")?).unwrap_or(Criterion::MinZone);
        match warm {
            None => fit(pts, crit, &opts).map(|r| (r, None)),
            Some((point, direction)) => fit_near(pts, crit, &opts, &Warm { point, direction }).map(|(r, f)| (r, Some(f))),
        }
    })?;
    Ok(CylinderResult { fit: r, warm_fallback })
}

/// A minimum-zone line in space (straightness): the thinnest enclosing cylinder.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct Line3Result {
    pub point: [f64; 3],
    pub direction: [f64; 3],
    /// Certificate: min and max distance of the points to the line.
    pub min_distance: f64,
    pub max_distance: f64,
    pub form_error: f64,
    pub control: Vec<usize>,
    pub reference: [f64; 3],
    pub tilt: f64,
    pub outside: Option<Py<OutsideResult>>,
}

/// Minimum-zone 3-D line, searched within `max_tilt` (rad) of `axis` (default: the
/// least-squares direction).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "line3_min_zone")]
#[pyo3(signature = (points, seed=0, axis=None, max_tilt=gagekit_form::cylinder::DEFAULT_MAX_TILT))]
fn form_line3_min_zone(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    seed: u64,
    axis: Option<[f64; 3]>,
    max_tilt: f64,
) -> PyResult<Line3Result> {
    use gagekit_form::cylinder::Options;
    let pts = rows(py, &points, 3, "points")?;
    let opts = Options { seed, stall_iterations: 50, refine_starts: 4, search: search_of(axis, max_tilt), ..Options::default() };
    let z = run(py, || gagekit_form::straightness::line3(pts, &opts))?;
    let outside = OutsideResult::wrap(py, z.outside.clone())?;
    Ok(Line3Result {
        point: z.point,
        direction: z.direction,
        min_distance: z.extent.min,
        max_distance: z.extent.max,
        form_error: z.form_error(),
        control: z.control,
        reference: z.reference,
        tilt: z.tilt,
        outside,
    })
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

/// A circle in space (any pose): the 2-D fit of a criterion in the least-squares plane.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct Circle3Result {
    pub center: [f64; 3],
    pub normal: [f64; 3],
    pub radius: f64,
    pub r_in: f64,
    pub r_out: f64,
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Certificate: min and max in-plane distance of the points to the centre.
    pub min_distance: f64,
    pub max_distance: f64,
    /// Largest distance of a point from the circle's plane.
    pub out_of_plane: f64,
    /// Points that fix the fit (minimum zone: `control_in`, then the rest of `control_out`).
    pub control: Vec<usize>,
    /// Arc (rad) covered seen from the centre (the least-squares centre for an MI of a
    /// short arc), and whether the fit is ill-posed (MI of an arc below 90 degrees).
    pub arc: f64,
    pub ill_posed: bool,
}

/// Circle of (n, 3) points in any pose: least-squares plane, projection, 2-D fit of
/// `criterion` (any name of the criterion table).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "circle_in_plane")]
fn form_circle_in_plane(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<Circle3Result> {
    let pts = rows(py, &points, 3, "points")?;
    let c = run(py, || {
        let crit = FitCriterion::parse_for(criterion, &FitCriterion::ALL, "circle")?;
        gagekit_form::circle::in_plane::fit(pts, crit)
    })?;
    Ok(Circle3Result {
        control: c.zone.control(),
        center: c.center,
        normal: c.normal,
        radius: c.radius,
        r_in: c.zone.r_in,
        r_out: c.zone.r_out,
        control_in: c.zone.control_in,
        control_out: c.zone.control_out,
        min_distance: c.extent.min,
        max_distance: c.extent.max,
        out_of_plane: c.out_of_plane,
        arc: c.arc,
        ill_posed: c.ill_posed,
    })
}

/// A Chebyshev sphere: centre, radii, control points and certificate.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct SphereResult {
    pub criterion: String,
    pub center: [f64; 3],
    pub r_in: f64,
    pub r_out: f64,
    pub control_in: Vec<usize>,
    pub control_out: Vec<usize>,
    /// Certificate: min and max distance of the points to the centre.
    pub min_distance: f64,
    pub max_distance: f64,
    /// Linear programs of the MI / MZ searches (0 for MC).
    pub iterations: usize,
    /// The certified global bound (MZ: no narrower zone; MI: no larger sphere; MC: the
    /// radius), within 1e-9 mm of the value.
    pub bound: f64,
}

/// Minimum circumscribed, maximum inscribed or minimum-zone sphere of (n, 3) points.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "sphere_fit")]
fn form_sphere_fit(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<SphereResult> {
    use gagekit_form::sphere;
    use FitCriterion as F;
    let pts = rows(py, &points, 3, "points")?;
    let (crit, z, e) = run(py, || {
        let crit = F::parse_for(criterion, &[F::MinCircumscribed, F::MaxInscribed, F::MinZone], "sphere")?;
        let z = match crit {
            F::MinCircumscribed => sphere::min_circumscribed(pts),
            F::MaxInscribed => sphere::max_inscribed(pts),
            _ => sphere::min_zone(pts),
        }?;
        let e = lsq::center_extent(pts, 3, &z.center);
        Ok((crit, z, e))
    })?;
    Ok(SphereResult {
        criterion: crit.name().to_string(),
        center: z.center,
        r_in: z.r_in,
        r_out: z.r_out,
        control_in: z.control_in,
        control_out: z.control_out,
        min_distance: e.min,
        max_distance: e.max,
        iterations: z.iterations,
        bound: z.bound,
    })
}

/// Minimum-zone sphere of (n, 3) points on an active set started near `center`, exact by
/// verification on every point (`gagekit_gdt::plan::active`).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "sphere_fit_near")]
fn form_sphere_fit_near(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, center: [f64; 3]) -> PyResult<SphereResult> {
    let pts = rows(py, &points, 3, "points")?;
    let (z, e) = run(py, || {
        gagekit_core::check_finite(pts, 3, "points")?;
        let z = gagekit_gdt::plan::active::sphere_near(pts, center)?;
        let e = lsq::center_extent(pts, 3, &z.center);
        Ok((z, e))
    })?;
    Ok(SphereResult {
        criterion: FitCriterion::MinZone.name().to_string(),
        center: z.center,
        r_in: z.r_in,
        r_out: z.r_out,
        control_in: z.control_in,
        control_out: z.control_out,
        min_distance: e.min,
        max_distance: e.max,
        iterations: z.iterations,
        bound: z.bound,
    })
}

/// A cone (issue 25 §3): the fields of the kernel's [`gagekit_form::cone::ConeFit`] (axis
/// point of the reference section, direction along which the radius grows, apex, half
/// angle rad, radii at the reference section, zone radii, control points, optimality gap),
/// read through [`mirror!`], plus the criterion's canonical name, the certificate (signed
/// normal deviations, positive away from the axis) and `form_error`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct ConeResult {
    fit: gagekit_form::cone::ConeFit,
}

mirror!(ConeResult {
    point, direction, apex, half_angle, fixed_angle, radius, distance, r_in, r_out, control_in, control_out, gap,
    evaluations
} extra {
    #[getter]
    fn criterion(&self) -> &'static str {
        self.fit.criterion.name()
    }
    #[getter]
    fn min_distance(&self) -> f64 {
        self.fit.extent.min
    }
    #[getter]
    fn max_distance(&self) -> f64 {
        self.fit.extent.max
    }
    #[getter]
    fn form_error(&self) -> f64 {
        self.fit.form_error()
    }
});

/// Cone of (n, 3) points: `criterion` any name of the criterion table; `half_angle` (rad)
/// fixes the half angle.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "cone_fit")]
#[pyo3(signature = (points, criterion, half_angle=None))]
fn form_cone_fit(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str, half_angle: Option<f64>) -> PyResult<ConeResult> {
    let pts = rows(py, &points, 3, "points")?;
    let fit = run(py, || {
        let crit = FitCriterion::parse_for(criterion, &FitCriterion::ALL, "cone")?;
        gagekit_form::cone::fit(pts, crit, &gagekit_form::cone::Options { half_angle })
    })?;
    Ok(ConeResult { fit })
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(form_cone_fit, m)?)?;
    m.add_function(wrap_pyfunction!(form_cylinder_fit, m)?)?;
    m.add_function(wrap_pyfunction!(form_line3_min_zone, m)?)?;
    m.add_function(wrap_pyfunction!(form_criterion, m)?)?;
    m.add_function(wrap_pyfunction!(form_criteria, m)?)?;
    m.add_class::<CylinderResult>()?;
    m.add_class::<OutsideResult>()?;
    m.add_class::<Line3Result>()?;
    m.add_function(wrap_pyfunction!(form_circle_in_plane, m)?)?;
    m.add_function(wrap_pyfunction!(form_sphere_fit, m)?)?;
    m.add_function(wrap_pyfunction!(form_sphere_fit_near, m)?)?;
    m.add_class::<Circle3Result>()?;
    m.add_class::<SphereResult>()?;
    m.add_class::<LeastSquaresCylinderResult>()?;
    m.add_class::<MinZoneFlatResult>()?;
    m.add_function(wrap_pyfunction!(form_min_zone_flat, m)?)?;
    m.add_class::<LineResult>()?;
    m.add_class::<PlaneResult>()?;
    m.add_class::<LeastSquaresSphereResult>()?;
    m.add_class::<LeastSquaresCircle3Result>()?;
    m.add_class::<ConeResult>()?;
    m.add_function(wrap_pyfunction!(form_line_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_plane_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_sphere_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle3d_lsq, m)?)?;
    m.add_function(wrap_pyfunction!(form_cylinder_lsq, m)?)?;
    Ok(())
}
