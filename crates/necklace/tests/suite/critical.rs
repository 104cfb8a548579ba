//! Link classification against the Morse identity: Σ (1 − χ(lower link)) over interior
//! vertices = g − 1 inside and g outside a connected genus-g surface.

use crate::common::{shell, Inside};

use necklace::morse::{
    classify, cotangent_stiffness, implicit_step, lumped_mass, Classification, LinkSides, Links,
    SolverOptions, VertexType,
};
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
        let m = stuff_volume(&shell(shape.clone(), 2.5), &StuffingOptions::new(0.08))
            .unwrap()
            .mesh;
        let c = classify(&m, &distance_field(&shape, &m)).unwrap();
        assert_eq!(c.morse_sum, genus, "{kind}");
    }
}

#[test]
fn classifying_a_sequence_of_fields_again_gives_what_classifying_each_gives() {
    let shape = Shape::new(ShapeKind::Eight);
    let m = stuff_volume(&Inside(shape.clone()), &StuffingOptions::new(0.07))
        .unwrap()
        .mesh;
    let links = Links::new(&m).unwrap();
    let stiffness = cotangent_stiffness(&m);
    let mass = lumped_mass(&m);
    let fixed: Vec<bool> = m.kinds.iter().map(|&k| k != VertexKind::Interior).collect();
    let mut sides = LinkSides::default();
    let mut f = distance_field(&shape, &m);
    let mut previous: Option<Classification> = None;
    let mut changed = 0;
    for level in 0..6 {
        // Heat steps: most links keep their order from one field to the next, and the
        // noise of the raw distance field's critical points goes away.
        if level > 0 {
            f = implicit_step(
                &stiffness,
                &mass,
                &fixed,
                &f,
                2e-4,
                &SolverOptions::default(),
            )
            .0;
        }
        let again = links.classify_again(&f, &mut sides);
        assert_eq!(again, links.classify(&f), "level {level}");
        if previous.is_some_and(|p| p.classes != again.classes) {
            changed += 1;
        }
        previous = Some(again);
    }
    assert!(changed > 0, "the fields must change some classes");
}
