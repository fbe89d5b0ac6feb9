//! Bindings of gagekit-gdt (GD&T zones and datum simulation, ISO 1101 / ISO 5459).

use crate::arrays::rows;
use crate::errors::run;
use gagekit_core::GkError;
use gagekit_gdt::datum::{self, AxisFit, Orientation, PlaneFit};
use gagekit_gdt::size::{self, Sections};
use gagekit_gdt::turn::{self, Frame};
use gagekit_gdt::plan;
use gagekit_gdt::width2;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

type V3 = (f64, f64, f64);

fn v3(a: [f64; 3]) -> V3 {
    (a[0], a[1], a[2])
}

fn arr(a: V3) -> [f64; 3] {
    [a.0, a.1, a.2]
}

fn orientation(mode: &str, axis: V3, angle: f64) -> gagekit_core::Result<Orientation> {
    Ok(match mode {
        "free" => Orientation::Free,
        "perpendicular" => Orientation::PerpendicularTo(arr(axis)),
        "angle" => Orientation::AtAngle(arr(axis), angle),
        "fixed" => Orientation::Fixed(arr(axis)),
        other => return Err(GkError::config(format!("unknown orientation constraint {other:?}"))),
    })
}

/// Minimum width of (n, 2) points: (width, normal, lo, hi).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "min_width_2d")]
fn gdt_min_width_2d<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<(f64, (f64, f64), f64, f64)> {
    let pts = rows(py, &points, 2, "points")?;
    let w = run(py, || width2::min_width(pts))?;
    Ok((w.width, (w.normal[0], w.normal[1]), w.lo, w.hi))
}

/// Thinnest slab of (n, 3) points with its normal constrained by `mode` ("free",
/// "perpendicular" to `axis`, at `angle` rad to `axis`, "fixed" along `axis`):
/// (normal, lo, hi, width).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "slab")]
fn gdt_slab<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>, mode: &str, axis: V3, angle: f64) -> PyResult<(V3, f64, f64, f64)> {
    let pts = rows(py, &points, 3, "points")?;
    let mode = mode.to_string();
    let s = run(py, move || datum::slab(pts, orientation(&mode, axis, angle)?))?;
    Ok((v3(s.normal), s.lo, s.hi, s.width))
}

/// Thinnest slab (free orientation) of (n, 3) points on an active set started near the
/// planes of normal `normal`, exact by verification on every point
/// (`gagekit_gdt::plan::active`): (normal, lo, hi, width).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "slab_near")]
fn gdt_slab_near<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>, normal: V3) -> PyResult<(V3, f64, f64, f64)> {
    let pts = rows(py, &points, 3, "points")?;
    let s = run(py, move || {
        gagekit_core::check_finite(pts, 3, "points")?;
        plan::active::slab_near(pts, arr(normal))
    })?;
    Ok((v3(s.normal), s.lo, s.hi, s.width))
}

/// Simulated datum plane (ISO 5459): (point, normal out of the material, offset, deviation).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "datum_plane")]
#[allow(clippy::too_many_arguments)]
fn gdt_datum_plane<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    outward: V3,
    mode: &str,
    axis: V3,
    angle: f64,
    fit: &str,
) -> PyResult<(V3, V3, f64, f64)> {
    let pts = rows(py, &points, 3, "points")?;
    let (mode, fit) = (mode.to_string(), fit.to_string());
    let d = run(py, move || {
        let fit = match fit.as_str() {
            "chebyshev" => PlaneFit::Chebyshev,
            "least-squares" => PlaneFit::LeastSquares,
            other => return Err(GkError::config(format!("unknown datum fit {other:?}"))),
        };
        datum::plane(pts, arr(outward), orientation(&mode, axis, angle)?, fit)
    })?;
    Ok((v3(d.point), v3(d.normal), d.offset, d.deviation))
}

fn axis_fit(fit: &str) -> gagekit_core::Result<AxisFit> {
    Ok(match fit {
        "inscribed" => AxisFit::Inscribed,
        "circumscribed" => AxisFit::Circumscribed,
        "least-squares" => AxisFit::LeastSquares,
        other => return Err(GkError::config(format!("unknown axis fit {other:?}"))),
    })
}

