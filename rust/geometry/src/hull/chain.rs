//! The one planar convex hull of the kernels: Andrew's monotone chain (A. M. Andrew,
//! "Another efficient algorithm for convex hulls in two dimensions", Inf. Proc. Letters
//! 9 (1979) 216-219) with Shewchuk's exact orientation predicate, after an Akl-Toussaint
//! prefilter for large inputs. Used by the 3-D hull for coplanar sets, by the minimum
//! width of a profile (`gagekit-gdt`) and by the circle fits' farthest-point Voronoi
//! diagram (`gagekit-form`).

use rayon::prelude::*;

use super::exact::orient2d;

/// Inputs larger than this are prefiltered (points strictly inside the polygon of the
/// extremes in eight directions cannot be hull vertices).
const PREFILTER_ABOVE: usize = 4096;

/// Lexicographic order on (x, y); -0.0 and 0.0 compare equal (the chain needs the order
/// of the values, not of their bit patterns); ties by index, so the result does not
/// depend on the sort's stability.
fn lex(p: &[[f64; 2]], i: usize, j: usize) -> std::cmp::Ordering {
    let (a, b) = (p[i], p[j]);
    (a[0] + 0.0)
        .total_cmp(&(b[0] + 0.0))
        .then((a[1] + 0.0).total_cmp(&(b[1] + 0.0)))
        .then(i.cmp(&j))
}

/// Indices of the strictly convex vertices of the hull of finite points `p`,
/// counter-clockwise from the lexicographically smallest; points on hull edges and
/// repeated points are left out (of equal points, the lowest index is kept). Fewer than
/// three indices when the set is collinear (its two extremes) or a single point.
pub fn hull_2d(p: &[[f64; 2]]) -> Vec<usize> {
    let mut ids: Vec<usize> = if p.len() > PREFILTER_ABOVE { survivors(p) } else { (0..p.len()).collect() };
    ids.sort_unstable_by(|&i, &j| lex(p, i, j));
    ids.dedup_by(|later, first| p[*later] == p[*first]);
    if ids.len() < 3 {
        return ids;
    }
    chain(p, &ids)
}

/// Andrew's two monotone chains over `ids`, lexicographically sorted and distinct (>= 3).
fn chain(p: &[[f64; 2]], ids: &[usize]) -> Vec<usize> {
    let mut hull: Vec<usize> = Vec::with_capacity(64);
    for pass in 0..2 {
        let start = hull.len();
        let seq: Box<dyn Iterator<Item = &usize>> = if pass == 0 { Box::new(ids.iter()) } else { Box::new(ids.iter().rev()) };
        for &i in seq {
            while hull.len() >= start + 2 && orient2d(p[hull[hull.len() - 2]], p[hull[hull.len() - 1]], p[i]) <= 0.0 {
                hull.pop();
            }
            hull.push(i);
        }
        hull.pop(); // the last point starts the other chain
    }
    hull
}

/// Akl-Toussaint: drop the points strictly inside the polygon of the extremes in 8
/// directions (they cannot be hull vertices). Exact predicate, parallel, deterministic.
fn survivors(p: &[[f64; 2]]) -> Vec<usize> {
    let dirs: [[f64; 2]; 8] = [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [-1.0, 1.0], [-1.0, 0.0], [-1.0, -1.0], [0.0, -1.0], [1.0, -1.0]];
    let ext: Vec<usize> = dirs
        .iter()
        .map(|d| {
            (0..p.len())
                .into_par_iter()
                .map(|i| (d[0] * p[i][0] + d[1] * p[i][1], i))
                .reduce(|| (f64::NEG_INFINITY, usize::MAX), |a, b| if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) { b } else { a })
                .1
        })
        .collect();
    let mut poly: Vec<usize> = Vec::new();
    for &i in &ext {
        if poly.last() != Some(&i) && poly.first() != Some(&i) {
            poly.push(i);
        }
    }
    if poly.len() < 3 {
        return (0..p.len()).collect();
    }
    (0..p.len())
        .into_par_iter()
        .filter(|&i| !(0..poly.len()).all(|k| orient2d(p[poly[k]], p[poly[(k + 1) % poly.len()]], p[i]) > 0.0))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A point is a strict hull vertex iff some direction has it as the only maximiser;
    /// for small integer sets: iff it is not in the closed hull of the others, tested
    /// with exact orientation against every triangle and segment of the others.
    fn is_vertex(p: &[[f64; 2]], i: usize) -> bool {
        let others: Vec<[f64; 2]> = p.iter().enumerate().filter(|&(j, q)| j != i && *q != p[i]).map(|(_, q)| *q).collect();
        let x = p[i];
        let n = others.len();
        for a in 0..n {
            for b in a..n {
                // on the segment a-b
                let (pa, pb) = (others[a], others[b]);
                if orient2d(pa, pb, x) == 0.0
                    && x[0] >= pa[0].min(pb[0])
                    && x[0] <= pa[0].max(pb[0])
                    && x[1] >= pa[1].min(pb[1])
                    && x[1] <= pa[1].max(pb[1])
                {
                    return false;
                }
                for c in b + 1..n {
                    let pc = others[c];
                    let (s1, s2, s3) = (orient2d(pa, pb, x), orient2d(pb, pc, x), orient2d(pc, pa, x));
                    if (s1 >= 0.0 && s2 >= 0.0 && s3 >= 0.0) || (s1 <= 0.0 && s2 <= 0.0 && s3 <= 0.0) {
                        if orient2d(pa, pb, pc) != 0.0 {
                            return false;
                        }
                    }
                }
            }
        }
        true
    }

    proptest! {
        #[test]
        fn vertices_are_exactly_the_extreme_points(raw in proptest::collection::vec((-3i32..4, -3i32..4), 1..14), negz in any::<bool>()) {
            let p: Vec<[f64; 2]> = raw.iter().map(|&(x, y)| {
                let zx = if negz && x == 0 { -0.0 } else { x as f64 };
                [zx, y as f64]
            }).collect();
            let h = hull_2d(&p);
            let mut want: Vec<[f64; 2]> = Vec::new();
            for i in 0..p.len() {
                if is_vertex(&p, i) && !want.contains(&p[i]) {
                    want.push(p[i]);
                }
            }
            let got: Vec<[f64; 2]> = h.iter().map(|&i| p[i]).collect();
            prop_assert_eq!(got.len(), want.len(), "{:?} -> {:?}", p, got);
            for q in &want {
                prop_assert!(got.contains(q));
            }
            // counter-clockwise
            if got.len() >= 3 {
                for k in 0..got.len() {
                    prop_assert!(orient2d(got[k], got[(k + 1) % got.len()], got[(k + 2) % got.len()]) > 0.0);
                }
            }
        }
    }

    #[test]
    fn prefilter_keeps_the_hull() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let p: Vec<[f64; 2]> = (0..20_000).map(|_| [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)]).collect();
        let mut small: Vec<usize> = (0..p.len()).collect();
        small.sort_unstable_by(|&i, &j| lex(&p, i, j));
        let fast = hull_2d(&p);
        // the same chain on every point, without the prefilter
        let slow = chain(&p, &small);
        assert_eq!(fast, slow);
    }
}
