//! Serial chains of homogeneous transforms and their first-order error model (Sec. 3.1).
//!
//! A chain lists elements from the table (the reference frame) to the spindle; the target
//! `tool` is a point in the spindle frame. With nominal element transforms A_k the target
//! in the table frame is p = A_1 A_2 ... A_m r_t (Eq. 3.1). Each element carries small error
//! parameters; the exact perturbed chain R (Eq. 3.7) is used for simulation and the analytic
//! first derivative dR/dp r_t at p = 0 gives the design matrix M (Eq. 3.8, 3.9, 3.13).
//!
//! Conventions (mm, rad): small rotations alpha, beta, gamma are about z, y, x; the exact
//! rotation for angles (alpha, beta, gamma) is Rz(alpha) Ry(beta) Rx(gamma), whose first
//! order is I + [(gamma, beta, alpha)]x.
//!
//! Parameters per element, in this order:
//! - shape (Eq. 3.2): `alpha, beta, gamma, dx, dy, dz`; exact form
//!   [Rz Ry Rx(alpha, beta, gamma), offset + (dx, dy, dz)].
//! - prismatic joint with unit axis u and command s (Eq. 3.3 for any axis):
//!   `dalpha, dbeta, dgamma, delta`; with eps' = (dgamma, dbeta, dalpha) the exact form is
//!   [Rz Ry Rx(s dalpha, s dbeta, s dgamma), s (1 + delta) u + (s^2 / 2) eps' x u].
//! - rotary joint with unit axis a and command theta (Eq. 3.5, 3.6), for n = 1..N:
//!   `alpha.n, beta.n, gamma.n, dx.n, dy.n, dz.n`, each scaled by w_n = sin(n theta / 2).
//!   With eps = sum_n w_n (gamma.n, beta.n, alpha.n) and d = sum_n w_n (dx.n, dy.n, dz.n), the
//!   component of eps along a adds to the joint angle, the rest tilts the joint in its fixed
//!   frame, and d translates it there: [Exp(eps - (a.eps) a) R_a(theta + a.eps), d]. To first
//!   order this is [(I + [eps]x) R_a(theta), d]; for a = y it is Eq. 3.5 with the tilt read in
//!   the fixed frame (as printed, Eq. 3.5 adds [eps]x to R(B) unrotated, which is not a rigid
//!   motion unless B = 0).

use gagekit_core::{check_coordinates, check_finite, interrupt, GkError, Result};

/// Commands per parallel task of the per-point kernels; each task first checks for an
/// interrupt (Ctrl-C answered within milliseconds, at the cost of one atomic load per task).
const ROWS: usize = 256;
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};
use rayon::prelude::*;

mod inverse;

type V3 = Vector3<f64>;
type M3 = Matrix3<f64>;

/// One element of a serial chain.
#[derive(Clone, Debug, PartialEq)]
pub enum Element {
    /// A structural member with nominal offset (Eq. 3.2).
    Shape { offset: [f64; 3] },
    /// A prismatic joint moving along the unit `axis` (Eq. 3.3).
    Prismatic { axis: [f64; 3] },
    /// A rotary joint about the unit `axis`, errors as `terms` Fourier sine terms (Eq. 3.5, 3.6).
    Rotary { axis: [f64; 3], terms: usize },
}

/// The label of one error parameter: its element, its name within the element, and the
/// power of length by which its effect on the volumetric error scales (0 for translations,
/// 1 for rotations and scale errors, 2 for angular rates of prismatic joints).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParamLabel {
    pub element: usize,
    pub name: String,
    pub length_power: u8,
}

const SHAPE_NAMES: [&str; 6] = ["alpha", "beta", "gamma", "dx", "dy", "dz"];
const PRISMATIC_NAMES: [&str; 4] = ["dalpha", "dbeta", "dgamma", "delta"];
/// Fixed-frame axis index (x = 0, y = 1, z = 2) of the rotations alpha, beta, gamma.
const ROT_AXIS: [usize; 3] = [2, 1, 0];
/// The most Fourier terms a rotary joint's error series may have (Eq. 3.6).
pub const MAX_TERMS: usize = 64;

impl Element {
    pub fn n_params(&self) -> usize {
        match self {
            Element::Shape { .. } => 6,
            Element::Prismatic { .. } => 4,
            Element::Rotary { terms, .. } => 6 * terms,
        }
    }

