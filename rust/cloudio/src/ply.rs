//! PLY reader (Greg Turk's polygon file format): ASCII, binary little- and big-endian.
//!
//! Only the `x`, `y`, `z` properties of the `vertex` element are returned (as f64, in
//! file order); every other element and property is walked over so that the file's size
//! can be checked against its header: a file holding more data than its header declares
//! (say 50 vertices under `element vertex 10`) or less (a truncated file) is an error,
//! never a silent partial read. Binary bodies are decoded in parallel straight from the
//! caller's bytes (a memory map), one pass, no intermediate copy.

use crate::ascii::{line_at, line_starts, parse_f64, trim};
use gagekit_core::{GkError, Result};
use rayon::prelude::*;

/// Scalar types of PLY properties (both the 1.0 names and the sized aliases).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Ty {
    fn parse(s: &str) -> Option<Ty> {
        Some(match s {
            "char" | "int8" => Ty::I8,
            "uchar" | "uint8" => Ty::U8,
            "short" | "int16" => Ty::I16,
            "ushort" | "uint16" => Ty::U16,
            "int" | "int32" => Ty::I32,
            "uint" | "uint32" => Ty::U32,
            "float" | "float32" => Ty::F32,
            "double" | "float64" => Ty::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::F64 => 8,
        }
    }
    /// Value at the start of `b` (at least `size()` bytes).
    #[inline(always)]
    fn get(self, b: &[u8], be: bool) -> f64 {
        macro_rules! rd {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                (if be { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
            }};
        }
        match self {
            Ty::I8 => b[0] as i8 as f64,
            Ty::U8 => b[0] as f64,
            Ty::I16 => rd!(i16, 2),
            Ty::U16 => rd!(u16, 2),
            Ty::I32 => rd!(i32, 4),
            Ty::U32 => rd!(u32, 4),
            Ty::F32 => rd!(f32, 4),
            Ty::F64 => rd!(f64, 8),
        }
    }
}

