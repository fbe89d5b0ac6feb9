//! Streaming readers: the points of a file in chunks of bounded size, in file order,
//! each chunk exactly what the whole-file reader returns for those points (the same
//! parser, the same values, the same error for a bad point, naming its line or vertex).
//!
//! - [`AsciiStream`]: XYZ / CSV / TXT, blocks of bytes cut after a line break, each
//!   parsed in parallel by [`crate::ascii::parse_body`] with the layout (separator style,
//!   columns) decided once from the top of the file, as the whole read decides it.
//! - [`PlyStream`]: binary PLY whose elements all have fixed-size records: ranges of
//!   vertex records read with positioned reads (no memory map kept: the pages read
//!   never count towards the process's resident memory) and decoded in parallel; a
//!   float64 file larger than the page cache can hold is read past it (`O_DIRECT`,
//!   [`PlyStream::next_direct`]): no copy from the cache, no page to allocate and drop.

use crate::ascii::{ascii_layout, check_no_nul, parse_body, AsciiOptions, Layout};
use crate::ply::{PlyFile, VertexRecords};
use gagekit_core::{GkError, Result};
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::FileExt;
use std::path::Path;

/// Points read by one positioned read of a float64 PLY (768 KiB: the block is checked
/// finite while the core's cache holds it).
const READ_BLOCK: usize = 1 << 15;

fn io_error(what: &str) -> impl Fn(std::io::Error) -> GkError + '_ {
    move |e| crate::read_error(what, e)
}

/// An ASCII point file read in blocks of about `block` bytes.
pub struct AsciiStream {
    file: File,
    what: String,
    layout: Layout,
    /// Bytes read and not yet parsed (whole lines from `line` on, then a partial line).
    carry: Vec<u8>,
    /// 0-based index of the first line of `carry`.
    line: usize,
    block: usize,
    eof: bool,
    /// Header lines and columns, as [`crate::ascii::Parsed`] reports them.
    pub header_lines: usize,
}

impl AsciiStream {
    /// Open `path` and read its top until the first data line (the file's layout).
    pub fn open(path: &Path, opts: &AsciiOptions, what: &str, block: usize) -> Result<AsciiStream> {
        let mut file = File::open(path).map_err(io_error(what))?;
        let block = block.max(1 << 16);
        let mut head = Vec::new();
        let mut eof;
        loop {
            let want = head.len().max(block);
            let got = (&mut file).take(want as u64).read_to_end(&mut head).map_err(io_error(what))?;
            eof = got < want;
            // whole lines only, unless the file ends: a cut line could pass for a header
            let cut = if eof { head.len() } else { memchr::memrchr(b'\n', &head).map_or(0, |i| i + 1) };
            match ascii_layout(&head[..cut], opts, what) {
                Ok(ds) => {
                    check_no_nul(&head, what)?;
                    let carry = head.split_off(ds.offset);
                    return Ok(AsciiStream {
                        file,
                        what: what.to_string(),
                        header_lines: ds.layout.header_lines,
                        layout: ds.layout,
                        carry,
                        line: ds.line,
                        block,
                        eof,
                    });
                }
                Err(e) if eof || !e.message.contains("no points found") => return Err(e),
                Err(_) => {} // comments or headers longer than a block: read on
            }
        }
    }

    /// The columns the coordinates are taken from.
    pub fn columns(&self) -> &[usize] {
        &self.layout.columns
    }

    /// The next chunk of coordinates (`dim` per point; a chunk may be empty when a block
    /// holds only comments), or `None` at the end of the file.
    pub fn next_chunk(&mut self) -> Result<Option<Vec<f64>>> {
        if self.eof && self.carry.is_empty() {
            return Ok(None);
        }
        let mut cut = if self.eof { self.carry.len() } else { 0 };
        while !self.eof && cut == 0 {
            let before = self.carry.len();
            let want = self.block.saturating_sub(before).max(1 << 16);
            let got = (&mut self.file).take(want as u64).read_to_end(&mut self.carry).map_err(io_error(&self.what))?;
            check_no_nul(&self.carry[before..], &self.what)?;
            self.eof = got < want;
            cut = if self.eof { self.carry.len() } else { memchr::memrchr(b'\n', &self.carry).map_or(0, |i| i + 1) };
        }
        let (coords, lines) = parse_body(&self.carry[..cut], self.line, &self.layout, &self.what)?;
        self.line += lines;
        self.carry.drain(..cut);
        Ok(Some(coords))
    }
}

