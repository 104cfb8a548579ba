//! Neck loops (sec. 4.3): plane cut, tightening and selection against shapes whose
//! narrowest loops are known in closed form.

use std::f64::consts::PI;

use necklace::loops::cut::{
    closed_length, encloses_another, loop_around, plane_cut, Cutter, EdgeTree, Plane,
};
use necklace::loops::tighten::{tighten, tighten_resumable, SurfaceGeometry, TightenStatus};
use necklace::loops::{
    complete_classes, find_loops, find_loops_with_progress, DropReason, Initial, LoopMemo,
    LoopOptions, MembraneFailure, MembraneUse, NeckLoop, Role, Seed, SurfacePoint, TightenOptions,
    Tightened,
};
use necklace::mesh::{HomologyBasis, Topology};
use necklace::morse::NormalSource;
use necklace::pipeline::{find_necks, NeckOptions, NeckReport};
use necklace::shapes::{Shape, ShapeKind};
use necklace::Side;
use necklace::SurfaceMesh;

/// A closed surface of revolution about z: radius `r(z)` for z in [-h, h], with a pole
/// at each end; `rings` latitude rings, `segments` vertices per ring.
fn revolution(r: impl Fn(f64) -> f64, h: f64, rings: usize, segments: usize) -> SurfaceMesh {
    wavy_revolution(r, h, rings, segments, 0.0)
}

/// [`revolution`] with each ring's vertices moved along the profile by up to `wave` ×
/// the ring spacing (a wave round the ring): still on the surface, but no plane
/// normal to the axis runs along a ring.
fn wavy_revolution(
    r: impl Fn(f64) -> f64,
    h: f64,
    rings: usize,
    segments: usize,
    wave: f64,
) -> SurfaceMesh {
    let mut positions = vec![[0.0, 0.0, -h]];
    for i in 1..rings {
        for j in 0..segments {
            let a = 2.0 * PI * j as f64 / segments as f64;
            let z = -h + 2.0 * h * (i as f64 + wave * (3.0 * a + i as f64).sin()) / rings as f64;
            positions.push([r(z) * a.cos(), r(z) * a.sin(), z]);
        }
    }
    positions.push([0.0, 0.0, h]);
    let top = (positions.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * segments + j % segments) as u32;
    let mut triangles = Vec::new();
    for j in 0..segments {
        triangles.push([0, ring(1, j + 1), ring(1, j)]);
        triangles.push([top, ring(rings - 1, j), ring(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            triangles.push([ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)]);
            triangles.push([ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)]);
        }
    }
    SurfaceMesh::new(positions, triangles).unwrap()
}

/// The triangles of a closed ring of `along` × `around` vertices, vertex `i · around + j`
/// the `j`-th round the tube of the `i`-th along it.
fn ring_triangles(along: usize, around: usize) -> Vec<[u32; 3]> {
    let id = |i: usize, j: usize| ((i % along) * around + j % around) as u32;
    let mut triangles = Vec::new();
    for i in 0..along {
        for j in 0..around {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    triangles
}

/// A ring whose core curve (cos t, sin t, `a` cos 2t) rises and falls like a saddle,
/// with a round tube of radius `rho`: a window whose rim is not flat. The planes z = h
/// that cut the tube all the way round, in a curve around the hole, are those with
/// |h| < `rho` − `a`.
fn saddle_ring(a: f64, rho: f64, along: usize, around: usize) -> SurfaceMesh {
    let mut positions = Vec::with_capacity(along * around);
    for i in 0..along {
        let t = 2.0 * PI * i as f64 / along as f64;
        let core = [t.cos(), t.sin(), a * (2.0 * t).cos()];
        let tangent = [-t.sin(), t.cos(), -2.0 * a * (2.0 * t).sin()];
        let tl = (tangent[0].powi(2) + tangent[1].powi(2) + tangent[2].powi(2)).sqrt();
        let tangent = tangent.map(|x| x / tl);
        // The radial direction made normal to the tangent, and the binormal.
        let radial = [t.cos(), t.sin(), 0.0];
        let along_t = radial[0] * tangent[0] + radial[1] * tangent[1];
        let n = [0, 1, 2].map(|k| radial[k] - along_t * tangent[k]);
        let nl = (n[0].powi(2) + n[1].powi(2) + n[2].powi(2)).sqrt();
        let n = n.map(|x| x / nl);
        let b = [
            tangent[1] * n[2] - tangent[2] * n[1],
            tangent[2] * n[0] - tangent[0] * n[2],
            tangent[0] * n[1] - tangent[1] * n[0],
        ];
        for j in 0..around {
            let phi = 2.0 * PI * j as f64 / around as f64;
            let (c, s) = (rho * phi.cos(), rho * phi.sin());
            positions.push([0, 1, 2].map(|k| core[k] + c * n[k] + s * b[k]));
        }
    }
    SurfaceMesh::new(positions, ring_triangles(along, around)).unwrap()
}

/// Profile with its narrowest circle, radius 0.2, at z = 0; capped towards the poles.
fn waist(z: f64) -> f64 {
    let h: f64 = 1.0;
    (0.2 + 0.6 * z * z) * (1.0 - (z / h).powi(8)).max(0.0).sqrt()
}

#[test]
fn tightening_a_tilted_loop_finds_the_narrowest_circle_of_a_surface_of_revolution() {
    let segments = 200;
    let mesh = revolution(waist, 1.0, 201, segments);
    let topology = Topology::new(&mesh);
    let geometry = SurfaceGeometry::new(&mesh, &topology);
    let tilt: f64 = 0.35;
    let plane = Plane {
        origin: [0.0, 0.0, 0.0],
        normal: [0.0, tilt.sin(), tilt.cos()],
    };
    let curves = plane_cut(&mesh, &topology, &plane);
    let i = loop_around(&mesh, &topology, &plane, &curves, plane.origin).unwrap();
    let t = tighten(
        &geometry,
        &curves[i].crossings,
        &curves[i].faces,
        &TightenOptions::default(),
    );
    // The polygonal ring at z = 0 is the mesh's own narrowest circle.
    let ring = 2.0 * segments as f64 * 0.2 * (PI / segments as f64).sin();
    eprintln!(
        "{:?} rounds {} updates {} length {} initial {} ring {} turn {} vangle {}",
        t.status,
        t.rounds,
        t.updates,
        t.length,
        t.initial_length,
        ring,
        t.max_edge_turn,
        t.min_vertex_angle
    );
    assert_eq!(t.status, TightenStatus::Converged);
    assert!(t.initial_length > 1.03 * ring);
    assert!((t.length - 2.0 * PI * 0.2).abs() < 0.005 * 2.0 * PI * 0.2);
    assert!(t.initial_length > 1.03 * ring);
    check_geodesic(
        &mesh,
        &topology,
        &t.points,
        &t.surface_points,
        t.length,
        t.initial_length,
        &t,
    );
}

#[test]
fn a_tightening_stopped_below_its_length_ratio_carries_on_to_what_a_fresh_one_gives() {
    // A tilted circle round z = 0.61 slides down towards the waist and settles on a
    // ring of the polygon about 0.7 of its start: it falls below 0.9 on the way.
    let mesh = revolution(waist, 1.0, 101, 64);
    let topology = Topology::new(&mesh);
    let geometry = SurfaceGeometry::new(&mesh, &topology);
    let tilt: f64 = 0.2;
    let plane = Plane {
        origin: [0.0, 0.0, 0.61],
        normal: [0.0, tilt.sin(), tilt.cos()],
    };
    let curves = plane_cut(&mesh, &topology, &plane);
    let c = &curves[loop_around(&mesh, &topology, &plane, &curves, plane.origin).unwrap()];
    let with_ratio = |min_length_ratio| TightenOptions {
        min_length_ratio,
        ..TightenOptions::default()
    };
    let (stopped, state) = tighten_resumable(&geometry, &c.crossings, &c.faces, &with_ratio(0.9));
    assert_eq!(stopped.status, TightenStatus::Collapsed);
    assert!(stopped.length < 0.9 * stopped.initial_length);
    assert_eq!(
        stopped,
        tighten(&geometry, &c.crossings, &c.faces, &with_ratio(0.9))
    );
    let state = state.expect("stopped by its ratio alone");
    // Not under a ratio as large: a fresh run could stop earlier.
    assert!(state.clone().resume(&geometry, &with_ratio(0.9)).is_none());
    for ratio in [0.2, f64::MIN_POSITIVE] {
        let (carried, more) = state.clone().resume(&geometry, &with_ratio(ratio)).unwrap();
        let fresh = tighten(&geometry, &c.crossings, &c.faces, &with_ratio(ratio));
        assert_eq!(carried, fresh);
        assert!(more.is_none());
        assert_eq!(fresh.status, TightenStatus::Converged);
        assert!(fresh.rounds > stopped.rounds);
        assert!(fresh.length < 0.9 * fresh.initial_length);
    }
    // A tightening that ends for a reason of its own gives no state.
    let (done, none) = tighten_resumable(&geometry, &c.crossings, &c.faces, &with_ratio(0.2));
    assert_eq!(done.status, TightenStatus::Converged);
    assert!(none.is_none());
}

#[test]
fn searches_that_share_a_memo_give_the_loops_of_fresh_searches() {
    // The dumbbell's neck (a loop), a circle near a ball's pole (it slides off the cap:
    // stopped at the length ratio, carried on where the seed needs a disk) and a point
    // away from the surface (no curve goes round it).
    let mesh = Shape::new(ShapeKind::Dumbbell).mesh().unwrap();
    let x = |position: [f64; 3]| Seed {
        position,
        normal: [1.0, 0.0, 0.0],
        persistence: 5,
        ..Seed::default()
    };
    let seeds = [x([0.0, 0.0, 0.0]), x([1.2, 0.0, 0.0]), x([0.0, 0.0, 3.0])];
    let strict: Vec<Seed> = seeds.iter().map(|s| s.needing_a_disk()).collect();
    let options = LoopOptions::default();
    let search = |seeds: &[Seed], memo: &LoopMemo| {
        let r = find_loops_with_progress(
            &mesh,
            None,
            seeds,
            Side::Inside,
            &options,
            memo,
            &necklace::progress::Silent,
        )
        .unwrap();
        (r.loops, r.dropped)
    };
    let fresh = [
        search(&seeds, &LoopMemo::default()),
        search(&strict, &LoopMemo::default()),
    ];
    assert_eq!(fresh[0].0.len(), 1, "{:?}", fresh[0].1);
    assert!((fresh[0].0[0].length - 2.0 * PI * 0.15).abs() < 0.02 * 2.0 * PI * 0.15);
    assert!(fresh[1]
        .1
        .iter()
        .any(|d| d.seed == 2 && matches!(d.reason, DropReason::NoLoopAroundSaddle { .. })));
    let memo = LoopMemo::default();
    assert_eq!(search(&seeds, &memo), fresh[0]);
    assert_eq!(search(&strict, &memo), fresh[1]);
    // And the other way round.
    let memo = LoopMemo::default();
    assert_eq!(search(&strict, &memo), fresh[1]);
    assert_eq!(search(&seeds, &memo), fresh[0]);
}

/// The properties every tightened loop must have: closed polyline of surface points that
/// lie on mesh edges or vertices, no longer than the start, simple, straight across
/// every edge and with both angles ≥ π at every vertex it passes.
fn check_geodesic(
    mesh: &SurfaceMesh,
    topology: &Topology,
    points: &[[f64; 3]],
    surface_points: &[SurfacePoint],
    length: f64,
    initial_length: f64,
    t: &impl TighteningDiagnostics,
) {
    assert!(points.len() >= 3);
    assert_eq!(points.len(), surface_points.len());
    assert_ne!(points.first(), points.last(), "first point not repeated");
    assert!((closed_length(points) - length).abs() <= 1e-9 * length);
    assert!(
        length <= initial_length * (1.0 + 1e-12),
        "{length} > {initial_length}"
    );
    let edges: std::collections::HashSet<[u32; 2]> = topology.edges().iter().copied().collect();
    for (p, s) in points.iter().zip(surface_points) {
        let q = match *s {
            SurfacePoint::Vertex { vertex } => mesh.positions[vertex as usize],
            SurfacePoint::Edge { edge, t } => {
                assert!(edges.contains(&edge), "point on a mesh edge");
                assert!((0.0..=1.0).contains(&t));
                let (a, b) = (
                    mesh.positions[edge[0] as usize],
                    mesh.positions[edge[1] as usize],
                );
                [0, 1, 2].map(|k| a[k] + t * (b[k] - a[k]))
            }
        };
        assert!(
            (0..3).all(|k| (p[k] - q[k]).abs() < 1e-12),
            "on the surface"
        );
    }
    let (turn, vertex_angle, simple) = t.diagnostics();
    assert!(simple, "simple");
    assert!(turn < 1e-6, "straight across edges: turn {turn}");
    assert!(
        vertex_angle >= PI - 1e-5,
        "both angles >= pi at vertices: {vertex_angle}"
    );
}

trait TighteningDiagnostics {
    fn diagnostics(&self) -> (f64, f64, bool);
}

impl TighteningDiagnostics for Tightened {
    fn diagnostics(&self) -> (f64, f64, bool) {
        (self.max_edge_turn, self.min_vertex_angle, self.simple)
    }
}

impl TighteningDiagnostics for NeckLoop {
    fn diagnostics(&self) -> (f64, f64, bool) {
        let t = &self.tightening;
        (t.max_edge_turn, t.min_vertex_angle, t.simple)
    }
}

pub(crate) fn check_loop(mesh: &SurfaceMesh, topology: &Topology, l: &NeckLoop) {
    check_geodesic(
        mesh,
        topology,
        &l.points,
        &l.surface_points,
        l.length,
        l.initial_length,
        l,
    );
    assert!((l.radius - l.length / (2.0 * PI)).abs() < 1e-12);
    assert!((norm(l.normal) - 1.0).abs() < 1e-9);
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]])
}

