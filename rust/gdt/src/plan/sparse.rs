//! A trial of a plan whose plane features are evaluated on the points that can be
//! extreme only, with a certificate that every other point lies inside every zone computed
//! (issue 26: "reuse the active sets"). Used by [`super::run`] for isotropic noise alone.
//!
//! **Noise in blocks.** The active points are split once into blocks: the rows of each
//! *sparse* plane feature (below) in square cells of its plane holding about [`BLOCK`]
//! points ([`cells`]), then every other point in the order of the active points, [`BLOCK`]
//! a block. Block `b` of trial `t` draws its points' deviates (x, y, z of each point in
//! order; `sigma` times the ziggurat's standard normal deviates,
//! [`super::perturb::normal`]) from its own xoshiro256++ generator, its state a bijection
//! of (seed, t, b) ([`block_rng`]): any block can be drawn alone, again, in any order and on
//! any thread, with the same values.
//!
//! **Sparse features.** A plane feature whose every use reads its points only through
//! zones of two parallel planes -- flatness (the minimum zone), a Chebyshev datum plane
//! of any orientation but a basic angle, the orientation zones of a plane but angularity
//! (perpendicular, parallel, fixed), its location zone without a turn searched -- and whose
//! points belong to no other feature. Each such zone is the zone of its extreme points:
//! a slab of fixed normal is the extent of the points; a thinnest slab over a set of
//! normals, computed on a subset, is the thinnest of every point when it contains every
//! point (the subset's width is at most every point's in each normal); a datum plane is
//! the outer plane of such a slab.
//!
//! **A trial.** Every block is drawn; a block of a sparse feature keeps only the smallest
//! and the largest deviate of each coordinate (m). Per block the measured points give
//! (once a run) their centre c, the largest |u . (p - c)| and |v . (p - c)| and the range
//! [h_lo, h_hi] of n0 . (p - c), (u, v, n0) the frame of the feature's least-squares
//! normal n0. With p - c = du u + dv v + dh n0 and p' = p + sigma d,
//!
//!   n . p' = n . c + (n . u) du + (n . v) dv + (n . n0) dh + sigma n . d,
//!
//! each term bounded by the block's extents and m ([`reach`]). The blocks whose reach along
//! a normal of the zones the measured evaluation read comes within [`START`] sigma of the
//! feature's largest (smallest) reach are drawn again into the feature's points and the
//! trial is evaluated on them, recording each zone (n, lo, hi) the feature's results read.
//! A block left out whose reach along n lies within [lo + tol, hi - tol] has every point
//! inside the zone. Blocks outside some zone join the points, and the trial is evaluated
//! again (the other features keep their fits, the callouts that depend on no sparse
//! feature their values) until every block left out is inside every zone: the values are
//! then those of the same draws evaluated on every point (the same zones, to the active
//! sets' containment tolerance of 1e-9 mm; the datum planes' reference point, a centroid,
//! is that of the points evaluated, so the frames agree to rounding). A trial that needs
//! every point of a sparse feature after all (an error on the subset, a result not read
//! through a zone) is evaluated on every point.
//!
//! The certificate is exact: no bound on the noise is assumed, m holds the deviates
//! actually drawn, and the blocks chosen depend on the draws alone (the same on any thread
//! count). The cost left is drawing every deviate (about 3.4 ns each) where a feature's
//! points are not used.

use super::perturb::{normal, TrialRng};
use super::{evaluate_feats, Characteristic, Feat, Plan, Shape, Values};
use crate::vec3::{dot, norm, sub, V3};
use gagekit_core::Result;
use rand::RngCore;
use rand::SeedableRng;

/// Points a block.
pub const BLOCK: usize = 64;
/// A sparse feature's blocks within this many sigma of its largest (smallest) reach along
/// a measured zone's normal start a trial's points (2 M bracket, one thread, CPU a trial
/// alternated at a load of 6-7: 0.4 104-117 ms, 0.75 99-137 ms, 1.5 127-148 ms; fewer
/// start blocks, more second rounds; any value gives the same zones).
pub const START: f64 = 0.75;
/// The certificate's margin, mm (above the rounding of the coordinates and dot products).
const TOL: f64 = 1e-9;
/// The message of a result that needs every point of a sparse feature.
pub(super) const NEEDS_ALL: &str = "a sparse feature's result needs every point";

const DENSE: usize = usize::MAX;

