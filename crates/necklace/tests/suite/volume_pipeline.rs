//! Volume meshes of real and generated surfaces through the pipeline (exact distance,
//! winding-number sign, thin-part refinement), against invariants and closed forms.

use std::f64::consts::PI;

use crate::common::{sphere, union};

use necklace::morse::{MorseOptions, Schedule, SolverOptions};
use necklace::pipeline::{critical_points, surface_morse_expected};
use necklace::shapes::{Shape, ShapeKind};
use necklace::volume::{volume_mesh, Mesher, VolumeOptions};
use necklace::Side;
use necklace::{io, TetMesh, VertexKind};

/// Connected components of the tets (through shared vertices).
fn components(m: &TetMesh) -> usize {
    let mut parent: Vec<usize> = (0..m.num_vertices()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for t in &m.tets {
        for k in 1..4 {
            let (a, b) = (
                find(&mut parent, t[0] as usize),
                find(&mut parent, t[k] as usize),
            );
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut used = vec![false; m.num_vertices()];
    for t in &m.tets {
        for &v in t {
            used[v as usize] = true;
        }
    }
    (0..m.num_vertices())
        .filter(|&v| used[v] && find(&mut parent, v) == v)
        .count()
}

#[test]
fn a_thin_dumbbell_neck_keeps_interior_vertices() {
    // Neck radius 0.05 on a dumbbell 2.8 long: thinner than 3h at the default h, so the
    // mesher refines there.
    let surface = Shape::from_name("dumbbell", &[("neck".into(), 0.05), ("res".into(), 128.0)])
        .unwrap()
        .mesh()
        .unwrap();
    let v = volume_mesh(&surface, Side::Inside, &VolumeOptions::default()).unwrap();
    let m = &v.mesh;
    let in_neck = m
        .positions
        .iter()
        .zip(&m.kinds)
        .filter(|(p, k)| {
            **k == VertexKind::Interior
                && p[0].abs() < 0.2
                && (p[1] * p[1] + p[2] * p[2]).sqrt() < 0.05
        })
        .count();
    assert!(in_neck > 0, "no interior vertex in the neck");
    assert_eq!(components(m), 1, "the neck must connect the two balls");
    assert_eq!(m.euler_characteristic(), 1);
}

#[test]
fn an_open_sphere_meshes_as_the_solid_it_bounds() {
    let closed = sphere(1.0, [0.0; 3], 24.0);
    let reference = closed.signed_volume();
    let mut open = closed.clone();
    // Cut a cap (z > 0.9) out: a hole of radius about 0.44.
    open.triangles
        .retain(|t| t.iter().all(|&v| open.positions[v as usize][2] < 0.9));
    assert!(open.triangles.len() < closed.triangles.len());
    let v = volume_mesh(&open, Side::Inside, &VolumeOptions::default()).unwrap();
    let volume = v.mesh.volume();
    assert!(
        (volume - reference).abs() / reference < 0.02,
        "{volume} vs {reference}"
    );
    assert_eq!(v.mesh.euler_characteristic(), 1);
}

#[test]
fn two_overlapping_spheres_mesh_as_their_union() {
    // Two unit spheres 1 apart, given as two intersecting closed meshes.
    let a = sphere(1.0, [-0.5, 0.0, 0.0], 24.0);
    let b = sphere(1.0, [0.5, 0.0, 0.0], 24.0);
    let both = union(&[a, b]);
    let v = volume_mesh(&both, Side::Inside, &VolumeOptions::default()).unwrap();
    // Union = two balls − lens, lens = π (4r + d)(2r − d)² / 12.
    let exact = 2.0 * 4.0 / 3.0 * PI - PI * 5.0 / 12.0;
    let volume = v.mesh.volume();
    assert!((volume - exact).abs() / exact < 0.02, "{volume} vs {exact}");
    assert_eq!(components(&v.mesh), 1);
    assert_eq!(v.mesh.euler_characteristic(), 1);
}

/// The genus of every shared mesh (MANIFEST.tsv), for the one whose topology the
/// surface cannot predict (it crosses itself).
fn manifest_genus(file: &std::path::Path) -> Option<i64> {
    let manifest = std::fs::read_to_string(file.with_file_name("MANIFEST.tsv")).ok()?;
    let name = file.file_name()?.to_str()?;
    let mut lines = manifest.lines();
    let header: Vec<&str> = lines.next()?.split('\t').collect();
    let column = header.iter().position(|&c| c == "genus")?;
    lines
        .map(|l| l.split('\t').collect::<Vec<_>>())
        .find(|row| row.first() == Some(&name))?
        .get(column)?
        .parse()
        .ok()
}

#[test]
fn every_shared_mesh_meshes_with_its_topology_and_angles_and_passes_the_morse_check_in_both_modes()
{
    let Some(files) = crate::common::shared_meshes() else {
        return;
    };
    for file in files {
        let surface = io::read_mesh(&file).unwrap();
        let prepared = necklace::pipeline::prepare_input(surface).unwrap();
        let (surface, surface_report) = (prepared.mesh, prepared.report);
        for side in [Side::Inside, Side::Outside] {
            let v = volume_mesh(&surface, side, &VolumeOptions::default()).unwrap();
            let r = v.report();
            let what = format!("{} {side:?}", file.display());
            println!("{what}: {r:?}");
            assert_eq!(r.stuffing.unwrap().inverted_tets, 0, "{what}");
            for t in 0..v.mesh.num_tets() {
                assert!(v.mesh.tet_volume(t) > 0.0, "{what}: tet {t}");
            }
            // A compact 3-manifold with boundary has χ(T) = χ(∂T) / 2.
            assert_eq!(2 * r.euler_volume, r.euler_boundary, "{what}");
            assert!(r.interior_vertices > 0, "{what}");
            assert_eq!(r.components, 1, "{what}: a part was lost or split off");
            // Topology first: what the surface predicts (the one surface that crosses
            // itself predicts nothing; its manifest genus must come out).
            match &r.topology.expected {
                Some(expected) => assert_eq!(&r.topology.found, expected, "{what}"),
                None => {
                    let genus = manifest_genus(&file).unwrap();
                    let boundary: Vec<i64> = match side {
                        Side::Inside => vec![2 - 2 * genus],
                        Side::Outside => vec![2, 2 - 2 * genus],
                    };
                    assert_eq!(
                        r.topology.found.components[0].boundary_eulers, boundary,
                        "{what}"
                    );
                }
            }
            // Quality: at least 8° everywhere (the quality step's target is 10°).
            assert!(r.min_dihedral_deg >= 8.0, "{what}: {}", r.min_dihedral_deg);
            assert_eq!(r.tets_below_8_deg, 0, "{what}");
            if side == Side::Outside {
                assert!(r.outer_vertices > 0, "{what}");
            }

            // The Morse identity at every classified step, on barely smoothed fields
            // (steps 1 and 2: the most critical points, the hardest case).
            // The identity is combinatorial: a loose solve gives as valid a field.
            let options = MorseOptions {
                schedule: Schedule::Paper,
                initial_steps: 1,
                steps: 2,
                solver: SolverOptions {
                    tolerance: 1e-6,
                    ..SolverOptions::default()
                },
                ..MorseOptions::default()
            };
            let m = critical_points(&surface, &v, &options).unwrap();
            println!("{what}: {:?}", m.steps);
            assert_eq!(m.steps.len(), 2, "{what}");
            for s in &m.steps {
                assert!(s.morse_ok, "{what}: {s:?}");
            }
            // Where the volume mesh kept the surface's topology, and no tet, face or
            // edge spans surface vertices only through the inside (a thin part without
            // interior vertices), the sum is the one the surface's genus predicts.
            let expected = surface_morse_expected(&surface_report, side).unwrap();
            let surface_euler: i64 = surface_report
                .component_details
                .iter()
                .map(|c| c.euler)
                .sum();
            let kinds = |keep: &dyn Fn(VertexKind) -> bool| -> Vec<bool> {
                v.mesh.kinds.iter().map(|&k| keep(k)).collect()
            };
            let k_surface = v
                .mesh
                .euler_characteristic_where(&kinds(&|k| k == VertexKind::Surface));
            let k_inner = v
                .mesh
                .euler_characteristic_where(&kinds(&|k| k != VertexKind::Outer));
            let clean = r.euler_boundary == surface_euler + 2 * i64::from(side == Side::Outside)
                && k_surface == surface_euler
                && k_inner == r.euler_volume;
            if clean {
                assert_eq!(m.steps[0].morse_sum, expected, "{what}");
            } else {
                println!(
                    "{what}: not clean: chi(boundary) {} chi(surface) {surface_euler} chi(K_S) {k_surface} chi(K_S+I) {k_inner} chi(T) {}",
                    r.euler_boundary, r.euler_volume
                );
            }
        }
    }
}

#[test]
fn the_mesh_does_not_depend_on_the_thread_count() {
    let surface = Shape::new(ShapeKind::Eight)
        .with("res", 48.0)
        .unwrap()
        .mesh()
        .unwrap();
    let mesh_with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| volume_mesh(&surface, Side::Outside, &VolumeOptions::default()).unwrap())
    };
    let (one, three) = (mesh_with(1), mesh_with(3));
    assert_eq!(one.mesh, three.mesh);
}

#[test]
fn a_sphere_mesh_gives_the_papers_angle_bounds_and_its_volume() {
    // Through the mesh-based distance (not the analytic one): uniform lattice along a
    // smooth surface, so the paper's dihedral bounds (10.7°, 164.8°) must hold.
    let surface = sphere(1.0, [0.0; 3], 32.0);
    let v = volume_mesh(&surface, Side::Inside, &VolumeOptions::default()).unwrap();
    let r = v.report();
    let exact = surface.signed_volume();
    assert!(
        (r.volume - exact).abs() / exact < 0.01,
        "{} vs {exact}",
        r.volume
    );
    assert_eq!(r.euler_volume, 1);
    assert!(
        r.min_dihedral_deg >= 10.7 && r.max_dihedral_deg <= 164.8,
        "{r:?}"
    );
    assert!(r.hausdorff_to_surface < 1e-9, "{r:?}");
    assert_eq!(r.thin_vertices, 0);
}

#[test]
fn a_hollow_ball_keeps_its_cavity_in_both_modes() {
    // Outer sphere of radius 1 (outward) and an inner one of radius 0.5 facing inward:
    // the solid is the shell between them; outside it are the cavity and the space
    // beyond, two components of the exterior mesh.
    let outer = sphere(1.0, [0.0; 3], 24.0);
    let mut inner = sphere(0.5, [0.0; 3], 24.0);
    inner.flip_orientation();
    let hollow = union(&[outer.clone(), inner]);
    let solid = hollow.signed_volume();

    let inside = volume_mesh(&hollow, Side::Inside, &VolumeOptions::default()).unwrap();
    assert!((inside.mesh.volume() - solid).abs() / solid < 0.02);
    // A solid ball with a cavity: χ = 2 (like a 2-sphere thickened).
    assert_eq!(inside.mesh.euler_characteristic(), 2);

    let outside = volume_mesh(&hollow, Side::Outside, &VolumeOptions::default()).unwrap();
    let r = outside.report();
    assert_eq!(r.components, 2, "the cavity is kept");
    assert_eq!(r.topology.matches, Some(true), "{r:?}");
    let (_, radius) = outside.sphere.unwrap();
    let ball = 4.0 / 3.0 * PI * radius.powi(3);
    let expected = ball - solid;
    assert!(
        (r.volume - expected).abs() / expected < 0.02,
        "{} vs {expected}",
        r.volume
    );
}

/// Edges between two surface vertices that no boundary face holds: across the inside.
fn chords(m: &TetMesh) -> usize {
    let surface = |v: u32| m.kinds[v as usize] == VertexKind::Surface;
    let mut held = std::collections::HashSet::new();
    for f in m.boundary_faces() {
        for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[0], f[2])] {
            held.insert((a.min(b), a.max(b)));
        }
    }
    let mut across = std::collections::HashSet::new();
    for t in &m.tets {
        for i in 0..4 {
            for j in i + 1..4 {
                let e = (t[i].min(t[j]), t[i].max(t[j]));
                if surface(e.0) && surface(e.1) && !held.contains(&e) {
                    across.insert(e);
                }
            }
        }
    }
    across.len()
}

