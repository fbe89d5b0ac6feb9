//! A trial of a plan whose plane features are evaluated on the points that can be
//! extreme only, with a certificate that every other point lies inside every zone computed
//! (issue 26: "reuse the active sets"). Used by [`super::run`] for isotropic noise alone.
//!
//! **Noise in blocks.** The active points are split once into blocks: the rows of each
//! *sparse* plane feature (below) in square cells of its plane holding about [`BLOCK`]
//! points ([`cells`]), then every other point in the order of the active points, [`BLOCK`]
//! a block. Block `b` of trial `t` draws its points' deviates (`sigma` times standard
//! normal deviates: a dense block x, y, z of each point in order by the ziggurat,
//! [`super::perturb::normal`]; a sparse block its [`Extremes`] first, then the others) from its own xoshiro256++ generator, its state a bijection
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
//! **A trial.** Every dense block is drawn; of a block of a sparse feature only the
//! smallest and the largest deviate of each coordinate (m) and where they are
//! ([`Extremes`], drawn directly: exact in distribution; the block drawn as points later
//! has exactly these extremes). Per block the measured points give
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
//! count). The cost left is drawing the extremes of every sparse block (2 M bracket:
//! about 23 M instructions a trial, against about 111 M for the deviates one by one; about
//! half their time) and every dense deviate.

use super::perturb::{normal, TrialRng};
use super::{evaluate_feats, Characteristic, Feat, Plan, Shape, Values};
use crate::vec3::{dot, norm, sub, V3};
use gagekit_core::Result;
use rand::{Rng, RngCore, SeedableRng};

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

/// The standard normal quantile Phi^-1(p), 0 < p < 1: Wichura's algorithm AS 241
/// (PPND16; "The percentage points of the normal distribution", Applied Statistics 37(3),
/// 1988, 477-484), relative error about 1e-16. The tails use r = sqrt(-ln p) of the
/// smaller tail, so a tail probability p near 0 keeps its full precision.
#[inline]
#[allow(clippy::excessive_precision)]
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 8] = [
        3.387_132_872_796_366_608, 133.141_667_891_784_377_45, 1_971.590_950_306_551_442_7, 13_731.693_765_509_461_125,
        45_921.953_931_549_871_457, 67_265.770_927_008_700_853, 33_430.575_583_588_128_105, 2_509.080_928_730_122_672_7,
    ];
    const B: [f64; 8] = [
        1.0, 42.313_330_701_600_911_252, 687.187_007_492_057_908_30, 5_394.196_021_424_751_107_7,
        21_213.794_301_586_595_867, 39_307.895_800_092_710_610, 28_729.085_735_721_942_674, 5_226.495_278_852_854_561_0,
    ];
    const C: [f64; 8] = [
        1.423_437_110_749_683_577_34, 4.630_337_846_156_545_295_90, 5.769_497_221_460_691_405_50, 3.647_848_324_763_204_605_04,
        1.270_458_252_452_368_382_58, 0.241_780_725_177_450_611_770, 0.022_723_844_989_269_184_583_3, 7.745_450_142_783_414_076_40e-4,
    ];
    const D: [f64; 8] = [
        1.0, 2.053_191_626_637_758_821_87, 1.676_384_830_183_803_849_40, 0.689_767_334_985_100_004_550,
        0.148_103_976_427_480_074_590, 0.015_198_666_563_616_457_196_6, 5.475_938_084_995_344_946_00e-4, 1.050_750_071_644_416_843_24e-9,
    ];
    const E: [f64; 8] = [
        6.657_904_643_501_103_777_20, 5.463_784_911_164_114_369_90, 1.784_826_539_917_291_335_80, 0.296_560_571_828_504_891_230,
        0.026_532_189_526_576_123_093_0, 0.001_242_660_947_388_078_438_60, 2.711_555_568_743_487_578_15e-5, 2.010_334_399_292_288_132_65e-7,
    ];
    const F: [f64; 8] = [
        1.0, 0.599_832_206_555_887_937_690, 0.136_929_880_922_735_805_310, 0.014_875_361_290_850_614_852_5,
        7.868_691_311_456_132_591_00e-4, 1.846_318_317_510_054_681_80e-5, 1.421_511_758_316_445_888_70e-7, 2.044_263_103_389_939_785_64e-15,
    ];
    fn ratio(a: &[f64; 8], b: &[f64; 8], r: f64) -> f64 {
        let (mut x, mut y) = (a[7], b[7]);
        for k in (0..7).rev() {
            x = x * r + a[k];
            y = y * r + b[k];
        }
        x / y
    }
    let q = p - 0.5;
    if q.abs() <= 0.425 {
        return q * ratio(&A, &B, 0.180625 - q * q);
    }
    let r = (-(if q < 0.0 { p } else { 1.0 - p }).ln()).sqrt();
    let x = if r <= 5.0 { ratio(&C, &D, r - 1.6) } else { ratio(&E, &F, r - 5.0) };
    if q < 0.0 {
        -x
    } else {
        x
    }
}

