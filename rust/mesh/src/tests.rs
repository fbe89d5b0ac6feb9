use crate::align::{best_fit, refine, FitOptions, Frame};
use crate::distance::Query;
use crate::mesh::TriMesh;
use crate::minimax::minimax;
use crate::rigid::Pose;
use gagekit_core::ErrorKind;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A box [-a, a] x [-b, b] x [-c, c], 12 triangles wound outwards.
pub fn box_mesh(h: [f64; 3]) -> (Vec<f64>, Vec<u32>) {
    let mut v = Vec::new();
    for i in 0..8 {
        v.extend([if i & 1 == 0 { -h[0] } else { h[0] }, if i & 2 == 0 { -h[1] } else { h[1] }, if i & 4 == 0 { -h[2] } else { h[2] }]);
    }
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let mut t = Vec::new();
    for q in quads {
        t.extend([q[0], q[1], q[2], q[0], q[2], q[3]]);
    }
    (v, t)
}

/// The exact signed distance of a box of half-sizes h (positive outside).
fn box_sdf(p: [f64; 3], h: [f64; 3]) -> f64 {
    let q = [p[0].abs() - h[0], p[1].abs() - h[1], p[2].abs() - h[2]];
    let out = (q[0].max(0.0).powi(2) + q[1].max(0.0).powi(2) + q[2].max(0.0).powi(2)).sqrt();
    out + q[0].max(q[1]).max(q[2]).min(0.0)
}

fn moved(v: &[f64], pose: &Pose) -> Vec<f64> {
    v.chunks_exact(3).flat_map(|p| pose.apply([p[0], p[1], p[2]])).collect()
}

fn random_pose(rng: &mut ChaCha8Rng, angle: f64, shift: f64) -> Pose {
    let p = [
        rng.random_range(-shift..shift),
        rng.random_range(-shift..shift),
        rng.random_range(-shift..shift),
        rng.random_range(-angle..angle),
        rng.random_range(-angle..angle),
        rng.random_range(-angle..angle),
    ];
    Pose::from_params(&p)
}

#[test]
fn box_distances_match_the_analytic_sdf() {
    let h = [2.0, 1.5, 1.0];
    let (v, t) = box_mesh(h);
    let mesh = TriMesh::new(&v, &t).unwrap();
    assert!(mesh.signed());
    assert!((mesh.topology.volume - 24.0).abs() < 1e-12);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let pts: Vec<f64> = (0..30000).map(|_| rng.random_range(-4.0..4.0)).collect();
    let d = mesh.distances(&pts, &Query::default()).unwrap();
    for (i, p) in pts.chunks_exact(3).enumerate() {
        let e = box_sdf([p[0], p[1], p[2]], h);
        assert!((d.distance[i] - e).abs() < 1e-12, "point {i}: {} vs {e}", d.distance[i]);
    }
}

#[test]
fn inward_wound_mesh_is_turned_outwards() {
    let (v, mut t) = box_mesh([1.0, 1.0, 1.0]);
    for tri in t.chunks_exact_mut(3) {
        tri.swap(1, 2);
    }
    let mesh = TriMesh::new(&v, &t).unwrap();
    assert!(mesh.topology.flipped && mesh.signed());
    let d = mesh.distances(&[0.0, 0.0, 3.0, 0.0, 0.0, 0.5], &Query::default()).unwrap();
    assert!((d.distance[0] - 2.0).abs() < 1e-15 && (d.distance[1] + 0.5).abs() < 1e-15);
}

#[test]
fn open_mesh_gives_unsigned_distances() {
    let (v, t) = box_mesh([1.0, 1.0, 1.0]);
    let mesh = TriMesh::new(&v, &t[..30]).unwrap();
    assert!(!mesh.signed());
    assert!(mesh.topology.reason.as_deref().unwrap().contains("open"));
    let d = mesh.distances(&[0.0, 0.0, 0.5], &Query::default()).unwrap();
    assert!(!d.signed && d.distance[0] > 0.0);
}

#[test]
fn bad_meshes_are_refused() {
    let e = TriMesh::new(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0], &[0, 1, 2]).unwrap_err();
    assert_eq!(e.kind, ErrorKind::DegenerateGeometry);
    let e = TriMesh::new(&[0.0, 0.0, 0.0, 1.0, f64::NAN, 0.0, 2.0, 1.0, 0.0], &[0, 1, 2]).unwrap_err();
    assert_eq!(e.kind, ErrorKind::InvalidInput);
    assert!(e.message.contains("vertex 1"));
    let e = TriMesh::new(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 1.0, 0.0], &[0, 1, 5]).unwrap_err();
    assert_eq!(e.kind, ErrorKind::InvalidInput);
    let e = TriMesh::new(&[0.0; 9], &[] as &[u32]).unwrap_err();
    assert!(e.message.contains("no triangles"));
    let (v, t) = box_mesh([1.0, 1.0, 1.0]);
    let mesh = TriMesh::new(&v, &t).unwrap();
    assert_eq!(mesh.distances(&[f64::NAN, 0.0, 0.0], &Query::default()).unwrap_err().kind, ErrorKind::InvalidInput);
    // the first bad point is named, however many blocks the parallel check reads (bad
    // points in several blocks, an infinity after the first NaN); a ragged buffer is refused
    let mut pts: Vec<f64> = (0..3 * 20_000).map(|i| (i % 7) as f64 * 0.1).collect();
    pts[3 * 15_000 + 2] = f64::NAN;
    pts[3 * 9_001 + 1] = f64::INFINITY;
    pts[3 * 19_000] = f64::NAN;
    let e = mesh.distances(&pts, &Query::default()).unwrap_err();
    assert_eq!(e.kind, ErrorKind::InvalidInput);
    assert!(e.message.contains("point 9001 "), "{}", e.message);
    pts[3 * 5] = f64::NEG_INFINITY;
    assert!(mesh.distances(&pts, &Query::default()).unwrap_err().message.contains("point 5 "));
    assert_eq!(mesh.distances(&[0.0; 4], &Query::default()).unwrap_err().kind, ErrorKind::InvalidInput);
    // bad vertices and triangle indices: the first is named
    let mut v = v.clone();
    let n_v = v.len() / 3;
    v[3 * (n_v - 1)] = f64::NAN;
    v[3 * 2 + 1] = f64::INFINITY;
    assert!(TriMesh::new(&v, &t).unwrap_err().message.contains("vertex 2 "));
    let (v, mut t) = box_mesh([1.0, 1.0, 1.0]);
    let last = t.len() - 1;
    t[last] = 99;
    t[4] = 77;
    let e = TriMesh::new(&v, &t).unwrap_err();
    assert!(e.message.contains("triangle 1 names vertex 77"), "{}", e.message);
    // i64 indices (numpy's): the same mesh as from u32; one no u32 can hold is named by its value
    let (v, t) = box_mesh([1.0, 2.0, 3.0]);
    let wide: Vec<i64> = t.iter().map(|&k| k as i64).collect();
    let (a, b) = (TriMesh::new(&v, &t).unwrap(), TriMesh::new(&v, &wide).unwrap());
    assert_eq!((a.triangles.clone(), a.bvh.order.clone(), a.edge_normals.clone(), a.topology.clone()), (b.triangles, b.bvh.order, b.edge_normals, b.topology));
    for (at, bad) in [(5usize, -1i64), (7, 1i64 << 32), (4, u32::MAX as i64), (8, i64::MIN)] {
        let mut w = wide.clone();
        w[at] = bad;
        w[10] = -2;
        let e = TriMesh::new(&v, &w).unwrap_err();
        assert_eq!(e.kind, ErrorKind::InvalidInput);
        assert!(e.message.contains(&format!("triangle {} names vertex {bad},", at / 3)), "{}", e.message);
    }
}

