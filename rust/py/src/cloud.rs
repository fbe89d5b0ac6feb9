//! Bindings of gagekit-cloudio: point-cloud reading (ASCII, PLY, E57) and ASCII writing.

use crate::arrays::{indices, matrix, rows, values};
use crate::errors::{invalid, run};
use gagekit_cloudio::{keys_below, cut_chunk, SampleSpec, data_columns, merged_scatter, Moments, MOMENTS_LEN, read_ascii_file, scale_in_place, Keep, PlyAsciiStream, read_e57, write_ascii, AsciiOptions, AsciiStream, E57Stream, PlyFile, PlyStream};
use gagekit_core::GkError;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadwriteArray2};
use pyo3::prelude::*;

/// A parsed ASCII point file.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.cloud")]
pub struct AsciiCloud {
    /// (n, dim) coordinates.
    points: Py<PyAny>,
    /// Header lines skipped before the first point.
    header_lines: usize,
    /// Number of columns of each data line.
    columns: Vec<usize>,
}

/// Read an ASCII point file: mapped, lines counted, then parsed in parallel straight
/// into one Rust allocation that numpy then owns (no copy of the file's bytes nor of the
/// result). Not numpy's allocator: it asks for transparent huge pages, whose compaction
/// on a busy machine cost more system time than the whole parse (measured).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "read_ascii")]
#[pyo3(signature = (path, dim=3, skip_lines=0))]
fn cloud_read_ascii<'py>(
    py: Python<'py>,
    path: String,
    dim: usize,
    skip_lines: usize,
) -> PyResult<AsciiCloud> {
    let parsed = run(py, || read_ascii_file(std::path::Path::new(&path), &AsciiOptions { dim, skip_lines }, &path))?;
    let n = parsed.coords.len() / dim;
    let arr = PyArray1::from_vec(py, parsed.coords).reshape([n, dim])?;
    Ok(AsciiCloud { points: arr.into_any().unbind(), header_lines: parsed.header_lines, columns: parsed.columns })
}

/// Number of values on the first data line of a text file's beginning `head` (its first
/// 1000 lines), read as `cloud_read_ascii` reads it (decimal commas included); 0 if none.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "ascii_columns")]
fn cloud_ascii_columns(head: &Bound<'_, pyo3::types::PyBytes>) -> usize {
    data_columns(head.as_bytes(), 1000)
}

/// The vertices of a PLY file.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.cloud")]
pub struct PlyCloud {
    /// (n, 3) coordinates.
    points: Py<PyAny>,
    /// `ascii`, `binary_little_endian` or `binary_big_endian`.
    format: &'static str,
}

/// Read the vertices of a PLY file (memory-mapped), decoded straight into numpy's
/// allocation (one pass, no copy).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "read_ply")]
fn cloud_read_ply(py: Python<'_>, path: String) -> PyResult<PlyCloud> {
    let file = run(py, || PlyFile::open(std::path::Path::new(&path), &path))?;
    let n = file.vertex_count();
    // SAFETY: uninitialised until `read_into` has written every element; on an error the
    // array is dropped without being seen by Python.
    let arr = unsafe { PyArray2::<f64>::new(py, [n, 3], false) };
    {
        // SAFETY: the array was just created, is C-contiguous and nothing else refers to it.
        let out = unsafe { arr.as_slice_mut() }.map_err(|e| invalid(e.to_string()))?;
        run(py, || file.read_into(out))?;
    }
    Ok(PlyCloud { points: arr.into_any().unbind(), format: file.format_name() })
}

/// Where the vertices of a PLY file are, when they can be used without decoding.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.cloud")]
pub struct PlyLayout {
    /// Number of vertices the header declares.
    vertices: usize,
    /// Byte offset of the first vertex when the file is in gagekit's own layout (binary
    /// little-endian `double x, y, z` only; sizes and finiteness checked), else None.
    direct_offset: Option<usize>,
}