#[test]
fn a_tube_about_a_cell_thick_keeps_its_topology_among_the_interior_vertices() {
    // A tube of radius 0.04 at the default spacing (about 0.045): stuffing leaves
    // edges straight across it, which the mesher splits. Without that, those edges
    // cut the chain of interior vertices along the tube, and the complex they span
    // had no cycle at all (H1 rank 0, measured with the split turned off).
    let shape = Shape::new(ShapeKind::Torus).with("r", 0.04).unwrap();
    let surface = shape.mesh().unwrap();
    let volume = volume_mesh(&surface, Side::Inside, &VolumeOptions::default()).unwrap();
    let split = volume.report().stuffing.map_or(0, |s| s.chords_split);
    assert!(split > 0, "no chord to split: the test lost its point");
    assert_eq!(chords(&volume.mesh), 0);
    let r = critical_points(&surface, &volume, &MorseOptions::default()).unwrap();
    assert_eq!(r.cycle_rank, 1);
    assert!(r
        .steps
        .iter()
        .all(|s| s.cycles_ok && s.essential_cycles == 1));
}

#[test]
fn a_tray_drawn_with_long_triangles_meshes_with_its_genus_on_both_sides_at_the_first_meshing() {
    // tm_1002_tray_bottom.STL: a genus-23 tray drawn with long triangles on a CAD grid.
    // Rays straight across its walls from grid vertices run along the faces of the
    // distance hierarchy's boxes; when the hierarchy lost such boxes, the walls read as
    // not thin at 207 of its 2215 thin vertices, and the first meshing of the inside fell
    // apart into three pieces of genus 12, 10 and 5 (the thickness sampled over the
    // triangles then mended it). Sized by what it measures first, both sides have the surface's
    // topology at once. Its holes (3.8 across, through the plate 3.2 thick) are drawn
    // with their rims' vertices alone, whose normals lean out of them: only the middles
    // of the holes' walls measure them, and without those the shell, which takes the
    // plate at one cell across, has another topology and 21 of the 23 tunnel classes.
    let dir = crate::common::realworld_dir();
    if !dir.is_dir() {
        println!("SKIPPED: no real-world folder at {}", dir.display());
        return;
    }
    let surface = io::read_mesh(dir.join("tm_1002_tray_bottom.STL")).unwrap();
    assert_eq!(necklace::MeshReport::new(&surface).genus, vec![Some(23)]);
    for side in [Side::Inside, Side::Outside] {
        let v = volume_mesh(&surface, side, &VolumeOptions::default()).unwrap();
        assert_eq!(
            v.topology.matches,
            Some(true),
            "{side:?}: {}",
            v.topology.found
        );
        assert!(v.thin_vertices >= 2215, "{side:?}: {}", v.thin_vertices);
        assert_eq!(v.topology.rounds, 1, "{side:?}");
    }
}