#[test]
fn max_distance_leaves_far_points_apart() {
    let (v, t) = box_mesh([1.0, 1.0, 1.0]);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let q = Query { max_distance: Some(0.5), ..Default::default() };
    let d = mesh.distances(&[0.0, 0.0, 1.2, 0.0, 0.0, 3.0], &q).unwrap();
    assert_eq!(d.beyond, 1);
    assert_eq!(d.triangle[1], -1);
    assert!((d.distance[0] - 0.2).abs() < 1e-15);
}

/// The output arrays are allocated zeroed, not filled with -1 / NaN: every point's entry
/// must be written by the query. Points beyond `max_distance` (triangle -1, distance NaN)
/// interleaved with near ones, over several chunks with a partial last group, in the
/// points' own order and shuffled (the Morton order, back to input order), with feet.
#[test]
fn every_output_entry_is_written() {
    let (v, t) = box_mesh([1.0, 1.0, 1.0]);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let n = 2 * crate::distance::CHUNK + 3;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for shuffle in [false, true] {
        // a scan line along x (coherent), every third point far above the box
        let mut idx: Vec<usize> = (0..n).collect();
        if shuffle {
            for i in (1..n).rev() {
                idx.swap(i, rng.random_range(0..=i));
            }
        }
        let pts: Vec<f64> = idx.iter().flat_map(|&i| [-0.9 + 1.8 * i as f64 / n as f64, 0.1, if i % 3 == 0 { 5.0 } else { 1.1 }]).collect();
        for foot in [false, true] {
            let q = Query { max_distance: Some(0.5), foot, ..Default::default() };
            let d = mesh.distances(&pts, &q).unwrap();
            assert_eq!(d.beyond, (0..n).filter(|i| i % 3 == 0).count());
            for (k, &i) in idx.iter().enumerate() {
                if i % 3 == 0 {
                    assert_eq!(d.triangle[k], -1, "point {k}");
                    assert!(d.distance[k].is_nan());
                    assert!(!foot || d.foot[3 * k..3 * k + 3].iter().all(|x| x.is_nan()));
                } else {
                    assert!(d.triangle[k] >= 0, "point {k}");
                    assert!((d.distance[k] - 0.1).abs() < 1e-12, "point {k}: {}", d.distance[k]);
                    assert!(!foot || (d.foot[3 * k + 2] - 1.0).abs() < 1e-12);
                }
            }
        }
    }
}

fn sphere_mesh(n: usize, r: f64) -> (Vec<f64>, Vec<u32>) {
    // a UV sphere: n rings, 2n segments
    let mut v = vec![0.0, 0.0, r];
    for i in 1..n {
        let th = std::f64::consts::PI * i as f64 / n as f64;
        for j in 0..2 * n {
            let ph = std::f64::consts::PI * j as f64 / n as f64;
            v.extend([r * th.sin() * ph.cos(), r * th.sin() * ph.sin(), r * th.cos()]);
        }
    }
    v.extend([0.0, 0.0, -r]);
    let m = 2 * n as u32;
    let last = (v.len() / 3 - 1) as u32;
    let mut t = Vec::new();
    for j in 0..m {
        t.extend([0, 1 + j, 1 + (j + 1) % m]);
    }
    for i in 0..(n as u32 - 2) {
        for j in 0..m {
            let a = 1 + i * m + j;
            let b = 1 + i * m + (j + 1) % m;
            t.extend([a, a + m, b + m, a, b + m, b]);
        }
    }
    let base = 1 + (n as u32 - 2) * m;
    for j in 0..m {
        t.extend([base + j, last, base + (j + 1) % m]);
    }
    (v, t)
}

/// Vertices no triangle names (more vertices than triangles: the pseudonormals get a
/// vector of their own) leave every normal of the others as it was, and get none.
#[test]
fn unused_vertices_leave_the_normals_unchanged() {
    let (v, t) = sphere_mesh(12, 5.0);
    let a = TriMesh::new(&v, &t).unwrap();
    let mut w = v.clone();
    w.extend((0..3 * 2000).map(|i| i as f64 * 1e-3));
    let b = TriMesh::new(&w, &t).unwrap();
    assert!(w.len() / 3 > t.len() / 3 && v.len() / 3 < t.len() / 3);
    let bits = |x: &[[f64; 3]]| x.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&b.vertex_normals[..v.len() / 3]), bits(&a.vertex_normals));
    assert!(b.vertex_normals[v.len() / 3..].iter().all(|n| *n == [0.0; 3]));
    assert_eq!(bits(&b.edge_normals.concat()), bits(&a.edge_normals.concat()));
    assert!(a.vertex_normals.iter().all(|n| n.iter().any(|c| *c != 0.0)));
}

/// The area is the sum of the triangles' in triangle order; degenerate triangles (a
/// repeated corner, collinear corners) are refused by index, the first five named.
#[test]
fn degenerate_triangles_are_named_and_the_area_summed() {
    let (v, t) = box_mesh([1.0, 2.0, 3.0]);
    let m = TriMesh::new(&v, &t).unwrap();
    let mut area = 0.0;
    for c in t.chunks_exact(3) {
        let p = |k: usize| [v[3 * c[k] as usize], v[3 * c[k] as usize + 1], v[3 * c[k] as usize + 2]];
        let n = gagekit_gdt::vec3::cross(gagekit_gdt::vec3::sub(p(1), p(0)), gagekit_gdt::vec3::sub(p(2), p(0)));
        area += 0.5 * gagekit_gdt::vec3::norm(n);
    }
    assert_eq!(m.area.to_bits(), area.to_bits());
    assert!((m.area - 8.0 * (2.0 + 6.0 + 3.0)).abs() < 1e-12);
    let mut bad_v = v.clone();
    // a vertex on the line of two others: triangle 12 flat
    bad_v.extend([0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0]);
    let nv = (bad_v.len() / 3) as u32;
    let mut bad_t = t.clone();
    bad_t.extend([nv - 3, nv - 2, nv - 1]);
    bad_t[3 * 4 + 2] = bad_t[3 * 4];
    let e = TriMesh::new(&bad_v, &bad_t).unwrap_err();
    assert_eq!(e.kind, ErrorKind::DegenerateGeometry);
    assert!(e.message.contains("2 degenerate triangle(s)") && e.message.contains("first: 4, 12"), "{}", e.message);
}

