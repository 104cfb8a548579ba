//! Generated shapes are closed, manifold, outward-oriented surfaces of the right genus at
//! every resolution, and their volumes match the analytic ones.

use std::f64::consts::PI;

use necklace::shapes::{Shape, ShapeKind};
use necklace::MeshReport;
use necklace::Side;

fn mesh_at(kind: ShapeKind, res_factor: f64) -> (Shape, MeshReport) {
    let base = Shape::new(kind);
    let res = (base.param("res") * res_factor).round();
    let shape = base.with("res", res).unwrap();
    let mesh = shape.mesh().unwrap();
    (shape, MeshReport::new(&mesh))
}

#[test]
fn every_shape_is_a_valid_solid_of_its_genus_at_three_resolutions() {
    for kind in ShapeKind::ALL {
        for factor in [0.5, 0.75, 1.0] {
            let (shape, r) = mesh_at(kind, factor);
            let what = format!("{kind} at res {}", shape.param("res"));
            assert!(r.watertight, "{what}: not watertight");
            assert!(r.manifold, "{what}: not manifold");
            assert!(r.oriented, "{what}: not oriented");
            assert_eq!(r.outward, Some(true), "{what}: not outward");
            assert_eq!(r.components, 1, "{what}: components");
            assert_eq!(r.genus, vec![Some(shape.genus() as i64)], "{what}: genus");
            assert_eq!(r.zero_area_faces, 0, "{what}: zero-area faces");
            assert_eq!(r.duplicate_vertices, 0, "{what}: duplicate vertices");
            assert!(r.is_valid_solid(), "{what}: {:?}", r.problems());
        }
    }
}

#[test]
fn volumes_match_closed_forms() {
    // Sphere: 4/3 π r³; torus: 2π² R r² (Pappus). Marching tetrahedra with projected
    // vertices is a chordal approximation, so allow 1 %.
    let (_, sphere) = mesh_at(ShapeKind::Sphere, 1.0);
    let exact = 4.0 / 3.0 * PI;
    assert!(
        (sphere.signed_volume - exact).abs() / exact < 0.01,
        "{}",
        sphere.signed_volume
    );
    let (_, torus) = mesh_at(ShapeKind::Torus, 1.0);
    let exact = 2.0 * PI * PI * 1.0 * 0.3 * 0.3;
    assert!(
        (torus.signed_volume - exact).abs() / exact < 0.01,
        "{}",
        torus.signed_volume
    );
    // Varying torus (Pappus per angle): V = ∫ π r(θ)² (R + ...)... use the exact
    // formula for tube radius r(θ) around a circle: V = ∫₀^{2π} π r(θ)² R dθ
    // = π R r0² (2π + π a²), valid because the cross-section centroid stays on the core.
    let (_, vt) = mesh_at(ShapeKind::VaryingTorus, 1.0);
    let (r0, a) = (0.3f64, 0.4f64);
    let exact = PI * r0 * r0 * (2.0 * PI + PI * a * a);
    assert!(
        (vt.signed_volume - exact).abs() / exact < 0.01,
        "{} vs {exact}",
        vt.signed_volume
    );
}

#[test]
fn expected_necks_follow_the_documented_formulas() {
    let dumbbell = Shape::new(ShapeKind::Dumbbell);
    let necks = dumbbell.expected_necks();
    assert_eq!(necks.len(), 1);
    assert!((necks[0].length.unwrap() - 2.0 * PI * 0.15).abs() < 1e-12);
    assert_eq!(necks[0].center, Some([0.0, 0.0, 0.0]));

    let chain = Shape::from_name("chain", &[("count".into(), 4.0)]).unwrap();
    assert_eq!(chain.expected_necks().len(), 3);

    let vt = Shape::new(ShapeKind::VaryingTorus);
    let handles: Vec<_> = vt
        .expected_necks()
        .into_iter()
        .filter(|n| n.kind == Side::Inside)
        .collect();
    assert_eq!(handles.len(), 1);
    assert!((handles[0].length.unwrap() - 2.0 * PI * 0.18).abs() < 1e-12);

    let eight = Shape::new(ShapeKind::Eight);
    let count = |k| {
        eight
            .expected_necks()
            .iter()
            .filter(|n| n.kind == k)
            .count()
    };
    assert_eq!((count(Side::Inside), count(Side::Outside)), (2, 2));
    let pretzel = Shape::from_name("pretzel", &[("g".into(), 4.0)]).unwrap();
    let count = |k| {
        pretzel
            .expected_necks()
            .iter()
            .filter(|n| n.kind == k)
            .count()
    };
    assert_eq!((count(Side::Inside), count(Side::Outside)), (4, 4));

    let satellites = Shape::new(ShapeKind::Satellites);
    let lengths: Vec<f64> = satellites
        .expected_necks()
        .iter()
        .map(|n| n.length.unwrap())
        .collect();
    let radii = [0.12, 0.15, 0.18, 0.21];
    assert_eq!(lengths.len(), 4);
    for (l, r) in lengths.iter().zip(radii) {
        assert!((l - 2.0 * PI * r).abs() < 1e-12);
    }
    let buckyball = Shape::new(ShapeKind::Buckyball);
    let count = |k| {
        buckyball
            .expected_necks()
            .iter()
            .filter(|n| n.kind == k)
            .count()
    };
    assert_eq!((count(Side::Inside), count(Side::Outside)), (90, 32));
    assert_eq!(buckyball.genus(), 31);
    for kind in [ShapeKind::Ellipsoid, ShapeKind::Capsule, ShapeKind::Limb] {
        assert!(Shape::new(kind).expected_necks().is_empty());
    }
}