    pub fn is_joint(&self) -> bool {
        !matches!(self, Element::Shape { .. })
    }

    fn labels(&self, element: usize) -> Vec<ParamLabel> {
        let lab = |name: String, p: u8| ParamLabel { element, name, length_power: p };
        match self {
            Element::Shape { .. } => {
                SHAPE_NAMES.iter().enumerate().map(|(i, n)| lab(n.to_string(), if i < 3 { 1 } else { 0 })).collect()
            }
            Element::Prismatic { .. } => {
                PRISMATIC_NAMES.iter().enumerate().map(|(i, n)| lab(n.to_string(), if i < 3 { 2 } else { 1 })).collect()
            }
            Element::Rotary { terms, .. } => (1..=*terms)
                .flat_map(|n| {
                    SHAPE_NAMES
                        .iter()
                        .enumerate()
                        .map(move |(i, s)| lab(format!("{s}.{n}"), if i < 3 { 1 } else { 0 }))
                })
                .collect(),
        }
    }
}

/// A rigid transform x -> r x + t.
#[derive(Clone, Copy, Debug)]
struct Rigid {
    r: M3,
    t: V3,
}

impl Rigid {
    fn identity() -> Self {
        Rigid { r: M3::identity(), t: V3::zeros() }
    }
    fn then(&self, other: &Rigid) -> Rigid {
        Rigid { r: self.r * other.r, t: self.r * other.t + self.t }
    }
    fn apply(&self, p: &V3) -> V3 {
        self.r * p + self.t
    }
}

fn axis_rot(axis: usize, angle: f64) -> M3 {
    let a = match axis {
        0 => V3::x_axis(),
        1 => V3::y_axis(),
        _ => V3::z_axis(),
    };
    *Rotation3::from_axis_angle(&a, angle).matrix()
}

/// Rz(alpha) Ry(beta) Rx(gamma).
pub fn rot_zyx(alpha: f64, beta: f64, gamma: f64) -> M3 {
    axis_rot(2, alpha) * axis_rot(1, beta) * axis_rot(0, gamma)
}

fn rot_vec(v: &V3) -> M3 {
    let angle = v.norm();
    if angle == 0.0 {
        M3::identity()
    } else {
        *Rotation3::from_axis_angle(&Unit::new_normalize(*v), angle).matrix()
    }
}

fn rot_about(axis: &V3, angle: f64) -> M3 {
    *Rotation3::from_axis_angle(&Unit::new_unchecked(*axis), angle).matrix()
}

fn v3(a: &[f64; 3]) -> V3 {
    V3::new(a[0], a[1], a[2])
}

/// A validated serial chain with its target point.
#[derive(Clone, Debug)]
pub struct Machine {
    elements: Vec<Element>,
    tool: V3,
    /// Unit axis of each joint element (zero for shapes).
    axes: Vec<V3>,
    /// Index of the command of each joint element (usize::MAX for shapes).
    joint_index: Vec<usize>,
    /// First parameter of each element.
    param_offset: Vec<usize>,
    n_joints: usize,
    n_params: usize,
}

impl Machine {
    /// Validate and build a chain. Joint axes must be non-zero (they are normalised);
    /// rotary joints need 1..=64 Fourier terms; the chain needs at least one joint.
    pub fn new(elements: Vec<Element>, tool: [f64; 3]) -> Result<Self> {
        if elements.is_empty() {
            return Err(GkError::config("the chain is empty"));
        }
        check_coordinates(&tool, 3, "tool offset")?;
        let mut axes = Vec::with_capacity(elements.len());
        let mut joint_index = Vec::with_capacity(elements.len());
        let mut param_offset = Vec::with_capacity(elements.len());
        let (mut nj, mut np) = (0usize, 0usize);
        for (k, e) in elements.iter().enumerate() {
            param_offset.push(np);
            np += e.n_params();
            match e {
                Element::Shape { offset } => {
                    check_coordinates(offset, 3, &format!("chain element {k}: offset"))?;
                    axes.push(V3::zeros());
                    joint_index.push(usize::MAX);
                }
                Element::Prismatic { axis } | Element::Rotary { axis, .. } => {
                    check_finite(axis, 3, &format!("chain element {k}: axis"))?;
                    let a = v3(axis);
                    if a.norm() < 1e-12 {
                        return Err(GkError::config(format!("chain element {k}: the joint axis is the zero vector")));
                    }
                    if let Element::Rotary { terms, .. } = e {
                        if *terms == 0 || *terms > MAX_TERMS {
                            return Err(GkError::config(format!(
                                "chain element {k}: a rotary joint needs 1 to {MAX_TERMS} Fourier terms, got {terms}"
                            )));
                        }
                    }
                    axes.push(a.normalize());
                    joint_index.push(nj);
                    nj += 1;
                }
            }
        }
        if nj == 0 {
            return Err(GkError::config("the chain has no joint: nothing moves"));
        }
        Ok(Machine { elements, tool: v3(&tool), axes, joint_index, param_offset, n_joints: nj, n_params: np })
    }

