//! The public results of the fits (`gagekit.CircleFit`, `CylinderFit`, `ConeFit`,
//! `LineFit`, `PlaneFit`, `SphereFit`, `Circle3DFit`, `Certificate`): each wraps the
//! kernel's result of `gagekit_form::result` and only converts it — getters (vectors as
//! tuples), `to_dict()` (the JSON keys of the `form` commands, in their order), equality
//! and a repr.

use gagekit_form::result as r;
use pyo3::exceptions::PyDeprecationWarning;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

fn tup<'py>(py: Python<'py>, v: &[f64]) -> PyResult<Bound<'py, PyTuple>> {
    PyTuple::new(py, v)
}

fn itup<'py>(py: Python<'py>, v: &[usize]) -> PyResult<Bound<'py, PyTuple>> {
    PyTuple::new(py, v)
}

fn deprecated(py: Python<'_>, message: &std::ffi::CStr) -> PyResult<()> {
    PyErr::warn(py, &py.get_type::<PyDeprecationWarning>(), message, 1)
}

/// The start of every 3-D fit's JSON (issue 3's keys): shape, criterion, n_points,
/// form_error; the feature's own keys follow, then [`certificate`].
fn head<'py>(py: Python<'py>, shape: &str, criterion: &str, n_points: usize, form_error: f64) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("shape", shape)?;
    d.set_item("criterion", criterion)?;
    d.set_item("n_points", n_points)?;
    d.set_item("form_error", form_error)?;
    Ok(d)
}

fn certificate<'py>(py: Python<'py>, c: &r::Certificate) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("min_distance", c.min_distance)?;
    d.set_item("max_distance", c.max_distance)?;
    Ok(d)
}

/// The radius keys of an axis fit (cylinders, cones): `radius`, and for the minimum zone
/// `inner_radius` / `outer_radius`.
fn radii(d: &Bound<'_, PyDict>, radius: f64, inner: Option<f64>, outer: Option<f64>) -> PyResult<()> {
    d.set_item("radius", radius)?;
    if let (Some(i), Some(o)) = (inner, outer) {
        d.set_item("inner_radius", i)?;
        d.set_item("outer_radius", o)?;
    }
    Ok(())
}

/// Minimum and maximum distance of the input points to the reported feature, recomputed
/// from the reported parameters (mm).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct Certificate(pub r::Certificate);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl Certificate {
    #[getter]
    fn min_distance(&self) -> f64 {
        self.0.min_distance
    }
    #[getter]
    fn max_distance(&self) -> f64 {
        self.0.max_distance
    }
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        certificate(py, &self.0)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, Certificate>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        format!("Certificate(min_distance={:?}, max_distance={:?})", self.0.min_distance, self.0.max_distance)
    }
}

fn cert(py: Python<'_>, c: r::Certificate) -> PyResult<Py<Certificate>> {
    Py::new(py, Certificate(c))
}

