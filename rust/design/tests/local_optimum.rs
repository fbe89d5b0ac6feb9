//! The low-rank updates agree with brute force: after the search no single
//! exchange improves A, D or I (checked by recomputing every swapped design).

use gagekit_design::{information, metrics, search, Criterion, Options, Problem};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn no_single_exchange_improves() {
    let (n_cand, r, k, n) = (150, 3, 7, 6);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let blocks: Vec<f64> = (0..n_cand * r * k)
        .map(|_| rng.random::<f64>() * 2.0 - 1.0)
        .collect();
    let mut w = vec![0.0; k * k];
    for a in 0..k {
        w[a * k + a] = 1.0 + a as f64;
    }
    for c in [Criterion::A, Criterion::D, Criterion::I] {
        let p = Problem {
            blocks: &blocks,
            n_cand,
            r,
            k,
            groups: vec![(0..n_cand).collect()],
            point_group: vec![0; n],
            weights: Some(&w),
        };
        let out = search(
            &p,
            &Options {
                criterion: c,
                starts: 2,
                max_sweeps: 100,
                seed: 9,
                initial: None,
            },
        )
        .unwrap();
        let best = out.objective;
        for i in 0..n {
            for j in 0..n_cand {
                let mut d = out.design.clone();
                d[i] = j;
                let v = metrics(&information(&blocks, &d, r, k), k, Some(&w)).objective(c);
                assert!(
                    v >= best - 1e-7 * best.abs().max(1.0),
                    "{c:?}: swap ({i},{j}) gives {v} < {best}"
                );
            }
        }
    }
}
