//! Fast path for the points of one E57 scan (ASTM E2807 compressed vectors), decoding
//! each field's byte stream as a whole instead of value by value.
//!
//! The file is in pages (1024 bytes: 1020 of data, then a big-endian CRC-32C); a
//! `CompressedVector` binary section starts with a 32-byte header (section id 1, length,
//! data offset, index offset) and holds data packets: id 1, flags, length - 1 (u16),
//! stream count (u16), one u16 buffer length per prototype field, then the buffers. Each
//! field's buffers, concatenated over the packets, form one little-endian, LSB-first bit
//! stream: IEEE floats (32 or 64 bits), or integers in ceil(log2(max - min + 1)) bits
//! holding `value - min` (scaled integers: `value * scale + offset`).
//!
//! Anything this path does not handle (other packet types before the last point,
//! inconsistent sizes) returns `Ok(None)`, and the caller uses the `e57` crate's reader.
//! Every page read is checked against its CRC.

use e57::{PointCloud, RecordDataType, RecordName};
use gagekit_core::{GkError, Result};
use rayon::prelude::*;

pub(crate) const CRC: usize = 4;

/// Reads the logical byte stream of an E57 file (page payloads, CRCs checked).
struct Logical<'a> {
    map: &'a [u8],
    page: usize,
    /// physical position
    pos: usize,
    checked: usize,
    what: &'a str,
}

impl<'a> Logical<'a> {
    fn new(map: &'a [u8], page: usize, physical: usize, what: &'a str) -> Self {
        Logical { map, page, pos: physical, checked: usize::MAX, what }
    }

    fn check_page(&mut self, p: usize) -> Result<()> {
        if self.checked == p {
            return Ok(());
        }
        let start = p * self.page;
        let Some(bytes) = self.map.get(start..start + self.page) else {
            return Err(GkError::file_format(format!("{}: not a readable E57 file (truncated: page {p} is missing)", self.what)));
        };
        let want = &bytes[self.page - CRC..];
        if crc32c::crc32c(&bytes[..self.page - CRC]).to_be_bytes() != want {
            return Err(GkError::file_format(format!("{}: not a readable E57 file (checksum mismatch on page {p})", self.what)));
        }
        self.checked = p;
        Ok(())
    }

    /// Append `n` logical bytes to `out`.
    fn read_into(&mut self, mut n: usize, out: &mut Vec<u8>) -> Result<()> {
        while n > 0 {
            let p = self.pos / self.page;
            self.check_page(p)?;
            let in_page = self.pos % self.page;
            if in_page >= self.page - CRC {
                self.pos = (p + 1) * self.page;
                continue;
            }
            let take = n.min(self.page - CRC - in_page);
            out.extend_from_slice(&self.map[self.pos..self.pos + take]);
            self.pos += take;
            n -= take;
        }
        Ok(())
    }

    fn bytes<const N: usize>(&mut self) -> Result<[u8; N]> {
        let mut v = Vec::with_capacity(N);
        self.read_into(N, &mut v)?;
        let mut a = [0u8; N];
        a.copy_from_slice(&v);
        Ok(a)
    }

    /// Skip `n` logical bytes.
    fn skip(&mut self, mut n: usize) {
        while n > 0 {
            let in_page = self.pos % self.page;
            if in_page >= self.page - CRC {
                self.pos = (self.pos / self.page + 1) * self.page;
                continue;
            }
            let take = n.min(self.page - CRC - in_page);
            self.pos += take;
            n -= take;
        }
    }
}

/// Bits per value of a field (0: every value is `min`).
pub(crate) fn bits(t: &RecordDataType) -> usize {
    match t {
        RecordDataType::Single { .. } => 32,
        RecordDataType::Double { .. } => 64,
        RecordDataType::ScaledInteger { min, max, .. } | RecordDataType::Integer { min, max } => {
            let range = (*max as i128 - *min as i128).max(0) as u128;
            if range == 0 {
                0
            } else {
                (128 - range.leading_zeros()) as usize
            }
        }
    }
}

/// Decode the first `n` values of a field's bit stream as f64.
fn decode_field(stream: &[u8], t: &RecordDataType, n: usize) -> Option<Vec<f64>> {
    decode_field_at(stream, 0, t, n)
}

