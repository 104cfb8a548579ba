//! The volume mesh has the surface's topology (issue 12): predictions from the surface,
//! many small parts, needles and plates at the budget, refusals, the angle bound in
//! refined thin parts.

use crate::common::{sphere, split_in_four, union, Inside};

use necklace::shapes::{Shape, ShapeKind};
use necklace::tet::{ComponentTopology, TetTopology, VertexKind};
use necklace::volume::{expected_topology, volume_mesh, VolumeOptions, BYTES_PER_TET};
use necklace::volume::{stuff_volume, StuffingOptions};
use necklace::Side;
use necklace::{ErrorKind, SurfaceMesh};

fn component(euler: i64, boundary: &[i64]) -> ComponentTopology {
    ComponentTopology {
        euler,
        boundary_eulers: boundary.to_vec(),
    }
}

/// A box `lo..hi` as 12 outward triangles.
fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> SurfaceMesh {
    let corner = |c: usize| {
        [
            if c & 1 == 0 { lo[0] } else { hi[0] },
            if c & 2 == 0 { lo[1] } else { hi[1] },
            if c & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut triangles = Vec::new();
    for q in quads {
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
    }
    let m = SurfaceMesh::new((0..8).map(corner).collect(), triangles).unwrap();
    assert!(m.signed_volume() > 0.0);
    m
}

/// `n` regular tetrahedra of edge `a` on a square grid, `3a` apart.
fn tetrahedra(n: usize, a: f64) -> SurfaceMesh {
    let s = a / (2.0 * 2f64.sqrt());
    let corners = [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    let side = (n as f64).sqrt().ceil() as usize;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..n {
        let offset = [
            3.0 * a * (k % side) as f64,
            3.0 * a * (k / side) as f64,
            0.0,
        ];
        let first = positions.len() as u32;
        for c in corners {
            positions.push([0, 1, 2].map(|i| offset[i] + s * c[i]));
        }
        for f in [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]] {
            triangles.push(f.map(|i| first + i));
        }
    }
    let mut m = SurfaceMesh::new(positions, triangles).unwrap();
    if m.signed_volume() < 0.0 {
        m.flip_orientation();
    }
    m
}

#[test]
fn the_surface_predicts_components_and_boundaries_from_genus_and_nesting() {
    // A ball: inside one component bounded by a sphere; outside the shell between it
    // and the outer sphere.
    let ball = sphere(1.0, [0.0; 3], 16.0);
    assert_eq!(
        expected_topology(&ball, Side::Inside),
        Some(TetTopology::new(vec![component(1, &[2])]))
    );
    assert_eq!(
        expected_topology(&ball, Side::Outside),
        Some(TetTopology::new(vec![component(2, &[2, 2])]))
    );
    // A torus: χ 0 inside, 1 outside.
    let torus = Shape::new(ShapeKind::Torus).mesh().unwrap();
    assert_eq!(
        expected_topology(&torus, Side::Inside),
        Some(TetTopology::new(vec![component(0, &[0])]))
    );
    assert_eq!(
        expected_topology(&torus, Side::Outside),
        Some(TetTopology::new(vec![component(1, &[2, 0])]))
    );
    // A hollow ball with a ball floating in its cavity: two solids (the shell with two
    // boundaries, the inner ball); outside, the space beyond and the cavity (bounded by
    // the cavity's wall and the inner ball).
    let mut cavity = sphere(0.7, [0.0; 3], 16.0);
    cavity.flip_orientation();
    let nested = union(&[ball.clone(), cavity, sphere(0.3, [0.0; 3], 12.0)]);
    assert_eq!(
        expected_topology(&nested, Side::Inside),
        Some(TetTopology::new(vec![
            component(2, &[2, 2]),
            component(1, &[2])
        ]))
    );
    assert_eq!(
        expected_topology(&nested, Side::Outside),
        Some(TetTopology::new(vec![
            component(2, &[2, 2]),
            component(2, &[2, 2])
        ]))
    );
    // Two balls that overlap cross each other: no prediction.
    let overlapping = union(&[ball.clone(), sphere(1.0, [1.0, 0.0, 0.0], 16.0)]);
    assert_eq!(expected_topology(&overlapping, Side::Inside), None);
}

#[test]
fn a_hollow_ball_with_a_ball_inside_meshes_as_predicted_on_both_sides() {
    let mut cavity = sphere(0.7, [0.0; 3], 24.0);
    cavity.flip_orientation();
    let nested = union(&[
        sphere(1.0, [0.0; 3], 24.0),
        cavity,
        sphere(0.3, [0.0; 3], 16.0),
    ]);
    for side in [Side::Inside, Side::Outside] {
        let v = volume_mesh(&nested, side, &VolumeOptions::default()).unwrap();
        assert_eq!(v.topology.matches, Some(true), "{side:?}: {:?}", v.topology);
        assert_eq!(v.topology.found.components.len(), 2);
    }
}

#[test]
fn four_hundred_separate_tetrahedra_are_four_hundred_components_with_their_volume() {
    let surface = tetrahedra(400, 1.0);
    let exact = surface.signed_volume();
    let v = volume_mesh(&surface, Side::Inside, &VolumeOptions::default()).unwrap();
    let r = v.report();
    println!("{:?}", r.stuffing);
    assert_eq!(r.topology.matches, Some(true), "{}", r.topology.found);
    assert_eq!(r.components, 400);
    assert!(r
        .topology
        .found
        .components
        .iter()
        .all(|c| *c == component(1, &[2])));
    assert!(
        (r.volume - exact).abs() / exact < 0.02,
        "volume {} against {exact}",
        r.volume
    );
    assert!(r.min_dihedral_deg >= 8.0, "{}", r.min_dihedral_deg);
}

/// Two slabs 10 × 10 × 1, one above the other, `gap` apart, drawn with edges of 1.25 so
/// that their faces' vertices look squarely across the gap.
fn two_slabs_a_hair_apart(gap: f64) -> SurfaceMesh {
    let slab = |z: f64| {
        let mut m = cuboid([0.0, 0.0, z], [10.0, 10.0, z + 1.0]);
        for _ in 0..3 {
            m = split_in_four(&m);
        }
        m
    };
    union(&[slab(0.0), slab(1.0 + gap)])
}

#[test]
fn a_gap_between_grids_is_seen_at_its_vertices_and_kept_on_both_sides() {
    // Thinner than 1/20 of the faces' edges (1.25), but across to another part: a gap,
    // not a fold of the surface.
    let gap = 0.06;
    let slabs = two_slabs_a_hair_apart(gap);
    let options = VolumeOptions::default();
    // Inside: two slabs, kept apart, with their volume. The gap (h = diagonal / 64 =
    // 0.22) is measured at the vertices of the faces across it, whose rays straight
    // across run along the faces of the distance hierarchy's boxes (at least the 7 × 7
    // inner vertices of each face).
    let inside = volume_mesh(&slabs, Side::Inside, &options).unwrap();
    let r = inside.report();
    assert!(r.thin_vertices >= 98, "{} thin vertices", r.thin_vertices);
    assert_eq!(r.topology.matches, Some(true), "{}", r.topology.found);
    assert_eq!(r.components, 2);
    assert!((r.volume - 200.0).abs() < 1.0, "volume {}", r.volume);
    // Outside: the shell reaches into the gap, with interior vertices across all of it
    // (the field the tunnels are read from has room there).
    let outside = volume_mesh(&slabs, Side::Outside, &options).unwrap();
    let r = outside.report();
    assert_eq!(r.topology.matches, Some(true), "{}", r.topology.found);
    let mesh = &outside.mesh;
    let mut found = [[false; 8]; 8];
    for (p, kind) in mesh.positions.iter().zip(&mesh.kinds) {
        let in_gap = p[2] > 1.0 && p[2] < 1.0 + gap && (1.0..9.0).contains(&p[0]);
        if *kind == VertexKind::Interior && in_gap && (1.0..9.0).contains(&p[1]) {
            found[(p[0] - 1.0) as usize][(p[1] - 1.0) as usize] = true;
        }
    }
    assert!(found.iter().flatten().all(|&f| f), "{found:?}");
}

#[test]
fn two_cubes_drawn_with_their_corners_keep_the_gap_between_them_on_both_sides() {
    // Two cubes of side 10, 0.2 apart, each drawn with its 8 corners: no vertex looks
    // across the gap (their normals run along the cubes' diagonals), and the first
    // meshing (h = diagonal / 64 = 0.39) joins them. The thickness sampled over the
    // triangles finds the gap: 1/50 of the triangles' edges, but across to another
    // part, so not a fold of the surface.
    let cubes = union(&[
        cuboid([0.0; 3], [10.0; 3]),
        cuboid([10.2, 0.0, 0.0], [20.2, 10.0, 10.0]),
    ]);
    for side in [Side::Inside, Side::Outside] {
        let v = volume_mesh(&cubes, side, &VolumeOptions::default()).unwrap();
        let r = v.report();
        assert_eq!(
            r.topology.matches,
            Some(true),
            "{side:?}: {}",
            r.topology.found
        );
        assert_eq!(v.thin_vertices, 0, "{side:?}");
        assert!(v.thickness_samples > 0, "{side:?}");
        assert_eq!(r.topology.rounds, 2, "{side:?}");
        if side == Side::Inside {
            assert_eq!(r.components, 2);
            assert!((r.volume - 2000.0).abs() < 20.0, "volume {}", r.volume);
        }
    }
}

/// A valid mesh (positive tets, one component) or a one-line refusal that names the
/// budget's option.
fn valid_or_refused(surface: &SurfaceMesh, side: Side, options: &VolumeOptions) {
    match volume_mesh(surface, side, options) {
        Ok(v) => {
            let m = &v.mesh;
            assert!(m.num_tets() > 0);
            assert!((0..m.num_tets()).all(|t| m.tet_volume(t) > 0.0));
            let max_tets = options.max_memory as f64 / BYTES_PER_TET;
            assert!(m.num_tets() as f64 <= max_tets, "{} tets", m.num_tets());
            // Whatever the budget left unresolved is said.
            if v.topology.matches != Some(true) {
                assert!(!v.warnings.is_empty(), "{side:?}: {:?}", v.topology);
            }
        }
        Err(e) => {
            let text = e.to_string();
            assert!(!text.contains('\n'), "{text}");
            assert!(
                e.kind() == ErrorKind::OverBudget && text.contains("--max-memory"),
                "{side:?}: {text}"
            );
        }
    }
}

#[test]
fn a_needle_and_a_thin_plate_give_a_valid_mesh_or_a_one_line_refusal() {
    // A needle 10⁵ times longer than thick, and a plate 10⁻⁷ thick; a small budget
    // keeps the test quick (the default one behaves the same, later).
    let options = VolumeOptions {
        max_memory: (2e6 * BYTES_PER_TET) as u64,
        ..VolumeOptions::default()
    };
    let needle = cuboid([0.0; 3], [1.0, 1e-5, 1e-5]);
    let plate = cuboid([0.0; 3], [1.0, 1.0, 1e-7]);
    for surface in [&needle, &plate] {
        for side in [Side::Inside, Side::Outside] {
            valid_or_refused(surface, side, &options);
        }
    }
    // The plate's solid is thinner than any cell the budget allows: refused at once.
    let err = volume_mesh(&plate, Side::Inside, &options).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::OverBudget, "{err}");
}

#[test]
fn a_mesh_over_the_budget_is_refused_with_its_estimate() {
    let ball = sphere(1.0, [0.0; 3], 16.0);
    // 1000 tets' worth of memory.
    let options = VolumeOptions {
        max_memory: (1000.0 * BYTES_PER_TET) as u64,
        ..VolumeOptions::default()
    };
    let err = volume_mesh(&ball, Side::Inside, &options).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::OverBudget);
    let text = err.to_string();
    assert!(
        text.contains("tets") && text.contains("400 kB") && text.contains("--max-memory"),
        "{text}"
    );
    // And the budget never lets a mesh through above it.
    let options = VolumeOptions {
        max_memory: (50_000.0 * BYTES_PER_TET) as u64,
        ..VolumeOptions::default()
    };
    if let Ok(v) = volume_mesh(&ball, Side::Inside, &options) {
        assert!(v.mesh.num_tets() <= 50_000);
    }
}

