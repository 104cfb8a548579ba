//! Dense surfaces worked on a simplified copy (`simplify`, `pipeline::working`,
//! `loops::transfer_loops`): the same shape meshed with about 9 times the triangles
//! gives the same necks, with loops that lie on the dense surface.

use std::f64::consts::PI;

use necklace::loops::TightenStatus;
use necklace::mesh::{MeshReport, Topology};
use necklace::pipeline::{find_necks, NeckOptions, NeckReport};
use necklace::shapes::{Shape, ShapeKind};
use necklace::simplify::{simplify, SimplifyOptions, Stop};
use necklace::{Side, SurfaceMesh};

use super::loops::check_loop;

/// The necks of `shape` meshed as it is and meshed with three times the lattice cells
/// along each side (about 9 times the triangles), simplified to the first's size.
fn coarse_and_dense(shape: &Shape) -> (NeckReport, NeckReport, SurfaceMesh) {
    let mesh = shape.mesh().unwrap();
    let fine = shape.clone().with("res", 3.0 * shape.param("res")).unwrap();
    let dense = fine.mesh().unwrap();
    let coarse = find_necks(&mesh, &NeckOptions::default()).unwrap();
    let options = NeckOptions {
        simplify: SimplifyOptions {
            above: mesh.num_triangles(),
            target: mesh.num_triangles(),
            ..SimplifyOptions::default()
        },
        ..NeckOptions::default()
    };
    let report = find_necks(&dense, &options).unwrap();
    (coarse, report, dense)
}

/// The same loops: per kind, the same count and lengths within 0.5 %; each loop a
/// closed geodesic on the dense surface.
fn same_loops(coarse: &NeckReport, dense: &NeckReport, surface: &SurfaceMesh) {
    let simplified = dense.simplified.expect("the dense surface was simplified");
    assert!(simplified.used, "{:?}", dense.warnings);
    assert_eq!(simplified.stop, Stop::Target);
    for kind in [Side::Inside, Side::Outside] {
        let lengths = |r: &NeckReport| {
            let mut l: Vec<f64> = r
                .loops
                .iter()
                .filter(|l| l.kind == kind)
                .map(|l| l.length)
                .collect();
            l.sort_by(f64::total_cmp);
            l
        };
        let (a, b) = (lengths(coarse), lengths(dense));
        assert_eq!(a.len(), b.len(), "{kind:?}: {a:?} against {b:?}");
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 0.005 * x, "{kind:?}: {x} against {y}");
        }
    }
    let topology = Topology::new(surface);
    for l in &dense.loops {
        // A loop whose last round no longer shortened it may sit a little off straight
        // at a vertex; the other checks hold for it all the same.
        let mut checked = l.clone();
        if l.tightening.status == TightenStatus::Stalled {
            assert!(
                l.tightening.min_vertex_angle >= PI - 1e-3,
                "{:?}",
                l.tightening
            );
            checked.tightening.min_vertex_angle = PI;
        }
        check_loop(surface, &topology, &checked);
        assert!(l.reason.contains("found on the simplified surface"));
    }
}

#[test]
fn a_split_dumbbell_has_the_dumbbells_neck() {
    let shape = Shape::new(ShapeKind::Dumbbell);
    let (coarse, dense, surface) = coarse_and_dense(&shape);
    assert_eq!(dense.loops.len(), 1, "{:?}", dense.dropped);
    let expected = 2.0 * PI * shape.param("neck");
    assert!((dense.loops[0].length - expected).abs() < 0.005 * expected);
    same_loops(&coarse, &dense, &surface);
}

#[test]
fn a_split_varying_torus_keeps_its_handle_and_tunnel() {
    let shape = Shape::new(ShapeKind::VaryingTorus);
    let (coarse, dense, surface) = coarse_and_dense(&shape);
    assert_eq!(dense.loops.len(), 2, "{:?}", dense.dropped);
    same_loops(&coarse, &dense, &surface);
    // The loops' classes are the dense surface's: together they span its homology.
    assert!(dense.morse.iter().all(|m| m.ok));
}

#[test]
fn simplifying_keeps_a_closed_surface_of_the_same_genus() {
    let eight = Shape::new(ShapeKind::Eight);
    let mesh = eight
        .clone()
        .with("res", 3.0 * eight.param("res"))
        .unwrap()
        .mesh()
        .unwrap();
    let before = MeshReport::new(&mesh);
    let genus = |r: &MeshReport| {
        r.component_details
            .iter()
            .map(|c| c.genus)
            .collect::<Vec<_>>()
    };
    // Far down (a loose error bound): still a closed manifold of genus 2.
    let deep = simplify(
        &mesh,
        &SimplifyOptions {
            target: 500,
            max_error: 0.05,
            ..SimplifyOptions::default()
        },
    )
    .unwrap();
    // With the default error bound: close to the input. A point of the copy is within
    // the largest collapse error of the planes merged into it, so the volume moves by
    // at most the area times that error; and by less than 1 %.
    let close = simplify(
        &mesh,
        &SimplifyOptions {
            target: 500,
            ..SimplifyOptions::default()
        },
    )
    .unwrap();
    for s in [&deep, &close] {
        assert_eq!(s.triangles, (mesh.num_triangles(), s.mesh.num_triangles()));
        let after = MeshReport::new(&s.mesh);
        assert!(after.watertight && after.manifold && after.oriented);
        assert_eq!(genus(&after), genus(&before));
        assert_eq!(genus(&after), vec![Some(2)]);
    }
    assert!(deep.mesh.num_triangles() < 2000, "{:?}", deep.triangles);
    assert!(10 * close.mesh.num_triangles() < mesh.num_triangles());
    let (v0, v1) = (mesh.signed_volume(), close.mesh.signed_volume());
    assert!(
        (v1 - v0).abs() < mesh.area() * close.max_error,
        "{v0} -> {v1}"
    );
    assert!((v1 - v0).abs() < 0.01 * v0, "{v0} -> {v1}");
}
