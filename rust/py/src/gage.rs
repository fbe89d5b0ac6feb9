//! Bindings of gagekit-gage: the virtual-gage LP of Eq. 5.11 (array conversion only).

use crate::arrays::{matrix, rows, values};
use crate::errors::{invalid, run};
use gagekit_gage::{result, GageSet, Motion, Options, MOTION_NAMES};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// Borrowed gage data checked for consistent lengths.
struct Args<'a> {
    points: &'a [f64],
    offsets: Vec<usize>,
    planes: &'a [f64],
    f: &'a [f64],
    g: &'a [f64],
    motion: Motion,
}

#[allow(clippy::too_many_arguments)]
fn args<'a>(
    py: Python<'_>,
    points: &'a PyReadonlyArray2<'_, f64>,
    offsets: Vec<usize>,
    planes: &'a PyReadonlyArray2<'_, f64>,
    f: &'a PyReadonlyArray1<'_, f64>,
    g: &'a PyReadonlyArray1<'_, f64>,
    free: Vec<bool>,
    max_angle: f64,
    max_shift: f64,
) -> PyResult<Args<'a>> {
    let free: [bool; 6] =
        free.try_into().map_err(|_| invalid("free: expected six flags (alpha, beta, gamma, dx, dy, dz)"))?;
    Ok(Args {
        points: rows(py, points, 3, "gage points")?,
        offsets,
        planes: rows(py, planes, 4, "gage planes")?,
        f: values(py, f, "f")?,
        g: values(py, g, "g")?,
        motion: Motion { free, max_angle, max_shift },
    })
}

impl Args<'_> {
    fn set(&self) -> GageSet<'_> {
        GageSet { points: self.points, offsets: &self.offsets, planes: self.planes, f: self.f, g: self.g }
    }
}

/// The solution of Eq. 5.11 (Sec. 5.2): T*, allowances, slacks, limiting bounds, groups.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.gage")]
pub struct GageSolution {
    /// (alpha, beta, gamma, dx, dy, dz) of T*, rad and mm.
    params: Vec<f64>,
    /// T* as a 4x4 homogeneous matrix (row lists).
    matrix: Vec<Vec<f64>>,
    allowance_before: Vec<f64>,
    allowance_after: Vec<f64>,
    /// q_i: the largest allowance of each gage.
    q: Vec<f64>,
    /// s_i: the slack (release) of each gage.
    s: Vec<f64>,
    /// u: the largest release.
    u: f64,
    objective: f64,
    lp_objective: f64,
    iterations: usize,
    last_step: f64,
    lp_status: String,
    /// (motion, "upper" | "lower", dual multiplier) of each motion bound that limits T*.
    active_bounds: Vec<(String, String, f64)>,
    /// Infeasible groups of gages (Eq. 5.10), as gage indices.
    groups: Vec<Vec<usize>>,
}

/// Solve Eq. 5.11 with exact re-linearisation; optionally the infeasible groups (Eq. 5.10).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gage"))]
#[pyfunction]
#[pyo3(name = "solve")]
#[pyo3(signature = (points, offsets, planes, f, g, free, max_angle, max_shift, tol=1e-10, slack_tol=1e-7, groups=true))]
#[allow(clippy::too_many_arguments)]
fn gage_solve<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    offsets: Vec<usize>,
    planes: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray1<'py, f64>,
    g: PyReadonlyArray1<'py, f64>,
    free: Vec<bool>,
    max_angle: f64,
    max_shift: f64,
    tol: f64,
    slack_tol: f64,
    groups: bool,
) -> PyResult<GageSolution> {
    let a = args(py, &points, offsets, &planes, &f, &g, free, max_angle, max_shift)?;
    let opts = Options { tol, slack_tol, ..Options::default() };
    let (sol, grp) = run(py, || {
        let set = a.set();
        let sol = gagekit_gage::solve(&set, &a.motion, &opts)?;
        let grp = if groups { gagekit_gage::infeasible_groups(&set, &a.motion, &opts, &sol)? } else { vec![] };
        Ok((sol, grp))
    })?;
    Ok(GageSolution {
        params: sol.params.to_vec(),
        matrix: sol.matrix.iter().map(|r| r.to_vec()).collect(),
        allowance_before: sol.allowance_before,
        allowance_after: sol.allowance_after,
        q: sol.q,
        s: sol.s,
        u: sol.u,
        objective: sol.objective,
        lp_objective: sol.lp_objective,
        iterations: sol.iterations,
        last_step: sol.last_step,
        lp_status: sol.lp_status.to_string(),
        active_bounds: sol
            .active_bounds
            .iter()
            .map(|b| (MOTION_NAMES[b.motion].to_string(), if b.side > 0 { "upper" } else { "lower" }.to_string(), b.dual))
            .collect(),
        groups: grp,
    })
}

