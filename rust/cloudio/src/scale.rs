//! Unit conversion of a read cloud in place (metres of an E57 file, feet of a LAS file...
//! to millimetres): one parallel pass, no second array.

use gagekit_core::{GkError, Result};
use rayon::prelude::*;

/// Multiply the coordinates of row-major points (`scale.len()` per point) by `scale`,
/// one factor per coordinate, in place. The input is finite; an `InvalidInput` error names
/// the first point a factor overflows to infinity (the values are then partly scaled).
pub fn scale_in_place(coords: &mut [f64], scale: &[f64], what: &str) -> Result<()> {
    let dim = scale.len();
    if dim == 0 || coords.len() % dim != 0 {
        return Err(GkError::invalid(format!("{what}: {} values are not points of {dim} coordinates", coords.len())));
    }
    let overflow = coords
        .par_chunks_mut(dim * 16384)
        .map(|block| {
            let mut ok = true;
            for p in block.chunks_exact_mut(dim) {
                for (v, s) in p.iter_mut().zip(scale) {
                    *v *= s;
                    ok &= v.is_finite();
                }
            }
            !ok
        })
        .reduce(|| false, |a, b| a || b);
    if overflow {
        let row = coords.chunks_exact(dim).position(|p| p.iter().any(|v| !v.is_finite())).unwrap_or(0);
        return Err(GkError::invalid(format!(
            "{what}: point {row} overflows when converted to millimetres (coordinates beyond 1e308 mm)"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_each_coordinate_and_names_an_overflow() {
        let mut v = vec![1.0, 2.0, 3.0, -4.0, 5.0, 6.0];
        scale_in_place(&mut v, &[1000.0, 1000.0, 304.8], "t").unwrap();
        assert_eq!(v, vec![1000.0, 2000.0, 3.0 * 304.8, -4000.0, 5000.0, 6.0 * 304.8]);
        let mut w = vec![1.0, 1.0, 1e307, 1.0];
        let e = scale_in_place(&mut w, &[1000.0, 1000.0], "f").unwrap_err();
        assert!(e.message.contains("point 1"), "{}", e.message);
        assert!(scale_in_place(&mut [1.0; 5], &[2.0, 2.0], "f").is_err());
    }
}
