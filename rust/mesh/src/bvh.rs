//! A bounding-volume hierarchy over a mesh's triangles and the nearest-triangle query.
//!
//! Build: axis-aligned boxes, split at the median centroid along the box's longest axis
//! (`select_nth_unstable`, deterministic), leaves of at most [`LEAF`] triangles, the two
//! halves built in parallel above 8192 triangles; nodes in depth-first order (the left
//! child follows its parent) and the triangles' corners copied into leaf order, so a
//! query reads memory front to back. The tree depends on the triangles only, never on
//! the thread count.
//!
//! Query: depth first, the nearer child first, every subtree whose box is not nearer
//! than the best triangle so far skipped. A starting bound (the distance to a hinted
//! triangle, e.g. the previous point's) prunes most of the tree for coherent points.

use crate::closest::{box_distance2, closest_point, Feature};
use gagekit_gdt::vec3::{sub, dot, V3};

/// Most triangles per leaf.
pub const LEAF: usize = 4;

#[derive(Debug, Clone, Copy)]
pub struct Node {
    pub lo: V3,
    pub hi: V3,
    /// leaf: first triangle slot; inner node: index of the right child
    pub start: u32,
    /// leaf: number of triangles (> 0); inner node: 0
    pub count: u32,
}

/// The hierarchy: nodes, and per slot (leaf order) the triangle's corners and its index.
#[derive(Debug, Clone)]
pub struct Bvh {
    pub nodes: Vec<Node>,
    pub corners: Vec<[V3; 3]>,
    pub order: Vec<u32>,
}

/// The nearest triangle found: its slot (leaf order), squared distance, closest point and feature.
#[derive(Debug, Clone, Copy)]
pub struct Nearest {
    pub slot: u32,
    pub d2: f64,
    pub foot: V3,
    pub feature: Feature,
}

struct Item {
    tri: u32,
    centroid: V3,
    lo: V3,
    hi: V3,
}

fn bounds(items: &[Item]) -> (V3, V3) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for it in items {
        for k in 0..3 {
            lo[k] = lo[k].min(it.lo[k]);
            hi[k] = hi[k].max(it.hi[k]);
        }
    }
    (lo, hi)
}

/// Build the subtree of `items` (slots from `first`): its nodes in depth-first order,
/// right-child indices relative to the subtree's first node.
fn build(items: &mut [Item], first: u32) -> Vec<Node> {
    let (lo, hi) = bounds(items);
    if items.len() <= LEAF {
        return vec![Node { lo, hi, start: first, count: items.len() as u32 }];
    }
    let mut clo = [f64::INFINITY; 3];
    let mut chi = [f64::NEG_INFINITY; 3];
    for it in items.iter() {
        for k in 0..3 {
            clo[k] = clo[k].min(it.centroid[k]);
            chi[k] = chi[k].max(it.centroid[k]);
        }
    }
    let ext = [chi[0] - clo[0], chi[1] - clo[1], chi[2] - clo[2]];
    let axis = if ext[0] >= ext[1] && ext[0] >= ext[2] { 0 } else if ext[1] >= ext[2] { 1 } else { 2 };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]).then(a.tri.cmp(&b.tri)));
    let (left, right) = items.split_at_mut(mid);
    let (ln, rn) = if left.len() + right.len() > 8192 {
        rayon::join(|| build(left, first), || build(right, first + mid as u32))
    } else {
        (build(left, first), build(right, first + mid as u32))
    };
    let mut nodes = Vec::with_capacity(1 + ln.len() + rn.len());
    let right_at = 1 + ln.len() as u32;
    nodes.push(Node { lo, hi, start: right_at, count: 0 });
    for n in &ln {
        let mut n = *n;
        if n.count == 0 {
            n.start += 1;
        }
        nodes.push(n);
    }
    for n in &rn {
        let mut n = *n;
        if n.count == 0 {
            n.start += right_at;
        }
        nodes.push(n);
    }
    nodes
}

