//! Region-first evaluation of one chunk of a streamed cloud (issue 29, Sec. 5.4.1): the
//! chunk classified into the region boxes, and for each box only what the evaluation
//! keeps: every point inside, or the convex-hull vertices of the points inside (the LP of
//! Eq. 5.11 needs only those; the hull of the union of the chunks is the hull of the union
//! of their hulls). One call a chunk, parallel inside (the classification over the points,
//! the boxes' gathers and hulls over the boxes): the same operations as classifying the
//! chunk, indexing it and hulling each box's points one after the other, hence the same
//! indices and points.

use crate::sample::sample_key;
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
    /// The hull vertices when at least this many points are inside, else every point
    /// inside (a caller piling up a region's points to hull them later: a large share
    /// of a chunk is hulled here, in the cut's parallel pass, the few points of a small
    /// region wait for a hull of many chunks' points together, which costs less a point).
    HullFrom(usize),
}

/// The bottom-k sample of each box's inside points a [`cut_chunk`] draws (the region
/// pictures of a streamed check): the points whose key ([`sample_key`] of `seed` and
/// the point's number, `start` + its row in the chunk) is below the box's `below` (the
/// largest key the caller's sample holds, or infinity while it holds fewer than k: any
/// value at least that leaves the sample the same).
#[derive(Debug, Clone, PartialEq)]
pub struct SampleSpec {
    pub seed: u64,
    /// Number of the chunk's first point.
    pub start: u64,
    /// Per box: the key below which its points may enter the sample.
    pub below: Vec<f64>,
}

/// The points of a box a [`cut_chunk`] drew for its sample ([`SampleSpec`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Sampled {
    /// Rows in the chunk (ascending).
    pub rows: Vec<usize>,
    /// Their keys.
    pub keys: Vec<f64>,
    /// Their points, row-major.
    pub points: Vec<f64>,
}

/// Number of `f64` in the flat form of [`Moments`] ([`Moments::to_array`]).
pub const MOMENTS_LEN: usize = 22;

/// First and second moments of a point sequence about its first point, by compensated
/// (Neumaier) sums added point by point in order: what the least-squares start of the
/// 3-2-1 datum fits needs of a datum region (centroid and scatter matrix, Eqs. 5.13-5.14)
/// without keeping its points. The sums depend only on the sequence, so a region streamed
/// chunk by chunk (the state carried from one chunk to the next) gets exactly the bits of
/// the whole region added at once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moments {
    /// Number of points added.
    pub n: u64,
    /// The first point: the sums are of `p - origin`.
    pub origin: [f64; 3],
    /// Sums of d_x, d_y, d_z, d_x d_x, d_x d_y, d_x d_z, d_y d_y, d_y d_z, d_z d_z
    /// (d = p - origin), and their running compensations.
    pub sum: [f64; 9],
    pub comp: [f64; 9],
}

impl Default for Moments {
    fn default() -> Self {
        Self { n: 0, origin: [0.0; 3], sum: [0.0; 9], comp: [0.0; 9] }
    }
}

impl Moments {
    /// Add the row-major (n, 3) `points`, in order.
    pub fn add(&mut self, points: &[f64]) {
        for p in points.chunks_exact(3) {
            if self.n == 0 {
                self.origin = [p[0], p[1], p[2]];
            }
            self.n += 1;
            let d = [p[0] - self.origin[0], p[1] - self.origin[1], p[2] - self.origin[2]];
            let t = [d[0], d[1], d[2], d[0] * d[0], d[0] * d[1], d[0] * d[2], d[1] * d[1], d[1] * d[2], d[2] * d[2]];
            for k in 0..9 {
                // Neumaier: the low-order bits lost by each addition kept in comp
                let s = self.sum[k] + t[k];
                self.comp[k] += if self.sum[k].abs() >= t[k].abs() { (self.sum[k] - s) + t[k] } else { (t[k] - s) + self.sum[k] };
                self.sum[k] = s;
            }
        }
    }

    /// The flat form: n, origin (3), sums (9), compensations (9).
    pub fn to_array(&self) -> [f64; MOMENTS_LEN] {
        let mut a = [0.0; MOMENTS_LEN];
        a[0] = self.n as f64;
        a[1..4].copy_from_slice(&self.origin);
        a[4..13].copy_from_slice(&self.sum);
        a[13..22].copy_from_slice(&self.comp);
        a
    }

    /// From the flat form of [`Moments::to_array`].
    pub fn from_array(a: &[f64]) -> Self {
        assert_eq!(a.len(), MOMENTS_LEN, "moments: {MOMENTS_LEN} values");
        let mut m = Self { n: a[0] as u64, ..Self::default() };
        m.origin.copy_from_slice(&a[1..4]);
        m.sum.copy_from_slice(&a[4..13]);
        m.comp.copy_from_slice(&a[13..22]);
        m
    }
}