#[derive(Debug, Clone)]
struct Prop {
    name: String,
    ty: Ty,
    /// `Some(count type)` for a list property.
    list: Option<Ty>,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

impl Element {
    /// Record size when every property is a scalar.
    fn fixed_size(&self) -> Option<usize> {
        self.props.iter().try_fold(0, |acc, p| if p.list.is_some() { None } else { Some(acc + p.ty.size()) })
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    Le,
    Be,
}

/// A PLY file's vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyPoints {
    /// x, y, z of each vertex, row-major.
    pub coords: Vec<f64>,
    /// `ascii`, `binary_little_endian` or `binary_big_endian`.
    pub format: &'static str,
}

const MAX_HEADER: usize = 1 << 20;

fn bad(what: &str, msg: impl std::fmt::Display) -> GkError {
    GkError::file_format(format!("{what}: not a readable PLY file ({msg})"))
}

/// Parse the header: (format, elements, byte offset of the body).
fn header(bytes: &[u8], what: &str) -> Result<(Format, Vec<Element>, usize)> {
    if !bytes.starts_with(b"ply\n") && !bytes.starts_with(b"ply\r\n") {
        return Err(bad(what, "it does not start with 'ply'"));
    }
    let mut pos = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut lineno = 0;
    loop {
        let rest = &bytes[pos..];
        let Some(nl) = memchr::memchr(b'\n', rest) else {
            return Err(bad(what, "the header has no 'end_header' line"));
        };
        lineno += 1;
        let line = std::str::from_utf8(trim(&rest[..nl]))
            .map_err(|_| bad(what, format!("header line {lineno} is not text")))?;
        pos += nl + 1;
        if pos > MAX_HEADER {
            return Err(bad(what, "the header is longer than 1 MiB"));
        }
        let mut w = line.split_ascii_whitespace();
        match w.next() {
            None | Some("ply") if lineno == 1 => {}
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                format = Some(match (w.next(), w.next()) {
                    (Some("ascii"), Some("1.0")) => Format::Ascii,
                    (Some("binary_little_endian"), Some("1.0")) => Format::Le,
                    (Some("binary_big_endian"), Some("1.0")) => Format::Be,
                    _ => return Err(bad(what, format!("header line {lineno}: unknown format {line:?}"))),
                });
            }
            Some("element") => {
                let (Some(name), Some(n), None) = (w.next(), w.next(), w.next()) else {
                    return Err(bad(what, format!("header line {lineno}: expected 'element NAME COUNT'")));
                };
                let count = n
                    .parse::<usize>()
                    .map_err(|_| bad(what, format!("header line {lineno}: element count {n:?} is not a count")))?;
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            Some("property") => {
                let Some(el) = elements.last_mut() else {
                    return Err(bad(what, format!("header line {lineno}: property before any element")));
                };
                let words: Vec<&str> = w.collect();
                let prop = match words.as_slice() {
                    ["list", ct, it, name] => {
                        let (Some(c), Some(t)) = (Ty::parse(ct), Ty::parse(it)) else {
                            return Err(bad(what, format!("header line {lineno}: unknown type in {line:?}")));
                        };
                        if matches!(c, Ty::F32 | Ty::F64) {
                            return Err(bad(what, format!("header line {lineno}: a list count must be an integer type")));
                        }
                        Prop { name: name.to_string(), ty: t, list: Some(c) }
                    }
                    [t, name] => {
                        let Some(t) = Ty::parse(t) else {
                            return Err(bad(what, format!("header line {lineno}: unknown type in {line:?}")));
                        };
                        Prop { name: name.to_string(), ty: t, list: None }
                    }
                    _ => return Err(bad(what, format!("header line {lineno}: cannot read {line:?}"))),
                };
                el.props.push(prop);
            }
            Some("end_header") => break,
            Some(_) => return Err(bad(what, format!("header line {lineno}: unknown keyword in {line:?}"))),
        }
    }
    let format = format.ok_or_else(|| bad(what, "the header has no 'format' line"))?;
    Ok((format, elements, pos))
}

/// Indices of the x, y, z properties of the vertex element, and that element's index.
fn xyz(elements: &[Element], what: &str) -> Result<(usize, [usize; 3])> {
    let vi = elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| bad(what, "no 'vertex' element"))?;
    let el = &elements[vi];
    let mut idx = [0; 3];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        idx[k] = el
            .props
            .iter()
            .position(|p| p.name == *name && p.list.is_none())
            .ok_or_else(|| GkError::file_format(format!("{what}: PLY file without vertex x, y, z properties (no '{name}')")))?;
    }
    Ok((vi, idx))
}

fn non_finite(what: &str, i: usize) -> GkError {
    GkError::file_format(format!("{what}: vertex {i} has a non-finite coordinate (NaN or inf)"))
}

/// A PLY file opened for reading: memory-mapped, header parsed, its size checked against
/// the header. [`PlyFile::vertex_count`] tells the caller how large a buffer to give
/// [`PlyFile::read_into`] (the binding hands numpy's own allocation, so the vertices are
/// written once, straight into the array the user gets).
pub struct PlyFile {
    map: memmap2::Mmap,
    what: String,
    format: Format,
    elements: Vec<Element>,
    body: usize,
    vi: usize,
    idx: [usize; 3],
}

impl PlyFile {
    /// Open and check the PLY file at `path`; `what` names it in messages.
    pub fn open(path: &std::path::Path, what: &str) -> Result<PlyFile> {
        Self::open_with(path, what, true)
    }

    /// [`PlyFile::open`] without reading the file ahead: only the pages touched (the
    /// header, and the tail [`PlyFile::vertex_records`] checks) are read, for a reader
    /// that then streams the vertices itself.
    pub fn open_lazy(path: &std::path::Path, what: &str) -> Result<PlyFile> {
        Self::open_with(path, what, false)
    }