/// Winding number of a loop's projection on the xy-plane around the point (x, y).
fn winding_xy(points: &[[f64; 3]], x: f64, y: f64) -> i64 {
    let n = points.len();
    let mut total = 0.0;
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        let a1 = (a[1] - y).atan2(a[0] - x);
        let b1 = (b[1] - y).atan2(b[0] - x);
        let mut d = b1 - a1;
        if d > PI {
            d -= 2.0 * PI;
        }
        if d < -PI {
            d += 2.0 * PI;
        }
        total += d;
    }
    (total / (2.0 * PI)).round() as i64
}

fn necks(shape: &Shape, handles: bool, tunnels: bool) -> NeckReport {
    let mesh = shape.mesh().unwrap();
    let options = NeckOptions {
        handles,
        tunnels,
        ..NeckOptions::default()
    };
    let report = find_necks(&mesh, &options).unwrap();
    let topology = Topology::new(&mesh);
    for l in &report.loops {
        check_loop(&mesh, &topology, l);
    }
    assert!(report.morse.iter().all(|m| m.ok));
    report
}

fn of_kind(report: &NeckReport, kind: Side) -> Vec<&NeckLoop> {
    report.loops.iter().filter(|l| l.kind == kind).collect()
}

#[test]
fn a_dumbbell_has_one_handle_loop_around_its_neck_and_no_tunnel() {
    let shape = Shape::new(ShapeKind::Dumbbell);
    let r = necks(&shape, true, true);
    let handles = of_kind(&r, Side::Inside);
    assert_eq!(handles.len(), 1, "{:?}", r.dropped);
    assert!(of_kind(&r, Side::Outside).is_empty());
    let l = handles[0];
    let expected = 2.0 * PI * shape.param("neck");
    assert!(
        (l.length - expected).abs() < 0.005 * expected,
        "{} vs {expected}",
        l.length
    );
    assert!(dist(l.center, [0.0; 3]) < 0.02, "{:?}", l.center);
    assert!(l.normal[0].abs() > 0.99);
    // The lasso is the neck's circle: its radius, round the axis, across it.
    let lasso = l.lasso.expect("a kept loop has its lasso");
    let neck = shape.param("neck");
    assert!((lasso.radius - neck).abs() < 0.005 * neck, "{lasso:?}");
    assert!(dist(lasso.center, [0.0; 3]) < 0.02, "{lasso:?}");
    assert!(lasso.normal[0].abs() > 0.99, "{lasso:?}");
    assert!(lasso.max_deviation < 0.02 * neck, "{lasso:?}");
    assert!(lasso.rms_deviation <= lasso.max_deviation);
}

#[test]
fn a_chain_of_three_balls_has_two_handle_loops() {
    let r = necks(&Shape::new(ShapeKind::Chain), true, false);
    let handles = of_kind(&r, Side::Inside);
    assert_eq!(handles.len(), 2, "{:?}", r.dropped);
    let mut xs: Vec<f64> = handles.iter().map(|l| l.center[0]).collect();
    xs.sort_by(f64::total_cmp);
    assert!(
        (xs[0] + 0.9).abs() < 0.02 && (xs[1] - 0.9).abs() < 0.02,
        "{xs:?}"
    );
}

#[test]
fn two_overlapping_balls_have_their_neck_loop_round_the_crossing_circle() {
    // Two unit spheres 1.6 apart, given as two closed meshes that cross: the solid is
    // their union, whose neck is the circle where they cross (x = 0, radius 0.6; a
    // bulge of 1/0.6). The caps buried in the other ball are no boundary of it:
    // measured to them, the distance had a valley inside the solid, and 2-saddles by
    // it.
    let balls = crate::common::union(&[
        crate::common::sphere(1.0, [-0.8, 0.0, 0.0], 24.0),
        crate::common::sphere(1.0, [0.8, 0.0, 0.0], 24.0),
    ]);
    let report = find_necks(
        &balls,
        &NeckOptions {
            tunnels: false,
            ..NeckOptions::default()
        },
    )
    .unwrap();
    // The distance to the union's boundary has one 2-saddle, at the circle's centre
    // (with the caps, a second one lay at x = −0.14, and 14 by the caps 1 apart).
    let saddles: Vec<[f64; 3]> = report.sides[0].saddles.iter().map(|s| s.position).collect();
    assert_eq!(saddles.len(), 1, "{saddles:?}");
    assert!(dist(saddles[0], [0.0; 3]) < 0.02, "{saddles:?}");
    assert_eq!(report.loops.len(), 1, "{:?}", report.dropped);
    let radius = 0.6;
    for p in &report.loops[0].points {
        let off = (p[1].hypot(p[2]) - radius).abs();
        assert!(p[0].abs() < 0.05 && off < 0.05, "{p:?}");
    }
}

#[test]
fn a_varying_torus_has_a_handle_at_its_thin_side_and_a_tunnel_around_its_hole() {
    let shape = Shape::new(ShapeKind::VaryingTorus);
    let r = necks(&shape, true, true);
    let handles = of_kind(&r, Side::Inside);
    assert_eq!(handles.len(), 1, "{:?}", r.dropped);
    let thin = 2.0 * PI * shape.param("r0") * (1.0 - shape.param("a"));
    assert!(
        (handles[0].length - thin).abs() < 0.01 * thin,
        "{}",
        handles[0].length
    );
    assert!(dist(handles[0].center, [-1.0, 0.0, 0.0]) < 0.02);
    let tunnels = of_kind(&r, Side::Outside);
    assert_eq!(tunnels.len(), 1, "{:?}", r.dropped);
    assert_eq!(winding_xy(&tunnels[0].points, 0.0, 0.0).abs(), 1);
    assert!(tunnels[0].normal[2].abs() > 0.99);
}

