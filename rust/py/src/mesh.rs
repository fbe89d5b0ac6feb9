//! Bindings of gagekit-mesh: a `Mesh` handle built once (BVH, topology, pseudonormals)
//! and its distance, best-fit and minimax calls. Conversion only.

use crate::arrays::{matrix, rows};
use crate::errors::{invalid, run};
use gagekit_mesh::align::{best_fit, FitOptions};
use gagekit_mesh::distance::Query;
use gagekit_mesh::minimax::minimax;
use gagekit_mesh::rigid::Pose;
use gagekit_mesh::TriMesh;
use numpy::{PyArray1, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::sync::Arc;

/// A validated triangle mesh ready for distance queries (built once; immutable).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, module = "gagekit._core.mesh")]
pub struct Mesh {
    mesh: Arc<TriMesh>,
}

/// The result of `Mesh.best_fit`: `matrix` (4x4, row-major rows) applied to the points.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.mesh")]
pub struct MeshBestFit {
    pub matrix: Vec<Vec<f64>>,
    pub iterations: usize,
    pub rms_before: f64,
    pub rms_after: f64,
    pub n_used: usize,
    pub start: usize,
}

/// The result of `Mesh.minimax`: `matrix`, the exact largest |distance| `max_abs` and the
/// certificate LP's optimum `lp_optimum` (equal at a Chebyshev optimum).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.mesh")]
pub struct MeshMinimax {
    pub matrix: Vec<Vec<f64>>,
    pub max_abs: f64,
    pub lp_optimum: f64,
    pub rms: f64,
    pub iterations: usize,
    pub active: usize,
    pub n_used: usize,
}

fn rows4(p: &Pose) -> Vec<Vec<f64>> {
    p.matrix().chunks_exact(4).map(|r| r.to_vec()).collect()
}

fn pose_of(initial: Option<PyReadonlyArray2<'_, f64>>) -> PyResult<Pose> {
    match initial {
        None => Ok(Pose::IDENTITY),
        Some(m) => {
            if m.shape() != [4, 4] {
                return Err(invalid("initial: expected a 4x4 matrix"));
            }
            let s = m.as_slice().map_err(|_| invalid("initial: array must be C-contiguous"))?;
            Pose::from_matrix(s).map_err(crate::errors::to_pyerr)
        }
    }
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl Mesh {
    /// Build from (n, 3) float64 vertices and (m, 3) int64 vertex indices.
    #[new]
    fn new(py: Python<'_>, vertices: PyReadonlyArray2<'_, f64>, triangles: PyReadonlyArray2<'_, i64>) -> PyResult<Self> {
        // read in place (TriMesh::new copies the vertices and indices before checking them)
        let v = rows(py, &vertices, 3, "vertices")?;
        if triangles.shape()[1] != 3 {
            return Err(invalid(format!("triangles: expected an (m, 3) array, got shape {:?}", triangles.shape())));
        }
        // the indices read in place too: TriMesh::new converts them to u32 in its parallel
        // copy (without the GIL), refusing an index out of range by its value
        let t = triangles.as_slice().map_err(|_| invalid("triangles: array must be C-contiguous"))?;
        let mesh = run(py, || TriMesh::new(v, t))?;
        Ok(Self { mesh: Arc::new(mesh) })
    }

    #[getter]
    fn n_vertices(&self) -> usize {
        self.mesh.vertices.len()
    }
    #[getter]
    fn n_triangles(&self) -> usize {
        self.mesh.triangles.len()
    }
    /// Closed, manifold and consistently oriented: distances are signed.
    #[getter]
    fn signed(&self) -> bool {
        self.mesh.signed()
    }
    /// Why distances are unsigned (None when signed).
    #[getter]
    fn reason(&self) -> Option<String> {
        self.mesh.topology.reason.clone()
    }
    /// The triangles were wound inwards and are read turned outwards.
    #[getter]
    fn flipped(&self) -> bool {
        self.mesh.topology.flipped
    }
    #[getter]
    fn volume(&self) -> f64 {
        self.mesh.topology.volume
    }
    #[getter]
    fn area(&self) -> f64 {
        self.mesh.area
    }
    /// Unit outward normal of each triangle, (m, 3).
    fn face_normals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix(py, self.mesh.face_normals.iter().flatten().copied().collect(), 3)
    }

    /// Distances of (n, 3) points: (distance, triangle (-1 beyond max_distance, distance
    /// NaN there), closest points (n, 3) or None, number beyond, signed?).
    #[pyo3(signature = (points, max_distance=None, unsigned=false, foot=false))]
    #[allow(clippy::type_complexity)]
    fn distances<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f64>,
        max_distance: Option<f64>,
        unsigned: bool,
        foot: bool,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<i64>>, Option<Bound<'py, PyArray2<f64>>>, usize, bool)> {
        let pts = rows(py, &points, 3, "points")?;
        let mesh = self.mesh.clone();
        let q = Query { max_distance, unsigned, foot };
        let d = run(py, || mesh.distances(pts, &q))?;
        let f = if foot { Some(matrix(py, d.foot, 3)?) } else { None };
        Ok((PyArray1::from_vec(py, d.distance), PyArray1::from_vec(py, d.triangle), f, d.beyond, d.signed))
    }

    /// Robust best-fit (point-to-plane ICP) of the points to the surface; `free`: x, y, z,
    /// rx, ry, rz; `search`: also start from the principal axes and their flips.
    #[pyo3(signature = (points, initial=None, free=[true; 6], max_distance=None, search=true))]
    fn best_fit(
        &self,
        py: Python<'_>,
        points: PyReadonlyArray2<'_, f64>,
        initial: Option<PyReadonlyArray2<'_, f64>>,
        free: [bool; 6],
        max_distance: Option<f64>,
        search: bool,
    ) -> PyResult<MeshBestFit> {
        let pts = rows(py, &points, 3, "points")?;
        let opt = FitOptions { initial: pose_of(initial)?, free, max_distance, search };
        let mesh = self.mesh.clone();
        let f = run(py, || best_fit(&mesh, pts, &opt))?;
        Ok(MeshBestFit {
            matrix: rows4(&f.pose),
            iterations: f.iterations,
            rms_before: f.rms_before,
            rms_after: f.rms_after,
            n_used: f.n_used,
            start: f.start,
        })
    }

    /// Minimax (Chebyshev) alignment from `initial`, with its LP certificate; `offset`: the
    /// zone's centre surface is the CAD surface offset outwards by it (ISO 1101 UZ).
    #[pyo3(signature = (points, initial=None, free=[true; 6], max_distance=None, offset=0.0))]
    #[allow(clippy::too_many_arguments)]
    fn minimax(
        &self,
        py: Python<'_>,
        points: PyReadonlyArray2<'_, f64>,
        initial: Option<PyReadonlyArray2<'_, f64>>,
        free: [bool; 6],
        max_distance: Option<f64>,
        offset: f64,
    ) -> PyResult<MeshMinimax> {
        let pts = rows(py, &points, 3, "points")?;
        let init = pose_of(initial)?;
        let mesh = self.mesh.clone();
        let m = run(py, || minimax(&mesh, pts, init, free, max_distance, offset))?;
        Ok(MeshMinimax {
            matrix: rows4(&m.pose),
            max_abs: m.max_abs,
            lp_optimum: m.lp_optimum,
            rms: m.rms,
            iterations: m.iterations,
            active: m.active,
            n_used: m.n_used,
        })
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Mesh>()?;
    m.add_class::<MeshBestFit>()?;
    m.add_class::<MeshMinimax>()?;
    Ok(())
}