    fn open_with(path: &std::path::Path, what: &str, populate: bool) -> Result<PlyFile> {
        let io = |e: std::io::Error| crate::read_error(what, e);
        let file = std::fs::File::open(path).map_err(io)?;
        if file.metadata().map_err(io)?.len() == 0 {
            return Err(bad(what, "the file is empty"));
        }
        // SAFETY: the map is read-only and lives only as long as this reader; a file
        // truncated by another process meanwhile is outside what any reader can guard against.
        let mut opts = memmap2::MmapOptions::new();
        if populate {
            opts.populate();
        }
        let map = unsafe { opts.map(&file) }.map_err(io)?;
        let (format, elements, body) = header(&map, what)?;
        let (vi, idx) = xyz(&elements, what)?;
        // a count no file of this size can hold: refuse before anyone allocates for it
        let el = &elements[vi];
        let least = match format {
            Format::Ascii => 2 * el.props.len(),
            _ => el.props.iter().map(|p| p.list.unwrap_or(p.ty).size()).sum(),
        };
        if el.count > (map.len() - body) / least.max(1) {
            return Err(GkError::file_format(format!(
                "{what}: the PLY header declares {} vertices, more than the file's {} bytes can hold: truncated or a wrong count",
                el.count,
                map.len()
            )));
        }
        Ok(PlyFile { map, what: what.to_string(), format, elements, body, vi, idx })
    }

    /// Number of vertices the header declares.
    pub fn vertex_count(&self) -> usize {
        self.elements[self.vi].count
    }

    /// `ascii`, `binary_little_endian` or `binary_big_endian`.
    pub fn format_name(&self) -> &'static str {
        match self.format {
            Format::Ascii => "ascii",
            Format::Le => "binary_little_endian",
            Format::Be => "binary_big_endian",
        }
    }

    /// When the vertices are stored exactly as gagekit needs them (binary little-endian,
    /// `vertex` the first element, properties `double x, y, z` and nothing else), the byte
    /// offset of the first vertex, after checking every coordinate is finite: the caller
    /// can then map the file itself and use its bytes as the (n, 3) array, with no copy.
    pub fn direct_f64_offset(&self) -> Result<Option<usize>> {
        let el = &self.elements[self.vi];
        let exact = self.format == Format::Le
            && self.vi == 0
            && el.props.len() == 3
            && el.props.iter().zip(["x", "y", "z"]).all(|(p, n)| p.name == n && p.ty == Ty::F64 && p.list.is_none());
        if !exact {
            return Ok(None);
        }
        // the element walk checks the file's size against every element of the header
        let end = self.body + 24 * el.count;
        let data = &self.map[self.body..end];
        let bad = data.par_chunks(24 * 65536).enumerate().find_map_first(|(c, block)| {
            block.chunks_exact(8).position(|b| !f64::from_le_bytes(b.try_into().unwrap_or([0; 8])).is_finite()).map(|i| c * 65536 + i / 3)
        });
        if let Some(i) = bad {
            return Err(non_finite(&self.what, i));
        }
        check_tail(&self.map, &self.elements, self.vi, &self.what, self.body, false)?;
        Ok(Some(self.body))
    }

    /// The vertices as fixed-size records, when the file is binary and every element has
    /// fixed-size records (no lists): the file's size is checked against the header here
    /// (the same errors as a whole read), so the caller can read any range of vertices.
    pub fn vertex_records(&self) -> Result<Option<VertexRecords>> {
        if self.format == Format::Ascii || self.elements.iter().any(|e| e.fixed_size().is_none()) {
            return Ok(None);
        }
        let be = self.format == Format::Be;
        check_tail(&self.map, &self.elements, self.vi, &self.what, self.body, be)?;
        let el = &self.elements[self.vi];
        let offset = self.body + self.elements[..self.vi].iter().map(|e| e.count * e.fixed_size().unwrap_or(0)).sum::<usize>();
        let field = |p: usize| el.props[..p].iter().map(|q| q.ty.size()).sum::<usize>();
        Ok(Some(VertexRecords {
            offset,
            count: el.count,
            stride: el.fixed_size().unwrap_or(0),
            fo: self.idx.map(field),
            ty: self.idx.map(|p| el.props[p].ty),
            be,
        }))
    }

    /// Decode x, y, z of every vertex into `out` (length 3 x [`Self::vertex_count`]).
    pub fn read_into(&self, out: &mut [f64]) -> Result<()> {
        if out.len() != 3 * self.vertex_count() {
            return Err(GkError::invalid(format!("{}: output buffer of {} values for {} vertices", self.what, out.len(), self.vertex_count())));
        }
        let (bytes, what) = (&self.map[..], self.what.as_str());
        match self.format {
            Format::Ascii => read_ascii(bytes, self.body, &self.elements, self.vi, self.idx, what, out),
            Format::Le | Format::Be => {
                read_binary(bytes, self.body, &self.elements, self.vi, self.idx, self.format == Format::Be, what, out)
            }
        }
    }
}