impl Bvh {
    /// The hierarchy of the triangles `corners` (at least one).
    pub fn new(corners: &[[V3; 3]]) -> Self {
        let mut items: Vec<Item> = corners
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let mut lo = c[0];
                let mut hi = c[0];
                for v in &c[1..] {
                    for k in 0..3 {
                        lo[k] = lo[k].min(v[k]);
                        hi[k] = hi[k].max(v[k]);
                    }
                }
                let centroid = [(c[0][0] + c[1][0] + c[2][0]) / 3.0, (c[0][1] + c[1][1] + c[2][1]) / 3.0, (c[0][2] + c[1][2] + c[2][2]) / 3.0];
                Item { tri: i as u32, centroid, lo, hi }
            })
            .collect();
        let nodes = build(&mut items, 0);
        let order: Vec<u32> = items.iter().map(|it| it.tri).collect();
        let corners = order.iter().map(|&t| corners[t as usize]).collect();
        Self { nodes, corners, order }
    }

    /// Squared distance from `p` to the triangle in `slot`, with the closest point and feature.
    #[inline]
    pub fn to_slot(&self, p: V3, slot: u32) -> Nearest {
        let c = &self.corners[slot as usize];
        let (foot, feature) = closest_point(p, c[0], c[1], c[2]);
        let v = sub(p, foot);
        Nearest { slot, d2: dot(v, v), foot, feature }
    }

    /// The nearest triangle to `p` closer than `sqrt(bound2)` (None if there is none).
    /// `hint`: a slot to try first (its distance starts the bound).
    pub fn nearest(&self, p: V3, bound2: f64, hint: Option<u32>) -> Option<Nearest> {
        let mut best: Option<Nearest> = None;
        let mut best_d2 = bound2;
        if let Some(h) = hint {
            if (h as usize) < self.corners.len() {
                let n = self.to_slot(p, h);
                if n.d2 < best_d2 || (n.d2 == best_d2 && bound2.is_infinite()) {
                    best_d2 = n.d2;
                    best = Some(n);
                }
            }
        }
        let mut stack: [(u32, f64); 96] = [(0, 0.0); 96];
        let mut sp = 0usize;
        let root = &self.nodes[0];
        let d_root = box_distance2(&p, &root.lo, &root.hi);
        if d_root > best_d2 || (d_root == best_d2 && best.is_some()) {
            return best;
        }
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if n.count > 0 {
                for slot in n.start..n.start + n.count {
                    if Some(slot) == best.map(|b| b.slot) {
                        continue;
                    }
                    let c = &self.corners[slot as usize];
                    let (foot, feature) = closest_point(p, c[0], c[1], c[2]);
                    let v = sub(p, foot);
                    let d2 = dot(v, v);
                    if d2 < best_d2 || (best.is_none() && d2 <= best_d2) {
                        best_d2 = d2;
                        best = Some(Nearest { slot, d2, foot, feature });
                    }
                }
            } else {
                let (l, r) = (node + 1, n.start as usize);
                let dl = box_distance2(&p, &self.nodes[l].lo, &self.nodes[l].hi);
                let dr = box_distance2(&p, &self.nodes[r].lo, &self.nodes[r].hi);
                let (near, dn, far, df) = if dl <= dr { (l, dl, r, dr) } else { (r, dr, l, dl) };
                let open = |d: f64, best_d2: f64, found: bool| d < best_d2 || (!found && d <= best_d2);
                if open(dn, best_d2, best.is_some()) {
                    if open(df, best_d2, best.is_some()) && sp < stack.len() {
                        stack[sp] = (far as u32, df);
                        sp += 1;
                    }
                    node = near;
                    continue;
                }
            }
            // pop the next subtree still worth visiting
            let mut next = None;
            while sp > 0 {
                sp -= 1;
                let (k, d) = stack[sp];
                if d < best_d2 || (best.is_none() && d <= best_d2) {
                    next = Some(k as usize);
                    break;
                }
            }
            match next {
                Some(k) => node = k,
                None => return best,
            }
        }
    }
}