/// T* = [Rz(alpha) Ry(beta) Rx(gamma) | (dx, dy, dz)] (rad, mm), applied to points of the
/// part frame (`gagekit_gage::result::Transform`).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.gage")]
pub struct Transform(result::Transform);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl Transform {
    #[getter]
    fn alpha(&self) -> f64 {
        self.0.params[0]
    }
    #[getter]
    fn beta(&self) -> f64 {
        self.0.params[1]
    }
    #[getter]
    fn gamma(&self) -> f64 {
        self.0.params[2]
    }
    #[getter]
    fn dx(&self) -> f64 {
        self.0.params[3]
    }
    #[getter]
    fn dy(&self) -> f64 {
        self.0.params[4]
    }
    #[getter]
    fn dz(&self) -> f64 {
        self.0.params[5]
    }
    /// The 4x4 homogeneous matrix, row by row.
    #[getter]
    fn matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, self.0.matrix.iter().map(|r| PyTuple::new(py, r)).collect::<PyResult<Vec<_>>>()?)
    }
    /// The 4x4 matrix as a numpy array.
    fn as_array<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix(py, self.0.matrix.iter().flatten().copied().collect(), 4)
    }
    /// The transform applied to (n, 3) points: R p + t, by the package's one point
    /// transform (`gagekit.gage.align.apply`, numpy), as for the alignment H.
    fn apply<'py>(&self, py: Python<'py>, points: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        py.import("gagekit.gage.align")?.getattr("apply")?.call1((self.as_array(py)?, points))
    }
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in MOTION_NAMES.iter().zip(self.0.params) {
            d.set_item(*k, v)?;
        }
        d.set_item("matrix", self.0.matrix.iter().map(|r| r.to_vec()).collect::<Vec<_>>())?;
        Ok(d)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, Transform>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        let p = self.0.params;
        format!("Transform(alpha={:?}, beta={:?}, gamma={:?}, dx={:?}, dy={:?}, dz={:?})", p[0], p[1], p[2], p[3], p[4], p[5])
    }
}

/// A bound of Omega (Eq. 5.2) with a non-zero Lagrange multiplier at T* (Sec. 5.2.2).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.gage")]
pub struct BoundLimit(result::BoundLimit);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl BoundLimit {
    #[getter]
    fn motion(&self) -> &'static str {
        self.0.motion
    }
    /// "upper" or "lower".
    #[getter]
    fn side(&self) -> &'static str {
        self.0.side
    }
    #[getter]
    fn dual(&self) -> f64 {
        self.0.dual
    }
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("motion", self.0.motion)?;
        d.set_item("side", self.0.side)?;
        d.set_item("dual", self.0.dual)?;
        Ok(d)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.extract::<PyRef<'_, BoundLimit>>().is_ok_and(|o| o.0 == self.0)
    }
    fn __repr__(&self) -> String {
        format!("BoundLimit(motion='{}', side='{}', dual={:?})", self.0.motion, self.0.side, self.0.dual)
    }
}