/// Decode `n` values of a field's bit stream from bit `bit0` of `stream` (below 8: the
/// streamed reader drops the bytes it has decoded) as f64: value i from bit
/// `bit0 + i * bits`, so a value reads the same bits, hence the same number, as
/// [`decode_field`] of the whole stream reads for it. Floats need `bit0 == 0`.
pub(crate) fn decode_field_at(stream: &[u8], bit0: usize, t: &RecordDataType, n: usize) -> Option<Vec<f64>> {
    let b = bits(t);
    if stream.len() * 8 < bit0 + b * n || (bit0 != 0 && b % 8 == 0) {
        return None;
    }
    let mut out = vec![0.0; n];
    let chunk = 1 << 16;
    match *t {
        RecordDataType::Double { .. } => out.par_chunks_mut(chunk).enumerate().for_each(|(c, o)| {
            for (j, v) in o.iter_mut().enumerate() {
                let i = (c * chunk + j) * 8;
                *v = f64::from_le_bytes(stream[i..i + 8].try_into().unwrap_or([0; 8]));
            }
        }),
        RecordDataType::Single { .. } => out.par_chunks_mut(chunk).enumerate().for_each(|(c, o)| {
            for (j, v) in o.iter_mut().enumerate() {
                let i = (c * chunk + j) * 4;
                *v = f32::from_le_bytes(stream[i..i + 4].try_into().unwrap_or([0; 4])) as f64;
            }
        }),
        RecordDataType::ScaledInteger { min, .. } | RecordDataType::Integer { min, .. } => {
            let (scale, offset) = match *t {
                RecordDataType::ScaledInteger { scale, offset, .. } => (scale, offset),
                _ => (1.0, 0.0),
            };
            if b > 56 {
                return None; // wider than one unaligned 64-bit load can serve; the crate reads it
            }
            let mask = (1u64 << b) - 1;
            out.par_chunks_mut(chunk).enumerate().for_each(|(c, o)| {
                for (j, v) in o.iter_mut().enumerate() {
                    let bit = bit0 + (c * chunk + j) * b;
                    let byte = bit / 8;
                    let mut w = [0u8; 8];
                    let end = (byte + 8).min(stream.len());
                    w[..end - byte].copy_from_slice(&stream[byte..end]);
                    let raw = (u64::from_le_bytes(w) >> (bit % 8)) & mask;
                    let int = raw as i128 + min as i128;
                    *v = int as f64 * scale + offset;
                }
            });
        }
    }
    Some(out)
}

/// The prototype fields of a scan's coordinates: the x, y, z fields (or range,
/// azimuth, elevation), the invalid-state field if any, and whether they are spherical;
/// `None` when the scan has neither a Cartesian nor a spherical triple.
pub(crate) fn coordinate_fields(pc: &PointCloud) -> Option<([usize; 3], Option<usize>, bool)> {
    let find = |name: RecordName| pc.prototype.iter().position(|r| r.name == name);
    match (
        find(RecordName::CartesianX),
        find(RecordName::CartesianY),
        find(RecordName::CartesianZ),
        find(RecordName::SphericalRange),
        find(RecordName::SphericalAzimuth),
        find(RecordName::SphericalElevation),
    ) {
        (Some(x), Some(y), Some(z), ..) => Some(([x, y, z], find(RecordName::CartesianInvalidState), false)),
        (_, _, _, Some(r), Some(a), Some(e)) => Some(([r, a, e], find(RecordName::SphericalInvalidState), true)),
        _ => None,
    }
}

/// The bit streams of every prototype field of a `CompressedVector` section (each at
/// least as long as `n` values need), concatenated over its data packets; `None` on a
/// section or packet this fast path does not handle.
fn read_streams(map: &[u8], page: usize, pc: &PointCloud, n: usize, what: &str) -> Result<Option<Vec<Vec<u8>>>> {
    let nf = pc.prototype.len();
    // section header
    let mut rd = Logical::new(map, page, pc.file_offset as usize, what);
    let h: [u8; 32] = rd.bytes()?;
    if h[0] != 1 {
        return Ok(None);
    }
    let data_offset = u64::from_le_bytes(h[16..24].try_into().unwrap_or([0; 8])) as usize;
    let mut rd = Logical::new(map, page, data_offset, what);
    let mut streams: Vec<Vec<u8>> = vec![Vec::new(); nf];
    let need: Vec<usize> = pc.prototype.iter().map(|r| (bits(&r.data_type) * n).div_ceil(8)).collect();
    let mut lens = vec![0usize; nf];
    while streams.iter().zip(&need).any(|(s, &k)| s.len() < k) {
        if read_packet(&mut rd, &mut lens, &mut streams)?.is_none() {
            return Ok(None);
        }
    }
    Ok(Some(streams))
}

/// Append the buffers of the data packet at `rd` to `streams` (one per prototype field;
/// `lens` is scratch for their lengths) and move `rd` to the next packet; `None` when the
/// packet is not a data packet of this prototype or its sizes are inconsistent.
fn read_packet(rd: &mut Logical, lens: &mut [usize], streams: &mut [Vec<u8>]) -> Result<Option<()>> {
    let nf = streams.len();
    let start = rd.pos;
    let head: [u8; 6] = rd.bytes()?;
    if head[0] != 1 {
        return Ok(None); // an index or ignored packet before the data ends
    }
    let packet_len = u16::from_le_bytes([head[2], head[3]]) as usize + 1;
    let count = u16::from_le_bytes([head[4], head[5]]) as usize;
    if count != nf {
        return Ok(None);
    }
    let mut sizes = Vec::with_capacity(2 * nf);
    rd.read_into(2 * nf, &mut sizes)?;
    for (i, l) in lens.iter_mut().enumerate() {
        *l = u16::from_le_bytes([sizes[2 * i], sizes[2 * i + 1]]) as usize;
    }
    if 6 + 2 * nf + lens.iter().sum::<usize>() > packet_len {
        return Ok(None);
    }
    for (s, &l) in streams.iter_mut().zip(lens.iter()) {
        rd.read_into(l, s)?;
    }
    // next packet: packet_len logical bytes after this one's start
    let mut probe = Logical::new(rd.map, rd.page, start, rd.what);
    probe.skip(packet_len);
    rd.pos = probe.pos;
    Ok(Some(()))
}