/// Open and check a PLY file; see [`PlyLayout`]. Python then maps the file
/// (copy-on-write) as the array: no copy at all.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "ply_layout")]
fn cloud_ply_layout(py: Python<'_>, path: String) -> PyResult<PlyLayout> {
    run(py, || {
        let f = PlyFile::open(std::path::Path::new(&path), &path)?;
        Ok(PlyLayout { vertices: f.vertex_count(), direct_offset: f.direct_f64_offset()? })
    })
}

/// The points of every scan of an E57 file.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(frozen, get_all, module = "gagekit._core.cloud")]
pub struct E57Cloud {
    /// (n, 3) coordinates in metres, poses applied, invalid points dropped.
    points: Py<PyAny>,
    /// Number of scans.
    scans: usize,
    /// Points dropped because their invalid state was not 0.
    invalid_dropped: usize,
}

/// Read every scan of an E57 file.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "read_e57")]
fn cloud_read_e57(py: Python<'_>, path: String) -> PyResult<E57Cloud> {
    let p = run(py, || read_e57(std::path::Path::new(&path), &path))?;
    let n = p.coords.len() / 3;
    let arr = PyArray1::from_vec(py, p.coords).reshape([n, 3])?;
    Ok(E57Cloud { points: arr.into_any().unbind(), scans: p.scans, invalid_dropped: p.invalid_dropped })
}

/// Multiply the columns of a C-contiguous (n, d) float64 array by `scale` (d factors) in
/// place: the unit conversion of a read cloud without a second array.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "scale_in_place")]
fn cloud_scale_in_place(py: Python<'_>, mut points: PyReadwriteArray2<'_, f64>, scale: Vec<f64>, what: String) -> PyResult<()> {
    let coords = points.as_slice_mut().map_err(|_| invalid("points: expected a C-contiguous float64 array"))?;
    // not interruptible (a rerun would scale twice): one pass at memory speed
    run(py, || scale_in_place(coords, &scale, &what))
}

/// Write points (n, d) as ASCII with separator `sep` and an optional header line.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "write_ascii")]
#[pyo3(signature = (path, points, sep=",", header=None))]
fn cloud_write_ascii(
    py: Python<'_>,
    path: String,
    points: PyReadonlyArray2<'_, f64>,
    sep: &str,
    header: Option<String>,
) -> PyResult<()> {
    let dim = points.as_array().ncols();
    let flat = rows(py, &points, dim, "points")?;
    let sep = match sep.as_bytes() {
        [b] => *b,
        _ => return Err(invalid(format!("separator must be one character, got {sep:?}"))),
    };
    run(py, || {
        let text = write_ascii(flat, dim, sep, header.as_deref())?;
        std::fs::write(&path, text).map_err(|e| GkError::invalid(format!("{path}: cannot be written ({e})")))
    })
}

