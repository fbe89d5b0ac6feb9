//! The datum reference frame of simulated datum planes and axes (ISO 5459; the rules of
//! `gagekit.inspect.datums.DatumSystem._build_frame`, which documents them): z from the
//! primary datum, x or y from the next datum not along z, the origin the least-norm
//! point meeting every datum's location constraint (Eq. 5.16), the free translations the
//! complement of the constraints' normals, the turn about z free when nothing fixes it.

use super::Simulated;
use crate::turn::Frame;
use crate::vec3::{basis, cross, dot, norm, scale, sub, V3};
use gagekit_core::{GkError, Result};

fn unit(v: V3) -> V3 {
    scale(v, 1.0 / norm(v))
}

/// The location constraints n.o = n.p kept independent: `q` their Gram-Schmidt basis.
#[derive(Default)]
struct Constraints {
    rows: Vec<V3>,
    vals: Vec<f64>,
    q: Vec<V3>,
}

impl Constraints {
    fn add(&mut self, n: V3, point: V3) {
        let mut r = n;
        for q in &self.q {
            r = sub(r, scale(*q, dot(*q, n)));
        }
        if !self.rows.is_empty() && norm(r) < 1e-6 {
            return;
        }
        self.q.push(unit(r));
        self.rows.push(n);
        self.vals.push(dot(n, point));
    }

    /// The least-norm correction of `reference` meeting every constraint
    /// (o = ref + A^T (A A^T)^-1 (b - A ref), A of independent rows).
    fn origin(&self, reference: V3) -> Result<V3> {
        let k = self.rows.len();
        let r: Vec<f64> = (0..k).map(|i| self.vals[i] - dot(self.rows[i], reference)).collect();
        let mut g = vec![vec![0.0; k]; k];
        for i in 0..k {
            for j in 0..k {
                g[i][j] = dot(self.rows[i], self.rows[j]);
            }
        }
        let y = solve(g, r)?;
        let mut o = reference;
        for i in 0..k {
            o = [o[0] + self.rows[i][0] * y[i], o[1] + self.rows[i][1] * y[i], o[2] + self.rows[i][2] * y[i]];
        }
        Ok(o)
    }

    /// An orthonormal basis of the translations no constraint locks.
    fn free(&self) -> Vec<V3> {
        match self.q.len() {
            0 => vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            1 => {
                let (u, v) = basis(self.q[0]);
                vec![u, v]
            }
            2 => vec![unit(cross(self.q[0], self.q[1]))],
            _ => Vec::new(),
        }
    }
}

/// Gaussian elimination with partial pivoting of a small system.
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Result<Vec<f64>> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs())).unwrap();
        if a[p][c].abs() < 1e-300 {
            return Err(GkError::degenerate("datum frame: dependent datum constraints"));
        }
        a.swap(c, p);
        b.swap(c, p);
        for r in c + 1..n {
            let f = a[r][c] / a[c][c];
            for k in c..n {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for c in (0..n).rev() {
        let s: f64 = (c + 1..n).map(|k| a[c][k] * x[k]).sum();
        x[c] = (b[c] - s) / a[c][c];
    }
    Ok(x)
}

/// The frame of the datums `sims` (planes and axes, in the feature control frame's
/// order); `box_axes`: the primary feature's region box (x when the turn is free).
pub fn build_frame(sims: &[Simulated], box_axes: [V3; 3]) -> Result<Frame> {
    let first = sims[0];
    let mut c = Constraints::default();
    let axis_rows = |d: V3| {
        let (u, v) = basis(d);
        [u, v]
    };
    let mut z = if first.plane { scale(first.vector, -1.0) } else { first.vector };
    let (mut x, mut y): (Option<V3>, Option<V3>) = (None, None);
    if first.plane {
        c.add(first.vector, first.point);
    } else {
        for n in axis_rows(first.vector) {
            c.add(n, first.point);
        }
    }
    let mut axis_seen = if first.plane { None } else { Some(first) };
    for (k, s) in sims.iter().enumerate().skip(1) {
        if s.plane {
            let inward = scale(s.vector, -1.0);
            if dot(inward, z).abs() > 0.999 {
                z = inward;
            } else {
                let w = unit(sub(inward, scale(z, dot(inward, z))));
                if k == 1 && first.plane && y.is_none() {
                    y = Some(w);
                } else if x.is_none() {
                    x = Some(match y {
                        None => w,
                        Some(y) => unit(sub(w, scale(y, dot(w, y)))),
                    });
                }
            }
            c.add(s.vector, s.point);
        } else {
            if let (Some(a), None, None) = (axis_seen, x, y) {
                let w = sub(s.point, a.point);
                let w = sub(w, scale(z, dot(w, z)));
                if norm(w) > 1e-9 {
                    x = Some(unit(w));
                }
            } else if x.is_none() && y.is_none() && dot(s.vector, z).abs() < 0.999 {
                x = Some(unit(sub(s.vector, scale(z, dot(s.vector, z)))));
            }
            for n in axis_rows(s.vector) {
                c.add(n, s.point);
            }
            axis_seen = axis_seen.or(Some(*s));
        }
    }
    let free_rotation = x.is_none() && y.is_none();
    if free_rotation {
        for cand in box_axes {
            let w = sub(cand, scale(z, dot(cand, z)));
            if norm(w) > 1e-6 {
                x = Some(unit(w));
                break;
            }
        }
    }
    let x = match x {
        Some(x) => x,
        None => cross(y.unwrap(), z),
    };
    let y = y.unwrap_or_else(|| cross(z, x));
    let origin = c.origin(first.point)?;
    Frame::checked(origin, [x, y, z], c.free(), free_rotation)
}
