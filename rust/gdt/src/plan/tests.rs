//! The compiled inspection on a synthetic part: a datum plane A, a plane B perpendicular to
//! it and a bore; trials are the same on any thread count and in any split, the perturbation
//! depends on (seed, trial) alone, and a bad plan is refused.

use super::perturb::{perturb, Model};
use super::*;
use gagekit_form::criterion::FitCriterion;
use gagekit_core::ErrorKind;

fn part() -> (Vec<f64>, Plan) {
    let mut pts = Vec::new();
    let mut rows = [Vec::new(), Vec::new(), Vec::new()];
    for i in 0..20 {
        for j in 0..20 {
            rows[0].push(pts.len() / 3);
            pts.extend([i as f64 * 3.0, j as f64 * 2.0, 1e-4 * ((i * 7 + j * 3) % 5) as f64]);
        }
    }
    for i in 0..20 {
        for j in 0..10 {
            rows[1].push(pts.len() / 3);
            pts.extend([i as f64 * 3.0, 1e-4 * ((i + j) % 3) as f64, 1.0 + j as f64 * 2.0]);
        }
    }
    for i in 0..72 {
        for j in 0..8 {
            let a = i as f64 * 5f64.to_radians();
            let r = 5.0 + 2e-4 * ((i * 5 + j) % 4) as f64;
            rows[2].push(pts.len() / 3);
            pts.extend([30.0 + r * a.cos(), 20.0 + r * a.sin(), 2.0 + j as f64 * 2.0]);
        }
    }
    let eye = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let feature = |shape, rows: Vec<usize>, outward: Option<V3>| Feature {
        shape,
        rows,
        outward,
        sign_hint: [0.0, 0.0, 1.0],
        box_axes: eye,
        hole: true,
        warm_lsq: None,
        warm_cylinder: [None, None, None],
        warm_slab: None,
        warm_sphere: None,
    };
    let features = vec![
        feature(Shape::Plane, rows[0].clone(), Some([0.0, 0.0, -1.0])),
        feature(Shape::Plane, rows[1].clone(), Some([0.0, -1.0, 0.0])),
        feature(Shape::Cylinder, rows[2].clone(), None),
    ];
    let datums = vec![Datum { feature: 0, prior: vec![], angle: 90.0 }, Datum { feature: 1, prior: vec![0], angle: 90.0 }];
    let callout = |characteristic, feature, datums: Vec<usize>, frame, p: Option<V3>, d: Option<V3>| Callout {
        characteristic,
        feature,
        tolerance: 0.05,
        datums,
        frame,
        angle: 0.0,
        sections: 4,
        nominal_point: p,
        nominal_direction: d,
    };
    let callouts = vec![
        callout(Characteristic::Flatness, 0, vec![], None, None, None),
        callout(Characteristic::Perpendicularity, 1, vec![0], None, None, None),
        callout(Characteristic::Perpendicularity, 2, vec![0], None, None, None),
        callout(Characteristic::Roundness, 2, vec![], None, None, None),
        callout(Characteristic::Position, 2, vec![0, 1], Some(0), Some([30.0, 20.0, 0.0]), Some([0.0, 0.0, 1.0])),
    ];
    (pts, Plan { features, datums, frames: vec![vec![0, 1]], callouts })
}

fn noise(sigma: f64) -> Model {
    Model { sigma, origin: None, sigma_per_m: 0.0, probing: 0.0, relative_scale: 0.0, offset: 0.0 }
}

#[test]
fn the_measured_part_gives_its_zones() {
    let (pts, plan) = part();
    let v = evaluate(&plan, &pts).unwrap();
    assert_eq!(v.values.len(), 10);
    for pair in v.values.chunks_exact(2) {
        assert!(pair[0] >= 0.0 && (pair[0] + pair[1] - 0.05).abs() < 1e-15);
    }
    assert!((v.values[0] - 4e-4).abs() < 1e-9, "flatness {}", v.values[0]);
    assert!(v.values[6] <= 6e-4 + 1e-9, "roundness {}", v.values[6]);
    assert!(v.values[8] < 1e-3, "position {}", v.values[8]); // the bore sits at its nominal (30, 20)
}