/// Count, centroid and scatter matrix sum (p - mean)(p - mean)^T of a point set: what
/// the least-squares starts of the 3-2-1 datum fits read (Eqs. 5.13-5.14).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scatter {
    pub n: u64,
    pub mean: [f64; 3],
    pub scatter: [[f64; 3]; 3],
}

impl Moments {
    /// The count, centroid and scatter of the points added (the compensations folded in).
    pub fn scatter(&self) -> Scatter {
        let k = self.n as f64;
        let s: [f64; 9] = std::array::from_fn(|i| self.sum[i] + self.comp[i]);
        let s1 = [s[0], s[1], s[2]];
        let s2 = [[s[3], s[4], s[5]], [s[4], s[6], s[7]], [s[5], s[7], s[8]]];
        Scatter {
            n: self.n,
            mean: std::array::from_fn(|i| self.origin[i] + s1[i] / k),
            scatter: std::array::from_fn(|i| std::array::from_fn(|j| s2[i][j] - s1[i] * s1[j] / k)),
        }
    }
}

/// The scatter of several regions' points together, from each region's moments, merged
/// by the parallel-axis rule; empty regions are skipped, and none with points gives n = 0.
pub fn merged_scatter(parts: &[Moments]) -> Scatter {
    let parts: Vec<Scatter> = parts.iter().filter(|m| m.n > 0).map(Moments::scatter).collect();
    let n: u64 = parts.iter().map(|p| p.n).sum();
    if n == 0 {
        return Scatter { n: 0, mean: [0.0; 3], scatter: [[0.0; 3]; 3] };
    }
    let mut mean = [0.0; 3];
    for p in &parts {
        for i in 0..3 {
            mean[i] += p.n as f64 * p.mean[i];
        }
    }
    let mean = mean.map(|v| v / n as f64);
    let mut scatter = [[0.0; 3]; 3];
    for p in &parts {
        let d: [f64; 3] = std::array::from_fn(|i| p.mean[i] - mean[i]);
        for i in 0..3 {
            for j in 0..3 {
                scatter[i][j] += p.scatter[i][j] + p.n as f64 * d[i] * d[j];
            }
        }
    }
    Scatter { n, mean, scatter }
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
    /// The points drawn for the box's sample, when asked for ([`SampleSpec`]).
    pub sample: Option<Sampled>,
}

fn gather(points: &[f64], idx: &[usize]) -> Vec<f64> {
    let mut out = Vec::with_capacity(3 * idx.len());
    for &i in idx {
        out.extend_from_slice(&points[3 * i..3 * i + 3]);
    }
    out
}

/// The ascending `a` without the members of the ascending `b` (one merge walk).
fn difference(a: &[usize], b: &[usize]) -> Vec<usize> {
    let mut out = Vec::with_capacity(a.len().saturating_sub(b.len()).max(a.len() / 16));
    let mut j = 0;
    for &i in a {
        while j < b.len() && b[j] < i {
            j += 1;
        }
        if j == b.len() || b[j] != i {
            out.push(i);
        }
    }
    out
}

/// Classify the row-major (n, 3) `points` into `boxes` and keep, per box, what `keep`
/// says; `want_inside` also returns every inside index of the [`Keep::Hull`] boxes (for
/// a sample of each region, or the numbers of all its points). `moments` (empty, or one
/// per box) receive the points inside their box, in order ([`Moments::add`]). `minus`
/// (empty, or one per box): `Some(k)` makes box i hold only its points outside box k (a
/// shell around box k; the count, kept points and moments are of those), decided on the
/// indices before any point is gathered. `sample`: each box's sample candidates
/// ([`SampleSpec`], of the points the box holds, after `minus`). The errors of
/// [`classify`] (a non-finite point, a bad box).
pub fn cut_chunk(
    points: &[f64],
    boxes: &[OrientedBox],
    keep: &[Keep],
    want_inside: bool,
    moments: &mut [Option<Moments>],
    minus: &[Option<usize>],
    sample: Option<&SampleSpec>,
) -> Result<Vec<RegionCut>> {
    assert_eq!(boxes.len(), keep.len(), "one keep mode per box");
    assert!(sample.is_none_or(|s| s.below.len() == boxes.len()), "sample: one bound per box");
    assert!(moments.is_empty() || moments.len() == boxes.len(), "no moments, or one per box");
    assert!(minus.is_empty() || minus.len() == boxes.len(), "no minus, or one per box");
    assert!(minus.iter().enumerate().all(|(i, m)| m.is_none_or(|k| k < boxes.len() && k != i)), "minus: another box");
    let mut inside = classify(points, boxes)?;
    if minus.iter().any(Option::is_some) {
        let shells: Vec<Option<Vec<usize>>> =
            minus.par_iter().enumerate().map(|(i, m)| m.map(|k| difference(&inside[i], &inside[k]))).collect();
        for (i, s) in shells.into_iter().enumerate() {
            if let Some(s) = s {
                inside[i] = s;
            }
        }
    }
    let mut none = vec![None; if moments.is_empty() { boxes.len() } else { 0 }];
    let moments = if moments.is_empty() { &mut none[..] } else { moments };
    inside
        .into_par_iter()
        .zip(keep.par_iter())
        .zip(moments.par_iter_mut())
        .enumerate()
        .map(|(b, ((idx, &k), mom))| {
            let sel = gather(points, &idx);
            if let Some(m) = mom {
                m.add(&sel);
            }
            let count = idx.len();
            let sample = sample.map(|s| draw(s, s.below[b], &idx, &sel));
            let hull = match k {
                Keep::All => false,
                Keep::Hull => true,
                Keep::HullFrom(m) => count >= m,
            };
            if !hull || idx.is_empty() {
                let inside = (k != Keep::All && want_inside).then(|| idx.clone());
                return Ok(RegionCut { count, inside, kept: idx, points: sel, sample });
            }
            let h = convex_hull_indices(&sel)?;
            let kept: Vec<usize> = h.iter().map(|&j| idx[j]).collect();
            let pts = gather(&sel, &h);
            Ok(RegionCut { count, inside: want_inside.then_some(idx), kept, points: pts, sample })
        })
        .collect()
}

