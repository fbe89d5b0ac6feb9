//! The few smallest and largest of many values in one pass.
//!
//! The order is total: values by `f64::total_cmp`, ties by index. So the sets are unique
//! and the same as the ends of a full sort (or of two partial selections), whatever the
//! method; this one reads every value once and keeps two bounded heaps, instead of two
//! `select_nth_unstable` partitions of an index array (several indirect passes).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// `f64::total_cmp`'s order as an integer key (the same transform it uses).
#[inline]
fn key(x: f64) -> i64 {
    let b = x.to_bits() as i64;
    b ^ ((((b >> 63) as u64) >> 1) as i64)
}

/// The indices of the `low` smallest and the `high` largest of `v` (values by
/// `total_cmp`, ties by index), each set in no particular order. Needs `low + high <=
/// v.len()`; then the two sets are disjoint.
pub fn extremes(v: &[f64], low: usize, high: usize) -> (Vec<usize>, Vec<usize>) {
    assert!(low + high <= v.len(), "extremes: {low} + {high} of {} values", v.len());
    // `small`: a max-heap of the `low` least seen so far; `large`: a min-heap of the `high`
    // greatest. Index `i` exceeds every index in either heap, so against a heap's bound a
    // tie in value ranks `i` after it: it enters `small` only below the bound, `large` at
    // or above it.
    let mut small: BinaryHeap<(i64, usize)> = BinaryHeap::with_capacity(low + 1);
    let mut large: BinaryHeap<Reverse<(i64, usize)>> = BinaryHeap::with_capacity(high + 1);
    let (mut s_bound, mut l_bound) = (i64::MAX, i64::MIN);
    for (i, &x) in v.iter().enumerate() {
        let k = key(x);
        if low > 0 && (small.len() < low || k < s_bound) {
            if small.len() == low {
                small.pop();
            }
            small.push((k, i));
            if small.len() == low {
                s_bound = small.peek().map_or(i64::MAX, |t| t.0);
            }
        }
        if high > 0 && (large.len() < high || k >= l_bound) {
            if large.len() == high {
                large.pop();
            }
            large.push(Reverse((k, i)));
            if large.len() == high {
                l_bound = large.peek().map_or(i64::MIN, |t| (t.0).0);
            }
        }
    }
    (small.into_iter().map(|t| t.1).collect(), large.into_iter().map(|t| (t.0).1).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference(v: &[f64], low: usize, high: usize) -> (Vec<usize>, Vec<usize>) {
        let mut order: Vec<usize> = (0..v.len()).collect();
        order.sort_by(|&i, &j| v[i].total_cmp(&v[j]).then(i.cmp(&j)));
        let n = v.len();
        (order[..low].to_vec(), order[n - high..].to_vec())
    }

    fn sorted(mut a: Vec<usize>) -> Vec<usize> {
        a.sort_unstable();
        a
    }

    #[test]
    fn the_extremes_are_the_ends_of_a_full_sort() {
        // ties (a few distinct values), signed zeros, infinities, NaN of both signs, and a
        // pseudo-random spread; every (low, high) split including empty ones
        let mut s = 0x9e3779b97f4a7c15u64;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for n in [0usize, 1, 5, 40, 300, 2049] {
            for kind in 0..4 {
                let v: Vec<f64> = (0..n)
                    .map(|i| {
                        let r = rnd();
                        match kind {
                            0 => (r % 7) as f64 * 0.5 - 1.0,
                            1 => (r >> 11) as f64 / (1u64 << 53) as f64 - 0.5,
                            2 => [0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -f64::NAN, 1e-300, -1e-300][i % 8],
                            _ => -(i as f64),
                        }
                    })
                    .collect();
                for (low, high) in [(0, 0), (0, 3), (3, 0), (1, 1), (16, 16), (128, 128), (256, 0), (0, 256), (n / 2, n - n / 2)] {
                    if low + high > n {
                        continue;
                    }
                    let (a, b) = extremes(&v, low, high);
                    let (ra, rb) = reference(&v, low, high);
                    assert_eq!(sorted(a), sorted(ra), "n {n} kind {kind} low {low}");
                    assert_eq!(sorted(b), sorted(rb), "n {n} kind {kind} high {high}");
                }
            }
        }
    }
}