#[test]
fn trials_are_the_same_on_any_thread_count_and_split() {
    let (pts, plan) = part();
    let m = noise(0.001);
    let one = run(&plan, &pts, &m, 5, 0, 6, 1).unwrap();
    let two = run(&plan, &pts, &m, 5, 0, 6, 2).unwrap();
    let mut split = run(&plan, &pts, &m, 5, 0, 2, 2).unwrap().values;
    split.extend(run(&plan, &pts, &m, 5, 2, 4, 2).unwrap().values);
    assert_eq!(one, two);
    assert_eq!(one.values, split);
    // trial 3 is the plan's evaluation of its simulated measurement 3 (its planes on their
    // certified extreme blocks: the same zones to the active sets' containment tolerance,
    // 1e-9 mm), and the same as the trials evaluated on every point
    let p = simulate(&plan, &pts, &m, 5, 3).unwrap();
    let full = evaluate(&plan, &p).unwrap().values;
    assert!(full.iter().zip(&one.values[30..40]).all(|(a, b)| (a - b).abs() <= 1e-9), "{full:?} {:?}", &one.values[30..40]);
    let every = run_with(&plan, &pts, &m, 5, 0, 6, 2, true, &sparse::Cache::default()).unwrap();
    assert!(every.values.iter().zip(&one.values).all(|(a, b)| (a - b).abs() <= 1e-9));
    // a model with more than isotropic noise draws as perturb does
    let m2 = Model { probing: 0.002, ..noise(0.001) };
    let p = perturb(&pts, 3, &m2, 5, 3).unwrap();
    assert_eq!(simulate(&plan, &pts, &m2, 5, 3).unwrap(), p);
    assert_eq!(evaluate(&plan, &p).unwrap().values, run(&plan, &pts, &m2, 5, 0, 4, 2).unwrap().values[30..40].to_vec());
}

#[test]
fn the_perturbation_depends_on_seed_and_trial_only() {
    let (pts, _) = part();
    let m = Model { probing: 0.002, relative_scale: 1e-5, offset: 0.001, ..noise(0.01) };
    let a = perturb(&pts, 3, &m, 1, 2).unwrap();
    assert_eq!(a, perturb(&pts, 3, &m, 1, 2).unwrap());
    assert_ne!(a, perturb(&pts, 3, &m, 1, 3).unwrap());
    assert_ne!(a, perturb(&pts, 3, &m, 2, 2).unwrap());
    let d: Vec<f64> = perturb(&pts, 3, &noise(0.01), 0, 0).unwrap().iter().zip(&pts).map(|(a, b)| a - b).collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let sd = (d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n).sqrt();
    assert!(mean.abs() < 5e-4 && (sd - 0.01).abs() < 5e-4, "mean {mean} sd {sd}");
    assert_eq!(perturb(&pts[..6], 2, &noise(0.01), 0, 0).unwrap().len(), 6);
    assert_eq!(perturb(&pts, 2, &Model { origin: Some([0.0; 3]), ..noise(0.01) }, 0, 0).unwrap_err().kind, ErrorKind::InvalidInput);
}

#[test]
fn a_bad_plan_is_refused() {
    let (pts, mut plan) = part();
    assert_eq!(evaluate(&plan, &pts[..30]).unwrap_err().kind, ErrorKind::InvalidInput);
    let mut nan = pts.clone();
    nan[4] = f64::NAN;
    assert_eq!(evaluate(&plan, &nan).unwrap_err().kind, ErrorKind::InvalidInput);
    plan.callouts[1].datums.clear();
    assert_eq!(evaluate(&plan, &pts).unwrap_err().kind, ErrorKind::Config);
    let bad = Model { sigma: -1.0, ..noise(0.0) };
    assert!(bad.checked().is_err());
}