/// One gage at T* (mm): the allowances before / after (the smallest signed distances of
/// its points from the gage plane; negative: short of material), `q` the largest (Eq.
/// 5.4) and `slack` the release s_i of Eq. 5.11 (0 when the gage is met). With an
/// uncertainty (`gagekit.gage.uncertainty`): `uncertainty` (the allowance after T*'s JCGM
/// 101 uncertainty) and `decision` (ISO 14253-1), set by `replace`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.gage")]
pub struct GageOutcome {
    outcome: result::GageOutcome,
    uncertainty: Option<Py<PyAny>>,
    decision: Option<String>,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl GageOutcome {
    #[getter]
    fn name(&self) -> &str {
        &self.outcome.label.name
    }
    #[getter]
    fn region(&self) -> &str {
        &self.outcome.label.region
    }
    #[getter]
    fn points(&self) -> usize {
        self.outcome.label.points
    }
    #[getter]
    fn filtered_points(&self) -> usize {
        self.outcome.label.filtered_points
    }
    #[getter]
    fn allowance_before(&self) -> f64 {
        self.outcome.allowance_before
    }
    #[getter]
    fn allowance_after(&self) -> f64 {
        self.outcome.allowance_after
    }
    #[getter]
    fn q(&self) -> f64 {
        self.outcome.q
    }
    #[getter]
    fn slack(&self) -> f64 {
        self.outcome.slack
    }
    #[getter]
    fn uncertainty(&self, py: Python<'_>) -> Option<Py<PyAny>> {
        self.uncertainty.as_ref().map(|u| u.clone_ref(py))
    }
    #[getter]
    fn decision(&self) -> Option<&str> {
        self.decision.as_deref()
    }
    /// A copy with `uncertainty` and / or `decision` replaced (the keywords given).
    #[pyo3(signature = (**changes))]
    fn replace(&self, py: Python<'_>, changes: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut out = Self {
            outcome: self.outcome.clone(),
            uncertainty: self.uncertainty.as_ref().map(|u| u.clone_ref(py)),
            decision: self.decision.clone(),
        };
        for (k, v) in changes.into_iter().flatten() {
            match k.extract::<String>()?.as_str() {
                "uncertainty" => out.uncertainty = (!v.is_none()).then(|| v.unbind()),
                "decision" => out.decision = v.extract()?,
                other => return Err(PyTypeError::new_err(format!("GageOutcome.replace: no field {other:?}"))),
            }
        }
        Ok(out)
    }
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (o, l) = (&self.outcome, &self.outcome.label);
        let d = PyDict::new(py);
        d.set_item("name", &l.name)?;
        d.set_item("region", &l.region)?;
        d.set_item("points", l.points)?;
        d.set_item("filtered_points", l.filtered_points)?;
        d.set_item("allowance_before", o.allowance_before)?;
        d.set_item("allowance_after", o.allowance_after)?;
        d.set_item("q", o.q)?;
        d.set_item("slack", o.slack)?;
        if let Some(u) = &self.uncertainty {
            d.set_item("uncertainty", u)?;
        }
        if let Some(x) = &self.decision {
            d.set_item("decision", x)?;
        }
        Ok(d)
    }
    fn __eq__(&self, py: Python<'_>, other: &Bound<'_, PyAny>) -> PyResult<bool> {
        let Ok(o) = other.extract::<PyRef<'_, GageOutcome>>() else { return Ok(false) };
        let same_u = match (&self.uncertainty, &o.uncertainty) {
            (None, None) => true,
            (Some(a), Some(b)) => a.bind(py).eq(b)?,
            _ => false,
        };
        Ok(o.outcome == self.outcome && o.decision == self.decision && same_u)
    }
    fn __repr__(&self) -> String {
        let (o, l) = (&self.outcome, &self.outcome.label);
        format!(
            "GageOutcome(name='{}', region='{}', allowance_before={:?}, allowance_after={:?}, q={:?}, slack={:?})",
            l.name, l.region, o.allowance_before, o.allowance_after, o.q, o.slack
        )
    }
}

/// The outcome of a virtual-gage check (Eq. 5.11 at T*; `gagekit_gage::result`): the
/// status ("conforming" when every slack is zero), the objective, T*, the limiting
/// motion bounds, each gage's outcome, the infeasible groups by gage name, u, and the
/// solver's re-linearisations, last step (mm) and LP status.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.gage")]
pub struct GageCheck(result::CheckResult);

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl GageCheck {
    #[getter]
    fn status(&self) -> &'static str {
        self.0.status
    }
    #[getter]
    fn objective(&self) -> f64 {
        self.0.objective
    }
    #[getter]
    fn transform(&self, py: Python<'_>) -> PyResult<Py<Transform>> {
        Py::new(py, Transform(self.0.transform))
    }
    #[getter]
    fn limited_by_motion_bounds(&self) -> bool {
        !self.0.bound_limits.is_empty()
    }
    #[getter]
    fn bound_limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, self.0.bound_limits.iter().map(|b| BoundLimit(b.clone())))
    }
    #[getter]
    fn gages<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(
            py,
            self.0.gages.iter().map(|g| GageOutcome { outcome: g.clone(), uncertainty: None, decision: None }),
        )
    }
    #[getter]
    fn infeasible_groups<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, self.0.infeasible_groups.iter().map(|g| PyTuple::new(py, g)).collect::<PyResult<Vec<_>>>()?)
    }
    #[getter]
    fn largest_release(&self) -> f64 {
        self.0.largest_release
    }
    #[getter]
    fn iterations(&self) -> usize {
        self.0.iterations
    }
    #[getter]
    fn last_step(&self) -> f64 {
        self.0.last_step
    }
    #[getter]
    fn lp_status(&self) -> &'static str {
        self.0.lp_status
    }
}