/// Cylinder of a fixed axis direction: (point, direction, radius, r_min, r_max).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "axis_along")]
fn gdt_axis_along<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>, direction: V3, fit: &str) -> PyResult<(V3, V3, f64, f64, f64)> {
    let pts = rows(py, &points, 3, "points")?;
    let fit = fit.to_string();
    let a = run(py, move || datum::axis_along(pts, arr(direction), axis_fit(&fit)?))?;
    Ok((v3(a.point), v3(a.direction), a.radius, a.r_min, a.r_max))
}

/// Datum axis at `tilt` rad from the plane normal `normal`, free to turn about it
/// (ISO 5459; `gagekit_gdt::turn::axis_on_cone`): (point, direction, radius, r_min, r_max).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "axis_on_cone")]
fn gdt_axis_on_cone<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    normal: V3,
    tilt: f64,
    ls_direction: V3,
    fit: &str,
) -> PyResult<(V3, V3, f64, f64, f64)> {
    let pts = rows(py, &points, 3, "points")?;
    let fit = fit.to_string();
    let a = run(py, move || turn::axis_on_cone(pts, arr(normal), tilt, arr(ls_direction), axis_fit(&fit)?))?;
    Ok((v3(a.point), v3(a.direction), a.radius, a.r_min, a.r_max))
}

/// Smallest cylinder whose axis is at `angle` rad from `axis`, free to turn about it
/// (angularity of a derived axis): (diameter, axis direction).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "cylinder_on_cone")]
fn gdt_cylinder_on_cone<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>, axis: V3, angle: f64) -> PyResult<(f64, V3)> {
    let pts = rows(py, &points, 3, "points")?;
    let (w, d) = run(py, move || turn::cylinder_on_cone(pts, arr(axis), angle))?;
    Ok((w, v3(d)))
}

type FrameArgs = (V3, (V3, V3, V3), Vec<V3>, bool);

fn frame(f: &FrameArgs) -> gagekit_core::Result<Frame> {
    let (o, (x, y, z), free, rot) = f;
    Frame::checked(arr(*o), [arr(*x), arr(*y), arr(*z)], free.iter().map(|t| arr(*t)).collect(), *rot)
}

/// Position zone radius of (n, 3) points about a nominal point (`direction` None) or
/// line, optimised over what the datum frame `(origin, (x, y, z), free translations,
/// free rotation)` leaves free: (radius, turn).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "position_zone")]
#[pyo3(signature = (points, frame_, point, direction=None))]
fn gdt_position_zone<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    frame_: FrameArgs,
    point: V3,
    direction: Option<V3>,
) -> PyResult<(f64, f64)> {
    let pts = rows(py, &points, 3, "points")?;
    run(py, move || turn::position(pts, &frame(&frame_)?, arr(point), direction.map(arr)))
}

/// Width of the location zone of a plane about the nominal plane (`point`, `normal`),
/// optimised over the frame's free turn: (width, turn).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "plane_location")]
fn gdt_plane_location<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>, frame_: FrameArgs, point: V3, normal: V3) -> PyResult<(f64, f64)> {
    let pts = rows(py, &points, 3, "points")?;
    run(py, move || turn::plane_location(pts, &frame(&frame_)?, arr(point), arr(normal)))
}

/// Position with a datum shift of radius `rho` in the plane (`u`, `v`) normal to the
/// shifted datum axis: (radius, shift used, turn).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "position_with_shift")]
#[allow(clippy::too_many_arguments)]
fn gdt_position_with_shift<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    frame_: FrameArgs,
    point: V3,
    u: V3,
    v: V3,
    rho: f64,
) -> PyResult<(f64, f64, f64)> {
    let pts = rows(py, &points, 3, "points")?;
    run(py, move || turn::position_with_shift(pts, &frame(&frame_)?, arr(point), arr(u), arr(v), rho))
}