/// Where and how the vertices of a binary PLY file are stored ([`PlyFile::vertex_records`]).
#[derive(Debug, Clone)]
pub struct VertexRecords {
    /// Byte offset of the first vertex record.
    pub offset: usize,
    /// Number of vertices.
    pub count: usize,
    /// Bytes per vertex record.
    pub stride: usize,
    fo: [usize; 3],
    ty: [Ty; 3],
    be: bool,
}

impl VertexRecords {
    /// Whether a record is exactly little-endian `double x, y, z` (its bytes are the points).
    pub fn is_f64_xyz(&self) -> bool {
        self.stride == 24 && self.fo == [0, 8, 16] && self.ty == [Ty::F64; 3] && !self.be
    }

    /// Decode the records `bytes` (whole records, the first being vertex `first`) into
    /// `out` (3 per record); a non-finite coordinate is the whole read's error.
    pub fn decode(&self, bytes: &[u8], first: usize, out: &mut [f64], what: &str) -> Result<()> {
        decode_fixed(bytes, self.stride, self.fo, self.ty, self.be, out).map_err(|i| non_finite(what, first + i))
    }
}

/// Read the vertices of the PLY file at `path` (memory-mapped).
pub fn read_ply_file(path: &std::path::Path, what: &str) -> Result<PlyPoints> {
    let f = PlyFile::open(path, what)?;
    let mut coords = vec![0.0; 3 * f.vertex_count()];
    f.read_into(&mut coords)?;
    Ok(PlyPoints { coords, format: f.format_name() })
}

/// Read the vertices of a PLY file held in `bytes`. `what` names the file in messages.
pub fn read_ply(bytes: &[u8], what: &str) -> Result<PlyPoints> {
    let (format, elements, body) = header(bytes, what)?;
    let (vi, idx) = xyz(&elements, what)?;
    let mut coords = vec![0.0; 3 * elements[vi].count.min(bytes.len())];
    if coords.len() != 3 * elements[vi].count {
        return Err(GkError::file_format(format!("{what}: the PLY header declares more vertices than the file has bytes: truncated or a wrong count")));
    }
    match format {
        Format::Ascii => read_ascii(bytes, body, &elements, vi, idx, what, &mut coords)?,
        Format::Le | Format::Be => read_binary(bytes, body, &elements, vi, idx, format == Format::Be, what, &mut coords)?,
    }
    Ok(PlyPoints { coords, format: match format { Format::Ascii => "ascii", Format::Le => "binary_little_endian", Format::Be => "binary_big_endian" } })
}

/// Walk the elements of a binary body (without decoding) and check that the file ends
/// where the header says it does.
fn check_tail(bytes: &[u8], elements: &[Element], vi: usize, what: &str, body: usize, be: bool) -> Result<()> {
    let mut none: [f64; 0] = [];
    walk_binary(bytes, body, elements, vi, None, be, what, &mut none)
}

/// x, y, z of `n` fixed-size records of `stride` bytes (fields at byte offsets `fo`, of
/// types `ty`), decoded in parallel chunks; `Err(i)` names the first non-finite vertex.
fn decode_fixed(data: &[u8], stride: usize, fo: [usize; 3], ty: [Ty; 3], be: bool, coords: &mut [f64]) -> std::result::Result<(), usize> {
    let chunk = 1 << 16;
    // one monomorphised loop per scalar type when x, y, z share it (the usual case)
    macro_rules! same_type {
        ($t:ty, $n:expr) => {
            coords.par_chunks_mut(3 * chunk).enumerate().try_for_each(|(c, out)| {
                let recs = &data[c * chunk * stride..];
                for (j, o) in out.chunks_exact_mut(3).enumerate() {
                    let rec = &recs[j * stride..j * stride + stride];
                    for a in 0..3 {
                        let b: [u8; $n] = rec[fo[a]..fo[a] + $n].try_into().unwrap_or([0; $n]);
                        o[a] = (if be { <$t>::from_be_bytes(b) } else { <$t>::from_le_bytes(b) }) as f64;
                    }
                    if !(o[0].is_finite() && o[1].is_finite() && o[2].is_finite()) {
                        return Err(c * chunk + j);
                    }
                }
                Ok(())
            })
        };
    }
    if ty[0] == ty[1] && ty[1] == ty[2] && matches!(ty[0], Ty::F32 | Ty::F64) {
        if ty[0] == Ty::F64 {
            same_type!(f64, 8)?;
        } else {
            same_type!(f32, 4)?;
        }
        return Ok(());
    }
    coords.par_chunks_mut(3 * chunk).enumerate().try_for_each(|(c, out)| {
        for (j, o) in out.chunks_exact_mut(3).enumerate() {
            let rec = &data[(c * chunk + j) * stride..];
            for a in 0..3 {
                o[a] = ty[a].get(&rec[fo[a]..], be);
            }
            if !(o[0].is_finite() && o[1].is_finite() && o[2].is_finite()) {
                return Err(c * chunk + j);
            }
        }
        Ok(())
    })
}

