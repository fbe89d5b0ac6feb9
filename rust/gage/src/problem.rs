//! The data of a virtual-gage problem (Eqs. 5.4, 5.11) and its exact evaluation.

use crate::transform::{pull_back, rotation_and_derivatives};
use gagekit_core::{check_coordinates, GkError, Result};

/// Gages with their point-sets, all in the part frame.
///
/// Gage `i` owns the points `points[3*offsets[i] .. 3*offsets[i+1]]` and the plane
/// `planes[4*i .. 4*i+4]` = (a, b, c, d) with a x + b y + c z + d >= 0 on the
/// material side (Table 5.1); `f[i]`, `g[i]` are the weights of q_i and s_i.
#[derive(Debug, Clone, Copy)]
pub struct GageSet<'a> {
    pub points: &'a [f64],
    pub offsets: &'a [usize],
    pub planes: &'a [f64],
    pub f: &'a [f64],
    pub g: &'a [f64],
}

/// The set Omega of Eq. 5.2: which motions vary and their bounds.
#[derive(Debug, Clone, Copy)]
pub struct Motion {
    /// alpha, beta, gamma, dx, dy, dz
    pub free: [bool; 6],
    /// delta_r (rad): |alpha|, |beta|, |gamma| <= max_angle
    pub max_angle: f64,
    /// delta_t (mm): |dx|, |dy|, |dz| <= max_shift
    pub max_shift: f64,
}

impl Motion {
    pub fn bound(&self, k: usize) -> f64 {
        if k < 3 {
            self.max_angle
        } else {
            self.max_shift
        }
    }
    pub fn free_indices(&self) -> Vec<usize> {
        (0..6).filter(|&k| self.free[k]).collect()
    }
}

impl<'a> GageSet<'a> {
    pub fn len(&self) -> usize {
        self.f.len()
    }
    pub fn is_empty(&self) -> bool {
        self.f.is_empty()
    }
    pub fn points_of(&self, i: usize) -> &'a [f64] {
        &self.points[3 * self.offsets[i]..3 * self.offsets[i + 1]]
    }
    pub fn normal(&self, i: usize) -> [f64; 3] {
        [self.planes[4 * i], self.planes[4 * i + 1], self.planes[4 * i + 2]]
    }
    pub fn offset(&self, i: usize) -> f64 {
        self.planes[4 * i + 3]
    }

    /// Check shapes, finiteness, unit normals, weights and non-empty point-sets.
    pub fn validate(&self, motion: &Motion) -> Result<()> {
        let k = self.f.len();
        if k == 0 {
            return Err(GkError::config("no gages given: a virtual-gage problem needs at least one gage"));
        }
        if self.g.len() != k || self.planes.len() != 4 * k || self.offsets.len() != k + 1 {
            return Err(GkError::invalid(format!(
                "inconsistent gage data: {k} weights f, {} weights g, {} plane values, {} offsets",
                self.g.len(),
                self.planes.len(),
                self.offsets.len()
            )));
        }
        if self.offsets[0] != 0
            || self.offsets.windows(2).any(|w| w[1] < w[0])
            || 3 * self.offsets[k] != self.points.len()
        {
            return Err(GkError::invalid("gage point offsets do not partition the point array"));
        }
        check_coordinates(self.points, 3, "gage points")?;
        for i in 0..k {
            if self.offsets[i + 1] == self.offsets[i] {
                return Err(GkError::invalid(format!("gage {i} has no points")));
            }
            let p = &self.planes[4 * i..4 * i + 4];
            if p.iter().any(|v| !v.is_finite()) {
                return Err(GkError::invalid(format!("gage {i}: plane {p:?} is not finite")));
            }
            let nn = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            if (nn - 1.0).abs() > 1e-9 {
                return Err(GkError::invalid(format!(
                    "gage {i}: plane normal has length {nn}, expected a unit normal"
                )));
            }
            if !(self.f[i] >= 0.0 && self.f[i].is_finite() && self.g[i] >= 0.0 && self.g[i].is_finite()) {
                return Err(GkError::invalid(format!(
                    "gage {i}: weights must be finite and non-negative, got f = {}, g = {}",
                    self.f[i], self.g[i]
                )));
            }
        }
        let bad = |v: f64| v < 0.0 || !v.is_finite();
        if bad(motion.max_angle) || bad(motion.max_shift) {
            return Err(GkError::config(format!(
                "motion bounds must be finite and non-negative, got max_angle = {}, max_shift = {}",
                motion.max_angle, motion.max_shift
            )));
        }
        Ok(())
    }

    /// Largest distance of any gage point from the origin (a lever arm in mm).
    pub fn radius(&self) -> f64 {
        self.points
            .chunks_exact(3)
            .map(|r| (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt())
            .fold(0.0, f64::max)
    }
}

/// Per gage: (min, max) of the exact signed distances e_ij of Eq. 5.1 under the
/// exact transform with parameters `p`.
pub fn extremes(set: &GageSet, p: &[f64; 6]) -> Vec<(f64, f64)> {
    let (r, _) = rotation_and_derivatives(p);
    (0..set.len())
        .map(|i| {
            let n = set.normal(i);
            let m = pull_back(&r, &n);
            let c = n[0] * p[3] + n[1] * p[4] + n[2] * p[5] + set.offset(i);
            set.points_of(i).chunks_exact(3).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                let e = m[0] * x[0] + m[1] * x[1] + m[2] * x[2] + c;
                (lo.min(e), hi.max(e))
            })
        })
        .collect()
}
