use std::time::Instant;
fn main() {
    let n: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let noise: f64 = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(0.02);
    let mut s = 12345u64;
    let mut rnd = || { s ^= s << 13; s ^= s >> 7; s ^= s << 17; (s >> 11) as f64 / (1u64 << 53) as f64 };
    let mut v = Vec::new();
    for _ in 0..n { let a = rnd() * std::f64::consts::TAU; let r = 50.0 + (rnd() - 0.5) * noise; v.push(r * a.cos()); v.push(r * a.sin()); }
    for (name, f) in [("mc", 0), ("lsq", 1), ("mi", 2), ("mz", 3)] {
        let t = Instant::now();
        match f {
            0 => { gagekit_form::circle::min_circumscribed(&v).unwrap(); }
            1 => { gagekit_form::circle::least_squares(&v).unwrap(); }
            2 => { gagekit_form::circle::max_inscribed(&v).unwrap(); }
            _ => { let z = gagekit_form::circle::min_zone(&v).unwrap(); eprintln!("w {} at {:?}; f(0,0) = {}; ctrl {:?} {:?}", z.width(), z.center, fr(&v, [0.0, 0.0]), z.control_in, z.control_out); }
        }
        println!("{name} {:?}", t.elapsed());
    }
}
#[allow(dead_code)]
fn fr(v: &[f64], c: [f64; 2]) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for p in v.chunks(2) { let d = (p[0] - c[0]).hypot(p[1] - c[1]); lo = lo.min(d); hi = hi.max(d); }
    hi - lo
}