/// A fitted 2-D circle, or a circle in space fitted in its least-squares plane (Sec. 6.2).
///
/// `criterion`: the canonical name; `radius`: the fitted radius (minimum zone: the mean
/// of `r_in` and `r_out`); `r_in` / `r_out`: the smallest / largest distance of the
/// points from `center` (minimum zone: the zone circles); `form_error = r_out - r_in`
/// (roundness); `control_points`: input indices of the points that fix the fit (minimum
/// zone: `control_in`, then the rest of `control_out`); `arc_deg`: the arc the points
/// cover seen from the centre; `warnings`: why a result is ill-posed (a maximum inscribed
/// circle of an arc below 90 degrees). In space `center` is 3-D, `normal` the unit normal
/// of the plane and `out_of_plane` the largest distance of a point from it.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct CircleFit(pub r::CircleResult);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl CircleFit {
    #[getter]
    fn criterion(&self) -> &'static str {
        self.0.criterion.name()
    }
    #[getter]
    fn method(&self) -> &'static str {
        self.0.method
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.0.n_points
    }
    #[getter]
    fn center<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        tup(py, &self.0.center)
    }
    #[getter]
    fn radius(&self) -> f64 {
        self.0.radius
    }
    #[getter]
    fn r_in(&self) -> f64 {
        self.0.r_in
    }
    #[getter]
    fn r_out(&self) -> f64 {
        self.0.r_out
    }
    #[getter]
    fn form_error(&self) -> f64 {
        self.0.form_error
    }
    /// Deprecated alias of `form_error`.
    #[getter]
    fn width(&self, py: Python<'_>) -> PyResult<f64> {
        deprecated(py, c"CircleFit.width is deprecated; use form_error")?;
        Ok(self.0.form_error)
    }
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        itup(py, &self.0.control_points)
    }
    #[getter]
    fn control_in<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        itup(py, &self.0.control_in)
    }
    #[getter]
    fn control_out<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        itup(py, &self.0.control_out)
    }
    #[getter]
    fn arc_deg(&self) -> f64 {
        self.0.arc_deg
    }
    #[getter]
    fn ill_posed(&self) -> bool {
        self.0.ill_posed
    }
    #[getter]
    fn warnings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, &self.0.warnings)
    }
    #[getter]
    fn normal(&self) -> Option<(f64, f64, f64)> {
        self.0.normal.map(|n| (n[0], n[1], n[2]))
    }
    #[getter]
    fn out_of_plane(&self) -> Option<f64> {
        self.0.out_of_plane
    }
    /// The JSON of `gagekit form circle`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = &self.0;
        let d = PyDict::new(py);
        d.set_item("shape", "circle")?;
        d.set_item("criterion", f.criterion.name())?;
        d.set_item("method", f.method)?;
        d.set_item("n_points", f.n_points)?;
        d.set_item("form_error", f.form_error)?;
        d.set_item("center", &f.center)?;
        d.set_item("radius", f.radius)?;
        if let Some(n) = f.normal {
            d.set_item("normal", n.to_vec())?;
            d.set_item("out_of_plane", f.out_of_plane)?;
        }
        if f.criterion == gagekit_form::criterion::FitCriterion::MinZone {
            d.set_item("inner_radius", f.r_in)?;
            d.set_item("outer_radius", f.r_out)?;
            d.set_item("control_in", &f.control_in)?;
            d.set_item("control_out", &f.control_out)?;
        }
        d.set_item("control_points", &f.control_points)?;
        d.set_item("certificate", certificate(py, &r::Certificate { min_distance: f.r_in, max_distance: f.r_out })?)?;
        d.set_item("arc_deg", f.arc_deg)?;
        d.set_item("ill_posed", f.ill_posed)?;
        d.set_item("warnings", &f.warnings)?;
        Ok(d)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, CircleFit>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        let f = &self.0;
        format!(
            "CircleFit(criterion='{}', center={:?}, radius={:?}, form_error={:?}, n_points={})",
            f.criterion.name(), f.center, f.radius, f.form_error, f.n_points
        )
    }
}

