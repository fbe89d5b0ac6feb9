//! Parallel, seeded particle swarm optimisation (Sec. 6.3, Fig. 6.11).
//!
//! A plain global-best PSO with inertia weight, box bounds and a stall test.
//! Particles are evaluated in parallel with rayon. Every particle owns its
//! random stream (ChaCha8 seeded with `seed`, stream = particle index), and the
//! global best is reduced sequentially in particle order after each
//! iteration, so the result depends on `seed` only, never on the number of
//! threads or their scheduling.
//!
//! ```
//! use gagekit_pso::{minimize, Settings};
//! let f = |x: &[f64]| (x[0] - 1.0).powi(2) + (x[1] + 2.0).powi(2);
//! let r = minimize(f, &[-5.0, -5.0], &[5.0, 5.0], &Settings::default()).unwrap();
//! assert!(r.value < 1e-8);
//! ```

mod simplex;
pub use simplex::{nelder_mead, Simplex};

use gagekit_core::{GkError, Result};
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// PSO settings. The defaults follow the dissertation (20 particles) with a
/// stall criterion so that converged swarms stop early.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Number of particles (>= 1).
    pub particles: usize,
    /// Maximum number of iterations (the dissertation uses 2000).
    pub max_iterations: usize,
    /// Seed of the random streams.
    pub seed: u64,
    /// Inertia weight w.
    pub inertia: f64,
    /// Cognitive (personal-best) acceleration c1.
    pub cognitive: f64,
    /// Social (global-best) acceleration c2.
    pub social: f64,
    /// Stop after this many iterations without an improvement of the best value
    /// by more than `tolerance` (absolute). 0 disables the stall test.
    pub stall_iterations: usize,
    /// Absolute improvement counted as progress by the stall test.
    pub tolerance: f64,
    /// Maximum velocity as a fraction of each box width.
    pub max_velocity: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            particles: 20,
            max_iterations: 2000,
            seed: 0,
            inertia: 0.7298,
            cognitive: 1.49618,
            social: 1.49618,
            stall_iterations: 50,
            tolerance: 0.0,
            max_velocity: 0.5,
        }
    }
}

/// What the swarm found.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Best position found.
    pub position: Vec<f64>,
    /// Objective value at `position`.
    pub value: f64,
    /// Iterations run (the initial evaluation not counted).
    pub iterations: usize,
    /// Objective evaluations in total.
    pub evaluations: usize,
    /// Best value after the initial evaluation and after each iteration
    /// (`iterations + 1` entries, non-increasing).
    pub history: Vec<f64>,
    /// Every particle's best position and value, in particle order (for
    /// multi-start local refinement).
    pub personal_best: Vec<(Vec<f64>, f64)>,
}

struct Particle {
    x: Vec<f64>,
    v: Vec<f64>,
    best_x: Vec<f64>,
    best_f: f64,
    rng: ChaCha8Rng,
}

fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

fn eval<F: Fn(usize, &[f64]) -> f64>(f: &F, i: usize, x: &[f64]) -> f64 {
    let v = f(i, x);
    if v.is_nan() {
        f64::INFINITY
    } else {
        v
    }
}

/// Index of the best personal best; ties go to the lowest index (deterministic).
fn best_index(swarm: &[Particle]) -> usize {
    let mut k = 0;
    for (i, p) in swarm.iter().enumerate() {
        if p.best_f < swarm[k].best_f {
            k = i;
        }
    }
    k
}

fn check(lower: &[f64], upper: &[f64], s: &Settings) -> Result<()> {
    if lower.is_empty() || lower.len() != upper.len() {
        return Err(GkError::config(format!(
            "PSO: bounds must be non-empty and of equal length (got {} and {})",
            lower.len(),
            upper.len()
        )));
    }
    for (d, (&lo, &hi)) in lower.iter().zip(upper).enumerate() {
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(GkError::config(format!(
                "PSO: bound {d} is not a finite interval (lower {lo}, upper {hi})"
            )));
        }
    }
    if s.particles == 0 {
        return Err(GkError::config("PSO: the swarm needs at least one particle"));
    }
    let coeffs = [s.inertia, s.cognitive, s.social, s.max_velocity, s.tolerance];
    if coeffs.iter().any(|c| !c.is_finite() || *c < 0.0) {
        return Err(GkError::config("PSO: coefficients must be finite and non-negative"));
    }
    Ok(())
}