#[test]
fn the_neck_of_a_generated_dumbbell_has_the_requested_radius() {
    // Vertices near the plane x = 0 lie on the neck cylinder: their distance to the x
    // axis is the neck radius (up to the projection's accuracy).
    let shape = Shape::new(ShapeKind::Dumbbell);
    let mesh = shape.mesh().unwrap();
    let near: Vec<f64> = mesh
        .positions
        .iter()
        .filter(|p| p[0].abs() < 0.05)
        .map(|p| (p[1] * p[1] + p[2] * p[2]).sqrt())
        .collect();
    assert!(near.len() > 20);
    for r in near {
        assert!((r - 0.15).abs() < 1e-6, "radius {r}");
    }
}

#[test]
fn bad_parameters_are_rejected_with_a_message() {
    type Case<'a> = (&'a str, &'a [(&'a str, f64)], &'a str);
    let cases: &[Case] = &[
        ("cube", &[], "unknown shape"),
        ("sphere", &[("radius", 1.0)], "no parameter"),
        ("sphere", &[("r", -1.0)], "outside"),
        ("sphere", &[("res", 10.5)], "whole number"),
        ("torus", &[("r", 2.0)], "must be < R"),
        ("dumbbell", &[("neck", 0.6)], "must be < radius"),
        ("dumbbell", &[("offset", 0.2)], "overlap"),
        ("chain", &[("spacing", 0.5)], "overlap"),
        ("eight", &[("c", 0.5)], "between"),
        ("varying-torus", &[("a", 0.9), ("r0", 0.6)], "thickest"),
        ("limb", &[("tip", 0.6)], "shrink"),
        ("limb", &[("length", 1.0)], "inside the body"),
        ("satellites", &[("distance", 1.2)], "touch the body"),
        ("satellites", &[("step", 0.2)], "narrower than the balls"),
        (
            "satellites",
            &[("count", 12.0), ("satellite", 0.5), ("step", 0.0)],
            "overlap",
        ),
        ("buckyball", &[("stick", 0.3)], "stick"),
        ("sphere", &[("r", f64::NAN)], "outside"),
    ];
    for (name, params, needle) in cases {
        let params: Vec<(String, f64)> = params.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        let err = Shape::from_name(name, &params).unwrap_err();
        assert_eq!(err.kind(), necklace::ErrorKind::InvalidArgument);
        assert!(err.to_string().contains(needle), "{name}: {err}");
    }
}

#[test]
fn a_ball_with_rings_has_a_handle_round_each_wire_and_a_tunnel_through_each_arch() {
    let shape = Shape::new(ShapeKind::Rings);
    let (count, wire) = (shape.param("count") as usize, shape.param("wire"));
    // Three resolutions, none crossing itself where the rings meet the ball.
    for res in [32.0, 48.0, 64.0] {
        let mesh = shape.clone().with("res", res).unwrap().mesh().unwrap();
        let crossings =
            necklace::distance::SurfaceDistance::new(&mesh).self_intersections(&mesh.triangles);
        assert!(
            crossings.is_empty(),
            "res {res}: {} crossings",
            crossings.len()
        );
    }
    let mesh = shape.mesh().unwrap();
    let report = necklace::find_necks(&mesh, &necklace::Options::default()).unwrap();
    let lengths = |side: Side| -> Vec<f64> {
        report
            .loops
            .iter()
            .filter(|l| l.kind == side)
            .map(|l| l.length)
            .collect()
    };
    let handles = lengths(Side::Inside);
    assert_eq!(handles.len(), count, "{handles:?}");
    // The marching mesh's wire is a polygon inside the round one: a few % shorter.
    for l in &handles {
        assert!((l / (2.0 * PI * wire) - 0.98).abs() < 0.03, "{l}");
    }
    assert_eq!(lengths(Side::Outside).len(), count);
    // Each tunnel loop passes through an arch: its centre is near the one expected.
    let arches: Vec<[f64; 3]> = shape
        .expected_necks()
        .iter()
        .filter(|n| n.kind == Side::Outside)
        .filter_map(|n| n.center)
        .collect();
    for l in report.loops.iter().filter(|l| l.kind == Side::Outside) {
        let nearest = arches
            .iter()
            .map(|c| {
                (0..3)
                    .map(|k| (c[k] - l.center[k]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest < shape.param("ring"),
            "{:?} is {nearest} from an arch",
            l.center
        );
    }
}