/// SplitMix64's output function (Steele, Lea and Flood, "Fast splittable pseudorandom
/// number generators", OOPSLA 2014): a bijection of 64-bit words.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The generator of block `block` of trial `trial` of the simulation seeded `seed`:
/// xoshiro256++ with the state (mix64(seed + k0), mix64(trial + k1), mix64(block + k2),
/// mix64 of the three), so distinct (seed, trial, block) give distinct states, after 8
/// outputs discarded (the words of nearby keys are unrelated after the bijection; the
/// discarded outputs mix the four).
pub fn block_rng(seed: u64, trial: u64, block: u64) -> TrialRng {
    let a = mix64(seed.wrapping_add(0x6761_6765_6b69_7431));
    let b = mix64(trial.wrapping_add(0x9e37_79b9_7f4a_7c15));
    let c = mix64(block.wrapping_add(0xd1b5_4a32_d192_ed03));
    let d = mix64(a ^ b.rotate_left(21) ^ c.rotate_left(42)) | 1;
    let mut state = [0u8; 32];
    for (k, w) in [a, b, c, d].iter().enumerate() {
        state[8 * k..8 * k + 8].copy_from_slice(&w.to_le_bytes());
    }
    let mut rng = TrialRng::from_seed(state);
    for _ in 0..8 {
        rng.next_u64();
    }
    rng
}

#[derive(Debug, Clone)]
struct Block {
    /// Its points: `order[start..end]`.
    start: usize,
    end: usize,
    /// Its sparse feature, or DENSE.
    feature: usize,
    c: V3,
    /// The largest |u . (p - c)|, |v . (p - c)| and the range of n0 . (p - c) of its
    /// measured points, (u, v, n0) the feature's frame.
    u_ext: f64,
    v_ext: f64,
    h_lo: f64,
    h_hi: f64,
}

/// The blocks of a plan's active points (module docs), built once a run.
#[derive(Debug, Clone)]
pub struct Layout {
    blocks: Vec<Block>,
    order: Vec<usize>,
    /// Per entry of `order`: its destinations `dests[dest_at[j]..dest_at[j + 1]]`
    /// (feature, position in the feature's points); sparse blocks have none.
    dest_at: Vec<usize>,
    dests: Vec<(usize, usize)>,
    /// Per feature when sparse: its frame (u, v, n0: n0 the least-squares normal) and
    /// its blocks.
    sparse: Vec<Option<([V3; 3], std::ops::Range<usize>)>>,

    /// Per feature: the normals of the zones the measured evaluation read (the start).
    normals: Vec<Vec<V3>>,
    /// Per callout: does its value depend on no sparse feature (its feature, datums and
    /// frame)? Then a trial's later rounds keep it.
    fixed: Vec<bool>,
}

/// The rows of a plane feature in square cells of its plane (frame u, v) holding about
/// [`BLOCK`] points each, cell by cell (each in row order).
fn cells(rows: &[usize], pts: &[f64], u: V3, v: V3) -> Vec<Vec<usize>> {
    let at = |i: usize| [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]];
    let uv: Vec<(f64, f64)> = rows.iter().map(|&i| (dot(u, at(i)), dot(v, at(i)))).collect();
    let (mut u0, mut u1, mut v0, mut v1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(a, b) in &uv {
        (u0, u1, v0, v1) = (u0.min(a), u1.max(a), v0.min(b), v1.max(b));
    }
    let side = ((u1 - u0).max(1e-9) * (v1 - v0).max(1e-9) * BLOCK as f64 / rows.len() as f64).sqrt();
    let nu = (((u1 - u0) / side) as usize + 1).min(1 << 20);
    let mut key: Vec<(usize, usize)> = uv
        .iter()
        .enumerate()
        .map(|(j, &(a, b))| ((((b - v0) / side) as usize).min(1 << 20) * nu + (((a - u0) / side) as usize).min(nu - 1), j))
        .collect();
    key.sort_unstable();
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut last = usize::MAX;
    for (k, j) in key {
        if k != last || out.last().is_some_and(|c| c.len() >= 2 * BLOCK) {
            out.push(Vec::new());
            last = k;
        }
        out.last_mut().unwrap().push(rows[j]);
    }
    out
}

