//! E57 (ASTM E2807) points streamed data packet by data packet: memory bounded by the
//! chunk, whatever the file's size (the 227 M-point files that crash whole reads).
//!
//! The `e57` crate reads the XML section (scans, prototypes, poses, record counts). Each
//! scan's `CompressedVector` section is then read in order: data packets (type 1) append
//! the buffers of the coordinate fields (x, y, z or range, azimuth, elevation, and the
//! invalid state) to one bit stream per field; index packets (type 0) and empty packets
//! (type 2) are skipped by their length. As soon as every field holds the values of a
//! chunk, they are decoded ([`crate::e57_fast::decode_field_at`]: value i from bit
//! `i * bits` of the field's stream, as the whole read decodes it), the decoded bytes
//! are dropped, and the valid points are posed ([`crate::e57_fast::place_points`]): each
//! point is the same arithmetic on the same bits as in [`crate::read_e57`], so the
//! chunks are bit for bit the rows of a whole read.
//!
//! Pages are read with positioned reads into a reused window of [`WINDOW`] bytes (no
//! memory map: pages read never count towards the process's resident memory), and each
//! page's CRC-32C is checked before its bytes are used.
//!
//! A file the fast path cannot stream (a scan without a coordinate triple, integers wider
//! than 56 bits, a section that is not a compressed vector) opens as `None`: the caller
//! reads it whole, through the crate's reader where needed.

use crate::e57_fast::{bits, coordinate_fields, decode_field_at, place_points, pose, CRC};
use e57::{PointCloud, RecordDataType};
use gagekit_core::{GkError, Result};
use rayon::prelude::*;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::Path;

/// Bytes of the file read at once (whole pages), their CRCs checked in parallel.
pub const WINDOW: usize = 8 << 20;

/// The physical pages of an E57 file read through a window, CRC-checked: the logical byte
/// stream (page payloads without their checksums).
struct Pages {
    file: File,
    len: usize,
    page: usize,
    /// Physical offset of `buf[0]` (a page boundary) and the checked bytes held.
    start: usize,
    buf: Vec<u8>,
    what: String,
}

impl Pages {
    /// Make sure the page holding physical byte `pos` is in the window (checked).
    fn load(&mut self, pos: usize) -> Result<()> {
        if pos >= self.start && pos < self.start + self.buf.len() {
            return Ok(());
        }
        let p = pos / self.page;
        let start = p * self.page;
        if start + self.page > self.len {
            return Err(GkError::file_format(format!("{}: not a readable E57 file (truncated: page {p} is missing)", self.what)));
        }
        let pages = ((self.len - start) / self.page).min((WINDOW / self.page).max(1));
        self.buf.resize(pages * self.page, 0);
        self.file.read_exact_at(&mut self.buf, start as u64).map_err(|e| crate::read_error(&self.what, e))?;
        self.start = start;
        let page = self.page;
        let bad = self.buf.par_chunks(page).with_min_len(64).position_first(|b| {
            crc32c::crc32c(&b[..page - CRC]).to_be_bytes() != b[page - CRC..]
        });
        if let Some(k) = bad {
            self.buf.clear();
            return Err(GkError::file_format(format!(
                "{}: not a readable E57 file (checksum mismatch on page {})",
                self.what,
                p + k
            )));
        }
        Ok(())
    }

    /// Append `n` logical bytes from physical position `*pos` to `out` (or skip them when
    /// `out` is `None`), moving `*pos`.
    fn read(&mut self, pos: &mut usize, mut n: usize, mut out: Option<&mut Vec<u8>>) -> Result<()> {
        while n > 0 {
            let in_page = *pos % self.page;
            if in_page >= self.page - CRC {
                *pos += self.page - in_page;
                continue;
            }
            let take = n.min(self.page - CRC - in_page);
            if let Some(o) = out.as_deref_mut() {
                self.load(*pos)?;
                let i = *pos - self.start;
                o.extend_from_slice(&self.buf[i..i + take]);
            }
            *pos += take;
            n -= take;
        }
        Ok(())
    }

    fn bytes<const N: usize>(&mut self, pos: &mut usize) -> Result<[u8; N]> {
        let mut v = Vec::with_capacity(N);
        self.read(pos, N, Some(&mut v))?;
        let mut a = [0u8; N];
        a.copy_from_slice(&v);
        Ok(a)
    }
}

/// What the stream needs of one scan.
struct Scan {
    /// The prototype fields read: x, y, z (or range, azimuth, elevation), then the
    /// invalid state if any.
    fields: Vec<usize>,
    types: Vec<RecordDataType>,
    spherical: bool,
    pose: ([[f64; 3]; 3], [f64; 3]),
    records: usize,
    nfields: usize,
    /// Physical offset of the first data packet.
    data: usize,
}

/// The points of an E57 file in chunks (see the module documentation).
pub struct E57Stream {
    pages: Pages,
    scans: Vec<Scan>,
    /// Current scan, its next packet's physical offset, records decoded so far.
    cur: usize,
    pos: usize,
    done: usize,
    /// Per read field: the bytes not yet decoded, and the bit where the next value starts.
    streams: Vec<Vec<u8>>,
    bit0: Vec<usize>,
    sizes: Vec<u8>,
    /// Valid points handed out, and points dropped for their invalid state.
    points: usize,
    invalid: usize,
}

