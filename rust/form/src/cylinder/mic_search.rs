//! Nelder–Mead on the exact values: the MIC of a partial arc, whose inscribed circle
//! touches the circumscribed one (Sec. 6.2.2, Cases I and II), a constraint the SLP
//! model of the points lacks.

use super::projection::{angles, project, zone_of, zone_value};
use super::{Criterion, HOPS, HOP_RADIUS, HOP_XTOL, NM_STEP, NM_XTOL};
use crate::circle;
use crate::lsq::orthonormal_basis;
use gagekit_pso::nelder_mead;
use nalgebra::Vector3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// The MIC objective for one Nelder–Mead search (a sequence of nearby axes; see
/// [`nelder_mead_search`]), warm-started: around the previous axis's centre, the
/// candidates built from the points nearest the circle ([`circle::max_inscribed_near`])
/// are tried first. Their best is accepted only when its control points are an active
/// set the exact kernel has already returned in this search (near the optimum the
/// projections cycle through a few active sets); otherwise the exact kernel runs, and
/// its circle becomes the warm start. Each search owns its state and is sequential, so
/// results do not depend on threads.
struct Warm<'a> {
    q: &'a [f64],
    size: f64,
    /// Centre of the last circle and the control points of every exact fit so far.
    state: std::sync::Mutex<(Option<[f64; 2]>, ActiveSets)>,
}

/// Control points (inner, outer) of exact 2-D fits.
type ActiveSets = Vec<(Vec<usize>, Vec<usize>)>;

/// Union of active sets, in order (deterministic).
fn merge_sets(into: &mut ActiveSets, more: ActiveSets) {
    for k in more {
        if !into.contains(&k) {
            into.push(k);
        }
    }
}

impl<'a> Warm<'a> {
    fn new(q: &'a [f64], size: f64) -> Self {
        Self::knowing(q, size, Vec::new())
    }

    /// A search that starts knowing the active sets other searches met.
    fn knowing(q: &'a [f64], size: f64, known: ActiveSets) -> Self {
        Self { q, size, state: std::sync::Mutex::new((None, known)) }
    }

    /// The active sets the exact kernel returned so far.
    fn active_sets(self) -> ActiveSets {
        self.state.into_inner().unwrap_or_else(|e| e.into_inner()).1
    }

    fn eval(&self, a: &Vector3<f64>) -> f64 {
        const MIC: Criterion = Criterion::MaxInscribed;
        let (t, f) = angles(&[a[0], a[1], a[2]]);
        let proj = project(self.q, t, f);
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let (center, seen) = &mut *state;
        let near = center.and_then(|c| circle::max_inscribed_near(&proj, c).ok().flatten()).map(zone_of);
        if let Some(z) = near {
            let v = zone_value(&z, MIC, self.size);
            if v.is_finite() && seen.iter().any(|(i, o)| *i == z.control_in && *o == z.control_out) {
                *center = Some(z.center);
                return v;
            }
        }
        let Ok(z) = circle::max_inscribed(&proj).map(zone_of) else {
            return f64::INFINITY;
        };
        let v = zone_value(&z, MIC, self.size);
        if v.is_finite() {
            *center = Some(z.center);
            let key = (z.control_in, z.control_out);
            if !seen.contains(&key) {
                seen.push(key);
            }
        }
        v
    }
}

/// Nelder–Mead over the tangent plane of the axis on the exact MIC values
/// (warm-started, see `Warm`), from each of `starts`, then `hop_rounds` rounds
/// of basin hopping about the best (restarts HOP_RADIUS away, polished to NM_XTOL).
/// Returns the best value and direction and the evaluations spent.
pub(super) fn nelder_mead_search(
    q: &[f64],
    size: f64,
    starts: &[Vector3<f64>],
    mut best: (f64, Vector3<f64>),
    hop_rounds: usize,
    in_region: &(dyn Fn(&Vector3<f64>) -> bool + Sync),
) -> (f64, Vector3<f64>, usize) {
    let descend = |a0: &Vector3<f64>, warm: Warm<'_>, step: f64, xtol: f64| {
        let (u, v) = orthonormal_basis(a0);
        let dir = |x: &[f64]| (a0 + u * x[0] + v * x[1]).normalize();
        let nm = nelder_mead(
            |x: &[f64]| {
                let a = dir(x);
                if in_region(&a) {
                    warm.eval(&a)
                } else {
                    f64::INFINITY
                }
            },
            &[0.0, 0.0],
            step,
            xtol,
        );
        (nm.value, dir(&nm.position), nm.evaluations, warm.active_sets())
    };
    let mut evaluations = 0;
    let refined: Vec<(f64, Vector3<f64>, usize, ActiveSets)> =
        starts.par_iter().map(|a0| descend(a0, Warm::new(q, size), NM_STEP, NM_XTOL)).collect();
    let mut known = ActiveSets::new();
    for (value, a, evals, sets) in refined {
        merge_sets(&mut known, sets);
        evaluations += evals;
        if value < best.0 {
            best = (value, a);
        }
    }
    for _ in 0..hop_rounds {
        let (u, v) = orthonormal_basis(&best.1);
        let a0 = best.1;
        let hops: Vec<(f64, Vector3<f64>, usize, ActiveSets)> = (0..HOPS)
            .into_par_iter()
            .map(|k| {
                let th = 0.3 + 2.0 * PI * k as f64 / HOPS as f64;
                let s0 = (a0 + (u * th.cos() + v * th.sin()) * HOP_RADIUS).normalize();
                descend(&s0, Warm::knowing(q, size, known.clone()), 0.2 * HOP_RADIUS, HOP_XTOL)
            })
            .collect();
        let before = best.0;
        for (value, a, evals, sets) in hops {
            merge_sets(&mut known, sets);
            evaluations += evals;
            if value < best.0 {
                best = (value, a);
            }
        }
        if best.0 >= before - 1e-9 * before.abs() {
            break;
        }
        let warm = Warm::knowing(q, size, known.clone());
        let (value, a, evals, _) = descend(&best.1, warm, 100.0 * HOP_XTOL, NM_XTOL);
        evaluations += evals;
        if value < best.0 {
            best = (value, a);
        }
    }
    (best.0, best.1, evaluations)
}

