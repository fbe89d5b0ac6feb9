//! Closed triangulated grids of a doubly periodic surface (a torus and its bumpy kin):
//! the meshes of the crate's tests and of its timing harness (`examples/profile.rs`),
//! built one way in one place. Not part of the API.

use std::f64::consts::PI;

/// The `nu` x `nv` grid of `at(u, w)` over u, w in [0, 2 pi), closed in both directions:
/// flat vertices (row i, column j at `3 (i nv + j)`) and two triangles a cell, oriented
/// outwards for a torus whose `at` runs u about the axis and w about the tube.
pub fn periodic_grid(nu: usize, nv: usize, at: impl Fn(f64, f64) -> [f64; 3]) -> (Vec<f64>, Vec<u32>) {
    let mut v = Vec::with_capacity(3 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            v.extend(at(2.0 * PI * i as f64 / nu as f64, 2.0 * PI * j as f64 / nv as f64));
        }
    }
    let mut t = Vec::with_capacity(6 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let a = (i * nv + j) as u32;
            let b = (((i + 1) % nu) * nv + j) as u32;
            let c = (((i + 1) % nu) * nv + (j + 1) % nv) as u32;
            let d = (i * nv + (j + 1) % nv) as u32;
            t.extend([a, b, c, a, c, d]);
        }
    }
    (v, t)
}
