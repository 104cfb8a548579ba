//! Distance queries against ground truth: an independent brute-force point–triangle
//! distance (written here: plane projection with an inside test, else the three edges),
//! analytic spheres, exact winding numbers and known ray hits.

use necklace::distance::{Closest, SurfaceDistance};
use necklace::shapes::{Shape, ShapeKind};
use necklace::SurfaceMesh;

// ---------------------------------------------------------------------------------------
// Small helpers, independent of the library's geometry code.

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Distance from `p` to the segment `uv`.
fn segment_distance(p: [f64; 3], u: [f64; 3], v: [f64; 3]) -> f64 {
    let e = sub(v, u);
    let ee = dot(e, e);
    let t = if ee > 0.0 {
        (dot(sub(p, u), e) / ee).clamp(0.0, 1.0)
    } else {
        0.0
    };
    norm(sub(p, [u[0] + t * e[0], u[1] + t * e[1], u[2] + t * e[2]]))
}

/// Distance from `p` to triangle `abc`: if the projection onto the plane lies inside
/// (three same-signed sub-triangle normals), the plane distance; else the nearest edge.
fn triangle_distance(p: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> f64 {
    let n = cross(sub(b, a), sub(c, a));
    let nn = dot(n, n);
    if nn > 0.0 {
        let h = dot(sub(p, a), n) / nn;
        let q = sub(p, [h * n[0], h * n[1], h * n[2]]);
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| dot(cross(sub(v, u), sub(q, u)), n) >= 0.0);
        if inside {
            return h.abs() * nn.sqrt();
        }
    }
    segment_distance(p, a, b)
        .min(segment_distance(p, b, c))
        .min(segment_distance(p, c, a))
}

fn brute_force_distance(mesh: &SurfaceMesh, p: [f64; 3]) -> f64 {
    (0..mesh.triangles.len())
        .map(|f| triangle_distance(p, mesh.corners(f)))
        .fold(f64::INFINITY, f64::min)
}

/// Fixed-seed 64-bit LCG (Knuth's MMIX constants); uniform in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A point uniform in the box `(lo, hi)` grown by `grow` of its size on each side.
    fn in_box(&mut self, (lo, hi): ([f64; 3], [f64; 3]), grow: f64) -> [f64; 3] {
        std::array::from_fn(|k| {
            let ext = hi[k] - lo[k];
            lo[k] - grow * ext + (1.0 + 2.0 * grow) * ext * self.next()
        })
    }
}

fn shape(kind: ShapeKind, params: &[(&str, f64)]) -> SurfaceMesh {
    let mut s = Shape::new(kind);
    for &(name, value) in params {
        s = s.with(name, value).unwrap();
    }
    s.mesh().unwrap()
}

fn sphere(res: f64) -> SurfaceMesh {
    shape(ShapeKind::Sphere, &[("r", 1.0), ("res", res)])
}

fn translated(mesh: &SurfaceMesh, t: [f64; 3]) -> SurfaceMesh {
    let mut m = mesh.clone();
    for p in &mut m.positions {
        *p = [p[0] + t[0], p[1] + t[1], p[2] + t[2]];
    }
    m
}

fn merged(a: &SurfaceMesh, b: &SurfaceMesh) -> SurfaceMesh {
    let mut m = a.clone();
    let off = a.positions.len() as u32;
    m.positions.extend_from_slice(&b.positions);
    m.triangles
        .extend(b.triangles.iter().map(|t| t.map(|v| v + off)));
    m
}

/// A stream of numbers uniform in [0, 1) from `seed` (a linear congruential generator).
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

// ---------------------------------------------------------------------------------------

#[test]
fn shared_across_threads() {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<SurfaceDistance>();
}

