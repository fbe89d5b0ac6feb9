//! Bindings of gagekit-design: exchange search, design figures, Halton points.

use crate::arrays::{indices, rows, values};
use crate::errors::{invalid, run, to_pyerr};
use gagekit_design::{Criterion, Metrics, Options, Problem};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// The stacked (n * r, k) design-matrix rows as a flat slice, with n and k.
fn blocks<'a>(py: Python<'_>, arr: &'a PyReadonlyArray2<'_, f64>, r: usize) -> PyResult<(&'a [f64], usize, usize)> {
    let shape = arr.shape();
    let k = shape[1];
    if r == 0 || shape[0] % r != 0 {
        return Err(invalid(format!("design-matrix rows: {} rows do not split into blocks of {r}", shape[0])));
    }
    Ok((rows(py, arr, k, "design-matrix rows")?, shape[0] / r, k))
}

fn criterion(name: &str) -> PyResult<Criterion> {
    name.parse::<Criterion>().map_err(to_pyerr)
}

/// Exact figures of a design's information matrix F = M^T M (Eqs. 4.3-4.5).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.design")]
pub struct DesignMetrics {
    /// tr(F^-1) (inf when F is singular).
    trace: f64,
    /// log det(F^-1) (inf when F is singular).
    log_det: f64,
    /// sqrt(l_max / l_min) of F: the singular-value ratio of M (ERRATA item 2).
    condition_number: f64,
    lambda_min: f64,
    lambda_max: f64,
    /// tr(W F^-1) when a weight matrix was given.
    i_value: Option<f64>,
    rank: usize,
}

impl From<Metrics> for DesignMetrics {
    fn from(m: Metrics) -> Self {
        Self {
            trace: m.trace,
            log_det: m.log_det,
            condition_number: m.condition_number,
            lambda_min: m.lambda_min,
            lambda_max: m.lambda_max,
            i_value: m.i_value,
            rank: m.rank,
        }
    }
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl DesignMetrics {
    /// The value a search minimises for criterion A, D, K, E or I (inf where undefined).
    fn objective(&self, criterion_name: &str) -> PyResult<f64> {
        let m = Metrics {
            trace: self.trace,
            log_det: self.log_det,
            condition_number: self.condition_number,
            lambda_min: self.lambda_min,
            lambda_max: self.lambda_max,
            i_value: self.i_value,
            rank: self.rank,
        };
        Ok(m.objective(criterion(criterion_name)?))
    }
}

/// The outcome of a multistart exchange search.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.design")]
pub struct DesignSearch {
    /// Candidate index of each design point.
    design: Py<PyArray1<i64>>,
    objective: f64,
    /// The objective reached by each start.
    start_objectives: Vec<f64>,
    /// Exchanges made by the best start.
    exchanges: usize,
    metrics: Py<DesignMetrics>,
}

/// Multistart point-exchange search (Eqs. 4.7, 4.8).
///
/// `blocks` is (N * r, k): candidate j owns rows j*r .. j*r + r. `groups[g]` lists the
/// candidates of zone g; design point i must stay in zone `point_group[i]`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.design"))]
#[pyfunction]
#[pyo3(name = "search")]
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
) -> PyResult<DesignSearch> {
    let c = criterion(criterion_name)?;
    let (flat, n_cand, k) = self::blocks(py, &blocks, r)?;
    let mut gs = Vec::with_capacity(groups.len());
    for g in &groups {
        let s = values(py, g, "zone members")?;
        if s.iter().any(|&j| j < 0) {
            return Err(invalid("negative candidate index in a zone"));
        }
        gs.push(s.iter().map(|&j| j as usize).collect());
    }
    let w = match &weights {
        Some(w) => Some(rows(py, w, k, "weight matrix")?),
        None => None,
    };
    let problem = Problem { blocks: flat, n_cand, r, k, groups: gs, point_group, weights: w };
    let opts = Options { criterion: c, starts, max_sweeps, seed, initial };
    let out = run(py, || gagekit_design::search(&problem, &opts))?;
    Ok(DesignSearch {
        design: indices(py, out.design).unbind(),
        objective: out.objective,
        start_objectives: out.start_objectives,
        exchanges: out.exchanges,
        metrics: Py::new(py, DesignMetrics::from(out.metrics))?,
    })
}

/// Exact figures of the design whose stacked rows are `blocks` ((n * r, k), any r).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.design"))]
#[pyfunction]
#[pyo3(name = "metrics")]
#[pyo3(signature = (blocks, weights=None))]
fn design_metrics<'py>(
    py: Python<'py>,
    blocks: PyReadonlyArray2<'py, f64>,
    weights: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<DesignMetrics> {
    let k = blocks.shape()[1];
    let flat = rows(py, &blocks, k, "design-matrix rows")?;
    let w = match &weights {
        Some(w) => Some(rows(py, w, k, "weight matrix")?),
        None => None,
    };
    Ok(run(py, || gagekit_design::design_metrics(flat, k, w))?.into())
}

/// `n` shifted-Halton points in [0, 1)^d as an (n, d) array.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.design"))]
#[pyfunction]
#[pyo3(name = "halton")]
#[pyo3(signature = (n, d, seed=0))]
fn design_halton<'py>(py: Python<'py>, n: usize, d: usize, seed: u64) -> PyResult<Bound<'py, PyAny>> {
    let v = run(py, || gagekit_design::halton(n, d, seed))?;
    Ok(PyArray1::from_vec(py, v).reshape([n, d])?.into_any())
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<DesignMetrics>()?;
    m.add_class::<DesignSearch>()?;
    m.add_function(wrap_pyfunction!(design_search, m)?)?;
    m.add_function(wrap_pyfunction!(design_metrics, m)?)?;
    m.add_function(wrap_pyfunction!(design_halton, m)?)?;
    Ok(())
}
