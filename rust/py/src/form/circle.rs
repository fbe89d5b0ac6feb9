//! Planar circle fits (Sec. 6.2): least squares, minimum zone, MC, MI, and the swarm search.

use super::*;

use gagekit_form::circle;
use gagekit_form::criterion::FitCriterion;

/// A 2-D circle fit, complete (Sec. 6.2): the fields of the kernel's
/// [`circle::CircleFit`] (centre, radius, `r_in` / `r_out`: the zone for the minimum zone,
/// else the certificate; control points; arc in rad, its centre, the ill-posed flag), read
/// through [`mirror!`], plus the criterion's canonical name and `form_error`.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.form")]
pub struct CircleResult {
    fit: circle::CircleFit,
}

mirror!(CircleResult {
    center, radius, r_in, r_out, control, control_in, control_out, arc, arc_center, ill_posed
} extra {
    #[getter]
    fn criterion(&self) -> &'static str {
        self.fit.criterion.name()
    }
    #[getter]
    fn form_error(&self) -> f64 {
        self.fit.form_error()
    }
});

impl From<circle::CircleFit> for CircleResult {
    fn from(fit: circle::CircleFit) -> Self {
        Self { fit }
    }
}

/// Circle of (n, 2) points by the exact kernels: `criterion` is any name of the
/// criterion table (least squares, MC Eq. 6.1, MI Eq. 6.2, MZ Eqs. 6.5-6.8).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "circle_fit")]
fn form_circle_fit(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, criterion: &str) -> PyResult<CircleResult> {
    let pts = rows(py, &points, 2, "points")?;
    run(py, || {
        let crit = FitCriterion::parse_for(criterion, &FitCriterion::ALL, "circle")?;
        circle::fit(pts, crit)
    })
    .map(CircleResult::from)
}

/// Minimum-zone circle of (n, 2) points on an active set started near `center`, exact by
/// verification on every point (`gagekit_gdt::plan::active`).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "circle_fit_near")]
fn form_circle_fit_near(py: Python<'_>, points: PyReadonlyArray2<'_, f64>, center: [f64; 2]) -> PyResult<CircleResult> {
    let pts = rows(py, &points, 2, "points")?;
    run(py, || {
        gagekit_core::check_finite(pts, 2, "points")?;
        gagekit_gdt::plan::active::circle_near(pts, center)
    })
    .map(CircleResult::from)
}

/// 2-D circle by the PSO over the centre (Eqs. 6.1, 6.4, 6.5; a cross-check of the
/// exact kernels) for MC, MI or MZ.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.form"))]
#[pyfunction]
#[pyo3(name = "circle_pso")]
#[pyo3(signature = (points, criterion, seed=0, particles=20, max_iterations=2000, stall_iterations=100))]
fn form_circle_pso(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    criterion: &str,
    seed: u64,
    particles: usize,
    max_iterations: usize,
    stall_iterations: usize,
) -> PyResult<CircleResult> {
    use gagekit_form::circle_pso::{fit, Kind};
    let pts = rows(py, &points, 2, "points")?;
    let settings = gagekit_pso::Settings { seed, particles, max_iterations, stall_iterations, ..Default::default() };
    run(py, || {
        let allowed = [FitCriterion::MinCircumscribed, FitCriterion::MaxInscribed, FitCriterion::MinZone];
        let crit = FitCriterion::parse_for(criterion, &allowed, "circle (PSO)")?;
        let kind = match crit {
            FitCriterion::MinCircumscribed => Kind::MinCircumscribed,
            FitCriterion::MaxInscribed => Kind::MaxInscribed,
            _ => Kind::MinZone,
        };
        circle::from_zone(pts, crit, fit(pts, kind, &settings)?.zone)
    })
    .map(CircleResult::from)
}

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<CircleResult>()?;
    m.add_function(wrap_pyfunction!(form_circle_fit, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle_fit_near, m)?)?;
    m.add_function(wrap_pyfunction!(form_circle_pso, m)?)?;
    Ok(())
}