fn count_desc(elements: &[Element]) -> String {
    elements.iter().map(|e| format!("{} {}", e.count, e.name)).collect::<Vec<_>>().join(", ")
}

#[allow(clippy::too_many_arguments)]
fn read_binary(
    bytes: &[u8],
    body: usize,
    elements: &[Element],
    vi: usize,
    idx: [usize; 3],
    be: bool,
    what: &str,
    coords: &mut [f64],
) -> Result<()> {
    walk_binary(bytes, body, elements, vi, Some(idx), be, what, coords)
}

/// Walk every element of a binary body, checking sizes; decode the vertices into
/// `coords` when `idx` (their x, y, z property indices) is given.
#[allow(clippy::too_many_arguments)]
fn walk_binary(
    bytes: &[u8],
    body: usize,
    elements: &[Element],
    vi: usize,
    idx: Option<[usize; 3]>,
    be: bool,
    what: &str,
    coords: &mut [f64],
) -> Result<()> {
    let truncated = || {
        GkError::file_format(format!(
            "{what}: the PLY file is shorter than its header declares ({}): truncated or a wrong count",
            count_desc(elements)
        ))
    };
    let mut off = body;
    for (k, el) in elements.iter().enumerate() {
        if let Some(stride) = el.fixed_size() {
            let size = stride.checked_mul(el.count).ok_or_else(truncated)?;
            let end = off.checked_add(size).filter(|&e| e <= bytes.len()).ok_or_else(truncated)?;
            if let (true, Some(idx)) = (k == vi, idx) {
                let field = |p: usize| el.props[..p].iter().map(|q| q.ty.size()).sum::<usize>();
                let (fo, ty) = (idx.map(field), idx.map(|p| el.props[p].ty));
                decode_fixed(&bytes[off..end], stride, fo, ty, be, coords).map_err(|i| non_finite(what, i))?;
            }
            off = end;
        } else {
            // records with list properties: walk them one by one
            for i in 0..el.count {
                let mut v = [0.0; 3];
                for (pi, p) in el.props.iter().enumerate() {
                    let n = match p.list {
                        Some(ct) => {
                            let b = bytes.get(off..off + ct.size()).ok_or_else(truncated)?;
                            let n = ct.get(b, be);
                            off += ct.size();
                            if !(0.0..=1e9).contains(&n) {
                                return Err(bad(what, format!("{} {i}: list length {n}", el.name)));
                            }
                            n as usize
                        }
                        None => 1,
                    };
                    let size = n * p.ty.size();
                    let b = bytes.get(off..off + size).ok_or_else(truncated)?;
                    if let (true, Some(idx)) = (k == vi, idx) {
                        if let Some(a) = idx.iter().position(|&x| x == pi) {
                            v[a] = p.ty.get(b, be);
                        }
                    }
                    off += size;
                }
                if k == vi && idx.is_some() {
                    if !v.iter().all(|x| x.is_finite()) {
                        return Err(non_finite(what, i));
                    }
                    coords[3 * i..3 * i + 3].copy_from_slice(&v);
                }
            }
        }
    }
    let extra = bytes.len() - off;
    if extra > 0 && !bytes[off..].iter().all(|b| b.is_ascii_whitespace() || *b == 0) || extra > 16 {
        let el = &elements[vi];
        let more = match (el.fixed_size(), vi + 1 == elements.len()) {
            (Some(s), true) if extra % s == 0 => format!(" (the file holds {} vertices)", el.count + extra / s),
            _ => String::new(),
        };
        return Err(GkError::file_format(format!(
            "{what}: {extra} bytes follow the data the PLY header declares ({}){more}: the header's counts are wrong",
            count_desc(elements)
        )));
    }
    Ok(())
}