#[test]
fn the_sampled_mesher_carves_clean_surfaces_along_them_and_reports_where_it_cannot() {
    // The experimental Delaunay mesher (`Mesher::Sampled`): once every boundary
    // triangle is a face of the tetrahedralization, the kept tets are bounded by the
    // bisected surface itself, so the inside's volume is the surface's to rounding,
    // its boundary vertices lie on the surface, and the topology is the surface's.
    let options = VolumeOptions {
        mesher: Mesher::Sampled,
        ..VolumeOptions::default()
    };
    let clean = [
        crate::common::meshes_dir().join("torus.obj"),
        crate::common::realworld_dir().join("ps_cube_with_hole.obj"),
    ];
    for path in clean.iter().filter(|p| p.exists()) {
        let surface = io::read_mesh(path).unwrap();
        for side in [Side::Inside, Side::Outside] {
            let v = volume_mesh(&surface, side, &options).unwrap();
            let r = v.report();
            let s = r.sampled.expect("the sampled mesher's statistics");
            assert_eq!(s.missing_triangles, 0, "{path:?} {side:?}: {s:?}");
            assert_eq!(r.topology.matches, Some(true), "{path:?} {side:?}: {r:?}");
            assert!(r.hausdorff_to_surface < 1e-9, "{path:?} {side:?}: {r:?}");
            assert!((0..v.mesh.num_tets()).all(|t| v.mesh.tet_volume(t) > 0.0));
            if side == Side::Inside {
                let exact = surface.signed_volume();
                assert!(
                    (r.volume - exact).abs() / exact < 1e-9,
                    "{} vs {exact}",
                    r.volume
                );
            }
        }
    }
    // A marching-tetrahedra torus (long thin triangles): the bisection does not make
    // all its triangles faces; the shortfall is said, not hidden.
    let skinny = Shape::new(ShapeKind::Torus).mesh().unwrap();
    let v = volume_mesh(&skinny, Side::Inside, &options).unwrap();
    let s = v.sampled.expect("statistics");
    if s.missing_triangles > 0 {
        assert!(
            v.warnings
                .iter()
                .any(|w| w.contains("are not faces of its tetrahedralization")),
            "{:?}",
            v.warnings
        );
    }
    let mesh_with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| volume_mesh(&skinny, Side::Outside, &options).unwrap())
    };
    assert_eq!(mesh_with(1).mesh, mesh_with(2).mesh);
}

