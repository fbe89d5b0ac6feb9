//! The design problem's own checks: shapes, zones, finite blocks, and the pooled scale.

use super::*;

impl Problem<'_> {
    pub(super) fn n(&self) -> usize {
        self.point_group.len()
    }

    pub(super) fn block(&self, j: usize) -> &[f64] {
        let sz = self.r * self.k;
        &self.blocks[j * sz..(j + 1) * sz]
    }

    pub(super) fn validate(&self, c: Criterion) -> Result<()> {
        let (r, k) = (self.r, self.k);
        if r == 0 || r > MAX_R {
            return Err(GkError::invalid(format!(
                "each design point must give 1 to {MAX_R} rows of the design matrix, got {r}"
            )));
        }
        if k == 0 {
            return Err(GkError::invalid("the model has no parameters (0 columns)"));
        }
        if self.n_cand == 0 {
            return Err(GkError::invalid("no candidate points to design from"));
        }
        if self.blocks.len() != self.n_cand * r * k {
            return Err(GkError::invalid(format!(
                "expected {} x {r} x {k} design-matrix values, got {}",
                self.n_cand,
                self.blocks.len()
            )));
        }
        if let Some(pos) = self.blocks.iter().position(|v| !v.is_finite()) {
            return Err(GkError::invalid(format!(
                "the design-matrix rows of candidate {} contain NaN or inf",
                pos / (r * k)
            )));
        }
        let n = self.n();
        if n == 0 {
            return Err(GkError::invalid("a plan needs at least one point"));
        }
        if n * r < k {
            return Err(GkError::invalid(format!(
                "{n} points give {} equations for {k} parameters: a plan needs at least {} points",
                n * r,
                k.div_ceil(r)
            )));
        }
        for (g, members) in self.groups.iter().enumerate() {
            if members.is_empty() && self.point_group.contains(&g) {
                return Err(GkError::infeasible(format!(
                    "zone {g} contains no candidate point"
                )));
            }
            if let Some(&bad) = members.iter().find(|&&j| j >= self.n_cand) {
                return Err(GkError::invalid(format!(
                    "zone {g} refers to candidate {bad}, but there are only {}",
                    self.n_cand
                )));
            }
        }
        if let Some(&g) = self.point_group.iter().find(|&&g| g >= self.groups.len()) {
            return Err(GkError::invalid(format!(
                "a design point belongs to zone {g}, but there are only {} zones",
                self.groups.len()
            )));
        }
        if c == Criterion::I {
            match self.weights {
                None => return Err(GkError::invalid("the I criterion needs a weight matrix")),
                Some(w) if w.len() != k * k || w.iter().any(|v| !v.is_finite()) => {
                    return Err(GkError::invalid(format!(
                        "the I weight matrix must be {k} x {k} and finite"
                    )))
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Information of all usable candidates: identifiability check and scale.
    pub(super) fn pooled(&self) -> Result<f64> {
        let mut used = vec![false; self.n_cand];
        for &g in &self.point_group {
            for &j in &self.groups[g] {
                used[j] = true;
            }
        }
        let idx: Vec<usize> = (0..self.n_cand).filter(|&j| used[j]).collect();
        let f = information(self.blocks, &idx, self.r, self.k);
        let m = metrics(&f, self.k, None);
        if m.rank < self.k {
            return Err(GkError::degenerate(format!(
                "the model has {} parameters but only {} independent combinations can be observed \
                 anywhere in the design space; remove dependent columns, rescale badly scaled ones, or widen the bounds",
                self.k, m.rank
            )));
        }
        let tr: f64 = (0..self.k).map(|a| f[a * self.k + a]).sum();
        Ok(tr / idx.len() as f64 * self.n() as f64 / self.k as f64)
    }
}
