//! Property tests of the convex-hull filter (Eq. 5.21) on generated point sets rich in
//! degeneracies: small integer grids give duplicates, collinear and coplanar subsets that
//! the exact predicates must resolve. Issue 12: fuzzing of the non-reader kernels.
//!
//! Properties: the call never panics (finite input within the documented magnitudes is
//! Ok, anything else an InvalidInput error); the indices are ascending, unique and in
//! range; the support function of the vertices equals that of the whole set in every
//! direction (CH(S') = CH(S)); the hull of the vertices alone is all of them (no
//! returned point is interior: idempotence); the vertex coordinates do not change under a
//! permutation of the input or an integer translation.

use gagekit_core::ErrorKind;
use gagekit_geometry::convex_hull_indices;
use proptest::prelude::*;

fn coords(pts: &[[i32; 3]]) -> Vec<f64> {
    pts.iter().flat_map(|p| p.iter().map(|&v| f64::from(v))).collect()
}

fn support(points: &[f64], idx: &[usize], d: [f64; 3]) -> f64 {
    idx.iter()
        .map(|&i| points[3 * i] * d[0] + points[3 * i + 1] * d[1] + points[3 * i + 2] * d[2])
        .fold(f64::NEG_INFINITY, f64::max)
}

fn vertex_set(points: &[f64], idx: &[usize]) -> Vec<[i64; 3]> {
    let mut v: Vec<[i64; 3]> =
        idx.iter().map(|&i| [points[3 * i] as i64, points[3 * i + 1] as i64, points[3 * i + 2] as i64]).collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// Integer points on a small grid (many degeneracies), up to 60 of them.
fn grid_points() -> impl Strategy<Value = Vec<[i32; 3]>> {
    (1i32..6, 0usize..60).prop_flat_map(|(span, n)| proptest::collection::vec([-span..=span, -span..=span, -span..=span], n))
}

/// Points of a plane or a line embedded in 3-D, with integer parameters.
fn flat_points() -> impl Strategy<Value = Vec<[i32; 3]>> {
    (proptest::collection::vec((-9i32..10, -9i32..10), 0..40), [-3i32..4, -3i32..4, -3i32..4], [-3i32..4, -3i32..4, -3i32..4], any::<bool>())
        .prop_map(|(uv, a, b, line)| {
            uv.into_iter()
                .map(|(u, v)| {
                    let v = if line { 0 } else { v };
                    [u * a[0] + v * b[0], u * a[1] + v * b[1], u * a[2] + v * b[2]]
                })
                .collect()
        })
}

fn check(pts: &[[i32; 3]]) -> Result<(), TestCaseError> {
    let p = coords(pts);
    let idx = convex_hull_indices(&p).map_err(|e| TestCaseError::fail(format!("error on valid input: {e}")))?;
    let n = pts.len();
    prop_assert!(idx.windows(2).all(|w| w[0] < w[1]), "indices not ascending/unique: {:?}", idx);
    prop_assert!(idx.iter().all(|&i| i < n));
    prop_assert_eq!(idx.is_empty(), n == 0);
    let all: Vec<usize> = (0..n).collect();
    let dirs = [
        [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0],
        [1.0, 1.0, 1.0], [-1.0, 2.0, 5.0], [3.0, -7.0, 19.0], [-2.0, -1.0, 3.0], [1.0, -3.0, -2.0], [1.0, 2.0, -9.0],
    ]; // integer directions: the dot products of integer points are exact
    for d in dirs {
        prop_assert_eq!(support(&p, &idx, d), support(&p, &all, d), "support differs in direction {:?}", d);
    }
    // idempotence: every vertex is extreme
    let sub: Vec<f64> = idx.iter().flat_map(|&i| p[3 * i..3 * i + 3].iter().copied()).collect();
    let again = convex_hull_indices(&sub).map_err(|e| TestCaseError::fail(format!("{e}")))?;
    prop_assert_eq!(vertex_set(&sub, &again), vertex_set(&p, &idx));
    // permutation (reversed) and integer translation
    let rev: Vec<[i32; 3]> = pts.iter().rev().copied().collect();
    let pr = coords(&rev);
    let ir = convex_hull_indices(&pr).map_err(|e| TestCaseError::fail(format!("{e}")))?;
    prop_assert_eq!(vertex_set(&pr, &ir), vertex_set(&p, &idx));
    let moved: Vec<[i32; 3]> = pts.iter().map(|q| [q[0] + 7, q[1] - 3, q[2] + 11]).collect();
    let im = convex_hull_indices(&coords(&moved)).map_err(|e| TestCaseError::fail(format!("{e}")))?;
    prop_assert_eq!(im, idx);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    #[test]
    fn grid_sets_satisfy_the_hull_properties(pts in grid_points()) {
        check(&pts)?;
    }

    #[test]
    fn flat_sets_satisfy_the_hull_properties(pts in flat_points()) {
        check(&pts)?;
    }

    /// Any f64 bits at all: never a panic; an error is an InvalidInput naming the problem.
    #[test]
    fn arbitrary_bits_never_panic(bits in proptest::collection::vec(any::<u64>(), 0..90)) {
        let v: Vec<f64> = bits.iter().map(|&b| f64::from_bits(b)).collect();
        let v = &v[..v.len() - v.len() % 3];
        match convex_hull_indices(v) {
            Ok(idx) => prop_assert!(idx.iter().all(|&i| i < v.len() / 3)),
            Err(e) => prop_assert_eq!(e.kind, ErrorKind::InvalidInput),
        }
    }

    /// Finite values of every magnitude the hull accepts, mixed.
    #[test]
    fn mixed_magnitudes_never_panic(vals in proptest::collection::vec(prop_oneof![
        Just(0.0), -1e100..1e100f64, -1.0..1.0f64, (-1e3..1e3f64).prop_map(|x| x * 1e-57)], 0..90)) {
        let v = &vals[..vals.len() - vals.len() % 3];
        match convex_hull_indices(v) {
            Ok(idx) => prop_assert!(idx.windows(2).all(|w| w[0] < w[1])),
            Err(e) => prop_assert_eq!(e.kind, ErrorKind::InvalidInput),
        }
    }
}