/// The plane features whose uses read their points only through zones (module docs).
fn eligible(plan: &Plan) -> Vec<bool> {
    use Characteristic as C;
    let mut ok: Vec<bool> = plan.features.iter().map(|f| f.shape == Shape::Plane).collect();
    for c in &plan.callouts {
        let zones_only = matches!(c.characteristic, C::Flatness | C::Parallelism | C::Perpendicularity | C::Position | C::Profile);
        if !zones_only {
            ok[c.feature] = false;
        }
    }
    for d in &plan.datums {
        // a plane behind one datum plane at a basic angle other than 90 degrees reads its
        // least-squares normal (and its zone turns freely about the datum)
        if let [j] = d.prior.as_slice() {
            if plan.features[plan.datums[*j].feature].shape == Shape::Plane && d.angle != 90.0 {
                ok[d.feature] = false;
            }
        }
    }
    ok
}

impl Layout {
    /// The layout of `plan` on its active points `pts` (flat (n, 3)), or None when no
    /// feature is sparse.
    pub fn new(plan: &Plan, pts: &[f64]) -> Option<Layout> {
        let n = pts.len() / 3;
        let mut members = vec![0u32; n];
        for f in &plan.features {
            for &i in &f.rows {
                members[i] += 1;
            }
        }
        let ok = eligible(plan);
        let mut sparse: Vec<Option<([V3; 3], std::ops::Range<usize>)>> = vec![None; plan.features.len()];
        let mut blocks = Vec::new();
        let mut order = Vec::new();
        let mut in_sparse = vec![false; n];

        for (k, f) in plan.features.iter().enumerate() {
            if !ok[k] || f.rows.len() < 4 * BLOCK || f.rows.iter().any(|&i| members[i] != 1) {
                continue;
            }
            let p: Vec<f64> = f.rows.iter().flat_map(|&i| pts[3 * i..3 * i + 3].iter().copied()).collect();
            let n0 = match gagekit_form::lsq::plane(&p) {
                Ok(l) => crate::vec3::scale([l.normal[0], l.normal[1], l.normal[2]], 1.0 / norm([l.normal[0], l.normal[1], l.normal[2]])),
                Err(_) => continue,
            };
            let (u, v) = crate::vec3::basis(n0);
            let first = blocks.len();
            for chunk in cells(&f.rows, pts, u, v) {
                let chunk = chunk.as_slice();
                let m = chunk.len() as f64;
                let mut c = [0.0; 3];
                for &i in chunk {
                    for k in 0..3 {
                        c[k] += pts[3 * i + k] / m;
                    }
                }
                let (mut u_ext, mut v_ext, mut h_lo, mut h_hi) = (0.0f64, 0.0f64, f64::INFINITY, f64::NEG_INFINITY);
                for &i in chunk {
                    let d = sub([pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]], c);
                    u_ext = u_ext.max(dot(u, d).abs());
                    v_ext = v_ext.max(dot(v, d).abs());
                    let h = dot(n0, d);
                    h_lo = h_lo.min(h);
                    h_hi = h_hi.max(h);
                }
                blocks.push(Block { start: order.len(), end: order.len() + chunk.len(), feature: k, c, u_ext, v_ext, h_lo, h_hi });
                order.extend_from_slice(chunk);
                for &i in chunk {
                    in_sparse[i] = true;
                }
            }
            sparse[k] = Some(([u, v, n0], first..blocks.len()));
        }
        if sparse.iter().all(|s| s.is_none()) {
            return None;
        }
        // every other point, in the order of the active points, with its destinations
        let mut at = vec![0usize; n + 1];
        for (k, f) in plan.features.iter().enumerate() {
            if sparse[k].is_none() {
                for &i in &f.rows {
                    at[i + 1] += 1;
                }
            }
        }
        for i in 0..n {
            at[i + 1] += at[i];
        }
        let mut fill = at.clone();
        let mut by_point = vec![(0usize, 0usize); at[n]];
        for (k, f) in plan.features.iter().enumerate() {
            if sparse[k].is_none() {
                for (pos, &i) in f.rows.iter().enumerate() {
                    by_point[fill[i]] = (k, pos);
                    fill[i] += 1;
                }
            }
        }
        let mut dest_at = vec![0usize; order.len()];
        let mut dests = Vec::with_capacity(by_point.len());
        let dense: Vec<usize> = (0..n).filter(|&i| !in_sparse[i]).collect();
        for chunk in dense.chunks(BLOCK) {
            blocks.push(Block { start: order.len(), end: order.len() + chunk.len(), feature: DENSE, c: [0.0; 3], u_ext: 0.0, v_ext: 0.0, h_lo: 0.0, h_hi: 0.0 });
            for &i in chunk {
                order.push(i);
                dest_at.push(dests.len());
                dests.extend_from_slice(&by_point[at[i]..at[i + 1]]);
            }
        }
        dest_at.push(dests.len());
        // the zones of the measured points: their normals choose a trial's first blocks
        let feats = plan.features.iter().map(|f| {
            let p: Vec<f64> = f.rows.iter().flat_map(|&i| pts[3 * i..3 * i + 3].iter().copied()).collect();
            Feat::new(f, p, false)
        }).collect();
        let (_, feats) = evaluate_feats(plan, feats, Vec::new());
        let normals = feats
            .iter()
            .zip(&sparse)
            .map(|(f, s)| {
                let mut v: Vec<V3> = f.zones.iter().map(|z| z.0).collect();
                if let Some((frame, _)) = s {
                    v.push(frame[2]);
                }
                v
            })
            .collect();
        let mut moving = vec![false; plan.datums.len()];
        for (k, d) in plan.datums.iter().enumerate() {
            moving[k] = sparse[d.feature].is_some() || d.prior.iter().any(|&j| moving[j]);
        }
        let fixed = plan
            .callouts
            .iter()
            .map(|c| {
                !(sparse[c.feature].is_some()
                    || c.datums.iter().any(|&k| moving[k])
                    || c.frame.is_some_and(|f| plan.frames[f].iter().any(|&k| moving[k])))
            })
            .collect();
        Some(Layout { blocks, order, dest_at, dests, sparse, normals, fixed })
    }

    /// The perturbed points of block `b` (flat, in block order).
    fn draw(&self, pts: &[f64], sigma: f64, seed: u64, trial: u64, b: usize) -> Vec<f64> {
        let blk = &self.blocks[b];
        let mut rng = block_rng(seed, trial, b as u64);
        let mut out = Vec::with_capacity(3 * (blk.end - blk.start));
        for &i in &self.order[blk.start..blk.end] {
            for k in 0..3 {
                out.push(pts[3 * i + k] + normal(&mut rng) * sigma);
            }
        }
        out
    }

    /// Every active point perturbed as trial `trial` draws it (flat (n, 3)).
    pub fn simulate(&self, pts: &[f64], sigma: f64, seed: u64, trial: u64) -> Vec<f64> {
        let mut out = pts.to_vec();
        for b in 0..self.blocks.len() {
            let p = self.draw(pts, sigma, seed, trial, b);
            let blk = &self.blocks[b];
            for (j, &i) in self.order[blk.start..blk.end].iter().enumerate() {
                out[3 * i..3 * i + 3].copy_from_slice(&p[3 * j..3 * j + 3]);
            }
        }
        out
    }
}