impl E57Stream {
    /// Open `path`: its XML (through the `e57` crate) and every scan's section header;
    /// `None` when a scan is not one the stream reads (the caller reads the file whole).
    pub fn open(path: &Path, what: &str) -> Result<Option<E57Stream>> {
        let file = File::open(path).map_err(|e| crate::read_error(what, e))?;
        let len = file.metadata().map_err(|e| crate::read_error(what, e))?.len() as usize;
        let reader = e57::E57Reader::new(std::io::BufReader::new(file.try_clone().map_err(|e| crate::read_error(what, e))?))
            .map_err(|e| crate::e57::unreadable(what, e))?;
        let page = reader.header().page_size as usize;
        if page <= CRC {
            return Ok(None);
        }
        let mut pages = Pages { file, len, page, start: 0, buf: Vec::new(), what: what.to_string() };
        let mut scans = Vec::new();
        for pc in reader.pointclouds() {
            match scan_plan(&mut pages, &pc, what)? {
                Some(s) => scans.push(s),
                None => return Ok(None),
            }
        }
        let mut s = E57Stream { pages, scans, cur: 0, pos: 0, done: 0, streams: Vec::new(), bit0: Vec::new(), sizes: Vec::new(), points: 0, invalid: 0 };
        s.start_scan();
        Ok(Some(s))
    }

    /// Number of scans (`data3D` entries).
    pub fn scans(&self) -> usize {
        self.scans.len()
    }

    /// Records of every scan (valid and invalid points).
    pub fn records(&self) -> usize {
        self.scans.iter().map(|s| s.records).sum()
    }

    /// Points dropped so far because their invalid state was not 0.
    pub fn invalid_dropped(&self) -> usize {
        self.invalid
    }

    fn start_scan(&mut self) {
        if let Some(s) = self.scans.get(self.cur) {
            self.pos = s.data;
            self.done = 0;
            self.streams = vec![Vec::new(); s.fields.len()];
            self.bit0 = vec![0; s.fields.len()];
        }
    }

    /// The next chunk of at most `max_points` records' valid points (x, y, z, metres,
    /// pose applied; it may be empty when every record of it is invalid), `None` at the end.
    pub fn next_chunk(&mut self, max_points: usize) -> Result<Option<Vec<f64>>> {
        while self.cur < self.scans.len() && self.done == self.scans[self.cur].records {
            self.cur += 1;
            self.start_scan();
        }
        let Some(scan) = self.scans.get(self.cur) else { return Ok(None) };
        let what = self.pages.what.clone();
        let want = max_points.max(1).min(scan.records - self.done);
        let need: Vec<usize> = scan.types.iter().zip(&self.bit0).map(|(t, &b0)| b0 + bits(t) * want).collect();
        while self.streams.iter().zip(&need).any(|(s, &k)| s.len() * 8 < k) {
            self.packet(what.as_str())?;
        }
        let scan = &self.scans[self.cur];
        let decoded: Option<Vec<Vec<f64>>> = (0..scan.fields.len())
            .into_par_iter()
            .map(|f| decode_field_at(&self.streams[f], self.bit0[f], &scan.types[f], want))
            .collect();
        let Some(v) = decoded else {
            return Err(GkError::file_format(format!("{what}: not a readable E57 file (scan {}: a field is wider than 56 bits)", self.cur)));
        };
        for (f, t) in scan.types.iter().enumerate() {
            let used = self.bit0[f] + bits(t) * want;
            self.streams[f].drain(..used / 8);
            self.bit0[f] = used % 8;
        }
        let st = scan.fields.get(3).map(|_| v[3].as_slice());
        let (coords, bad) = place_points(&v[..3], st, scan.spherical, scan.pose, want);
        if let Some(i) = coords.par_iter().with_min_len(1 << 16).position_first(|x| !x.is_finite()) {
            return Err(GkError::file_format(format!(
                "{what}: scan {}: point {} has a non-finite coordinate (NaN or inf)",
                self.cur,
                self.points + i / 3
            )));
        }
        self.done += want;
        self.points += coords.len() / 3;
        self.invalid += bad;
        Ok(Some(coords))
    }

