//! Circular and helical moves (G2 clockwise, G3 counter-clockwise) as chords within a
//! tolerance: the plane G17 (X, Y; centre offsets I, J), G18 (Z, X; K, I) or G19 (Y, Z; J, K),
//! the centre from I/J/K (incremental from the start) or from R (R < 0: the longer arc).
//! The chord of a circle of radius r through an angle t deviates from it by r (1 - cos(t/2)),
//! so chords of at most 2 acos(1 - tol / r) keep the path within `tol`.

use std::f64::consts::TAU;

/// Intermediate points (row-major, all joints) from `p0` to `end`, end excluded; joints
/// other than the plane's two move linearly with the swept angle (a helix for the third axis).
pub fn linearize(
    p0: &[f64],
    end: &[f64],
    xyz: &[usize],
    plane: u8,
    clockwise: bool,
    ijkr: [Option<f64>; 4],
    tol: f64,
) -> std::result::Result<Vec<f64>, String> {
    let (a, b, oa, ob) = match plane {
        17 => (xyz[0], xyz[1], ijkr[0], ijkr[1]),
        18 => (xyz[2], xyz[0], ijkr[2], ijkr[0]),
        _ => (xyz[1], xyz[2], ijkr[1], ijkr[2]),
    };
    if a == usize::MAX || b == usize::MAX {
        return Err(format!("an arc in the G{plane} plane needs joints named X, Y and Z"));
    }
    let (s0, s1) = ((p0[a], p0[b]), (end[a], end[b]));
    let centre = if let Some(r) = ijkr[3] {
        if oa.is_some() || ob.is_some() {
            return Err("an arc has both R and centre offsets".into());
        }
        let (dx, dy) = (s1.0 - s0.0, s1.1 - s0.1);
        let d = (dx * dx + dy * dy).sqrt();
        if d == 0.0 || r == 0.0 {
            return Err("an R arc needs distinct end points and R != 0".into());
        }
        let h2 = r * r - d * d / 4.0;
        if h2 < -1e-6 * r * r {
            return Err(format!("arc radius R{r} is smaller than half the chord ({:.6})", d / 2.0));
        }
        let h = h2.max(0.0).sqrt();
        // centre left of the travel direction for G3 with R > 0 (and G2 with R < 0)
        let left = (!clockwise) == (r > 0.0);
        let sgn = if left { 1.0 } else { -1.0 };
        (s0.0 + dx / 2.0 - sgn * h * dy / d, s0.1 + dy / 2.0 + sgn * h * dx / d)
    } else {
        (s0.0 + oa.unwrap_or(0.0), s0.1 + ob.unwrap_or(0.0))
    };
    let r0 = ((s0.0 - centre.0).powi(2) + (s0.1 - centre.1).powi(2)).sqrt();
    let r1 = ((s1.0 - centre.0).powi(2) + (s1.1 - centre.1).powi(2)).sqrt();
    if r0 == 0.0 || (r0 - r1).abs() > 1e-3 + 1e-6 * r0 {
        return Err(format!("arc start and end are not on one circle (radii {r0:.6} and {r1:.6})"));
    }
    let t0 = (s0.1 - centre.1).atan2(s0.0 - centre.0);
    let t1 = (s1.1 - centre.1).atan2(s1.0 - centre.0);
    let mut sweep = t1 - t0;
    if clockwise {
        if sweep >= -1e-12 {
            sweep -= TAU;
        }
    } else if sweep <= 1e-12 {
        sweep += TAU;
    }
    let step = if tol >= r0 { std::f64::consts::PI } else { 2.0 * (1.0 - tol / r0).acos() };
    let n = ((sweep.abs() / step).ceil() as usize).max(1);
    if n > 1_000_000 {
        return Err(format!("the arc needs {n} chords: raise the tolerance"));
    }
    let nj = p0.len();
    let mut out = Vec::with_capacity((n - 1) * nj);
    for i in 1..n {
        let f = i as f64 / n as f64;
        let t = t0 + sweep * f;
        let r = r0 + (r1 - r0) * f;
        for j in 0..nj {
            out.push(if j == a {
                centre.0 + r * t.cos()
            } else if j == b {
                centre.1 + r * t.sin()
            } else {
                p0[j] + (end[j] - p0[j]) * f
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_circle_within_tolerance() {
        // X, Y, Z = joints 0, 1, 2; CCW quarter from (10, 0) about the origin to (0, 10)
        let pts = linearize(&[10.0, 0.0, 5.0], &[0.0, 10.0, 5.0], &[0, 1, 2], 17, false, [Some(-10.0), Some(0.0), None, None], 0.001).unwrap();
        let n = pts.len() / 3 + 1;
        assert_eq!(n, 56, "chords: 2 acos(1 - 1e-4) = 0.02828 rad per chord");
        for p in pts.chunks(3) {
            assert!(((p[0] * p[0] + p[1] * p[1]).sqrt() - 10.0).abs() < 1e-9 && p[0] > 0.0 && p[1] > 0.0 && p[2] == 5.0);
        }
        // the same arc by radius, and clockwise the long way round
        let by_r = linearize(&[10.0, 0.0, 5.0], &[0.0, 10.0, 5.0], &[0, 1, 2], 17, false, [None, None, None, Some(10.0)], 0.001).unwrap();
        assert!(by_r.iter().zip(&pts).all(|(a, b)| (a - b).abs() < 1e-9));
        let cw = linearize(&[10.0, 0.0, 5.0], &[0.0, 10.0, 5.0], &[0, 1, 2], 17, true, [Some(-10.0), Some(0.0), None, None], 0.001).unwrap();
        assert!(cw.len() / 3 + 1 >= 3 * n - 3);
        assert!(linearize(&[10.0, 0.0, 5.0], &[0.0, 11.0, 5.0], &[0, 1, 2], 17, false, [Some(-10.0), Some(0.0), None, None], 0.001).is_err());
    }
}
