//! Segmentation along the found loops, against answers computed without it: the parts
//! of the surface between the planes the analytic necks lie in (clipped triangle by
//! triangle), their areas and the volumes they enclose (divergence theorem with a field
//! that vanishes on the cutting plane), and the topology of a torus cut open.

use necklace::mesh::{Side, SurfaceMesh};
use necklace::pipeline::{find_necks, segment_along_loops, NeckOptions, NeckReport};
use necklace::shapes::{Shape, ShapeKind};

fn necks(mesh: &SurfaceMesh, handles: bool, tunnels: bool) -> NeckReport {
    let options = NeckOptions {
        handles,
        tunnels,
        ..NeckOptions::default()
    };
    find_necks(mesh, &options).unwrap()
}

/// The part of the surface with `x < c` (or `x > c`): its area, and the volume of the
/// solid part it bounds with the plane `x = c`, from `∫ (x − c) n_x dA` over it (the
/// field `(x − c, 0, 0)` has divergence 1 and vanishes on the plane).
fn clipped(mesh: &SurfaceMesh, c: f64, below: bool) -> (f64, f64) {
    let sign = if below { 1.0 } else { -1.0 };
    let mut area = 0.0;
    let mut volume = 0.0;
    for t in &mesh.triangles {
        let corners: Vec<[f64; 3]> = t.iter().map(|&v| mesh.positions[v as usize]).collect();
        // Sutherland–Hodgman against sign·(c − x) ≥ 0.
        let keep = |p: &[f64; 3]| sign * (c - p[0]) >= 0.0;
        let mut polygon = Vec::new();
        for i in 0..3 {
            let (p, q) = (corners[i], corners[(i + 1) % 3]);
            if keep(&p) {
                polygon.push(p);
            }
            if keep(&p) != keep(&q) {
                let s = (c - p[0]) / (q[0] - p[0]);
                polygon.push([c, p[1] + s * (q[1] - p[1]), p[2] + s * (q[2] - p[2])]);
            }
        }
        for i in 1..polygon.len().saturating_sub(1) {
            let (a, b, d) = (polygon[0], polygon[i], polygon[i + 1]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
            let n = [
                u[1] * w[2] - u[2] * w[1],
                u[2] * w[0] - u[0] * w[2],
                u[0] * w[1] - u[1] * w[0],
            ];
            let twice = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let centroid_x = (a[0] + b[0] + d[0]) / 3.0;
            area += 0.5 * twice;
            volume += 0.5 * n[0] * (centroid_x - c);
        }
    }
    (area, volume)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

#[test]
fn a_chain_of_three_balls_falls_into_its_three_balls() {
    let shape = Shape::new(ShapeKind::Chain);
    let mesh = shape.mesh().unwrap();
    let report = necks(&mesh, true, false);
    assert_eq!(report.loops.len(), 2);
    let loops: Vec<_> = report.loops.iter().collect();
    let cut = segment_along_loops(&mesh, &loops).unwrap();
    assert_eq!(cut.segments.len(), 3, "{:?}", cut.segments);
    // The necks lie midway between the balls, at x = ±spacing / 2.
    let half = 0.5 * shape.param("spacing");
    let (left_area, left_volume) = clipped(&mesh, -half, true);
    let (right_area, right_volume) = clipped(&mesh, half, false);
    let total_volume = mesh.signed_volume();
    let expected = [
        (left_area, left_volume),
        (
            mesh.area() - left_area - right_area,
            total_volume - left_volume - right_volume,
        ),
        (right_area, right_volume),
    ];
    // Segments in x order, by the x of their centroid... by which loops bound them: the
    // middle ball is the one bounded by both.
    let mut by_x: Vec<(f64, &necklace::segment::Segment)> = cut
        .segments
        .iter()
        .map(|s| {
            let x = cut
                .mesh
                .triangles
                .iter()
                .zip(&cut.segment_of)
                .filter(|(_, &id)| id as usize == s.id)
                .map(|(t, _)| cut.mesh.positions[t[0] as usize][0])
                .sum::<f64>()
                / s.triangles as f64;
            (x, s)
        })
        .collect();
    by_x.sort_by(|a, b| a.0.total_cmp(&b.0));
    for ((_, s), (area, volume)) in by_x.iter().zip(expected) {
        assert!(close(s.area, area, 0.01), "{s:?}: area {area}");
        let v = s.volume.unwrap();
        assert!(close(v, volume, 0.01), "{s:?}: volume {volume}");
    }
    // The end balls are disks cut off by one loop, the middle one a tube between two.
    let shapes: Vec<(i64, usize, usize)> = by_x
        .iter()
        .map(|(_, s)| (s.euler, s.boundaries, s.loops.len()))
        .collect();
    assert_eq!(shapes, vec![(1, 1, 1), (0, 2, 2), (1, 1, 1)]);
    // Nothing is lost: the parts add up to the whole.
    let area: f64 = cut.segments.iter().map(|s| s.area).sum();
    assert!(close(area, mesh.area(), 1e-9));
    let volume: f64 = cut.segments.iter().map(|s| s.volume.unwrap()).sum();
    assert!(close(volume, total_volume, 1e-9));
}

#[test]
fn a_dumbbell_falls_into_two_halves() {
    let mesh = Shape::new(ShapeKind::Dumbbell).mesh().unwrap();
    let report = necks(&mesh, true, false);
    let loops: Vec<_> = report.loops.iter().collect();
    let cut = segment_along_loops(&mesh, &loops).unwrap();
    assert_eq!(cut.segments.len(), 2);
    for s in &cut.segments {
        assert_eq!((s.euler, s.boundaries, s.genus), (1, 1, 0));
        assert!(close(s.area, 0.5 * mesh.area(), 0.01), "{s:?}");
        assert!(
            close(s.volume.unwrap(), 0.5 * mesh.signed_volume(), 0.01),
            "{s:?}"
        );
    }
    // Every refined triangle lies in an input triangle, and the cut keeps the surface.
    assert_eq!(cut.parent.len(), cut.mesh.triangles.len());
    assert!(close(cut.mesh.area(), mesh.area(), 1e-9));
}

#[test]
fn a_torus_cut_along_its_handle_loop_is_one_cylinder_and_along_both_one_disk() {
    let mesh = Shape::new(ShapeKind::Torus).mesh().unwrap();
    let report = necks(&mesh, true, true);
    let handle: Vec<_> = report
        .loops
        .iter()
        .filter(|l| l.kind == Side::Inside)
        .collect();
    assert_eq!(handle.len(), 1);
    let cut = segment_along_loops(&mesh, &handle).unwrap();
    assert_eq!(cut.segments.len(), 1);
    let s = &cut.segments[0];
    assert_eq!((s.euler, s.boundaries, s.genus), (0, 2, 0), "{s:?}");
    assert!(close(s.volume.unwrap(), mesh.signed_volume(), 1e-9));

    let both: Vec<_> = report.loops.iter().collect();
    assert_eq!(both.len(), 2);
    let cut = segment_along_loops(&mesh, &both).unwrap();
    assert_eq!(cut.segments.len(), 1);
    let s = &cut.segments[0];
    assert_eq!((s.euler, s.boundaries, s.genus), (1, 1, 0), "{s:?}");
}
