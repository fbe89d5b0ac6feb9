use crate::*;
use gagekit_core::ErrorKind;

/// A grid of points on the plane through `c` spanned by `u`, `v`.
fn patch(c: [f64; 3], u: [f64; 3], v: [f64; 3], n: usize, bump: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for a in 0..n {
        for b in 0..n {
            let (s, t) = (a as f64 / (n - 1) as f64 - 0.5, b as f64 / (n - 1) as f64 - 0.5);
            // a small deterministic form error along u x v
            let w = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            let wn = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
            let w = [w[0] / wn, w[1] / wn, w[2] / wn];
            let h = bump * (3.0 * s).sin() * (2.0 * t).cos();
            for k in 0..3 {
                out.push(c[k] + s * u[k] + t * v[k] + h * w[k]);
            }
        }
    }
    out
}

fn rotate_y(pts: &mut [f64], beta: f64, shift: [f64; 3]) {
    let (sb, cb) = beta.sin_cos();
    for p in pts.chunks_exact_mut(3) {
        let (x, z) = (p[0], p[2]);
        p[0] = cb * x + sb * z + shift[0];
        p[1] += shift[1];
        p[2] = -sb * x + cb * z + shift[2];
    }
}

struct Owned {
    points: Vec<f64>,
    offsets: Vec<usize>,
    planes: Vec<f64>,
    f: Vec<f64>,
    g: Vec<f64>,
}

impl Owned {
    fn new() -> Self {
        Self { points: vec![], offsets: vec![0], planes: vec![], f: vec![], g: vec![] }
    }
    fn add(&mut self, pts: &[f64], plane: [f64; 4]) {
        self.points.extend_from_slice(pts);
        self.offsets.push(self.points.len() / 3);
        self.planes.extend_from_slice(&plane);
        self.f.push(1.0);
        self.g.push(10.0);
    }
    fn set(&self) -> GageSet<'_> {
        GageSet { points: &self.points, offsets: &self.offsets, planes: &self.planes, f: &self.f, g: &self.g }
    }
}

/// A block with a top face and four sides, allowance `a` everywhere, wall faces
/// `width` apart in x, then tilted and shifted.
fn block(width: f64, a: f64, beta: f64, shift: [f64; 3]) -> Owned {
    let x0 = 0.0;
    let x1 = width;
    let faces = [
        (patch([50.0, 50.0, 100.0 + a], [80.0, 0.0, 0.0], [0.0, 80.0, 0.0], 12, 0.05), [0.0, 0.0, 1.0, -100.0]),
        (patch([x1, 50.0, 60.0], [0.0, 80.0, 0.0], [0.0, 0.0, 60.0], 12, 0.05), [1.0, 0.0, 0.0, -(x1 - a)]),
        (patch([x0, 50.0, 60.0], [0.0, 80.0, 0.0], [0.0, 0.0, 60.0], 12, 0.05), [-1.0, 0.0, 0.0, x0 + a]),
        (patch([50.0, 100.0, 60.0], [80.0, 0.0, 0.0], [0.0, 0.0, 60.0], 12, 0.05), [0.0, 1.0, 0.0, -(100.0 - a)]),
    ];
    let mut o = Owned::new();
    for (mut pts, plane) in faces {
        rotate_y(&mut pts, beta, shift);
        o.add(&pts, plane);
    }
    o
}

fn four_axis() -> Motion {
    Motion { free: [false, true, false, true, true, true], max_angle: 0.05, max_shift: 20.0 }
}

#[test]
fn misplaced_block_is_corrected_and_exact() {
    let o = block(100.0, 1.0, 0.02, [3.0, 3.0, -1.0]);
    let set = o.set();
    let sol = solve(&set, &four_axis(), &Options::default()).unwrap();
    assert!(sol.allowance_before.iter().any(|&a| a < 0.0), "{:?}", sol.allowance_before);
    assert!(sol.conforming(), "{:?}", sol.s);
    assert!(sol.allowance_after.iter().all(|&a| a >= -1e-9));
    assert!(sol.last_step < 1e-10);
    // the tilt is undone
    assert!((sol.params[1] + 0.02).abs() < 2e-3, "{:?}", sol.params);
    // objective at T* equals the last LP's objective (linearisation at T* is exact at delta = 0)
    assert!((sol.objective - sol.lp_objective).abs() < 1e-6, "{} {}", sol.objective, sol.lp_objective);
    assert!(sol.active_bounds.is_empty());
}