#[test]
fn an_empty_volume_mesh_is_an_error() {
    // A ball far smaller than one cell, without sizing: no lattice vertex inside.
    let tiny = Shape::new(ShapeKind::Sphere);
    let err = stuff_volume(&Inside(tiny), &StuffingOptions::new(100.0)).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidMesh);
    assert!(err.to_string().contains("empty"), "{err}");
}

#[test]
fn refined_thin_parts_keep_dihedral_angles_above_eight_degrees() {
    // Dumbbells with necks thinner than 2h (h = 0.049): graded cells along the neck.
    for neck in [0.02, 0.03] {
        let surface = Shape::from_name("dumbbell", &[("neck".into(), neck), ("res".into(), 256.0)])
            .unwrap()
            .mesh()
            .unwrap();
        for side in [Side::Inside, Side::Outside] {
            let v = volume_mesh(&surface, side, &VolumeOptions::default()).unwrap();
            let r = v.report();
            assert!(r.finest_cell < r.h, "neck {neck}: not refined");
            assert!(
                r.min_dihedral_deg >= 8.0,
                "neck {neck} {side:?}: {}",
                r.min_dihedral_deg
            );
            assert_eq!(r.topology.matches, Some(true), "neck {neck} {side:?}");
            // The histogram holds six angles per tet.
            assert_eq!(r.dihedral_histogram.iter().sum::<usize>(), 6 * r.tets);
        }
    }
}