fn read_ascii(
    bytes: &[u8],
    body: usize,
    elements: &[Element],
    vi: usize,
    idx: [usize; 3],
    what: &str,
    coords: &mut [f64],
) -> Result<()> {
    let text = &bytes[body..];
    if memchr::memchr(0, text).is_some() {
        return Err(bad(what, "binary bytes in an ASCII PLY body"));
    }
    let starts = line_starts(text);
    let nlines = if text.is_empty() { 0 } else { starts.len() };
    // header lines before the body, for 1-based line numbers in messages
    let line0 = bytes[..body].iter().filter(|&&b| b == b'\n').count();
    // non-blank lines in order
    let data: Vec<usize> = (0..nlines).filter(|&k| !trim(line_at(text, &starts, k)).is_empty()).collect();
    if let Some(e) = ascii_count_error(elements, vi, data.len(), what) {
        return Err(e);
    }
    let first: usize = elements[..vi].iter().map(|e| e.count).sum();
    let el = &elements[vi];
    let lines = &data[first..first + el.count];
    coords.par_chunks_mut(3 * 4096).enumerate().try_for_each(|(c, out)| {
        for (j, o) in out.chunks_exact_mut(3).enumerate() {
            let k = lines[c * 4096 + j];
            ascii_vertex(line_at(text, &starts, k), el, idx, line0 + k + 1, what, o)?;
        }
        Ok(())
    })
}

/// The x, y, z of one vertex line of an ASCII PLY body (1-based line `lno` of the file)
/// into `o`: every property of the vertex element in order (lists by their length).
fn ascii_vertex(line: &[u8], el: &Element, idx: [usize; 3], lno: usize, what: &str, o: &mut [f64]) -> Result<()> {
    let line = trim(line);
    let err = |m: &str| GkError::file_format(format!("{what}: line {lno}: {m}"));
    let mut tok = line.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty());
    for (pi, p) in el.props.iter().enumerate() {
        let n = match p.list {
            Some(_) => {
                let t = tok.next().ok_or_else(|| err("too few values for the vertex properties"))?;
                let n = parse_f64(t).filter(|n| (0.0..=1e9).contains(n) && n.fract() == 0.0);
                n.ok_or_else(|| err("a list length is not a count"))? as usize
            }
            None => 1,
        };
        for _ in 0..n {
            let t = tok.next().ok_or_else(|| err("too few values for the vertex properties"))?;
            let v = parse_f64(t).ok_or_else(|| err(&format!("{:?} is not a number", String::from_utf8_lossy(t))))?;
            if let Some(a) = idx.iter().position(|&x| x == pi) {
                if !v.is_finite() {
                    return Err(err("non-finite coordinate (NaN or inf)"));
                }
                o[a] = v;
            }
        }
    }
    if tok.next().is_some() {
        return Err(err("more values than the vertex properties of the header"));
    }
    Ok(())
}

/// The errors of an ASCII PLY body holding `data` non-blank lines where the header
/// declares other counts (the whole read's words).
fn ascii_count_error(elements: &[Element], vi: usize, data: usize, what: &str) -> Option<GkError> {
    let declared: usize = elements.iter().map(|e| e.count).sum();
    if data < declared {
        return Some(GkError::file_format(format!(
            "{what}: the PLY header declares {} ({declared} lines) but the file has {data} data lines: truncated or a wrong count",
            count_desc(elements),
        )));
    }
    if data > declared {
        let extra = data - declared;
        let more = if vi + 1 == elements.len() {
            format!(" (the file holds {} vertices)", elements[vi].count + extra)
        } else {
            String::new()
        };
        return Some(GkError::file_format(format!(
            "{what}: {extra} lines follow the data the PLY header declares ({}){more}: the header's counts are wrong",
            count_desc(elements)
        )));
    }
    None
}

