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
        let cut = necklace::pipeline::cut_along_loop(surface, neck, 0.05).unwrap();
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