#[test]
fn distance_equals_brute_force_on_torus_and_dumbbell() {
    let meshes = [
        shape(ShapeKind::Torus, &[("res", 32.0)]),
        shape(ShapeKind::Dumbbell, &[("res", 40.0)]),
    ];
    let mut rng = Lcg(0x5eed);
    for mesh in &meshes {
        let sd = SurfaceDistance::new(mesh);
        let bbox = mesh.bounding_box().unwrap();
        let diag = mesh.bbox_diagonal();
        let mut points: Vec<[f64; 3]> = (0..200).map(|_| rng.in_box(bbox, 0.3)).collect();
        // Points right next to the surface too: vertices pushed off a little.
        for i in 0..50 {
            let v = mesh.positions[(i * 7919) % mesh.positions.len()];
            let e = 1e-3 * diag * (rng.next() - 0.5);
            points.push([v[0] + e, v[1] - e, v[2] + 0.5 * e]);
        }
        for p in points {
            let want = brute_force_distance(mesh, p);
            let c = sd.closest_point(p);
            // 1e-12 relative; the absolute floor only matters for a point on the surface.
            let tol = 1e-12 * want + 1e-15 * diag;
            assert!(
                (c.distance - want).abs() <= tol,
                "{p:?}: {} vs brute force {want}",
                c.distance
            );
            assert_eq!(sd.distance(p), c.distance);
            // The named face is a nearest one.
            let on_face = triangle_distance(p, mesh.corners(c.face as usize));
            assert!((on_face - want).abs() <= tol);
        }
    }
}

#[test]
fn sphere_signed_distance_and_closest_point() {
    let mesh = sphere(24.0);
    let sd = SurfaceDistance::new(&mesh);
    assert_eq!(sd.num_triangles(), mesh.triangles.len());
    let d0 = sd.signed_distance([0.0; 3]);
    assert!(
        (d0 + 1.0).abs() < 0.01,
        "signed distance at the centre: {d0}"
    );
    let d3 = sd.signed_distance([3.0, 0.0, 0.0]);
    assert!((d3 - 2.0).abs() < 0.01, "signed distance at (3,0,0): {d3}");
    assert!(sd.is_inside([0.0; 3]) && !sd.is_inside([3.0, 0.0, 0.0]));

    let mut rng = Lcg(7);
    for _ in 0..100 {
        let p = rng.in_box(([-2.0; 3], [2.0; 3]), 0.0);
        let c: Closest = sd.closest_point(p);
        let on_face = triangle_distance(c.point, mesh.corners(c.face as usize));
        assert!(on_face < 1e-14, "closest point {on_face} off its face");
        assert!((norm(sub(p, c.point)) - c.distance).abs() < 1e-14);
        // Against the analytic sphere, within the chordal error.
        assert!((c.distance - (norm(p) - 1.0).abs()).abs() < 0.01);
        let s = sd.signed_distance(p);
        assert_eq!(s.abs(), c.distance);
        assert!(s.abs() < 0.01 || (s < 0.0) == (norm(p) < 1.0));
    }
}

#[test]
fn fast_winding_number_matches_exact() {
    let mesh = shape(ShapeKind::Torus, &[("res", 32.0)]);
    let sd = SurfaceDistance::new(&mesh);
    let bbox = mesh.bounding_box().unwrap();
    let diag = mesh.bbox_diagonal();
    let mut rng = Lcg(42);
    let (mut inside, mut outside, mut near, mut far) = (0, 0, 0, 0);
    let mut max_err: f64 = 0.0;
    while inside + outside < 400 {
        // Mostly near the shape, some far away.
        let grow = if rng.next() < 0.8 { 0.1 } else { 5.0 };
        let p = rng.in_box(bbox, grow);
        let d = sd.distance(p);
        if d <= 0.01 * diag {
            continue;
        }
        let exact = sd.winding_number_exact(p);
        let fast = sd.winding_number(p);
        max_err = max_err.max((fast - exact).abs());
        assert!(
            (fast - exact).abs() < 0.01,
            "{p:?}: fast {fast}, exact {exact}"
        );
        // On a closed outward mesh the exact number is 1 inside and 0 outside.
        if exact > 0.5 {
            assert!((exact - 1.0).abs() < 1e-6, "{p:?}: {exact}");
            inside += 1;
        } else {
            assert!(exact.abs() < 1e-6, "{p:?}: {exact}");
            outside += 1;
        }
        assert_eq!(sd.is_inside(p), exact > 0.5);
        if d < 0.05 * diag {
            near += 1;
        }
        if d > diag {
            far += 1;
        }
    }
    assert!(inside > 20 && outside > 20 && near > 50 && far > 20);
    assert!(max_err < 0.01);
}