/// The topology's counts and the edge normals, against a map of every undirected edge
/// to its (triangle, k) in triangle order: closed, open, non-manifold (a fin, a repeated
/// triangle) and inconsistently wound meshes, and closed and open meshes wound inwards
/// (the edge normals are the sums of the face normals as read: turned, or as given), with
/// an unused vertex and vertices in several of the sort's blocks.
#[test]
fn edge_groups_equal_a_map_of_the_edges() {
    let (v, t) = sphere_mesh(50, 10.0);
    let nt = t.len() / 3;
    let mut open = t.clone();
    open.drain(3 * 100..3 * 103);
    let mut fin_v = v.clone();
    fin_v.extend([30.0, 0.0, 0.0, 31.0, 1.0, 2.0]);
    let far = (fin_v.len() / 3 - 2) as u32;
    let mut fin = t.clone();
    fin.extend([t[3 * 7], t[3 * 7 + 1], far]);
    let mut twice = t.clone();
    twice.extend_from_slice(&t[3 * 40..3 * 41]);
    let mut flipped = t.clone();
    flipped.swap(3 * 50, 3 * 50 + 1);
    // wound inwards: closed (read turned outwards), and open (read as given)
    let inward: Vec<u32> = t.chunks_exact(3).flat_map(|c| [c[0], c[2], c[1]]).collect();
    let mut inward_open = inward.clone();
    inward_open.drain(3 * 200..3 * 201);
    let cases: [(&[f64], &[u32]); 7] = [(&v, &t), (&v, &open), (&fin_v, &fin), (&v, &twice), (&v, &flipped), (&v, &inward), (&v, &inward_open)];
    for (case, (v, t)) in cases.into_iter().enumerate() {
        let m = TriMesh::new(v, t).unwrap();
        assert_eq!(m.topology.flipped, case == 5, "case {case}");
        // the face normals: as wound, or turned for the closed inward mesh
        let c = &t[3 * 9..3 * 9 + 3];
        let p = |k: usize| [v[3 * c[k] as usize], v[3 * c[k] as usize + 1], v[3 * c[k] as usize + 2]];
        let wound = gagekit_gdt::vec3::cross(gagekit_gdt::vec3::sub(p(1), p(0)), gagekit_gdt::vec3::sub(p(2), p(0)));
        assert_eq!(gagekit_gdt::vec3::dot(wound, m.face_normals[9]) > 0.0, case != 5, "case {case}");
        let mut map = std::collections::BTreeMap::<(u32, u32), Vec<(usize, usize)>>::new();
        for (i, c) in t.chunks_exact(3).enumerate() {
            for k in 0..3 {
                let (a, b) = (c[k], c[(k + 1) % 3]);
                map.entry((a.min(b), a.max(b))).or_default().push((i, k));
            }
        }
        let (mut boundary, mut nonmanifold, mut inconsistent) = (0, 0, 0);
        for (&(lo, _), g) in &map {
            match g.len() {
                1 => boundary += 1,
                2 => inconsistent += usize::from((t[3 * g[0].0 + g[0].1] == lo) == (t[3 * g[1].0 + g[1].1] == lo)),
                _ => nonmanifold += 1,
            }
            let mut sum = [0.0; 3];
            for &(i, _) in g {
                sum = gagekit_gdt::vec3::add(sum, m.face_normals[i]);
            }
            for &(i, k) in g {
                assert_eq!(m.edge_normals[i][k].map(f64::to_bits), sum.map(f64::to_bits), "case {case}, triangle {i}, edge {k}");
            }
        }
        assert_eq!((m.topology.boundary_edges, m.topology.nonmanifold_edges), (boundary, nonmanifold), "case {case}");
        let reason = m.topology.reason.clone().unwrap_or_default();
        assert_eq!(m.signed(), boundary + nonmanifold + inconsistent == 0, "case {case}: {reason}");
        if boundary + nonmanifold == 0 && inconsistent > 0 {
            assert!(reason.contains(&format!("({inconsistent} edges)")), "case {case}: {reason}");
        }
        assert_eq!([boundary > 0, nonmanifold > 0, inconsistent > 0], [[false; 3], [true, false, false], [true, true, false], [false, true, false], [false, false, true], [false; 3], [true, false, false]][case], "case {case}");
    }
    assert!(nt > 9000 && v.len() / 3 > 4096);
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let (v, t) = sphere_mesh(60, 10.0);
    let mesh = TriMesh::new(&v, &t).unwrap();
    assert!(mesh.signed());
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pts: Vec<f64> = (0..60000).map(|_| rng.random_range(-12.0..12.0)).collect();
    let q = Query { foot: true, ..Default::default() };
    // the tree itself does not depend on the thread count (its build is parallel above 4096 triangles)
    let (v2, t2) = sphere_mesh(120, 10.0);
    let b1 = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| TriMesh::new(&v2, &t2).unwrap());
    let b3 = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(|| TriMesh::new(&v2, &t2).unwrap());
    assert_eq!(b1.bvh.order, b3.bvh.order);
    assert_eq!(b1.bvh.nodes.iter().map(|n| n.child).collect::<Vec<_>>(), b3.bvh.nodes.iter().map(|n| n.child).collect::<Vec<_>>());
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| mesh.distances(&pts, &q).unwrap());
    let two = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(|| mesh.distances(&pts, &q).unwrap());
    assert_eq!(one.distance.iter().map(|d| d.to_bits()).collect::<Vec<_>>(), two.distance.iter().map(|d| d.to_bits()).collect::<Vec<_>>());
    assert_eq!(one.triangle, two.triangle);
    // brute force on a subset: the same distance
    for i in (0..20000).step_by(97) {
        let p = [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]];
        let best = (0..mesh.bvh.corners.len() as u32).map(|s| mesh.bvh.to_slot(p, s).d2).fold(f64::INFINITY, f64::min);
        assert!((one.distance[i].abs() - best.sqrt()).abs() < 1e-12);
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert_eq!(one.distance[i] > 0.0, r > 10.0 || one.distance[i] > 0.0 && r > 9.9, "sign at r = {r}");
    }
}

fn box_scan(h: [f64; 3], step: f64, bump: f64) -> Vec<f64> {
    // points on the faces of the box, offset along the outward normal by a smooth bump
    let mut pts = Vec::new();
    for axis in 0..3 {
        for side in [-1.0, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let nu = (2.0 * h[u] / step) as i64;
            let nv = (2.0 * h[v] / step) as i64;
            for i in 1..nu {
                for j in 1..nv {
                    let mut p = [0.0; 3];
                    p[u] = -h[u] + i as f64 * step;
                    p[v] = -h[v] + j as f64 * step;
                    let dev = bump * (p[u] * 1.3 + axis as f64).sin() * (p[v] * 0.7 + side).cos();
                    p[axis] = side * (h[axis] + dev);
                    pts.extend(p);
                }
            }
        }
    }
    pts
}

#[test]
fn best_fit_undoes_a_rigid_motion() {
    let h = [20.0, 12.0, 7.0];
    let (v, t) = box_mesh(h);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let scan = box_scan(h, 0.8, 0.01);
    let truth = mesh.distances(&scan, &Query::default()).unwrap().distance;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..3 {
        let pose = random_pose(&mut rng, 3.0, 50.0);
        let moved_scan = moved(&scan, &pose);
        let fit = best_fit(&mesh, &moved_scan, &FitOptions::default()).unwrap();
        let back = moved(&moved_scan, &fit.pose);
        let d = mesh.distances(&back, &Query::default()).unwrap().distance;
        let worst = d.iter().zip(&truth).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-3, "largest change of a deviation {worst}");
        assert!(fit.rms_after < fit.rms_before);
    }
}

#[test]
fn minimax_is_certified_and_below_the_best_fit() {
    let h = [20.0, 12.0, 7.0];
    let (v, t) = box_mesh(h);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let scan = box_scan(h, 1.0, 0.02);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let pose = random_pose(&mut rng, 0.01, 0.2);
    let s = moved(&scan, &pose);
    let fit = best_fit(&mesh, &s, &FitOptions::default()).unwrap();
    let bf_max = mesh.distances(&moved(&s, &fit.pose), &Query::default()).unwrap().distance.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let mm = minimax(&mesh, &s, fit.pose, [true; 6], None, 0.0).unwrap();
    let check = mesh.distances(&moved(&s, &mm.pose), &Query::default()).unwrap().distance.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    assert!((check - mm.max_abs).abs() < 1e-12);
    assert!(mm.max_abs <= bf_max + 1e-12, "{} > {}", mm.max_abs, bf_max);
    assert!((mm.max_abs - mm.lp_optimum).abs() < 1e-8 * (1.0 + mm.max_abs), "{} vs {}", mm.max_abs, mm.lp_optimum);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// A moved box: every distance equals the box's analytic SDF in its own frame (1e-9).
    #[test]
    fn moved_box_distances_are_exact(seed in 0u64..1_000_000, hx in 0.5f64..50.0, hy in 0.5f64..50.0, hz in 0.5f64..50.0) {
        let h = [hx, hy, hz];
        let (v, t) = box_mesh(h);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let pose = random_pose(&mut rng, 3.0, 100.0);
        let mesh = TriMesh::new(&moved(&v, &pose), &t).unwrap();
        let local: Vec<f64> = (0..600).map(|k| rng.random_range(-2.0..2.0) * h[k % 3]).collect();
        let d = mesh.distances(&moved(&local, &pose), &Query::default()).unwrap();
        for (i, p) in local.chunks_exact(3).enumerate() {
            let e = box_sdf([p[0], p[1], p[2]], h);
            prop_assert!((d.distance[i] - e).abs() < 1e-9, "{} vs {}", d.distance[i], e);
        }
    }

    /// Moving the points and the mesh together leaves every distance unchanged.
    #[test]
    fn distances_are_invariant_under_rigid_motion(seed in 0u64..1_000_000) {
        let (v, t) = sphere_mesh(12, 5.0);
        let mesh = TriMesh::new(&v, &t).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let pts: Vec<f64> = (0..300).map(|_| rng.random_range(-7.0..7.0)).collect();
        let pose = random_pose(&mut rng, 3.0, 100.0);
        let a = mesh.distances(&pts, &Query::default()).unwrap().distance;
        let mesh2 = TriMesh::new(&moved(&v, &pose), &t).unwrap();
        let b = mesh2.distances(&moved(&pts, &pose), &Query::default()).unwrap().distance;
        for (x, y) in a.iter().zip(&b) {
            prop_assert!((x - y).abs() < 1e-9);
        }
    }
}