#[test]
fn thin_wall_gets_equal_releases_and_one_group() {
    // faces 100 - 2*1.5 = 97 apart in x, gages need 98 -> deficit 1 mm... the block
    // is 97 wide, gages at x >= 97 - 1.5 + ... : build directly
    let mut o = block(97.0, 1.0, 0.0, [0.0, 0.0, 0.0]);
    // move the -x gage so the faces must be 98 apart: x <= -0.5 ... i.e. -x - 0.5 >= 0
    o.planes[8..12].copy_from_slice(&[-1.0, 0.0, 0.0, -0.5]);
    o.planes[4..8].copy_from_slice(&[1.0, 0.0, 0.0, -97.5]);
    let set = o.set();
    let m = four_axis();
    let opts = Options::default();
    let sol = solve(&set, &m, &opts).unwrap();
    assert!(!sol.conforming());
    assert!((sol.s[1] - sol.s[2]).abs() < 1e-6, "{:?}", sol.s);
    let total = sol.s[1] + sol.s[2];
    // deficit: 98 mm needed, 97 mm available less 2 x 0.05 mm of form error
    assert!(total > 0.95 && total < 1.15, "{total}");
    assert_eq!(sol.s[0], 0.0);
    assert_eq!(sol.s[3], 0.0);
    assert!((sol.u - sol.s[1]).abs() < 1e-12);
    let groups = infeasible_groups(&set, &m, &opts, &sol).unwrap();
    assert_eq!(groups, vec![vec![1, 2]]);
}

#[test]
fn motion_bound_limits_are_reported() {
    let o = block(100.0, 1.0, 0.04, [0.0, 0.0, 0.0]);
    let set = o.set();
    let m = Motion { free: [false, true, false, true, true, true], max_angle: 0.01, max_shift: 20.0 };
    let sol = solve(&set, &m, &Options::default()).unwrap();
    assert!((sol.params[1] + 0.01).abs() < 1e-12, "{:?}", sol.params);
    assert_eq!(sol.active_bounds.len(), 1, "{:?}", sol.active_bounds);
    assert_eq!(sol.active_bounds[0].motion, 1);
    assert_eq!(sol.active_bounds[0].side, -1);
}

#[test]
fn linearised_lp_matches_exact_distances_at_zero_step() {
    let o = block(100.0, 1.0, 0.02, [3.0, 3.0, -1.0]);
    let set = o.set();
    let p = [0.0, -0.019, 0.0, -2.0, -3.0, 1.0];
    let lp = assemble(&set, &four_axis(), &p, None);
    let ext = extremes(&set, &p);
    // rows 0, 2, ... hold -e0; the smallest distance of gage 0 is the max of those rows
    let n0 = set.offsets[1];
    let min0 = (0..n0).map(|j| -lp.b[2 * j]).fold(f64::INFINITY, f64::min);
    assert!((min0 - ext[0].0).abs() < 1e-12);
}

#[test]
fn bad_input_is_reported() {
    let mut o = block(100.0, 1.0, 0.0, [0.0; 3]);
    o.planes[0] = f64::NAN;
    let e = solve(&o.set(), &four_axis(), &Options::default()).unwrap_err();
    assert_eq!(e.kind, ErrorKind::InvalidInput);
    let mut o = block(100.0, 1.0, 0.0, [0.0; 3]);
    o.points[4] = f64::INFINITY;
    assert!(solve(&o.set(), &four_axis(), &Options::default()).is_err());
    let mut o = block(100.0, 1.0, 0.0, [0.0; 3]);
    o.offsets[1] = 0;
    assert!(solve(&o.set(), &four_axis(), &Options::default()).is_err());
    let e = solve(
        &GageSet { points: &[], offsets: &[0], planes: &[], f: &[], g: &[] },
        &four_axis(),
        &Options::default(),
    )
    .unwrap_err();
    assert_eq!(e.kind, ErrorKind::Config);
}

#[test]
fn forced_release_infeasible_within_bounds_gives_singleton_group() {
    // a face 5 mm short of its gage with only 1 mm of travel: it cannot be met alone
    let mut o = Owned::new();
    o.add(&patch([0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0], 5, 0.0), [0.0, 0.0, 1.0, -5.0]);
    let set = o.set();
    let m = Motion { free: [false, false, false, false, false, true], max_angle: 0.0, max_shift: 1.0 };
    let opts = Options::default();
    let sol = solve(&set, &m, &opts).unwrap();
    assert!((sol.s[0] - 4.0).abs() < 1e-9, "{:?}", sol.s);
    assert_eq!(sol.active_bounds.len(), 1);
    assert_eq!(infeasible_groups(&set, &m, &opts, &sol).unwrap(), vec![vec![0]]);
}