/// The active-set zones (a roundness section's circle, a sphere) equal the exact kernel's
/// zone of every point, whatever nearby start they are given.
#[test]
fn active_zones_equal_the_zones_of_all_points() {
    let model = Model { sigma: 1e-3, origin: None, sigma_per_m: 0.0, probing: 0.0, relative_scale: 0.0, offset: 0.0 };
    let circle: Vec<f64> = (0..600)
        .flat_map(|i| {
            let a = i as f64 * 0.6f64.to_radians();
            [4.0 + 7.0 * a.cos(), -1.0 + 7.0 * a.sin()]
        })
        .collect();
    let sphere: Vec<f64> = (0..900)
        .flat_map(|i| {
            let (t, p) = (0.2 + 1.2 * (i / 30) as f64 / 30.0, (i % 30) as f64 * 12f64.to_radians());
            [1.0 + 8.0 * t.sin() * p.cos(), 2.0 + 8.0 * t.sin() * p.sin(), 3.0 + 8.0 * t.cos()]
        })
        .collect();
    for trial in 0..5 {
        let xy = perturb(&circle, 2, &model, 7, trial).unwrap();
        let all = gagekit_form::circle::min_zone(&xy).unwrap();
        // from starts near and far (a trial's roundness sections start from its axis)
        for start in [[4.05, -1.02], [3.9, -0.9], [4.0, -1.0]] {
            let z = active::circle_zone_near(&xy, start).unwrap();
            assert!((z.form_error() - all.form_error()).abs() < 1e-12, "circle trial {trial} from {start:?}");
        }
        let near = active::circle_zone_near(&xy, [4.0 + 1e-3, -1.0]).unwrap();
        assert!((near.form_error() - all.form_error()).abs() < 1e-12, "circle trial {trial}");
        // the control points are numbered among every point (not the subset) and lie on the zone
        let on = |pts: &[f64], dim: usize, c: &[f64], i: usize, r: f64| {
            let d: f64 = (0..dim).map(|k| (pts[dim * i + k] - c[k]).powi(2)).sum::<f64>().sqrt();
            (d - r).abs() < 1e-9
        };
        assert!(near.control_in.iter().all(|&i| on(&xy, 2, &near.center, i, near.r_in)), "circle trial {trial}");
        assert!(near.control_out.iter().all(|&i| on(&xy, 2, &near.center, i, near.r_out)), "circle trial {trial}");
        let complete = active::circle_near(&xy, [4.0 + 1e-3, -1.0]).unwrap();
        assert_eq!(complete.control_in, near.control_in);
        assert!((complete.arc - gagekit_form::circle::fit(&xy, FitCriterion::MinZone).unwrap().arc).abs() < 1e-9);
        let p = perturb(&sphere, 3, &model, 7, trial).unwrap();
        let all = gagekit_form::sphere::min_zone(&p).unwrap();
        let near = active::sphere_near(&p, [1.0, 2.0 + 1e-3, 3.0]).unwrap();
        assert!(((near.r_out - near.r_in) - (all.r_out - all.r_in)).abs() < 2e-9, "sphere trial {trial}");
        assert!(near.control_in.iter().all(|&i| on(&p, 3, &near.center, i, near.r_in)), "sphere trial {trial}");
        assert!(near.control_out.iter().all(|&i| on(&p, 3, &near.center, i, near.r_out)), "sphere trial {trial}");
    }
}

#[test]
fn the_feature_buffers_hold_the_perturbed_rows_bit_for_bit() {
    let (pts, _) = part();
    let n = pts.len() / 3;
    // overlapping, unsorted and gapped rows, and active points in no feature
    let a: Vec<usize> = (0..300).collect();
    let b: Vec<usize> = (250..400).chain(10..20).collect();
    let c: Vec<usize> = (0..n).rev().step_by(7).collect();
    let d: Vec<usize> = vec![5, 5, 900, 3];
    let rows: Vec<&[usize]> = vec![&a, &b, &c, &d];
    let map = super::perturb::Scatter::new(n, &rows);
    let models = [
        noise(0.01),
        Model { probing: 0.002, relative_scale: 1e-5, offset: 0.001, ..noise(0.01) },
        Model { origin: Some([1.0, -2.0, 30.0]), sigma_per_m: 0.5, probing: 0.002, relative_scale: 1e-5, offset: 0.001, ..noise(0.01) },
        Model { relative_scale: 1e-5, ..noise(0.0) },
        noise(0.0),
    ];
    for m in &models {
        let flat = perturb(&pts, 3, m, 3, 9).unwrap();
        let bufs = super::perturb::perturb_features(&pts, &map, m, 3, 9).unwrap();
        for (r, buf) in rows.iter().zip(&bufs) {
            let want: Vec<f64> = r.iter().flat_map(|&i| flat[3 * i..3 * i + 3].to_vec()).collect();
            assert_eq!(want.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), buf.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
        }
    }
    assert!(super::perturb::perturb_features(&pts[..30], &map, &models[0], 3, 9).is_err());
}

#[test]
fn the_band_holds_the_extremes_of_a_full_sort() {
    use super::active::{band, BAND, MIN_EXTREMES};
    let reference = |r: &[f64]| -> Vec<bool> {
        let lo = r.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = r.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let w = BAND * (hi - lo);
        let mut sel: Vec<bool> = r.iter().map(|&x| x <= lo + w || x >= hi - w).collect();
        let mut order: Vec<usize> = (0..r.len()).collect();
        order.sort_by(|a, b| r[*a].total_cmp(&r[*b]).then(a.cmp(b)));
        for &i in order[..MIN_EXTREMES].iter().chain(&order[r.len() - MIN_EXTREMES..]) {
            sel[i] = true;
        }
        sel
    };
    let mut cases: Vec<Vec<f64>> = Vec::new();
    for n in [40usize, 100, 1000] {
        // even spread; one far outlier on each side (few points in the band); ties
        cases.push((0..n).map(|i| ((i * 7919) % n) as f64).collect());
        let mut v: Vec<f64> = (0..n).map(|i| ((i * 31) % 17) as f64 * 0.01).collect();
        v[3] = -10.0;
        v[n - 2] = 10.0;
        cases.push(v);
        cases.push((0..n).map(|i| (i % 3) as f64).collect());
        cases.push((0..n).map(|i| if i == 5 { 1.0 } else { 0.0 }).collect());
    }
    for r in &cases {
        assert_eq!(band(r), reference(r));
    }
}

