//! Binding of the filtered form parameters (`gagekit_profile`): the public results
//! (`RoundnessParameters`, `StraightnessParameters`, `FlatnessParameters`) wrap the kernel
//! results and only convert them (getters, `to_dict()`).

use crate::arrays::{indices, matrix, rows, values};
use crate::errors::run;
use gagekit_profile::{flatness, gaussian, reference, roundness, straightness};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `{prefix}t`, `{prefix}p`, `{prefix}v`, `{prefix}q`: peak-to-valley, peak, valley and
/// RMS of the local deviations (mm), in that order.
fn params<'py>(py: Python<'py>, prefix: &str, p: &gagekit_profile::Params) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in [("t", p.t), ("p", p.p), ("v", p.v), ("q", p.q)] {
        d.set_item(format!("{prefix}{k}"), v)?;
    }
    Ok(d)
}

fn dict<'py, V: IntoPyObject<'py> + Clone>(py: Python<'py>, items: &[(&str, V)]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in items {
        d.set_item(*k, v.clone())?;
    }
    Ok(d)
}

/// Roundness of a closed profile (ISO 12181-1; `gagekit.roundness_parameters`).
/// `parameters`: RONt, RONp, RONv, RONq (mm); `center` / `radius`: the reference circle
/// (MZCI: the mean of the zone circles `r_in` / `r_out`); `eccentricity`: the reference
/// centre relative to the coordinate origin (the spindle axis of a roundness instrument);
/// `amplitude` / `phase`: the spectrum, harmonic 1 first. `profile` (evaluated points),
/// `points` (the measured ones) and `resampled` (unfiltered radii at `samples` equal
/// angles about `ls_center`) are for plots; not in `to_dict()`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct RoundnessParameters {
    r: roundness::Roundness,
    points: Py<PyArray2<f64>>,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl RoundnessParameters {
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        params(py, "RON", &self.r.params)
    }
    #[getter]
    fn reference(&self) -> &'static str {
        roundness::reference_name(self.r.reference)
    }
    /// `{"type": "none"}`, or the Gaussian filter's cut-off (UPR) and standard.
    #[getter]
    fn filter<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        match self.r.upr {
            None => d.set_item("type", "none")?,
            Some(u) => {
                d.set_item("type", "gaussian")?;
                d.set_item("upr", u)?;
                d.set_item("standard", "ISO 16610-21")?;
            }
        }
        Ok(d)
    }
    #[getter]
    fn center(&self) -> (f64, f64) {
        (self.r.center[0], self.r.center[1])
    }
    #[getter]
    fn radius(&self) -> f64 {
        self.r.radius
    }
    #[getter]
    fn r_in(&self) -> f64 {
        self.r.r_in
    }
    #[getter]
    fn r_out(&self) -> f64 {
        self.r.r_out
    }
    #[getter]
    fn ls_center(&self) -> (f64, f64) {
        (self.r.ls_center[0], self.r.ls_center[1])
    }
    #[getter]
    fn samples(&self) -> usize {
        self.r.samples
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.r.n_points
    }
    /// The largest angular gap of the measured points about `ls_center` (degrees).
    #[getter]
    fn max_gap_deg(&self) -> f64 {
        self.r.max_gap.to_degrees()
    }
    #[getter]
    fn amplitude<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.r.amplitude)
    }
    #[getter]
    fn phase<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.r.phase)
    }
    #[getter]
    fn control<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        indices(py, self.r.control.clone())
    }
    #[getter]
    fn profile<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix(py, self.r.profile.clone(), 2)
    }
    #[getter]
    fn points(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.points.clone_ref(py)
    }
    #[getter]
    fn resampled<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.r.resampled)
    }
    /// The reference centre relative to the origin: x, y, magnitude, angle_deg in [0, 360).
    #[getter]
    fn eccentricity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let [x, y] = self.r.center;
        // + 0.0: an angle of -0 is 0, as Python's float modulo gives it
        let angle = y.atan2(x).to_degrees().rem_euclid(360.0) + 0.0;
        dict(py, &[("x", x), ("y", y), ("magnitude", x.hypot(y)), ("angle_deg", angle)])
    }
    /// The JSON of `gagekit form roundness`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.r;
        let d = PyDict::new(py);
        d.set_item("shape", "roundness")?;
        d.set_item("n_points", r.n_points)?;
        d.set_item("filter", self.filter(py)?)?;
        d.set_item("reference", self.reference())?;
        d.set_item("parameters", self.parameters(py)?)?;
        let circle = PyDict::new(py);
        circle.set_item("center", r.center.to_vec())?;
        circle.set_item("radius", r.radius)?;
        d.set_item("reference_circle", circle)?;
        d.set_item("zone", dict(py, &[("inner_radius", r.r_in), ("outer_radius", r.r_out)])?)?;
        d.set_item("eccentricity", self.eccentricity(py)?)?;
        let resampling = PyDict::new(py);
        resampling.set_item("samples", r.samples)?;
        resampling.set_item("center", r.ls_center.to_vec())?;
        resampling.set_item("largest_gap_deg", self.max_gap_deg())?;
        resampling.set_item("method", "linear interpolation in angle about the least-squares centre")?;
        d.set_item("resampling", resampling)?;
        let spectrum = PyDict::new(py);
        spectrum.set_item("upr", (1..=r.amplitude.len()).collect::<Vec<_>>())?;
        spectrum.set_item("amplitude", &r.amplitude)?;
        d.set_item("spectrum", spectrum)?;
        d.set_item("units", "mm")?;
        Ok(d)
    }
}