/// The vertices of a binary PLY file read in ranges of records.
pub struct PlyStream {
    file: File,
    what: String,
    rec: VertexRecords,
    next: usize,
    buf: Vec<u8>,
    /// Byte range (start, length) of the last range read: where the reads are heading
    /// (see [`advise`]), and dropped from the page cache when the next one is read if the
    /// file is larger than the cache can hold.
    read: Option<(u64, u64)>,
    /// Size of the file and of the machine's memory in bytes, for [`consumed_to_drop`]
    /// (memory 0: never drop, as on systems other than Linux).
    file_len: u64,
    mem: u64,
    /// The file opened a second time with `O_DIRECT` (Linux), for [`PlyStream::next_direct`]
    /// on a file larger than the page cache can hold: the device writes the records
    /// straight into the caller's buffer, with no page-cache copy, no page to allocate,
    /// account and drop again. `None`: every read goes through the page cache.
    direct: Option<File>,
}

/// Alignment of the memory, file offsets and lengths of an `O_DIRECT` read (the largest
/// logical block size of common devices).
pub const DIRECT_ALIGN: usize = 4096;

/// Bytes of a buffer for [`PlyStream::next_direct`] of `points` vertices: their 24
/// `points` bytes and the whole aligned blocks of an `O_DIRECT` read around them (up to
/// one block to align the buffer's start, one before the first point and one after the
/// last). Saturates at `usize::MAX` (no buffer that large exists, so a count beyond any
/// file is refused rather than wrapped to a small size).
pub fn direct_buffer_len(points: usize) -> usize {
    points.saturating_mul(24).saturating_add(3 * DIRECT_ALIGN)
}

/// Read at least `need` bytes of `file` from `at` into `area` (aligned reads of whole
/// blocks); false when the file ends before.
fn read_direct(file: &File, area: &mut [u8], at: u64, need: usize) -> std::io::Result<bool> {
    let mut got = 0;
    while got < need {
        match file.read_at(&mut area[got..], at + got as u64) {
            Ok(0) => return Ok(false),
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(true)
}

/// Open `path` for `O_DIRECT` reads, or `None` where the system or the file system has none.
fn open_direct(path: &Path) -> Option<File> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        std::fs::OpenOptions::new().read(true).custom_flags(libc::O_DIRECT).open(path).ok()
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = path;
        None
    }
}

/// The byte range (start, length) of the page cache to drop once a stream has read the
/// range `prev` and goes on to another one, or `None` to keep everything.
///
/// A file that fits in the page cache (at most half of the machine's memory `mem`) is
/// never dropped from it: a second pass or a re-run reads it from memory. A larger file
/// cannot stay cached anyway; without a hint the kernel fills the cache with it and
/// then reclaims pages under pressure while the stream reads on, CPU spent on every
/// page. Dropping each range once it is consumed (in either direction of reading) keeps
/// the cache from filling. The last quarter of `mem`'s worth of the file is never
/// dropped: a forward pass reads it last and a backward second pass (from the end of the
/// file back, [`PlyStream::seek`]) starts there, from memory.
pub(crate) fn consumed_to_drop(file_len: u64, mem: u64, prev: (u64, u64)) -> Option<(u64, u64)> {
    if mem == 0 || file_len <= mem / 2 {
        return None;
    }
    let keep_from = file_len.saturating_sub(mem / 4);
    let end = prev.0.saturating_add(prev.1).min(keep_from);
    (end > prev.0).then(|| (prev.0, end - prev.0))
}