#[test]
fn a_side_that_fails_stops_the_other_and_its_error_is_the_runs() {
    use necklace::error::ErrorKind;
    use necklace::pipeline::{find_necks_with_progress, NeckOptions};
    use necklace::progress::Progress;
    use std::sync::Mutex;

    /// Records the names of the stages that start.
    struct Stages(Mutex<Vec<String>>);
    impl Progress for Stages {
        fn start_lane(&self, _lane: usize, stage: &str, _total: u64) {
            self.0.lock().unwrap().push(stage.to_string());
        }
        fn advance_lane(&self, _lane: usize, _units: u64) {}
        fn finish_lane(&self, _lane: usize) {}
    }

    // A plate thinner than any cell the budget allows: its inside is refused at once,
    // its outside meshes (with a warning). One thread: the inside runs first.
    let plate = cuboid([0.0; 3], [1.0, 1.0, 1e-4]);
    let options = NeckOptions {
        volume: VolumeOptions {
            max_memory: (400_000.0 * BYTES_PER_TET) as u64,
            ..VolumeOptions::default()
        },
        ..NeckOptions::default()
    };
    let stages = Stages(Mutex::new(Vec::new()));
    let err = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| find_necks_with_progress(&plate, &options, &stages))
        .unwrap_err();
    assert_eq!(err.kind(), ErrorKind::OverBudget, "{err}");
    let stages = stages.0.into_inner().unwrap();
    assert!(
        stages.contains(&"volume mesh (outside)".to_string()),
        "{stages:?}"
    );
    assert!(
        !stages.iter().any(|s| s.starts_with("smoothing")),
        "the outside went on after the inside failed: {stages:?}"
    );
}

