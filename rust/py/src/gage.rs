//! Bindings of gagekit-gage: the virtual-gage LP of Eq. 5.11 (array conversion only).

use crate::arrays::{rows, values};
use crate::errors::{invalid, run};
use gagekit_gage::{GageSet, Motion, Options, MOTION_NAMES};
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

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
