//! The rigid-body transform of Eq. 5.2, applied exactly:
//! T = [Rz(alpha) Ry(beta) Rx(gamma) | (dx, dy, dz)].
//!
//! Parameter order everywhere: alpha (about z), beta (about y), gamma (about x),
//! dx, dy, dz (rad, mm).

pub type Mat3 = [[f64; 3]; 3];

/// Names of the six motions, in parameter order.
pub const MOTION_NAMES: [&str; 6] = ["alpha", "beta", "gamma", "dx", "dy", "dz"];

fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn rz(a: f64) -> (Mat3, Mat3) {
    let (s, c) = a.sin_cos();
    ([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], [[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])
}

fn ry(b: f64) -> (Mat3, Mat3) {
    let (s, c) = b.sin_cos();
    ([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]], [[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]])
}

fn rx(g: f64) -> (Mat3, Mat3) {
    let (s, c) = g.sin_cos();
    ([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]], [[0.0, 0.0, 0.0], [0.0, -s, -c], [0.0, c, -s]])
}

/// The exact rotation Rz(alpha) Ry(beta) Rx(gamma) and its three partial derivatives.
pub fn rotation_and_derivatives(p: &[f64; 6]) -> (Mat3, [Mat3; 3]) {
    let (z, dz) = rz(p[0]);
    let (y, dy) = ry(p[1]);
    let (x, dx) = rx(p[2]);
    let r = mul(&mul(&z, &y), &x);
    let da = mul(&mul(&dz, &y), &x);
    let db = mul(&mul(&z, &dy), &x);
    let dg = mul(&mul(&z, &y), &dx);
    (r, [da, db, dg])
}

/// The 4x4 homogeneous matrix of the parameters (applied to column vectors).
pub fn matrix(p: &[f64; 6]) -> [[f64; 4]; 4] {
    let (r, _) = rotation_and_derivatives(p);
    let mut m = [[0.0; 4]; 4];
    for i in 0..3 {
        m[i][..3].copy_from_slice(&r[i]);
        m[i][3] = p[3 + i];
    }
    m[3][3] = 1.0;
    m
}

/// R^T n: the plane normal pulled back through the rotation, so that
/// n . (R r) = (R^T n) . r.
pub fn pull_back(r: &Mat3, n: &[f64; 3]) -> [f64; 3] {
    [
        r[0][0] * n[0] + r[1][0] * n[1] + r[2][0] * n[2],
        r[0][1] * n[0] + r[1][1] * n[1] + r[2][1] * n[2],
        r[0][2] * n[0] + r[1][2] * n[1] + r[2][2] * n[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        let p = [0.03, -0.02, 0.015, 1.0, 2.0, 3.0];
        let (_, d) = rotation_and_derivatives(&p);
        let h = 1e-7;
        for k in 0..3 {
            let mut pp = p;
            let mut pm = p;
            pp[k] += h;
            pm[k] -= h;
            let (rp, _) = rotation_and_derivatives(&pp);
            let (rm, _) = rotation_and_derivatives(&pm);
            for i in 0..3 {
                for j in 0..3 {
                    let fd = (rp[i][j] - rm[i][j]) / (2.0 * h);
                    assert!((fd - d[k][i][j]).abs() < 1e-8);
                }
            }
        }
    }

    #[test]
    fn small_angles_give_eq_5_2() {
        let e = 1e-6;
        let m = matrix(&[e, 2.0 * e, 3.0 * e, 0.0, 0.0, 0.0]);
        // Eq. 5.2: [1 -a b; a 1 -g; -b g 1]
        assert!((m[0][1] + e).abs() < 1e-11 && (m[0][2] - 2.0 * e).abs() < 1e-11);
        assert!((m[1][2] + 3.0 * e).abs() < 1e-11 && (m[2][0] + 2.0 * e).abs() < 1e-11);
    }
}
