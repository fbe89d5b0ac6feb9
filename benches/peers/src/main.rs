//! Peer comparisons for the design card's crates (see Cargo.toml). Prints one line per case:
//! case, gagekit time, peer time, ratio, and what each found.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::Instant;

fn best_of<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..reps.max(1) {
        let t = Instant::now();
        out = Some(f());
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, out.unwrap())
}

/// Raw little-endian f64 triples (as written by benches/bench_hull.py --parry).
fn read_points(path: &str) -> Vec<f64> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect()
}

/// parry3d's hull: (time, distinct vertex count) or the panic message.
fn parry_hull(flat: &[f64], reps: usize) -> Result<(f64, usize), String> {
    let pts: Vec<parry3d_f64::math::Point<f64>> =
        flat.chunks_exact(3).map(|c| parry3d_f64::math::Point::new(c[0], c[1], c[2])).collect();
    let run = || {
        best_of(reps, || {
            let (v, _faces) = parry3d_f64::transformation::convex_hull(&pts);
            v.len()
        })
    };
    catch_unwind(AssertUnwindSafe(run)).map_err(|p| {
        p.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| p.downcast_ref::<String>().cloned()).unwrap_or_default()
    })
}

fn gagekit_hull(flat: &[f64], reps: usize) -> Result<(f64, usize), String> {
    let run = || best_of(reps, || gagekit_geometry::convex_hull_indices(flat).map(|v| v.len()));
    match catch_unwind(AssertUnwindSafe(run)) {
        Ok((t, Ok(n))) => Ok((t, n)),
        Ok((_, Err(e))) => Err(format!("error: {e}")),
        Err(_) => Err("panic".into()),
    }
}

fn show(r: &Result<(f64, usize), String>) -> String {
    match r {
        Ok((t, n)) => format!("{:9.1} ms {:>8} vertices", t * 1e3, n),
        Err(e) => format!("FAILED: {}", e.lines().next().unwrap_or("")),
    }
}

fn hull_case(name: &str, flat: &[f64], reps: usize) {
    let g = gagekit_hull(flat, reps);
    let p = parry_hull(flat, reps);
    let ratio = match (&g, &p) {
        (Ok((tg, _)), Ok((tp, _))) => format!("{:6.1}x", tp / tg),
        _ => "     -".into(),
    };
    println!("{name:<26} gagekit {} | parry3d {} | ratio {ratio}", show(&g), show(&p));
}

/// Degenerate sets: where an exact hull must not fail and a floating-point one may.
fn degenerate_cases() {
    let mut s: u64 = 0x9E3779B97F4A7C15;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let n = 100_000;
    let plane: Vec<f64> = (0..n).flat_map(|_| [rnd() * 100.0, rnd() * 100.0, 5.0]).collect();
    let line: Vec<f64> = (0..n).flat_map(|_| { let t = rnd(); [t, 2.0 * t, 3.0 * t] }).collect();
    let same: Vec<f64> = (0..n).flat_map(|_| [1.0, 2.0, 3.0]).collect();
    let grid: Vec<f64> = (0..50).flat_map(|i| (0..50).flat_map(move |j| (0..40).flat_map(move |k| [i as f64, j as f64, k as f64]))).collect();
    let mut dup: Vec<f64> = (0..n / 2).flat_map(|_| [rnd(), rnd(), rnd()]).collect();
    dup.extend_from_within(..);
    let tiny: Vec<f64> = (0..n).flat_map(|_| [1.0 + rnd() * 1e-13, 1.0 + rnd() * 1e-13, 1.0 + rnd() * 1e-13]).collect();
    for (name, pts) in [("coplanar 100k", &plane), ("collinear 100k", &line), ("one point x100k", &same),
                        ("integer grid 50x50x40", &grid), ("every point twice 100k", &dup), ("1e-13 mm cloud 100k", &tiny)] {
        hull_case(name, pts, 1);
    }
}

fn lstsq_case(n_commands: usize) {
    let m = gagekit_kinematics::example_machine();
    let j = m.n_joints();
    // commands spread over +-1 rad and +-100 mm; the 52 columns have rank 32 (Eq. 3.14), so the
    // kernel runs its SVD and then reports the rank deficiency: the timing is the SVD's
    let mut s: u64 = 12345;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let cmds: Vec<f64> = (0..n_commands * j).map(|i| if i % j == 0 { rnd() } else { 100.0 * rnd() }).collect();
    let a = m.design_matrix(&cmds).expect("design matrix");
    let k = m.n_params();
    let rows = a.len() / k;
    let b: Vec<f64> = (0..rows).map(|_| rnd()).collect();
    // the shipped kernel: nalgebra SVD of the column-equilibrated matrix (+ cov, kappa)
    let (t_na, na) = best_of(1, || gagekit_kinematics::lstsq(&a, rows, k, &b));
    let na = na.map_err(|e| e.message);
    // faer: thin SVD of the same equilibrated matrix, and QR least squares
    let norms: Vec<f64> = (0..k).map(|c| (0..rows).map(|r| a[r * k + c].powi(2)).sum::<f64>().sqrt()).collect();
    let (t_fsvd, fs) = best_of(1, || {
        let eq = faer::Mat::<f64>::from_fn(rows, k, |r, c| a[r * k + c] / norms[c]);
        eq.singular_values()
    });
    let (t_fqr, fx) = best_of(1, || {
        let am = faer::Mat::<f64>::from_fn(rows, k, |r, c| a[r * k + c]);
        let bm = faer::Mat::<f64>::from_fn(rows, 1, |r, _| b[r]);
        let qr = am.col_piv_qr();
        use faer::linalg::solvers::SolveLstsq;
        let x = qr.solve_lstsq(&bm);
        (0..k).map(|c| x[(c, 0)]).collect::<Vec<f64>>()
    });
    let (agree_sv, agree_x) = match (&na, &fs) {
        (Ok(l), Ok(sv)) => {
            let mut sv = sv.clone();
            sv.sort_by(|x, y| y.total_cmp(x));
            let dsv = l.singular_values.iter().zip(&sv).map(|(p, q)| ((p - q) / p).abs()).fold(0.0, f64::max);
            let dx = l.x.iter().zip(&fx).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max)
                / l.x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            (format!("{dsv:.1e}"), format!("{dx:.1e}"))
        }
        _ => ("-".into(), "-".into()),
    };
    println!(
        "lstsq {n_commands:>8} commands ({rows} x {k}): nalgebra SVD lstsq {:.2} s | faer thin SVD {:.2} s ({:.1}x) | faer col-piv QR lstsq {:.2} s ({:.1}x) | rel. diff singular values {agree_sv}, x {agree_x}{}",
        t_na, t_fsvd, t_na / t_fsvd, t_fqr, t_na / t_fqr,
        if let Err(e) = &na { format!(" (nalgebra: {e})") } else { String::new() }
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("hull") => {
            for f in &args[1..] {
                let pts = read_points(f);
                let name = std::path::Path::new(f).file_stem().unwrap().to_string_lossy().to_string();
                hull_case(&name, &pts, 3);
            }
            degenerate_cases();
        }
        Some("lstsq") => {
            for n in &args[1..] {
                lstsq_case(n.parse().expect("number of commands"));
            }
        }
        _ => eprintln!("usage: peers hull FILE... | peers lstsq N..."),
    }
}
