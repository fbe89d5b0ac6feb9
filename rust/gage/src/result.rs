//! The public result of a virtual-gage check (Eq. 5.11 at T*, Secs. 5.2-5.5): each gage's
//! allowances, q_i and slack s_i under its name, T* with its matrix, the motion bounds that
//! limit it (Sec. 5.2.2), the infeasible groups by name (Eq. 5.10) and the part's status,
//! assembled once here from a [`Solution`]; the binding only converts it.

use crate::solve::Solution;
use crate::transform::MOTION_NAMES;
use gagekit_core::{GkError, Result};

/// A gage by name with its region and the region's point counts (as cut, after the hull
/// filter).
#[derive(Debug, Clone, PartialEq)]
pub struct GageLabel {
    pub name: String,
    pub region: String,
    pub points: usize,
    pub filtered_points: usize,
}

/// One gage at T* (mm): the smallest signed distance of its points from the gage plane
/// before and after T* (negative: short of material), `q` the largest (Eq. 5.4) and
/// `slack` the release s_i of Eq. 5.11 (0 when the gage is met).
#[derive(Debug, Clone, PartialEq)]
pub struct GageOutcome {
    pub label: GageLabel,
    pub allowance_before: f64,
    pub allowance_after: f64,
    pub q: f64,
    pub slack: f64,
}

/// A bound of Omega (Eq. 5.2) with a non-zero Lagrange multiplier at T* (Sec. 5.2.2).
#[derive(Debug, Clone, PartialEq)]
pub struct BoundLimit {
    pub motion: &'static str,
    /// "upper" or "lower".
    pub side: &'static str,
    pub dual: f64,
}

/// T* = [Rz(alpha) Ry(beta) Rx(gamma) | (dx, dy, dz)] (rad, mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// alpha, beta, gamma, dx, dy, dz.
    pub params: [f64; 6],
    pub matrix: [[f64; 4]; 4],
}

/// The outcome of a virtual-gage check.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckResult {
    /// "conforming" when every slack is zero, else "nonconforming".
    pub status: &'static str,
    /// Eq. 5.11 at T*: sum f_i q_i + sum g_i s_i + u.
    pub objective: f64,
    pub transform: Transform,
    pub bound_limits: Vec<BoundLimit>,
    pub gages: Vec<GageOutcome>,
    pub infeasible_groups: Vec<Vec<String>>,
    /// u of Eq. 5.11.
    pub largest_release: f64,
    pub iterations: usize,
    pub last_step: f64,
    pub lp_status: &'static str,
}

/// The status of a solution: "conforming" when every slack is zero.
pub fn status(sol: &Solution) -> &'static str {
    if sol.conforming() {
        "conforming"
    } else {
        "nonconforming"
    }
}

impl CheckResult {
    /// The result of `sol` for the gages `labels` (in the order of the gage set), with the
    /// infeasible `groups` as gage indices.
    pub fn new(sol: Solution, groups: Vec<Vec<usize>>, labels: Vec<GageLabel>) -> Result<Self> {
        if labels.len() != sol.s.len() {
            return Err(GkError::invalid(format!("{} gage labels for {} gages", labels.len(), sol.s.len())));
        }
        let name = |i: usize| labels.get(i).map(|l| l.name.clone()).ok_or_else(|| GkError::invalid("a group names no gage"));
        let infeasible_groups =
            groups.iter().map(|g| g.iter().map(|&i| name(i)).collect::<Result<Vec<_>>>()).collect::<Result<Vec<_>>>()?;
        let bound_limits = sol
            .active_bounds
            .iter()
            .map(|b| BoundLimit { motion: MOTION_NAMES[b.motion], side: if b.side > 0 { "upper" } else { "lower" }, dual: b.dual })
            .collect();
        let gages = labels
            .into_iter()
            .enumerate()
            .map(|(i, label)| GageOutcome {
                label,
                allowance_before: sol.allowance_before[i],
                allowance_after: sol.allowance_after[i],
                q: sol.q[i],
                slack: sol.s[i],
            })
            .collect();
        Ok(Self {
            status: status(&sol),
            objective: sol.objective,
            transform: Transform { params: sol.params, matrix: sol.matrix },
            bound_limits,
            gages,
            infeasible_groups,
            largest_release: sol.u,
            iterations: sol.iterations,
            last_step: sol.last_step,
            lp_status: sol.lp_status,
        })
    }
}
