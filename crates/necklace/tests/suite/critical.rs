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

/// `1 − χ(lower link)` of interior vertex `v`, counted from the tets round it: the
/// lower link's vertices, edges and triangles (below: surface, then `(f, index)`,
/// then the outer sphere).
fn euler_term_by_count(m: &TetMesh, f: &[f64], v: usize) -> i32 {
    let rank = |u: usize| match m.kinds[u] {
        VertexKind::Surface => 0,
        VertexKind::Interior => 1,
        VertexKind::Outer => 2,
    };
    let below = |u: usize| {
        (rank(u), f[u], u)
            .partial_cmp(&(rank(v), f[v], v))
            .is_some_and(|o| o.is_lt())
    };
    let round: Vec<Vec<usize>> = m
        .tets
        .iter()
        .filter(|t| t.contains(&(v as u32)))
        .map(|t| t.iter().map(|&u| u as usize).filter(|&u| u != v).collect())
        .collect();
    let mut vertices: Vec<usize> = round
        .iter()
        .flatten()
        .copied()
        .filter(|&u| below(u))
        .collect();
    vertices.sort_unstable();
    vertices.dedup();
    let mut edges: Vec<(usize, usize)> = round
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])])
        .filter(|&(a, b)| below(a) && below(b))
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let triangles = round.iter().filter(|t| t.iter().all(|&u| below(u))).count();
    1 - (vertices.len() as i32 - edges.len() as i32 + triangles as i32)
}

/// A field with many ties broken by index and many critical points.
fn noisy(m: &TetMesh, seed: u64) -> Vec<f64> {
    let mut state = seed;
    (0..m.num_vertices())
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            f64::from((state >> 60) as u32)
        })
        .collect()
}

#[test]
fn the_euler_terms_read_from_components_are_those_counted_on_the_lower_links() {
    // Sphere links (every interior vertex of a 3-manifold mesh), with smooth and
    // noisy fields.
    let shape = Shape::new(ShapeKind::Eight);
    let m = stuff_volume(&Inside(shape.clone()), &StuffingOptions::new(0.1))
        .unwrap()
        .mesh;
    let links = Links::new(&m).unwrap();
    for f in [distance_field(&shape, &m), noisy(&m, 1), noisy(&m, 2)] {
        let c = links.classify(&f);
        for v in (0..m.num_vertices()).filter(|&v| m.kinds[v] == VertexKind::Interior) {
            assert_eq!(
                c.classes[v].euler_term,
                euler_term_by_count(&m, &f, v),
                "vertex {v}"
            );
        }
    }
    // A vertex whose link is two octahedra (a pinch of two balls), and corners whose
    // links are disks: none a sphere, so counted, where the components alone would
    // give another term (both octahedra above the pinch: χ(lower) = 0, not −1).
    let mut positions = vec![[0.0; 3]];
    let mut tets = Vec::new();
    for ball in 0..2u32 {
        let shift = 3.0 * f64::from(ball);
        for d in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            positions.push([d[0] + shift, d[1], d[2]]);
            positions.push([shift - d[0], -d[1], -d[2]]);
        }
        let corner = |i: u32| 1 + 6 * ball + i;
        for x in [corner(0), corner(1)] {
            for y in [corner(2), corner(3)] {
                for z in [corner(4), corner(5)] {
                    tets.push([0, x, y, z]);
                }
            }
        }
    }
    let kinds = vec![VertexKind::Interior; positions.len()];
    let pinched = TetMesh::new(positions, tets, kinds).unwrap();
    let links = Links::new(&pinched).unwrap();
    let mut differs = false;
    for seed in 0..64 {
        let f = noisy(&pinched, seed);
        let c = links.classify(&f);
        for (v, class) in c.classes.iter().enumerate() {
            let counted = euler_term_by_count(&pinched, &f, v);
            assert_eq!(class.euler_term, counted, "seed {seed}, vertex {v}");
            differs |= counted != class.upper as i32 - class.lower as i32;
        }
    }
    assert!(
        differs,
        "some field must give a term the components alone do not"
    );
}
