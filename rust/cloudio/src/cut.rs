//! Region-first evaluation of one chunk of a streamed cloud (issue 29, Sec. 5.4.1): the
//! chunk classified into the region boxes, and for each box only what the evaluation
//! keeps: every point inside, or the convex-hull vertices of the points inside (the LP of
//! Eq. 5.11 needs only those; the hull of the union of the chunks is the hull of the union
//! of their hulls). One call a chunk, parallel inside (the classification over the points,
//! the boxes' gathers and hulls over the boxes): the same operations as classifying the
//! chunk, indexing it and hulling each box's points one after the other, hence the same
//! indices and points.

use gagekit_core::Result;
use gagekit_geometry::{classify, convex_hull_indices, OrientedBox};
use rayon::prelude::*;

/// What a [`cut_chunk`] keeps of one box.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Keep {
    /// Every point inside.
    All,
    /// The convex-hull vertices of the points inside (Eq. 5.21, exact predicates).
    Hull,
}

/// What [`cut_chunk`] kept of one box.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionCut {
    /// Number of points of the chunk inside the box.
    pub count: usize,
    /// Indices in the chunk (ascending) of every point inside, when asked for with
    /// [`Keep::Hull`] (with [`Keep::All`] they are `kept`).
    pub inside: Option<Vec<usize>>,
    /// Indices in the chunk (ascending) of the kept points.
    pub kept: Vec<usize>,
    /// The kept points, row-major (x, y, z).
    pub points: Vec<f64>,
}

fn gather(points: &[f64], idx: &[usize]) -> Vec<f64> {
    let mut out = Vec::with_capacity(3 * idx.len());
    for &i in idx {
        out.extend_from_slice(&points[3 * i..3 * i + 3]);
    }
    out
}

/// Classify the row-major (n, 3) `points` into `boxes` and keep, per box, what `keep`
/// says; `want_inside` also returns every inside index of the [`Keep::Hull`] boxes (for
/// a sample of each region, or the numbers of all its points). The errors of
/// [`classify`] (a non-finite point, a bad box).
pub fn cut_chunk(points: &[f64], boxes: &[OrientedBox], keep: &[Keep], want_inside: bool) -> Result<Vec<RegionCut>> {
    assert_eq!(boxes.len(), keep.len(), "one keep mode per box");
    let inside = classify(points, boxes)?;
    inside
        .into_par_iter()
        .zip(keep.par_iter())
        .map(|(idx, &k)| {
            let sel = gather(points, &idx);
            let count = idx.len();
            if k == Keep::All || idx.is_empty() {
                let inside = (k == Keep::Hull && want_inside).then(|| idx.clone());
                return Ok(RegionCut { count, inside, kept: idx, points: sel });
            }
            let h = convex_hull_indices(&sel)?;
            let kept: Vec<usize> = h.iter().map(|&j| idx[j]).collect();
            let pts = gather(&sel, &h);
            Ok(RegionCut { count, inside: want_inside.then_some(idx), kept, points: pts })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use gagekit_geometry::select;

    #[test]
    fn cut_equals_classify_then_hull() {
        let pts: Vec<f64> = (0..3 * 4000).map(|i| ((i * 7919) % 1000) as f64 * 0.013 - 6.0).collect();
        let boxes = [
            OrientedBox { center: [0.0; 3], size: [6.0, 6.0, 6.0], rotation: [0.0; 3] },
            OrientedBox { center: [1.0, -1.0, 0.5], size: [3.0, 4.0, 5.0], rotation: [0.1, 0.2, 0.3] },
            OrientedBox { center: [100.0; 3], size: [1.0; 3], rotation: [0.0; 3] },
        ];
        let cuts = cut_chunk(&pts, &boxes, &[Keep::All, Keep::Hull, Keep::Hull], true).unwrap();
        for (b, c) in boxes.iter().zip(&cuts) {
            let idx = select(&pts, b).unwrap();
            assert_eq!(c.count, idx.len());
            assert_eq!(c.inside.as_deref().unwrap_or(&c.kept), &idx[..]);
        }
        assert_eq!(cuts[0].points, gather(&pts, &cuts[0].kept));
        let idx = select(&pts, &boxes[1]).unwrap();
        let h = convex_hull_indices(&gather(&pts, &idx)).unwrap();
        assert_eq!(cuts[1].kept, h.iter().map(|&j| idx[j]).collect::<Vec<_>>());
        assert_eq!(cuts[1].points, gather(&pts, &cuts[1].kept));
        assert_eq!((cuts[2].count, cuts[2].kept.len()), (0, 0));
        let no = cut_chunk(&pts, &boxes[1..2], &[Keep::Hull], false).unwrap();
        assert!(no[0].inside.is_none());
    }
}