#[test]
fn sphere_with_a_hole_still_reads_as_solid() {
    let mut mesh = sphere(24.0);
    let before = mesh.triangles.len();
    let positions = mesh.positions.clone();
    mesh.triangles
        .retain(|t| t.iter().any(|&v| positions[v as usize][2] < 0.9));
    assert!(mesh.triangles.len() < before);
    let sd = SurfaceDistance::new(&mesh);
    let w = sd.winding_number([0.0; 3]);
    assert!(w > 0.9 && w < 1.0, "winding number at the centre: {w}");
    assert!(sd.is_inside([0.0; 3]) && sd.is_inside([0.0, 0.0, 0.5]));
    for p in [
        [3.0, 0.0, 0.0],
        [0.0, 0.0, 2.0],
        [0.0, 0.0, -2.0],
        [0.0, 1.5, 1.0],
    ] {
        assert!(!sd.is_inside(p), "{p:?} reads as inside");
        assert!(sd.signed_distance(p) > 0.0);
    }
    assert!(sd.signed_distance([0.0; 3]) < 0.0);
}

#[test]
fn overlapping_spheres_give_winding_number_two() {
    let a = sphere(16.0);
    let b = translated(&a, [1.0, 0.0, 0.0]);
    let sd = SurfaceDistance::new(&merged(&a, &b));
    let overlap = [0.5, 0.0, 0.0];
    assert!((sd.winding_number_exact(overlap) - 2.0).abs() < 1e-6);
    assert!((sd.winding_number(overlap) - 2.0).abs() < 0.01);
    assert!(sd.is_inside(overlap) && sd.signed_distance(overlap) < 0.0);
    assert!((sd.winding_number([-0.5, 0.0, 0.0]) - 1.0).abs() < 0.01);
    assert!(!sd.is_inside([0.5, 0.0, 2.0]));
}

/// Two squares 10 × 10 drawn as 8 × 8 grids, at z = 0 and z = 0.1 (facing each other).
fn two_grids() -> SurfaceMesh {
    let n = 8;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (z, up) in [(0.0, true), (0.1, false)] {
        let base = positions.len() as u32;
        for i in 0..=n {
            for j in 0..=n {
                positions.push([1.25 * i as f64, 1.25 * j as f64, z]);
            }
        }
        for i in 0..n {
            for j in 0..n {
                let a = base + i * (n + 1) + j;
                let (b, c, d) = (a + n + 1, a + n + 2, a + 1);
                if up {
                    triangles.extend([[a, b, c], [a, c, d]]);
                } else {
                    triangles.extend([[a, c, b], [a, d, c]]);
                }
            }
        }
    }
    SurfaceMesh::new(positions, triangles).unwrap()
}

#[test]
fn a_ray_along_an_axis_through_a_grids_vertices_and_edges_hits_it() {
    // From every vertex and edge midpoint of the lower grid, straight up: the ray runs
    // along the faces of boxes of the hierarchy (the grid's coordinates) and meets the
    // upper grid at a vertex or on an edge.
    let grids = two_grids();
    let sd = SurfaceDistance::new(&grids);
    for i in 0..=16 {
        for j in 0..=16 {
            let o = [0.625 * i as f64, 0.625 * j as f64, 0.0];
            let hit = sd.ray_hit(o, [0.0, 0.0, 1.0], 1.0);
            let (t, _) = hit.unwrap_or_else(|| panic!("the ray up from {o:?} misses"));
            assert!((t - 0.1).abs() < 1e-12, "{o:?}: {t}");
        }
    }
}

#[test]
fn ray_hits_sphere_and_misses_elsewhere() {
    let mesh = sphere(24.0);
    let sd = SurfaceDistance::new(&mesh);
    let (t, f) = sd
        .ray_hit([0.0; 3], [1.0, 0.0, 0.0], f64::INFINITY)
        .unwrap();
    assert!((t - 1.0).abs() < 0.01, "t = {t}");
    assert!(triangle_distance([t, 0.0, 0.0], mesh.corners(f as usize)) < 1e-12);
    // A non-unit direction: t in units of dir.
    let (t2, f2) = sd
        .ray_hit([0.0; 3], [2.0, 0.0, 0.0], f64::INFINITY)
        .unwrap();
    assert!((t2 - 0.5 * t).abs() < 1e-12 && f2 == f);
    // t_max before the surface.
    assert_eq!(sd.ray_hit([0.0; 3], [1.0, 0.0, 0.0], 0.9), None);
    // Every direction from the centre hits, at about the radius.
    let mut rng = Lcg(3);
    for _ in 0..100 {
        let d = [rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5];
        let (t, _) = sd
            .ray_hit([0.0; 3], d, f64::INFINITY)
            .expect("a ray from inside hits");
        assert!((t * norm(d) - 1.0).abs() < 0.01);
    }

    let away = SurfaceDistance::new(&translated(&mesh, [5.0, 0.0, 0.0]));
    assert_eq!(
        away.ray_hit([0.0; 3], [-1.0, 0.0, 0.0], f64::INFINITY),
        None
    );
    assert_eq!(away.ray_hit([0.0; 3], [0.0, 1.0, 0.0], f64::INFINITY), None);
    let (t, _) = away
        .ray_hit([0.0; 3], [1.0, 0.0, 0.0], f64::INFINITY)
        .unwrap();
    assert!((t - 4.0).abs() < 0.01, "t = {t}");
}