/// A fitted cylinder (Sec. 6.3). `radius`: least squares, circumscribed, inscribed (the
/// minimum zone: the mean of `inner_radius` and `outer_radius`); `form_error`: the
/// cylindricity about this axis (the zone width for the minimum zone); `certificate`: min
/// and max distance of the points to the reported axis, recomputed in 3-D; `arc_deg`: the
/// angle the points cover around the axis; `warnings`: a short arc (`ill_posed` for a
/// maximum inscribed cylinder of an arc below 90 degrees, Sec. 6.2.2), an axis on the
/// search cone's boundary, a better optimum outside it; `tilt_deg`: the angle between the
/// fitted and the reference axis (Chebyshev fits).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct CylinderFit(pub r::CylinderResult);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl CylinderFit {
    #[getter]
    fn shape(&self) -> &'static str {
        "cylinder"
    }
    #[getter]
    fn criterion(&self) -> &'static str {
        self.0.criterion.name()
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.0.n_points
    }
    #[getter]
    fn point(&self) -> (f64, f64, f64) {
        let p = self.0.point;
        (p[0], p[1], p[2])
    }
    #[getter]
    fn direction(&self) -> (f64, f64, f64) {
        let p = self.0.direction;
        (p[0], p[1], p[2])
    }
    /// Deprecated alias of `point` (the JSON key stays `axis_point`).
    #[getter]
    fn axis_point(&self, py: Python<'_>) -> PyResult<(f64, f64, f64)> {
        deprecated(py, c"CylinderFit.axis_point is deprecated; use point")?;
        Ok(self.point())
    }
    /// Deprecated alias of `direction` (the JSON key stays `axis_direction`).
    #[getter]
    fn axis_direction(&self, py: Python<'_>) -> PyResult<(f64, f64, f64)> {
        deprecated(py, c"CylinderFit.axis_direction is deprecated; use direction")?;
        Ok(self.direction())
    }
    #[getter]
    fn theta(&self) -> f64 {
        self.0.theta
    }
    #[getter]
    fn phi(&self) -> f64 {
        self.0.phi
    }
    #[getter]
    fn radius(&self) -> f64 {
        self.0.radius
    }
    #[getter]
    fn form_error(&self) -> f64 {
        self.0.form_error
    }
    #[getter]
    fn certificate(&self, py: Python<'_>) -> PyResult<Py<Certificate>> {
        cert(py, self.0.certificate)
    }
    #[getter]
    fn inner_radius(&self) -> Option<f64> {
        self.0.inner_radius
    }
    #[getter]
    fn outer_radius(&self) -> Option<f64> {
        self.0.outer_radius
    }
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        itup(py, &self.0.control_points)
    }
    #[getter]
    fn iterations(&self) -> usize {
        self.0.iterations
    }
    #[getter]
    fn evaluations(&self) -> usize {
        self.0.evaluations
    }
    #[getter]
    fn arc_deg(&self) -> f64 {
        self.0.arc_deg
    }
    #[getter]
    fn ill_posed(&self) -> bool {
        self.0.ill_posed
    }
    #[getter]
    fn warnings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, &self.0.warnings)
    }
    #[getter]
    fn tilt_deg(&self) -> Option<f64> {
        self.0.tilt_deg
    }
    #[getter]
    fn reference_axis(&self) -> Option<(f64, f64, f64)> {
        self.0.reference_axis.map(|p| (p[0], p[1], p[2]))
    }
    /// With a warm start: `True` when the local method could not decide and the global
    /// search ran; `None` without a warm start.
    #[getter]
    fn warm_fallback(&self) -> Option<bool> {
        self.0.warm_fallback
    }
    /// The JSON of `gagekit form fit cylinder`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = &self.0;
        let d = head(py, "cylinder", f.criterion.name(), f.n_points, f.form_error)?;
        radii(&d, f.radius, f.inner_radius, f.outer_radius)?;
        d.set_item("axis_point", f.point.to_vec())?;
        d.set_item("axis_direction", f.direction.to_vec())?;
        d.set_item("theta", f.theta)?;
        d.set_item("phi", f.phi)?;
        d.set_item("control_points", &f.control_points)?;
        d.set_item("certificate", certificate(py, &f.certificate)?)?;
        if f.criterion != gagekit_form::criterion::FitCriterion::LeastSquares {
            d.set_item("iterations", f.iterations)?;
            d.set_item("evaluations", f.evaluations)?;
            d.set_item("tilt_deg", f.tilt_deg)?;
        }
        d.set_item("arc_deg", f.arc_deg)?;
        d.set_item("ill_posed", f.ill_posed)?;
        d.set_item("warnings", &f.warnings)?;
        Ok(d)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, CylinderFit>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        let f = &self.0;
        format!(
            "CylinderFit(criterion='{}', point={:?}, direction={:?}, radius={:?}, form_error={:?}, n_points={})",
            f.criterion.name(), f.point, f.direction, f.radius, f.form_error, f.n_points
        )
    }
}