/// The vertices of an ASCII PLY file read in blocks of lines, with bounded memory: a
/// first pass counts the body's non-blank lines (the whole read's count check, same
/// errors), then each [`PlyAsciiStream::next_chunk`] parses the next vertex lines in
/// parallel, by the whole read's rules ([`ascii_vertex`]: same values, same errors,
/// same line numbers).
pub struct PlyAsciiStream {
    file: std::fs::File,
    what: String,
    el: Element,
    idx: [usize; 3],
    /// Non-blank body lines before the first vertex (elements before `vertex`).
    skip: usize,
    /// Vertices read so far.
    done: usize,
    /// Bytes read and not yet consumed (whole lines from `line` on, then a partial line).
    carry: Vec<u8>,
    /// 1-based file line number of the first line of `carry`.
    line: usize,
    eof: bool,
    block: usize,
}

const PLY_BLOCK: usize = 8 << 20;

impl PlyAsciiStream {
    /// Open an ASCII PLY file (`Ok(None)` for a binary one): header checked, body lines
    /// counted against it in one bounded pass.
    pub fn open(path: &std::path::Path, what: &str) -> Result<Option<PlyAsciiStream>> {
        use std::io::{Read, Seek};
        let ply = PlyFile::open_lazy(path, what)?;
        if ply.format != Format::Ascii {
            return Ok(None);
        }
        let (elements, vi, idx, body) = (ply.elements.clone(), ply.vi, ply.idx, ply.body);
        let line0 = ply.map[..body].iter().filter(|&&b| b == b'\n').count();
        drop(ply);
        let io = |e: std::io::Error| crate::read_error(what, e);
        let mut file = std::fs::File::open(path).map_err(io)?;
        file.seek(std::io::SeekFrom::Start(body as u64)).map_err(io)?;
        let (mut data, mut buf, mut carry) = (0usize, vec![0u8; PLY_BLOCK], Vec::new());
        loop {
            let got = file.read(&mut buf).map_err(io)?;
            if memchr::memchr(0, &buf[..got]).is_some() {
                return Err(bad(what, "binary bytes in an ASCII PLY body"));
            }
            carry.extend_from_slice(&buf[..got]);
            let cut = if got == 0 { carry.len() } else { memchr::memrchr(b'\n', &carry).map_or(0, |i| i + 1) };
            data += carry[..cut].split(|&b| b == b'\n').filter(|l| !trim(l).is_empty()).count();
            carry.drain(..cut);
            if got == 0 {
                break;
            }
        }
        if let Some(e) = ascii_count_error(&elements, vi, data, what) {
            return Err(e);
        }
        file.seek(std::io::SeekFrom::Start(body as u64)).map_err(io)?;
        let skip = elements[..vi].iter().map(|e| e.count).sum();
        let el = elements[vi].clone();
        Ok(Some(PlyAsciiStream { file, what: what.to_string(), el, idx, skip, done: 0, carry: Vec::new(), line: line0 + 1, eof: false, block: PLY_BLOCK }))
    }

    /// Number of vertices.
    pub fn count(&self) -> usize {
        self.el.count
    }

