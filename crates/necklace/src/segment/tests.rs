use super::*;
use std::f64::consts::PI;

/// A torus of radii `big` (core circle, in the xy plane) and `small`, as a `nu × nv`
/// grid: vertex `i * nv + j` at angle `2π i / nu` round the core and `2π j / nv` round
/// the tube; outward.
fn torus(big: f64, small: f64, nu: usize, nv: usize) -> SurfaceMesh {
    let mut positions = Vec::new();
    for i in 0..nu {
        let u = 2.0 * PI * i as f64 / nu as f64;
        for j in 0..nv {
            let v = 2.0 * PI * j as f64 / nv as f64;
            let r = big + small * v.cos();
            positions.push([r * u.cos(), r * u.sin(), small * v.sin()]);
        }
    }
    let id = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
    let mut triangles = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let mesh = SurfaceMesh {
        positions,
        triangles,
    };
    assert!(mesh.signed_volume() > 0.0);
    mesh
}

/// The closed curve where the plane `n · x = d` cuts the mesh's edges, walked from
/// triangle to triangle (the mesh is cut by it in one closed curve; no vertex on it).
fn plane_loop(mesh: &SurfaceMesh, n: [f64; 3], d: f64) -> Vec<CurvePoint> {
    let side = |v: u32| dot(mesh.positions[v as usize], n) - d;
    let crossing = |a: u32, b: u32| -> Option<CurvePoint> {
        let (fa, fb) = (side(a), side(b));
        (fa * fb < 0.0).then(|| {
            let edge = sorted([a, b]);
            let t = side(edge[0]) / (side(edge[0]) - side(edge[1]));
            CurvePoint::Edge { edge, t }
        })
    };
    // Each cut triangle joins its two crossed edges.
    let mut next: HashMap<[u32; 2], Vec<[u32; 2]>> = HashMap::new();
    let mut point: HashMap<[u32; 2], CurvePoint> = HashMap::new();
    for t in &mesh.triangles {
        let cut: Vec<([u32; 2], CurvePoint)> = (0..3)
            .filter_map(|k| {
                crossing(t[k], t[(k + 1) % 3]).map(|p| (sorted([t[k], t[(k + 1) % 3]]), p))
            })
            .collect();
        if cut.len() == 2 {
            next.entry(cut[0].0).or_default().push(cut[1].0);
            next.entry(cut[1].0).or_default().push(cut[0].0);
            point.insert(cut[0].0, cut[0].1);
            point.insert(cut[1].0, cut[1].1);
        }
    }
    let start = *next.keys().min().unwrap();
    let mut curve = vec![point[&start]];
    let (mut prev, mut at) = (start, next[&start][0]);
    while at != start {
        curve.push(point[&at]);
        let following = next[&at].iter().copied().find(|&e| e != prev).unwrap();
        (prev, at) = (at, following);
    }
    curve
}

fn torus_volume(big: f64, small: f64) -> f64 {
    2.0 * PI * PI * big * small * small
}

#[test]
fn a_meridian_loop_cuts_a_torus_open_into_one_cylinder_with_the_tori_volume() {
    let (big, small) = (1.0, 0.3);
    let mesh = torus(big, small, 48, 24);
    let curve = meridian(&mesh, 0.31);
    let result = segment(&mesh, &[curve]).unwrap();
    assert_eq!(result.segments.len(), 1, "{:?}", result.segments);
    let s = &result.segments[0];
    assert_eq!((s.euler, s.boundaries, s.genus), (0, 2, 0), "{s:?}");
    assert_eq!(s.loops, vec![0]);
    // Cutting moves no surface: the area is the mesh's, and the two caps cancel.
    assert!((s.area - mesh.area()).abs() < 1e-9 * mesh.area());
    let volume = s.volume.unwrap();
    assert!((volume - mesh.signed_volume()).abs() < 1e-9, "{volume}");
    assert!((volume - torus_volume(big, small)).abs() < 0.02 * torus_volume(big, small));
    // The refined mesh is still closed and oriented: every edge twice, opposite ways.
    let mut directed: HashMap<[u32; 2], usize> = HashMap::new();
    for t in &result.mesh.triangles {
        for k in 0..3 {
            *directed.entry([t[k], t[(k + 1) % 3]]).or_default() += 1;
        }
    }
    assert!(directed
        .iter()
        .all(|(e, &c)| c == 1 && directed.get(&[e[1], e[0]]) == Some(&1)));
}

#[test]
fn a_handle_and_a_tunnel_loop_together_cut_a_torus_into_one_disk() {
    let mesh = torus(1.0, 0.3, 48, 24);
    // The tunnel loop: the ring of grid vertices round the hole (j = 12, the innermost
    // circle), a curve along mesh edges, crossing the meridian once.
    let ring: Vec<CurvePoint> = (0..48)
        .map(|i| CurvePoint::Vertex((i * 24 + 12) as u32))
        .collect();
    let result = segment(&mesh, &[meridian(&mesh, 0.31), ring]).unwrap();
    assert_eq!(result.segments.len(), 1);
    let s = &result.segments[0];
    assert_eq!((s.euler, s.boundaries, s.genus), (1, 1, 0), "{s:?}");
    assert_eq!(s.loops, vec![0, 1]);
    assert!((s.volume.unwrap() - mesh.signed_volume()).abs() < 1e-9);
}