#[test]
fn constraint_generation_matches_the_whole_lp() {
    // 4 faces x 1600 points: above the direct limit
    let mut o = Owned::new();
    let b = block(100.0, 1.0, 0.02, [3.0, 3.0, -1.0]);
    let faces = [
        (patch([50.0, 50.0, 101.0], [80.0, 0.0, 0.0], [0.0, 80.0, 0.0], 40, 0.05), 0),
        (patch([100.0, 50.0, 60.0], [0.0, 80.0, 0.0], [0.0, 0.0, 60.0], 40, 0.05), 1),
        (patch([0.0, 50.0, 60.0], [0.0, 80.0, 0.0], [0.0, 0.0, 60.0], 40, 0.05), 2),
        (patch([50.0, 100.0, 60.0], [80.0, 0.0, 0.0], [0.0, 0.0, 60.0], 40, 0.05), 3),
    ];
    for (mut pts, i) in faces {
        rotate_y(&mut pts, 0.02, [3.0, 3.0, -1.0]);
        let plane: [f64; 4] = b.planes[4 * i..4 * i + 4].try_into().unwrap();
        o.add(&pts, plane);
    }
    let set = o.set();
    assert!(set.offsets[4] > lp::DIRECT_LIMIT);
    let m = four_axis();
    for p in [[0.0; 6], [0.0, -0.019, 0.0, -2.0, -3.0, 1.0]] {
        let whole = solve_lp(&assemble(&set, &m, &p, None)).unwrap();
        let (sub, cg) = solve_linearised(&set, &m, &p, None, set.radius(), false).unwrap();
        assert!(sub.nrows < assemble(&set, &m, &p, None).nrows / 10, "{}", sub.nrows);
        assert!((whole.objective - cg.objective).abs() < 1e-7 * (1.0 + whole.objective.abs()));
    }
    let sol = solve(&set, &m, &Options::default()).unwrap();
    assert!(sol.conforming() && sol.last_step < 1e-10);
}

#[test]
fn three_gages_that_conflict_only_together_form_one_group() {
    // Fig. 5.7: gage 0 needs dx >= 0.5; gages 1 and 2 (normals (-1, +-1)/sqrt 2)
    // together allow dx <= 0.141 only; any two of the three can be met.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let mut o = Owned::new();
    o.add(&patch([0.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0], 3, 0.0), [1.0, 0.0, 0.0, -0.5]);
    let p1 = patch([5.0, 5.0, 0.0], [h, h, 0.0], [0.0, 0.0, 2.0], 3, 0.0);
    let d1 = -(-h * 5.0 + h * 5.0) + 0.1;
    o.add(&p1, [-h, h, 0.0, d1]);
    let p2 = patch([5.0, -5.0, 0.0], [h, -h, 0.0], [0.0, 0.0, 2.0], 3, 0.0);
    let d2 = -(-h * 5.0 + h * 5.0) + 0.1;
    o.add(&p2, [-h, -h, 0.0, d2]);
    let set = o.set();
    let m = Motion { free: [false, false, false, true, true, false], max_angle: 0.0, max_shift: 5.0 };
    let opts = Options::default();
    let sol = solve(&set, &m, &opts).unwrap();
    assert!(!sol.conforming());
    // allowances before: gage 0 short by 0.5, gages 1 and 2 at +0.1
    assert!((sol.allowance_before[0] + 0.5).abs() < 1e-12 && (sol.allowance_before[1] - 0.1).abs() < 1e-12);
    let groups = infeasible_groups(&set, &m, &opts, &sol).unwrap();
    assert!(groups.contains(&vec![0, 1, 2]), "{groups:?}");
    // no group is a single gage: each one alone can be met
    assert!(groups.iter().all(|g| g.len() >= 2), "{groups:?}");
}

#[test]
fn loose_bounds_do_not_change_the_answer() {
    // issue 12: the LP was scaled by its bound rows, so max_shift = 1e12 returned a
    // non-optimal point; the capped-and-widened bounds give the same optimum for any
    // bound that is not limiting
    let o = block(40.0, 2.0, 0.01, [0.3, -0.2, 0.5]);
    let reference = solve(&o.set(), &four_axis(), &Options::default()).unwrap();
    assert!(reference.active_bounds.is_empty());
    for e in [5.0f64, 10.0, 30.0, 100.0, 1e3, 1e6, 1e10, 1e12, 1e50, 1e100, 1e200, 1e300] {
        let m = Motion { max_shift: e, max_angle: 0.05, ..four_axis() };
        let s = solve(&o.set(), &m, &Options::default()).unwrap();
        assert_eq!(s.conforming(), reference.conforming(), "max_shift {e}");
        assert!((s.objective - reference.objective).abs() <= 1e-7 * (1.0 + reference.objective.abs()), "max_shift {e}: {} vs {}", s.objective, reference.objective);
        let m = Motion { max_angle: e, ..four_axis() };
        let s = solve(&o.set(), &m, &Options::default()).unwrap();
        assert!(s.objective <= reference.objective + 1e-7, "max_angle {e}");
        assert!(s.objective.is_finite() && s.params.iter().all(|v| v.is_finite()));
    }
}
