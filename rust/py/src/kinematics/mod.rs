//! Bindings of gagekit-kinematics. A chain crosses the boundary once, when a machine file is
//! loaded: [`KinematicChain`] holds the validated Rust `Machine` and its parameter labels;
//! every later call passes only commands. The chain is given as a list of
//! `(kind, vector, terms)` tuples (kind "shape" with its offset, "prismatic" or "rotary" with
//! its axis; terms = Fourier terms of a rotary joint, else 0) and the tool offset.

use crate::arrays::{matrix, rows, values};
use crate::errors::run;
use gagekit_core::GkError;
use gagekit_kinematics::{identifiability, lstsq, rigid_fit, Element, Machine};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

type Spec = Vec<(String, [f64; 3], usize)>;

fn elements(spec: Spec) -> gagekit_core::Result<Vec<Element>> {
    spec.into_iter()
        .enumerate()
        .map(|(k, (kind, v, terms))| match kind.as_str() {
            "shape" => Ok(Element::Shape { offset: v }),
            "prismatic" => Ok(Element::Prismatic { axis: v }),
            "rotary" => Ok(Element::Rotary { axis: v, terms }),
            other => Err(GkError::config(format!("chain element {k}: unknown kind '{other}'"))),
        })
        .collect()
}

/// A validated kinematic chain (Eq. 3.1), built once per machine file.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.kinematics")]
pub struct KinematicChain {
    machine: Machine,
    /// (element index, parameter name, length power) in design-matrix column order.
    #[pyo3(get)]
    parameter_labels: Vec<(usize, String, u8)>,
    #[pyo3(get)]
    n_joints: usize,
    #[pyo3(get)]
    n_parameters: usize,
}

impl KinematicChain {
    /// The validated Rust chain (for the other binding modules, e.g. `nc`).
    pub(crate) fn chain(&self) -> &Machine {
        &self.machine
    }
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl KinematicChain {
    #[new]
    fn new(py: Python<'_>, spec: Spec, tool: [f64; 3]) -> PyResult<Self> {
        let machine = run(py, || Machine::new(elements(spec.clone())?, tool))?;
        let parameter_labels =
            machine.param_labels().into_iter().map(|l| (l.element, l.name, l.length_power)).collect();
        Ok(Self { n_joints: machine.n_joints(), n_parameters: machine.n_params(), machine, parameter_labels })
    }

    /// Nominal target positions (n, 3) in the table frame (Eq. 3.1); commands (n, J), rad for rotary.
    fn nominal<'py>(&self, py: Python<'py>, commands: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let c = rows(py, &commands, self.n_joints, "commands")?;
        matrix(py, run(py, || self.machine.nominal_positions(c))?, 3)
    }

    /// Target positions (n, 3) of the exactly perturbed chain (Eq. 3.7) for parameters (P,).
    fn exact<'py>(
        &self,
        py: Python<'py>,
        commands: PyReadonlyArray2<'py, f64>,
        params: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let c = rows(py, &commands, self.n_joints, "commands")?;
        let p = values(py, &params, "parameters")?;
        matrix(py, run(py, || self.machine.exact_positions(c, p))?, 3)
    }

    /// The design matrix (3n, P) of Eq. 3.13, assembled in parallel.
    fn design_matrix<'py>(&self, py: Python<'py>, commands: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let c = rows(py, &commands, self.n_joints, "commands")?;
        matrix(py, run(py, || self.machine.design_matrix(c))?, self.n_parameters)
    }

    /// Jacobian (3n, J) of the nominal target position with respect to the commands.
    fn command_jacobian<'py>(&self, py: Python<'py>, commands: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let c = rows(py, &commands, self.n_joints, "commands")?;
        matrix(py, run(py, || self.machine.command_jacobian(c))?, self.n_joints)
    }
}

/// Identifiability of a design matrix (Eq. 3.14).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.kinematics")]
pub struct Identifiability {
    /// Numerical rank of the column-equilibrated matrix.
    rank: usize,
    singular_values: Py<PyArray1<f64>>,
    /// Columns with no effect on the volumetric error.
    no_effect: Vec<usize>,
    /// Leader column of each group (ordered pivoted QR).
    leaders: Vec<usize>,
    /// (rank, P) coefficients of each group in the parameters' own units.
    coefficients: Py<PyArray2<f64>>,
    reconstruction_error: f64,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.kinematics"))]
#[pyfunction]
#[pyo3(name = "identifiability")]
#[pyo3(signature = (design, length_scale, length_power, rtol=1e-9, no_effect_tol=1e-12))]
fn machine_identifiability<'py>(
    py: Python<'py>,
    design: PyReadonlyArray2<'py, f64>,
    length_scale: f64,
    length_power: Vec<u8>,
    rtol: f64,
    no_effect_tol: f64,
) -> PyResult<Identifiability> {
    let shape = design.shape();
    let (n, p) = (shape[0], shape[1]);
    let a = rows(py, &design, p, "design matrix")?;
    let r = run(py, || identifiability(a, n, p, length_scale, &length_power, rtol, no_effect_tol))?;
    Ok(Identifiability {
        rank: r.rank,
        singular_values: PyArray1::from_vec(py, r.singular_values).unbind(),
        no_effect: r.no_effect,
        leaders: r.leaders,
        coefficients: matrix(py, r.coefficients, p)?.unbind(),
        reconstruction_error: r.reconstruction_error,
    })
}

