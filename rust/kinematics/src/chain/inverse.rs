//! The first-order error of a point without forming the design matrix, and its inverse:
//! commands corrected so that the predicted actual target is the nominal one.
//!
//! `first_order_errors` is M(c) p (Eq. 3.9, 3.13) summed element by element with the same
//! levers as the design matrix; `compensate` iterates c <- c - pinv(J_S) (P(c) + M(c) p - P(c0))
//! over the compensating joints S (Gauss-Newton with the command Jacobian J of the nominal
//! chain, minimum-norm steps when S is redundant), as `gagekit.machine.compensate` specifies.

use super::{Element, Machine, Rigid, M3, V3};
use gagekit_core::{check_finite, interrupt, GkError, Result};
use nalgebra::DMatrix;
use rayon::prelude::*;

/// Nominal target and first-order error of one point (Jacobian columns in the scratch).
struct PointState {
    position: V3,
    error: V3,
}

/// Reused buffers: prefix rotations, levers, nominal transforms, Jacobian columns (all joints).
type Scratch = (Vec<M3>, Vec<V3>, Vec<Rigid>, Vec<V3>);

impl Machine {
    fn check_params(&self, params: &[f64]) -> Result<()> {
        if params.len() != self.n_params {
            return Err(GkError::invalid(format!("parameters: expected {} values, got {}", self.n_params, params.len())));
        }
        check_finite(params, 1, "parameters")
    }

    fn point_state(&self, cmd: &[f64], params: &[f64], s: &mut Scratch) -> PointState {
        let (prefix, lever, nominal, cols) = s;
        self.frames(cmd, prefix, lever, nominal);
        cols.clear();
        cols.resize(self.n_joints, V3::zeros());
        let mut position = self.tool;
        for a in nominal.iter().rev() {
            position = a.apply(&position);
        }
        let mut e = V3::zeros();
        for (k, el) in self.elements.iter().enumerate() {
            let q = &params[self.param_offset[k]..self.param_offset[k] + el.n_params()];
            let rk = &prefix[k];
            match el {
                Element::Shape { .. } => {
                    e += (rk * V3::new(q[2], q[1], q[0])).cross(&lever[k]) + rk * V3::new(q[3], q[4], q[5]);
                }
                Element::Prismatic { .. } => {
                    let sj = cmd[self.joint_index[k]];
                    let u = rk * self.axes[k];
                    let arm = lever[k] * sj + u * (0.5 * sj * sj);
                    e += (rk * V3::new(q[2], q[1], q[0])).cross(&arm) + u * (sj * q[3]);
                    cols[self.joint_index[k]] = u;
                }
                Element::Rotary { terms, .. } => {
                    let th = cmd[self.joint_index[k]];
                    for n in 0..*terms {
                        let w = ((n + 1) as f64 * th / 2.0).sin();
                        let c = &q[6 * n..6 * n + 6];
                        e += ((rk * V3::new(c[2], c[1], c[0])).cross(&lever[k]) + rk * V3::new(c[3], c[4], c[5])) * w;
                    }
                    cols[self.joint_index[k]] = (rk * self.axes[k]).cross(&lever[k]);
                }
            }
        }
        PointState { position, error: e }
    }

    /// First-order volumetric errors M(c) p, (n, 3) row-major (Eq. 3.9, 3.13), rotary in rad.
    pub fn first_order_errors(&self, commands: &[f64], params: &[f64]) -> Result<Vec<f64>> {
        let n = self.check_commands(commands)?;
        self.check_params(params)?;
        let mut out = vec![0.0; 3 * n];
        out.par_chunks_mut(3 * 256).zip(commands.par_chunks(self.n_joints * 256)).try_for_each(|(o, cmds)| {
            interrupt::check()?;
            let mut s: Scratch = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for (oi, cmd) in o.chunks_mut(3).zip(cmds.chunks(self.n_joints)) {
                oi.copy_from_slice(self.point_state(cmd, params, &mut s).error.as_slice());
            }
            Ok(())
        })?;
        Ok(out)
    }