    /// The next at most `max_points` vertices (x, y, z each), or `None` at the end.
    pub fn next_chunk(&mut self, max_points: usize) -> Result<Option<Vec<f64>>> {
        use std::io::Read;
        let want = max_points.max(1).min(self.el.count - self.done);
        if want == 0 {
            return Ok(None);
        }
        // (1-based line, start, end) of the next `want` vertex lines, in `carry`
        let mut lines: Vec<(usize, usize, usize)> = Vec::with_capacity(want);
        let (mut pos, mut lno) = (0usize, self.line);
        while lines.len() < want {
            let Some(e) = memchr::memchr(b'\n', &self.carry[pos..]).map(|i| pos + i).or((self.eof && pos < self.carry.len()).then_some(self.carry.len())) else {
                if self.eof {
                    break; // counted at open: cannot happen unless the file changed
                }
                let mut buf = vec![0u8; self.block];
                let got = self.file.read(&mut buf).map_err(|e| crate::read_error(&self.what, e))?;
                self.eof = got == 0;
                self.carry.extend_from_slice(&buf[..got]);
                continue;
            };
            if !trim(&self.carry[pos..e]).is_empty() {
                if self.skip > 0 {
                    self.skip -= 1;
                } else {
                    lines.push((lno, pos, e));
                }
            }
            pos = (e + 1).min(self.carry.len());
            lno += 1;
        }
        if lines.len() < want {
            return Err(bad(&self.what, "the file changed while it was read"));
        }
        let mut out = vec![0.0; 3 * want];
        let (carry, el, idx, what) = (&self.carry, &self.el, self.idx, self.what.as_str());
        out.par_chunks_mut(3 * 4096).enumerate().try_for_each(|(c, o)| {
            for (j, p) in o.chunks_exact_mut(3).enumerate() {
                let (l, a, b) = lines[c * 4096 + j];
                ascii_vertex(&carry[a..b], el, idx, l, what, p)?;
            }
            Ok::<(), GkError>(())
        })?;
        self.carry.drain(..pos);
        self.line = lno;
        self.done += want;
        Ok(Some(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bin(n_decl: usize, pts: &[[f32; 3]], extra: &str) -> Vec<u8> {
        let mut b = format!(
            "ply\nformat binary_little_endian 1.0\ncomment t\nelement vertex {n_decl}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n{extra}end_header\n"
        )
        .into_bytes();
        for p in pts {
            for v in p {
                b.extend_from_slice(&v.to_le_bytes());
            }
            b.push(7);
        }
        b
    }

    #[test]
    fn binary_and_counts() {
        let pts: Vec<[f32; 3]> = (0..50).map(|i| [i as f32, 2.0 * i as f32, -0.5]).collect();
        let p = read_ply(&bin(50, &pts, ""), "a.ply").unwrap();
        assert_eq!(p.coords.len(), 150);
        assert_eq!(&p.coords[3..6], &[1.0, 2.0, -0.5]);
        // issue 12: header says 10, file holds 50
        let e = read_ply(&bin(10, &pts, ""), "a.ply").unwrap_err();
        assert!(e.message.contains("holds 50 vertices"), "{}", e.message);
        let e = read_ply(&bin(60, &pts, ""), "a.ply").unwrap_err();
        assert!(e.message.contains("shorter"), "{}", e.message);
    }

    #[test]
    fn big_endian_and_faces() {
        let mut b = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
        for v in [1.0f64, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.5] {
            b.extend_from_slice(&v.to_be_bytes());
        }
        b.push(3);
        for i in [0i32, 1, 2] {
            b.extend_from_slice(&i.to_be_bytes());
        }
        let p = read_ply(&b, "f.ply").unwrap();
        assert_eq!(p.coords, vec![1., 2., 3., 4., 5., 6., 7., 8., 9.5]);
        b.extend_from_slice(&[0u8; 40]);
        assert!(read_ply(&b, "f.ply").is_err());
    }

    #[test]
    fn ascii_counts_and_lists() {
        let head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
        let ok = format!("{head}1 2 3\n4 5 6\n3 0 1 1\n");
        assert_eq!(read_ply(ok.as_bytes(), "a").unwrap().coords, vec![1., 2., 3., 4., 5., 6.]);
        let more = format!("{head}1 2 3\n4 5 6\n3 0 1 1\n7 8 9\n");
        assert!(read_ply(more.as_bytes(), "a").unwrap_err().message.contains("1 lines follow"));
        let short = format!("{head}1 2 3\n");
        assert!(read_ply(short.as_bytes(), "a").is_err());
        let bad = format!("{head}1 2 3 4\n4 5 6\n3 0 1 1\n");
        assert!(read_ply(bad.as_bytes(), "a").unwrap_err().message.contains("line 10"));
        let nan = format!("{head}1 nan 3\n4 5 6\n3 0 1 1\n");
        assert!(read_ply(nan.as_bytes(), "a").is_err());
    }

    #[test]
    fn header_errors() {
        for h in [
            &b""[..],
            b"ply\n",
            b"ply\nformat ascii 2.0\nend_header\n",
            b"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n",
            b"ply\nformat binary_little_endian 1.0\nelement vertex 99999999999999999\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
        ] {
            assert!(read_ply(h, "h").is_err());
        }
    }
}