/// The layout of the last active points a plan ran on (building it evaluates the plan
/// on the measured points once: about a trial's time), kept between blocks of trials.
#[derive(Debug, Default)]
pub struct Cache(std::sync::Mutex<Option<Cached>>);

/// The points a layout was built on, and the layout (None: no sparse feature).
type Cached = (Vec<f64>, Option<std::sync::Arc<Layout>>);

impl Cache {
    /// The layout of `plan` on `pts`, built once for the same points.
    pub fn layout(&self, plan: &Plan, pts: &[f64]) -> Option<std::sync::Arc<Layout>> {
        let mut g = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((p, lay)) = g.as_ref() {
            if p.as_slice() == pts {
                return lay.clone();
            }
        }
        let lay = Layout::new(plan, pts).map(std::sync::Arc::new);
        *g = Some((pts.to_vec(), lay.clone()));
        lay
    }
}

/// Does every point of block `blk` (deviates at most `m` sigma a coordinate) lie in the
/// zone (n, lo, hi)? (Module docs.)
fn inside(blk: &Block, frame: &[V3; 3], m: [[f64; 2]; 3], sigma: f64, (n, lo, hi): (V3, f64, f64)) -> bool {
    let (lo_b, hi_b) = reach(blk, frame, m, sigma, n);
    let tol = TOL + 1e-15 * (lo_b.abs() + hi_b.abs());
    hi_b <= hi - tol && lo_b >= lo + tol
}