    /// Corrected commands (n, J) and the predicted error left (n, 3): `iterations` Gauss-Newton
    /// steps moving only `joints` (indices into the commands) so that P(c) + M(c) p = P(c0).
    pub fn compensate(&self, commands: &[f64], params: &[f64], joints: &[usize], iterations: usize) -> Result<(Vec<f64>, Vec<f64>)> {
        let n = self.check_commands(commands)?;
        self.check_params(params)?;
        if joints.is_empty() {
            return Err(GkError::invalid("compensation joints: none given"));
        }
        if let Some(&j) = joints.iter().find(|&&j| j >= self.n_joints) {
            return Err(GkError::invalid(format!("compensation joint index {j} out of range (machine has {})", self.n_joints)));
        }
        let nj = self.n_joints;
        let mut out = commands.to_vec();
        let mut left = vec![0.0; 3 * n];
        out.par_chunks_mut(nj * 256).zip(left.par_chunks_mut(3 * 256)).try_for_each(|(cs, ls)| {
            interrupt::check()?;
            let mut s: Scratch = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            let mut jac: Vec<V3> = Vec::with_capacity(joints.len());
            let mut step: Vec<f64> = Vec::with_capacity(joints.len());
            for (c, l) in cs.chunks_mut(nj).zip(ls.chunks_mut(3)) {
                let mut st = self.point_state(c, params, &mut s);
                let target = st.position;
                for _ in 0..iterations {
                    let miss = st.position + st.error - target;
                    if miss.amax() < 1e-12 {
                        break;
                    }
                    jac.clear();
                    jac.extend(joints.iter().map(|&j| s.3[j]));
                    min_norm_solve(&jac, &miss, &mut step);
                    for (&j, d) in joints.iter().zip(&step) {
                        c[j] -= d;
                    }
                    st = self.point_state(c, params, &mut s);
                }
                l.copy_from_slice((st.position + st.error - target).as_slice());
            }
            Ok(())
        })?;
        Ok((out, left))
    }
}

/// pinv(J) b for J = [cols] (3 x k): closed forms for full rank, SVD otherwise.
fn min_norm_solve(cols: &[V3], b: &V3, out: &mut Vec<f64>) {
    out.clear();
    let k = cols.len();
    let scale = cols.iter().map(|c| c.norm_squared()).fold(0.0, f64::max);
    if k >= 3 {
        let mut a = M3::zeros();
        for c in cols {
            a += c * c.transpose();
        }
        if a.determinant().abs() > 1e-10 * scale.powi(3) {
            if let Some(inv) = a.try_inverse() {
                let y = inv * b;
                out.extend(cols.iter().map(|c| c.dot(&y)));
                return;
            }
        }
    } else if k == 1 && scale > 0.0 {
        out.push(cols[0].dot(b) / scale);
        return;
    } else if k == 2 {
        let (a, bb, d) = (cols[0].norm_squared(), cols[0].dot(&cols[1]), cols[1].norm_squared());
        let det = a * d - bb * bb;
        if det.abs() > 1e-10 * scale * scale {
            let (r0, r1) = (cols[0].dot(b), cols[1].dot(b));
            out.extend([(d * r0 - bb * r1) / det, (a * r1 - bb * r0) / det]);
            return;
        }
    }
    let j = DMatrix::from_fn(3, k, |r, c| cols[c][r]);
    let svd = j.svd(true, true);
    let smax = svd.singular_values.max();
    match svd.pseudo_inverse(1e-15 * smax.max(f64::MIN_POSITIVE)) {
        Ok(p) => out.extend((p * nalgebra::DVector::from_column_slice(b.as_slice())).iter().copied()),
        Err(_) => out.resize(k, 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::example;

    fn cmds(n: usize) -> Vec<f64> {
        (0..n)
            .flat_map(|i| {
                let t = i as f64 / n as f64;
                [t * 6.0, -1000.0 + 2000.0 * t, 1000.0 + 900.0 * t, 400.0 + 2000.0 * (1.0 - t), -700.0 + 400.0 * t]
            })
            .collect()
    }

    fn params(m: &crate::Machine) -> Vec<f64> {
        let mag = [1e-2, 1e-5, 1e-8];
        m.param_labels().iter().enumerate().map(|(i, l)| ((i * 37 % 11) as f64 - 5.0) * mag[l.length_power as usize]).collect()
    }

    #[test]
    fn first_order_errors_equal_design_matrix_times_p() {
        let m = example();
        let c = cmds(40);
        let p = params(&m);
        let dm = m.design_matrix(&c).unwrap();
        let e = m.first_order_errors(&c, &p).unwrap();
        for r in 0..e.len() {
            let want: f64 = (0..p.len()).map(|j| dm[r * p.len() + j] * p[j]).sum();
            assert!((want - e[r]).abs() < 1e-12 * (1.0 + want.abs()), "row {r}: {want} vs {}", e[r]);
        }
    }

    #[test]
    fn compensation_cancels_the_predicted_error() {
        let m = example();
        let c = cmds(40);
        let p = params(&m);
        for joints in [vec![1usize, 2, 3], vec![1, 2, 3, 4]] {
            let (out, left) = m.compensate(&c, &p, &joints, 4).unwrap();
            assert!(left.iter().all(|v| v.abs() < 1e-9), "{left:?}");
            // B is not a compensating joint: unchanged
            for i in 0..40 {
                assert_eq!(out[5 * i], c[5 * i]);
            }
        }
        assert!(m.compensate(&c, &p, &[], 4).is_err());
        assert!(m.compensate(&c, &p, &[9], 4).is_err());
    }
}