/// The machine's physical memory in bytes; 0 where unknown (then nothing is dropped).
fn physical_memory() -> u64 {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: plain queries without arguments to fill.
        let (pages, size) = unsafe { (libc::sysconf(libc::_SC_PHYS_PAGES), libc::sysconf(libc::_SC_PAGESIZE)) };
        if pages > 0 && size > 0 {
            return (pages as u64).saturating_mul(size as u64);
        }
    }
    0
}

/// Ask the kernel to start reading `len` bytes of `file` at `at` into the page cache now
/// (`POSIX_FADV_WILLNEED`): the disk reads the range a stream will ask for next while
/// the cores work on the range just read. Only a hint: where it fails or is not
/// available, the read itself reads the range as before.
fn advise(file: &File, at: u64, len: usize, how: Advice) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::io::AsRawFd;
        let advice = match how {
            Advice::Sequential => libc::POSIX_FADV_SEQUENTIAL,
            Advice::WillNeed => libc::POSIX_FADV_WILLNEED,
            Advice::DontNeed => libc::POSIX_FADV_DONTNEED,
        };
        // SAFETY: a plain system call on an open descriptor; any range is valid for it.
        unsafe { libc::posix_fadvise(file.as_raw_fd(), at as libc::off_t, len as libc::off_t, advice) };
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (file, at, len, how);
}

#[derive(Clone, Copy)]
enum Advice {
    /// The whole file is read in order (a larger kernel read-ahead window).
    Sequential,
    /// This range is needed soon.
    WillNeed,
    /// This range was consumed: its pages may leave the page cache (whole pages only:
    /// the kernel keeps a page the range only partly covers).
    DontNeed,
}

impl PlyStream {
    /// Open a binary PLY file whose elements all have fixed-size records (sizes checked
    /// against the header as a whole read checks them); `Ok(None)` for an ASCII PLY or
    /// one with list properties (faces), which are read whole.
    pub fn open(path: &Path, what: &str) -> Result<Option<PlyStream>> {
        let ply = PlyFile::open_lazy(path, what)?;
        let Some(rec) = ply.vertex_records()? else { return Ok(None) };
        drop(ply);
        let file = File::open(path).map_err(io_error(what))?;
        advise(&file, 0, 0, Advice::Sequential);
        let file_len = file.metadata().map_or(0, |m| m.len());
        let mem = physical_memory();
        let mut s = PlyStream { file, what: what.to_string(), rec, next: 0, buf: Vec::new(), read: None, file_len, mem, direct: None };
        // a file the page cache cannot hold is read past it (its pages would only be
        // dropped again: see consumed_to_drop)
        let large = mem > 0 && file_len > mem / 2;
        s.set_direct(path, large);
        Ok(Some(s))
    }

    /// Read the records past the page cache (`O_DIRECT`) in [`PlyStream::next_direct`], or
    /// not. Only float64 x, y, z records at an offset that is a multiple of 8 can be read so
    /// (they are the points, in place); where the system or file system has no `O_DIRECT`,
    /// the reads stay buffered. Whether the reads go direct.
    pub fn set_direct(&mut self, path: &Path, on: bool) -> bool {
        let able = self.rec.is_f64_xyz() && cfg!(target_endian = "little") && self.rec.offset % 8 == 0;
        self.direct = if on && able { open_direct(path) } else { None };
        self.direct.is_some()
    }

    /// Whether the reads of [`PlyStream::next_direct`] go past the page cache.
    pub fn is_direct(&self) -> bool {
        self.direct.is_some()
    }

    /// Number of vertices.
    pub fn count(&self) -> usize {
        self.rec.count
    }

    /// The next at most `max_points` vertices (x, y, z each), or `None` at the end.
    pub fn next_chunk(&mut self, max_points: usize) -> Result<Option<Vec<f64>>> {
        let m = max_points.max(1).min(self.rec.count - self.next);
        if m == 0 {
            return Ok(None);
        }
        let mut out = vec![0.0f64; 3 * m];
        self.next_into(&mut out)?;
        Ok(Some(out))
    }