#[test]
fn the_refinement_mesher_bounds_a_torus_by_the_surface_with_its_topology_and_volume() {
    // The experimental restricted Delaunay refinement (`Mesher::Refined`) on the
    // analytic torus R = 1, r = 0.3 drawn by marching tetrahedra (long thin
    // triangles, where the sampled mesher cannot recover its boundary): both sides get
    // the surface's topology, no tet is flat or inverted, the boundary vertices lie on
    // the surface, and the inside holds the surface's volume to its chordal error.
    let options = VolumeOptions {
        mesher: Mesher::Refined,
        h: Some(0.15),
        ..VolumeOptions::default()
    };
    let torus = Shape::new(ShapeKind::Torus)
        .with("res", 20.0)
        .unwrap()
        .mesh()
        .unwrap();
    for side in [Side::Inside, Side::Outside] {
        let v = volume_mesh(&torus, side, &options).unwrap();
        let r = v.report();
        let s = r.refined.expect("the refinement mesher's statistics");
        assert_eq!(r.topology.matches, Some(true), "{side:?}: {r:?}");
        assert!(!s.over_budget && s.non_manifold == 0, "{side:?}: {s:?}");
        assert!(r.hausdorff_to_surface < 1e-9, "{side:?}: {r:?}");
        assert!((0..v.mesh.num_tets()).all(|t| v.mesh.tet_volume(t) > 0.0));
        assert!(r.interior_vertices > 0 && s.circumcentres > 0, "{s:?}");
        if side == Side::Inside {
            let exact = torus.signed_volume();
            assert!(
                (r.volume - exact).abs() / exact < 0.005,
                "{} vs {exact}",
                r.volume
            );
        }
    }
    let mesh_with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| volume_mesh(&torus, Side::Inside, &options).unwrap())
    };
    assert_eq!(mesh_with(1).mesh, mesh_with(2).mesh);
}

