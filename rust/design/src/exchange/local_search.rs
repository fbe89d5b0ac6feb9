//! Local search of one start: sweeps until no point moves, perturb-and-polish rounds
//! (iterated local search), and the randomised greedy start.

use super::*;

/// Perturb-and-polish rounds after a start's local optimum (see [`Run::perturb_and_polish`]).
pub(super) fn polish_rounds(c: Criterion) -> usize {
    // by the cost of a re-optimisation (D and I are cheap, K and E dear); A keeps its
    // time for the main search, whose result already beats a plain exchange's
    match c {
        Criterion::D | Criterion::I => 6,
        Criterion::K | Criterion::E => 1,
        Criterion::A => 0,
    }
}

/// Candidates sampled per point when building a greedy start.
pub(super) const GREEDY_SAMPLE: usize = 64;

impl<'p, 'a> Run<'p, 'a> {

    /// Sweep until no point moves; returns the number of exchanges.
    pub(super) fn optimise(&mut self, max_sweeps: usize, rng: &mut ChaCha8Rng) -> usize {
        let n = self.p.n();
        let mut order: Vec<usize> = (0..n).collect();
        let mut moves = 0;
        let mut stale = usize::MAX; // exchanges since the per-candidate blocks were refreshed
                                    // A and I (k-exchange): cheap sweeps visit only the quarter of the points whose removal
                                    // costs least; when they stop improving, a sweep over every point confirms (so the
                                    // result is a local optimum for single exchanges either way).
        let k_exchange = self.needs_e() && n >= 16;
        let mut full = !k_exchange;
        for _ in 0..max_sweeps {
            if !self.c.is_spectral() && stale >= REFRESH_AFTER {
                self.refresh();
                stale = 0;
            }
            let visit: Vec<usize> = if full {
                order.shuffle(rng);
                order.clone()
            } else {
                self.cheapest_points(n.div_ceil(4))
            };
            let mut moved = false;
            for &i in &visit {
                if interrupt::requested() {
                    return moves; // Ctrl-C: `search` reports it after the starts return
                }
                let m = if self.c.is_spectral() {
                    self.visit_spectral(i)
                } else {
                    self.visit_algebraic(i)
                };
                if m {
                    moves += 1;
                    stale = stale.saturating_add(1);
                    moved = true;
                }
            }
            if !moved {
                if full {
                    break;
                }
                full = true;
            } else if k_exchange {
                full = false;
            }
        }
        moves
    }

    /// Iterated local search from the local optimum reached: `rounds` times, move a few
    /// random points to random candidates of their zones, optimise again, and keep the
    /// result only if it beats the best so far (so the value never gets worse).
    pub(super) fn perturb_and_polish(
        &mut self,
        rounds: usize,
        max_sweeps: usize,
        rng: &mut ChaCha8Rng,
    ) -> usize {
        let n = self.p.n();
        let mut moves = 0;
        for _ in 0..rounds {
            if interrupt::requested() {
                break;
            }
            let (best, best_value) = (self.design.clone(), self.value);
            let kick = (n / PERTURB_FRACTION).clamp(1, n);
            for i in sample(rng, n, kick).iter() {
                let members = &self.p.groups[self.p.point_group[i]];
                self.design[i] = members[rng.random_range(0..members.len())];
            }
            let mut m = 0;
            let improved = self.recompute().is_ok() && {
                m = self.optimise(max_sweeps, rng);
                self.value < best_value - self.tol()
            };
            if improved {
                moves += m;
            } else {
                self.design = best;
                // the best design was valid a moment ago
                let _ = self.recompute();
            }
        }
        moves
    }

    /// The `m` design points whose removal raises the criterion least: tr(Q^-1 e_O)
    /// with Q = I - O F^-1 O^T (A, I), from the stored per-candidate blocks.
    pub(super) fn cheapest_points(&self, m: usize) -> Vec<usize> {
        let r = self.p.r;
        let rr = r * r;
        let mut loss: Vec<(f64, usize)> = (0..self.p.n())
            .map(|i| {
                let o = self.design[i];
                let mut q = [0.0; MAX_R * MAX_R];
                for a in 0..r {
                    for b in 0..r {
                        q[a * r + b] = if a == b { 1.0 } else { 0.0 } - self.d[o * rr + a * r + b];
                    }
                }
                let mut qi = [0.0; MAX_R * MAX_R];
                let v = match small_spd_inverse(&q, r, &mut qi) {
                    Some(_) => (0..rr).map(|t| qi[t] * self.e[o * rr + t]).sum(),
                    None => f64::INFINITY,
                };
                (sane(v), i)
            })
            .collect();
        loss.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        loss.into_iter().take(m).map(|x| x.1).collect()
    }
}


/// Randomised greedy D-optimal construction: each point (random order) takes the
/// best of a random sample of its zone's candidates.
pub(super) fn greedy_start(p: &Problem, ridge0: f64, rng: &mut ChaCha8Rng) -> Vec<usize> {
    let (r, k, n) = (p.r, p.k, p.n());
    let mut f = vec![0.0; k * k];
    for a in 0..k {
        f[a * k + a] = ridge0;
    }
    let mut finv = spd_inverse(&f, k).map(|x| x.0).unwrap_or_else(|| f.clone());
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(rng);
    let mut design = vec![0; n];
    let mut g = vec![0.0; r * k];
    let mut m = [0.0; MAX_R * MAX_R];
    let mut piv = [0; MAX_R];
    for &i in &order {
        let members = &p.groups[p.point_group[i]];
        let take = GREEDY_SAMPLE.min(members.len());
        let picks = sample(rng, members.len(), take);
        let mut best = (f64::NEG_INFINITY, members[picks.index(0)]);
        for q in picks.iter() {
            let j = members[q];
            let b = p.block(j);
            mul_ab(b, &finv, r, k, &mut g);
            mul_abt(&g, b, r, k, r, &mut m);
            for a in 0..r {
                m[a * r + a] += 1.0;
            }
            let det = lu_in_place(&mut m[..r * r], &mut piv[..r], r).unwrap_or(0.0);
            if det > best.0 {
                best = (det, j);
            }
        }
        design[i] = best.1;
        gram_add(&mut f, p.block(best.1), r, k, 1.0);
        if let Some((inv, _)) = spd_inverse(&f, k) {
            finv = inv;
        }
    }
    design
}