/// RONt, RONp, RONv, RONq of (n, 2) points: Gaussian filter of `upr` undulations per
/// revolution (None: unfiltered), reference LSCI / MZCI / MCCI / MICI.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "roundness")]
#[pyo3(signature = (points, upr=None, reference="LSCI", samples=None, max_gap_deg=None, harmonics=None))]
fn form_roundness(
    py: Python<'_>,
    points: Bound<'_, PyArray2<f64>>,
    upr: Option<f64>,
    reference: &str,
    samples: Option<usize>,
    max_gap_deg: Option<f64>,
    harmonics: Option<usize>,
) -> PyResult<RoundnessParameters> {
    let read = points.readonly();
    let pts = rows(py, &read, 2, "points")?;
    let r = run(py, || {
        let crit = reference_of(reference)?;
        roundness::roundness(pts, &roundness::Options { upr, reference: crit, samples, max_gap_deg, harmonics })
    })?;
    Ok(RoundnessParameters { r, points: points.unbind() })
}

fn reference_of(name: &str) -> gagekit_core::Result<gagekit_form::criterion::FitCriterion> {
    reference(name)
}

/// Straightness of a 2-D profile (ISO 12780-1; `gagekit.straightness_parameters`):
/// STRt, STRp, STRv, STRq (mm) against LSLI or MZLI (deviations positive to the left of
/// the direction from the profile's first point to its last).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct StraightnessParameters {
    s: straightness::Straightness,
    cutoff: Option<f64>,
    spline: bool,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl StraightnessParameters {
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        params(py, "STR", &self.s.params)
    }
    #[getter]
    fn reference(&self) -> &'static str {
        if self.s.reference == gagekit_form::criterion::FitCriterion::MinZone { "MZLI" } else { "LSLI" }
    }
    /// `{"type": "none"}`, or the filter's type, cut-off (mm), standard and end handling.
    #[getter]
    fn filter<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        match self.cutoff {
            None => d.set_item("type", "none")?,
            Some(lc) => {
                let (kind, standard, ends) = if self.spline {
                    ("spline", "ISO 16610-22", "none dropped")
                } else {
                    ("gaussian", "ISO 16610-21", "one cut-off dropped at each end")
                };
                d.set_item("type", kind)?;
                d.set_item("cutoff_mm", lc)?;
                d.set_item("standard", standard)?;
                d.set_item("ends", ends)?;
            }
        }
        Ok(d)
    }
    #[getter]
    fn point(&self) -> (f64, f64) {
        (self.s.point[0], self.s.point[1])
    }
    #[getter]
    fn direction(&self) -> (f64, f64) {
        (self.s.direction[0], self.s.direction[1])
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.s.n_points
    }
    /// The length of profile evaluated (mm).
    #[getter]
    fn length(&self) -> f64 {
        self.s.length
    }
    /// The resampling step (filtered profiles; mm).
    #[getter]
    fn step(&self) -> Option<f64> {
        self.s.step
    }
    #[getter]
    fn profile<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix(py, self.s.profile.clone(), 2)
    }
    /// The JSON of `gagekit form straightness`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.s;
        let d = PyDict::new(py);
        d.set_item("shape", "straightness")?;
        d.set_item("n_points", s.n_points)?;
        d.set_item("filter", self.filter(py)?)?;
        d.set_item("reference", self.reference())?;
        d.set_item("parameters", self.parameters(py)?)?;
        let line = PyDict::new(py);
        line.set_item("point", s.point.to_vec())?;
        line.set_item("direction", s.direction.to_vec())?;
        d.set_item("reference_line", line)?;
        d.set_item("length_mm", s.length)?;
        d.set_item("units", "mm")?;
        if let Some(step) = s.step {
            d.set_item("step_mm", step)?;
        }
        Ok(d)
    }
}

/// STRt, STRp, STRv, STRq of (n, 2) points: Gaussian (or, `spline`, ISO 16610-22 cubic
/// spline) filter of cut-off `cutoff` mm (None: unfiltered), reference LSLI or MZLI.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "straightness")]
#[pyo3(signature = (points, cutoff=None, reference="LSLI", step=None, max_gap=None, spline=false))]
fn form_straightness(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    cutoff: Option<f64>,
    reference: &str,
    step: Option<f64>,
    max_gap: Option<f64>,
    spline: bool,
) -> PyResult<StraightnessParameters> {
    let pts = rows(py, &points, 2, "points")?;
    let s = run(py, || {
        let crit = reference_of(reference)?;
        straightness::straightness(pts, &straightness::Options { cutoff, spline, reference: crit, step, max_gap })
    })?;
    Ok(StraightnessParameters { s, cutoff, spline })
}

