//! Bindings of gagekit-nc (corrected G-code programs) and of the inverse error model.

use crate::arrays::{matrix, rows, values};
use crate::errors::run;
use crate::kinematics::KinematicChain;
use gagekit_nc::{compensate_program, Options, Settings};
use numpy::{PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

/// Corrected commands (n, J) and predicted error left (n, 3) of the inverse first-order model:
/// only `joints` move; rotary commands in rad.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.nc"))]
#[pyfunction]
#[pyo3(name = "compensate_commands")]
fn machine_compensate<'py>(
    py: Python<'py>,
    chain: &Bound<'py, KinematicChain>,
    commands: PyReadonlyArray2<'py, f64>,
    params: PyReadonlyArray1<'py, f64>,
    joints: Vec<usize>,
    iterations: usize,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
    let m = chain.get().chain();
    let nj = m.n_joints();
    let c = rows(py, &commands, nj, "commands")?;
    let p = values(py, &params, "parameters")?;
    let (out, left) = run(py, || m.compensate(c, p, &joints, iterations))?;
    Ok((matrix(py, out, nj)?, matrix(py, left, 3)?))
}

/// Correct a G-code program (bytes); returns (bytes, report dict).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.nc"))]
#[pyfunction]
#[pyo3(name = "compensate_program")]
#[pyo3(signature = (chain, params, text, letters, unit, start, joints, max_step, decimals, header, arc_tolerance=None, iterations=4, ranges=Vec::new()))]
#[allow(clippy::too_many_arguments)]
fn nc_compensate<'py>(
    py: Python<'py>,
    chain: &Bound<'py, KinematicChain>,
    params: PyReadonlyArray1<'py, f64>,
    text: &Bound<'py, PyBytes>,
    letters: String,
    unit: Vec<f64>,
    start: Vec<Option<f64>>,
    joints: Vec<usize>,
    max_step: f64,
    decimals: usize,
    header: String,
    arc_tolerance: Option<f64>,
    iterations: usize,
    ranges: Vec<(f64, f64)>,
) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyDict>)> {
    let m = chain.get().chain();
    let p = values(py, &params, "parameters")?;
    let settings = Settings {
        options: Options { letters: letters.into_bytes(), start, arc_tolerance },
        unit,
        joints,
        max_step,
        decimals,
        header,
        iterations,
        ranges,
    };
    let text = text.as_bytes();
    let (out, r) = run(py, || compensate_program(text, m, p, &settings))?;
    let d = PyDict::new(py);
    d.set_item("lines", r.lines)?;
    d.set_item("lines_written", r.lines_written)?;
    d.set_item("order", r.order)?;
    let outside: Vec<(usize, usize, usize)> = r.outside.iter().map(|o| (o.joint, o.count, o.first_line)).collect();
    d.set_item("outside", outside)?;
    d.set_item("moves", r.moves)?;
    d.set_item("inserted", r.inserted)?;
    d.set_item("subdivided", r.subdivided)?;
    d.set_item("max_correction", r.max_correction)?;
    d.set_item("max_remaining", r.max_remaining)?;
    Ok((PyBytes::new(py, &out), d))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(machine_compensate, m)?)?;
    m.add_function(wrap_pyfunction!(nc_compensate, m)?)?;
    Ok(())
}