    pub fn n_joints(&self) -> usize {
        self.n_joints
    }
    pub fn n_params(&self) -> usize {
        self.n_params
    }
    pub fn elements(&self) -> &[Element] {
        &self.elements
    }

    /// Labels of all parameters, in the order of the design-matrix columns.
    pub fn param_labels(&self) -> Vec<ParamLabel> {
        self.elements.iter().enumerate().flat_map(|(k, e)| e.labels(k)).collect()
    }

    fn check_commands(&self, commands: &[f64]) -> Result<usize> {
        let nj = self.n_joints;
        if commands.len() % nj != 0 {
            return Err(GkError::invalid(format!(
                "commands: expected {nj} values per row, got a buffer of {} values",
                commands.len()
            )));
        }
        check_coordinates(commands, nj, "commands")?;
        Ok(commands.len() / nj)
    }

    /// Nominal transform of element k for the commands of one point.
    fn nominal(&self, k: usize, cmd: &[f64]) -> Rigid {
        match &self.elements[k] {
            Element::Shape { offset } => Rigid { r: M3::identity(), t: v3(offset) },
            Element::Prismatic { .. } => Rigid { r: M3::identity(), t: self.axes[k] * cmd[self.joint_index[k]] },
            Element::Rotary { .. } => Rigid { r: rot_about(&self.axes[k], cmd[self.joint_index[k]]), t: V3::zeros() },
        }
    }

    /// Exact perturbed transform of element k (module docs) for parameters `q` of that element.
    fn exact(&self, k: usize, cmd: &[f64], q: &[f64]) -> Rigid {
        match &self.elements[k] {
            Element::Shape { offset } => {
                Rigid { r: rot_zyx(q[0], q[1], q[2]), t: v3(offset) + V3::new(q[3], q[4], q[5]) }
            }
            Element::Prismatic { .. } => {
                let s = cmd[self.joint_index[k]];
                let u = self.axes[k];
                let eps = V3::new(q[2], q[1], q[0]);
                Rigid { r: rot_zyx(s * q[0], s * q[1], s * q[2]), t: u * (s * (1.0 + q[3])) + eps.cross(&u) * (0.5 * s * s) }
            }
            Element::Rotary { terms, .. } => {
                let th = cmd[self.joint_index[k]];
                let a = self.axes[k];
                let (mut eps, mut d) = (V3::zeros(), V3::zeros());
                for n in 0..*terms {
                    let w = ((n + 1) as f64 * th / 2.0).sin();
                    let c = &q[6 * n..6 * n + 6];
                    eps += V3::new(c[2], c[1], c[0]) * w;
                    d += V3::new(c[3], c[4], c[5]) * w;
                }
                let own = a.dot(&eps);
                Rigid { r: rot_vec(&(eps - a * own)) * rot_about(&a, th + own), t: d }
            }
        }
    }

    /// Nominal target positions in the table frame, (n, 3) row-major (Eq. 3.1).
    pub fn nominal_positions(&self, commands: &[f64]) -> Result<Vec<f64>> {
        let n = self.check_commands(commands)?;
        let mut out = vec![0.0; 3 * n];
        out.par_chunks_mut(3 * ROWS).zip(commands.par_chunks(self.n_joints * ROWS)).try_for_each(|(o, cmds)| {
            interrupt::check()?;
            for (o, cmd) in o.chunks_mut(3).zip(cmds.chunks(self.n_joints)) {
                let mut h = Rigid::identity();
                for k in 0..self.elements.len() {
                    h = h.then(&self.nominal(k, cmd));
                }
                o.copy_from_slice(h.apply(&self.tool).as_slice());
            }
            Ok(())
        })?;
        Ok(out)
    }

