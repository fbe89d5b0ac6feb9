//! Bindings of gagekit-design: exchange search, design figures, Halton points.

use crate::arrays::{indices, rows, values};
use crate::errors::{gagekit_err, run};
use gagekit_design::{Criterion, Metrics, Options, Problem};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The stacked (n * r, k) design-matrix rows as a flat slice, with n and k.
fn blocks<'a>(
    py: Python<'_>,
    arr: &'a PyReadonlyArray2<'_, f64>,
    r: usize,
) -> PyResult<(&'a [f64], usize, usize)> {
    let shape = arr.shape();
    let k = shape[1];
    if r == 0 || shape[0] % r != 0 {
        return Err(gagekit_err(
            py,
            "InvalidInputError",
            format!(
                "design-matrix rows: {} rows do not split into blocks of {r}",
                shape[0]
            ),
        ));
    }
    Ok((rows(py, arr, k, "design-matrix rows")?, shape[0] / r, k))
}

fn metrics_dict<'py>(py: Python<'py>, m: &Metrics) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("trace", m.trace)?;
    d.set_item("log_det", m.log_det)?;
    d.set_item("condition_number", m.condition_number)?;
    d.set_item("lambda_min", m.lambda_min)?;
    d.set_item("lambda_max", m.lambda_max)?;
    d.set_item("i_value", m.i_value)?;
    d.set_item("rank", m.rank)?;
    Ok(d)
}

fn criterion(py: Python<'_>, name: &str) -> PyResult<Criterion> {
    name.parse::<Criterion>()
        .map_err(|e| crate::errors::to_pyerr(py, e))
}

/// Multistart point-exchange search (Eqs. 4.7, 4.8).
///
/// `blocks` is (N * r, k): candidate j owns rows j*r .. j*r + r. `groups[g]` lists the
/// candidates of zone g; design point i must stay in zone `point_group[i]`.
#[pyfunction]
#[pyo3(signature = (blocks, r, groups, point_group, criterion_name, weights=None, starts=8, max_sweeps=50, seed=0, initial=None))]
#[allow(clippy::too_many_arguments)]
fn design_search<'py>(
    py: Python<'py>,
    blocks: PyReadonlyArray2<'py, f64>,
    r: usize,
    groups: Vec<PyReadonlyArray1<'py, i64>>,
    point_group: Vec<usize>,
    criterion_name: &str,
    weights: Option<PyReadonlyArray2<'py, f64>>,
    starts: usize,
    max_sweeps: usize,
    seed: u64,
    initial: Option<Vec<usize>>,
) -> PyResult<Bound<'py, PyDict>> {
    let c = criterion(py, criterion_name)?;
    let (flat, n_cand, k) = self::blocks(py, &blocks, r)?;
    let mut gs = Vec::with_capacity(groups.len());
    for g in &groups {
        let s = values(py, g, "zone members")?;
        if s.iter().any(|&j| j < 0) {
            return Err(gagekit_err(
                py,
                "InvalidInputError",
                "negative candidate index in a zone".into(),
            ));
        }
        gs.push(s.iter().map(|&j| j as usize).collect());
    }
    let w = match &weights {
        Some(w) => Some(rows(py, w, k, "weight matrix")?),
        None => None,
    };
    let problem = Problem {
        blocks: flat,
        n_cand,
        r,
        k,
        groups: gs,
        point_group,
        weights: w,
    };
    let opts = Options {
        criterion: c,
        starts,
        max_sweeps,
        seed,
        initial,
    };
    let out = run(py, || gagekit_design::search(&problem, &opts))?;
    let d = PyDict::new(py);
    d.set_item("design", indices(py, out.design))?;
    d.set_item("objective", out.objective)?;
    d.set_item("start_objectives", out.start_objectives)?;
    d.set_item("exchanges", out.exchanges)?;
    d.set_item("metrics", metrics_dict(py, &out.metrics)?)?;
    Ok(d)
}

/// Exact figures of the design whose stacked rows are `blocks` ((n * r, k), any r).
#[pyfunction]
#[pyo3(signature = (blocks, weights=None))]
fn design_metrics<'py>(
    py: Python<'py>,
    blocks: PyReadonlyArray2<'py, f64>,
    weights: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (flat, n, k) = self::blocks(py, &blocks, 1)?;
    let w = match &weights {
        Some(w) => Some(rows(py, w, k, "weight matrix")?),
        None => None,
    };
    let m = run(py, || {
        if n == 0 || k == 0 {
            return Err(gagekit_core::GkError::invalid(
                "an empty design matrix has no figures",
            ));
        }
        gagekit_core::check_finite(flat, k, "design-matrix rows")?;
        let idx: Vec<usize> = (0..n).collect();
        Ok(gagekit_design::metrics(
            &gagekit_design::information(flat, &idx, 1, k),
            k,
            w,
        ))
    })?;
    metrics_dict(py, &m)
}

/// `n` shifted-Halton points in [0, 1)^d as an (n, d) array.
#[pyfunction]
#[pyo3(signature = (n, d, seed=0))]
fn design_halton<'py>(
    py: Python<'py>,
    n: usize,
    d: usize,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let v = run(py, || gagekit_design::halton(n, d, seed))?;
    Ok(PyArray1::from_vec(py, v).reshape([n, d])?.into_any())
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(design_search, m)?)?;
    m.add_function(wrap_pyfunction!(design_metrics, m)?)?;
    m.add_function(wrap_pyfunction!(design_halton, m)?)?;
    Ok(())
}