#[test]
fn minimax_with_an_offset_centres_the_zone_on_the_offset_surface() {
    let h = [20.0, 12.0, 7.0];
    let (v, t) = box_mesh(h);
    let mesh = TriMesh::new(&v, &t).unwrap();
    // the scan is the box grown by 0.05 everywhere (plus bumps of 0.01): offset 0.05 leaves 0.01
    let scan = box_scan([h[0] + 0.05, h[1] + 0.05, h[2] + 0.05], 1.0, 0.01);
    let m0 = minimax(&mesh, &scan, Pose::IDENTITY, [true; 6], None, 0.0).unwrap();
    let m1 = minimax(&mesh, &scan, Pose::IDENTITY, [true; 6], None, 0.05).unwrap();
    assert!(m0.max_abs > 0.05 && m1.max_abs <= 0.0100001, "{} {}", m0.max_abs, m1.max_abs);
}

/// A triangle soup: `n` random triangles in [-10, 10]^3, a share of them slivers (a
/// corner within 1e-7 of the opposite edge's line) and needles (two corners 1e-7 apart),
/// plus a heightfield patch whose triangles share edges and vertices (ties).
fn soup(rng: &mut ChaCha8Rng, n: usize) -> Vec<[[f64; 3]; 3]> {
    let mut out = Vec::new();
    let r = |rng: &mut ChaCha8Rng, s: f64| -> [f64; 3] { [rng.random_range(-s..s), rng.random_range(-s..s), rng.random_range(-s..s)] };
    for _ in 0..n {
        let c = r(rng, 10.0);
        let size = [0.01, 0.3, 3.0][rng.random_range(0..3)];
        let a = gagekit_gdt::vec3::add(c, r(rng, size));
        let b = gagekit_gdt::vec3::add(c, r(rng, size));
        let kind = rng.random_range(0..4);
        let third = match kind {
            // sliver: near the line through a and b
            0 => {
                let t: f64 = rng.random_range(-0.5..1.5);
                gagekit_gdt::vec3::add([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])], r(rng, 1e-7))
            }
            // needle: next to a
            1 => gagekit_gdt::vec3::add(a, r(rng, 1e-7)),
            _ => gagekit_gdt::vec3::add(c, r(rng, size)),
        };
        out.push([a, b, third]);
    }
    // a heightfield patch: shared edges and vertices
    let z = |i: usize, j: usize| ((i * 7 + j * 3) % 5) as f64 * 0.1;
    for i in 0..6 {
        for j in 0..6 {
            let p = |a: usize, b: usize| [a as f64, b as f64, z(a, b)];
            out.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            out.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    out
}

fn brute_force(corners: &[[[f64; 3]; 3]], p: [f64; 3]) -> f64 {
    corners
        .iter()
        .map(|c| {
            let (f, _) = crate::closest::closest_point(p, c[0], c[1], c[2]);
            let v = [p[0] - f[0], p[1] - f[1], p[2] - f[2]];
            v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        })
        .fold(f64::INFINITY, f64::min)
}

/// Brute force over a hierarchy's slots: the least squared distance within `bound2`, then
/// the lowest slot (the tie rule of the searches).
fn brute_force_slot(bvh: &crate::bvh::Bvh, q: [f64; 3], bound2: f64) -> Option<(f64, u32)> {
    let mut want: Option<(f64, u32)> = None;
    for (slot, c) in bvh.corners.iter().enumerate() {
        let d2 = brute_force(&[*c], q);
        if d2 <= bound2 && want.map_or(true, |(w, _)| d2 < w) {
            want = Some((d2, slot as u32));
        }
    }
    want
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]
    /// The BVH's nearest triangle has exactly the squared distance of a brute-force scan
    /// over every triangle (random soups with slivers, needles and shared edges; points
    /// near, inside and far away; with and without a hint and a bound).
    #[test]
    fn bvh_nearest_equals_brute_force(seed in 0u64..1_000_000, n in 1usize..400) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let corners = soup(&mut rng, n);
        let bvh = crate::bvh::Bvh::new(&corners);
        prop_assert!(bvh.depth() <= crate::bvh::MAX_DEPTH);
        let mut hint = None;
        for k in 0..300 {
            let s = [0.5, 12.0, 1e3, 1e6][k % 4];
            let p = [rng.random_range(-s..s), rng.random_range(-s..s), rng.random_range(-s..s)];
            let exact = brute_force(&corners, p);
            let got = bvh.nearest(p, f64::INFINITY, hint).unwrap();
            prop_assert_eq!(got.d2.to_bits(), exact.to_bits(), "point {:?}: {} vs {}", p, got.d2, exact);
            let t = bvh.order[got.slot as usize] as usize;
            prop_assert_eq!(brute_force(&corners[t..t + 1], p).to_bits(), exact.to_bits());
            // a bound: found exactly when the nearest is within it
            let bound2 = exact * [0.5, 1.0, 2.0][k % 3];
            match bvh.nearest(p, bound2, hint) {
                Some(b) => prop_assert!(b.d2.to_bits() == exact.to_bits() && exact <= bound2),
                None => prop_assert!(exact > bound2),
            }
            hint = if k % 5 == 0 { None } else { Some(got.slot) };
        }
    }
}

/// The same through the mesh's distance query: a closed mesh of slivers (a fine fan on a
/// sphere's pole cap) against brute force, points near and far, any thread count.
#[test]
fn mesh_distances_equal_brute_force_with_slivers() {
    let (mut v, t) = sphere_mesh(40, 10.0);
    // squash the rings next to the poles: the triangles there become slivers
    for p in v.chunks_exact_mut(3) {
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        if r < 1.0 {
            p[0] *= 1e-5;
            p[1] *= 1e-5;
        }
    }
    let mesh = TriMesh::new(&v, &t).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut pts = Vec::new();
    for k in 0..20000 {
        let s = [11.0, 1e4][k % 2];
        pts.extend([rng.random_range(-s..s), rng.random_range(-s..s), rng.random_range(-s..s)]);
    }
    let d = mesh.distances(&pts, &Query::default()).unwrap();
    for (i, p) in pts.chunks_exact(3).enumerate() {
        let exact = brute_force(&mesh.bvh.corners, [p[0], p[1], p[2]]).sqrt();
        assert!((d.distance[i].abs() - exact).abs() <= 1e-12 * (1.0 + exact), "point {i}: {} vs {exact}", d.distance[i]);
    }
}