#[test]
fn the_trials_draw_independent_standard_normals() {
    // 200 trials of 3,000 deviates (1,000 points, sigma 1): pooled moments and tails of
    // N(0, 1), and no correlation between the streams of neighbouring trials or seeds
    let pts = vec![0.0; 3000];
    let m = noise(1.0);
    let draws: Vec<Vec<f64>> = (0..200).map(|t| perturb(&pts, 3, &m, 11, t).unwrap()).collect();
    let all: Vec<f64> = draws.concat();
    let n = all.len() as f64;
    let mean = all.iter().sum::<f64>() / n;
    let var = all.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
    let tail = all.iter().filter(|x| x.abs() > 1.959964).count() as f64 / n;
    let kurt = all.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / n / (var * var);
    // 600,000 deviates: standard errors 0.0013 (mean), 0.0018 (variance), 0.00028 (tail), 0.0063 (kurtosis)
    assert!(mean.abs() < 0.006 && (var - 1.0).abs() < 0.009, "mean {mean} var {var}");
    assert!((tail - 0.05).abs() < 0.0015 && (kurt - 3.0).abs() < 0.035, "tail {tail} kurtosis {kurt}");
    let corr = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>() / a.len() as f64;
    let other_seed = perturb(&pts, 3, &m, 12, 0).unwrap();
    for r in [corr(&draws[0], &draws[1]), corr(&draws[7], &draws[8]), corr(&draws[0], &other_seed)] {
        assert!(r.abs() < 5.0 / 3000f64.sqrt() * 1.2, "correlation {r}");
    }
    // the generator of (seed, trial) is pinned: a change of it changes every Monte Carlo result
    let mut g = perturb::trial_rng(0, 0);
    assert_eq!(rand::RngCore::next_u64(&mut g), PINNED_FIRST_OUTPUT);
}

const PINNED_FIRST_OUTPUT: u64 = 10309557242948042334;

#[test]
fn a_trial_from_the_measured_least_squares_cylinder_gives_the_complete_fits_values() {
    // the bore's least-squares cylinder by Gauss-Newton from the measured fit
    // (lsq::cylinder_warm) against the complete fit from the principal axes: every callout
    // (perpendicularity, roundness and position ride on the bore's axis) to 1e-10 mm
    let (pts, cold) = part();
    let mut warm = cold.clone();
    let bore: Vec<f64> = cold.features[2].rows.iter().flat_map(|&i| pts[3 * i..3 * i + 3].to_vec()).collect();
    warm.features[2].warm_lsq = Some(LsqStart::Cylinder(lsq::cylinder(&bore, None).unwrap()));
    let m = Model { probing: 0.002, ..noise(0.002) };
    for trial in 0..6 {
        let p = perturb(&pts, 3, &m, 9, trial).unwrap();
        let (a, b) = (evaluate(&cold, &p).unwrap().values, evaluate(&warm, &p).unwrap().values);
        let gap = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        assert!(gap <= 1e-10, "trial {trial}: {gap:e}\n{a:?}\n{b:?}");
    }
}

#[test]
fn the_inlined_ziggurat_draws_the_deviates_of_rand_distr_bit_for_bit() {
    use rand::Rng;
    // 4 M draws: the rectangle, the wedges (about 1 % of the draws) and the tail beyond R
    // (about 1 in 4,000) all met; the two generators stay in step
    let (mut a, mut b) = (perturb::trial_rng(3, 1), perturb::trial_rng(3, 1));
    let mut tail = 0;
    for _ in 0..4_000_000 {
        let (x, y): (f64, f64) = (perturb::normal(&mut a), b.sample(rand_distr::StandardNormal));
        assert_eq!(x.to_bits(), y.to_bits());
        tail += (x.abs() > 3.654152885361008796) as usize;
    }
    assert!(tail > 200, "{tail}");
    assert_eq!(a.random::<u64>(), b.random::<u64>());
}