/// The virtual-gage check of Eq. 5.11 (the solve of `solve`, then the public result):
/// `gages` names each gage of the set in order, (name, region, points, filtered points).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gage"))]
#[pyfunction]
#[pyo3(signature = (points, offsets, planes, f, g, free, max_angle, max_shift, gages, tol=1e-10, slack_tol=1e-7, groups=true))]
#[allow(clippy::too_many_arguments)]
fn check<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    offsets: Vec<usize>,
    planes: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray1<'py, f64>,
    g: PyReadonlyArray1<'py, f64>,
    free: Vec<bool>,
    max_angle: f64,
    max_shift: f64,
    gages: Vec<(String, String, usize, usize)>,
    tol: f64,
    slack_tol: f64,
    groups: bool,
) -> PyResult<GageCheck> {
    let a = args(py, &points, offsets, &planes, &f, &g, free, max_angle, max_shift)?;
    let opts = Options { tol, slack_tol, ..Options::default() };
    let labels: Vec<result::GageLabel> = gages
        .into_iter()
        .map(|(name, region, points, filtered_points)| result::GageLabel { name, region, points, filtered_points })
        .collect();
    run(py, || {
        let set = a.set();
        let sol = gagekit_gage::solve(&set, &a.motion, &opts)?;
        let grp = if groups { gagekit_gage::infeasible_groups(&set, &a.motion, &opts, &sol)? } else { vec![] };
        result::CheckResult::new(sol, grp, labels.clone())
    })
    .map(GageCheck)
}

/// The LP of Eq. 5.11 linearised about given motions: minimise c.x subject to A x <= b,
/// x free, A in compressed-column form (colptr, rowval, nzval) with `nrows` rows.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core._testing")]
pub struct LinearProgram {
    c: Py<PyArray1<f64>>,
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    nzval: Py<PyArray1<f64>>,
    b: Py<PyArray1<f64>>,
    nrows: usize,
}

/// The solution of one LP of Eq. 5.11 (clarabel).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core._testing")]
pub struct LpResult {
    x: Py<PyArray1<f64>>,
    objective: f64,
    status: String,
    /// Rows of the LP actually solved (fewer than all with constraint generation).
    nrows: usize,
}

/// Test and benchmark binding: the LP of Eq. 5.11 linearised about `params`
/// (alpha, beta, gamma, dx, dy, dz), for comparisons with other LP solvers.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core._testing"))]
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn gage_lp<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    offsets: Vec<usize>,
    planes: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray1<'py, f64>,
    g: PyReadonlyArray1<'py, f64>,
    free: Vec<bool>,
    max_angle: f64,
    max_shift: f64,
    params: [f64; 6],
) -> PyResult<LinearProgram> {
    let a = args(py, &points, offsets, &planes, &f, &g, free, max_angle, max_shift)?;
    let lp = run(py, || gagekit_gage::assemble_checked(&a.set(), &a.motion, &params))?;
    Ok(LinearProgram {
        c: PyArray1::from_vec(py, lp.c).unbind(),
        colptr: lp.colptr,
        rowval: lp.rowval,
        nzval: PyArray1::from_vec(py, lp.nzval).unbind(),
        b: PyArray1::from_vec(py, lp.b).unbind(),
        nrows: lp.nrows,
    })
}

/// Test and benchmark binding: solve the single LP of `gage_lp` with clarabel (no
/// re-linearisation, no polish), by constraint generation above 4000 points unless
/// `generate` is false.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core._testing"))]
#[pyfunction]
#[pyo3(signature = (points, offsets, planes, f, g, free, max_angle, max_shift, params, generate=true))]
#[allow(clippy::too_many_arguments)]
fn gage_lp_solve<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    offsets: Vec<usize>,
    planes: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray1<'py, f64>,
    g: PyReadonlyArray1<'py, f64>,
    free: Vec<bool>,
    max_angle: f64,
    max_shift: f64,
    params: [f64; 6],
    generate: bool,
) -> PyResult<LpResult> {
    let a = args(py, &points, offsets, &planes, &f, &g, free, max_angle, max_shift)?;
    let (lp, sol) = run(py, || gagekit_gage::solve_single(&a.set(), &a.motion, &params, generate))?;
    Ok(LpResult {
        x: PyArray1::from_vec(py, sol.x).unbind(),
        objective: sol.objective,
        status: sol.status.to_string(),
        nrows: lp.nrows,
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<GageSolution>()?;
    m.add_function(wrap_pyfunction!(gage_solve, m)?)?;
    m.add_class::<GageCheck>()?;
    m.add_class::<GageOutcome>()?;
    m.add_class::<BoundLimit>()?;
    m.add_class::<Transform>()?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    Ok(())
}

/// The test-only bindings of this module, for `gagekit._core._testing`.
pub fn register_testing(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<LinearProgram>()?;
    m.add_class::<LpResult>()?;
    m.add_function(wrap_pyfunction!(gage_lp, m)?)?;
    m.add_function(wrap_pyfunction!(gage_lp_solve, m)?)?;
    Ok(())
}