/// A fitted cone (issue 25 §3). `point`: the axis point of the reference section (the
/// plane normal to the axis through the foot of the points' centroid); `direction`: the
/// unit axis along which the radius grows; `half_angle` (rad); `radius` at the reference
/// section (minimum zone: the mean of `inner_radius` and `outer_radius`); `distance` =
/// radius cos(half_angle); `form_error`: the normal width of the points about this cone;
/// `certificate`: min / max signed normal deviation; `gap` (Chebyshev cones): the decrease
/// a linear step of the local search predicts (0 certifies a local optimum to first order).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct ConeFit(pub r::ConeResult);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl ConeFit {
    #[getter]
    fn shape(&self) -> &'static str {
        "cone"
    }
    #[getter]
    fn criterion(&self) -> &'static str {
        self.0.criterion.name()
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.0.n_points
    }
    #[getter]
    fn point(&self) -> (f64, f64, f64) {
        let p = self.0.point;
        (p[0], p[1], p[2])
    }
    #[getter]
    fn direction(&self) -> (f64, f64, f64) {
        let p = self.0.direction;
        (p[0], p[1], p[2])
    }
    #[getter]
    fn apex(&self) -> (f64, f64, f64) {
        let p = self.0.apex;
        (p[0], p[1], p[2])
    }
    #[getter]
    fn half_angle(&self) -> f64 {
        self.0.half_angle
    }
    /// The full apex angle (rad).
    #[getter]
    fn apex_angle(&self) -> f64 {
        self.0.apex_angle()
    }
    #[getter]
    fn radius(&self) -> f64 {
        self.0.radius
    }
    #[getter]
    fn distance(&self) -> f64 {
        self.0.distance
    }
    #[getter]
    fn form_error(&self) -> f64 {
        self.0.form_error
    }
    #[getter]
    fn certificate(&self, py: Python<'_>) -> PyResult<Py<Certificate>> {
        cert(py, self.0.certificate)
    }
    #[getter]
    fn fixed_angle(&self) -> bool {
        self.0.fixed_angle
    }
    #[getter]
    fn inner_radius(&self) -> Option<f64> {
        self.0.inner_radius
    }
    #[getter]
    fn outer_radius(&self) -> Option<f64> {
        self.0.outer_radius
    }
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        itup(py, &self.0.control_points)
    }
    #[getter]
    fn gap(&self) -> f64 {
        self.0.gap
    }
    #[getter]
    fn evaluations(&self) -> usize {
        self.0.evaluations
    }
    /// Radius of the cone at axial coordinate `z` (mm, along `direction`) from the
    /// reference section.
    fn radius_at(&self, z: f64) -> f64 {
        self.0.radius_at(z)
    }
    /// The JSON of `gagekit form fit cone`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = &self.0;
        let d = head(py, "cone", f.criterion.name(), f.n_points, f.form_error)?;
        radii(&d, f.radius, f.inner_radius, f.outer_radius)?;
        d.set_item("axis_point", f.point.to_vec())?;
        d.set_item("axis_direction", f.direction.to_vec())?;
        d.set_item("apex", f.apex.to_vec())?;
        d.set_item("half_angle", f.half_angle)?;
        d.set_item("half_angle_deg", f.half_angle.to_degrees())?;
        d.set_item("apex_angle", f.apex_angle())?;
        d.set_item("distance", f.distance)?;
        d.set_item("fixed_angle", f.fixed_angle)?;
        d.set_item("certificate", certificate(py, &f.certificate)?)?;
        if f.criterion != gagekit_form::criterion::FitCriterion::LeastSquares {
            d.set_item("control_points", &f.control_points)?;
            d.set_item("gap", f.gap)?;
            d.set_item("evaluations", f.evaluations)?;
        }
        Ok(d)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, ConeFit>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        let f = &self.0;
        format!(
            "ConeFit(criterion='{}', point={:?}, direction={:?}, half_angle={:?}, radius={:?}, form_error={:?}, n_points={})",
            f.criterion.name(), f.point, f.direction, f.half_angle, f.radius, f.form_error, f.n_points
        )
    }
}

