//! Isosurface stuffing on analytic domains, against closed-form answers.

use crate::common::{shell, Inside};

use std::f64::consts::PI;

use necklace::shapes::{Shape, ShapeKind};
use necklace::volume::{stuff_volume, StuffingOptions, VolumeMesh};
use necklace::{TetMesh, VertexKind};

fn check_valid(v: &VolumeMesh) -> &TetMesh {
    let m = &v.mesh;
    assert_eq!(v.stats.inverted_tets, 0, "{:?}", v.stats);
    for t in 0..m.num_tets() {
        assert!(m.tet_volume(t) > 0.0, "tet {t} not positive");
    }
    m
}

#[test]
fn sphere_volume_euler_angles_and_boundary() {
    let shape = Shape::new(ShapeKind::Sphere);
    let h = 0.1;
    let v = stuff_volume(&Inside(shape.clone()), &StuffingOptions::new(h)).unwrap();
    let m = check_valid(&v);
    let exact = 4.0 / 3.0 * PI;
    println!(
        "{:?} vertices {} tets {} volume {} dihedral {:?}",
        v.stats,
        m.num_vertices(),
        m.num_tets(),
        m.volume(),
        m.dihedral_range_deg()
    );
    assert!(
        (m.volume() - exact).abs() / exact < 0.01,
        "volume {}",
        m.volume()
    );
    assert_eq!(m.euler_characteristic(), 1);
    let (lo, hi) = m.dihedral_range_deg().unwrap();
    assert!(lo >= 10.7 && hi <= 164.8, "dihedral angles {lo}..{hi}");
    for (p, k) in m.positions.iter().zip(&m.kinds) {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        match k {
            VertexKind::Surface => assert!((r - 1.0).abs() < h / 10.0, "surface vertex at r = {r}"),
            VertexKind::Interior => assert!(r < 1.0),
            VertexKind::Outer => panic!("no outer boundary inside"),
        }
    }
}

#[test]
fn torus_inside_has_euler_0_and_its_shell_euler_1() {
    let shape = Shape::new(ShapeKind::Torus);
    let h = 0.06;
    let inside = stuff_volume(&Inside(shape.clone()), &StuffingOptions::new(h)).unwrap();
    let m = check_valid(&inside);
    println!(
        "inside {:?} dihedral {:?}",
        inside.stats,
        m.dihedral_range_deg()
    );
    assert_eq!(m.euler_characteristic(), 0);
    let shell = stuff_volume(&shell(shape, 2.0), &StuffingOptions::new(h)).unwrap();
    let m = check_valid(&shell);
    println!(
        "shell {:?} dihedral {:?} kinds {:?}",
        shell.stats,
        m.dihedral_range_deg(),
        m.kind_counts()
    );
    assert_eq!(m.euler_characteristic(), 1);
    let (_, surface, outer) = m.kind_counts();
    assert!(surface > 0 && outer > 0);
    let exact = 4.0 / 3.0 * PI * 8.0 - 2.0 * PI * PI * 0.3 * 0.3;
    assert!(
        (m.volume() - exact).abs() / exact < 0.01,
        "shell volume {}",
        m.volume()
    );
}