/// The range of n . p' over block `blk`'s perturbed points p' = p + sigma d, m[k] the
/// (smallest, largest) deviate d_k of the block: with p - c = du u + dv v + dh n0,
/// n . p' = n . c + (n . u) du + (n . v) dv + (n . n0) dh + sigma n . d, each term bounded
/// by the block's extents.
fn reach(blk: &Block, [u, v, n0]: &[V3; 3], m: [[f64; 2]; 3], sigma: f64, n: V3) -> (f64, f64) {
    let g = dot(n, *n0);
    let (g_lo, g_hi) = if g >= 0.0 { (g * blk.h_lo, g * blk.h_hi) } else { (g * blk.h_hi, g * blk.h_lo) };
    let spread = dot(n, *u).abs() * blk.u_ext + dot(n, *v).abs() * blk.v_ext;
    let (mut e_lo, mut e_hi) = (0.0, 0.0);
    for k in 0..3 {
        let (a, b) = (n[k] * m[k][0], n[k] * m[k][1]);
        e_lo += a.min(b);
        e_hi += a.max(b);
    }
    let x = dot(n, blk.c);
    (x + g_lo - spread + sigma * e_lo, x + g_hi + spread + sigma * e_hi)
}

/// Trial `trial` of the plan on the active points `pts` with isotropic noise `sigma`
/// (module docs). `all`: every block drawn into the points (the reference evaluation).
pub fn trial(plan: &Plan, pts: &[f64], lay: &Layout, sigma: f64, seed: u64, trial: u64, all: bool) -> Result<Values> {
    let nf = plan.features.len();
    let mut bufs: Vec<Vec<f64>> =
        (0..nf).map(|k| if lay.sparse[k].is_some() { Vec::new() } else { vec![0.0; 3 * plan.features[k].rows.len()] }).collect();
    let mut bound = vec![[[0.0f64; 2]; 3]; lay.blocks.len()];
    for (b, blk) in lay.blocks.iter().enumerate() {
        let mut rng = block_rng(seed, trial, b as u64);
        if blk.feature == DENSE {
            for j in blk.start..blk.end {
                let i = lay.order[j];
                let mut p = [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]];
                for x in p.iter_mut() {
                    *x += normal(&mut rng) * sigma;
                }
                for &(k, pos) in &lay.dests[lay.dest_at[j]..lay.dest_at[j + 1]] {
                    bufs[k][3 * pos..3 * pos + 3].copy_from_slice(&p);
                }
            }
        } else {
            let mut m = [[f64::INFINITY, f64::NEG_INFINITY]; 3];
            for _ in blk.start..blk.end {
                for mk in m.iter_mut() {
                    let d = normal(&mut rng);
                    mk[0] = mk[0].min(d);
                    mk[1] = mk[1].max(d);
                }
            }
            bound[b] = m;
        }
    }
    // the start: the blocks of largest reach along the feature's normal
    let mut explicit = vec![all; lay.blocks.len()];
    for (k, s) in lay.sparse.iter().enumerate() {
        let Some((frame, range)) = s else { continue };
        for &n in &lay.normals[k] {
            let reach = |b: usize| reach(&lay.blocks[b], frame, bound[b], sigma, n);
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for b in range.clone() {
                let (l, h) = reach(b);
                lo = lo.min(l);
                hi = hi.max(h);
            }
            for b in range.clone() {
                let (l, h) = reach(b);
                if l <= lo + START * sigma || h >= hi - START * sigma {
                    explicit[b] = true;
                }
            }
        }
    }
    let mut drawn: Vec<Option<Vec<f64>>> = vec![None; lay.blocks.len()];
    let mut feats: Vec<Feat> = plan.features.iter().zip(bufs).map(|(spec, p)| Feat::new(spec, p, false)).collect();
    let (mut fits, mut fallbacks) = (0, 0);
    let mut whole = all;
    let mut reuse: Vec<Option<f64>> = Vec::new();
    loop {
        for (k, s) in lay.sparse.iter().enumerate() {
            if let Some((_, range)) = s {
                let mut p = Vec::new();
                for b in range.clone() {
                    if explicit[b] || whole {
                        p.extend_from_slice(drawn[b].get_or_insert_with(|| lay.draw(pts, sigma, seed, trial, b)));
                    }
                }
                feats[k] = Feat::new(&plan.features[k], p, !whole);
            }
        }
        let (r, back) = evaluate_feats(plan, feats, std::mem::take(&mut reuse));
        feats = back;
        let v = match r {
            Ok(v) => v,
            Err(e) if whole => return Err(e),
            Err(_) => {
                // every point of the sparse features, every fit again (a fresh trial)
                whole = true;
                (fits, fallbacks) = (0, 0);
                reuse.clear();
                for f in feats.iter_mut() {
                    *f = Feat::new(f.spec, std::mem::take(&mut f.pts), false);
                }
                continue;
            }
        };
        fits += v.warm_fits;
        fallbacks += v.fallbacks;
        let mut grew = false;
        if !whole {
            for (k, s) in lay.sparse.iter().enumerate() {
                if let Some((n0, range)) = s {
                    for b in range.clone() {
                        if !explicit[b] && !feats[k].zones.iter().all(|z| inside(&lay.blocks[b], n0, bound[b], sigma, *z)) {
                            explicit[b] = true;
                            grew = true;
                        }
                    }
                }
            }
        }
        if !grew {
            return Ok(Values { values: v.values, warm_fits: fits, fallbacks });
        }
        reuse = lay.fixed.iter().enumerate().map(|(i, &f)| if f { Some(v.values[2 * i]) } else { None }).collect();
    }
}