    /// Target positions of the exactly perturbed chain (Eq. 3.7), (n, 3) row-major.
    pub fn exact_positions(&self, commands: &[f64], params: &[f64]) -> Result<Vec<f64>> {
        let n = self.check_commands(commands)?;
        if params.len() != self.n_params {
            return Err(GkError::invalid(format!(
                "parameters: expected {} values, got {}",
                self.n_params,
                params.len()
            )));
        }
        check_finite(params, 1, "parameters")?;
        let mut out = vec![0.0; 3 * n];
        out.par_chunks_mut(3 * ROWS).zip(commands.par_chunks(self.n_joints * ROWS)).try_for_each(|(o, cmds)| {
            interrupt::check()?;
            for (o, cmd) in o.chunks_mut(3).zip(cmds.chunks(self.n_joints)) {
                let mut h = Rigid::identity();
                for (k, e) in self.elements.iter().enumerate() {
                    let off = self.param_offset[k];
                    h = h.then(&self.exact(k, cmd, &params[off..off + e.n_params()]));
                }
                o.copy_from_slice(h.apply(&self.tool).as_slice());
            }
            Ok(())
        })?;
        Ok(out)
    }

    /// Prefix rotations R_k = R(A_1 ... A_{k-1}) and the lever vectors R_k R(A_k) v_k, where
    /// v_k = A_{k+1} ... A_m r_t, for the commands of one point; all in the table frame.
    fn frames(&self, cmd: &[f64], prefix: &mut Vec<M3>, lever: &mut Vec<V3>, nominal: &mut Vec<Rigid>) {
        let m = self.elements.len();
        nominal.clear();
        nominal.extend((0..m).map(|k| self.nominal(k, cmd)));
        prefix.clear();
        let mut r = M3::identity();
        for a in nominal.iter() {
            prefix.push(r);
            r *= a.r;
        }
        lever.clear();
        lever.resize(m, V3::zeros());
        let mut v = self.tool;
        for k in (0..m).rev() {
            let q = nominal[k].r * v;
            lever[k] = prefix[k] * q;
            v = q + nominal[k].t;
        }
    }

    /// One point's 3 x P block of the design matrix, row-major into `out` (length 3 P).
    fn design_block(&self, cmd: &[f64], out: &mut [f64], scratch: &mut (Vec<M3>, Vec<V3>, Vec<Rigid>)) {
        let p = self.n_params;
        let (prefix, lever, nominal) = scratch;
        self.frames(cmd, prefix, lever, nominal);
        let mut put = |col: usize, v: V3| {
            out[col] = v[0];
            out[p + col] = v[1];
            out[2 * p + col] = v[2];
        };
        for (k, e) in self.elements.iter().enumerate() {
            let off = self.param_offset[k];
            let rk = &prefix[k];
            let axis_col = |j: usize| -> V3 { rk.column(j).into_owned() };
            match e {
                Element::Shape { .. } => {
                    for (i, &ax) in ROT_AXIS.iter().enumerate() {
                        put(off + i, axis_col(ax).cross(&lever[k]));
                    }
                    for j in 0..3 {
                        put(off + 3 + j, axis_col(j));
                    }
                }
                Element::Prismatic { .. } => {
                    let s = cmd[self.joint_index[k]];
                    let u = rk * self.axes[k];
                    // rotation s*eps' about the lever, and the straightness (s^2/2) eps' x u
                    let arm = lever[k] * s + u * (0.5 * s * s);
                    for (i, &ax) in ROT_AXIS.iter().enumerate() {
                        put(off + i, axis_col(ax).cross(&arm));
                    }
                    put(off + 3, u * s);
                }
                Element::Rotary { terms, .. } => {
                    let th = cmd[self.joint_index[k]];
                    for n in 0..*terms {
                        let w = ((n + 1) as f64 * th / 2.0).sin();
                        let o = off + 6 * n;
                        for (i, &ax) in ROT_AXIS.iter().enumerate() {
                            put(o + i, axis_col(ax).cross(&lever[k]) * w);
                        }
                        for j in 0..3 {
                            put(o + 3 + j, axis_col(j) * w);
                        }
                    }
                }
            }
        }
    }