#[test]
fn a_side_meshed_within_a_step_of_its_budget_keeps_the_surfaces_topology_and_loop_ranks() {
    // th_65004.stl: a genus-2 Thingi10K part whose slivers ask for cells the budget
    // floors. With budget steps, meshed within a sixteenth of each side's budget first, both sides keep
    // that mesh only because its topology and the loops' Z2 rank match the surface's
    // (genus 2), and a note says which budget was kept; the whole budget is not used.
    let path = crate::common::realworld_dir().join("th_65004.stl");
    if !path.exists() {
        println!("SKIPPED: no {}", path.display());
        return;
    }
    let surface = io::read_mesh(&path).unwrap();
    let options = necklace::pipeline::NeckOptions {
        budget_steps: true,
        ..necklace::pipeline::NeckOptions::default()
    };
    let report = necklace::pipeline::find_necks(&surface, &options).unwrap();
    let per_side = options.volume.max_memory / 2;
    for side in &report.sides {
        assert_eq!(side.homology.genus, Some(2), "{:?}", side.side);
        assert!(side.homology.ok, "{:?}: {:?}", side.side, side.homology);
        assert_eq!(side.volume.topology.matches, Some(true), "{:?}", side.side);
        assert!(
            side.volume.budget_bound,
            "{:?}: the budget did not bind",
            side.side
        );
        assert!(
            side.volume.budget < per_side,
            "{:?}: meshed within {} of {per_side}",
            side.side,
            side.volume.budget
        );
        let name = side.side.name();
        assert!(
            report
                .notes
                .iter()
                .any(|n| n.starts_with(name) && n.contains("were not made")),
            "{name}: no note on the budget kept: {:?}",
            report.notes
        );
    }
}