#[test]
fn an_eight_has_two_handle_loops_of_the_tube_radius_and_two_tunnels() {
    let shape = Shape::new(ShapeKind::Eight);
    let r = necks(&shape, true, true);
    let handles = of_kind(&r, Side::Inside);
    assert_eq!(handles.len(), 2, "{:?}", r.dropped);
    let tube = 2.0 * PI * shape.param("r");
    for l in &handles {
        assert!((l.length - tube).abs() < 0.01 * tube, "{}", l.length);
    }
    let tunnels = of_kind(&r, Side::Outside);
    assert_eq!(tunnels.len(), 2, "{:?}", r.dropped);
    let c = shape.param("c");
    let around: Vec<(i64, i64)> = tunnels
        .iter()
        .map(|l| {
            (
                winding_xy(&l.points, -c, 0.0).abs(),
                winding_xy(&l.points, c, 0.0).abs(),
            )
        })
        .collect();
    assert!(
        around.contains(&(1, 0)) && around.contains(&(0, 1)),
        "{around:?}"
    );
}

#[test]
fn a_torus_has_exactly_one_handle_of_its_tube_radius_and_one_tunnel() {
    let shape = Shape::new(ShapeKind::Torus);
    let r = necks(&shape, true, true);
    let handles = of_kind(&r, Side::Inside);
    assert_eq!(handles.len(), 1, "{:?}", r.dropped);
    let tube = 2.0 * PI * shape.param("r");
    assert!((handles[0].length - tube).abs() < 0.01 * tube);
    assert_eq!(of_kind(&r, Side::Outside).len(), 1, "{:?}", r.dropped);
    // Neither separates the torus; together they span its homology.
    for l in &r.loops {
        assert!(!l.separating && l.areas.is_none(), "{l:?}");
        assert_eq!(l.homology.len(), 2);
    }
    assert_ne!(r.loops[0].homology, r.loops[1].homology);
    // The other saddles of the uniform tube are the same cycle, or bumps whose loops
    // do not open out (a cylinder's opening is 0), and say so.
    assert!(r.dropped.iter().all(|d| match d.reason {
        DropReason::SameCycle { .. } | DropReason::Duplicate { .. } => true,
        DropReason::NotANeck { opening, .. } => opening.is_none_or(|o| o < 0.05),
        _ => false,
    }));
}

#[test]
fn a_pretzel_of_genus_3_has_three_handles_and_three_tunnels_of_rank_3_each() {
    let shape = Shape::new(ShapeKind::Pretzel).with("g", 3.0).unwrap();
    let r = necks(&shape, true, true);
    let rank = |kind| {
        let classes: Vec<Vec<u64>> = of_kind(&r, kind).iter().map(|l| l.class()).collect();
        (classes.len(), necklace::mesh::z2_rank(&classes))
    };
    assert_eq!(rank(Side::Inside), (3, 3), "{:?}", r.dropped);
    assert_eq!(rank(Side::Outside), (3, 3), "{:?}", r.dropped);
    let tube = 2.0 * PI * shape.param("r");
    for l in of_kind(&r, Side::Inside) {
        assert!((l.length - tube).abs() < 0.01 * tube, "{}", l.length);
    }
}

#[test]
fn a_dumbbell_neck_loop_separates_the_surface_into_two_equal_halves() {
    let r = necks(&Shape::new(ShapeKind::Dumbbell), true, false);
    let l = &r.loops[0];
    assert!(l.separating && l.homology.is_empty());
    let [a, b] = l.areas.unwrap();
    assert!((a - b).abs() < 0.02 * b, "{a} {b}");
    assert!(l.bulge.unwrap() > 2.0, "{:?}", l.bulge);
}

#[test]
fn every_satellite_neck_is_found_at_its_radius_and_there_is_no_tunnel() {
    let shape = Shape::new(ShapeKind::Satellites);
    let r = necks(&shape, true, true);
    assert!(of_kind(&r, Side::Outside).is_empty(), "{:?}", r.dropped);
    let mut handles = of_kind(&r, Side::Inside);
    handles.sort_by(|a, b| a.length.total_cmp(&b.length));
    let expected = shape.expected_necks();
    assert_eq!(handles.len(), expected.len(), "{:?}", r.dropped);
    for (l, e) in handles.iter().zip(&expected) {
        let length = e.length.unwrap();
        assert!(
            (l.length - length).abs() < 0.01 * length,
            "{} vs {length}",
            l.length
        );
        // Around its own neck, cutting a satellite off the body.
        assert!(dist(l.center, e.center.unwrap()) < 0.25, "{:?}", l.center);
        assert!(l.separating && l.bulge.unwrap() >= 1.5, "{l:?}");
    }
}

#[test]
fn shapes_without_a_narrow_part_have_no_loop() {
    // An ellipsoid, a uniform capsule (every circle of its cylinder equally narrow) and
    // a ball with a limb that tapers to its tip: nothing bulges beyond a narrow part.
    for kind in [ShapeKind::Ellipsoid, ShapeKind::Capsule, ShapeKind::Limb] {
        let r = necks(&Shape::new(kind), true, true);
        assert!(r.loops.is_empty(), "{kind}: {:?}", r.loops);
    }
}

#[test]
fn a_buckyball_has_a_handle_per_stick_and_a_tunnel_per_window() {
    let shape = Shape::new(ShapeKind::Buckyball);
    let r = necks(&shape, true, true);
    let handles = of_kind(&r, Side::Inside);
    let tunnels = of_kind(&r, Side::Outside);
    assert_eq!((handles.len(), tunnels.len()), (90, 32));
    let stick = 2.0 * PI * shape.param("stick");
    for l in &handles {
        assert!((l.length - stick).abs() < 0.01 * stick, "{}", l.length);
    }
    // Each stick once: the loops' centres are the 90 edge midpoints.
    let mut hit = vec![0; 90];
    for l in &handles {
        let nearest = shape
            .expected_necks()
            .iter()
            .take(90)
            .enumerate()
            .min_by(|a, b| {
                dist(a.1.center.unwrap(), l.center).total_cmp(&dist(b.1.center.unwrap(), l.center))
            })
            .unwrap()
            .0;
        hit[nearest] += 1;
    }
    assert!(hit.iter().all(|h| *h == 1), "{hit:?}");
    let rank = |kind| {
        let classes: Vec<Vec<u64>> = of_kind(&r, kind).iter().map(|l| l.class()).collect();
        necklace::mesh::z2_rank(&classes)
    };
    assert_eq!((rank(Side::Inside), rank(Side::Outside)), (31, 31));
    // A tunnel per window: 12 pentagons and 20 hexagons, told apart by their girth.
    let mut lengths: Vec<f64> = tunnels.iter().map(|l| l.length).collect();
    lengths.sort_by(f64::total_cmp);
    let pentagons = lengths
        .iter()
        .filter(|l| **l < 0.5 * (lengths[0] + lengths[31]))
        .count();
    assert_eq!(pentagons, 12, "{lengths:?}");
}

#[test]
fn the_whole_pipeline_gives_the_same_necks_with_one_and_two_threads() {
    let mesh = Shape::new(ShapeKind::Satellites)
        .with("res", 64.0)
        .unwrap()
        .mesh()
        .unwrap();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| find_necks(&mesh, &NeckOptions::default()).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.loops, b.loops);
    assert_eq!(a.dropped, b.dropped);
    for (x, y) in a.sides.iter().zip(&b.sides) {
        assert_eq!(x.saddles, y.saddles);
        assert_eq!(x.rejected, y.rejected);
        assert_eq!(x.bars, y.bars);
    }
}

#[test]
fn a_sphere_has_no_loop_inside_or_outside() {
    let r = necks(&Shape::new(ShapeKind::Sphere), true, true);
    assert!(r.loops.is_empty());
    assert!(r.dropped.is_empty());
}

#[test]
fn a_loop_that_slides_off_a_cap_is_dropped_as_collapsed() {
    let mesh = Shape::new(ShapeKind::Sphere).mesh().unwrap();
    // A small circle of a round sphere shrinks to a point when shortened.
    let seeds = [Seed {
        position: [0.0, 0.0, 0.5],
        normal: [0.0, 0.0, 1.0],
        persistence: 10,
        ..Seed::default()
    }];
    let r = find_loops(&mesh, &seeds, Side::Inside, &LoopOptions::default()).unwrap();
    assert!(r.loops.is_empty());
    assert_eq!(r.dropped.len(), 1);
    assert!(
        matches!(r.dropped[0].reason, DropReason::Collapsed { .. }),
        "{:?}",
        r.dropped
    );
}

/// The one tunnel loop of a bent ring, checked to go once around the z axis.
fn bent_ring_tunnel(bend: f64) {
    let shape = Shape::new(ShapeKind::BentRing).with("bend", bend).unwrap();
    let r = necks(&shape, true, true);
    let (handles, tunnels) = (of_kind(&r, Side::Inside), of_kind(&r, Side::Outside));
    assert_eq!((handles.len(), tunnels.len()), (1, 1), "{:?}", r.dropped);
    let expected = 2.0 * PI * shape.param("r");
    assert!((handles[0].length - expected).abs() < 0.01 * expected);
    let t = tunnels[0];
    assert_eq!(t.initial, Initial::Membrane);
    assert_eq!(winding_xy(&t.points, 0.0, 0.0).abs(), 1);
    // It goes round the hole inside the tube's core curve, whose shadow on z = 0 is the
    // circle of radius R: longer than the hole's inner circle, shorter than the core.
    let (big_r, rho) = (shape.param("R"), shape.param("r"));
    assert!(2.0 * PI * (big_r - rho) < t.length, "{}", t.length);
    assert!(t.length < 2.0 * PI * (big_r.powi(2) + 2.0 * bend.powi(2)).sqrt());
    for s in &r.sides {
        assert!(s.homology.ok, "{:?}", s.homology);
    }
    check_membranes(&shape.mesh().unwrap(), &r, &format!("bent-{bend}"));
}