/// The scan pose as a rotation matrix (from its unit quaternion (w, x, y, z), normalised
/// here) and a translation; the identity without a pose.
pub(crate) fn pose(pc: &PointCloud, what: &str) -> Result<([[f64; 3]; 3], [f64; 3])> {
    let Some(tr) = &pc.transform else {
        return Ok(([[1., 0., 0.], [0., 1., 0.], [0., 0., 1.]], [0.; 3]));
    };
    let q = &tr.rotation;
    let norm = (q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z).sqrt();
    if !(norm > 0.0) {
        return Err(GkError::file_format(format!("{what}: a scan pose has a zero rotation quaternion")));
    }
    let (w, x, y, z) = (q.w / norm, q.x / norm, q.y / norm, q.z / norm);
    Ok((
        [
            [1. - 2. * (y * y + z * z), 2. * (x * y - w * z), 2. * (x * z + w * y)],
            [2. * (x * y + w * z), 1. - 2. * (x * x + z * z), 2. * (y * z - w * x)],
            [2. * (x * z - w * y), 2. * (y * z + w * x), 1. - 2. * (x * x + y * y)],
        ],
        [tr.translation.x, tr.translation.y, tr.translation.z],
    ))
}

/// The valid points (state 0, or every point without a state field) of the decoded
/// fields `v` (x, y, z or range, azimuth, elevation when `spherical`), posed by `r` and
/// `t`, flat: (coordinates, invalid count). Valid points are counted per block, then
/// every block is written into its place in parallel.
pub(crate) fn place_points(
    v: &[Vec<f64>],
    st: Option<&[f64]>,
    spherical: bool,
    (r, t): ([[f64; 3]; 3], [f64; 3]),
    n: usize,
) -> (Vec<f64>, usize) {
    const BLOCK: usize = 1 << 16;
    let valid = |i: usize| st.is_none_or(|s| s[i] == 0.0);
    let counts: Vec<usize> = (0..n.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| (b * BLOCK..((b + 1) * BLOCK).min(n)).filter(|&i| valid(i)).count())
        .collect();
    let kept: usize = counts.iter().sum();
    let invalid = n - kept;
    let mut coords = vec![0.0; 3 * kept];
    let mut parts: Vec<(usize, &mut [f64])> = Vec::with_capacity(counts.len());
    let mut rest = &mut coords[..];
    for (b, &c) in counts.iter().enumerate() {
        let (head, tail) = rest.split_at_mut(3 * c);
        parts.push((b, head));
        rest = tail;
    }
    parts.into_par_iter().for_each(|(b, out)| {
        let mut o = out.chunks_exact_mut(3);
        for i in (b * BLOCK..((b + 1) * BLOCK).min(n)).filter(|&i| valid(i)) {
            let p = if spherical {
                let (rg, az, el) = (v[0][i], v[1][i], v[2][i]);
                [rg * el.cos() * az.cos(), rg * el.cos() * az.sin(), rg * el.sin()]
            } else {
                [v[0][i], v[1][i], v[2][i]]
            };
            if let Some(q) = o.next() {
                for k in 0..3 {
                    q[k] = r[k][0] * p[0] + r[k][1] * p[1] + r[k][2] * p[2] + t[k];
                }
            }
        }
    });
    (coords, invalid)
}

/// Decode one scan: (x, y, z per valid point with the pose applied, invalid count), or
/// `None` when this fast path does not apply.
pub(crate) fn decode(map: &[u8], page: usize, pc: &PointCloud, what: &str) -> Result<Option<(Vec<f64>, usize)>> {
    let n = usize::try_from(pc.records).unwrap_or(usize::MAX);
    if page <= CRC || n > map.len() {
        return Ok(None);
    }
    let Some((fields, state, spherical)) = coordinate_fields(pc) else { return Ok(None) };
    let Some(streams) = read_streams(map, page, pc, n, what)? else { return Ok(None) };
    let decoded: Option<Vec<Vec<f64>>> = fields
        .par_iter()
        .map(|&f| decode_field(&streams[f], &pc.prototype[f].data_type, n))
        .collect();
    let Some(v) = decoded else { return Ok(None) };
    let st = match state {
        Some(s) => match decode_field(&streams[s], &pc.prototype[s].data_type, n) {
            Some(x) => Some(x),
            None => return Ok(None),
        },
        None => None,
    };
    let rt = pose(pc, what)?;
    Ok(Some(place_points(&v, st.as_deref(), spherical, rt, n)))
}