/// Flatness (ISO 12781-1; `gagekit.flatness_parameters`): FLTt, FLTp, FLTv, FLTq (mm)
/// against LSPL or MZPL (deviations positive along `normal`, oriented towards `up`,
/// default +z). Unfiltered.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct FlatnessParameters {
    f: flatness::Flatness,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl FlatnessParameters {
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        params(py, "FLT", &self.f.params)
    }
    #[getter]
    fn reference(&self) -> &'static str {
        if self.f.reference == gagekit_form::criterion::FitCriterion::MinZone { "MZPL" } else { "LSPL" }
    }
    #[getter]
    fn point(&self) -> (f64, f64, f64) {
        (self.f.point[0], self.f.point[1], self.f.point[2])
    }
    #[getter]
    fn normal(&self) -> (f64, f64, f64) {
        (self.f.normal[0], self.f.normal[1], self.f.normal[2])
    }
    #[getter]
    fn n_points(&self) -> usize {
        self.f.n_points
    }
    /// The JSON of `gagekit form flatness`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = &self.f;
        let d = PyDict::new(py);
        d.set_item("shape", "flatness")?;
        d.set_item("n_points", f.n_points)?;
        d.set_item("filter", dict(py, &[("type", "none")])?)?;
        d.set_item("reference", self.reference())?;
        d.set_item("parameters", self.parameters(py)?)?;
        let plane = PyDict::new(py);
        plane.set_item("point", f.point.to_vec())?;
        plane.set_item("normal", f.normal.to_vec())?;
        d.set_item("reference_plane", plane)?;
        d.set_item("units", "mm")?;
        Ok(d)
    }
}

/// FLTt, FLTp, FLTv, FLTq of (n, 3) points against LSPL or MZPL (deviations positive
/// along the normal oriented towards `up`, default +z).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "flatness")]
#[pyo3(signature = (points, reference="LSPL", up=None))]
fn form_flatness(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    reference: &str,
    up: Option<(f64, f64, f64)>,
) -> PyResult<FlatnessParameters> {
    let pts = rows(py, &points, 3, "points")?;
    let f = run(py, || flatness::flatness(pts, reference_of(reference)?, up.map(|u| [u.0, u.1, u.2])))?;
    Ok(FlatnessParameters { f })
}

/// ISO 16610-21 Gaussian filter (mean line) of a closed profile sampled at equal angles.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
fn profile_gaussian_closed<'py>(py: Python<'py>, radii: PyReadonlyArray1<'py, f64>, upr: f64) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let r = values(py, &radii, "radii")?;
    let out = run(py, || {
        gagekit_core::check_finite(r, 1, "radii")?;
        gaussian::filter_closed(r, upr)
    })?;
    Ok(PyArray1::from_vec(py, out))
}

/// ISO 16610-21 Gaussian filter (mean line) of an open profile at spacing `step`:
/// (index of the first filtered sample, filtered values); one cut-off dropped at each end.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
fn profile_gaussian_open<'py>(
    py: Python<'py>,
    values_: PyReadonlyArray1<'py, f64>,
    step: f64,
    cutoff: f64,
) -> PyResult<(usize, Bound<'py, PyArray1<f64>>)> {
    let z = values(py, &values_, "values")?;
    let (first, out) = run(py, || {
        gagekit_core::check_finite(z, 1, "values")?;
        gaussian::filter_open(z, step, cutoff)
    })?;
    Ok((first, PyArray1::from_vec(py, out)))
}

/// ISO 16610-22 cubic spline filter (mean line) of an open profile at spacing `step`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
fn profile_spline_open<'py>(
    py: Python<'py>,
    values_: PyReadonlyArray1<'py, f64>,
    step: f64,
    cutoff: f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let z = values(py, &values_, "values")?;
    let out = run(py, || {
        gagekit_core::check_finite(z, 1, "values")?;
        gagekit_profile::spline::filter_open(z, step, cutoff)
    })?;
    Ok(PyArray1::from_vec(py, out))
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<RoundnessParameters>()?;
    m.add_class::<StraightnessParameters>()?;
    m.add_class::<FlatnessParameters>()?;
    m.add_function(wrap_pyfunction!(form_roundness, m)?)?;
    m.add_function(wrap_pyfunction!(form_straightness, m)?)?;
    m.add_function(wrap_pyfunction!(form_flatness, m)?)?;
    m.add_function(wrap_pyfunction!(profile_gaussian_closed, m)?)?;
    m.add_function(wrap_pyfunction!(profile_gaussian_open, m)?)?;
    m.add_function(wrap_pyfunction!(profile_spline_open, m)?)?;
    Ok(())
}
