//! Rigid motions x -> R x + t, and the six parameters of a motion step.
//!
//! Parameters, in the order of `--lock`: translations x, y, z (mm), then rotations about
//! x, y, z (rad) with R = Rz(rz) Ry(ry) Rx(rx) (the dissertation's Eq. 3.2 / 5.2 order:
//! alpha about z, beta about y, gamma about x). A locked parameter stays 0, so the locked
//! degree of freedom is exactly kept in the model's axes.

use gagekit_core::{GkError, Result};
use gagekit_gdt::vec3::{add, V3};

pub type M3 = [[f64; 3]; 3];

pub const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

pub fn mul(a: &M3, b: &M3) -> M3 {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    m
}

#[inline]
pub fn apply(m: &M3, v: V3) -> V3 {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

fn rx(a: f64) -> (M3, M3) {
    let (s, c) = a.sin_cos();
    ([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]], [[0.0, 0.0, 0.0], [0.0, -s, -c], [0.0, c, -s]])
}
fn ry(a: f64) -> (M3, M3) {
    let (s, c) = a.sin_cos();
    ([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]], [[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]])
}
fn rz(a: f64) -> (M3, M3) {
    let (s, c) = a.sin_cos();
    ([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], [[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])
}

/// R(p) = Rz Ry Rx and its derivatives with respect to p[3], p[4], p[5].
pub fn rotation_and_derivatives(p: &[f64; 6]) -> (M3, [M3; 3]) {
    let (x, dx) = rx(p[3]);
    let (y, dy) = ry(p[4]);
    let (z, dz) = rz(p[5]);
    let zy = mul(&z, &y);
    let r = mul(&zy, &x);
    (r, [mul(&zy, &dx), mul(&mul(&z, &dy), &x), mul(&mul(&dz, &y), &x)])
}

/// A rigid motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub r: M3,
    pub t: V3,
}

impl Pose {
    pub const IDENTITY: Pose = Pose { r: IDENTITY, t: [0.0; 3] };

    #[inline]
    pub fn apply(&self, v: V3) -> V3 {
        add(apply(&self.r, v), self.t)
    }

    /// The motion of parameters `p`.
    pub fn from_params(p: &[f64; 6]) -> Self {
        Pose { r: rotation_and_derivatives(p).0, t: [p[0], p[1], p[2]] }
    }

    /// `self` after `first`: x -> self(first(x)).
    pub fn after(&self, first: &Pose) -> Pose {
        Pose { r: mul(&self.r, &first.r), t: self.apply(first.t) }
    }

    /// Row-major 4x4 homogeneous matrix.
    pub fn matrix(&self) -> [f64; 16] {
        let r = &self.r;
        [
            r[0][0], r[0][1], r[0][2], self.t[0], r[1][0], r[1][1], r[1][2], self.t[1], r[2][0], r[2][1], r[2][2], self.t[2], 0.0,
            0.0, 0.0, 1.0,
        ]
    }

    /// From a row-major 4x4 matrix whose upper 3x3 is a rotation (to 1e-6).
    pub fn from_matrix(m: &[f64]) -> Result<Pose> {
        if m.len() != 16 || m.iter().any(|v| !v.is_finite()) {
            return Err(GkError::invalid("pose: expected a finite 4x4 matrix"));
        }
        let r = [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]];
        let mut rtr = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                rtr[i][j] = (0..3).map(|k| r[k][i] * r[k][j]).sum::<f64>();
            }
        }
        let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
            + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
        let off = (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).map(|(i, j)| (rtr[i][j] - if i == j { 1.0 } else { 0.0 }).abs()).fold(0.0, f64::max);
        if off > 1e-6 || (det - 1.0).abs() > 1e-6 || m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0 {
            return Err(GkError::invalid("pose: the matrix is not a rigid motion (rotation and translation)"));
        }
        Ok(Pose { r, t: [m[3], m[7], m[11]] })
    }
}