#[test]
fn two_parallel_plane_loops_cut_a_band_off_the_torus_with_the_volume_between_them() {
    let mesh = torus(1.0, 0.3, 60, 24);
    let result = segment(&mesh, &[meridian(&mesh, 0.31), meridian(&mesh, 1.13)]).unwrap();
    assert_eq!(result.segments.len(), 2, "{:?}", result.segments);
    for s in &result.segments {
        assert_eq!((s.euler, s.boundaries, s.genus), (0, 2, 0), "{s:?}");
        assert_eq!(s.loops, vec![0, 1]);
    }
    let total: f64 = result.segments.iter().map(|s| s.area).sum();
    assert!((total - mesh.area()).abs() < 1e-9 * total);
    // The band between the planes is (1.13 − 0.31) / 2π of the torus, in area and in
    // volume (Pappus), up to the polygon's faceting.
    let band = result
        .segments
        .iter()
        .min_by(|a, b| a.area.total_cmp(&b.area))
        .unwrap();
    let fraction = (1.13 - 0.31) / (2.0 * PI);
    assert!(
        (band.area / mesh.area() - fraction).abs() < 0.01,
        "{}",
        band.area / mesh.area()
    );
    let v = band.volume.unwrap() / mesh.signed_volume();
    assert!((v - fraction).abs() < 0.01, "{v}");
    let sum: f64 = result.segments.iter().map(|s| s.volume.unwrap()).sum();
    assert!((sum - mesh.signed_volume()).abs() < 1e-9);
}

/// The meridian at `angle`: where the plane through the z axis at that angle cuts the
/// tube on the side of the core circle's point at `angle` (the triangles on the other
/// side, round `angle + π`, are left out of the walk).
fn meridian(mesh: &SurfaceMesh, angle: f64) -> Vec<CurvePoint> {
    let n = [-angle.sin(), angle.cos(), 0.0];
    let towards = [angle.cos(), angle.sin(), 0.0];
    let half = SurfaceMesh {
        positions: mesh.positions.clone(),
        triangles: mesh
            .triangles
            .iter()
            .copied()
            .filter(|t| {
                t.iter()
                    .all(|&v| dot(mesh.positions[v as usize], towards) > 0.0)
            })
            .collect(),
    };
    plane_loop(&half, n, 0.0)
}

#[test]
fn points_off_the_mesh_are_refused_with_the_loop_and_point() {
    let mesh = torus(1.0, 0.3, 12, 8);
    let bad = vec![
        CurvePoint::Vertex(0),
        CurvePoint::Vertex(1),
        CurvePoint::Vertex(10_000),
    ];
    let err = segment(&mesh, &[bad]).unwrap_err().to_string();
    assert!(
        err.contains("loop 0, point 2") && err.contains("not in the mesh"),
        "{err}"
    );
    let far = vec![
        CurvePoint::Vertex(0),
        CurvePoint::Edge {
            edge: [0, 50],
            t: 0.5,
        },
    ];
    let err = segment(&mesh, &[far]).unwrap_err().to_string();
    assert!(err.contains("not an edge"), "{err}");
    // Two vertices far apart: no triangle holds both.
    let jump = vec![
        CurvePoint::Vertex(0),
        CurvePoint::Vertex(45),
        CurvePoint::Vertex(46),
    ];
    let err = segment(&mesh, &[jump]).unwrap_err().to_string();
    assert!(err.contains("no common triangle"), "{err}");
}

#[test]
fn far_from_the_origin_the_parts_are_measured_the_same() {
    // The band between two meridians, the torus moved 10⁴ away: the same areas,
    // volumes and topology (volumes are taken about a point of the mesh).
    let near = torus(1.0, 0.3, 60, 24);
    let mut far = near.clone();
    for p in &mut far.positions {
        *p = add(*p, [1e4, -2e4, 3e4]);
    }
    let cut = |mesh: &SurfaceMesh| {
        segment(mesh, &[meridian(&near, 0.31), meridian(&near, 1.13)]).unwrap()
    };
    let (a, b) = (cut(&near), cut(&far));
    assert_eq!(a.segments.len(), b.segments.len());
    for (x, y) in a.segments.iter().zip(&b.segments) {
        assert_eq!(
            (x.euler, x.boundaries, &x.loops),
            (y.euler, y.boundaries, &y.loops)
        );
        assert!(
            (x.area - y.area).abs() < 1e-8 * x.area,
            "{} {}",
            x.area,
            y.area
        );
        let (vx, vy) = (x.volume.unwrap(), y.volume.unwrap());
        assert!((vx - vy).abs() < 1e-8 * vx.abs(), "{vx} {vy}");
    }
}