/// Exact min over |s| <= rho of max_i |w_i - s| for (n, 2) points: (value, s).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "min_in_disk")]
fn gdt_min_in_disk<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>, rho: f64) -> PyResult<(f64, (f64, f64))> {
    let pts = rows(py, &points, 2, "points")?;
    let (r, s) = run(py, move || {
        gagekit_core::check_finite(pts, 2, "points")?;
        let w: Vec<[f64; 2]> = pts.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
        turn::min_in_disk(&w, rho)
    })?;
    Ok((r, (s[0], s[1])))
}

/// Two-point sizes (ISO 14405-1) about an axis: (sizes, section index, direction angle,
/// sections used); directions from `reference` projected normal to the axis; `kind` "axial" (cylinder, circle, cone) or "great-circles" (sphere).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "two_point_sizes")]
#[allow(clippy::type_complexity)]
fn gdt_two_point_sizes<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    origin: V3,
    axis: V3,
    reference: V3,
    kind: &str,
    sections: usize,
    angles: usize,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<f64>>, usize)> {
    let pts = rows(py, &points, 3, "points")?;
    let kind = kind.to_string();
    let t = run(py, move || {
        let kind = match kind.as_str() {
            "axial" => Sections::Axial,
            "great-circles" => Sections::GreatCircles,
            other => return Err(GkError::config(format!("unknown section kind {other:?}"))),
        };
        size::two_point_sizes(pts, arr(origin), arr(axis), arr(reference), kind, sections, angles)
    })?;
    let sec: Vec<i64> = t.section.iter().map(|&k| k as i64).collect();
    Ok((PyArray1::from_vec(py, t.sizes), PyArray1::from_vec(py, sec), PyArray1::from_vec(py, t.angle), t.sections_used))
}

/// Two-point sizes of a width: each point of `face_a` to the opposite point of `face_b`
/// along `normal`, interpolated on `face_b`'s triangulation.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "width_sizes")]
fn gdt_width_sizes<'py>(
    py: Python<'py>,
    face_a: PyReadonlyArray2<'py, f64>,
    face_b: PyReadonlyArray2<'py, f64>,
    normal: V3,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let a = rows(py, &face_a, 3, "face_a")?;
    let b = rows(py, &face_b, 3, "face_b")?;
    let s = run(py, move || size::width_sizes(a, b, arr(normal)))?;
    Ok(PyArray1::from_vec(py, s))
}

/// Distance between the convex hulls of two point sets and the unit direction from the
/// first to the second (GJK).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "hull_distance")]
fn gdt_hull_distance<'py>(py: Python<'py>, a: PyReadonlyArray2<'py, f64>, b: PyReadonlyArray2<'py, f64>) -> PyResult<(f64, V3)> {
    let a = rows(py, &a, 3, "a")?;
    let b = rows(py, &b, 3, "b")?;
    let (d, n) = run(py, move || size::hull_distance(a, b))?;
    Ok((d, v3(n)))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(gdt_two_point_sizes, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_width_sizes, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_hull_distance, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_min_width_2d, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_slab, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_slab_near, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_datum_plane, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_axis_along, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_axis_on_cone, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_cylinder_on_cone, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_position_zone, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_plane_location, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_position_with_shift, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_min_in_disk, m)?)?;
    m.add_function(wrap_pyfunction!(gdt_perturb, m)?)?;
    m.add_class::<InspectionPlan>()?;
    Ok(())
}

// -- the compiled inspection of the Monte Carlo uncertainty (gagekit_gdt::plan) -------------