/// Minimise `f` over the box `lower <= x <= upper`.
///
/// Positions leaving the box are clamped to it (and that velocity component
/// zeroed). A NaN objective value counts as +infinity.
pub fn minimize<F>(f: F, lower: &[f64], upper: &[f64], settings: &Settings) -> Result<Outcome>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    minimize_from(f, lower, upper, settings, &[])
}

/// As [`minimize`], with the first particles started at `starts` (clamped to
/// the box; e.g. a least-squares solution) instead of random positions.
pub fn minimize_from<F>(
    f: F,
    lower: &[f64],
    upper: &[f64],
    settings: &Settings,
    starts: &[Vec<f64>],
) -> Result<Outcome>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    minimize_particles(|_, x| f(x), lower, upper, settings, starts)
}

/// As [`minimize_from`], with an objective `f(particle, x)` that is told which
/// particle asks. Each particle's positions reach `f` in order (one per
/// iteration, never two at once), so per-particle state in `f` (a warm start)
/// keeps the result independent of the thread count.
pub fn minimize_particles<F>(
    f: F,
    lower: &[f64],
    upper: &[f64],
    settings: &Settings,
    starts: &[Vec<f64>],
) -> Result<Outcome>
where
    F: Fn(usize, &[f64]) -> f64 + Sync,
{
    check(lower, upper, settings)?;
    if starts.iter().any(|s| s.len() != lower.len() || s.iter().any(|v| !v.is_finite())) {
        return Err(GkError::config("PSO: every start must be a finite point of the search space"));
    }
    let dim = lower.len();
    let width: Vec<f64> = lower.iter().zip(upper).map(|(l, u)| u - l).collect();
    let vmax: Vec<f64> = width.iter().map(|w| w * settings.max_velocity).collect();

    let mut swarm: Vec<Particle> = (0..settings.particles)
        .into_par_iter()
        .map(|i| {
            let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
            rng.set_stream(i as u64);
            let mut x: Vec<f64> = (0..dim).map(|d| lower[d] + width[d] * uniform(&mut rng)).collect();
            if let Some(s) = starts.get(i) {
                x = (0..dim).map(|d| s[d].clamp(lower[d], upper[d])).collect();
            }
            let v: Vec<f64> = (0..dim).map(|d| vmax[d] * (2.0 * uniform(&mut rng) - 1.0)).collect();
            let fx = eval(&f, i, &x);
            Particle { best_x: x.clone(), x, v, best_f: fx, rng }
        })
        .collect();
    let mut evaluations = settings.particles;
    let mut g = best_index(&swarm);
    let mut g_x = swarm[g].best_x.clone();
    let mut g_f = swarm[g].best_f;
    let mut history = vec![g_f];
    let mut stall = 0usize;
    let mut iterations = 0usize;

    while iterations < settings.max_iterations {
        iterations += 1;
        let gx = &g_x;
        swarm.par_iter_mut().enumerate().for_each(|(i, p)| {
            for d in 0..dim {
                let r1 = uniform(&mut p.rng);
                let r2 = uniform(&mut p.rng);
                let mut v = settings.inertia * p.v[d]
                    + settings.cognitive * r1 * (p.best_x[d] - p.x[d])
                    + settings.social * r2 * (gx[d] - p.x[d]);
                v = v.clamp(-vmax[d], vmax[d]);
                let mut x = p.x[d] + v;
                if x < lower[d] {
                    x = lower[d];
                    v = 0.0;
                } else if x > upper[d] {
                    x = upper[d];
                    v = 0.0;
                }
                p.v[d] = v;
                p.x[d] = x;
            }
            let fx = eval(&f, i, &p.x);
            if fx < p.best_f {
                p.best_f = fx;
                p.best_x.copy_from_slice(&p.x);
            }
        });
        evaluations += settings.particles;
        g = best_index(&swarm);
        let improved = swarm[g].best_f < g_f - settings.tolerance;
        if swarm[g].best_f < g_f {
            g_f = swarm[g].best_f;
            g_x.copy_from_slice(&swarm[g].best_x);
        }
        history.push(g_f);
        stall = if improved { 0 } else { stall + 1 };
        if settings.stall_iterations > 0 && stall >= settings.stall_iterations {
            break;
        }
    }
    let personal_best = swarm.into_iter().map(|p| (p.best_x, p.best_f)).collect();
    Ok(Outcome { position: g_x, value: g_f, iterations, evaluations, history, personal_best })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rastrigin(x: &[f64]) -> f64 {
        10.0 * x.len() as f64
            + x.iter().map(|v| v * v - 10.0 * (2.0 * std::f64::consts::PI * v).cos()).sum::<f64>()
    }

    #[test]
    fn finds_quadratic_minimum() {
        let f = |x: &[f64]| (x[0] - 0.3).powi(2) + 10.0 * (x[1] + 0.7).powi(2);
        let r = minimize(f, &[-2.0, -2.0], &[2.0, 2.0], &Settings::default()).unwrap();
        assert!((r.position[0] - 0.3).abs() < 1e-4 && (r.position[1] + 0.7).abs() < 1e-4);
        assert_eq!(r.history.len(), r.iterations + 1);
        assert!(r.history.windows(2).all(|w| w[1] <= w[0]));
    }

    #[test]
    fn finds_global_minimum_of_rastrigin() {
        let s = Settings { particles: 40, stall_iterations: 200, ..Settings::default() };
        let r = minimize(rastrigin, &[-5.12; 2], &[5.12; 2], &s).unwrap();
        assert!(r.value < 1e-6, "{}", r.value);
    }

    #[test]
    fn deterministic_across_thread_counts() {
        let s = Settings { seed: 42, max_iterations: 100, ..Settings::default() };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| minimize(rastrigin, &[-5.12; 3], &[5.12; 3], &s).unwrap())
        };
        let (a, b) = (run(1), run(4));
        assert_eq!(a.position, b.position);
        assert_eq!(a.value.to_bits(), b.value.to_bits());
        assert_eq!(a.history, b.history);
        let c = minimize(rastrigin, &[-5.12; 3], &[5.12; 3], &Settings { seed: 43, ..s }).unwrap();
        assert_ne!(a.history, c.history);
    }

    #[test]
    fn respects_bounds_and_nan() {
        let f = |x: &[f64]| if x[0] > 0.5 { f64::NAN } else { -x[0] };
        let r = minimize(f, &[0.0], &[1.0], &Settings::default()).unwrap();
        assert!(r.position[0] <= 0.5 && r.position[0] > 0.49);
    }

    #[test]
    fn starts_are_used() {
        let f = |x: &[f64]| (x[0] - 0.123).abs();
        let s = Settings { max_iterations: 0, ..Settings::default() };
        let r = minimize_from(f, &[-1.0], &[1.0], &s, &[vec![0.123]]).unwrap();
        assert_eq!(r.value, 0.0);
        assert!(minimize_from(f, &[-1.0], &[1.0], &s, &[vec![0.1, 0.2]]).is_err());
    }

    #[test]
    fn rejects_bad_bounds() {
        let f = |x: &[f64]| x[0];
        assert!(minimize(f, &[], &[], &Settings::default()).is_err());
        assert!(minimize(f, &[1.0], &[0.0], &Settings::default()).is_err());
        assert!(minimize(f, &[f64::NAN], &[0.0], &Settings::default()).is_err());
        let s = Settings { particles: 0, ..Settings::default() };
        assert!(minimize(f, &[0.0], &[1.0], &s).is_err());
    }

    #[test]
    fn per_particle_state_is_thread_independent() {
        // an objective whose value depends on the particle's own history
        let s = Settings { seed: 9, max_iterations: 60, ..Settings::default() };
        let run = |threads: usize| {
            let calls: Vec<std::sync::Mutex<usize>> = (0..s.particles).map(|_| Default::default()).collect();
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                minimize_particles(
                    |i, x| {
                        let mut n = calls[i].lock().unwrap();
                        *n += 1;
                        rastrigin(x) + 1e-3 * (*n % 7) as f64
                    },
                    &[-5.12; 2],
                    &[5.12; 2],
                    &s,
                    &[],
                )
                .unwrap()
            })
        };
        let (a, b) = (run(1), run(3));
        assert_eq!(a.position, b.position);
        assert_eq!(a.value, b.value);
    }
}