#[test]
fn where_the_surface_crosses_itself_a_rank_off_its_components_genus_is_said_to_be_so() {
    // Two rings of genus 1 in one plane, each through the other's centre: their tubes
    // cross twice, and the solid they bound has three holes (each ring's own and the
    // lens between them), not the two their components add up to. The warning must
    // not call 2 the surface's genus.
    let ring = Shape::new(ShapeKind::Torus)
        .with("res", 24.0)
        .unwrap()
        .mesh()
        .unwrap();
    let mut moved = ring.clone();
    for p in &mut moved.positions {
        p[0] += 1.0;
    }
    let rings = union(&[ring, moved]);
    let r = necklace::pipeline::find_necks(&rings, &necklace::pipeline::NeckOptions::default())
        .unwrap();
    assert!(
        r.sides.iter().any(|s| s.homology.rank != 2),
        "{:?}",
        r.sides.iter().map(|s| s.homology).collect::<Vec<_>>()
    );
    for side in &r.sides {
        if side.homology.rank != 2 {
            assert!(
                r.warnings.iter().any(|w| w.starts_with(side.side.name())
                    && w.contains("crosses itself")
                    && w.contains("genus 2")),
                "{:?}",
                r.warnings
            );
        }
    }
    assert!(
        !r.warnings
            .iter()
            .any(|w| w.contains("the surface has genus")),
        "{:?}",
        r.warnings
    );
}

#[test]
fn a_side_whose_topology_is_not_predicted_gets_no_cells_below_its_bound_and_says_so() {
    // Two unit spheres 1 apart cross along a circle, which asks for cells of h/8; no
    // topology check confirms what the inside needs, so the cells stop at h/4.
    let both = union(&[
        sphere(1.0, [-0.5, 0.0, 0.0], 24.0),
        sphere(1.0, [0.5, 0.0, 0.0], 24.0),
    ]);
    let exact = 2.0 * 4.0 / 3.0 * PI - PI * 5.0 / 12.0;
    let mesh = |unchecked_min_cell: f64| {
        let options = VolumeOptions {
            unchecked_min_cell,
            ..VolumeOptions::default()
        };
        volume_mesh(&both, Side::Inside, &options).unwrap()
    };
    let (bound, free) = (mesh(0.25), mesh(0.0));
    assert_eq!(bound.topology.expected, None);
    let said: Vec<&String> = bound
        .warnings
        .iter()
        .filter(|w| w.contains("unchecked_min_cell"))
        .collect();
    assert_eq!(said.len(), 1, "{:?}", bound.warnings);
    assert!(
        !free
            .warnings
            .iter()
            .any(|w| w.contains("unchecked_min_cell")),
        "{:?}",
        free.warnings
    );
    let h = bound.h;
    let finest = [&bound, &free].map(|v| v.stats.as_ref().unwrap().finest_cell);
    assert!(
        finest[0] >= 0.25 * h * (1.0 - 1e-9) && finest[1] < 0.25 * h,
        "{finest:?} (h {h})"
    );
    assert!(bound.mesh.num_tets() < free.mesh.num_tets());
    // The same solid either way: its volume, one component, no hole.
    for v in [&bound, &free] {
        let volume = v.mesh.volume();
        assert!((volume - exact).abs() / exact < 0.02, "{volume} vs {exact}");
        assert_eq!(components(&v.mesh), 1);
        assert_eq!(v.mesh.euler_characteristic(), 1);
    }
}