#[test]
fn batches_equal_per_point_results_bit_for_bit() {
    let mesh = shape(ShapeKind::Dumbbell, &[("res", 32.0)]);
    let sd = SurfaceDistance::new(&mesh);
    let mut rng = Lcg(99);
    let bbox = mesh.bounding_box().unwrap();
    let points: Vec<[f64; 3]> = (0..2000).map(|_| rng.in_box(bbox, 0.2)).collect();
    let single: Vec<u64> = points
        .iter()
        .map(|&p| sd.signed_distance(p).to_bits())
        .collect();
    let unsigned: Vec<u64> = points.iter().map(|&p| sd.distance(p).to_bits()).collect();
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (s, d) = pool.install(|| (sd.signed_distances(&points), sd.distances(&points)));
        assert!(s.iter().map(|x| x.to_bits()).eq(single.iter().copied()));
        assert!(d.iter().map(|x| x.to_bits()).eq(unsigned.iter().copied()));
    }
    assert!(single.iter().any(|&b| f64::from_bits(b) < 0.0));
}

#[test]
fn self_intersections_are_the_crossing_pairs_only() {
    // A closed sphere, and two apart: nothing crosses.
    let ball = sphere(16.0);
    let apart = merged(&ball, &translated(&ball, [3.0, 0.0, 0.0]));
    for mesh in [&ball, &apart] {
        let sd = SurfaceDistance::new(mesh);
        assert!(sd.self_intersections(&mesh.triangles).is_empty());
    }
    // Two overlapping spheres cross along a circle: every pair joins the two balls.
    let overlap = merged(&ball, &translated(&ball, [1.0, 0.0, 0.0]));
    let sd = SurfaceDistance::new(&overlap);
    let pairs = sd.self_intersections(&overlap.triangles);
    let first = ball.triangles.len() as u32;
    assert!(pairs.len() > 10, "{}", pairs.len());
    assert!(pairs.iter().all(|&[a, b]| a < first && b >= first));
    // Two triangles that only touch (a corner of one on a side of the other) do not.
    let touching = SurfaceMesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, -1.0, 1.0],
            [1.0, -1.0, -1.0],
        ],
        triangles: vec![[0, 1, 2], [3, 4, 5]],
    };
    let sd = SurfaceDistance::new(&touching);
    assert!(sd.self_intersections(&touching.triangles).is_empty());
    // The same second triangle pushed through the first crosses it.
    let mut through = touching.clone();
    for p in &mut through.positions[3..] {
        p[1] += 0.5;
    }
    let sd = SurfaceDistance::new(&through);
    assert_eq!(sd.self_intersections(&through.triangles), vec![[0, 1]]);
}

