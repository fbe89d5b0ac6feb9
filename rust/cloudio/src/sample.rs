//! Seeded keys of point numbers for the bottom-k sample of a streamed region (the region
//! pictures of a streamed check): one key per point number, whatever the order or the
//! chunks the points come in, so the sample is that of the whole set.

/// The key in [0, 1) of point number `id` for `seed`: the SplitMix64 finalizer (Steele,
/// Lea & Flood, OOPSLA 2014) of `id * 0x9E3779B97F4A7C15 + (seed * 0xD1B54A32D192ED03 + 1)`
/// (arithmetic modulo 2^64), its top 53 bits as a fraction (exact in f64).
pub fn sample_key(seed: u64, id: u64) -> f64 {
    let mut z = id.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(seed.wrapping_mul(0xD1B5_4A32_D192_ED03).wrapping_add(1));
    z ^= z >> 30;
    z = z.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z ^= z >> 27;
    z = z.wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// The positions in `ids` whose key ([`sample_key`]) is below `below` (all of them for an
/// infinite `below`), ascending, and their keys: the only points a bottom-k sample whose
/// largest held key is `below` can take (one pass, no temporaries the size of `ids`).
pub fn keys_below(seed: u64, ids: &[i64], below: f64) -> (Vec<usize>, Vec<f64>) {
    let (mut pos, mut keys) = (Vec::new(), Vec::new());
    for (i, &id) in ids.iter().enumerate() {
        let k = sample_key(seed, id as u64);
        if k < below {
            pos.push(i);
            keys.push(k);
        }
    }
    (pos, keys)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `float.hex()` of a number in [2^-8, 1) (Python's form: 13 hex digits of mantissa).
    fn hex(v: f64) -> String {
        let b = v.to_bits();
        format!("0x1.{:013x}p{}", b & ((1 << 52) - 1), ((b >> 52) & 0x7ff) as i64 - 1023)
    }

    /// Pinned against the numpy form the streamed sample used before (uint64 arithmetic
    /// of the same constants, the top 53 bits times 2^-53).
    #[test]
    fn keys_are_the_splitmix_finalizer() {
        for (seed, id, want) in [
            (0u64, 0u64, "0x1.5a485874402c0p-2"),
            (0, 1, "0x1.22145bd91204bp-1"),
            (0, (1 << 40) + 3, "0x1.a11024ac5d3dfp-1"),
            (12345, 0, "0x1.9a7df26d77a28p-4"),
            (12345, (1 << 40) + 3, "0x1.6859409064246p-1"),
        ] {
            assert_eq!(hex(sample_key(seed, id)), want, "seed {seed} id {id}");
        }
        let ks: Vec<f64> = (0..1000).map(|i| sample_key(7, i)).collect();
        assert!(ks.iter().all(|&k| (0.0..1.0).contains(&k)));
        let mean = ks.iter().sum::<f64>() / ks.len() as f64;
        assert!((mean - 0.5).abs() < 0.05, "{mean}");
        assert_ne!(sample_key(1, 5), sample_key(2, 5));
    }

    #[test]
    fn below_keeps_exactly_the_smaller_keys_in_order() {
        let ids: Vec<i64> = (0..5000).map(|i| (i * 7919) % 100_003).collect();
        let (pos, keys) = keys_below(3, &ids, 0.1);
        let want: Vec<usize> = (0..ids.len()).filter(|&i| sample_key(3, ids[i] as u64) < 0.1).collect();
        assert_eq!(pos, want);
        assert_eq!(keys, want.iter().map(|&i| sample_key(3, ids[i] as u64)).collect::<Vec<_>>());
        assert_eq!(keys_below(3, &ids, f64::INFINITY).0.len(), ids.len());
        assert!(keys_below(3, &ids, 0.0).0.is_empty());
    }
}