/// A fitted line. `certificate`: signed distances (2-D) or distances (3-D) to the line;
/// `form_error`: max - min of the signed distances (2-D), twice the largest distance
/// (3-D); `tilt_deg` and `warnings`: the minimum-zone line in space (as for cylinders).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct LineFit(pub r::LineResult);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl LineFit {
    #[getter]
    fn shape(&self) -> &'static str {
        "line"
    }
    #[getter]
    fn criterion(&self) -> &'static str {
        self.0.criterion.name()
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.0.n_points
    }
    #[getter]
    fn point<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        tup(py, &self.0.point)
    }
    #[getter]
    fn direction<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        tup(py, &self.0.direction)
    }
    #[getter]
    fn form_error(&self) -> f64 {
        self.0.form_error
    }
    #[getter]
    fn certificate(&self, py: Python<'_>) -> PyResult<Py<Certificate>> {
        cert(py, self.0.certificate)
    }
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        itup(py, &self.0.control_points)
    }
    #[getter]
    fn tilt_deg(&self) -> Option<f64> {
        self.0.tilt_deg
    }
    #[getter]
    fn warnings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, &self.0.warnings)
    }
    /// The JSON of `gagekit form fit line`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = &self.0;
        let d = head(py, "line", f.criterion.name(), f.n_points, f.form_error)?;
        d.set_item("point", &f.point)?;
        d.set_item("direction", &f.direction)?;
        d.set_item("control_points", &f.control_points)?;
        d.set_item("certificate", certificate(py, &f.certificate)?)?;
        if let Some(t) = f.tilt_deg {
            d.set_item("tilt_deg", t)?;
            d.set_item("warnings", &f.warnings)?;
        }
        Ok(d)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, LineFit>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        let f = &self.0;
        format!(
            "LineFit(criterion='{}', point={:?}, direction={:?}, form_error={:?}, n_points={})",
            f.criterion.name(), f.point, f.direction, f.form_error, f.n_points
        )
    }
}

/// A fitted plane. `certificate`: signed distances to it; `form_error` = max - min.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct PlaneFit(pub r::PlaneResult);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl PlaneFit {
    #[getter]
    fn shape(&self) -> &'static str {
        "plane"
    }
    #[getter]
    fn criterion(&self) -> &'static str {
        self.0.criterion.name()
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.0.n_points
    }
    #[getter]
    fn point(&self) -> (f64, f64, f64) {
        let p = self.0.point;
        (p[0], p[1], p[2])
    }
    #[getter]
    fn normal(&self) -> (f64, f64, f64) {
        let p = self.0.normal;
        (p[0], p[1], p[2])
    }
    #[getter]
    fn form_error(&self) -> f64 {
        self.0.form_error
    }
    #[getter]
    fn certificate(&self, py: Python<'_>) -> PyResult<Py<Certificate>> {
        cert(py, self.0.certificate)
    }
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        itup(py, &self.0.control_points)
    }
    /// The JSON of `gagekit form fit plane`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = &self.0;
        let d = head(py, "plane", f.criterion.name(), f.n_points, f.form_error)?;
        d.set_item("point", f.point.to_vec())?;
        d.set_item("normal", f.normal.to_vec())?;
        d.set_item("control_points", &f.control_points)?;
        d.set_item("certificate", certificate(py, &f.certificate)?)?;
        Ok(d)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, PlaneFit>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        let f = &self.0;
        format!(
            "PlaneFit(criterion='{}', point={:?}, normal={:?}, form_error={:?}, n_points={})",
            f.criterion.name(), f.point, f.normal, f.form_error, f.n_points
        )
    }
}

