//! Surgery along neck loops (issue 41, in progress): the band's curves on either side of
//! a found loop, and the caps that close them, against the torus's closed forms.

use std::f64::consts::PI;

use necklace::mesh::Topology;
use necklace::shapes::{Shape, ShapeKind};
use necklace::surgery::{cap, offset_curves, CapOptions};
use necklace::Side;

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// The closest point to `p` on the segment `a`–`b`.
fn closest_on_segment(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let d = sub(b, a);
    let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let t = if dd > 0.0 {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1] + (p[2] - a[2]) * d[2]) / dd).clamp(0.0, 1.0)
    } else {
        0.0
    };
    [a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]]
}

#[test]
fn the_torus_handle_loop_has_meridians_on_either_side_and_their_caps_are_its_disks() {
    let shape = Shape::new(ShapeKind::Torus);
    let r = shape.param("r");
    let report =
        necklace::find_necks(&shape.mesh().unwrap(), &necklace::Options::default()).unwrap();
    let surface = &report.surface;
    let handle = report
        .loops
        .iter()
        .find(|l| l.kind == Side::Inside)
        .unwrap();
    let curve = necklace::pipeline::loop_on_surface(handle);
    let delta = 0.1 * handle.radius;
    let offsets = offset_curves(surface, &Topology::new(surface), &curve, delta).unwrap();
    let loop_points = &handle.points;
    let distance_to_loop = |p: [f64; 3]| {
        (0..loop_points.len())
            .map(|k| {
                let q =
                    closest_on_segment(p, loop_points[k], loop_points[(k + 1) % loop_points.len()]);
                norm(sub(p, q))
            })
            .fold(f64::INFINITY, f64::min)
    };
    for c in &offsets.curves {
        let points: Vec<[f64; 3]> = c.iter().map(|p| p.position(surface)).collect();
        // On the tube, a curve δ from a meridian is a meridian too: about 2πr long (the
        // polygon tube's, a little shorter), and δ from the loop everywhere.
        let length: f64 = (0..points.len())
            .map(|i| norm(sub(points[(i + 1) % points.len()], points[i])))
            .sum();
        assert!((length / (2.0 * PI * r) - 1.0).abs() < 0.05, "{length}");
        for p in &points {
            let d = distance_to_loop(*p);
            assert!((d / delta - 1.0).abs() < 0.05, "{d} for δ {delta}");
        }
        // Its cap is about the tube's disk, πr² (faired flat, a little under it).
        let disk = cap(&points, handle.saddle, &CapOptions::default()).unwrap();
        assert!(
            (disk.area / (PI * r * r) - 1.0).abs() < 0.05,
            "{}",
            disk.area
        );
        assert!(disk.area <= disk.cone_area);
    }
}

#[test]
fn cutting_the_torus_through_its_handle_or_plugging_its_hole_leaves_a_valid_ball() {
    let shape = Shape::new(ShapeKind::Torus);
    let report =
        necklace::find_necks(&shape.mesh().unwrap(), &necklace::Options::default()).unwrap();
    let surface = &report.surface;
    let volume = surface.signed_volume();
    for side in [Side::Inside, Side::Outside] {
        let neck = report.loops.iter().find(|l| l.kind == side).unwrap();
        let cut = necklace::pipeline::cut_along_loop(
            surface,
            neck,
            0.05,
            necklace::surgery::Fairing::MinimalArea,
        )
        .unwrap();
        let r = necklace::MeshReport::new(&cut.mesh);
        assert!(r.is_valid_solid(), "{side:?}: {:?}", r.problems());
        assert_eq!(r.genus, vec![Some(0)], "{side:?}");
        assert_eq!(r.outward, Some(true), "{side:?}");
        let crossings = necklace::distance::SurfaceDistance::new(&cut.mesh)
            .self_intersections(&cut.mesh.triangles);
        assert!(
            crossings.is_empty(),
            "{side:?}: {} crossings",
            crossings.len()
        );
        match side {
            // The band is 2δ of the tube: about δ/(πR) of the volume.
            Side::Inside => {
                assert!(cut.volume_change < 0.0);
                assert!(-cut.volume_change / volume < 0.02, "{}", cut.volume_change);
            }
            Side::Outside => assert!(cut.volume_change > 0.0, "{}", cut.volume_change),
        }
    }
}

fn torus_repaired(only: Option<Side>) -> (necklace::SurfaceMesh, necklace::pipeline::RepairReport) {
    let mesh = Shape::new(ShapeKind::Torus).mesh().unwrap();
    let options = necklace::pipeline::RepairOptions {
        only,
        ..Default::default()
    };
    necklace::pipeline::repair(&mesh, &options).unwrap()
}