/// The rows `idx` (ascending, points `sel`) whose key is below `below`.
fn draw(s: &SampleSpec, below: f64, idx: &[usize], sel: &[f64]) -> Sampled {
    let mut out = Sampled::default();
    for (j, &i) in idx.iter().enumerate() {
        let k = sample_key(s.seed, s.start.wrapping_add(i as u64));
        if k < below {
            out.rows.push(i);
            out.keys.push(k);
            out.points.extend_from_slice(&sel[3 * j..3 * j + 3]);
        }
    }
    out
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
        let cuts = cut_chunk(&pts, &boxes, &[Keep::All, Keep::Hull, Keep::Hull], true, &mut [], &[], None).unwrap();
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
        let no = cut_chunk(&pts, &boxes[1..2], &[Keep::Hull], false, &mut [], &[], None).unwrap();
        assert!(no[0].inside.is_none());
    }

    /// `HullFrom(m)` hulls a box holding at least m points and keeps every point of a
    /// smaller one; the sample drawn in the cut is the points whose key of their number
    /// (chunk start + row) is below the box's bound, with their keys and points.
    #[test]
    fn hull_from_and_sample() {
        use crate::sample::sample_key;
        let pts: Vec<f64> = (0..3 * 4000).map(|i| ((i * 7919) % 1000) as f64 * 0.013 - 6.0).collect();
        let b = OrientedBox { center: [1.0, -1.0, 0.5], size: [3.0, 4.0, 5.0], rotation: [0.1, 0.2, 0.3] };
        let idx = select(&pts, &b).unwrap();
        assert!(idx.len() > 100);
        let boxes = [b.clone(), b.clone(), b.clone()];
        let keep = [Keep::HullFrom(idx.len()), Keep::HullFrom(idx.len() + 1), Keep::All];
        let spec = SampleSpec { seed: 7, start: 1 << 33, below: vec![f64::INFINITY, 0.25, 0.0] };
        let cuts = cut_chunk(&pts, &boxes, &keep, false, &mut [], &[], Some(&spec)).unwrap();
        let h = convex_hull_indices(&gather(&pts, &idx)).unwrap();
        assert_eq!(cuts[0].kept, h.iter().map(|&j| idx[j]).collect::<Vec<_>>());
        assert_eq!((cuts[1].count, &cuts[1].kept), (idx.len(), &idx));
        assert_eq!(cuts[1].points, gather(&pts, &idx));
        for (c, below) in cuts.iter().zip(&spec.below) {
            let s = c.sample.as_ref().unwrap();
            let want: Vec<usize> = idx.iter().copied().filter(|&i| sample_key(7, (1 << 33) + i as u64) < *below).collect();
            assert_eq!(s.rows, want);
            assert_eq!(s.keys, want.iter().map(|&i| sample_key(7, (1 << 33) + i as u64)).collect::<Vec<_>>());
            assert_eq!(s.points, gather(&pts, &want));
        }
        assert_eq!(cuts[0].sample.as_ref().unwrap().rows, idx);
        assert!(cuts[2].sample.as_ref().unwrap().rows.is_empty());
        assert!(cut_chunk(&pts, &boxes, &keep, false, &mut [], &[], None).unwrap().iter().all(|c| c.sample.is_none()));
    }

    /// A box cut `minus` another keeps exactly its points outside that box (the shell),
    /// with the count and points of those, whatever the order of the two boxes.
    #[test]
    fn minus_keeps_the_points_outside_the_other_box() {
        let pts: Vec<f64> = (0..3 * 6000).map(|i| ((i * 7919) % 1000) as f64 * 0.013 - 6.0).collect();
        let grown = OrientedBox { center: [0.5, -0.5, 0.2], size: [5.0, 6.0, 7.0], rotation: [0.1, 0.2, 0.3] };
        let core = OrientedBox { size: [4.0, 5.0, 6.0], ..grown.clone() };
        let (g, c) = (select(&pts, &grown).unwrap(), select(&pts, &core).unwrap());
        let want: Vec<usize> = g.iter().copied().filter(|i| !c.contains(i)).collect();
        assert!(!want.is_empty() && want.len() < g.len());
        assert_eq!(difference(&g, &c), want);
        assert_eq!(difference(&c, &g), Vec::<usize>::new());
        assert_eq!(difference(&g, &[]), g);
        for (boxes, minus, at) in [([core.clone(), grown.clone()], [None, Some(0)], 1), ([grown.clone(), core.clone()], [Some(1), None], 0)] {
            let cuts = cut_chunk(&pts, &boxes, &[Keep::All, Keep::All], false, &mut [], &minus, None).unwrap();
            assert_eq!((cuts[at].count, &cuts[at].kept), (want.len(), &want));
            assert_eq!(cuts[at].points, gather(&pts, &want));
            assert_eq!(cuts[1 - at].kept, c);
        }
    }

    /// A region's moments are the same bits whether its points come at once or chunk by
    /// chunk, at any chunk size, and the flat form round-trips.
    #[test]
    fn streamed_moments_equal_whole() {
        let pts: Vec<f64> = (0..3 * 5000).map(|i| ((i * 7919) % 1000) as f64 * 0.013 - 6.0 + 1e3).collect();
        let b = [OrientedBox { center: [1000.0; 3], size: [6.0, 6.0, 6.0], rotation: [0.1, 0.2, 0.3] }];
        let idx = select(&pts, &b[0]).unwrap();
        let mut whole = Moments::default();
        whole.add(&gather(&pts, &idx));
        assert_eq!(whole.n as usize, idx.len());
        for chunk in [1usize, 7, 997, 5000] {
            let mut m = [Some(Moments::default())];
            for c in pts.chunks(3 * chunk) {
                cut_chunk(c, &b, &[Keep::Hull], false, &mut m, &[], None).unwrap();
            }
            assert_eq!(m[0].unwrap(), whole, "chunk {chunk}");
        }
        assert_eq!(Moments::from_array(&whole.to_array()), whole);
        // the compensated sums: the centroid to the last bits of a plain f64 sum
        let sel = gather(&pts, &idx);
        let mean_x: f64 = sel.chunks_exact(3).map(|p| p[0]).sum::<f64>() / idx.len() as f64;
        let got = whole.origin[0] + (whole.sum[0] + whole.comp[0]) / whole.n as f64;
        assert!((got - mean_x).abs() < 1e-9, "{got} {mean_x}");
    }

    /// The scatter merged from two regions' moments (parallel-axis rule) equals the scatter
    /// of their points together, computed directly about their mean.
    #[test]
    fn merged_scatter_equals_the_scatter_of_all_points() {
        let a: Vec<f64> = (0..3 * 700).map(|i| ((i * 7919) % 1000) as f64 * 0.011 + 250.0).collect();
        let b: Vec<f64> = (0..3 * 300).map(|i| ((i * 104729) % 997) as f64 * 0.007 - 40.0).collect();
        let (mut ma, mut mb) = (Moments::default(), Moments::default());
        ma.add(&a);
        mb.add(&b);
        let got = merged_scatter(&[ma, Moments::default(), mb]);
        let all: Vec<f64> = a.iter().chain(&b).copied().collect();
        let n = all.len() / 3;
        assert_eq!(got.n as usize, n);
        let mean: [f64; 3] = std::array::from_fn(|i| all.chunks_exact(3).map(|p| p[i]).sum::<f64>() / n as f64);
        for i in 0..3 {
            assert!((got.mean[i] - mean[i]).abs() < 1e-10, "mean {i}");
            for j in 0..3 {
                let want: f64 = all.chunks_exact(3).map(|p| (p[i] - mean[i]) * (p[j] - mean[j])).sum();
                assert!((got.scatter[i][j] - want).abs() <= 1e-9 * want.abs().max(1.0), "scatter {i}{j}: {} {want}", got.scatter[i][j]);
            }
        }
        assert_eq!(merged_scatter(&[Moments::default()]).n, 0);
        assert_eq!(ma.scatter(), merged_scatter(&[ma]));
    }
}