#[test]
fn the_pseudonormal_sign_agrees_with_the_winding_number() {
    // A closed manifold qualifies; its signs by pseudonormal and by winding number agree
    // everywhere off the surface, including right next to edges and corners.
    for mesh in [
        shape(ShapeKind::Torus, &[("res", 24.0)]),
        shape(ShapeKind::Dumbbell, &[("res", 32.0)]),
    ] {
        let by_winding = SurfaceDistance::new(&mesh);
        let mut by_normal = SurfaceDistance::new(&mesh);
        assert!(by_normal.use_pseudonormal_sign(&mesh));
        let mut random = uniform(7);
        let mut checked = 0;
        for i in 0..4000 {
            // Points near vertices (a tiny offset) and anywhere in the box.
            let p = if i % 2 == 0 {
                let v = mesh.positions[(random() * mesh.positions.len() as f64) as usize];
                [0, 1, 2].map(|k| v[k] + 1e-3 * (random() - 0.5))
            } else {
                [0, 1, 2].map(|_| 3.0 * (random() - 0.5))
            };
            let (a, b) = (by_winding.signed_distance(p), by_normal.signed_distance(p));
            assert_eq!(a.abs(), b.abs());
            if a.abs() > 1e-9 {
                assert_eq!(a.signum(), b.signum(), "at {p:?}: {a} vs {b}");
                checked += 1;
            }
            let w = by_normal.signed_distance_within(p, 0.1);
            assert_eq!(w.signum(), a.signum(), "within at {p:?}");
        }
        assert!(checked > 3900);
    }
    // An open mesh does not qualify.
    let mut open = sphere(12.0);
    open.triangles.pop();
    assert!(!SurfaceDistance::new(&open).use_pseudonormal_sign(&open));
}

#[test]
fn the_pseudonormal_sign_holds_on_open_surfaces_away_from_their_holes() {
    // A sphere with a small hole (the faces round one vertex removed) and one with a
    // large one (every face above z = 0.5). The winding number is not an integer off
    // them; the solid is where the exact one is at least ½ (the hole spanned by a cap).
    // Triangles far enough from the hole decide by their pseudonormal, the others by
    // the winding number, and every sign matches the exact winding number's.
    let mut small = sphere(16.0);
    let pole = (0..small.positions.len())
        .max_by(|&a, &b| small.positions[a][2].total_cmp(&small.positions[b][2]))
        .unwrap() as u32;
    small.triangles.retain(|t| !t.contains(&pole));
    let mut large = sphere(16.0);
    let positions = large.positions.clone();
    large
        .triangles
        .retain(|t| t.iter().all(|&v| positions[v as usize][2] < 0.5));
    for (name, mesh) in [("small hole", small), ("large hole", large)] {
        let reference = SurfaceDistance::new(&mesh);
        let mut local = SurfaceDistance::new(&mesh).recording(Vec::new());
        assert!(
            local.use_pseudonormal_sign(&mesh),
            "{name}: no triangle decides locally"
        );
        let mut random = uniform(5);
        let mut checked = 0;
        for i in 0..4000 {
            let p = if i % 2 == 0 {
                let v = mesh.positions[(random() * mesh.positions.len() as f64) as usize];
                [0, 1, 2].map(|k| v[k] + 2e-2 * (random() - 0.5))
            } else {
                [0, 1, 2].map(|_| 3.0 * (random() - 0.5))
            };
            let exact = reference.winding_number_exact(p);
            if (exact - 0.5).abs() < 0.05 {
                continue; // on the cap, up to the fast winding number's error
            }
            let a = local.signed_distance(p);
            if a.abs() < 1e-9 {
                continue;
            }
            assert_eq!(
                a < 0.0,
                exact >= 0.5,
                "{name} at {p:?}: {a}, winding {exact}"
            );
            checked += 1;
        }
        assert!(checked > 3500, "{name}: {checked}");
    }
}

/// A sphere of radius `r` about `c`, its faces turned inward when `inward` (a cavity).
fn ball(r: f64, c: [f64; 3], inward: bool) -> SurfaceMesh {
    let mut m = sphere(24.0);
    for p in &mut m.positions {
        *p = [0, 1, 2].map(|k| c[k] + r * p[k]);
    }
    if inward {
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
    }
    m
}