/// Coarse to fine (subsamples first, then every point) ends where iterating on every
/// point from the start ends: the whole cloud's robust fit, to 1e-6 mm on every point.
#[test]
fn coarse_to_fine_equals_the_full_robust_fit() {
    let h = [20.0, 12.0, 7.0];
    let (v, t) = box_mesh(h);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let mut scan = box_scan(h, 0.25, 0.01);
    // clutter: every 50th point 2 mm off the surface
    for (i, p) in scan.chunks_exact_mut(3).enumerate() {
        if i % 50 == 0 {
            p[2] += 2.0;
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let pose = random_pose(&mut rng, 0.02, 0.5);
    let s = moved(&scan, &pose);
    let n = s.len() / 3;
    assert!(n > 40_000);
    let frame = Frame::new(&mesh, &s, Pose::IDENTITY, None, [true; 6]).unwrap();
    let mut p_full = [0.0; 6];
    let (full, _) = refine(&frame, &mut p_full, &[usize::MAX]).unwrap();
    let mut p_ladder = [0.0; 6];
    let (ladder, it) = refine(&frame, &mut p_ladder, &[3000, 10_000, 30_000, usize::MAX]).unwrap();
    let (a, b) = (moved(&s, &frame.pose(&p_full)), moved(&s, &frame.pose(&p_ladder)));
    let worst = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-6, "largest displacement between the two fits {worst} mm");
    assert!((full.rms - ladder.rms).abs() < 1e-9 && full.used == ladder.used);
    assert!(ladder.iterations < full.iterations, "{} full-cloud steps after the ladder ({it} in all) vs {}", ladder.iterations, full.iterations);
    // and best_fit (which runs the ladder on its winning start) lands there too
    let fit = best_fit(&mesh, &s, &FitOptions::default()).unwrap();
    let c = moved(&s, &fit.pose);
    let worst = a.iter().zip(&c).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-6, "best_fit vs the full fit: {worst} mm");
}