/// An ASCII point file read in blocks (`gagekit-cloudio`'s `AsciiStream`).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(module = "gagekit._core.cloud")]
pub struct AsciiChunks {
    inner: AsciiStream,
    dim: usize,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl AsciiChunks {
    /// Header lines skipped before the first point.
    #[getter]
    fn header_lines(&self) -> usize {
        self.inner.header_lines
    }

    /// The next (m, dim) chunk of points (m may be 0 for a block of comments), None at the end.
    fn next_chunk(&mut self, py: Python<'_>) -> PyResult<Option<Py<PyAny>>> {
        let inner = &mut self.inner;
        let chunk = run(py, || inner.next_chunk())?;
        let dim = self.dim;
        chunk.map(|c| Ok(matrix(py, c, dim)?.into_any().unbind())).transpose()
    }
}

/// Open an ASCII point file for reading in blocks of about `block` bytes.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "ascii_chunks")]
#[pyo3(signature = (path, dim=3, skip_lines=0, block=1 << 26))]
fn cloud_ascii_chunks(py: Python<'_>, path: String, dim: usize, skip_lines: usize, block: usize) -> PyResult<AsciiChunks> {
    let inner = run(py, || AsciiStream::open(std::path::Path::new(&path), &AsciiOptions { dim, skip_lines }, &path, block))?;
    Ok(AsciiChunks { inner, dim })
}

/// The vertices of a binary PLY file read in ranges (`gagekit-cloudio`'s `PlyStream`).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(module = "gagekit._core.cloud")]
pub struct PlyChunks {
    inner: PlyStream,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl PlyChunks {
    /// Number of vertices.
    #[getter]
    fn count(&self) -> usize {
        self.inner.count()
    }

    /// The next at most `max_points` vertices as an (m, 3) array, None at the end.
    fn next_chunk(&mut self, py: Python<'_>, max_points: usize) -> PyResult<Option<Py<PyAny>>> {
        let inner = &mut self.inner;
        let chunk = run(py, || inner.next_chunk(max_points))?;
        chunk.map(|c| Ok(matrix(py, c, 3)?.into_any().unbind())).transpose()
    }

    /// The next vertices into the C-contiguous (m, 3) float64 array `out` (a buffer
    /// reused from chunk to chunk); the number read, 0 at the end.
    fn next_into(&mut self, py: Python<'_>, mut out: PyReadwriteArray2<'_, f64>) -> PyResult<usize> {
        if out.as_array().ncols() != 3 {
            return Err(invalid("out: expected an (m, 3) array"));
        }
        let buf = out.as_slice_mut().map_err(|_| invalid("out: expected a C-contiguous float64 array"))?;
        let inner = &mut self.inner;
        run(py, || inner.next_into(buf))
    }

    /// The next at most `max_points` vertices into the uint8 array `buf` (a buffer reused
    /// from chunk to chunk, at least `direct_buffer_len` of the points read): (byte offset of
    /// the first point in `buf`, number of points), float64 x, y, z rows from there; past
    /// the page cache when `direct` (whole aligned blocks around the points land in `buf`).
    fn next_direct(&mut self, py: Python<'_>, mut buf: numpy::PyReadwriteArray1<'_, u8>, max_points: usize) -> PyResult<(usize, usize)> {
        let bytes = buf.as_slice_mut().map_err(|_| invalid("buf: expected a contiguous uint8 array"))?;
        let inner = &mut self.inner;
        run(py, || inner.next_direct(bytes, max_points))
    }

    /// Whether `next_direct` reads past the page cache (O_DIRECT).
    #[getter]
    fn direct(&self) -> bool {
        self.inner.is_direct()
    }

    /// Move to vertex `index` (clamped to the count): the next read starts there.
    fn seek(&mut self, index: usize) {
        self.inner.seek(index);
    }
}

/// Bytes of a read buffer for `PlyChunks.next_direct` of `points` vertices: the points
/// and the whole aligned blocks of a read past the page cache around them.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "direct_buffer_len")]
fn cloud_direct_buffer_len(points: usize) -> usize {
    gagekit_cloudio::direct_buffer_len(points)
}

/// Open a binary PLY file (every element of fixed-size records) for reading its vertices
/// in ranges; None for an ASCII PLY or one with lists (faces), which is read whole.
/// `direct`: read past the page cache (O_DIRECT, float64 x y z records only) or not; by
/// default only a file larger than half the memory (which the cache cannot hold).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "ply_chunks")]
#[pyo3(signature = (path, direct=None))]
fn cloud_ply_chunks(py: Python<'_>, path: String, direct: Option<bool>) -> PyResult<Option<PlyChunks>> {
    let p = std::path::Path::new(&path);
    let mut s = run(py, || PlyStream::open(p, &path))?;
    if let (Some(s), Some(on)) = (s.as_mut(), direct) {
        s.set_direct(p, on);
    }
    Ok(s.map(|inner| PlyChunks { inner }))
}

/// The vertices of an ASCII PLY file read in blocks of lines (`gagekit-cloudio`'s `PlyAsciiStream`).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(module = "gagekit._core.cloud")]
pub struct PlyAsciiChunks {
    inner: PlyAsciiStream,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl PlyAsciiChunks {
    /// Number of vertices.
    #[getter]
    fn count(&self) -> usize {
        self.inner.count()
    }

    /// The next at most `max_points` vertices as an (m, 3) array, None at the end.
    fn next_chunk(&mut self, py: Python<'_>, max_points: usize) -> PyResult<Option<Py<PyAny>>> {
        let inner = &mut self.inner;
        let chunk = run(py, || inner.next_chunk(max_points))?;
        chunk.map(|c| Ok(matrix(py, c, 3)?.into_any().unbind())).transpose()
    }
}

/// Open an ASCII PLY file for reading its vertices in blocks of lines (its body's lines
/// counted against the header first, as a whole read checks them); None for a binary one.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "ply_ascii_chunks")]
fn cloud_ply_ascii_chunks(py: Python<'_>, path: String) -> PyResult<Option<PlyAsciiChunks>> {
    let s = run(py, || PlyAsciiStream::open(std::path::Path::new(&path), &path))?;
    Ok(s.map(|inner| PlyAsciiChunks { inner }))
}

/// The points of an E57 file read data packet by data packet (`gagekit-cloudio`'s `E57Stream`).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyclass)]
#[pyclass(module = "gagekit._core.cloud")]
pub struct E57Chunks {
    inner: E57Stream,
}

#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pymethods)]
#[pymethods]
impl E57Chunks {
    /// Number of scans.
    #[getter]
    fn scans(&self) -> usize {
        self.inner.scans()
    }