    /// Move to vertex `index` (at most the count): the next read starts there (the
    /// ranges may be read in any order, e.g. from the end of the file back).
    pub fn seek(&mut self, index: usize) {
        self.next = index.min(self.rec.count);
    }

    /// The next at most `max_points` vertices into the byte buffer `buf` (reused from
    /// chunk to chunk; at least [`direct_buffer_len`] of the points read, `max_points` or
    /// the fewer left, else an invalid-argument error): (byte offset in
    /// `buf` of the first point, number of points), the points being float64 x, y, z rows
    /// from that offset, which is a multiple of 8 from an 8-aligned `buf`. Past the page
    /// cache when [`PlyStream::is_direct`] (the device writes whole aligned blocks around
    /// the points; the bytes of `buf` outside the points are left undefined), else as
    /// [`PlyStream::next_into`]. The same values and errors as `next_into`; 0 points at
    /// the end.
    pub fn next_direct(&mut self, buf: &mut [u8], max_points: usize) -> Result<(usize, usize)> {
        let m = max_points.min(self.rec.count - self.next);
        if buf.len() < direct_buffer_len(m) {
            return Err(GkError::invalid(format!("{}: a read buffer of {} bytes for {m} points; expected at least {}", self.what,
                                                buf.len(), direct_buffer_len(m))));
        }
        if m == 0 {
            return Ok((0, 0));
        }
        let at = self.rec.offset + self.next * self.rec.stride;
        let pad = buf.as_ptr().align_offset(DIRECT_ALIGN);
        let head = at % DIRECT_ALIGN;
        if let Some(f) = &self.direct {
            // whole aligned blocks from the one holding the first point to the one
            // holding the last, into the aligned part of `buf`: the first point lands at
            // pad + head (a multiple of 8 from buf's alignment: `at` is one of 8)
            let need = head + 24 * m;
            let len = need.div_ceil(DIRECT_ALIGN) * DIRECT_ALIGN;
            match read_direct(f, &mut buf[pad..pad + len], (at - head) as u64, need) {
                Ok(true) => {}
                Ok(false) => return Err(GkError::file_format(format!("{}: the file ends before its last vertex", self.what))),
                Err(e) if e.raw_os_error() == Some(libc::EINVAL) => {
                    // no O_DIRECT for this file after all: buffered from here on
                    self.direct = None;
                    return self.next_direct(buf, max_points);
                }
                Err(e) => return Err(io_error(&self.what)(e)),
            }
            let s = pad + head;
            // SAFETY: s is 8-aligned in memory (pad aligns to 4096, head is a multiple of
            // 8), and s + 24 m <= pad + len <= buf.len(); any 8 bytes are a valid f64.
            let out = unsafe { std::slice::from_raw_parts(buf.as_ptr().add(s).cast::<f64>(), 3 * m) };
            for (b, block) in out.chunks(3 * READ_BLOCK).enumerate() {
                self.check_finite(block, b)?;
            }
            self.next += m;
            return Ok((s, m));
        }
        let s = buf.as_ptr().align_offset(8);
        // SAFETY: s is 8-aligned in memory and s + 24 m <= buf.len() (s < 8 <= direct_buffer_len(0)).
        let out = unsafe { std::slice::from_raw_parts_mut(buf.as_mut_ptr().add(s).cast::<f64>(), 3 * m) };
        let k = self.next_into(out)?;
        Ok((s, k))
    }

    /// The error of a non-finite coordinate in `block` (block number `b` of READ_BLOCK
    /// points from the vertex `self.next`), if any.
    fn check_finite(&self, block: &[f64], b: usize) -> Result<()> {
        if block.iter().fold(true, |ok, v| ok & v.is_finite()) {
            return Ok(());
        }
        let i = b * READ_BLOCK + block.iter().position(|v| !v.is_finite()).unwrap_or(0) / 3;
        Err(GkError::file_format(format!("{}: vertex {} has a non-finite coordinate (NaN or inf)", self.what, self.next + i)))
    }