    /// The design matrix M (Eq. 3.13): 3 rows per command (x, y, z of the volumetric error in
    /// the table frame), one column per parameter, row-major (3n, P); assembled in parallel.
    pub fn design_matrix(&self, commands: &[f64]) -> Result<Vec<f64>> {
        let n = self.check_commands(commands)?;
        let p = self.n_params;
        let mut out = vec![0.0; 3 * n * p];
        out.par_chunks_mut(3 * p * 64).zip(commands.par_chunks(self.n_joints * 64)).try_for_each(|(o, cmds)| {
            interrupt::check()?;
            let mut scratch = (Vec::new(), Vec::new(), Vec::new());
            for (blk, cmd) in o.chunks_mut(3 * p).zip(cmds.chunks(self.n_joints)) {
                self.design_block(cmd, blk, &mut scratch);
            }
            Ok(())
        })?;
        Ok(out)
    }

    /// Jacobian of the nominal target position with respect to the commands: (3n, J)
    /// row-major, rotary commands in radians.
    pub fn command_jacobian(&self, commands: &[f64]) -> Result<Vec<f64>> {
        let n = self.check_commands(commands)?;
        let nj = self.n_joints;
        let mut out = vec![0.0; 3 * n * nj];
        out.par_chunks_mut(3 * nj * ROWS).zip(commands.par_chunks(nj * ROWS)).try_for_each(|(o, cmds)| {
            interrupt::check()?;
            let (mut prefix, mut lever, mut nominal) = (Vec::new(), Vec::new(), Vec::new());
            for (o, cmd) in o.chunks_mut(3 * nj).zip(cmds.chunks(nj)) {
                self.frames(cmd, &mut prefix, &mut lever, &mut nominal);
                for (k, e) in self.elements.iter().enumerate() {
                    let col = match e {
                        Element::Shape { .. } => continue,
                        Element::Prismatic { .. } => prefix[k] * self.axes[k],
                        Element::Rotary { .. } => (prefix[k] * self.axes[k]).cross(&lever[k]),
                    };
                    let j = self.joint_index[k];
                    for r in 0..3 {
                        o[r * nj + j] = col[r];
                    }
                }
            }
            Ok(())
        })?;
        Ok(out)
    }
}

