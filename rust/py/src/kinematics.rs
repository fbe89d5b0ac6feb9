//! Bindings of gagekit-kinematics. A chain crosses the boundary as a list of
//! `(kind, vector, terms)` tuples (kind "shape" with its offset, "prismatic" or "rotary" with
//! its axis; terms = Fourier terms of a rotary joint, else 0) and the tool offset.

use crate::arrays::{rows, values};
use crate::errors::{gagekit_err, run};
use gagekit_kinematics::{identifiability, lstsq, rigid_fit, Element, Machine};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

pub(crate) type Spec = Vec<(String, [f64; 3], usize)>;

pub(crate) fn machine(py: Python<'_>, spec: Spec, tool: [f64; 3]) -> PyResult<Machine> {
    let mut elements = Vec::with_capacity(spec.len());
    for (k, (kind, v, terms)) in spec.into_iter().enumerate() {
        elements.push(match kind.as_str() {
            "shape" => Element::Shape { offset: v },
            "prismatic" => Element::Prismatic { axis: v },
            "rotary" => Element::Rotary { axis: v, terms },
            other => {
                return Err(gagekit_err(py, "ConfigError", format!("chain element {k}: unknown kind '{other}'")))
            }
        });
    }
    run(py, || Machine::new(elements, tool))
}

fn matrix<'py>(py: Python<'py>, v: Vec<f64>, ncols: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let nrows = if ncols == 0 { 0 } else { v.len() / ncols };
    PyArray1::from_vec(py, v).reshape([nrows, ncols])
}

/// Labels of the parameters: list of (element index, name, length power), design-matrix order.
#[pyfunction]
fn machine_parameter_labels(py: Python<'_>, spec: Spec, tool: [f64; 3]) -> PyResult<Vec<(usize, String, u8)>> {
    let m = machine(py, spec, tool)?;
    Ok(m.param_labels().into_iter().map(|l| (l.element, l.name, l.length_power)).collect())
}

/// Nominal target positions (n, 3) in the table frame (Eq. 3.1); commands (n, J), rad for rotary.
#[pyfunction]
fn machine_nominal<'py>(
    py: Python<'py>,
    spec: Spec,
    tool: [f64; 3],
    commands: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = machine(py, spec, tool)?;
    let c = rows(py, &commands, m.n_joints(), "commands")?;
    let out = run(py, || m.nominal_positions(c))?;
    matrix(py, out, 3)
}

/// Target positions (n, 3) of the exactly perturbed chain (Eq. 3.7) for parameters (P,).
#[pyfunction]
fn machine_exact<'py>(
    py: Python<'py>,
    spec: Spec,
    tool: [f64; 3],
    commands: PyReadonlyArray2<'py, f64>,
    params: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = machine(py, spec, tool)?;
    let c = rows(py, &commands, m.n_joints(), "commands")?;
    let p = values(py, &params, "parameters")?;
    let out = run(py, || m.exact_positions(c, p))?;
    matrix(py, out, 3)
}

/// The design matrix (3n, P) of Eq. 3.13, assembled in parallel.
#[pyfunction]
fn machine_design_matrix<'py>(
    py: Python<'py>,
    spec: Spec,
    tool: [f64; 3],
    commands: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = machine(py, spec, tool)?;
    let c = rows(py, &commands, m.n_joints(), "commands")?;
    let out = run(py, || m.design_matrix(c))?;
    matrix(py, out, m.n_params())
}

/// Jacobian (3n, J) of the nominal target position with respect to the commands.
#[pyfunction]
fn machine_command_jacobian<'py>(
    py: Python<'py>,
    spec: Spec,
    tool: [f64; 3],
    commands: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = machine(py, spec, tool)?;
    let c = rows(py, &commands, m.n_joints(), "commands")?;
    let out = run(py, || m.command_jacobian(c))?;
    matrix(py, out, m.n_joints())
}

/// Identifiability of a design matrix (Eq. 3.14): dict with rank, singular_values,
/// no_effect, leaders, coefficients (rank, P), reconstruction_error.
#[pyfunction]
#[pyo3(signature = (design, length_scale, length_power, rtol=1e-9, no_effect_tol=1e-12))]
fn machine_identifiability<'py>(
    py: Python<'py>,
    design: PyReadonlyArray2<'py, f64>,
    length_scale: f64,
    length_power: Vec<u8>,
    rtol: f64,
    no_effect_tol: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let shape = design.shape();
    let (n, p) = (shape[0], shape[1]);
    let a = rows(py, &design, p, "design matrix")?;
    let r = run(py, || identifiability(a, n, p, length_scale, &length_power, rtol, no_effect_tol))?;
    let d = PyDict::new(py);
    d.set_item("rank", r.rank)?;
    d.set_item("singular_values", PyArray1::from_vec(py, r.singular_values))?;
    d.set_item("no_effect", r.no_effect)?;
    d.set_item("leaders", r.leaders)?;
    d.set_item("coefficients", matrix(py, r.coefficients, p)?)?;
    d.set_item("reconstruction_error", r.reconstruction_error)?;
    Ok(d)
}

/// Least squares by SVD of the column-equilibrated matrix: dict with x, cov_unscaled
/// ((A^T A)^-1), rss, singular_values, condition_number, weakest.
#[pyfunction]
fn machine_lstsq<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'py, f64>,
    b: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let shape = a.shape();
    let (n, k) = (shape[0], shape[1]);
    let av = rows(py, &a, k, "design matrix")?;
    let bv = values(py, &b, "observations")?;
    let r = run(py, || lstsq(av, n, k, bv))?;
    let d = PyDict::new(py);
    d.set_item("x", PyArray1::from_vec(py, r.x))?;
    d.set_item("cov_unscaled", matrix(py, r.cov_unscaled, k)?)?;
    d.set_item("rss", r.rss)?;
    d.set_item("singular_values", PyArray1::from_vec(py, r.singular_values))?;
    d.set_item("condition_number", r.condition_number)?;
    d.set_item("weakest", PyArray1::from_vec(py, r.weakest))?;
    Ok(d)
}

/// Closed-form rigid fit dst ~ R src + t: (R (3, 3), t (3,), rms).
#[pyfunction]
fn machine_rigid_fit<'py>(
    py: Python<'py>,
    src: PyReadonlyArray2<'py, f64>,
    dst: PyReadonlyArray2<'py, f64>,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>, f64)> {
    let s = rows(py, &src, 3, "nominal positions")?;
    let d = rows(py, &dst, 3, "measured positions")?;
    let r = run(py, || rigid_fit(s, d))?;
    Ok((matrix(py, r.rotation.to_vec(), 3)?, PyArray1::from_vec(py, r.translation.to_vec()), r.rms))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(machine_parameter_labels, m)?)?;
    m.add_function(wrap_pyfunction!(machine_nominal, m)?)?;
    m.add_function(wrap_pyfunction!(machine_exact, m)?)?;
    m.add_function(wrap_pyfunction!(machine_design_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(machine_command_jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(machine_identifiability, m)?)?;
    m.add_function(wrap_pyfunction!(machine_lstsq, m)?)?;
    m.add_function(wrap_pyfunction!(machine_rigid_fit, m)?)?;
    Ok(())
}