    /// Records of every scan (valid and invalid points).
    #[getter]
    fn records(&self) -> usize {
        self.inner.records()
    }

    /// Points dropped so far because their invalid state was not 0.
    #[getter]
    fn invalid_dropped(&self) -> usize {
        self.inner.invalid_dropped()
    }

    /// The valid points of the next at most `max_points` records as an (m, 3) array in
    /// metres (m may be 0), None at the end.
    fn next_chunk(&mut self, py: Python<'_>, max_points: usize) -> PyResult<Option<Py<PyAny>>> {
        let inner = &mut self.inner;
        let chunk = run(py, || inner.next_chunk(max_points))?;
        chunk.map(|c| Ok(matrix(py, c, 3)?.into_any().unbind())).transpose()
    }
}

/// Open an E57 file for reading its points in chunks, data packet by data packet; None
/// when a scan is not one the stream reads (the file is then read whole).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "e57_chunks")]
fn cloud_e57_chunks(py: Python<'_>, path: String) -> PyResult<Option<E57Chunks>> {
    let s = run(py, || E57Stream::open(std::path::Path::new(&path), &path))?;
    Ok(s.map(|inner| E57Chunks { inner }))
}

/// The sample candidates of a region in a chunk: (rows, keys, points (m, 3)).
type SampleRow<'py> = (Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);

/// One region's share of a streamed chunk: (points inside, every inside index or None,
/// kept indices, kept points (m, 3), sample candidates or None); indices are rows of the chunk.
type CutRow<'py> = (usize, Option<Bound<'py, PyArray1<i64>>>, Bound<'py, PyArray1<i64>>, Bound<'py, PyArray2<f64>>, Option<SampleRow<'py>>);

/// Classify a chunk of points into region boxes ((k, 9): centre, size, rotation vector)
/// and keep, per box, every inside point or (`hull[i]`) the hull vertices of them;
/// `inside` also returns every inside index of the hull boxes; `moments` ((k, 22), the
/// flat moments of each box, see `point_moments`) gets the inside points of the boxes
/// flagged in `moments_of` added, in place; `minus[i]` = k makes box i keep only its
/// points outside box k (a shell; decided on the indices, before any point is gathered).
/// `hull_from` > 0: a hull box holding fewer points than that keeps every point inside
/// (its points are hulled later with other chunks'). `sample_below` (one bound per box, or
/// empty for no sample): the rows, keys and points of each box's points whose seeded key
/// (`sample_keys_below` of `sample_seed` and the point's number, `start` + its row) is
/// below the box's bound (`gagekit-cloudio`'s `cut_chunk`: one call a chunk, parallel inside).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "cut_chunk")]
#[pyo3(signature = (points, boxes, hull, inside=false, moments=None, moments_of=Vec::new(), minus=Vec::new(), hull_from=0, start=0, sample_seed=0, sample_below=Vec::new()))]
#[allow(clippy::too_many_arguments)]
fn cloud_cut_chunk<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    boxes: PyReadonlyArray2<'py, f64>,
    hull: Vec<bool>,
    inside: bool,
    moments: Option<PyReadwriteArray2<'py, f64>>,
    moments_of: Vec<bool>,
    minus: Vec<Option<usize>>,
    hull_from: usize,
    start: u64,
    sample_seed: u64,
    sample_below: Vec<f64>,
) -> PyResult<Vec<CutRow<'py>>> {
    let pts = rows(py, &points, 3, "points")?;
    let bx = crate::geometry::boxes_from(py, &boxes)?;
    if hull.len() != bx.len() {
        return Err(invalid(format!("hull: expected {} flags (one per box), got {}", bx.len(), hull.len())));
    }
    if !minus.is_empty() && minus.len() != bx.len() {
        return Err(invalid(format!("minus: expected {} entries (one per box), got {}", bx.len(), minus.len())));
    }
    if let Some((i, k)) = minus.iter().enumerate().find_map(|(i, m)| m.filter(|&k| k >= bx.len() || k == i).map(|k| (i, k))) {
        return Err(invalid(format!("minus: box {i} cannot be cut by box {k} (another of the {} boxes)", bx.len())));
    }
    if !sample_below.is_empty() && sample_below.len() != bx.len() {
        return Err(invalid(format!("sample_below: expected {} bounds (one per box), got {}", bx.len(), sample_below.len())));
    }
    let keep: Vec<Keep> = hull
        .iter()
        .map(|&h| match (h, hull_from) {
            (false, _) => Keep::All,
            (true, 0) => Keep::Hull,
            (true, m) => Keep::HullFrom(m),
        })
        .collect();
    let spec = (!sample_below.is_empty()).then(|| SampleSpec { seed: sample_seed, start, below: sample_below });
    let mut moments = moments;
    let mut state: Vec<Option<Moments>> = Vec::new();
    if let Some(m) = moments.as_mut() {
        let flat = m.as_slice_mut().map_err(|_| invalid("moments: expected a C-contiguous array".to_string()))?;
        if flat.len() != bx.len() * MOMENTS_LEN || moments_of.len() != bx.len() {
            return Err(invalid(format!("moments: expected a ({}, {MOMENTS_LEN}) array and {} flags", bx.len(), bx.len())));
        }
        state = flat.chunks_exact(MOMENTS_LEN).zip(&moments_of).map(|(r, &f)| f.then(|| Moments::from_array(r))).collect();
    }
    let cuts = run(py, || cut_chunk(pts, &bx, &keep, inside, &mut state, &minus, spec.as_ref()))?;
    if let Some(m) = moments.as_mut() {
        let flat = m.as_slice_mut().map_err(|_| invalid("moments: expected a C-contiguous array".to_string()))?;
        for (r, s) in flat.chunks_exact_mut(MOMENTS_LEN).zip(&state) {
            if let Some(s) = s {
                r.copy_from_slice(&s.to_array());
            }
        }
    }
    cuts.into_iter()
        .map(|c| {
            let sample = match c.sample {
                Some(s) => Some((indices(py, s.rows), PyArray1::from_vec(py, s.keys), matrix(py, s.points, 3)?)),
                None => None,
            };
            Ok((c.count, c.inside.map(|v| indices(py, v)), indices(py, c.kept), matrix(py, c.points, 3)?, sample))
        })
        .collect()
}

/// The first and second moments of (n, 3) points about the first, by compensated sums in
/// order (`gagekit-cloudio`'s `Moments`): n, origin (3), sums of d, d d^T (upper
/// triangle, row by row), their compensations (9); `cut_chunk` continues them chunk by
/// chunk to the same bits.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "point_moments")]
fn cloud_point_moments<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let pts = rows(py, &points, 3, "points")?;
    let mut m = Moments::default();
    m.add(pts);
    Ok(PyArray1::from_vec(py, m.to_array().to_vec()))
}

