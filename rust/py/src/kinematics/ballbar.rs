//! Binding of the ballbar analysis (ISO 230-4): converts arrays, returns a frozen result.

use crate::arrays::values;
use crate::errors::run;
use gagekit_kinematics::ballbar::{analyse, BallbarInput, CircleFit};
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;

/// A least-squares circle of ballbar readings: centre (mm, about the pivot), radius
/// deviation (mm), circular deviation G (mm), number of readings.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.kinematics")]
pub struct BallbarCircle {
    centre: (f64, f64),
    radius_deviation: f64,
    g: f64,
    n: usize,
}

fn circle(c: CircleFit) -> BallbarCircle {
    BallbarCircle { centre: (c.centre[0], c.centre[1]), radius_deviation: c.radius_deviation, g: c.g, n: c.n }
}

/// Everything a ballbar test gives (mm, rad, s); see `gagekit_kinematics::ballbar`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.kinematics")]
pub struct BallbarAnalysis {
    both: Py<BallbarCircle>,
    ccw: Option<Py<BallbarCircle>>,
    cw: Option<Py<BallbarCircle>>,
    f_max: f64,
    f_min: f64,
    hysteresis: Option<f64>,
    radius_term: f64,
    squareness: f64,
    squareness_fraction: f64,
    scale_mismatch: f64,
    scale_fraction: f64,
    servo_lag: Option<f64>,
    servo_mismatch: Option<f64>,
    servo_fraction: Option<f64>,
    /// [[axis 1 ccw, axis 1 cw], [axis 2 ccw, axis 2 cw]]
    backlash: Vec<Vec<Option<f64>>>,
    backlash_fraction: Vec<f64>,
    centre_fraction: f64,
    cyclic: Option<Vec<f64>>,
    cyclic_fraction: Option<Vec<f64>>,
    pitch: Option<f64>,
    /// [[axis 1 positive end, negative end], [axis 2 ...]]
    spikes: Vec<Vec<f64>>,
    residual_rms: f64,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.kinematics"))]
#[pyfunction]
#[pyo3(name = "ballbar")]
#[pyo3(signature = (radius, angles, deviations, directions, pitch=None, feed=None))]
fn machine_ballbar<'py>(
    py: Python<'py>,
    radius: f64,
    angles: PyReadonlyArray1<'py, f64>,
    deviations: PyReadonlyArray1<'py, f64>,
    directions: PyReadonlyArray1<'py, i8>,
    pitch: Option<f64>,
    feed: Option<f64>,
) -> PyResult<BallbarAnalysis> {
    let a = values(py, &angles, "angles")?;
    let d = values(py, &deviations, "deviations")?;
    let s = values(py, &directions, "directions")?;
    let r = run(py, || analyse(&BallbarInput { radius, angles: a, deviations: d, directions: s, pitch, feed }))?;
    let opt = |c: Option<CircleFit>| c.map(|c| Py::new(py, circle(c))).transpose();
    Ok(BallbarAnalysis {
        both: Py::new(py, circle(r.both))?,
        ccw: opt(r.ccw)?,
        cw: opt(r.cw)?,
        f_max: r.f_max,
        f_min: r.f_min,
        hysteresis: r.hysteresis,
        radius_term: r.radius_term,
        squareness: r.squareness,
        squareness_fraction: r.squareness_fraction,
        scale_mismatch: r.scale_mismatch,
        scale_fraction: r.scale_fraction,
        servo_lag: r.servo_lag,
        servo_mismatch: r.servo_mismatch,
        servo_fraction: r.servo_fraction,
        backlash: r.backlash.iter().map(|a| a.to_vec()).collect(),
        backlash_fraction: r.backlash_fraction.to_vec(),
        centre_fraction: r.centre_fraction,
        cyclic: r.cyclic.map(|c| c.to_vec()),
        cyclic_fraction: r.cyclic_fraction.map(|c| c.to_vec()),
        pitch: r.pitch,
        spikes: r.spikes.iter().map(|a| a.to_vec()).collect(),
        residual_rms: r.residual_rms,
    })
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<BallbarCircle>()?;
    m.add_class::<BallbarAnalysis>()?;
    m.add_function(wrap_pyfunction!(machine_ballbar, m)?)?;
    Ok(())
}
