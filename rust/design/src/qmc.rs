//! Quasi-random candidate points: the Halton sequence with a random shift
//! (Cranley-Patterson rotation) chosen by the seed.

use gagekit_core::{GkError, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn primes(d: usize) -> Vec<u64> {
    let mut out = Vec::with_capacity(d);
    let mut c = 2u64;
    while out.len() < d {
        if out.iter().take_while(|&&p| p * p <= c).all(|&p| c % p != 0) {
            out.push(c);
        }
        c += 1;
    }
    out
}

fn radical_inverse(mut i: u64, base: u64) -> f64 {
    let inv = 1.0 / base as f64;
    let mut f = inv;
    let mut x = 0.0;
    while i > 0 {
        x += (i % base) as f64 * f;
        i /= base;
        f *= inv;
    }
    x
}

/// `n` points of the shifted Halton sequence in [0, 1)^d, (n, d) row-major.
/// `seed = 0` gives the unshifted sequence (starting at index 1, not the origin).
pub fn halton(n: usize, d: usize, seed: u64) -> Result<Vec<f64>> {
    if d == 0 || d > 64 {
        return Err(GkError::invalid(format!(
            "quasi-random points need 1 to 64 dimensions, got {d}"
        )));
    }
    let bases = primes(d);
    let shift: Vec<f64> = if seed == 0 {
        vec![0.0; d]
    } else {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..d).map(|_| rng.random::<f64>()).collect()
    };
    let mut out = Vec::with_capacity(n * d);
    for i in 0..n {
        for (a, &b) in bases.iter().enumerate() {
            let v = radical_inverse(i as u64 + 1, b) + shift[a];
            out.push(v - v.floor());
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halton_is_uniform_and_seeded() {
        let x = halton(1000, 3, 0).unwrap();
        assert!((x[0] - 0.5).abs() < 1e-15 && (x[1] - 1.0 / 3.0).abs() < 1e-15);
        for a in 0..3 {
            let mean: f64 = (0..1000).map(|i| x[i * 3 + a]).sum::<f64>() / 1000.0;
            assert!((mean - 0.5).abs() < 0.01);
        }
        assert_eq!(halton(10, 2, 7).unwrap(), halton(10, 2, 7).unwrap());
        assert_ne!(halton(10, 2, 7).unwrap(), halton(10, 2, 8).unwrap());
        assert!(halton(10, 0, 0).is_err());
    }
}
