//! Binding of the filtered form parameters (`gagekit_profile`): converts arrays, returns
//! frozen results.

use crate::arrays::{indices, matrix, rows, values};
use crate::errors::run;
use gagekit_profile::{flatness, gaussian, reference, roundness, straightness};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

/// Peak-to-valley `t`, peak `p`, valley `v`, RMS `q` of the local deviations (mm).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct FormParams {
    t: f64,
    p: f64,
    v: f64,
    q: f64,
}

fn params(p: gagekit_profile::Params) -> FormParams {
    FormParams { t: p.t, p: p.p, v: p.v, q: p.q }
}

/// Roundness of a closed profile; see `gagekit_profile::roundness`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct RoundnessResult {
    params: Py<FormParams>,
    reference: String,
    center: (f64, f64),
    radius: f64,
    r_in: f64,
    r_out: f64,
    control: Py<PyArray1<i64>>,
    ls_center: (f64, f64),
    profile: Py<PyArray2<f64>>,
    resampled: Py<PyArray1<f64>>,
    samples: usize,
    n_points: usize,
    upr: Option<f64>,
    max_gap: f64,
    amplitude: Py<PyArray1<f64>>,
    phase: Py<PyArray1<f64>>,
}

/// RONt, RONp, RONv, RONq of (n, 2) points: Gaussian filter of `upr` undulations per
/// revolution (None: unfiltered), reference LSCI / MZCI / MCCI / MICI.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "roundness")]
#[pyo3(signature = (points, upr=None, reference="LSCI", samples=None, max_gap_deg=None, harmonics=None))]
fn form_roundness(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    upr: Option<f64>,
    reference: &str,
    samples: Option<usize>,
    max_gap_deg: Option<f64>,
    harmonics: Option<usize>,
) -> PyResult<RoundnessResult> {
    let pts = rows(py, &points, 2, "points")?;
    let r = run(py, || {
        let crit = reference_of(reference)?;
        roundness::roundness(pts, &roundness::Options { upr, reference: crit, samples, max_gap_deg, harmonics })
    })?;
    Ok(RoundnessResult {
        params: Py::new(py, params(r.params))?,
        reference: roundness::reference_name(r.reference).to_string(),
        center: (r.center[0], r.center[1]),
        radius: r.radius,
        r_in: r.r_in,
        r_out: r.r_out,
        control: indices(py, r.control).unbind(),
        ls_center: (r.ls_center[0], r.ls_center[1]),
        profile: matrix(py, r.profile, 2)?.unbind(),
        resampled: PyArray1::from_vec(py, r.resampled).unbind(),
        samples: r.samples,
        n_points: r.n_points,
        upr: r.upr,
        max_gap: r.max_gap,
        amplitude: PyArray1::from_vec(py, r.amplitude).unbind(),
        phase: PyArray1::from_vec(py, r.phase).unbind(),
    })
}

fn reference_of(name: &str) -> gagekit_core::Result<gagekit_form::criterion::FitCriterion> {
    reference(name)
}

/// Straightness of a 2-D profile; see `gagekit_profile::straightness`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct StraightnessResult {
    params: Py<FormParams>,
    reference: String,
    point: (f64, f64),
    direction: (f64, f64),
    profile: Py<PyArray2<f64>>,
    n_points: usize,
    step: Option<f64>,
    length: f64,
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
) -> PyResult<StraightnessResult> {
    let pts = rows(py, &points, 2, "points")?;
    let s = run(py, || {
        let crit = reference_of(reference)?;
        straightness::straightness(pts, &straightness::Options { cutoff, spline, reference: crit, step, max_gap })
    })?;
    let name = if s.reference == gagekit_form::criterion::FitCriterion::MinZone { "MZLI" } else { "LSLI" };
    Ok(StraightnessResult {
        params: Py::new(py, params(s.params))?,
        reference: name.to_string(),
        point: (s.point[0], s.point[1]),
        direction: (s.direction[0], s.direction[1]),
        profile: matrix(py, s.profile, 2)?.unbind(),
        n_points: s.n_points,
        step: s.step,
        length: s.length,
    })
}

/// Flatness of a surface; see `gagekit_profile::flatness`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.form")]
pub struct FlatnessResult {
    params: Py<FormParams>,
    reference: String,
    point: (f64, f64, f64),
    normal: (f64, f64, f64),
    n_points: usize,
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
) -> PyResult<FlatnessResult> {
    let pts = rows(py, &points, 3, "points")?;
    let f = run(py, || flatness::flatness(pts, reference_of(reference)?, up.map(|u| [u.0, u.1, u.2])))?;
    let name = if f.reference == gagekit_form::criterion::FitCriterion::MinZone { "MZPL" } else { "LSPL" };
    Ok(FlatnessResult {
        params: Py::new(py, params(f.params))?,
        reference: name.to_string(),
        point: (f.point[0], f.point[1], f.point[2]),
        normal: (f.normal[0], f.normal[1], f.normal[2]),
        n_points: f.n_points,
    })
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
    m.add_class::<FormParams>()?;
    m.add_class::<RoundnessResult>()?;
    m.add_class::<StraightnessResult>()?;
    m.add_class::<FlatnessResult>()?;
    m.add_function(wrap_pyfunction!(form_roundness, m)?)?;
    m.add_function(wrap_pyfunction!(form_straightness, m)?)?;
    m.add_function(wrap_pyfunction!(form_flatness, m)?)?;
    m.add_function(wrap_pyfunction!(profile_gaussian_closed, m)?)?;
    m.add_function(wrap_pyfunction!(profile_gaussian_open, m)?)?;
    m.add_function(wrap_pyfunction!(profile_spline_open, m)?)?;
    Ok(())
}