#[test]
fn repair_takes_the_torus_to_genus_0_by_its_cheaper_cut_or_by_a_plug_of_the_hole() {
    let (big_r, r) = (1.0, 0.3);
    for only in [None, Some(Side::Outside)] {
        let (out, report) = torus_repaired(only);
        let check = necklace::MeshReport::new(&out);
        assert!(check.is_valid_solid(), "{:?}", check.problems());
        assert_eq!(check.genus, vec![Some(0)]);
        assert_eq!(report.genus, [1, 0]);
        assert_eq!(report.operations.len(), 1);
        let op = &report.operations[0];
        let delta = 0.5 * op.band_width;
        match only {
            // The handle's cap (2πr²) is cheaper than the hole's (2π(R − r)²).
            None => {
                assert_eq!(op.neck.kind, Side::Inside);
                assert!(
                    (op.cap_area / (2.0 * PI * r * r) - 1.0).abs() < 0.05,
                    "{}",
                    op.cap_area
                );
                assert!(-op.volume_change / report.volume[0] < 0.02);
            }
            // The plug fills the hole between heights ±δ: its section at height z is
            // the disk of radius R − √(r² − z²); the caps are those at ±δ.
            _ => {
                assert_eq!(op.neck.kind, Side::Outside);
                let disk = |z: f64| PI * (big_r - (r * r - z * z).sqrt()).powi(2);
                assert!(
                    (op.cap_area / (2.0 * disk(delta)) - 1.0).abs() < 0.05,
                    "{}",
                    op.cap_area
                );
                let steps = 100;
                let plug: f64 = (0..steps)
                    .map(|i| disk(-delta + (i as f64 + 0.5) * 2.0 * delta / steps as f64))
                    .sum::<f64>()
                    * 2.0
                    * delta
                    / steps as f64;
                assert!(
                    (op.volume_change / plug - 1.0).abs() < 0.05,
                    "{} for {plug}",
                    op.volume_change
                );
            }
        }
        // No neck loop is left.
        let again = necklace::find_necks(&out, &necklace::Options::default()).unwrap();
        assert!(again.loops.is_empty(), "{} loops left", again.loops.len());
    }
}

#[test]
fn repair_by_length_removes_the_rings_handles_only_and_changes_nothing_else() {
    let shape = Shape::new(ShapeKind::Rings);
    let wire = shape.param("wire");
    let mesh = shape.mesh().unwrap();
    let options = necklace::pipeline::RepairOptions {
        target: necklace::pipeline::RepairTarget::MaxLength(3.0 * 2.0 * PI * wire),
        ..Default::default()
    };
    let (out, report) = necklace::pipeline::repair(&mesh, &options).unwrap();
    assert_eq!(report.operations.len(), shape.param("count") as usize);
    assert!(report
        .operations
        .iter()
        .all(|op| op.neck.kind == Side::Inside));
    assert_eq!(necklace::MeshReport::new(&out).genus, vec![Some(0)]);
    // The caps lie inside the wires: nothing moves farther than the wire's radius.
    assert!(report.hausdorff < 1.5 * wire, "{}", report.hausdorff);
}

#[test]
fn repair_takes_the_rings_to_genus_0_with_every_change_inside_a_ring() {
    let shape = Shape::new(ShapeKind::Rings);
    let (ring, wire) = (shape.param("ring"), shape.param("wire"));
    let mesh = shape.mesh().unwrap();
    let (out, report) = necklace::pipeline::repair(&mesh, &Default::default()).unwrap();
    let count = shape.param("count") as usize;
    assert_eq!(report.genus, [count as i64, 0]);
    // Each ring's cheaper class is its wire's handle (a disk of the wire's section).
    assert_eq!(report.operations.len(), count);
    for op in &report.operations {
        assert_eq!(op.neck.kind, Side::Inside);
        assert!((op.cap_area / (2.0 * PI * wire * wire) - 1.0).abs() < 0.1);
        assert!(op.max_displacement < 1.1 * wire, "{}", op.max_displacement);
    }
    let check = necklace::MeshReport::new(&out);
    assert!(check.is_valid_solid(), "{:?}", check.problems());
    assert_eq!(check.genus, vec![Some(0)]);
    // Every point that moved lies within a ring: the rings' centres are on the ball,
    // below their tunnels' centres.
    let centres: Vec<[f64; 3]> = shape
        .expected_necks()
        .iter()
        .filter(|n| n.kind == Side::Outside)
        .filter_map(|n| n.center)
        .map(|c| {
            let s = shape.param("body") / norm(c);
            [c[0] * s, c[1] * s, c[2] * s]
        })
        .collect();
    assert_eq!(centres.len(), count);
    let to_input = necklace::distance::SurfaceDistance::without_winding(&mesh);
    let moved = out
        .positions
        .iter()
        .zip(to_input.distances(&out.positions))
        .filter(|(_, d)| *d > 1e-6 * mesh.bbox_diagonal())
        .map(|(p, _)| *p)
        .collect::<Vec<_>>();
    assert!(!moved.is_empty());
    for p in moved {
        let near = centres
            .iter()
            .map(|&c| norm(sub(p, c)))
            .fold(f64::MAX, f64::min);
        assert!(near < ring + 2.0 * wire, "{p:?} is {near} from every ring");
    }
    assert!(report.hausdorff < 2.0 * wire, "{}", report.hausdorff);
}

#[test]
fn repair_refuses_a_genus_above_the_surfaces_and_an_open_surface_in_one_line() {
    let torus = Shape::new(ShapeKind::Torus)
        .with("res", 24.0)
        .unwrap()
        .mesh()
        .unwrap();
    let options = necklace::pipeline::RepairOptions {
        target: necklace::pipeline::RepairTarget::Genus(2),
        ..Default::default()
    };
    let err = necklace::pipeline::repair(&torus, &options)
        .unwrap_err()
        .to_string();
    assert!(err.contains("--genus 2: the surface has genus 1"), "{err}");
    let mut open = torus.clone();
    open.triangles.pop();
    let err = necklace::pipeline::repair(&open, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(!err.contains('\n'), "{err}");
}
