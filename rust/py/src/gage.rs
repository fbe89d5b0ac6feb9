//! Bindings of gagekit-gage: the virtual-gage LP of Eq. 5.11 (array conversion only).

use crate::arrays::{rows, values};
use crate::errors::{gagekit_err, run};
use gagekit_gage::{GageSet, Motion, Options, MOTION_NAMES};
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

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
    let invalid = |m: &str| gagekit_err(py, "InvalidInputError", m.to_string());
    let free: [bool; 6] = free.try_into().map_err(|_| invalid("free: expected six flags (alpha, beta, gamma, dx, dy, dz)"))?;
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

/// Solve Eq. 5.11 with exact re-linearisation; optionally the infeasible groups (Eq. 5.10).
/// Returns a dict of plain lists and numbers.
#[pyfunction]
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
) -> PyResult<Bound<'py, PyDict>> {
    let a = args(py, &points, offsets, &planes, &f, &g, free, max_angle, max_shift)?;
    let opts = Options { tol, slack_tol, ..Options::default() };
    let (sol, grp) = run(py, || {
        let set = a.set();
        let sol = gagekit_gage::solve(&set, &a.motion, &opts)?;
        let grp = if groups { gagekit_gage::infeasible_groups(&set, &a.motion, &opts, &sol)? } else { vec![] };
        Ok((sol, grp))
    })?;
    let d = PyDict::new(py);
    d.set_item("params", sol.params.to_vec())?;
    d.set_item("matrix", sol.matrix.iter().map(|r| r.to_vec()).collect::<Vec<_>>())?;
    d.set_item("allowance_before", sol.allowance_before)?;
    d.set_item("allowance_after", sol.allowance_after)?;
    d.set_item("q", sol.q)?;
    d.set_item("s", sol.s)?;
    d.set_item("u", sol.u)?;
    d.set_item("objective", sol.objective)?;
    d.set_item("lp_objective", sol.lp_objective)?;
    d.set_item("iterations", sol.iterations)?;
    d.set_item("last_step", sol.last_step)?;
    d.set_item("lp_status", sol.lp_status)?;
    let bounds: Vec<(String, String, f64)> = sol
        .active_bounds
        .iter()
        .map(|b| (MOTION_NAMES[b.motion].to_string(), if b.side > 0 { "upper" } else { "lower" }.to_string(), b.dual))
        .collect();
    d.set_item("active_bounds", bounds)?;
    d.set_item("groups", grp)?;
    Ok(d)
}

/// The LP of Eq. 5.11 linearised about `params` (alpha, beta, gamma, dx, dy, dz), as
/// (c, colptr, rowval, nzval, b, nrows): minimise c.x subject to A x <= b, x free.
/// For comparisons with other LP solvers; `gage_lp_solve` solves the same LP.
#[pyfunction]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
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
) -> PyResult<(Vec<f64>, Vec<usize>, Vec<usize>, Vec<f64>, Vec<f64>, usize)> {
    let a = args(py, &points, offsets, &planes, &f, &g, free, max_angle, max_shift)?;
    let lp = run(py, || {
        a.set().validate(&a.motion)?;
        Ok(gagekit_gage::assemble(&a.set(), &a.motion, &params, None))
    })?;
    Ok((lp.c, lp.colptr, lp.rowval, lp.nzval, lp.b, lp.nrows))
}

/// Solve the single LP of `gage_lp` with clarabel (no re-linearisation, no polish),
/// by constraint generation above 4000 points unless `generate` is false:
/// returns (x, objective, status, rows of the LP solved).
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
) -> PyResult<(Vec<f64>, f64, String, usize)> {
    let a = args(py, &points, offsets, &planes, &f, &g, free, max_angle, max_shift)?;
    let (lp, sol) = run(py, || {
        let set = a.set();
        set.validate(&a.motion)?;
        if generate {
            gagekit_gage::solve_linearised(&set, &a.motion, &params, None, set.radius(), false)
        } else {
            let lp = gagekit_gage::assemble(&set, &a.motion, &params, None);
            let sol = gagekit_gage::solve_lp(&lp)?;
            Ok((lp, sol))
        }
    })?;
    Ok((sol.x, sol.objective, sol.status.to_string(), lp.nrows))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(gage_solve, m)?)?;
    m.add_function(wrap_pyfunction!(gage_lp, m)?)?;
    m.add_function(wrap_pyfunction!(gage_lp_solve, m)?)?;
    Ok(())
}
