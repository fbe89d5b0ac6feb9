//! An inner "height field" of the prefilter polytope: boxes aligned with the
//! coordinate axes, on a grid over two axes, each proven (exactly) to lie
//! strictly inside the polytope. A point inside one of them is certainly not a
//! hull vertex; the test is six floating-point comparisons, which are exact.
//! It pays off for point sets flat along a coordinate axis, the common case of
//! a face of a part aligned with its CAD frame; elsewhere it just misses.

use super::exact::{cross, dot, sub, P3};

/// Most cells per grid side.
pub(super) const MAX_SIDE: usize = 32;

pub(super) struct InnerGrid {
    /// Cells per side.
    g: usize,
    axis: usize,
    uv: [usize; 2],
    lo: [f64; 2],
    inv: [f64; 2],
    nodes: [Vec<f64>; 2],
    /// Per cell (row-major over u, v): the proven height interval, or empty.
    h: Vec<[f64; 2]>,
}

impl InnerGrid {
    /// Grid over the coordinates other than `axis` of the box `lo..hi`;
    /// `strictly_inside` must decide exactly, `faces` (outward, counter-clockwise)
    /// give the floating-point guess of each cell's height interval.
    pub fn build(
        g: usize,
        faces: &[[P3; 3]],
        strictly_inside: impl Fn(P3) -> bool,
        axis: usize,
        lo: P3,
        hi: P3,
    ) -> Option<Self> {
        let uv = [(axis + 1) % 3, (axis + 2) % 3];
        if uv.iter().any(|&k| hi[k] <= lo[k]) {
            return None;
        }
        let nodes = uv.map(|k| {
            (0..=g)
                .map(|i| lo[k] + (hi[k] - lo[k]) * i as f64 / g as f64)
                .collect::<Vec<f64>>()
        });
        let planes: Vec<(P3, f64)> = faces
            .iter()
            .map(|f| {
                let n = cross(sub(f[1], f[0]), sub(f[2], f[0]));
                (n, dot(n, f[0]))
            })
            .collect();
        // Interval of heights inside all face planes over one column (u, v).
        let column = |u: f64, v: f64| {
            let (mut h0, mut h1) = (lo[axis], hi[axis]);
            for &(n, d) in &planes {
                let rest = d - n[uv[0]] * u - n[uv[1]] * v;
                if n[axis] > 0.0 {
                    h1 = h1.min(rest / n[axis]);
                } else if n[axis] < 0.0 {
                    h0 = h0.max(rest / n[axis]);
                } else if rest < 0.0 {
                    return (1.0, -1.0);
                }
            }
            (h0, h1)
        };
        let point = |u: f64, v: f64, h: f64| {
            let mut p = [0.0; 3];
            p[uv[0]] = u;
            p[uv[1]] = v;
            p[axis] = h;
            p
        };
        let mut h = Vec::with_capacity(g * g);
        for i in 0..g {
            for j in 0..g {
                let (u0, u1, v0, v1) = (nodes[0][i], nodes[0][i + 1], nodes[1][j], nodes[1][j + 1]);
                let (mut h0, mut h1) = (f64::NEG_INFINITY, f64::INFINITY);
                for (u, v) in [(u0, v0), (u0, v1), (u1, v0), (u1, v1)] {
                    let (a, b) = column(u, v);
                    h0 = h0.max(a);
                    h1 = h1.min(b);
                }
                // shrink a little towards the middle, then prove the 8 corners
                let (mid, half) = ((h0 + h1) / 2.0, (h1 - h0) / 2.0 * 0.98);
                let cell = [mid - half, mid + half];
                let proven = half > 0.0
                    && [u0, u1].iter().all(|&u| {
                        [v0, v1]
                            .iter()
                            .all(|&v| cell.iter().all(|&z| strictly_inside(point(u, v, z))))
                    });
                h.push(if proven {
                    cell
                } else {
                    [f64::INFINITY, f64::NEG_INFINITY]
                });
            }
        }
        if h.iter().all(|c| c[0] > c[1]) {
            // no cell proven (a thin face tilted off the axis, a curved band): the test
            // would only cost every point its lookup
            return None;
        }
        let inv = [0, 1].map(|k| g as f64 / (hi[uv[k]] - lo[uv[k]]));
        Some(InnerGrid {
            g,
            axis,
            uv,
            lo: uv.map(|k| lo[k]),
            inv,
            nodes,
            h,
        })
    }

    /// True only if `x` lies in a proven cell (exact comparisons).
    #[inline(always)]
    pub fn contains(&self, x: P3) -> bool {
        let (u, v) = (x[self.uv[0]], x[self.uv[1]]);
        // `as usize` saturates negative values at 0; the comparisons below decide.
        let i = (((u - self.lo[0]) * self.inv[0]) as usize).min(self.g - 1);
        let j = (((v - self.lo[1]) * self.inv[1]) as usize).min(self.g - 1);
        let [h0, h1] = self.h[i * self.g + j];
        let z = x[self.axis];
        (z >= h0)
            & (z <= h1)
            & (u >= self.nodes[0][i])
            & (u <= self.nodes[0][i + 1])
            & (v >= self.nodes[1][j])
            & (v <= self.nodes[1][j + 1])
    }
}