/// Is the model isotropic noise alone (the case [`trial`] covers)?
pub fn covers(model: &super::perturb::Model) -> bool {
    model.sigma > 0.0 && model.origin.is_none() && model.sigma_per_m == 0.0 && model.probing == 0.0 && model.relative_scale == 0.0 && model.offset == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn a_block_generator_depends_on_seed_trial_and_block_alone() {
        let first = |s, t, b| block_rng(s, t, b).next_u64();
        assert_eq!(first(1, 2, 3), first(1, 2, 3));
        let mut seen = std::collections::HashSet::new();
        for s in 0..4 {
            for t in 0..50 {
                for b in 0..50 {
                    assert!(seen.insert(first(s, t, b)));
                }
            }
        }
    }

    #[test]
    fn the_reach_of_a_block_bounds_every_perturbed_point_along_any_normal() {
        let mut rng = block_rng(7, 0, 0);
        for _ in 0..200 {
            let n0 = crate::vec3::unit([rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5], "n0").unwrap();
            let (u, v) = crate::vec3::basis(n0);
            let c0 = [rng.random::<f64>() * 100.0, rng.random::<f64>() * 100.0, rng.random::<f64>() * 100.0];
            let sigma = 1e-3;
            let m = 1 + rng.random_range(0..80usize);
            let pts: Vec<V3> = (0..m)
                .map(|_| {
                    let (a, b, h) = (rng.random::<f64>() * 3.0, rng.random::<f64>() - 0.5, (rng.random::<f64>() - 0.5) * 0.01);
                    crate::vec3::add(c0, crate::vec3::add(crate::vec3::scale(u, a), crate::vec3::add(crate::vec3::scale(v, b), crate::vec3::scale(n0, h))))
                })
                .collect();
            let dev: Vec<V3> = (0..m).map(|_| [normal(&mut rng), normal(&mut rng), normal(&mut rng)]).collect();
            let mut c = [0.0; 3];
            for p in &pts {
                for k in 0..3 {
                    c[k] += p[k] / m as f64;
                }
            }
            let (mut ue, mut ve, mut lo, mut hi) = (0.0f64, 0.0f64, f64::INFINITY, f64::NEG_INFINITY);
            for p in &pts {
                let d = sub(*p, c);
                ue = ue.max(dot(u, d).abs());
                ve = ve.max(dot(v, d).abs());
                lo = lo.min(dot(n0, d));
                hi = hi.max(dot(n0, d));
            }
            let blk = Block { start: 0, end: m, feature: 0, c, u_ext: ue, v_ext: ve, h_lo: lo, h_hi: hi };
            let mut mm = [[f64::INFINITY, f64::NEG_INFINITY]; 3];
            for d in &dev {
                for k in 0..3 {
                    mm[k] = [mm[k][0].min(d[k]), mm[k][1].max(d[k])];
                }
            }
            for _ in 0..10 {
                // normals near n0 and anywhere
                let w = [rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5];
                let t = if rng.random::<bool>() { 1e-3 } else { 1.0 };
                let n = crate::vec3::unit(crate::vec3::add(n0, crate::vec3::scale(w, t)), "n").unwrap();
                let (a, b) = reach(&blk, &[u, v, n0], mm, sigma, n);
                for (p, d) in pts.iter().zip(&dev) {
                    let q = [p[0] + d[0] * sigma, p[1] + d[1] * sigma, p[2] + d[2] * sigma];
                    let x = dot(n, q);
                    assert!(a - 1e-12 <= x && x <= b + 1e-12, "{a} {x} {b}");
                }
                assert!(inside(&blk, &[u, v, n0], mm, sigma, (n, a - 2e-9, b + 2e-9)));
                assert!(!inside(&blk, &[u, v, n0], mm, sigma, (n, a + 1e-6, b)));
            }
        }
    }
}