    /// Read the packet at `self.pos`: a data packet's buffers of the read fields are
    /// appended to their streams; index and empty packets are skipped.
    fn packet(&mut self, what: &str) -> Result<()> {
        let scan = &self.scans[self.cur];
        if self.pos >= self.pages.len {
            return Err(GkError::file_format(format!(
                "{what}: not a readable E57 file (scan {}: the data ends before its {} records)",
                self.cur, scan.records
            )));
        }
        let start = self.pos;
        let mut pos = start;
        let head: [u8; 4] = self.pages.bytes(&mut pos)?;
        let packet_len = u16::from_le_bytes([head[2], head[3]]) as usize + 1;
        if head[0] == 1 {
            let count: [u8; 2] = self.pages.bytes(&mut pos)?;
            let nf = scan.nfields;
            if u16::from_le_bytes(count) as usize != nf {
                return Err(GkError::file_format(format!(
                    "{what}: not a readable E57 file (scan {}: a data packet has {} streams, the prototype {nf} fields)",
                    self.cur,
                    u16::from_le_bytes(count)
                )));
            }
            self.sizes.clear();
            let mut sizes = std::mem::take(&mut self.sizes);
            self.pages.read(&mut pos, 2 * nf, Some(&mut sizes))?;
            let lens: Vec<usize> = sizes.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]]) as usize).collect();
            self.sizes = sizes;
            if 6 + 2 * nf + lens.iter().sum::<usize>() > packet_len {
                return Err(GkError::file_format(format!(
                    "{what}: not a readable E57 file (scan {}: a data packet's buffers overrun it)",
                    self.cur
                )));
            }
            for (f, &l) in lens.iter().enumerate() {
                match scan.fields.iter().position(|&x| x == f) {
                    Some(k) => self.pages.read(&mut pos, l, Some(&mut self.streams[k]))?,
                    None => self.pages.read(&mut pos, l, None)?,
                }
            }
        } else if head[0] > 2 {
            return Err(GkError::file_format(format!(
                "{what}: not a readable E57 file (scan {}: unknown packet type {})",
                self.cur, head[0]
            )));
        }
        let mut next = start;
        self.pages.read(&mut next, packet_len, None)?;
        self.pos = next;
        Ok(())
    }
}

/// The plan of one scan, from its section header; `None` when the stream does not read it.
fn scan_plan(pages: &mut Pages, pc: &PointCloud, what: &str) -> Result<Option<Scan>> {
    let Some((xyz, state, spherical)) = coordinate_fields(pc) else { return Ok(None) };
    let mut fields = xyz.to_vec();
    fields.extend(state);
    let types: Vec<RecordDataType> = fields.iter().map(|&f| pc.prototype[f].data_type.clone()).collect();
    if types.iter().any(|t| bits(t) > 56 && !matches!(t, RecordDataType::Double { .. } | RecordDataType::Single { .. })) {
        return Ok(None);
    }
    let mut pos = pc.file_offset as usize;
    let h: [u8; 32] = pages.bytes(&mut pos)?;
    if h[0] != 1 {
        return Ok(None);
    }
    let data = u64::from_le_bytes(h[16..24].try_into().unwrap_or([0; 8])) as usize;
    Ok(Some(Scan {
        fields,
        types,
        spherical,
        pose: pose(pc, what)?,
        records: usize::try_from(pc.records).unwrap_or(usize::MAX),
        nfields: pc.prototype.len(),
        data,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every sample file streams, in chunks of any size, to the whole read's points, bit
    /// for bit, with the same count of invalid points.
    #[test]
    fn chunks_equal_the_whole_read() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/e57");
        let mut n = 0;
        for name in ["bunnyDouble", "bunnyInt19", "tiny_spherical", "cartesian_invalid_state_single", "translationWithoutRotation"] {
            let f = dir.join(format!("{name}.e57"));
            if !f.exists() {
                continue;
            }
            let whole = crate::read_e57(&f, name).unwrap();
            for chunk in [1, 7, 1000, 1 << 20] {
                let mut s = E57Stream::open(&f, name).unwrap().expect("streamable");
                let mut got = Vec::new();
                while let Some(c) = s.next_chunk(chunk).unwrap() {
                    got.extend(c);
                }
                assert_eq!(s.scans(), whole.scans, "{name}");
                assert_eq!(s.invalid_dropped(), whole.invalid_dropped, "{name} {chunk}");
                assert_eq!(got.len(), whole.coords.len(), "{name} {chunk}");
                assert!(got.iter().zip(&whole.coords).all(|(a, b)| a.to_bits() == b.to_bits()), "{name} {chunk}");
            }
            n += 1;
        }
        assert!(n == 5 || !dir.exists());
    }

    /// A flipped byte in a data page is a checksum error naming the page, never a
    /// partial read.
    #[test]
    fn a_corrupt_page_is_an_error() {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/e57/bunnyDouble.e57");
        let Ok(mut bytes) = std::fs::read(&src) else { return };
        let dir = std::env::temp_dir().join(format!("gk-e57s-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("bad.e57");
        let k = bytes.len() / 2;
        bytes[k] ^= 0x40;
        std::fs::write(&f, &bytes).unwrap();
        // at the open (the window holding the section header covers the page) or later
        let e = match E57Stream::open(&f, "bad.e57") {
            Err(e) => e,
            Ok(s) => {
                let mut s = s.unwrap();
                loop {
                    match s.next_chunk(5000) {
                        Ok(Some(_)) => {}
                        Ok(None) => panic!("read to the end"),
                        Err(e) => break e,
                    }
                }
            }
        };
        assert!(e.message.contains("checksum mismatch on page"), "{}", e.message);
        std::fs::remove_dir_all(&dir).ok();
    }
}