/// A fitted sphere (3-D) or least-squares circle (2-D). `certificate`: distances to the
/// centre; `form_error` = max - min (sphericity about this centre; the zone width for the
/// minimum zone). Chebyshev spheres also give `inner_radius` / `outer_radius` (the zone,
/// minimum zone only), `control_points` and `global_bound`: the certificate of the global
/// search (minimum zone: no centre gives a narrower zone; maximum inscribed: no larger
/// sphere; within 1e-9 mm of the value).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct SphereFit(pub r::SphereResult);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl SphereFit {
    #[getter]
    fn shape(&self) -> &'static str {
        self.0.shape
    }
    #[getter]
    fn criterion(&self) -> &'static str {
        self.0.criterion.name()
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.0.n_points
    }
    #[getter]
    fn center<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        tup(py, &self.0.center)
    }
    #[getter]
    fn radius(&self) -> f64 {
        self.0.radius
    }
    #[getter]
    fn form_error(&self) -> f64 {
        self.0.form_error
    }
    #[getter]
    fn certificate(&self, py: Python<'_>) -> PyResult<Py<Certificate>> {
        cert(py, self.0.certificate)
    }
    #[getter]
    fn inner_radius(&self) -> Option<f64> {
        self.0.inner_radius
    }
    #[getter]
    fn outer_radius(&self) -> Option<f64> {
        self.0.outer_radius
    }
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyTuple>>> {
        self.0.control_points.as_deref().map(|c| itup(py, c)).transpose()
    }
    #[getter]
    fn global_bound(&self) -> Option<f64> {
        self.0.global_bound
    }
    /// The JSON of `gagekit form fit sphere`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = &self.0;
        let d = head(py, f.shape, f.criterion.name(), f.n_points, f.form_error)?;
        d.set_item("radius", f.radius)?;
        if let Some(control) = &f.control_points {
            if let (Some(i), Some(o)) = (f.inner_radius, f.outer_radius) {
                d.set_item("inner_radius", i)?;
                d.set_item("outer_radius", o)?;
            }
            if let Some(b) = f.global_bound {
                d.set_item("global_bound", b)?;
            }
            d.set_item("center", &f.center)?;
            d.set_item("control_points", control)?;
        } else {
            d.set_item("center", &f.center)?;
        }
        d.set_item("certificate", certificate(py, &f.certificate)?)?;
        Ok(d)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, SphereFit>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        let f = &self.0;
        format!(
            "SphereFit(criterion='{}', center={:?}, radius={:?}, form_error={:?}, n_points={})",
            f.criterion.name(), f.center, f.radius, f.form_error, f.n_points
        )
    }
}

/// A least-squares circle in space (NIST's convention: least-squares plane, projection,
/// least-squares circle in that plane). `certificate`: radial distances of the projected
/// points to its centre; `form_error` = max - min (roundness about the fit).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct Circle3DFit(pub r::Circle3Result);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl Circle3DFit {
    #[getter]
    fn shape(&self) -> &'static str {
        "circle3d"
    }
    #[getter]
    fn criterion(&self) -> &'static str {
        "least-squares"
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.0.n_points
    }
    #[getter]
    fn center(&self) -> (f64, f64, f64) {
        let p = self.0.center;
        (p[0], p[1], p[2])
    }
    #[getter]
    fn normal(&self) -> (f64, f64, f64) {
        let p = self.0.normal;
        (p[0], p[1], p[2])
    }
    #[getter]
    fn radius(&self) -> f64 {
        self.0.radius
    }
    #[getter]
    fn form_error(&self) -> f64 {
        self.0.form_error
    }
    #[getter]
    fn certificate(&self, py: Python<'_>) -> PyResult<Py<Certificate>> {
        cert(py, self.0.certificate)
    }
    /// The JSON of `gagekit form fit circle3d`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = &self.0;
        let d = head(py, "circle3d", "least-squares", f.n_points, f.form_error)?;
        d.set_item("radius", f.radius)?;
        d.set_item("center", f.center.to_vec())?;
        d.set_item("normal", f.normal.to_vec())?;
        d.set_item("certificate", certificate(py, &f.certificate)?)?;
        Ok(d)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, Circle3DFit>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        let f = &self.0;
        format!(
            "Circle3DFit(center={:?}, normal={:?}, radius={:?}, form_error={:?}, n_points={})",
            f.center, f.normal, f.radius, f.form_error, f.n_points
        )
    }
}