type WarmAxis = Option<(V3, V3)>;
/// The measured least-squares fit: (a cylinder's point or a sphere's centre, the
/// cylinder's direction or None for a sphere, radius)
type WarmLsq = Option<(V3, Option<V3>, f64)>;
/// The measured starts: (least-squares fit, minimum-zone / min-circumscribed /
/// max-inscribed axes, flatness normal, minimum-zone sphere centre)
type WarmArgs = (WarmLsq, WarmAxis, WarmAxis, WarmAxis, Option<V3>, Option<V3>);
/// (shape, rows, outward, sign hint, box axes, hole, the measured starts)
type FeatureArgs<'py> = (String, PyReadonlyArray1<'py, i64>, Option<V3>, V3, (V3, V3, V3), bool, WarmArgs);
/// (characteristic, feature, tolerance, datum entries, frame, angle deg, sections, nominal point, nominal direction)
type CalloutArgs = (String, usize, f64, Vec<usize>, Option<usize>, f64, usize, Option<V3>, Option<V3>);
/// (sigma, origin, sigma_per_m, probing, relative scale, offset)
type ModelArgs = (f64, Option<V3>, f64, f64, f64, f64);

fn plan_feature(f: FeatureArgs<'_>) -> PyResult<plan::Feature> {
    let (shape, rows, outward, hint, (bx, by, bz), hole, (warm_lsq, mz, mc, mi, slab, sphere)) = f;
    let shape = match shape.as_str() {
        "plane" => plan::Shape::Plane,
        "line" => plan::Shape::Line,
        "circle" => plan::Shape::Circle,
        "sphere" => plan::Shape::Sphere,
        "cylinder" => plan::Shape::Cylinder,
        other => return Err(crate::errors::invalid(format!("inspection plan: unsupported shape {other:?}"))),
    };
    let rows = rows
        .as_slice()
        .map_err(|_| crate::errors::invalid("inspection plan: rows must be C-contiguous"))?
        .iter()
        .map(|&i| usize::try_from(i).map_err(|_| crate::errors::invalid(format!("inspection plan: row {i} out of range"))))
        .collect::<PyResult<Vec<usize>>>()?;
    let axis = |w: WarmAxis| w.map(|(p, d)| (arr(p), arr(d)));
    Ok(plan::Feature {
        shape,
        rows,
        outward: outward.map(arr),
        sign_hint: arr(hint),
        box_axes: [arr(bx), arr(by), arr(bz)],
        hole,
        warm_lsq: warm_lsq.map(|(p, d, radius)| match d {
            Some(d) => plan::LsqStart::Cylinder(gagekit_form::lsq::Cylinder { point: arr(p), direction: arr(d), radius }),
            None => plan::LsqStart::Sphere { center: arr(p), radius },
        }),
        warm_cylinder: [axis(mz), axis(mc), axis(mi)],
        warm_slab: slab.map(arr),
        warm_sphere: sphere.map(arr),
    })
}

fn plan_callout(c: CalloutArgs) -> PyResult<plan::Callout> {
    use plan::Characteristic as C;
    let (name, feature, tolerance, datums, frame, angle, sections, nominal_point, nominal_direction) = c;
    let characteristic = match name.as_str() {
        "flatness" => C::Flatness,
        "straightness" => C::Straightness,
        "roundness" => C::Roundness,
        "cylindricity" => C::Cylindricity,
        "sphericity" => C::Sphericity,
        "parallelism" => C::Parallelism,
        "perpendicularity" => C::Perpendicularity,
        "angularity" => C::Angularity,
        "position" => C::Position,
        "coaxiality" => C::Coaxiality,
        "profile" => C::Profile,
        "circular-runout" => C::CircularRunout,
        "total-runout" => C::TotalRunout,
        other => return Err(crate::errors::invalid(format!("inspection plan: unsupported characteristic {other:?}"))),
    };
    Ok(plan::Callout {
        characteristic,
        feature,
        tolerance,
        datums,
        frame,
        angle,
        sections,
        nominal_point: nominal_point.map(arr),
        nominal_direction: nominal_direction.map(arr),
    })
}

fn plan_model(m: ModelArgs) -> gagekit_core::Result<plan::perturb::Model> {
    let (sigma, origin, sigma_per_m, probing, relative_scale, offset) = m;
    plan::perturb::Model { sigma, origin: origin.map(arr), sigma_per_m, probing, relative_scale, offset }.checked()
}