/// The smallest and largest of a sparse block's m standard normal deviates of each
/// coordinate and where they are, drawn first from the block's generator without the
/// others (exact in distribution; David and Nagaraja, "Order statistics", 3rd ed., 2003,
/// Sec. 2.2 and 2.5): per coordinate, with U, V uniform on (0, 1),
///
/// - the largest b: P(max <= x) = Phi(x)^m, so b = Phi^-1(U^(1/m)), computed from its
///   upper tail 1 - U^(1/m) = -expm1(ln U / m);
/// - the smallest a, of the other m - 1 given b (independent, Phi truncated to x < b):
///   P(min > x) = (1 - Phi(x) / Phi(b))^(m-1), so a = Phi^-1(Phi(b) (1 - V^(1/(m-1))));
/// - the position of b uniform among the m, that of a uniform among the other m - 1.
///
/// Given them, the other m - 2 are independent standard normal deviates conditioned on
/// (a, b): [`Extremes::rest`] draws them (the ziggurat's deviates, each rejected until one
/// lies in (a, b)), so a block drawn as points has exactly these extremes. About 5 times
/// fewer instructions than drawing the 3 m deviates of a block of 64 one by one, and
/// about half the time.
struct Extremes {
    lo: [f64; 3],
    hi: [f64; 3],
    at_lo: [usize; 3],
    at_hi: [usize; 3],
}

impl Extremes {
    fn draw(rng: &mut TrialRng, m: usize) -> Extremes {
        // the generator's outputs first, in the order U, V, the two positions of each
        // coordinate; then the three coordinates' arithmetic side by side (independent
        // chains of logarithms and quantiles the processor overlaps)
        let mut e = Extremes { lo: [0.0; 3], hi: [0.0; 3], at_lo: [0; 3], at_hi: [0; 3] };
        let (mut u, mut v) = ([0.0f64; 3], [0.5f64; 3]);
        for k in 0..3 {
            u[k] = rng.sample(rand::distr::Open01);
            if m > 1 {
                v[k] = rng.sample(rand::distr::Open01);
            }
            e.at_hi[k] = rng.random_range(0..m);
            if m > 1 {
                let j = rng.random_range(0..m - 1);
                e.at_lo[k] = j + usize::from(j >= e.at_hi[k]);
            }
        }
        let t = u.map(|x| x.ln() / m as f64);
        let up = t.map(|x| -x.exp_m1()); // 1 - Phi(b)
        e.hi = up.map(|x| -normal_quantile(x));
        if m == 1 {
            e.lo = e.hi;
            return e;
        }
        let w = v.map(|x| -(x.ln() / (m - 1) as f64).exp_m1());
        for k in 0..3 {
            let below = if up[k] < 0.5 { 1.0 - up[k] } else { t[k].exp() }; // Phi(b)
            e.lo[k] = normal_quantile(below * w[k]).min(e.hi[k]);
        }
        e
    }

