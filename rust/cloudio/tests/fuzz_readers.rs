//! Property-based fuzzing of the readers (issue 12): random and mutated inputs never
//! panic, never hang, and every `Ok` is a correct read.

use gagekit_cloudio::{parse_ascii, read_ply, write_ascii, AsciiOptions};
use proptest::prelude::*;

fn ascii_bytes() -> impl Strategy<Value = Vec<u8>> {
    // bytes biased towards what point files contain
    let alphabet = prop::sample::select(
        b"0123456789.,;-+eE \t\r\n#xyzXYZ\"nanif\x00\xef\xbb\xbf/".to_vec(),
    );
    prop::collection::vec(alphabet, 0..400)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, .. ProptestConfig::default() })]

    /// Arbitrary bytes: an error or points that are finite and complete.
    #[test]
    fn ascii_random_bytes(bytes in ascii_bytes(), dim in 2usize..=3, skip in 0usize..2) {
        let opts = AsciiOptions { dim, skip_lines: skip };
        if let Ok(p) = parse_ascii(&bytes, &opts, "fuzz") {
            prop_assert_eq!(p.coords.len() % dim, 0);
            prop_assert!(!p.coords.is_empty());
            prop_assert!(p.coords.iter().all(|v| v.is_finite()));
        }
    }

    /// Fully random bytes (any value) never panic either.
    #[test]
    fn ascii_any_bytes(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        let _ = parse_ascii(&bytes, &AsciiOptions::default(), "fuzz");
    }

    /// Written points read back exactly, whatever the separator.
    #[test]
    fn ascii_round_trip(pts in prop::collection::vec(-1e12f64..1e12, 3..300), sep in prop::sample::select(vec![b' ', b',', b'\t', b';'])) {
        let n = pts.len() / 3 * 3;
        let text = write_ascii(&pts[..n], 3, sep, None).unwrap();
        let p = parse_ascii(&text, &AsciiOptions::default(), "rt").unwrap();
        prop_assert_eq!(&p.coords[..], &pts[..n]);
    }

    /// Decimal-comma files (`1,5;2,5;3,5`) read as the numbers they mean.
    #[test]
    fn decimal_comma_round_trip(pts in prop::collection::vec((-99999i64..99999, 1u32..999), 3..60)) {
        let n = pts.len() / 3 * 3;
        let mut text = String::new();
        let mut want = Vec::new();
        for row in pts[..n].chunks(3) {
            let cells: Vec<String> = row.iter().map(|(i, f)| format!("{i},{f:03}")).collect();
            want.extend(row.iter().map(|(i, f)| format!("{i}.{f:03}").parse::<f64>().unwrap()));
            text.push_str(&cells.join(";"));
            text.push('\n');
        }
        let p = parse_ascii(text.as_bytes(), &AsciiOptions::default(), "dc").unwrap();
        prop_assert_eq!(p.coords, want);
    }

    /// Random bytes after a plausible PLY header, and random truncations or mutations of
    /// a valid file: an error or exactly the declared vertices.
    #[test]
    fn ply_mutations(n in 0usize..40, cut in any::<prop::sample::Index>(), flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..4), binary in any::<bool>()) {
        let head = format!(
            "ply\nformat {} 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
            if binary { "binary_little_endian" } else { "ascii" }
        );
        let mut b = head.into_bytes();
        let mut want = Vec::new();
        for i in 0..n {
            let v = [i as f32, -(i as f32) * 0.5, 3.25];
            want.extend(v.iter().map(|&x| x as f64));
            if binary {
                for x in v { b.extend_from_slice(&x.to_le_bytes()); }
            } else {
                b.extend_from_slice(format!("{} {} {}\n", v[0], v[1], v[2]).as_bytes());
            }
        }
        if binary {
            b.push(3);
            for i in [0i32, 1, 2] { b.extend_from_slice(&i.to_le_bytes()); }
        } else {
            b.extend_from_slice(b"3 0 1 2\n");
        }
        let whole = read_ply(&b, "ok.ply").unwrap();
        prop_assert_eq!(&whole.coords, &want);
        let mut m = b.clone();
        for (at, val) in &flips {
            let i = at.index(m.len());
            m[i] = *val;
        }
        m.truncate(cut.index(m.len() + 1));
        if let Ok(p) = read_ply(&m, "fuzz.ply") {
            prop_assert_eq!(p.coords.len() % 3, 0);
            prop_assert!(p.coords.iter().all(|v| v.is_finite()));
            if flips.is_empty() { prop_assert_eq!(p.coords, want); }
        }
    }

    #[test]
    fn ply_any_bytes(tail in prop::collection::vec(any::<u8>(), 0..200)) {
        let mut b = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nproperty list uchar uchar l\nend_header\n".to_vec();
        b.extend(tail);
        if let Ok(p) = read_ply(&b, "fuzz.ply") {
            prop_assert_eq!(p.coords.len(), 9);
        }
    }
}