/// An inspection compiled for the Monte Carlo trials (`gagekit_gdt::plan`): features
/// (rows into the active points, warm starts), datums (feature, prior datum entries,
/// basic angle), frames (datum entries) and callouts. `gagekit.uncertainty.plan` builds it.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.gdt")]
pub struct InspectionPlan {
    plan: plan::Plan,
    cache: plan::sparse::Cache,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl InspectionPlan {
    #[new]
    fn new(
        features: Vec<FeatureArgs<'_>>,
        datums: Vec<(usize, Vec<usize>, f64)>,
        frames: Vec<Vec<usize>>,
        callouts: Vec<CalloutArgs>,
    ) -> PyResult<Self> {
        let features = features.into_iter().map(plan_feature).collect::<PyResult<Vec<_>>>()?;
        let datums = datums.into_iter().map(|(feature, prior, angle)| plan::Datum { feature, prior, angle }).collect();
        let callouts = callouts.into_iter().map(plan_callout).collect::<PyResult<Vec<_>>>()?;
        Ok(Self { plan: plan::Plan { features, datums, frames, callouts }, cache: Default::default() })
    }

    /// The callouts' (measured, margin) of the active points (n, 3), one evaluation:
    /// (values, warm-started cylinder fits, fallbacks to the global search).
    fn evaluate<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<(Bound<'py, PyArray1<f64>>, usize, usize)> {
        let pts = rows(py, &points, 3, "points")?;
        let v = run(py, || plan::evaluate(&self.plan, pts))?;
        Ok((PyArray1::from_vec(py, v.values), v.warm_fits, v.fallbacks))
    }

    /// Trials `first .. first + count`, each a perturbation of the active points (n, 3)
    /// by `model` (sigma, origin, sigma_per_m, probing, relative scale, offset) drawn by
    /// the generator of (seed, trial), evaluated on `threads` threads (0: all): ((count,
    /// 2 x callouts) values, warm-started cylinder fits, fallbacks). `every_point`: the
    /// plane features evaluated on every point instead of their certified extreme blocks
    /// (the reference; `gagekit_gdt::plan::sparse`).
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (points, model, seed, first, count, threads, every_point = false))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f64>,
        model: ModelArgs,
        seed: u64,
        first: u64,
        count: usize,
        threads: usize,
        every_point: bool,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, usize, usize)> {
        let pts = rows(py, &points, 3, "points")?;
        let v = run(py, || plan::run_with(&self.plan, pts, &plan_model(model)?, seed, first, count, threads, every_point, &self.cache))?;
        let m = 2 * self.plan.callouts.len();
        Ok((crate::arrays::matrix(py, v.values, m)?, v.warm_fits, v.fallbacks))
    }

    /// Trial `trial`'s simulated measurement of the active points (n, 3) as `run` draws
    /// it (by blocks, `gagekit_gdt::plan::sparse`, for isotropic noise alone; else as
    /// `gagekit._core.gdt.perturb`).
    fn simulate<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>, model: ModelArgs, seed: u64, trial: u64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let pts = rows(py, &points, 3, "points")?;
        let p = run(py, || plan::simulate(&self.plan, pts, &plan_model(model)?, seed, trial))?;
        crate::arrays::matrix(py, p, 3)
    }
}

/// One simulated measurement of (n, 3) or (n, 2) points by the measurement model (sigma,
/// origin, sigma_per_m, probing, relative scale, offset), drawn by the generator of
/// (seed, trial) (`gagekit_gdt::plan::perturb`).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.gdt"))]
#[pyfunction]
#[pyo3(name = "perturb")]
fn gdt_perturb<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>, model: ModelArgs, seed: u64, trial: u64) -> PyResult<Bound<'py, PyArray2<f64>>> {
    use numpy::PyUntypedArrayMethods;
    let dim = points.shape()[1];
    let pts = points.as_slice().map_err(|_| crate::errors::invalid("points: array must be C-contiguous"))?;
    let p = run(py, || {
        gagekit_core::check_finite(pts, dim.max(1), "points")?;
        plan::perturb::perturb(pts, dim, &plan_model(model)?, seed, trial)
    })?;
    crate::arrays::matrix(py, p, dim)
}