    /// The deviate of coordinate `k` of the block's point `j` (the points in order, x, y,
    /// z each): an extreme where it lies, else the next ziggurat deviate in (lo, hi).
    #[inline]
    fn rest(&self, rng: &mut TrialRng, j: usize, k: usize) -> f64 {
        if j == self.at_hi[k] {
            return self.hi[k];
        }
        if j == self.at_lo[k] {
            return self.lo[k];
        }
        if !(self.lo[k] < self.hi[k]) {
            // lo rounded up to hi (b in the far tail, Phi(b) = 1 in f64): no deviate lies
            // strictly between, and the loop below would never end
            return self.lo[k];
        }
        loop {
            let d = normal(rng);
            if d > self.lo[k] && d < self.hi[k] {
                return d;
            }
        }
    }
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
    /// Per feature: do its points come in the dense blocks in its order (then a trial
    /// appends them to an empty buffer instead of writing a zeroed one)?
    appended: Vec<bool>,
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
        let mut next = vec![0usize; plan.features.len()];
        let mut appended = vec![true; plan.features.len()];
        for &(k, pos) in &dests {
            appended[k] &= pos == next[k];
            next[k] += 1;
        }
        for (k, f) in plan.features.iter().enumerate() {
            appended[k] &= next[k] == f.rows.len();
        }
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
        Some(Layout { blocks, order, dest_at, dests, appended, sparse, normals, fixed })
    }

    /// The perturbed points of block `b` (flat, in block order): a dense block's deviates
    /// in order, a sparse block's its [`Extremes`] first, then the others given them
    /// ([`Extremes::rest`]), so the block's extremes are those a trial drew for it.
    fn draw(&self, pts: &[f64], sigma: f64, seed: u64, trial: u64, b: usize) -> Vec<f64> {
        let blk = &self.blocks[b];
        let mut rng = block_rng(seed, trial, b as u64);
        let rows = &self.order[blk.start..blk.end];
        let mut out = Vec::with_capacity(3 * rows.len());
        if blk.feature == DENSE {
            for &i in rows {
                for k in 0..3 {
                    out.push(pts[3 * i + k] + normal(&mut rng) * sigma);
                }
            }
        } else {
            let e = Extremes::draw(&mut rng, rows.len());
            for (j, &i) in rows.iter().enumerate() {
                for k in 0..3 {
                    out.push(pts[3 * i + k] + e.rest(&mut rng, j, k) * sigma);
                }
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
    let mut bufs: Vec<Vec<f64>> = (0..nf)
        .map(|k| match (&lay.sparse[k], lay.appended[k]) {
            (Some(_), _) => Vec::new(),
            (None, true) => Vec::with_capacity(3 * plan.features[k].rows.len()),
            (None, false) => vec![0.0; 3 * plan.features[k].rows.len()],
        })
        .collect();
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
                    if lay.appended[k] {
                        bufs[k].extend_from_slice(&p);
                    } else {
                        bufs[k][3 * pos..3 * pos + 3].copy_from_slice(&p);
                    }
                }
            }
        } else {
            let e = Extremes::draw(&mut rng, blk.end - blk.start);
            bound[b] = [[e.lo[0], e.hi[0]], [e.lo[1], e.hi[1]], [e.lo[2], e.hi[2]]];
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
    fn the_normal_quantile_matches_reference_values() {
        // Phi^-1 by an independent implementation (to 1e-15)
        for (p, x) in [
            (0.5, 0.0),
            (0.975, 1.959963984540054),
            (0.02, -2.053748910631823),
            (0.001, -3.090232306167813),
            (1e-10, -6.361340902404056),
            (1e-300, -37.0470962993612),
            (0.3, -0.5244005127080409),
        ] {
            let q = normal_quantile(p);
            assert!((q - x).abs() <= 2e-15 * x.abs().max(1.0), "{p} {q} {x}");
            // 1 - p is exact for these p
            assert!(p < 1e-3 || (normal_quantile(1.0 - p) + x).abs() <= 2e-15 * x.abs().max(1.0), "{p}");
        }
    }

    /// The two-sample Kolmogorov-Smirnov statistic.
    fn ks(mut a: Vec<f64>, mut b: Vec<f64>) -> f64 {
        a.sort_by(f64::total_cmp);
        b.sort_by(f64::total_cmp);
        let (mut i, mut j, mut d) = (0, 0, 0.0f64);
        while i < a.len() && j < b.len() {
            if a[i] <= b[j] {
                i += 1;
            } else {
                j += 1;
            }
            d = d.max((i as f64 / a.len() as f64 - j as f64 / b.len() as f64).abs());
        }
        d
    }

    #[test]
    fn a_block_drawn_as_points_has_the_extremes_drawn_and_every_deviate_is_standard_normal() {
        for m in [1usize, 2, 3, 5, 64, 100] {
            let n = 20_000 / m.min(8);
            let (mut lo, mut hi, mut lo_ref, mut hi_ref) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            let (mut all, mut all_ref, mut first, mut first_ref) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for t in 0..n as u64 {
                let mut rng = block_rng(3, t, m as u64);
                let e = Extremes::draw(&mut rng, m);
                let d: Vec<[f64; 3]> = (0..m).map(|j| [e.rest(&mut rng, j, 0), e.rest(&mut rng, j, 1), e.rest(&mut rng, j, 2)]).collect();
                for k in 0..3 {
                    let (a, b) = d.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x[k]), b.max(x[k])));
                    assert_eq!((a, b), (e.lo[k], e.hi[k]));
                    assert_eq!((d[e.at_lo[k]][k], d[e.at_hi[k]][k]), (a, b));
                    assert!(m == 1 || e.at_lo[k] != e.at_hi[k]);
                }
                lo.push(e.lo[1]);
                hi.push(e.hi[1]);
                first.push(d[0][2]);
                all.extend(d.iter().map(|x| x[0]));
                // the same from m ziggurat deviates a coordinate
                let mut rng = block_rng(4, t, m as u64);
                let r: Vec<f64> = (0..m).map(|_| normal(&mut rng)).collect();
                lo_ref.push(r.iter().copied().fold(f64::INFINITY, f64::min));
                hi_ref.push(r.iter().copied().fold(f64::NEG_INFINITY, f64::max));
                first_ref.push(r[0]);
                all_ref.extend(r);
            }
            // KS at the 1e-4 level: 2.15 sqrt(2 / n)
            let crit = |k: usize| 2.15 * (2.0 / k as f64).sqrt();
            assert!(ks(lo.clone(), lo_ref) < crit(n), "min m={m}");
            assert!(ks(hi.clone(), hi_ref) < crit(n), "max m={m}");
            assert!(ks(first.clone(), first_ref) < crit(n), "first point m={m}");
            // the pooled deviates are not independent within a block: a looser bound
            assert!(ks(all.clone(), all_ref) < 2.0 * crit(n), "all m={m}");
            // the deviates in (lo, hi) of a block: inside
            assert!(lo.iter().zip(&hi).all(|(a, b)| a <= b));
        }
    }

    #[test]
    fn extremes_rounded_together_draw_the_rest_without_looping() {
        // b far in the tail: Phi(b) is 1 in f64 and the smallest can round up to b; the
        // other deviates then take that value instead of being rejected for ever
        let e = Extremes { lo: [8.3; 3], hi: [8.3; 3], at_lo: [1; 3], at_hi: [0; 3] };
        let mut rng = block_rng(0, 0, 0);
        assert_eq!((0..5).map(|j| e.rest(&mut rng, j, 2)).collect::<Vec<_>>(), vec![8.3; 5]);
    }

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