/// The query order (input order for scan lines, a Morton sort otherwise) changes no
/// result: a scan-line cloud and the same points shuffled give the same distance, to the
/// bit, and the same triangle per point.
#[test]
fn shuffled_points_give_the_same_distances() {
    let (v, t) = sphere_mesh(50, 10.0);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let mut pts = Vec::new();
    for i in 0..300 {
        for j in 0..600 {
            let (th, ph) = (std::f64::consts::PI * (i as f64 + 0.5) / 300.0, std::f64::consts::PI * j as f64 / 300.0);
            let r = 10.0 + 0.05 * ((i * 7 + j * 13) % 11) as f64 - 0.25;
            pts.extend([r * th.sin() * ph.cos(), r * th.sin() * ph.sin(), r * th.cos()]);
        }
    }
    let n = pts.len() / 3;
    assert!(crate::distance::query_order(&pts).is_none(), "scan lines keep their order");
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let mut perm: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        perm.swap(i, rng.random_range(0..=i));
    }
    let shuffled: Vec<f64> = perm.iter().flat_map(|&i| [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]]).collect();
    let mut order = crate::distance::query_order(&shuffled).expect("a shuffled cloud is sorted");
    assert!(order != (0..n as u32).collect::<Vec<_>>(), "a shuffled cloud is sorted");
    order.sort_unstable();
    assert!(order == (0..n as u32).collect::<Vec<_>>(), "a permutation");
    let a = mesh.distances(&pts, &Query::default()).unwrap();
    let b = mesh.distances(&shuffled, &Query::default()).unwrap();
    for (k, &i) in perm.iter().enumerate() {
        assert!(a.distance[i].to_bits() == b.distance[k].to_bits() && a.triangle[i] == b.triangle[k], "point {i}: {} vs {}", a.distance[i], b.distance[k]);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// Points walking the tree in groups get, each, the single search's answer to the
    /// bit (triangle, squared distance, closest point, feature) and the brute force's
    /// least squared distance, the lowest slot among exact ties; whatever their starts
    /// (none, the previous group's triangles, a random one) and bound. Points are
    /// coherent (a walk) or scattered, on soups with shared edges (exact ties).
    #[test]
    fn group_queries_equal_the_single_search(seed in 0u64..1_000_000, n in 1usize..300, step in 1e-4f64..3.0) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let corners = soup(&mut rng, n);
        let bvh = crate::bvh::Bvh::new(&corners);
        let mut p = [rng.random_range(-12.0..12.0), rng.random_range(-12.0..12.0), rng.random_range(-12.0..12.0)];
        for round in 0..30 {
            let g = rng.random_range(1..=crate::bvh::GROUP);
            let mut ps = Vec::new();
            for _ in 0..g {
                for k in 0..3 {
                    p[k] += rng.random_range(-step..step);
                }
                ps.push(if rng.random_range(0.0..1.0) < 0.1 { [rng.random_range(-20.0..20.0), 0.5, 0.5] } else { p });
            }
            let bound2 = [f64::INFINITY, 0.25, 4.0][round % 3];
            let mut best: Vec<Option<crate::bvh::Nearest>> = ps
                .iter()
                .map(|&q| match round % 4 {
                    0 => None,
                    _ => Some(bvh.to_slot(q, rng.random_range(0..bvh.corners.len() as u32))),
                })
                .collect();
            // hints measured for every lane at once (some out of range, some repeated)
            let hints: Vec<u32> = (0..rng.random_range(0..4)).map(|_| rng.random_range(0..bvh.corners.len() as u32 + 2)).collect();
            let builds = bvh.nearest_group_every_build(&ps, bound2, &hints, &best);
            bvh.nearest_group_from(&ps, bound2, &hints, &mut best);
            // every build (plain, AVX2, AVX-512, as the processor has them) gives the same bits
            let bits = |b: &Option<crate::bvh::Nearest>| b.map(|n| (n.slot, n.d2.to_bits(), n.foot.map(f64::to_bits), n.feature));
            for other in &builds {
                prop_assert_eq!(other.iter().map(bits).collect::<Vec<_>>(), best.iter().map(bits).collect::<Vec<_>>());
            }
            for (q, got) in ps.iter().zip(&best) {
                let single = bvh.nearest(*q, bound2, None);
                let want = brute_force_slot(&bvh, *q, bound2);
                match (got, single, want) {
                    (Some(a), Some(b), Some((d2, slot))) => {
                        prop_assert_eq!((a.slot, a.d2.to_bits()), (b.slot, b.d2.to_bits()));
                        prop_assert_eq!(a.foot.map(f64::to_bits), b.foot.map(f64::to_bits));
                        prop_assert_eq!(a.feature, b.feature);
                        prop_assert_eq!((a.slot, a.d2.to_bits()), (slot, d2.to_bits()));
                    }
                    (None, None, None) => {}
                    (a, b, w) => prop_assert!(false, "group {:?}, single {:?}, brute force {:?}", a.map(|x| x.slot), b.map(|x| x.slot), w),
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// A cached query (a point walking in small and large steps, its triangle certified by
    /// the margin when it can be) gives the plain search's answer from the same hint, to
    /// the bit: the same triangle, distance, closest point and feature.
    #[test]
    fn cached_queries_equal_the_search(seed in 0u64..1_000_000, n in 1usize..300, step in 1e-6f64..2.0) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let corners = soup(&mut rng, n);
        let v: Vec<f64> = corners.iter().flat_map(|c| c.iter().flatten().copied()).collect();
        let t: Vec<u32> = (0..3 * corners.len() as u32).collect();
        let Ok(mesh) = TriMesh::new(&v, &t) else { return Ok(()) };
        let mut cache = crate::distance::Cache::EMPTY;
        let mut p = [rng.random_range(-12.0..12.0), rng.random_range(-12.0..12.0), rng.random_range(-12.0..12.0)];
        for _ in 0..60 {
            let hint = (cache.slot != u32::MAX).then_some(cache.slot);
            let plain = mesh.hit(p, f64::INFINITY, hint, false).unwrap();
            let cached = mesh.hit_cached(p, f64::INFINITY, &mut cache, false).unwrap();
            prop_assert_eq!(plain.slot, cached.slot);
            prop_assert_eq!(plain.distance.to_bits(), cached.distance.to_bits());
            prop_assert_eq!(plain.foot.map(f64::to_bits), cached.foot.map(f64::to_bits));
            prop_assert_eq!(plain.feature, cached.feature);
            let s = if rng.random_range(0.0..1.0) < 0.8 { step * 1e-3 } else { step };
            for k in 0..3 {
                p[k] += rng.random_range(-s..s);
            }
        }
    }
}

/// On a closed mesh, points on and near the edges and vertices two or more triangles
/// share (the cache's runner-up certifies an edge's tie), walking in tiny steps: every
/// cached query gives the plain search's triangle, distance and closest point to the bit,
/// and some queries are certified by the pair (the runner-up path is exercised).
#[test]
fn cached_queries_at_shared_edges_equal_the_search() {
    let (v, t) = sphere_mesh(12, 10.0);
    let mesh = TriMesh::new(&v, &t).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (mut searched, mut walked) = (0usize, 0usize);
    for k in 0..t.len() / 3 {
        // the midpoint of an edge of triangle k, pushed out or in along the radius
        let (a, b) = (t[3 * k] as usize, t[3 * k + 1] as usize);
        let mid = [(v[3 * a] + v[3 * b]) / 2.0, (v[3 * a + 1] + v[3 * b + 1]) / 2.0, (v[3 * a + 2] + v[3 * b + 2]) / 2.0];
        let s = 1.0 + rng.random_range(-0.05..0.05);
        let mut p = [mid[0] * s, mid[1] * s, mid[2] * s];
        let mut cache = crate::distance::Cache::EMPTY;
        for _ in 0..20 {
            let hint = (cache.slot != u32::MAX).then_some(cache.slot);
            let plain = mesh.hit(p, f64::INFINITY, hint, true).unwrap();
            let before = cache;
            let cached = mesh.hit_cached(p, f64::INFINITY, &mut cache, true).unwrap();
            assert_eq!(plain.slot, cached.slot);
            assert_eq!(plain.distance.to_bits(), cached.distance.to_bits());
            assert_eq!(plain.foot.map(f64::to_bits), cached.foot.map(f64::to_bits));
            assert_eq!(plain.feature, cached.feature);
            if cache.at != before.at {
                searched += 1;
            } else if before.slot != cached.slot {
                walked += 1; // certified as the runner-up
            }
            for x in p.iter_mut() {
                *x += rng.random_range(-1e-4..1e-4);
            }
        }
    }
    assert!(walked > 0, "the runner-up never certified a query ({searched} searches)");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// The leaf test's single-precision lower bound never rejects a triangle at its own
    /// exact squared distance (nor at anything larger), and passes every triangle the
    /// double-precision test of the same planes passes, down to the least best that test
    /// passes; on soups of slivers, needles and shared edges, near the origin and moved
    /// 1e3 and 1e5 away (where single precision's grid is 1e-4 and 1e-2 mm), for points
    /// near, far, very far (1e6, 1e12) and beyond single precision's range. And it does
    /// reject where the bound is clearly below (a point straight above a face, against a
    /// best at half its distance).
    #[test]
    fn triangle_lower_bound_never_exceeds_the_exact_distance(seed in 0u64..1_000_000, n in 1usize..200) {
        use crate::bvh::Planes;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let shift: f64 = [0.0, 1e3, 1e5][(seed % 3) as usize];
        let corners: Vec<[[f64; 3]; 3]> = soup(&mut rng, n).into_iter().map(|c| c.map(|v| [v[0] + shift, v[1] - shift, v[2] + 0.5 * shift])).collect();
        let bvh = crate::bvh::Bvh::new(&corners);
        let planes: Vec<Planes> = bvh.corners.iter().map(Planes::of).collect();
        let (mut tight, mut above) = (0usize, 0usize);
        for k in 0..200 {
            let s: f64 = [0.5, 12.0, 1e3, 1e6, 1e12, 1e39][k % 6];
            let p: [f64; 3] = [shift + rng.random_range(-s..s), rng.random_range(-s..s) - shift, 0.5 * shift + rng.random_range(-s..s)];
            let slack = bvh.slack_at(&p);
            for (slot, c) in bvh.corners.iter().enumerate() {
                let d2 = brute_force(&[*c], p);
                prop_assert!(bvh.bounds[slot].may_beat(&p, d2, slack), "slot {} point {:?} d2 {}", slot, p, d2);
                // the least best the double-precision test passes (its right side
                // best (1 + 1e-12) at its bound, then the next doubles down while it passes)
                let lower = planes[slot].lower(&p, slack);
                if !(lower > 0.0 && lower.is_finite()) {
                    continue;
                }
                let mut best = lower / (1.0 + 1e-12);
                while !planes[slot].may_beat(&p, best, slack) {
                    best = best.next_up();
                }
                while planes[slot].may_beat(&p, best.next_down(), slack) {
                    best = best.next_down();
                }
                prop_assert!(bvh.bounds[slot].may_beat(&p, best, slack), "slot {} point {:?} best {}", slot, p, best);
                tight += 1;
                // and above it: the double-precision test passes, so must this one
                let more = best * [1.0 + 1e-9, 1.001, 4.0][k % 3];
                prop_assert!(!planes[slot].may_beat(&p, more, slack) || bvh.bounds[slot].may_beat(&p, more, slack));
                above += 1;
            }
        }
        prop_assert!(tight > 0 && above > 0);
        // the lanes' form: bit i is lane i's may_beat (random lanes near and far, bests
        // at, below and above their exact distances)
        for k in 0..50 {
            let s: f64 = [0.5, 12.0, 1e3, 1e6][k % 4];
            let mut lanes = [[0.0; crate::bvh::GROUP]; 3];
            let (mut best, mut slack) = ([0.0; crate::bvh::GROUP], [0.0; crate::bvh::GROUP]);
            let slot = rng.random_range(0..bvh.corners.len());
            for i in 0..crate::bvh::GROUP {
                let p: [f64; 3] = [shift + rng.random_range(-s..s), rng.random_range(-s..s) - shift, 0.5 * shift + rng.random_range(-s..s)];
                (lanes[0][i], lanes[1][i], lanes[2][i]) = (p[0], p[1], p[2]);
                slack[i] = bvh.slack_at(&p);
                best[i] = brute_force(&[bvh.corners[slot]], p) * [0.25, 1.0, 4.0, 0.999][rng.random_range(0..4)];
            }
            let b = &bvh.bounds[slot];
            let got = b.may_beat_lanes([&lanes[0], &lanes[1], &lanes[2]], &best, &slack);
            for i in 0..crate::bvh::GROUP {
                let want = b.may_beat(&[lanes[0][i], lanes[1][i], lanes[2][i]], best[i], slack[i]);
                prop_assert_eq!(got >> i & 1 == 1, want, "lane {}", i);
            }
        }
        // above the centroid of a fat triangle of the patch, 1 mm off its plane
        let slot = (0..bvh.corners.len()).rev().find(|&s| (bvh.corners[s][0][0] - shift).fract() == 0.0 && (bvh.corners[s][1][0] - shift).fract() == 0.0).unwrap();
        let c = bvh.corners[slot];
        let b = &bvh.bounds[slot];
        let nrm = planes[slot].n;
        let g = [(c[0][0] + c[1][0] + c[2][0]) / 3.0, (c[0][1] + c[1][1] + c[2][1]) / 3.0, (c[0][2] + c[1][2] + c[2][2]) / 3.0];
        let p = [g[0] + nrm[0], g[1] + nrm[1], g[2] + nrm[2]];
        let d2 = brute_force(&[c], p);
        prop_assert!((d2 - 1.0).abs() < 1e-9 * (1.0 + shift));
        let slack = bvh.slack_at(&p);
        prop_assert!(!b.may_beat(&p, 0.25, slack));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Groups of points near, far and very far (up to 1e6, where single precision is
    /// coarse: the lanes' box tests run in f32 with a widened threshold) get the brute
    /// force's least squared distance and lowest slot, to the bit.
    #[test]
    fn group_queries_of_far_points_equal_brute_force(seed in 0u64..1_000_000, n in 1usize..200) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let corners = soup(&mut rng, n);
        let bvh = crate::bvh::Bvh::new(&corners);
        for round in 0..20 {
            let s: f64 = [0.5, 12.0, 1e3, 1e6][round % 4];
            let c: [f64; 3] = [rng.random_range(-s..s), rng.random_range(-s..s), rng.random_range(-s..s)];
            let ps: Vec<[f64; 3]> = (0..crate::bvh::GROUP)
                .map(|_| [c[0] + rng.random_range(-1e-3..1e-3) * s, c[1] + rng.random_range(-1e-3..1e-3) * s, c[2]])
                .collect();
            let mut best: Vec<Option<crate::bvh::Nearest>> = vec![None; ps.len()];
            bvh.nearest_group(&ps, f64::INFINITY, &mut best);
            // and every build the processor runs (plain, AVX2, AVX-512)
            for best in std::iter::once(best.clone()).chain(bvh.nearest_group_every_build(&ps, f64::INFINITY, &[], &best.iter().map(|_| None).collect::<Vec<_>>())) {
                for (q, got) in ps.iter().zip(&best) {
                    let (d2, slot) = brute_force_slot(&bvh, *q, f64::INFINITY).unwrap();
                    let a = got.unwrap();
                    prop_assert_eq!((a.slot, a.d2.to_bits()), (slot, d2.to_bits()));
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    /// The lanes' comparison masks by AVX instructions equal the plain `<=` lane by lane,
    /// with ties, signed zeros, infinities and NaN among the lanes (run where the
    /// processor has AVX2, as the group query does).
    #[test]
    fn lane_masks_equal_the_plain_comparison(seed in 0u64..1_000_000) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let special = [0.0, -0.0, 1.0, -1.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 1e-300];
        let pick = |rng: &mut ChaCha8Rng| if rng.random_range(0..3) == 0 { special[rng.random_range(0..special.len())] } else { rng.random_range(-2.0..2.0) };
        let (mut a, mut b) = ([0.0f64; crate::bvh::GROUP], [0.0f64; crate::bvh::GROUP]);
        for i in 0..crate::bvh::GROUP {
            a[i] = pick(&mut rng);
            b[i] = if rng.random_range(0..4) == 0 { a[i] } else { pick(&mut rng) };
        }
        let (a32, b32) = (a.map(|x| x as f32), b.map(|x| x as f32));
        let want32 = (0..crate::bvh::GROUP).fold(0u32, |o, i| o | ((a32[i] <= b32[i]) as u32) << i);
        prop_assert_eq!(crate::bvh::lanes_le32::<false>(&a32, &b32), want32);
        // the slots' equality mask, with u32::MAX (no start) among the lanes
        let slots = [0u32, 1, 7, u32::MAX];
        let s: [u32; crate::bvh::GROUP] = std::array::from_fn(|_| slots[rng.random_range(0..slots.len())]);
        let x = slots[rng.random_range(0..slots.len())];
        let want_eq = (0..crate::bvh::GROUP).fold(0u32, |o, i| o | ((s[i] == x) as u32) << i);
        prop_assert_eq!(crate::bvh::lanes_eq::<false>(&s, x), want_eq);
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            prop_assert_eq!(crate::bvh::lanes_le32::<true>(&a32, &b32), want32);
            // SAFETY: lanes_eq::<true> needs AVX2, detected above
            prop_assert_eq!(unsafe { eq_avx2(&s, x) }, want_eq);
        }
    }
}

/// [`crate::bvh::lanes_eq`] compiled for AVX2, as the group query runs it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn eq_avx2(a: &[u32; crate::bvh::GROUP], b: u32) -> u32 {
    crate::bvh::lanes_eq::<true>(a, b)
}

/// [`crate::closest::closest_lanes`] on eight points, lane by lane against
/// [`crate::closest::closest_point`]: the same closest point, feature and squared distance
/// to the bit (also compiled for AVX2 where the processor has it, as the group query runs it).
fn check_lanes(ps: &[[f64; 3]; 8], c: &[[f64; 3]; 3]) -> Result<(), TestCaseError> {
    use crate::closest::{closest_lanes, closest_point, feature_of_code, Closest8, LANES};
    let axes: [[f64; LANES]; 3] = std::array::from_fn(|k| std::array::from_fn(|i| ps[i][k]));
    let mut outs = vec![];
    let mut out = Closest8 { d2: [0.0; LANES], foot: [[0.0; LANES]; 3], code: [0; LANES] };
    closest_lanes([&axes[0], &axes[1], &axes[2]], c[0], c[1], c[2], &mut out);
    outs.push(out);
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 was detected
        unsafe { crate::closest::closest_lanes_avx2([&axes[0], &axes[1], &axes[2]], c[0], c[1], c[2], &mut out) };
        outs.push(out);
    }
    for out in &outs {
        for (i, p) in ps.iter().enumerate() {
            let (f, feature) = closest_point(*p, c[0], c[1], c[2]);
            let v = [p[0] - f[0], p[1] - f[1], p[2] - f[2]];
            let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            prop_assert_eq!(out.d2[i].to_bits(), d2.to_bits(), "lane {}", i);
            prop_assert_eq!([out.foot[0][i], out.foot[1][i], out.foot[2][i]].map(f64::to_bits), f.map(f64::to_bits));
            prop_assert_eq!(feature_of_code(out.code[i]), feature);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    /// Eight points at once get [`crate::closest::closest_point`]'s answers to the bit:
    /// triangles of every shape (slivers, needles, repeated corners), points near and far,
    /// on corners, edges and in the plane (the regions' boundaries, where ties decide).
    #[test]
    fn closest_lanes_equal_closest_point(seed in 0u64..1_000_000) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut tris = soup(&mut rng, 6);
        let a = tris[0][0];
        tris.push([a, a, tris[1][2]]);
        tris.push([a, a, a]);
        for c in &tris {
            let ps: [[f64; 3]; 8] = std::array::from_fn(|_| {
                let (s, t) = (rng.random_range(-0.5..1.5), rng.random_range(-0.5..1.5));
                let on = [0, 1, 2].map(|k| c[0][k] + s * (c[1][k] - c[0][k]) + t * (c[2][k] - c[0][k]));
                match rng.random_range(0..6) {
                    0 => c[rng.random_range(0..3)],
                    1 => [0, 1, 2].map(|k| 0.5 * (c[0][k] + c[1][k])),
                    2 => on,
                    3 => [0, 1, 2].map(|k| on[k] + rng.random_range(-1.0..1.0)),
                    4 => [0, 1, 2].map(|_| rng.random_range(-1e3..1e3)),
                    _ => [0, 1, 2].map(|k| c[0][k] + rng.random_range(-1e-9..1e-9)),
                }
            });
            check_lanes(&ps, c)?;
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]
    /// The group query's single-precision threshold (without a square root) is never
    /// below the one with it, (sqrt(bd) (1 + 2^-21) + sqrt(3) err)^2, which bounds the f32
    /// box distance of every box the exact test opens: from distances 1e-10 to 1e6 and
    /// rounding errors 1e-12 to 1 (the point's f32 error at any coordinate up to 1e6),
    /// and at 0 and infinity.
    #[test]
    fn widened_threshold_covers_the_rounded_box_distance(e_bd in -20.0f64..12.0, e_err in -12.0f64..0.0, special in 0usize..6) {
        let bd = match special { 0 => 0.0, 1 => f64::INFINITY, _ => 10f64.powf(e_bd) };
        let err = 10f64.powf(e_err);
        let need = bd.sqrt() * (1.0 + 1.0 / (1u64 << 21) as f64) + 3f64.sqrt() * err;
        let w = crate::bvh::widen(bd, crate::bvh::widen_err2(err));
        prop_assert!(w as f64 >= need * need, "bd {} err {}: {} < {}", bd, err, w, need * need);
        // no lane is opened by a lane without a best (NEG_INFINITY) or a NaN
        prop_assert_eq!(crate::bvh::widen(f64::NEG_INFINITY, crate::bvh::widen_err2(err)), f32::NEG_INFINITY);
        prop_assert_eq!(crate::bvh::widen(f64::NAN, crate::bvh::widen_err2(err)), f32::NEG_INFINITY);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    /// The median split's key sort of at most 32 items gives `select_nth_unstable_by`'s
    /// arrangement for up to 16 items (it sorts them all) and its two halves' sets above
    /// (centroids from a few values, signed zeros among them: many ties, broken by the index).
    #[test]
    fn small_sort_is_the_median_selection(n in 5usize..=crate::bvh::SMALL_SORT, seed in 0u64..1_000_000, axis in 0usize..3) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let values = [-0.0, 0.0, 1.5, -2.25, 1e300, -1e-300, 7.0];
        let items: Vec<crate::bvh::Item> = (0..n)
            .map(|_| {
                let c = [0; 3].map(|_| values[rng.random_range(0..values.len())]);
                crate::bvh::Item { tri: rng.random_range(0..40), centroid: c, lo: c, hi: c }
            })
            .collect();
        // distinct triangles (as in a build)
        let mut items: Vec<_> = items.into_iter().enumerate().map(|(i, mut it)| { it.tri = it.tri * 64 + i as u32; it }).collect();
        items.reverse();
        let mut want = items.clone();
        want.select_nth_unstable_by(n / 2, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]).then(a.tri.cmp(&b.tri)));
        crate::bvh::sort_small(&mut items, axis);
        let tris = |v: &[crate::bvh::Item]| v.iter().map(|it| it.tri).collect::<Vec<u32>>();
        if n <= 16 {
            prop_assert_eq!(tris(&items), tris(&want));
        } else {
            let (mut a, mut b) = (tris(&items[..n / 2]), tris(&want[..n / 2]));
            a.sort_unstable();
            b.sort_unstable();
            prop_assert_eq!(a, b);
        }
        prop_assert!(items.windows(2).all(|w| w[0].centroid[axis].total_cmp(&w[1].centroid[axis]).then(w[0].tri.cmp(&w[1].tri)).is_lt()));
    }

    /// A centroid's bin is `((c - lo) * scale) as usize` capped at the last bin, for any
    /// numbers (NaN, infinities and negative products too).
    #[test]
    fn bin_of_is_the_saturating_cast(c in prop::num::f64::ANY, lo in prop::num::f64::ANY, scale in prop::num::f64::ANY) {
        let want = (((c - lo) * scale) as usize).min(crate::bvh::BINS - 1);
        prop_assert_eq!(crate::bvh::bin_of(c, lo, scale), want);
    }
}

/// Checks `c < t` against `bin_of(c, lo, scale) < b` for the node's centroids `cs` (its
/// bins: `lo` its least centroid, `scale` from the extent, as the build takes them).
fn check_threshold(cs: &[f64]) -> Result<(), TestCaseError> {
    use crate::bvh::{bin_of, bin_threshold, BINS};
    let lo_c = cs.iter().fold(f64::INFINITY, |a, &c| if c < a { c } else { a });
    let hi_c = cs.iter().fold(f64::NEG_INFINITY, |a, &c| if c > a { c } else { a });
    let ext = hi_c - lo_c;
    if !(ext > 0.0) {
        return Ok(());
    }
    let scale = BINS as f64 / ext;
    for b in 1..BINS {
        if bin_of(hi_c, lo_c, scale) < b {
            break;
        }
        let t = bin_threshold(lo_c, scale, b, lo_c, hi_c);
        // the node's centroids, and the coordinates next to the edge and to the ends
        let near = [t, t.next_down(), t.next_up(), t.next_down().next_down(), t.next_up().next_up(), lo_c, hi_c, lo_c.next_up(), hi_c.next_down()];
        for &c in cs.iter().chain(near.iter().filter(|&&c| c >= lo_c && c <= hi_c)) {
            prop_assert_eq!(c < t, bin_of(c, lo_c, scale) < b, "c {} t {} b {} lo {} scale {}", c, t, b, lo_c, scale);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2048))]
    /// The partition's one comparison with the bin's edge (`bin_threshold`) puts every
    /// centroid on the side its bin does: centroids at any offset and scale, spans down to
    /// a few units in the last place, signed zeros, and coordinates at the edge.
    #[test]
    fn bin_threshold_splits_as_the_bins(seed in 0u64..1_000_000, e_off in -300.0f64..300.0, e_span in -300.0f64..300.0, ulps in 1u64..64, zeros in 0usize..3) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let off = if rng.random_range(0..2) == 0 { 10f64.powf(e_off) } else { -(10f64.powf(e_off)) };
        let span = 10f64.powf(e_span);
        let mut cs: Vec<f64> = (0..40).map(|_| off + span * rng.random_range(-1.0..1.0)).collect();
        cs.retain(|c| c.is_finite());
        check_threshold(&cs)?;
        // a span of a few units in the last place
        let mut x = off;
        let tiny: Vec<f64> = (0..ulps).map(|_| { x = x.next_up(); x }).collect();
        check_threshold(&tiny)?;
        // signed zeros among small values
        let z: Vec<f64> = (0..20).map(|i| match (i + zeros) % 4 { 0 => 0.0, 1 => -0.0, 2 => 1e-300 * i as f64, _ => -1e-310 * i as f64 }).collect();
        check_threshold(&z)?;
        // huge values: infinite extent or scale 0
        check_threshold(&[f64::MAX, -f64::MAX, 1.0, 0.0])?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]
    /// The pseudonormals' atan2 (y >= 0) is within 2 units in the last place of libm's:
    /// angles from 1e-12 rad to pi - 1e-12, at every scale (up to where y + x overflows),
    /// and the axes and zeros.
    #[test]
    fn corner_angle_is_libm_atan2_within_two_ulp(e_a in -12.0f64..0.5, near_pi in any::<bool>(), e_s in -300.0f64..308.2, special in 0usize..8) {
        let a = 10f64.powf(e_a).min(std::f64::consts::PI);
        let a = if near_pi { std::f64::consts::PI - a } else { a };
        let r = 10f64.powf(e_s);
        let (y, x) = match special {
            0 => (0.0, r),
            1 => (0.0, -r),
            2 => (r, 0.0),
            3 => (0.0, 0.0),
            4 => (0.0, -0.0),
            _ => (r * a.sin(), r * a.cos()),
        };
        let (got, want) = (crate::mesh::atan2_upper(y, x), y.atan2(x));
        prop_assert!((got - want).abs() <= 2.0 * f64::EPSILON * want, "atan2({}, {}): {} against {}", y, x, got, want);
        prop_assert!(got >= 0.0 && got <= std::f64::consts::PI);
    }
}