/// The example machine of the dissertation (B X Z Y W with shapes between, Eq. 3.1; 52
/// parameters), for tests and benchmarks.
#[allow(clippy::unwrap_used, reason = "a fixed chain of valid elements: Machine::new cannot fail on it (tested)")]
pub fn example_machine() -> Machine {
    let s = |z: f64| Element::Shape { offset: [0.0, 0.0, z] };
    let pj = |a: [f64; 3]| Element::Prismatic { axis: a };
    Machine::new(
        vec![
            Element::Rotary { axis: [0.0, 1.0, 0.0], terms: 1 },
            s(0.0),
            pj([1.0, 0.0, 0.0]),
            s(0.0),
            pj([0.0, 0.0, 1.0]),
            s(0.0),
            pj([0.0, 1.0, 0.0]),
            s(-450.0),
            pj([0.0, 0.0, 1.0]),
            s(0.0),
        ],
        [0.0, 0.0, -312.035],
    )
    .unwrap()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub use super::example_machine as example;

    /// A skewed chain: tilted axes, two rotary joints with several terms, offsets everywhere.
    fn skewed() -> Machine {
        Machine::new(
            vec![
                Element::Shape { offset: [10.0, -20.0, 30.0] },
                Element::Rotary { axis: [0.0, 0.6, 0.8], terms: 3 },
                Element::Shape { offset: [100.0, 50.0, -40.0] },
                Element::Prismatic { axis: [1.0, 1.0, 0.0] },
                Element::Shape { offset: [0.0, 200.0, 10.0] },
                Element::Rotary { axis: [1.0, 0.0, 0.0], terms: 2 },
                Element::Prismatic { axis: [0.0, 0.0, 1.0] },
                Element::Shape { offset: [5.0, 5.0, 5.0] },
            ],
            [12.0, -7.0, 150.0],
        )
        .unwrap()
    }

    fn commands(m: &Machine, n: usize) -> Vec<f64> {
        // deterministic spread: rotary joints over 0..2 pi, prismatic over +-1000 mm
        let rotary: Vec<bool> =
            m.elements().iter().filter(|e| e.is_joint()).map(|e| matches!(e, Element::Rotary { .. })).collect();
        let mut out = Vec::new();
        for i in 0..n {
            for (j, &rot) in rotary.iter().enumerate() {
                let t = (((i * 7919 + j * 104729) % 1000) as f64) / 1000.0;
                out.push(if rot { t * std::f64::consts::TAU } else { t * 2000.0 - 1000.0 });
            }
        }
        out
    }

    fn check_fd(m: &Machine, cmds: &[f64]) {
        let dm = m.design_matrix(cmds).unwrap();
        let p = m.n_params();
        let n = cmds.len() / m.n_joints();
        let labels = m.param_labels();
        for j in 0..p {
            let h = match labels[j].length_power {
                0 => 1e-1,
                1 => 1e-5,
                _ => 1e-7,
            };
            let mut pp = vec![0.0; p];
            pp[j] = h;
            let plus = m.exact_positions(cmds, &pp).unwrap();
            pp[j] = -h;
            let minus = m.exact_positions(cmds, &pp).unwrap();
            for i in 0..n {
                for r in 0..3 {
                    let fd = (plus[3 * i + r] - minus[3 * i + r]) / (2.0 * h);
                    let an = dm[(3 * i + r) * p + j];
                    let scale = 1.0 + an.abs().max(fd.abs());
                    assert!(
                        (fd - an).abs() <= 1e-6 * scale,
                        "param {} ({}), point {i}, row {r}: analytic {an}, central difference {fd}",
                        j,
                        labels[j].name
                    );
                }
            }
        }
    }

    #[test]
    fn example_has_52_parameters() {
        let m = example();
        assert_eq!(m.n_params(), 52);
        assert_eq!(m.n_joints(), 5);
        let l = m.param_labels();
        assert_eq!(l[0].name, "alpha.1");
        assert_eq!(l[6].name, "alpha");
        assert_eq!(l[12].name, "dalpha");
    }

    #[test]
    fn design_matrix_matches_central_differences() {
        let m = example();
        let cmds = commands(&m, 12);
        check_fd(&m, &cmds);
        let m = skewed();
        let cmds = commands(&m, 12);
        check_fd(&m, &cmds);
    }

    #[test]
    fn nominal_equals_exact_at_zero_and_known_point() {
        let m = example();
        let cmd = [std::f64::consts::FRAC_PI_2, 100.0, 1000.0, 500.0, -300.0];
        let nom = m.nominal_positions(&cmd).unwrap();
        let ex = m.exact_positions(&cmd, &[0.0; 52]).unwrap();
        for r in 0..3 {
            assert!((nom[r] - ex[r]).abs() < 1e-12);
        }
        // spindle-frame point: (x, y, z + w - 450 - 312.035) rotated by Ry(90 deg)
        let local = V3::new(100.0, 500.0, 1000.0 - 300.0 - 450.0 - 312.035);
        let want = rot_about(&V3::y(), std::f64::consts::FRAC_PI_2) * local;
        for r in 0..3 {
            assert!((nom[r] - want[r]).abs() < 1e-9, "{nom:?} vs {want:?}");
        }
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let m = skewed();
        let cmds = commands(&m, 5);
        let jac = m.command_jacobian(&cmds).unwrap();
        let nj = m.n_joints();
        for i in 0..5 {
            for j in 0..nj {
                let mut c = cmds[i * nj..(i + 1) * nj].to_vec();
                let h = 1e-5;
                c[j] += h;
                let plus = m.nominal_positions(&c).unwrap();
                c[j] -= 2.0 * h;
                let minus = m.nominal_positions(&c).unwrap();
                for r in 0..3 {
                    let fd = (plus[r] - minus[r]) / (2.0 * h);
                    assert!((fd - jac[(3 * i + r) * nj + j]).abs() < 1e-5 * (1.0 + fd.abs()));
                }
            }
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(Machine::new(vec![], [0.0; 3]).is_err());
        assert!(Machine::new(vec![Element::Shape { offset: [0.0; 3] }], [0.0; 3]).is_err());
        assert!(Machine::new(vec![Element::Prismatic { axis: [0.0; 3] }], [0.0; 3]).is_err());
        assert!(Machine::new(vec![Element::Rotary { axis: [0.0, 1.0, 0.0], terms: 0 }], [0.0; 3]).is_err());
        let m = example();
        assert!(m.design_matrix(&[0.0; 7]).is_err());
        assert!(m.design_matrix(&[0.0, 1.0, f64::NAN, 0.0, 0.0]).is_err());
        assert!(m.exact_positions(&[0.0; 5], &[0.0; 3]).is_err());
        assert_eq!(m.design_matrix(&[]).unwrap().len(), 0);
    }
}
