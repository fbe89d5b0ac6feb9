//! 2-D circles by the particle swarm (Sec. 6.2, Eqs. 6.1, 6.4, 6.5): a
//! cross-check of the exact kernels in [`crate::circle`].
//!
//! The swarm searches the centre c over the (slightly enlarged) bounding box of
//! the points, minimising max_i |q_i - c| (MC), maximising min_i |q_i - c|
//! subject to the MI lying within the MC, r + |c - c_MC| <= r_MC (Eq. 6.2), or
//! minimising max - min (MZ); a Nelder–Mead search then refines the centre.

use crate::circle::{self, Circle, Zone};
use gagekit_core::{GkError, Result};
use gagekit_pso::{minimize, nelder_mead, Settings};

/// Which 2-D circle the swarm fits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    MinCircumscribed,
    MaxInscribed,
    MinZone,
}

/// A circle fitted by the swarm, as a zone (r_in = r_out for MC and MI), with
/// the swarm's iterations and evaluations.
#[derive(Debug, Clone)]
pub struct SwarmFit {
    pub zone: Zone,
    pub iterations: usize,
    pub evaluations: usize,
}

fn extremes(pts: &[[f64; 2]], c: [f64; 2]) -> (f64, f64) {
    pts.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
        let d = (p[0] - c[0]).hypot(p[1] - c[1]);
        (lo.min(d), hi.max(d))
    })
}

/// Fit a 2-D circle of the given kind with the seeded PSO (`settings.seed`).
pub fn fit(pts: &[f64], kind: Kind, settings: &Settings) -> Result<SwarmFit> {
    // centre the data on its bounding box (checks: finite, at least 3 points, sane units)
    let circle::Centered { pts: q, shift: mid, half, .. } = circle::Centered::new(pts, "circle", 3)?;
    let size = half[0].hypot(half[1]);
    if size == 0.0 {
        return Err(GkError::degenerate("circle: all points coincide"));
    }
    let mc = match kind {
        Kind::MaxInscribed => {
            let flat: Vec<f64> = q.iter().flat_map(|p| *p).collect();
            Some(circle::min_circumscribed(&flat)?)
        }
        _ => None,
    };
    let objective = |x: &[f64]| {
        let c = [x[0], x[1]];
        let (dmin, dmax) = extremes(&q, c);
        match kind {
            Kind::MinCircumscribed => dmax,
            Kind::MinZone => dmax - dmin,
            Kind::MaxInscribed => {
                let m: &Circle = mc.as_ref().expect("MC computed for MI");
                let off = (c[0] - m.center[0]).hypot(c[1] - m.center[1]);
                if dmin + off <= m.radius {
                    -dmin
                } else {
                    f64::INFINITY
                }
            }
        }
    };
    let ext = [half[0].max(1e-3 * size) * 1.1, half[1].max(1e-3 * size) * 1.1];
    let swarm = minimize(objective, &[-ext[0], -ext[1]], &[ext[0], ext[1]], settings)?;
    if !swarm.value.is_finite() {
        return Err(GkError::numerical("circle (PSO): the swarm found no feasible centre"));
    }
    let nm = nelder_mead(objective, &swarm.position, 1e-3 * size, 1e-15 * size);
    let c = [nm.position[0], nm.position[1]];
    let (dmin, dmax) = extremes(&q, c);
    let tol = 1e-9 * size;
    let near = |target: f64| -> Vec<usize> {
        q.iter()
            .enumerate()
            .filter(|(_, p)| ((p[0] - c[0]).hypot(p[1] - c[1]) - target).abs() <= tol)
            .map(|(i, _)| i)
            .collect()
    };
    let (r_in, r_out) = match kind {
        Kind::MinCircumscribed => (dmax, dmax),
        Kind::MaxInscribed => (dmin, dmin),
        Kind::MinZone => (dmin, dmax),
    };
    let zone = Zone {
        center: [c[0] + mid[0], c[1] + mid[1]],
        r_in,
        r_out,
        control_in: near(r_in),
        control_out: near(r_out),
    };
    Ok(SwarmFit { zone, iterations: swarm.iterations, evaluations: swarm.evaluations + nm.evaluations })
}
