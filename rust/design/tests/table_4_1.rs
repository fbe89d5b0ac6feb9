//! Table 4.1 (with ERRATA item 7) from a grid of candidates, and the search's contracts.

use gagekit_design::{search, Criterion, Options, Problem};

fn grid(step: f64) -> (Vec<f64>, Vec<f64>) {
    let m = (1.0 / step).round() as usize;
    let xs: Vec<f64> = (0..=m).map(|i| i as f64 * step).collect();
    let blocks = xs.iter().flat_map(|&x| [x, 1.0]).collect();
    (xs, blocks)
}

fn members(xs: &[f64], lo: f64, hi: f64) -> Vec<usize> {
    (0..xs.len())
        .filter(|&i| xs[i] >= lo - 1e-12 && xs[i] <= hi + 1e-12)
        .collect()
}

fn design(c: Criterion, zoned: bool, seed: u64) -> (Vec<f64>, gagekit_design::Outcome) {
    let (xs, blocks) = grid(0.05);
    let (groups, point_group) = if zoned {
        (
            vec![
                members(&xs, 0.0, 0.25),
                members(&xs, 0.25, 0.75),
                members(&xs, 0.75, 1.0),
            ],
            vec![0, 1, 1, 2],
        )
    } else {
        (vec![(0..xs.len()).collect()], vec![0; 4])
    };
    let p = Problem {
        blocks: &blocks,
        n_cand: xs.len(),
        r: 1,
        k: 2,
        groups,
        point_group,
        weights: None,
    };
    let out = search(
        &p,
        &Options {
            criterion: c,
            starts: 6,
            max_sweeps: 50,
            seed,
            initial: None,
        },
    )
    .unwrap();
    let mut x: Vec<f64> = out.design.iter().map(|&j| xs[j]).collect();
    x.sort_by(f64::total_cmp);
    (x, out)
}

#[test]
fn table_4_1_a_and_d() {
    for c in [Criterion::A, Criterion::D] {
        let (x, o) = design(c, false, 1);
        assert_eq!(x, vec![0.0, 0.0, 1.0, 1.0], "{c:?}");
        assert!((o.metrics.trace - 1.5).abs() < 1e-9);
        assert!((o.metrics.log_det.exp() - 0.25).abs() < 1e-9);
        assert!((o.metrics.condition_number - 2.618).abs() < 1e-3);
        let (x, o) = design(c, true, 1);
        assert_eq!(x, vec![0.0, 0.25, 0.75, 1.0], "{c:?}");
        assert!((o.metrics.trace - 2.25).abs() < 1e-9);
        assert!((o.metrics.log_det.exp() - 0.4).abs() < 1e-9);
        assert!((o.metrics.condition_number - 3.25).abs() < 1e-3);
    }
}

#[test]
fn table_4_1_k_as_corrected() {
    let (x, o) = design(Criterion::K, false, 2);
    assert_eq!(x, vec![0.0, 0.0, 0.0, 1.0]);
    assert!((o.metrics.condition_number - 2.484).abs() < 1e-3);
    let (x, o) = design(Criterion::K, true, 2);
    assert_eq!(x, vec![0.0, 0.25, 0.25, 1.0]);
    assert!((o.metrics.condition_number - 3.093).abs() < 1e-3);
}

#[test]
fn same_seed_same_design() {
    for c in [Criterion::A, Criterion::D, Criterion::K, Criterion::E] {
        let (_, a) = design(c, true, 5);
        let (_, b) = design(c, true, 5);
        assert_eq!(a.design, b.design);
        assert_eq!(a.start_objectives, b.start_objectives);
    }
}

#[test]
fn bad_problems_are_errors() {
    let (xs, blocks) = grid(0.5);
    let base = Problem {
        blocks: &blocks,
        n_cand: xs.len(),
        r: 1,
        k: 2,
        groups: vec![vec![0, 1, 2]],
        point_group: vec![0],
        weights: None,
    };
    let e = search(&base, &Options::default()).unwrap_err();
    assert!(e.message.contains("at least 2 points"), "{}", e.message);
    let empty = Problem {
        groups: vec![vec![]],
        point_group: vec![0, 0],
        ..base.clone()
    };
    assert!(search(&empty, &Options::default())
        .unwrap_err()
        .message
        .contains("no candidate"));
    let one = Problem {
        groups: vec![vec![1]],
        point_group: vec![0, 0, 0],
        ..base.clone()
    };
    assert!(search(&one, &Options::default())
        .unwrap_err()
        .message
        .contains("only 1 independent"));
    let mut nan = blocks.clone();
    nan[3] = f64::NAN;
    let bad = Problem {
        blocks: &nan,
        point_group: vec![0, 0],
        ..base.clone()
    };
    assert!(search(&bad, &Options::default())
        .unwrap_err()
        .message
        .contains("candidate 1"));
    let i = Problem {
        point_group: vec![0, 0],
        ..base
    };
    assert!(search(
        &i,
        &Options {
            criterion: Criterion::I,
            ..Options::default()
        }
    )
    .is_err());
}