/// The count, centroid (3,) and scatter matrix (3, 3) of the points of several regions
/// together, from each region's flat moments (`point_moments`, `cut_chunk`'s `moments`):
/// each region's sums with their compensations folded in, merged by the parallel-axis rule
/// (`gagekit-cloudio`'s `merged_scatter`); regions without points are skipped.
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "moments_scatter")]
fn cloud_moments_scatter<'py>(
    py: Python<'py>,
    moments: Vec<PyReadonlyArray1<'py, f64>>,
) -> PyResult<(u64, Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>)> {
    let mut parts = Vec::with_capacity(moments.len());
    for a in &moments {
        let flat = values(py, a, "moments")?;
        if flat.len() != MOMENTS_LEN {
            return Err(invalid(format!("moments: expected {MOMENTS_LEN} values a region, got {}", flat.len())));
        }
        parts.push(Moments::from_array(flat));
    }
    let s = merged_scatter(&parts);
    Ok((s.n, PyArray1::from_vec(py, s.mean.to_vec()), matrix(py, s.scatter.concat(), 3)?))
}

/// The positions (ascending) in `ids` (point numbers) whose seeded sample key is below
/// `below` (every position for an infinite `below`), and those keys: the SplitMix64
/// finalizer of the number mixed with `seed` (modulo 2^64), its top 53 bits as a fraction
/// in [0, 1) (`gagekit-cloudio`'s `keys_below`, one pass without the GIL).
#[cfg_attr(feature = "stubs", pyo3_stub_gen::derive::gen_stub_pyfunction(module = "gagekit._core.cloud"))]
#[pyfunction]
#[pyo3(name = "sample_keys_below")]
fn cloud_sample_keys_below<'py>(
    py: Python<'py>,
    ids: PyReadonlyArray1<'py, i64>,
    seed: u64,
    below: f64,
) -> PyResult<(Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<f64>>)> {
    let ids = ids.as_slice().map_err(|_| invalid("ids: expected a contiguous int64 array"))?;
    let (pos, keys) = run(py, || Ok(keys_below(seed, ids, below)))?;
    Ok((indices(py, pos), PyArray1::from_vec(py, keys)))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<AsciiChunks>()?;
    m.add_class::<PlyChunks>()?;
    m.add_function(wrap_pyfunction!(cloud_ascii_chunks, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_point_moments, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_moments_scatter, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_ply_chunks, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_direct_buffer_len, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_cut_chunk, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_sample_keys_below, m)?)?;
    m.add_class::<PlyAsciiChunks>()?;
    m.add_function(wrap_pyfunction!(cloud_ply_ascii_chunks, m)?)?;
    m.add_class::<AsciiCloud>()?;
    m.add_function(wrap_pyfunction!(cloud_read_ascii, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_ascii_columns, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_scale_in_place, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_write_ascii, m)?)?;
    m.add_class::<PlyCloud>()?;
    m.add_class::<PlyLayout>()?;
    m.add_class::<E57Cloud>()?;
    m.add_function(wrap_pyfunction!(cloud_read_ply, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_ply_layout, m)?)?;
    m.add_function(wrap_pyfunction!(cloud_read_e57, m)?)?;
    m.add_class::<E57Chunks>()?;
    m.add_function(wrap_pyfunction!(cloud_e57_chunks, m)?)?;
    Ok(())
}
