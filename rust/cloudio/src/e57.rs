//! E57 (ASTM E2807) point clouds through the pure-Rust `e57` crate: every scan, its pose
//! applied, Cartesian or spherical coordinates (range, azimuth, elevation converted to
//! x = r cos(el) cos(az), y = r cos(el) sin(az), z = r sin(el)), scaled-integer, integer
//! and float fields. Points whose `cartesianInvalidState` / `sphericalInvalidState` is
//! not 0 are dropped and counted. Coordinates stay in the file's unit, metres.
//!
//! Page checksums (CRC-32C) are verified while reading: a corrupt file is an error
//! naming the page, never a partial read. Nothing is printed. The file is memory-mapped;
//! the crate parses the XML (scans, prototypes, poses), and each scan's binary section is
//! decoded by the fast path of `e57_fast` (whole byte streams at once, in parallel), or by
//! the crate's point-by-point reader where that path does not apply.

use gagekit_core::{GkError, Result};
use rayon::prelude::*;
use std::path::Path;

/// The points of every scan of an E57 file, in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct E57Points {
    /// x, y, z per valid point (pose applied), row-major, metres.
    pub coords: Vec<f64>,
    /// Number of scans (`data3D` entries).
    pub scans: usize,
    /// Points dropped because their invalid state was not 0.
    pub invalid_dropped: usize,
}

pub(crate) fn unreadable(what: &str, e: impl std::fmt::Display) -> GkError {
    let msg = e.to_string();
    // "... Detected invalid checksum (expected: [..], actual: [..]) for page N" -> short form
    let msg = match (msg.contains("invalid checksum"), msg.rsplit_once("for page ")) {
        (true, Some((_, page))) => format!("checksum mismatch on page {}", page.trim()),
        _ => msg,
    };
    GkError::file_format(format!("{what}: not a readable E57 file ({msg})"))
}

/// Read every scan of the E57 file at `path`; `what` names it in messages.
pub fn read_e57(path: &Path, what: &str) -> Result<E57Points> {
    use e57::{CartesianCoordinate, E57Reader, RecordName};

    let file = std::fs::File::open(path).map_err(|e| crate::read_error(what, e))?;
    // SAFETY: read-only map, alive only during this call. Reading pages from memory
    // instead of a BufReader avoids two system calls per 1 KiB page (seek + read).
    let map = unsafe { memmap2::MmapOptions::new().populate().map(&file) }
        .map_err(|e| crate::read_error(what, e))?;
    let mut reader = E57Reader::new(std::io::Cursor::new(&map[..])).map_err(|e| unreadable(what, e))?;
    let clouds = reader.pointclouds();
    let page = reader.header().page_size as usize;
    let mut coords = Vec::with_capacity(3 * clouds.iter().map(|c| c.records as usize).sum::<usize>().min(1 << 28));
    let mut invalid = 0usize;
    for (k, pc) in clouds.iter().enumerate() {
        let has = |n: RecordName| pc.prototype.iter().any(|r| r.name == n);
        let cart = has(RecordName::CartesianX) && has(RecordName::CartesianY) && has(RecordName::CartesianZ);
        let sph_dir = has(RecordName::SphericalAzimuth) && has(RecordName::SphericalElevation);
        if !cart && sph_dir && !has(RecordName::SphericalRange) {
            return Err(GkError::file_format(format!(
                "{what}: scan {k} has spherical coordinates without sphericalRange: directions only, no points"
            )));
        }
        if !cart && !sph_dir {
            return Err(GkError::file_format(format!("{what}: scan {k} has neither Cartesian nor spherical coordinates")));
        }
        // fast path: whole byte streams decoded at once (e57_fast), else the crate's reader
        if let Some((c, bad)) = crate::e57_fast::decode(&map, page, pc, what)? {
            if let Some(i) = c.par_iter().with_min_len(1 << 16).position_first(|v| !v.is_finite()) {
                return Err(GkError::file_format(format!(
                    "{what}: scan {k}: point {} has a non-finite coordinate (NaN or inf)",
                    coords.len() / 3 + i / 3
                )));
            }
            if coords.is_empty() {
                coords = c; // the first scan: its buffer is the result (no copy)
            } else {
                coords.extend_from_slice(&c);
            }
            invalid += bad;
            continue;
        }
        let mut it = reader.pointcloud_simple(pc).map_err(|e| unreadable(what, e))?;
        it.spherical_to_cartesian(true);
        it.apply_pose(true);
        it.normalize_color(false);
        it.normalize_intensity(false);
        for p in it {
            let p = p.map_err(|e| unreadable(what, e))?;
            match p.cartesian {
                CartesianCoordinate::Valid { x, y, z } => {
                    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                        return Err(GkError::file_format(format!(
                            "{what}: scan {k}: point {} has a non-finite coordinate (NaN or inf)",
                            coords.len() / 3 + invalid
                        )));
                    }
                    coords.extend_from_slice(&[x, y, z]);
                }
                _ => invalid += 1,
            }
        }
    }
    Ok(E57Points { coords, scans: clouds.len(), invalid_dropped: invalid })
}