/// The surface's solid with the signs callers vouch for ignored: the default
/// [`Domain::values_within_signed`], everything else the wrapped domain's.
struct IgnoringSigns<'a>(necklace::volume::SurfaceInside<'a>);

impl necklace::volume::Domain for IgnoringSigns<'_> {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.0.value(p)
    }
    fn values(&self, points: &[[f64; 3]]) -> Vec<f64> {
        self.0.values(points)
    }
    fn values_within(&self, points: &[[f64; 3]], band: f64) -> Vec<f64> {
        self.0.values_within(points, band)
    }
    fn crossing(&self, a: [f64; 3], b: [f64; 3]) -> Option<f64> {
        self.0.crossing(a, b)
    }
    fn project(&self, p: [f64; 3]) -> [f64; 3] {
        self.0.project(p)
    }
    fn boundary_kind(&self, p: [f64; 3]) -> necklace::VertexKind {
        self.0.boundary_kind(p)
    }
    fn distance_within(&self, p: [f64; 3], limit: f64) -> f64 {
        self.0.distance_within(p, limit)
    }
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.0.bounds()
    }
}

/// The octree takes a cell's sign from its parent where the parent's value says no
/// boundary lies between them, instead of asking the winding number (the cost of a
/// signed distance far from a surface that crosses itself). On two spheres that
/// cross, inside and in the shell round them, the meshes are the ones the winding
/// number gives.
#[test]
fn signs_taken_from_the_parent_cell_give_the_mesh_the_winding_number_gives() {
    use necklace::distance::SurfaceDistance;
    use necklace::volume::{Domain, SharpFeatures, Shell, SurfaceInside};
    let mesh = union(&[
        sphere(1.0, [0.0; 3], 12.0),
        sphere(0.8, [1.2, 0.3, 0.1], 12.0),
    ]);
    let distance = SurfaceDistance::of_surface(&mesh);
    assert!(
        !distance.crossings().unwrap().is_empty(),
        "the spheres cross"
    );
    let inside = || SurfaceInside {
        distance: &distance,
        bounds: ([-1.0, -1.0, -1.0], [2.0, 1.1, 0.9]),
        sizing: Vec::new(),
        features: SharpFeatures::default(),
    };
    let options = StuffingOptions::new(0.1);
    let same = |a: &dyn Domain, b: &dyn Domain, what: &str| {
        let (a, b) = (
            stuff_volume(a, &options).unwrap(),
            stuff_volume(b, &options).unwrap(),
        );
        assert!(a.mesh.num_tets() > 1000, "{what}: {}", a.mesh.num_tets());
        assert_eq!(a.mesh.tets, b.mesh.tets, "{what}");
        assert_eq!(a.mesh.positions, b.mesh.positions, "{what}");
    };
    same(&inside(), &IgnoringSigns(inside()), "inside");
    let centre = [0.5, 0.05, -0.05];
    same(
        &Shell::new(inside(), centre, 3.0),
        &Shell::new(IgnoringSigns(inside()), centre, 3.0),
        "shell",
    );
}
