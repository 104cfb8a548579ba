//! Link classification against the Morse identity: Σ (1 − χ(lower link)) over interior
//! vertices = g − 1 inside and g outside a connected genus-g surface.

mod common;

use common::{Inside, Shell};

use necklace::morse::{classify, VertexType};
use necklace::shapes::{Shape, ShapeKind};
use necklace::volume::{stuff_volume, StuffingOptions};
use necklace::{TetMesh, VertexKind};

/// Distance to the shape's surface at every vertex (0 on the surface).
fn distance_field(shape: &Shape, m: &TetMesh) -> Vec<f64> {
    m.positions
        .iter()
        .zip(&m.kinds)
        .map(|(&p, &k)| {
            if k == VertexKind::Surface {
                0.0
            } else {
                shape.sdf(p).abs()
            }
        })
        .collect()
}

#[test]
fn the_morse_sum_inside_is_genus_minus_one() {
    for (kind, h) in [
        (ShapeKind::Sphere, 0.12),
        (ShapeKind::Torus, 0.06),
        (ShapeKind::Eight, 0.07),
    ] {
        let shape = Shape::new(kind);
        let genus = shape.genus() as i64;
        let m = stuff_volume(&Inside(shape.clone()), &StuffingOptions::new(h))
            .unwrap()
            .mesh;
        let c = classify(&m, &distance_field(&shape, &m)).unwrap();
        assert_eq!(c.morse_sum, genus - 1, "{kind}");
        assert!(
            c.count(VertexType::Maximum) >= 1,
            "{kind}: a distance field has a maximum"
        );
        assert_eq!(
            c.count(VertexType::Minimum),
            0,
            "{kind}: no minimum above the surface"
        );
        // Each term is ±1 for a non-degenerate critical point and 0 for a regular one.
        for class in &c.classes {
            match class.kind {
                VertexType::Regular | VertexType::Boundary => assert_eq!(class.euler_term, 0),
                VertexType::Maximum | VertexType::Saddle1 => assert_eq!(class.euler_term, -1),
                VertexType::Minimum | VertexType::Saddle2 => assert_eq!(class.euler_term, 1),
                VertexType::Degenerate => {}
            }
        }
    }
}

#[test]
fn the_morse_sum_outside_is_the_genus() {
    for kind in [ShapeKind::Sphere, ShapeKind::Torus] {
        let shape = Shape::new(kind);
        let genus = shape.genus() as i64;
        let m = stuff_volume(&Shell(shape.clone(), 2.5), &StuffingOptions::new(0.08))
            .unwrap()
            .mesh;
        let c = classify(&m, &distance_field(&shape, &m)).unwrap();
        assert_eq!(c.morse_sum, genus, "{kind}");
    }
}