/// The crate's own point-by-point reader, for comparing the fast path with it.
#[cfg(test)]
fn read_e57_simple(path: &Path) -> (Vec<f64>, usize) {
    use e57::{CartesianCoordinate, E57Reader};
    let mut reader = E57Reader::from_file(path).unwrap();
    let (mut coords, mut invalid) = (Vec::new(), 0);
    for pc in reader.pointclouds() {
        let mut it = reader.pointcloud_simple(&pc).unwrap();
        it.spherical_to_cartesian(true);
        it.apply_pose(true);
        for p in it {
            match p.unwrap().cartesian {
                CartesianCoordinate::Valid { x, y, z } => coords.extend_from_slice(&[x, y, z]),
                _ => invalid += 1,
            }
        }
    }
    (coords, invalid)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast path agrees with the e57 crate's reader on the real sample files
    /// (tests/data/e57: Cartesian double, 19-bit scaled integers, spherical floats with
    /// invalid states, integer invalid states, a pose).
    #[test]
    fn fast_path_matches_the_crate_reader() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/e57");
        let mut n = 0;
        for name in ["bunnyDouble", "bunnyInt19", "tiny_spherical", "cartesian_invalid_state_single", "translationWithoutRotation"] {
            let f = dir.join(format!("{name}.e57"));
            if !f.exists() {
                continue;
            }
            // the fast path serves every scan of these files (no silent fallback)
            let map = std::fs::read(&f).unwrap();
            let r = e57::E57Reader::from_file(&f).unwrap();
            for pc in r.pointclouds() {
                let fast = crate::e57_fast::decode(&map, r.header().page_size as usize, &pc, name).unwrap();
                assert!(fast.is_some(), "{name}: fast path not taken");
            }
            let got = read_e57(&f, name).unwrap();
            let (want, bad) = read_e57_simple(&f);
            assert_eq!(got.invalid_dropped, bad, "{name}");
            assert_eq!(got.coords.len(), want.len(), "{name}");
            for (a, b) in got.coords.iter().zip(&want) {
                assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{name}: {a} vs {b}");
            }
            n += 1;
        }
        assert!(n == 5 || !dir.exists());
    }

    #[test]
    fn missing_and_garbage_files_are_errors() {
        let dir = std::env::temp_dir().join(format!("gk-e57-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("junk.e57");
        std::fs::write(&f, b"ASTM-E57 but nothing else").unwrap();
        let e = read_e57(&f, "junk.e57").unwrap_err();
        assert!(e.message.starts_with("junk.e57: not a readable E57 file ("), "{}", e.message);
        assert!(read_e57(&dir.join("none.e57"), "none").is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
