//! The four amplitude parameters every form standard defines on local deviations from a
//! reference feature (ISO 12181-1 Sec. 3.2.x: RONt, RONp, RONv, RONq; ISO 12780-1: STR...;
//! ISO 12781-1: FLT...).

/// Peak-to-valley `t`, peak-to-reference `p`, reference-to-valley `v` (both >= 0) and the
/// root mean square deviation `q` of the local deviations from a reference feature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    pub t: f64,
    pub p: f64,
    pub v: f64,
    pub q: f64,
}

impl Params {
    /// The parameters of signed local deviations (positive outward / above the reference).
    /// `p` is the largest positive deviation (0 if none: a minimum circumscribed reference
    /// has every point inside), `v` the magnitude of the largest negative one, `t = p + v`,
    /// `q = sqrt(mean(d^2))`. An empty slice gives zeros.
    pub fn from_deviations(d: &[f64]) -> Self {
        if d.is_empty() {
            return Params { t: 0.0, p: 0.0, v: 0.0, q: 0.0 };
        }
        let (lo, hi) = d.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
        let p = hi.max(0.0);
        let v = (-lo).max(0.0);
        let q = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
        Params { t: p + v, p, v, q }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_valley_rms() {
        let p = Params::from_deviations(&[1.0, -2.0, 0.5, -0.5]);
        assert_eq!((p.t, p.p, p.v), (3.0, 1.0, 2.0));
        assert!((p.q - (5.5f64 / 4.0).sqrt()).abs() < 1e-15);
        let inside = Params::from_deviations(&[-1.0, -3.0]);
        assert_eq!((inside.t, inside.p, inside.v), (3.0, 0.0, 3.0));
    }
}