#[test]
fn the_pseudonormal_sign_holds_on_overlapping_parts_away_from_their_crossings() {
    // Three balls that cross each other (each pair along a circle), a fourth buried in
    // the first, and a cavity (an inward ball) in the second. The solid is where the
    // exact winding number is at least ½. Taking the pseudonormal's side alone (as on an
    // embedded surface) would call the points round the buried ball outside.
    let parts = [
        ball(1.0, [0.0, 0.0, 0.0], false),
        ball(1.0, [1.2, 0.0, 0.0], false),
        ball(0.8, [0.0, 1.1, 0.0], false),
        ball(0.3, [-0.4, -0.3, 0.0], false),
        ball(0.3, [1.6, 0.0, 0.0], true),
    ];
    let mesh = parts[1..]
        .iter()
        .fold(parts[0].clone(), |m, p| merged(&m, p));
    let reference = SurfaceDistance::new(&mesh);
    let crossings = reference.self_intersections(&mesh.triangles);
    assert!(!crossings.is_empty());
    let mut local = SurfaceDistance::new(&mesh).recording(crossings.clone());
    assert!(
        local.use_pseudonormal_sign(&mesh),
        "no triangle decides locally"
    );
    // The same through `of_surface`, which every run uses.
    let shared = SurfaceDistance::of_surface(&mesh);
    let mut random = uniform(11);
    let mut checked = 0;
    for i in 0..6000 {
        // Half the points within 1e-3 of a vertex (of a buried part too), half anywhere.
        let p = if i % 2 == 0 {
            let v = mesh.positions[(random() * mesh.positions.len() as f64) as usize];
            [0, 1, 2].map(|k| v[k] + 2e-3 * (random() - 0.5))
        } else {
            [0, 1, 2].map(|k| [0.6, 0.3, 0.0][k] + 4.0 * (random() - 0.5))
        };
        let exact = reference.winding_number_exact(p);
        if (exact - 0.5).abs() < 0.25 {
            continue; // on the surface, up to the offset
        }
        let inside = exact >= 0.5;
        let (a, b) = (local.signed_distance(p), shared.signed_distance(p));
        if a.abs() < 1e-9 {
            continue;
        }
        assert_eq!(a < 0.0, inside, "at {p:?}: {a}, winding {exact}");
        assert_eq!(b < 0.0, inside, "of_surface at {p:?}: {b}, winding {exact}");
        assert_eq!(
            local.signed_distance_within(p, 0.05) < 0.0,
            inside,
            "within at {p:?}"
        );
        checked += 1;
    }
    assert!(checked > 5000, "{checked}");
}

#[test]
fn a_fold_round_a_shared_corner_leaves_the_sign_there_to_the_winding_number() {
    // os_cow-low-resolution.obj is closed, manifold and outward, and no two of its faces
    // without a common corner cross; but at a hoof, faces with one corner in common do
    // (OBJ faces 2 and 4, round vertex 1: a fold). The pseudonormals there called points
    // below the hoof inside. The solid is where the exact winding number is at least ½.
    let Some(prepared) = crate::common::realworld_surface("os_cow-low-resolution.obj") else {
        return;
    };
    let fold = [2.33969, 0.032583, 0.756243];
    let checked = signs_agree_round(&prepared.distance, fold, 0.8, 3000, 3);
    assert!(checked > 2500, "{checked}");
}

/// Asserts that the sign of the distance is the exact winding number's (the solid is
/// where it is at least ½) at `samples` random points of the cube of side `side`
/// round `centre`, but those within ¼ of ½ or on the surface; returns how many were
/// checked.
fn signs_agree_round(
    distance: &SurfaceDistance,
    centre: [f64; 3],
    side: f64,
    samples: usize,
    seed: u64,
) -> usize {
    let mut random = uniform(seed);
    let mut checked = 0;
    for _ in 0..samples {
        let p = [0, 1, 2].map(|k| centre[k] + side * (random() - 0.5));
        let exact = distance.winding_number_exact(p);
        let signed = distance.signed_distance(p);
        if (exact - 0.5).abs() < 0.25 || signed.abs() < 1e-9 {
            continue;
        }
        assert_eq!(
            signed < 0.0,
            exact >= 0.5,
            "at {p:?}: {signed}, winding {exact}"
        );
        checked += 1;
    }
    checked
}

#[test]
fn a_closest_point_on_a_needles_edge_takes_the_edges_pseudonormal() {
    // vtk_gears.stl's face 3222 is a needle (a 0.02° corner, 5.08 long, 0.002 wide)
    // along a concave edge. A point inside, 0.094 from it, has its closest point on the
    // needle's long edge; its barycentric coordinates put that point 1.1e-9 inside the
    // face, whose normal gave the outside. The solid is where the exact winding number
    // is at least ½.
    let Some(prepared) = crate::common::realworld_surface("vtk_gears.stl") else {
        return;
    };
    let distance = &prepared.distance;
    let inside = [-23.399624783412662, 0.0815533548347137, 7.568291314334779];
    assert!(distance.winding_number_exact(inside) > 0.75);
    assert!(distance.signed_distance(inside) < 0.0);
    let checked = signs_agree_round(distance, inside, 0.4, 2000, 5);
    assert!(checked > 1500, "{checked}");
}