/// Gauss's linking number of two closed polylines, by the midpoint rule over each pair
/// of segments (each polyline's segments split in `split`): accurate to a few
/// hundredths when the segments are short against the curves' distance.
fn linking_number(a: &[[f64; 3]], b: &[[f64; 3]], split: usize) -> f64 {
    let pieces = |p: &[[f64; 3]]| -> Vec<([f64; 3], [f64; 3])> {
        let n = p.len();
        (0..n)
            .flat_map(|i| {
                let (u, v) = (p[i], p[(i + 1) % n]);
                (0..split).map(move |k| {
                    let t = (k as f64 + 0.5) / split as f64;
                    let at = [0, 1, 2].map(|c| u[c] + t * (v[c] - u[c]));
                    let d = [0, 1, 2].map(|c| (v[c] - u[c]) / split as f64);
                    (at, d)
                })
            })
            .collect()
    };
    let (pa, pb) = (pieces(a), pieces(b));
    let mut total = 0.0;
    for (x, dx) in &pa {
        for (y, dy) in &pb {
            let r = [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
            let c = [
                dx[1] * dy[2] - dx[2] * dy[1],
                dx[2] * dy[0] - dx[0] * dy[2],
                dx[0] * dy[1] - dx[1] * dy[0],
            ];
            let d = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            total += (r[0] * c[0] + r[1] * c[1] + r[2] * c[2]) / (d * d * d);
        }
    }
    total / (4.0 * PI)
}

#[test]
fn a_knotted_tube_has_a_tunnel_loop_along_it_that_links_its_core_zero_times() {
    // A trefoil tube: no plane through an outside saddle cuts its tunnel loop, which runs
    // once along the tube and bounds a Seifert surface outside, not a disk. The linked
    // search finds it from the handle loop and the inside's cycle; the answer is checked
    // against the analytic core curve by Gauss's integral, independent of the code.
    let shape = Shape::new(ShapeKind::TorusKnot).with("res", 48.0).unwrap();
    let mesh = shape.mesh().unwrap();
    let r = find_necks(&mesh, &NeckOptions::default()).unwrap();
    let topology = Topology::new(&mesh);
    for l in &r.loops {
        check_loop(&mesh, &topology, l);
    }
    assert!(r.morse.iter().all(|m| m.ok));
    let (handles, tunnels) = (of_kind(&r, Side::Inside), of_kind(&r, Side::Outside));
    assert_eq!((handles.len(), tunnels.len()), (1, 1), "{:?}", r.dropped);
    for s in &r.sides {
        assert!(s.homology.ok, "{:?}", s.homology);
    }
    let core: Vec<[f64; 3]> = (0..2400)
        .map(|i| shape.knot_core(2.0 * PI * i as f64 / 2400.0))
        .collect();
    // The handle loop is a meridian: length 2πr, linking the core once.
    let h = handles[0];
    let expected = 2.0 * PI * shape.param("r");
    assert!(
        (h.length - expected).abs() < 0.02 * expected,
        "{}",
        h.length
    );
    let lk = linking_number(&h.points, &core, 4);
    assert!(
        (lk.abs() - 1.0).abs() < 0.05,
        "handle links the core {lk} times"
    );
    // The tunnel loop: a non-separating geodesic of linking number 0 with the core (so
    // it bounds outside) that runs once along the tube: between half the core's length
    // and a fifth more than it.
    let t = tunnels[0];
    assert_eq!(t.initial, Initial::Linked);
    assert!(!t.separating);
    let lk = linking_number(&t.points, &core, 4);
    assert!(lk.abs() < 0.05, "tunnel links the core {lk} times");
    let core_length = closed_length(&core);
    assert!(
        t.length < 1.2 * core_length,
        "{} against {core_length}",
        t.length
    );
    assert!(
        t.length > 0.5 * core_length,
        "{} against {core_length}",
        t.length
    );
    assert!(t.reason.contains("no disk"), "{}", t.reason);
    // The same loops on one thread.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| find_necks(&mesh, &NeckOptions::default()).unwrap());
    let lengths = |r: &NeckReport| r.loops.iter().map(|l| l.length).collect::<Vec<_>>();
    assert_eq!(lengths(&one), lengths(&r));
}

/// `membranes.ply` of a run reads back as one disk per loop (χ = 1, oriented) whose
/// boundary lies on the surface.
fn check_membranes(surface: &SurfaceMesh, report: &NeckReport, name: &str) {
    let dir =
        std::env::temp_dir().join(format!("necklace-membranes-{name}-{}", std::process::id()));
    let files = necklace::output::OutputOptions {
        picture: None,
        volume: false,
        html: false,
    };
    necklace::output::write_run(&dir, surface, report, &files, None).unwrap();
    let path = dir.join("membranes.ply");
    let bytes = std::fs::read(&path).unwrap();
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(400)]).to_string();
    assert!(header.contains("property int loop"), "{header}");
    let mesh = necklace::io::read_mesh(&path).unwrap();
    let topology = Topology::new(&mesh);
    let (component, count) = topology.components(&mesh);
    assert_eq!(count, report.loops.len());
    let mut chi = vec![0i64; count];
    for c in component.iter().flatten() {
        chi[*c as usize] += 1;
    }
    for [a, _] in topology.edges() {
        chi[component[*a as usize].unwrap() as usize] -= 1;
    }
    for t in &mesh.triangles {
        chi[component[t[0] as usize].unwrap() as usize] += 1;
    }
    assert!(chi.iter().all(|&x| x == 1), "{chi:?}");
    assert!(topology.inconsistently_oriented_edges(&mesh).is_empty());
    let distance = necklace::distance::SurfaceDistance::new(surface);
    for e in topology.boundary_edges() {
        for v in topology.edges()[e] {
            let d = distance.distance(mesh.positions[v as usize]);
            assert!(d < 1e-9 * surface.bbox_diagonal(), "{d}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_bent_ring_has_one_handle_and_one_tunnel_from_its_membrane() {
    // Both bends exceed the tube radius 0.15: no plane through the hole's centre
    // cuts a closed curve around it.
    bent_ring_tunnel(0.45);
    bent_ring_tunnel(-0.45);
}

#[test]
fn membrane_loops_agree_with_plane_loops_where_planes_work() {
    let options = |membranes| LoopOptions {
        membranes,
        slide_steps: 0,
        ..LoopOptions::default()
    };
    let torus = Shape::new(ShapeKind::Torus).mesh().unwrap();
    let dumbbell = Shape::new(ShapeKind::Dumbbell).mesh().unwrap();
    let x_normal = Seed {
        normal: [1.0, 0.0, 0.0],
        ..seed_on_z_axis(0.0)
    };
    let cases = [
        (&torus, seed_on_z_axis(0.0), Side::Outside),
        (&dumbbell, x_normal, Side::Inside),
    ];
    for (mesh, seed, kind) in cases {
        let by = |m| {
            let r = find_loops(mesh, &[seed], kind, &options(m)).unwrap();
            assert_eq!(r.loops.len(), 1, "{:?}", r.dropped);
            r.loops.into_iter().next().unwrap()
        };
        let (plane, membrane) = (by(MembraneUse::Never), by(MembraneUse::Always));
        assert_eq!(plane.initial, Initial::Plane);
        assert_eq!(membrane.initial, Initial::Membrane);
        assert!(
            (plane.length - membrane.length).abs() < 0.005 * plane.length,
            "{kind:?}: {} vs {}",
            plane.length,
            membrane.length
        );
    }
}

#[test]
fn a_plane_that_misses_the_saddle_gives_a_reasoned_drop_and_bad_seeds_an_error() {
    let mesh = Shape::new(ShapeKind::Sphere).mesh().unwrap();
    let outside = [Seed {
        position: [3.0, 0.0, 0.0],
        normal: [0.0, 0.0, 1.0],
        persistence: 5,
        ..Seed::default()
    }];
    // Its membrane lands on one side of the ball: not around the saddle's axis.
    let r = find_loops(&mesh, &outside, Side::Outside, &LoopOptions::default()).unwrap();
    assert!(matches!(
        r.dropped[0].reason,
        DropReason::NoMembraneLoop {
            failure: MembraneFailure::NotAround,
            closed_curves: 1,
            ..
        }
    ));
    let planes_only = LoopOptions {
        membranes: MembraneUse::Never,
        ..LoopOptions::default()
    };
    let r = find_loops(&mesh, &outside, Side::Outside, &planes_only).unwrap();
    assert!(matches!(
        r.dropped[0].reason,
        DropReason::NoLoopAroundSaddle {
            closed_curves: 1,
            ..
        }
    ));
    let zero = [Seed {
        normal: [0.0; 3],
        ..outside[0]
    }];
    let e = find_loops(&mesh, &zero, Side::Inside, &LoopOptions::default()).unwrap_err();
    assert_eq!(e.kind(), necklace::ErrorKind::InvalidArgument);
    let bad = LoopOptions {
        max_length: -1.0,
        ..LoopOptions::default()
    };
    assert!(find_loops(&mesh, &outside, Side::Inside, &bad).is_err());
}

/// A ring about the z axis (core circle of radius 1) whose round tube has radius
/// `tube(t)` at angle `t` of the core; `along` × `around` vertices.
fn ring_with_tube(tube: impl Fn(f64) -> f64, along: usize, around: usize) -> SurfaceMesh {
    let mut positions = Vec::with_capacity(along * around);
    for i in 0..along {
        let t = 2.0 * PI * i as f64 / along as f64;
        let rho = tube(t);
        for j in 0..around {
            let phi = 2.0 * PI * j as f64 / around as f64;
            let out = 1.0 + rho * phi.cos();
            positions.push([out * t.cos(), out * t.sin(), rho * phi.sin()]);
        }
    }
    SurfaceMesh::new(positions, ring_triangles(along, around)).unwrap()
}

#[test]
fn a_completion_loop_of_a_longer_selected_loops_class_takes_its_place() {
    // A ring with two waists, each a closed geodesic by the ring's mirror symmetry
    // through it: tube radius 0.1875 at t = π/2, 0.1375 at t = 3π/2. Their meridians
    // are of one class; a selected saddle's loop at the wider waist, a completion's at
    // the narrower.
    let tube = |t: f64| 0.25 * (1.0 + 0.35 * (2.0 * t).cos() + 0.1 * t.sin());
    let mesh = ring_with_tube(tube, 256, 64);
    let options = LoopOptions::default();
    let cut = |t: f64| {
        let seeds = [Seed {
            position: [t.cos(), t.sin(), 0.0],
            normal: [-t.sin(), t.cos(), 0.0],
            persistence: 5,
            role: Some(Role::CycleClosing),
            ..Seed::default()
        }];
        find_loops(&mesh, &seeds, Side::Inside, &options).unwrap()
    };
    let (wide, narrow) = (cut(PI / 2.0), cut(1.5 * PI));
    assert_eq!((wide.loops.len(), narrow.loops.len()), (1, 1));
    let (wide_length, narrow_length) = (wide.loops[0].length, narrow.loops[0].length);
    for (length, t) in [(wide_length, PI / 2.0), (narrow_length, 1.5 * PI)] {
        let circle = 2.0 * PI * tube(t);
        assert!(
            (length - circle).abs() < 0.01 * circle,
            "{length} vs {circle}"
        );
    }
    assert_eq!(wide.loops[0].homology, narrow.loops[0].homology);

    // The shorter loop of the class is kept, under its own seed (numbered after the
    // selected one), and the longer one is dropped as the same cycle.
    let mut found = wide.clone();
    complete_classes(&mut found, narrow.clone(), 1);
    assert_eq!(found.loops.len(), 1);
    assert_eq!(
        (found.loops[0].seed, found.loops[0].length),
        (1, narrow_length)
    );
    assert!(
        found.loops[0].reason.contains("replaces"),
        "{}",
        found.loops[0].reason
    );
    let dropped: Vec<_> = found.dropped.iter().filter(|d| d.seed == 0).collect();
    assert_eq!(dropped.len(), 1);
    assert!(matches!(
        dropped[0].reason,
        DropReason::SameCycle { of: Some(1), length } if length == wide_length
    ));

    // A neck by its bulge keeps its place: the completion is the same cycle.
    let mut by_shape = wide.clone();
    by_shape.loops[0].bulge = Some(2.0);
    complete_classes(&mut by_shape, narrow.clone(), 1);
    assert_eq!(by_shape.loops.len(), 1);
    assert_eq!(by_shape.loops[0].length, wide_length);
    assert!(by_shape
        .dropped
        .iter()
        .any(|d| d.seed == 1 && matches!(d.reason, DropReason::SameCycle { of: Some(0), .. })));

    // The other way round (the selected loop the shorter), nothing moves.
    let mut shorter_first = narrow;
    complete_classes(&mut shorter_first, wide, 1);
    assert_eq!(shorter_first.loops.len(), 1);
    assert_eq!(shorter_first.loops[0].length, narrow_length);
}

/// A seed on the z axis at height `z`, cutting with horizontal planes.
fn seed_on_z_axis(z: f64) -> Seed {
    Seed {
        position: [0.0, 0.0, z],
        normal: [0.0, 0.0, 1.0],
        persistence: 5,
        ..Seed::default()
    }
}

/// The one tunnel loop of `seeds`, checked to come from the plane `offset` away.
fn one_tunnel_loop(
    mesh: &SurfaceMesh,
    seeds: &[Seed],
    options: &LoopOptions,
    offset: f64,
) -> NeckLoop {
    let found = find_loops(mesh, seeds, Side::Outside, options).unwrap();
    assert_eq!(found.loops.len(), 1, "{:?}", found.dropped);
    let l = found.loops.into_iter().next().unwrap();
    assert!(
        (l.plane_offset - offset).abs() < 1e-12,
        "{} vs {offset}",
        l.plane_offset
    );
    l
}

#[test]
fn where_the_plane_through_the_saddle_misses_a_parallel_plane_gives_the_loop() {
    let shape = Shape::new(ShapeKind::Torus);
    let mesh = shape.mesh().unwrap();
    let (big_r, r) = (shape.param("R"), shape.param("r"));
    // Above the tube, on the hole's axis: the plane z = const misses the torus.
    let step = LoopOptions::default().offset_step * mesh.bbox_diagonal();
    let seeds = [seed_on_z_axis(r + 1.5 * step)];
    // The nearest plane that cuts the tube: two steps down (one step is still above).
    let planes_only = LoopOptions {
        membranes: MembraneUse::Never,
        ..LoopOptions::default()
    };
    let l = one_tunnel_loop(&mesh, &seeds, &planes_only, -2.0 * step);
    // It tightens to the hole's narrowest circle.
    let hole = 2.0 * PI * (big_r - r);
    assert!(
        (l.length - hole).abs() < 0.01 * hole,
        "{} vs {hole}",
        l.length
    );
    assert_eq!(winding_xy(&l.points, 0.0, 0.0).abs(), 1);

    // By default the membrane comes before the parallel planes: the same loop.
    let m = one_tunnel_loop(&mesh, &seeds, &LoopOptions::default(), 0.0);
    assert_eq!(m.initial, Initial::Membrane);
    assert!((m.length - l.length).abs() < 0.005 * l.length);

    // Without parallel planes the seed is dropped, with what was tried.
    let none = LoopOptions {
        plane_offsets: 0,
        ..planes_only
    };
    let missed = find_loops(&mesh, &seeds, Side::Outside, &none).unwrap();
    assert!(missed.loops.is_empty());
    assert!(matches!(
        missed.dropped[0].reason,
        DropReason::NoLoopAroundSaddle {
            closed_curves: 0,
            open_curves: 0,
            offsets_tried: 0,
            ..
        }
    ));
}

#[test]
fn a_window_with_a_curved_rim_finds_its_thin_band_of_planes() {
    // Planes cut the tube all the way round only for |z| < 0.003.
    let (a, rho) = (0.147, 0.15);
    let mesh = saddle_ring(a, rho, 256, 48);
    let band = rho - a;
    let step = LoopOptions::default().offset_step * mesh.bbox_diagonal();
    // The seed's own plane and the first step down miss; two steps down cut.
    let seeds = [seed_on_z_axis(band + 1.5 * step)];
    let options = LoopOptions {
        membranes: MembraneUse::Never,
        ..LoopOptions::default()
    };
    let l = one_tunnel_loop(&mesh, &seeds, &options, -2.0 * step);
    // Around the hole: its shadow on z = 0 winds once outside the disk of radius
    // 1 - rho, and it is shorter than the core circle.
    assert_eq!(winding_xy(&l.points, 0.0, 0.0).abs(), 1);
    assert!(
        2.0 * PI * (1.0 - rho) <= l.length && l.length < 2.0 * PI,
        "{}",
        l.length
    );

    // Planes four times as far apart (the spacing before) jump over the band.
    let coarse = LoopOptions {
        plane_offsets: 4,
        offset_step: 4.0 * LoopOptions::default().offset_step,
        ..options
    };
    assert!(4.0 * step > 2.0 * band);
    let missed = find_loops(&mesh, &seeds, Side::Outside, &coarse).unwrap();
    assert!(missed.loops.is_empty());
    assert!(matches!(
        missed.dropped[0].reason,
        DropReason::NoLoopAroundSaddle {
            offsets_tried: 4,
            ..
        }
    ));
}

#[test]
fn a_cycle_loop_slides_to_the_narrower_of_two_waists() {
    // Waists at z = ±0.05 (radii 0.2675 below, 0.2725 above) with a bump between them:
    // each is a closed geodesic that tightening alone keeps.
    let profile = |z: f64| {
        let r = 0.3 + 0.03 * (2.0 * PI * z / 0.1).cos() + 0.05 * z;
        r * (1.0 - z.powi(8)).max(0.0).sqrt()
    };
    let mesh = wavy_revolution(profile, 1.0, 400, 96, 0.4);
    let seeds = [Seed {
        position: [0.0, 0.0, 0.05],
        normal: [0.0, 0.0, 1.0],
        persistence: 5,
        role: Some(necklace::loops::Role::CycleClosing),
        ..Seed::default()
    }];
    // The surface is a sphere: its loops separate, so no homology selection here.
    let options = LoopOptions {
        homology_selection: false,
        ..LoopOptions::default()
    };
    let stuck = LoopOptions {
        slide_steps: 0,
        ..options
    };
    let ring = |r: f64| 2.0 * PI * r;
    let upper = find_loops(&mesh, &seeds, Side::Inside, &stuck).unwrap();
    assert_eq!(upper.loops.len(), 1, "{:?}", upper.dropped);
    assert!(
        (upper.loops[0].length - ring(0.2725)).abs() < 0.005 * ring(0.2725),
        "{}",
        upper.loops[0].length
    );
    let slid = find_loops(&mesh, &seeds, Side::Inside, &options).unwrap();
    assert_eq!(slid.loops.len(), 1, "{:?}", slid.dropped);
    let l = &slid.loops[0];
    assert!(
        (l.length - ring(0.2675)).abs() < 0.005 * ring(0.2675),
        "{}",
        l.length
    );
    assert!(l.plane_offset < -0.05 && l.center[2] < 0.0, "{l:?}");
}

#[test]
fn tightening_keeps_the_homology_class_of_the_curve_it_starts_from() {
    // Tightening moves the loop across vertices of the surface, a homotopy: the Z2
    // class of a plane's curve is the class of its geodesic (the narrowest-place search
    // skips tightening a plane's curve of another class than the loop's on this).
    let mesh = Shape::new(ShapeKind::Pretzel).mesh().unwrap();
    let topology = Topology::new(&mesh);
    let basis = HomologyBasis::new(&mesh, &topology);
    let geometry = SurfaceGeometry::new(&mesh, &topology);
    let (lo, hi) = mesh.bounding_box().unwrap();
    let golden = PI * (3.0 - 5f64.sqrt());
    let (mut essential, mut checked) = (0, 0);
    for j in 0..24 {
        // Normals over a hemisphere, origins along the box's diagonal.
        let z = (j as f64 + 0.5) / 24.0;
        let (r, phi) = ((1.0 - z * z).sqrt(), golden * j as f64);
        let normal = [r * phi.cos(), r * phi.sin(), z];
        let f = (j as f64 + 0.5) / 24.0;
        let origin = [0, 1, 2].map(|k| lo[k] + f * (hi[k] - lo[k]));
        let plane = Plane { origin, normal };
        for curve in plane_cut(&mesh, &topology, &plane)
            .into_iter()
            .filter(|c| c.closed)
        {
            let before = basis.class_of_crossings(curve.crossings.iter().map(|c| c.edge as usize));
            let t = tighten(
                &geometry,
                &curve.crossings,
                &curve.faces,
                &TightenOptions::default(),
            );
            if !matches!(t.status, TightenStatus::Converged | TightenStatus::Stalled) {
                continue;
            }
            let crossed = necklace::loops::classes::crossings(&mesh, &topology, &t.surface_points);
            let after = basis.class_of_crossings(crossed);
            assert_eq!(
                before, after,
                "plane {j}: length {} → {}",
                t.initial_length, t.length
            );
            checked += 1;
            essential += usize::from(before.iter().any(|w| *w != 0));
        }
    }
    assert!(
        checked >= 30 && essential >= 25,
        "{checked} loops, {essential} essential"
    );
}

#[test]
fn plane_cuts_through_vertices_still_give_closed_curves() {
    // The revolution mesh has whole rings of vertices exactly on z = ±k·h.
    let mesh = revolution(waist, 1.0, 20, 16);
    let topology = Topology::new(&mesh);
    let z = -1.0 + 2.0 * 10.0 / 20.0;
    let plane = Plane {
        origin: [0.0, 0.0, z],
        normal: [0.0, 0.0, 1.0],
    };
    let curves = plane_cut(&mesh, &topology, &plane);
    assert_eq!(curves.len(), 1);
    assert!(curves[0].closed);
    let ring = 2.0 * 16.0 * waist(z) * (PI / 16.0).sin();
    assert!((closed_length(&curves[0].points(&mesh, &topology)) - ring).abs() < 1e-9);
}

#[test]
fn a_cut_through_the_edge_tree_gives_the_curves_of_the_whole_surface_cut() {
    // The tree only narrows the edges looked at: the same curves, in the same order,
    // with the same crossings, also for planes through whole rings of vertices (the
    // revolution's rings lie exactly on z = ±k·h) and for planes that miss the surface.
    let golden = PI * (3.0 - 5f64.sqrt());
    let meshes = [
        revolution(waist, 1.0, 20, 16),
        Shape::new(ShapeKind::Pretzel).mesh().unwrap(),
    ];
    for_each_cutter(&meshes, |mesh, topology, cutter| {
        let (lo, hi) = mesh.bounding_box().unwrap();
        let mut planes: Vec<Plane> = (0..=20)
            .map(|k| Plane {
                origin: [0.0, 0.0, -1.0 + 0.1 * k as f64],
                normal: [0.0, 0.0, 1.0],
            })
            .collect();
        planes.extend((0..40).map(|j| {
            let z = (j as f64 + 0.5) / 40.0;
            let (r, phi) = ((1.0 - z * z).sqrt(), golden * j as f64);
            let f = -0.2 + 1.4 * j as f64 / 39.0;
            Plane {
                origin: [0, 1, 2].map(|k| lo[k] + f * (hi[k] - lo[k])),
                normal: [r * phi.cos(), r * phi.sin(), z],
            }
        }));
        let mut crossed = 0;
        for plane in &planes {
            let whole = plane_cut(mesh, topology, plane);
            assert_eq!(cutter.cut(plane), whole, "{plane:?}");
            crossed += whole.len();
        }
        assert!(crossed >= 40, "{crossed} curves");
    });
}

/// Calls `f` with each mesh, its topology and its cutter.
fn for_each_cutter(meshes: &[SurfaceMesh], mut f: impl FnMut(&SurfaceMesh, &Topology, &Cutter)) {
    for mesh in meshes {
        let topology = Topology::new(mesh);
        let tree = EdgeTree::new(mesh, &topology);
        let cutter = Cutter {
            mesh,
            topology: &topology,
            tree: &tree,
        };
        f(mesh, &topology, &cutter);
    }
}

#[test]
fn a_cut_round_a_point_keeps_the_curves_that_may_go_round_it_and_the_one_that_does() {
    // `Cutter::cut_round` walks only the curves near the line through the plane's
    // origin: they must come out as `Cutter::cut` gives them, in its order, and the
    // curve round the origin must be the one the whole cut has there; the islands found
    // inside each curve looking near it only must be those of the whole cut. Planes through
    // points on a grid over the box (in and out of the solid), with normals along the
    // axes (the revolution's rings lie exactly on such planes) and spread over the
    // sphere.
    let golden = PI * (3.0 - 5f64.sqrt());
    let mut normals: Vec<[f64; 3]> = vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    normals.extend((0..9).map(|j| {
        let z = (j as f64 + 0.5) / 9.0;
        let (r, phi) = ((1.0 - z * z).sqrt(), golden * j as f64);
        [r * phi.cos(), r * phi.sin(), z]
    }));
    let (mut fewer, mut round, mut islands) = (0, 0, 0);
    let meshes = [
        revolution(waist, 1.0, 20, 16),
        Shape::new(ShapeKind::Pretzel).mesh().unwrap(),
        Shape::new(ShapeKind::Torus).mesh().unwrap(),
    ];
    for_each_cutter(&meshes, |mesh, topology, cutter| {
        let (lo, hi) = mesh.bounding_box().unwrap();
        for i in 0..64 {
            let f = [i % 4, (i / 4) % 4, i / 16].map(|k| (k as f64 + 0.5) / 4.0);
            let origin = [0, 1, 2].map(|k| lo[k] + f[k] * (hi[k] - lo[k]));
            for &normal in &normals {
                let plane = Plane { origin, normal };
                let all = cutter.cut(&plane);
                let near = cutter.cut_round(&plane);
                // In the whole cut's order: each of them is one of its curves, later
                // than the one before.
                let mut from = 0;
                for curve in &near {
                    let at = all[from..].iter().position(|c| c == curve);
                    let at = at.unwrap_or_else(|| panic!("{plane:?}: a curve not in the cut"));
                    from += at + 1;
                }
                fewer += usize::from(near.len() < all.len());
                let pick = |curves: &[necklace::loops::cut::CutCurve]| {
                    loop_around(mesh, topology, &plane, curves, origin).map(|i| curves[i].clone())
                };
                let whole = pick(&all);
                assert_eq!(pick(&near), whole, "{plane:?}");
                round += usize::from(whole.is_some());
                // Islands inside a curve are found looking near it only.
                for (i, curve) in all.iter().enumerate() {
                    let inside = encloses_another(mesh, topology, &plane, &all, i);
                    assert_eq!(cutter.encloses_another_round(&plane, curve), inside);
                    islands += usize::from(inside);
                }
            }
        }
    });
    assert!(
        fewer >= 100 && round >= 100 && islands >= 20,
        "{fewer} cuts with fewer curves, {round} round the origin, {islands} with islands"
    );
}

#[test]
fn loops_do_not_depend_on_the_thread_count_and_duplicates_merge() {
    let shape = Shape::new(ShapeKind::Torus);
    let mesh = shape.mesh().unwrap();
    // Twelve seeds on the same meridian plane: one loop, eleven duplicates.
    let seeds: Vec<Seed> = (0..12)
        .map(|i| Seed {
            position: [1.0 + 0.01 * i as f64, 0.0, 0.0],
            normal: [0.0, 1.0, 0.0],
            persistence: 10 + i % 3,
            ..Seed::default()
        })
        .collect();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| find_loops(&mesh, &seeds, Side::Inside, &LoopOptions::default()).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.loops, b.loops);
    assert_eq!(a.dropped, b.dropped);
    assert_eq!(a.loops.len(), 1);
    assert_eq!(a.loops[0].duplicates.len(), 11);
    assert_eq!(
        a.loops[0].persistence, 12,
        "the most persistent seed is kept"
    );
    let tube = 2.0 * PI * shape.param("r");
    assert!((a.loops[0].length - tube).abs() < 0.01 * tube);
}

#[test]
fn every_loop_of_every_shared_model_is_a_closed_simple_geodesic() {
    let Some(files) = crate::common::shared_meshes() else {
        return;
    };
    let mut total = 0;
    for file in files {
        let mesh = necklace::io::read_mesh(&file).unwrap();
        let mesh = necklace::pipeline::prepare_input(mesh)
            .expect("a usable mesh")
            .mesh;
        // Both sides of every model, the wire sphere's shell too (1.4M tets, about two
        // minutes and 3 GB).
        let r = find_necks(&mesh, &NeckOptions::default()).unwrap();
        let topology = Topology::new(&mesh);
        for l in &r.loops {
            check_loop(&mesh, &topology, l);
        }
        // Every selected saddle ends as a loop or a reasoned drop (a linked loop has no
        // saddle).
        let saddles: usize = r.sides.iter().map(|s| s.saddles.len()).sum();
        let seeded = r.loops.iter().filter(|l| l.initial != Initial::Linked);
        assert_eq!(
            saddles,
            seeded.count() + r.dropped.len(),
            "{}",
            file.display()
        );
        println!(
            "{}: {} loops, {} dropped",
            file.display(),
            r.loops.len(),
            r.dropped.len()
        );
        // The interior vertices span a complex with the surface's genus as H1 rank,
        // and the superlevel sweep finds every one of its classes at every level.
        let genus: Option<i64> = necklace::MeshReport::new(&mesh)
            .component_details
            .iter()
            .map(|c| c.genus)
            .sum();
        for m in &r.morse {
            // The Morse sum holds at every level of both sides.
            assert!(m.ok, "{} {:?}: Morse sum", file.display(), m.side);
            assert!(
                m.cycles_ok,
                "{} {:?}: {:?}",
                file.display(),
                m.side,
                m.steps
            );
            if let Some(g) = genus {
                assert_eq!(m.cycle_rank as i64, g, "{} {:?}", file.display(), m.side);
            }
        }
        // On a surface of genus g the handle loops span the g handle classes (Z2).
        let inside = r.sides.iter().find(|s| s.side == Side::Inside).unwrap();
        assert!(
            inside.homology.ok,
            "{}: {:?}",
            file.display(),
            inside.homology
        );
        let count = |kind| of_kind(&r, kind).len();
        let name = file.file_name().unwrap().to_string_lossy();
        // Handles and tunnels together: a homology basis of the surface, 2g (a knotted
        // tube's tunnel from the linked search: checked below).
        if let Some(g) = genus {
            let classes: Vec<Vec<u64>> = r.loops.iter().map(NeckLoop::class).collect();
            assert_eq!(
                necklace::mesh::z2_rank(&classes) as i64,
                2 * g,
                "{}",
                file.display()
            );
        }
        match &*name {
            // The paper's figures: the kitten's tail and neck and its one tunnel; the
            // botijo's five handles. A torus: its tube and its hole.
            "kitten.off" => assert_eq!((count(Side::Inside), count(Side::Outside)), (2, 1)),
            "botijo.obj" => assert!(count(Side::Inside) >= 5),
            "torus.obj" => assert_eq!((count(Side::Inside), count(Side::Outside)), (1, 1)),
            "eight.off" => assert_eq!((count(Side::Inside), count(Side::Outside)), (2, 2)),
            // More than twice its genus in handles (the paper's Fig. 1): the mother's
            // arms and neck, the baby's neck, the mother's waist, the arch and the base.
            // Its holes' rims no plane closes around: their membranes give the tunnels.
            "fertility.off" => {
                assert!(count(Side::Inside) >= 8);
                let outside = r.sides.iter().find(|s| s.side == Side::Outside).unwrap();
                assert!(outside.homology.ok, "{name}: {:?}", outside.homology);
            }
            "skull.obj" => {
                let outside = r.sides.iter().find(|s| s.side == Side::Outside).unwrap();
                assert!(outside.homology.ok, "{name}: {:?}", outside.homology);
            }
            // A knotted tube: no loop on it bounds a disk outside (its tunnel bounds a
            // Seifert surface), so every tunnel saddle is dropped, with that reason, and
            // its one tunnel loop comes from the linked search.
            "trefoil_knot.obj" => {
                let tunnels = of_kind(&r, Side::Outside);
                assert_eq!(tunnels.len(), 1);
                assert_eq!(tunnels[0].initial, Initial::Linked);
                assert!(r.dropped.iter().any(|d| matches!(
                    d.reason,
                    DropReason::NoMembraneLoop {
                        failure: MembraneFailure::NotEmbedded,
                        ..
                    }
                )));
            }
            // A loop round every one of its 96 windows, whose rims are not flat.
            "wiresphere.obj" => {
                assert!(count(Side::Outside) >= 95);
                let outside = r.sides.iter().find(|s| s.side == Side::Outside).unwrap();
                assert!(outside.homology.ok, "{:?}", outside.homology);
            }
            _ => {}
        }
        total += r.loops.len();
    }
    assert!(total > 50);
}

#[test]
fn the_kitten_and_the_botijo_split_in_four_have_the_same_necks() {
    // The paper's figures: the kitten's tail and neck and its one tunnel; the botijo's
    // five handles and five tunnels, and the neck of the jug below its handles (a
    // neck by its opening).
    for (name, handles, tunnels) in [("kitten.off", 2, 1), ("botijo.obj", 6, 5)] {
        let file = crate::common::meshes_dir().join(name);
        if !file.exists() {
            println!("SKIPPED: no {}", file.display());
            return;
        }
        let mesh = necklace::io::read_mesh(&file).unwrap();
        let mesh = necklace::pipeline::prepare_input(mesh)
            .expect("a usable mesh")
            .mesh;
        let fine = crate::common::split_in_four(&mesh);
        assert_eq!(fine.triangles.len(), 4 * mesh.triangles.len());
        let (coarse, fine) = (
            find_necks(&mesh, &NeckOptions::default()).unwrap(),
            find_necks(&fine, &NeckOptions::default()).unwrap(),
        );
        let lengths = |r: &NeckReport, kind: Side| {
            let mut l: Vec<f64> = of_kind(r, kind).iter().map(|l| l.length).collect();
            l.sort_by(f64::total_cmp);
            l
        };
        for (kind, expected) in [(Side::Inside, handles), (Side::Outside, tunnels)] {
            let (a, b) = (lengths(&coarse, kind), lengths(&fine, kind));
            assert_eq!(
                (a.len(), b.len()),
                (expected, expected),
                "{name} {kind:?}: {a:?} vs {b:?}"
            );
            for (x, y) in a.iter().zip(&b) {
                assert!(
                    (x - y).abs() <= 0.005 * x,
                    "{name} {kind:?}: {a:?} vs {b:?}"
                );
            }
        }
    }
}

/// The opening of each side of the ring of vertices at z = 0 of a surface of
/// revolution over [−h, h] with profile `r` (radius `r(0)` there), smaller first.
fn opening_at_waist(r: impl Fn(f64) -> f64, h: f64) -> [f64; 2] {
    use necklace::loops::classes::crossings;
    use necklace::loops::opening::Openings;
    let (rings, segments) = (400, 240);
    let mesh = revolution(&r, h, rings, segments);
    let topology = Topology::new(&mesh);
    // Ring `rings / 2` lies at z = 0.
    let first = 1 + (rings / 2 - 1) * segments;
    let points: Vec<SurfacePoint> = (0..segments)
        .map(|j| SurfacePoint::Vertex {
            vertex: (first + j) as u32,
        })
        .collect();
    assert!(mesh.positions[first][2].abs() < 1e-12);
    let positions: Vec<[f64; 3]> = (0..segments).map(|j| mesh.positions[first + j]).collect();
    let crossed = crossings(&mesh, &topology, &points);
    let geometry = SurfaceGeometry::new(&mesh, &topology);
    Openings::new(&mesh, &topology, &geometry)
        .of_loop(&mesh, &topology, &points, &positions, &crossed, r(0.0))
        .unwrap()
}

/// `r(z_W) / r(0) − 1` where `z_W` is one radius `r(0)` of arc length up the profile:
/// what the opening is on the side z > 0, from the profile alone.
fn opening_from_profile(r: impl Fn(f64) -> f64) -> f64 {
    let (mut z, mut arc, dz) = (0.0, 0.0, 1e-6);
    while arc < r(0.0) {
        let slope = (r(z + dz) - r(z)) / dz;
        arc += dz * (1.0 + slope * slope).sqrt();
        z += dz;
    }
    r(z) / r(0.0) - 1.0
}

#[test]
fn the_opening_is_how_much_longer_the_parallel_curve_one_radius_away_is() {
    // Capped far from the waist (|z| > 0.8), where the measure does not reach.
    let cap = |z: f64| (1.0 - z.powi(16)).max(0.0).sqrt();
    // A cylinder neither opens nor closes.
    let cylinder = opening_at_waist(|z| 0.2 * cap(z), 1.0);
    assert!(cylinder.iter().all(|o| o.abs() < 0.01), "{cylinder:?}");
    // A hyperboloid of one sheet opens out on both sides, as its profile says: a
    // gentle waist and a sharp neck.
    for slope in [0.5f64, 1.5] {
        let hyperboloid = |z: f64| (0.04 + (slope * z).powi(2)).sqrt() * cap(z);
        let expected = opening_from_profile(hyperboloid);
        let o = opening_at_waist(hyperboloid, 1.0);
        for side in o {
            assert!(
                (side - expected).abs() < 0.03 * expected,
                "{o:?} vs {expected}"
            );
        }
    }
    // A cylinder ending in a hemisphere at its equator (a geodesic): the cylinder's
    // side stays at 0, the cap's side closes: the circle one radius up the sphere is
    // cos 1 as long. Not a neck.
    let capsule = |z: f64| {
        if z <= 0.0 {
            0.2
        } else {
            (0.04 - z * z).max(0.0).sqrt()
        }
    };
    let o = opening_at_waist(capsule, 0.2);
    assert!((o[0] - (1f64.cos() - 1.0)).abs() < 0.02, "{o:?}");
    assert!(o[1].abs() < 0.01, "{o:?}");
}

#[test]
fn surface_points_index_the_input_even_when_unused_vertices_are_dropped() {
    // A torus whose vertex list starts with three vertices no face uses (far away, so
    // they are not merely ignored): preparing drops them, the loops' surface points
    // must still name the input's vertices.
    let mut input = Shape::new(ShapeKind::Torus).mesh().unwrap();
    input.positions.splice(0..0, [[50.0, 0.0, 0.0]; 3]);
    for t in &mut input.triangles {
        *t = t.map(|v| v + 3);
    }
    let report = find_necks(&input, &NeckOptions::default()).unwrap();
    assert!(!report.loops.is_empty());
    for l in &report.loops {
        for (p, at) in l.points.iter().zip(&l.surface_points) {
            let q = match *at {
                SurfacePoint::Vertex { vertex } => input.positions[vertex as usize],
                SurfacePoint::Edge { edge, t } => {
                    let (a, b) = (
                        input.positions[edge[0] as usize],
                        input.positions[edge[1] as usize],
                    );
                    [0, 1, 2].map(|k| (1.0 - t) * a[k] + t * b[k])
                }
            };
            let gap = (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max);
            assert!(gap < 1e-9, "{p:?} vs {q:?}");
        }
    }
}

#[test]
fn both_sides_at_once_give_the_report_of_one_side_after_the_other() {
    let mesh = Shape::new(ShapeKind::Torus).mesh().unwrap();
    // At once, the meshes at once then the analyses one after the other (as on
    // large meshes), and one side after the other.
    let run = |sides_at_once: bool, at_once_max_tets: usize| {
        let report = find_necks(
            &mesh,
            &NeckOptions {
                sides_at_once,
                at_once_max_tets,
                ..NeckOptions::default()
            },
        )
        .unwrap();
        // Wall-clock seconds are all that may differ, and the budget each side was
        // given (half the run's when both run at once; it does not bind here).
        fn strip(value: &mut serde_json::Value) {
            match value {
                serde_json::Value::Object(map) => {
                    map.retain(|k, _| k != "timings" && k != "seconds" && k != "budget");
                    map.values_mut().for_each(strip);
                }
                serde_json::Value::Array(items) => items.iter_mut().for_each(strip),
                _ => {}
            }
        }
        let mut json = serde_json::to_value(&report).unwrap();
        strip(&mut json);
        (report.loops.len(), json)
    };
    let at_once = run(true, usize::MAX);
    assert_eq!(at_once.0, 2);
    assert_eq!(at_once.1, run(true, 0).1);
    assert_eq!(at_once.1, run(false, usize::MAX).1);
}

#[test]
fn a_seed_that_needs_a_disk_keeps_a_curve_only_where_no_other_lies_inside_it() {
    // A torus (R = 1, r = 0.3) cut by its equatorial plane: two concentric circles.
    // From a point in the tube, the curve around it is the outer circle, which has
    // the inner one inside it: the plane's region it bounds is an annulus of the solid,
    // not a disk, and the loop (the sum of the tunnel and the rim) bounds nothing
    // inside; so do the parallel planes'. The plane through the axis cuts two separate
    // meridians: disks.
    let torus = Shape::new(ShapeKind::Torus).mesh().unwrap();
    let in_tube = |normal| Seed {
        position: [1.0, 0.0, 0.0],
        normal,
        persistence: 5,
        role: Some(necklace::loops::Role::CycleClosing),
        disk_only: true,
        ..Seed::default()
    };
    let seeds = [in_tube([0.0, 0.0, 1.0]), in_tube([0.0, 1.0, 0.0])];
    let r = find_loops(&torus, &seeds, Side::Inside, &LoopOptions::default()).unwrap();
    assert_eq!(r.loops.len(), 1, "{:?}", r.dropped);
    assert_eq!(r.loops[0].seed, 1);
    let tube = 2.0 * PI * 0.3;
    assert!((r.loops[0].length - tube).abs() < 0.01 * tube);
    // The plane and every parallel one cut two concentric circles.
    let planes = 1 + 2 * LoopOptions::default().plane_offsets;
    assert!(
        matches!(r.dropped[0].reason, DropReason::NoDiskAroundSaddle { planes: p, .. } if p == planes),
        "{:?}",
        r.dropped
    );
    // Without the check the same equatorial seed gives a loop.
    let free = Seed {
        disk_only: false,
        ..seeds[0]
    };
    let r = find_loops(&torus, &[free], Side::Inside, &LoopOptions::default()).unwrap();
    assert_eq!(r.loops.len(), 1, "{:?}", r.dropped);
}

#[test]
fn a_seed_that_needs_a_disk_tries_parallel_planes_and_keeps_a_disk_of_its_own_side() {
    // On the axis of a torus (R = 1, r = 0.3), above it, the plane z = 0.35 meets
    // nothing (as where a short hole opens into a wider space and its saddle lies
    // beyond the hole's end). Parallel planes below cut the tube near its top; the
    // curve around the axis, the inner circle, bounds the disk across the hole, the
    // outside's, and tightens to the hole's rim 2π(R − r).
    let torus = Shape::new(ShapeKind::Torus).mesh().unwrap();
    let above = Seed {
        position: [0.0, 0.0, 0.35],
        normal: [0.0, 0.0, 1.0],
        persistence: 5,
        role: Some(necklace::loops::Role::CycleClosing),
        disk_only: true,
        ..Seed::default()
    };
    let r = find_loops(&torus, &[above], Side::Outside, &LoopOptions::default()).unwrap();
    assert_eq!(r.loops.len(), 1, "{:?}", r.dropped);
    assert!(r.loops[0].plane_offset < 0.0);
    let rim = 2.0 * PI * (1.0 - 0.3);
    assert!(
        (r.loops[0].length - rim).abs() < 0.01 * rim,
        "{}",
        r.loops[0].length
    );
    // Above a ball the parallel planes below cut its cap: a disk of the solid, which a
    // tunnel loop may not bound, so the seed is dropped for it.
    let ball = Shape::new(ShapeKind::Sphere);
    let over = Seed {
        position: [0.0, 0.0, 1.02 * ball.param("r")],
        ..above
    };
    let r = find_loops(
        &ball.mesh().unwrap(),
        &[over],
        Side::Outside,
        &LoopOptions::default(),
    )
    .unwrap();
    assert!(r.loops.is_empty());
    assert!(
        matches!(
            r.dropped[0].reason,
            DropReason::NoDiskAroundSaddle { planes, .. } if planes > 0
        ),
        "{:?}",
        r.dropped
    );
}

#[test]
fn where_the_selection_keeps_no_saddle_the_completions_find_every_handle_and_tunnel() {
    // No track lives 1000 levels, so the Morse stage selects nothing; the vertices
    // that close the essential cycles at each level (the completions), cut across
    // their upper links' axes, still give the torus' and the pretzel's loops: the
    // tube's meridian 2πr inside and the hole's rim 2π(R − r) outside, of full rank.
    for shape in [
        Shape::new(ShapeKind::Torus),
        Shape::new(ShapeKind::Pretzel).with("g", 2.0).unwrap(),
    ] {
        let mesh = shape.mesh().unwrap();
        let mut options = NeckOptions::default();
        options.morse.min_levels = 1000;
        let r = find_necks(&mesh, &options).unwrap();
        let topology = Topology::new(&mesh);
        let genus = shape.genus();
        for side in &r.sides {
            assert_eq!(
                side.homology.rank,
                genus,
                "{}: {:?}",
                shape.kind(),
                r.dropped
            );
        }
        assert_eq!(r.loops.len(), 2 * genus, "{:?}", r.dropped);
        let (big, small) = (shape.param("R"), shape.param("r"));
        for l in &r.loops {
            check_loop(&mesh, &topology, l);
            assert!(l.reason.starts_with("completes the genus"), "{}", l.reason);
            // Its seed is one of its side's completions (none was selected).
            let side = r.sides.iter().find(|s| s.side == l.kind).unwrap();
            let saddle = side.saddles[l.seed];
            assert_ne!(saddle.normal_from, NormalSource::Hessian);
            assert_eq!(saddle.position, l.saddle);
            let expected = match l.kind {
                Side::Inside => 2.0 * PI * small,
                Side::Outside => 2.0 * PI * (big - small),
            };
            assert!(
                (l.length - expected).abs() < 0.01 * expected,
                "{}: {:?} {} vs {expected}",
                shape.kind(),
                l.kind,
                l.length
            );
        }
    }
}

/// A square frame of `cell`-sized voxels: the plate `[0, 10]² × [0, 1]` without the hole
/// `[3, 7]²`, so four bars 3 wide and 1 thick. Outward quads split in two.
fn square_frame(cell: f64) -> SurfaceMesh {
    let n = (10.0 / cell).round() as i64;
    let (hole_lo, hole_hi) = ((3.0 / cell).round() as i64, (7.0 / cell).round() as i64);
    let layers = (1.0 / cell).round() as i64;
    let solid = |i: i64, j: i64, k: i64| {
        (0..n).contains(&i)
            && (0..n).contains(&j)
            && (0..layers).contains(&k)
            && !((hole_lo..hole_hi).contains(&i) && (hole_lo..hole_hi).contains(&j))
    };
    let mut index = std::collections::HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |p: [i64; 3]| {
        *index.entry(p).or_insert_with(|| {
            positions.push(p.map(|c| c as f64 * cell));
            positions.len() as u32 - 1
        })
    };
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..layers {
                if !solid(i, j, k) {
                    continue;
                }
                for axis in 0..3 {
                    for dir in [-1i64, 1] {
                        let mut next = [i, j, k];
                        next[axis] += dir;
                        if solid(next[0], next[1], next[2]) {
                            continue;
                        }
                        // The face's corners, counter-clockwise seen from outside.
                        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                        let mut base = [i, j, k];
                        if dir > 0 {
                            base[axis] += 1;
                        }
                        let corner = |du: i64, dv: i64| {
                            let mut c = base;
                            c[u] += du;
                            c[v] += dv;
                            c
                        };
                        let mut quad = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                        if dir < 0 {
                            quad.reverse();
                        }
                        let q = quad.map(&mut vertex);
                        triangles.push([q[0], q[1], q[2]]);
                        triangles.push([q[0], q[2], q[3]]);
                    }
                }
            }
        }
    }
    let mesh = SurfaceMesh::new(positions, triangles).unwrap();
    assert!(mesh.signed_volume() > 0.0);
    mesh
}