    /// The next vertices into `out` (as many as fit: `out.len() / 3`, fewer at the end of
    /// the file), reusing the caller's buffer (no fresh pages a chunk); the number read,
    /// 0 at the end.
    pub fn next_into(&mut self, out: &mut [f64]) -> Result<usize> {
        let m = (out.len() / 3).min(self.rec.count - self.next);
        if m == 0 {
            return Ok(0);
        }
        let out = &mut out[..3 * m];
        let at = (self.rec.offset + self.next * self.rec.stride) as u64;
        // the range after this one (before it, when the reads go from the end of the file
        // back) is asked for while this one is read and worked on
        let ahead = if self.read.is_some_and(|(l, _)| l > at) { self.next.checked_sub(m) } else { Some(self.next + m) };
        if let Some(a) = ahead.filter(|&a| a < self.rec.count) {
            let k = m.min(self.rec.count - a);
            advise(&self.file, (self.rec.offset + a * self.rec.stride) as u64, k * self.rec.stride, Advice::WillNeed);
        }
        // the range read before this one is consumed: off the page cache if the file is
        // larger than the cache can hold (its end kept for a backward pass)
        if let Some((a, k)) = self.read.and_then(|prev| consumed_to_drop(self.file_len, self.mem, prev)) {
            advise(&self.file, a, k as usize, Advice::DontNeed);
        }
        self.read = Some((at, (m * self.rec.stride) as u64));
        if self.rec.is_f64_xyz() && cfg!(target_endian = "little") {
            // the records are the points: read them straight into the output, a block at a
            // time, each block checked finite while the core's cache still holds it (one
            // pass over memory instead of a read and a second pass to check)
            for (b, block) in out.chunks_mut(3 * READ_BLOCK).enumerate() {
                // SAFETY: any 8 bytes are a valid f64 bit pattern; the slice covers `block` exactly.
                let bytes = unsafe { std::slice::from_raw_parts_mut(block.as_mut_ptr().cast::<u8>(), 8 * block.len()) };
                self.file.read_exact_at(bytes, at + (24 * b * READ_BLOCK) as u64).map_err(io_error(&self.what))?;
                self.check_finite(block, b)?;
            }
        } else {
            self.buf.resize(m * self.rec.stride, 0);
            self.file.read_exact_at(&mut self.buf, at).map_err(io_error(&self.what))?;
            self.rec.decode(&self.buf, self.next, out, &self.what)?;
        }
        self.next += m;
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ascii::{parse_ascii, write_ascii};
    use crate::ply::read_ply_file;

    fn tmp(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("gk-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    fn drain_ascii(p: &Path, block: usize) -> Result<Vec<f64>> {
        let mut s = AsciiStream::open(p, &AsciiOptions::default(), "s", block)?;
        s.block = block; // below the floor of `open`, to cut many blocks
        let mut all = Vec::new();
        while let Some(c) = s.next_chunk()? {
            all.extend(c);
        }
        Ok(all)
    }

    #[test]
    fn ascii_blocks_equal_the_whole_read() {
        let coords: Vec<f64> = (0..3 * 5000).map(|i| (i as f64) * 0.0137 - 41.5).collect();
        let mut text = b"# scan\nX,Y,Z,i\n".to_vec();
        text.extend(write_ascii(&coords, 3, b',', None).unwrap());
        text.extend_from_slice(b"\n# end\n1,2,3");
        let p = tmp("a.csv", &text);
        let whole = parse_ascii(&text, &AsciiOptions::default(), "s").unwrap().coords;
        for block in [1, 7, 100, 4096, 1 << 20] {
            assert_eq!(drain_ascii(&p, block).unwrap(), whole, "block {block}");
        }
        let mut bad = text.clone();
        bad.extend_from_slice(b"\n4,x,6\n");
        let p = tmp("b.csv", &bad);
        let want = parse_ascii(&bad, &AsciiOptions::default(), "s").unwrap_err().message;
        for block in [1, 100, 1 << 20] {
            assert_eq!(drain_ascii(&p, block).unwrap_err().message, want);
        }
    }

    /// A non-finite coordinate is the same error (the vertex named in the whole file)
    /// whether it lies in the first read block of a range or a later one, and whatever
    /// range it is read in.
    #[test]
    fn a_non_finite_vertex_is_named_in_any_block() {
        let n = 2 * READ_BLOCK + 100;
        for bad in [0, 7, READ_BLOCK - 1, READ_BLOCK, READ_BLOCK + 5, n - 1] {
            let mut b = format!("ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\nend_header\n").into_bytes();
            for i in 0..3 * n {
                let v = if i == 3 * bad + 2 { f64::NAN } else { i as f64 * 0.5 };
                b.extend_from_slice(&v.to_le_bytes());
            }
            let p = tmp(&format!("nan{bad}.ply"), &b);
            let want = format!("s: vertex {bad} has a non-finite coordinate (NaN or inf)");
            let mut s = PlyStream::open(&p, "s").unwrap().unwrap();
            assert_eq!(s.next_into(&mut vec![0.0; 3 * n]).unwrap_err().message, want);
            let mut s = PlyStream::open(&p, "s").unwrap().unwrap();
            let step = READ_BLOCK / 2 + 3;
            let mut got = None;
            for start in (0..n).step_by(step) {
                s.seek(start);
                if let Err(e) = s.next_into(&mut vec![0.0; 3 * step]) {
                    got = Some((start, e.message));
                    break;
                }
            }
            assert_eq!(got, Some((bad / step * step, want)));
        }
    }

    #[test]
    fn ply_ranges_equal_the_whole_read() {
        let n = 1000usize;
        for (ty, size, be) in [("double", 8, false), ("float", 4, false), ("float", 4, true)] {
            let fmt = if be { "binary_big_endian" } else { "binary_little_endian" };
            let mut b = format!("ply\nformat {fmt} 1.0\nelement vertex {n}\nproperty {ty} x\nproperty {ty} y\nproperty {ty} z\nend_header\n").into_bytes();
            for i in 0..3 * n {
                let v = i as f64 * 0.25 - 7.0;
                match (size, be) {
                    (8, _) => b.extend_from_slice(&v.to_le_bytes()),
                    (_, false) => b.extend_from_slice(&(v as f32).to_le_bytes()),
                    _ => b.extend_from_slice(&(v as f32).to_be_bytes()),
                }
            }
            let p = tmp(&format!("p{size}{be}.ply"), &b);
            let whole = read_ply_file(&p, "s").unwrap().coords;
            let mut s = PlyStream::open(&p, "s").unwrap().unwrap();
            reads_the_whole_forward_and_back(&mut s, &whole, 77);
            s.seek(n + 5);
            assert_eq!(s.next_into(&mut vec![0.0; 3 * n]).unwrap(), 0);
        }
    }

    /// `s` read forward in ranges of `step` points, then from the end back after a seek
    /// each: both times the rows of the whole read `whole`.
    /// A float64 PLY whose header is padded to `pad` bytes past a multiple of 8.
    fn f64_ply(name: &str, n: usize, pad: usize, nan_at: Option<usize>) -> (std::path::PathBuf, Vec<f64>) {
        let mut head = format!("ply\nformat binary_little_endian 1.0\ncomment x\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\nend_header\n");
        while head.len() % 8 != pad {
            head = head.replacen("comment x", "comment xx", 1);
        }
        let mut b = head.into_bytes();
        let vals: Vec<f64> = (0..3 * n).map(|i| if nan_at == Some(i / 3) && i % 3 == 1 { f64::NAN } else { i as f64 * 0.125 - 9.0 }).collect();
        for v in &vals {
            b.extend_from_slice(&v.to_le_bytes());
        }
        (tmp(name, &b), vals)
    }

    /// Reads past the page cache (O_DIRECT, on a file system that has it) give the
    /// buffered reads' points, forward and from the end back, for chunks across the
    /// device's blocks, from buffers at any 8-byte offset; a header at an offset that is
    /// not a multiple of 8 reads buffered, and a non-finite vertex is named alike.
    #[test]
    fn direct_reads_equal_the_buffered_ones() {
        let n = 5000;
        let (p, whole) = f64_ply("direct.ply", n, 0, None);
        for on in [true, false] {
            let mut s = PlyStream::open(&p, "s").unwrap().unwrap();
            let direct = s.set_direct(&p, on);
            assert!(!on || direct || cfg!(not(target_os = "linux")), "ext4 and most Linux file systems have O_DIRECT");
            for step in [1usize, 77, 700, 5000] {
                for shift in [0usize, 8, 24, 4000] {
                    let mut buf = vec![0u8; shift + direct_buffer_len(step)];
                    let buf = &mut buf[shift..];
                    let starts: Vec<usize> = (0..n).step_by(step).collect();
                    for &start in starts.iter().rev().chain(&starts) {
                        s.seek(start);
                        let (at, k) = s.next_direct(buf, step).unwrap();
                        assert_eq!(k, step.min(n - start));
                        assert_eq!((buf.as_ptr() as usize + at) % 8, 0);
                        let got: Vec<f64> = buf[at..at + 24 * k].chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect();
                        assert_eq!(got, whole[3 * start..3 * (start + k)], "on {on} step {step} shift {shift} start {start}");
                    }
                    s.seek(n);
                    assert_eq!(s.next_direct(buf, step).unwrap().1, 0);
                }
            }
        }
        // a buffer too small for the points read is an error, not a panic; one for the
        // points left is enough however many are asked for
        let mut s = PlyStream::open(&p, "s").unwrap().unwrap();
        s.set_direct(&p, true);
        let mut small = vec![0u8; direct_buffer_len(100) - 1];
        let e = s.next_direct(&mut small, 100).unwrap_err();
        assert_eq!(e.kind, gagekit_core::ErrorKind::InvalidInput);
        assert!(e.message.contains("expected at least 14688"), "{}", e.message);
        s.seek(n - 10);
        assert_eq!(direct_buffer_len(usize::MAX / 8), usize::MAX);
        let mut ten = vec![0u8; direct_buffer_len(10)];
        assert_eq!(s.next_direct(&mut ten, 1000).unwrap().1, 10);
        let (q, _) = f64_ply("direct4.ply", 300, 4, None);
        assert!(!PlyStream::open(&q, "s").unwrap().unwrap().set_direct(&q, true));
        let (r, _) = f64_ply("directnan.ply", n, 0, Some(4321));
        for on in [true, false] {
            let mut s = PlyStream::open(&r, "r").unwrap().unwrap();
            s.set_direct(&r, on);
            let mut buf = vec![0u8; direct_buffer_len(3000)];
            s.seek(2000);
            assert_eq!(s.next_direct(&mut buf, 3000).unwrap_err().message, "r: vertex 4321 has a non-finite coordinate (NaN or inf)");
        }
    }

    fn reads_the_whole_forward_and_back(s: &mut PlyStream, whole: &[f64], step: usize) {
        let n = whole.len() / 3;
        let mut all = Vec::new();
        while let Some(c) = s.next_chunk(step).unwrap() {
            all.extend(c);
        }
        assert_eq!(all, whole);
        let mut back = vec![0.0; 3 * n];
        for start in (0..n).step_by(step).rev() {
            s.seek(start);
            let k = s.next_into(&mut back[3 * start..3 * (start + step).min(n)]).unwrap();
            assert_eq!(k, step.min(n - start));
        }
        assert_eq!(back, whole);
    }

    #[test]
    fn consumed_ranges_are_dropped_only_from_a_file_larger_than_the_cache() {
        const G: u64 = 1 << 30;
        let mem = 24 * G;
        // a file that fits in the cache (up to half the memory): nothing dropped, at any
        // position, in either direction
        for len in [0, 1, G, 12 * G] {
            for prev in [(0, 1 << 20), (len / 2, 1 << 20), (len.saturating_sub(1 << 20), 1 << 20)] {
                assert_eq!(consumed_to_drop(len, mem, prev), None, "file {len} range {prev:?}");
            }
        }
        // unknown memory: nothing dropped
        assert_eq!(consumed_to_drop(24 * G, 0, (0, G)), None);
        // a 24 GB file: the range consumed is dropped, forward (the range before the
        // current one) as backward (the range after it)
        let len = 24 * G;
        let keep_from = len - mem / 4; // the last 6 GB stay cached
        assert_eq!(consumed_to_drop(len, mem, (0, 100 << 20)), Some((0, 100 << 20)));
        assert_eq!(consumed_to_drop(len, mem, (5 * G, 100 << 20)), Some((5 * G, 100 << 20)));
        // a range across the kept end: only its part before the end is dropped
        assert_eq!(consumed_to_drop(len, mem, (keep_from - 10, 100)), Some((keep_from - 10, 10)));
        // ranges inside the kept end: never dropped
        assert_eq!(consumed_to_drop(len, mem, (keep_from, 100 << 20)), None);
        assert_eq!(consumed_to_drop(len, mem, (len - (100 << 20), 100 << 20)), None);
        // just over half the memory: dropped below the last quarter
        let len = 12 * G + 1;
        assert_eq!(consumed_to_drop(len, mem, (0, G)), Some((0, G)));
        assert_eq!(consumed_to_drop(len, mem, (6 * G, G)), Some((6 * G, 1)));
        // empty ranges and ranges past any size: no drop, no overflow
        assert_eq!(consumed_to_drop(len, mem, (0, 0)), None);
        assert_eq!(consumed_to_drop(u64::MAX, mem, (u64::MAX - 1, u64::MAX)), None);
        assert_eq!(consumed_to_drop(u64::MAX, mem, (0, u64::MAX)), Some((0, u64::MAX - mem / 4)));
    }

    #[test]
    fn ply_ranges_read_the_same_while_dropping_what_was_read() {
        // a memory small enough that the file counts as larger than the cache: the
        // consumed ranges are dropped from the page cache as the stream reads on
        let n = 20_000usize;
        let mut b = format!("ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\nend_header\n").into_bytes();
        for i in 0..3 * n {
            b.extend_from_slice(&(i as f64 * 0.5 - 3.0).to_le_bytes());
        }
        let p = tmp("drop.ply", &b);
        let whole = read_ply_file(&p, "s").unwrap().coords;
        let mut s = PlyStream::open(&p, "s").unwrap().unwrap();
        s.mem = 4 * 4096; // keeps the last 4 KiB
        assert!(consumed_to_drop(s.file_len, s.mem, (0, s.file_len)).is_some());
        reads_the_whole_forward_and_back(&mut s, &whole, 1000);
    }
}

#[cfg(test)]
mod timing {
    #[test]
    #[ignore]
    fn parse_speed() {
        let p = std::path::Path::new("/tmp/scale_a.xyz");
        let bytes = std::fs::read(p).unwrap();
        let opts = crate::ascii::AsciiOptions::default();
        // user and system CPU seconds of this process (the machine may be shared)
        let cpu = || {
            let s = std::fs::read_to_string("/proc/self/stat").unwrap();
            let f: Vec<f64> = s.rsplit(')').next().unwrap().split_whitespace().skip(11).take(2).map(|x| x.parse().unwrap()).collect();
            (f[0] / 100.0, f[1] / 100.0)
        };
        for _ in 0..3 {
            let t = std::time::Instant::now();
            let c0 = cpu();
            let r = crate::ascii::parse_ascii(&bytes, &opts, "t").unwrap();
            let el = t.elapsed().as_secs_f64();
            let c1 = cpu();
            println!("parse {:.3}s {:.0} MB/s n={} cpu user {:.2}s sys {:.2}s", el, bytes.len() as f64 / el / 1e6, r.coords.len(), c1.0 - c0.0, c1.1 - c0.1);
            let t = std::time::Instant::now();
            let n: usize = memchr::memchr_iter(b'\n', &bytes).count();
            println!("count {:.3}s {n}", t.elapsed().as_secs_f64());
        }
    }
}
