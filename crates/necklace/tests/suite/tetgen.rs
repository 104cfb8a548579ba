#![cfg(feature = "tetgen")]
//! TetGen meshing (`--features tetgen`) of generated shapes, against closed-form answers.

use std::f64::consts::PI;

use crate::common::union;

use necklace::shapes::{Shape, ShapeKind};
use necklace::volume::tetgen::{mesh_inside, mesh_shell};
use necklace::{SurfaceMesh, TetMesh, VertexKind};

fn shape(kind: ShapeKind, res: f64) -> SurfaceMesh {
    Shape::new(kind).with("res", res).unwrap().mesh().unwrap()
}

fn assert_positive(m: &TetMesh) {
    assert!(m.num_tets() > 0);
    for t in 0..m.num_tets() {
        assert!(m.tet_volume(t) > 0.0, "tet {t} not positive");
    }
}

#[test]
fn inside_a_unit_sphere_is_a_ball() {
    let surface = shape(ShapeKind::Sphere, 16.0);
    let m = mesh_inside(&surface).unwrap();
    assert_positive(&m);
    let ball = 4.0 / 3.0 * PI;
    assert!(
        (m.volume() - ball).abs() < 0.02 * ball,
        "volume {} vs {ball}",
        m.volume()
    );
    // TetGen fills the PLC (up to its merging of nearly coplanar input facets).
    let exact = surface.signed_volume();
    assert!(
        (m.volume() - exact).abs() < 1e-5 * exact,
        "{} vs {exact}",
        m.volume()
    );
    assert_eq!(m.euler_characteristic(), 1);
    let (interior, on_surface, outer) = m.kind_counts();
    assert!(interior > 0 && on_surface >= surface.num_vertices() && outer == 0);
}

#[test]
fn inside_a_torus_is_a_solid_torus() {
    let m = mesh_inside(&shape(ShapeKind::Torus, 16.0)).unwrap();
    assert_positive(&m);
    assert_eq!(m.euler_characteristic(), 0);
    assert_eq!(m.kind_counts().2, 0);
}

#[test]
fn the_shell_around_a_torus_is_a_ball_minus_a_solid_torus() {
    let surface = shape(ShapeKind::Torus, 16.0);
    let radius = 2.5;
    let m = mesh_shell(&surface, [0.0; 3], radius).unwrap();
    assert_positive(&m);
    assert_eq!(m.euler_characteristic(), 1);
    let (_, on_surface, outer) = m.kind_counts();
    assert!(on_surface >= surface.num_vertices() && outer >= 642);
    for (p, k) in m.positions.iter().zip(&m.kinds) {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        match k {
            // On the inscribed icosphere: between its inradius and the sphere.
            VertexKind::Outer => assert!(r > 0.98 * radius && r <= radius * (1.0 + 1e-12)),
            VertexKind::Surface => assert!(r < 1.5),
            VertexKind::Interior => assert!(r < radius),
        }
    }
    // Ball (inscribed polyhedron) minus the torus volume.
    let expected = 4.0 / 3.0 * PI * radius.powi(3) - surface.signed_volume();
    assert!((m.volume() - expected).abs() < 0.02 * expected);
}

#[test]
fn two_separate_spheres_give_two_balls_all_surface() {
    let a = shape(ShapeKind::Sphere, 8.0);
    let mut both = a.clone();
    let n = a.positions.len() as u32;
    both.positions
        .extend(a.positions.iter().map(|p| [p[0] + 3.0, p[1], p[2]]));
    both.triangles
        .extend(a.triangles.iter().map(|t| t.map(|v| v + n)));
    let m = mesh_inside(&both).unwrap();
    assert_positive(&m);
    assert_eq!(m.euler_characteristic(), 2);
    assert_eq!(m.kind_counts().2, 0);
    let shell = mesh_shell(&both, [1.5, 0.0, 0.0], 4.0).unwrap();
    assert_positive(&shell);
    // A ball minus two open balls: χ(B) = χ(X) + 2 χ(ball) − 2 χ(S²), so χ(X) = 1 − 2 + 4.
    assert_eq!(shell.euler_characteristic(), 3);
}

#[test]
fn a_hollow_ball_keeps_its_cavity_empty() {
    let outer = shape(ShapeKind::Sphere, 8.0);
    let mut inner = outer.clone();
    for p in &mut inner.positions {
        *p = p.map(|c| 0.5 * c);
    }
    inner.flip_orientation();
    let hollow = union(&[outer.clone(), inner]);
    let m = mesh_inside(&hollow).unwrap();
    assert_positive(&m);
    let exact = hollow.signed_volume();
    assert!(
        (m.volume() - exact).abs() < 1e-5 * exact,
        "{} vs {exact}",
        m.volume()
    );
    // A thick sphere shell S² × I: χ = 2.
    assert_eq!(m.euler_characteristic(), 2);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let mut open = shape(ShapeKind::Sphere, 8.0);
    open.triangles.pop();
    let e = mesh_inside(&open).unwrap_err();
    assert!(e.to_string().contains("not closed"), "{e}");

    let mut inward = shape(ShapeKind::Sphere, 8.0);
    inward.flip_orientation();
    assert!(mesh_inside(&inward).is_err());

    let sphere = shape(ShapeKind::Sphere, 8.0);
    let e = mesh_shell(&sphere, [0.0; 3], 1.0).unwrap_err();
    assert!(e.to_string().contains("strictly inside"), "{e}");
    assert!(mesh_shell(&sphere, [0.0; 3], f64::NAN).is_err());

    // Two overlapping spheres: self-intersecting input.
    let a = shape(ShapeKind::Sphere, 8.0);
    let mut both = a.clone();
    let n = a.positions.len() as u32;
    both.positions.extend(
        a.positions
            .iter()
            .map(|p| [p[0] + 0.5, p[1] + 0.1, p[2] + 0.05]),
    );
    both.triangles
        .extend(a.triangles.iter().map(|t| t.map(|v| v + n)));
    let e = mesh_inside(&both).unwrap_err();
    assert!(!e.to_string().contains('\n'));
}