#[test]
fn a_saddle_on_a_plateau_whose_plane_separates_turns_the_plane_round_its_bar() {
    // A bar wider than the plate is thick: the distance is flat on its mid-plane, so
    // the Hessian's normal may run along the bar. The plane x = 1.4 through the left
    // bar cuts the whole plate without meeting the hole: a loop 22 long that separates.
    // Turned, the shortest essential section through the saddle is the bar's, a
    // rectangle 3 × 1 round: 8 long.
    let frame = square_frame(0.5);
    let seed = Seed {
        position: [1.4, 5.1, 0.45],
        normal: [1.0, 0.0, 0.0],
        persistence: 5,
        role: Some(Role::CycleClosing),
        ..Seed::default()
    };
    let found = find_loops(&frame, &[seed], Side::Inside, &LoopOptions::default()).unwrap();
    assert_eq!(found.loops.len(), 1, "{:?}", found.dropped);
    let l = &found.loops[0];
    assert_eq!(l.initial, Initial::TurnedPlane);
    assert!(!l.separating);
    assert!((l.length - 8.0).abs() < 0.02 * 8.0, "length {}", l.length);
    // Not turned, the separating loop is dropped with its reason.
    let options = LoopOptions {
        turned_planes: 0,
        ..LoopOptions::default()
    };
    let found = find_loops(&frame, &[seed], Side::Inside, &options).unwrap();
    assert!(found.loops.is_empty());
    assert!(
        matches!(found.dropped[0].reason, DropReason::NotEssential { length } if length > 20.0),
        "{:?}",
        found.dropped
    );
}