/// Least squares by SVD of the column-equilibrated matrix.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.kinematics")]
pub struct LeastSquares {
    x: Py<PyArray1<f64>>,
    /// (A^T A)^-1, to be scaled by sigma^2.
    cov_unscaled: Py<PyArray2<f64>>,
    /// Residual sum of squares.
    rss: f64,
    singular_values: Py<PyArray1<f64>>,
    condition_number: f64,
    /// Right singular vector of the smallest singular value (the weakest combination).
    weakest: Py<PyArray1<f64>>,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.kinematics"))]
#[pyfunction]
#[pyo3(name = "lstsq")]
fn machine_lstsq<'py>(py: Python<'py>, a: PyReadonlyArray2<'py, f64>, b: PyReadonlyArray1<'py, f64>) -> PyResult<LeastSquares> {
    let shape = a.shape();
    let (n, k) = (shape[0], shape[1]);
    let av = rows(py, &a, k, "design matrix")?;
    let bv = values(py, &b, "observations")?;
    let r = run(py, || lstsq(av, n, k, bv))?;
    Ok(LeastSquares {
        x: PyArray1::from_vec(py, r.x).unbind(),
        cov_unscaled: matrix(py, r.cov_unscaled, k)?.unbind(),
        rss: r.rss,
        singular_values: PyArray1::from_vec(py, r.singular_values).unbind(),
        condition_number: r.condition_number,
        weakest: PyArray1::from_vec(py, r.weakest).unbind(),
    })
}

/// Closed-form rigid fit dst ~ rotation @ src + translation (Kabsch/Horn).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.kinematics")]
pub struct RigidTransform {
    rotation: Py<PyArray2<f64>>,
    translation: Py<PyArray1<f64>>,
    rms: f64,
}

/// Leave-one-cycle-out error sums of the temperature ridge model, one per strength
/// (`gagekit_kinematics::ridge::loo_errors`): temperatures (k, S), groups (k, G), residuals
/// (k, 3n), reduced design matrix (3n, G).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.kinematics"))]
#[pyfunction]
fn tracking_loo_errors<'py>(
    py: Python<'py>,
    temperatures: PyReadonlyArray2<'py, f64>,
    groups: PyReadonlyArray2<'py, f64>,
    residuals: PyReadonlyArray2<'py, f64>,
    design: PyReadonlyArray2<'py, f64>,
    lambdas: Vec<f64>,
) -> PyResult<Vec<f64>> {
    let (k, s) = (temperatures.shape()[0], temperatures.shape()[1]);
    let g = groups.shape()[1];
    let t = rows(py, &temperatures, s, "temperatures")?;
    let p = rows(py, &groups, g, "groups")?;
    let r = rows(py, &residuals, residuals.shape()[1], "residuals")?;
    let m = rows(py, &design, g, "design matrix")?;
    run(py, || gagekit_kinematics::ridge::loo_errors(t, p, r, m, k, s, g, &lambdas))
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.kinematics"))]
#[pyfunction]
#[pyo3(name = "rigid_fit")]
fn machine_rigid_fit<'py>(py: Python<'py>, src: PyReadonlyArray2<'py, f64>, dst: PyReadonlyArray2<'py, f64>) -> PyResult<RigidTransform> {
    let s = rows(py, &src, 3, "nominal positions")?;
    let d = rows(py, &dst, 3, "measured positions")?;
    let r = run(py, || rigid_fit(s, d))?;
    Ok(RigidTransform {
        rotation: matrix(py, r.rotation.to_vec(), 3)?.unbind(),
        translation: PyArray1::from_vec(py, r.translation.to_vec()).unbind(),
        rms: r.rms,
    })
}

mod ballbar;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    ballbar::register(m)?;
    m.add("MAX_FOURIER_TERMS", gagekit_kinematics::chain::MAX_TERMS)?;
    m.add_class::<KinematicChain>()?;
    m.add_class::<Identifiability>()?;
    m.add_class::<LeastSquares>()?;
    m.add_class::<RigidTransform>()?;
    m.add_function(wrap_pyfunction!(machine_identifiability, m)?)?;
    m.add_function(wrap_pyfunction!(machine_lstsq, m)?)?;
    m.add_function(wrap_pyfunction!(machine_rigid_fit, m)?)?;
    m.add_function(wrap_pyfunction!(tracking_loo_errors, m)?)?;
    Ok(())
}
