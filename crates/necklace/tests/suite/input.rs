//! The input step on what real files hold: corners that STL keeps apart or an exporter
//! rounds are welded (and said so), parts that touch stay apart, and input with no
//! volume to mesh (a triangle soup, open sheets) is refused at once with the reason.
//! Ground truth: the counts and genus that trimesh (which merges at 1e-8) gives for the
//! shared real-world models (`MANIFEST.tsv`), and shapes built here.

use necklace::error::ErrorKind;
use necklace::io::{read_mesh, read_mesh_bytes, Format};
use necklace::pipeline::{prepare_input, prepare_input_with, weld_input, InputOptions};
use necklace::{MeshReport, SurfaceMesh};

use crate::common::{realworld_dir, sphere};

/// An ASCII STL of `mesh`, each corner written with `wobble(facet, corner)` added to
/// every coordinate (an exporter's rounding: `6e-17` where it means 0).
fn ascii_stl(mesh: &SurfaceMesh, wobble: impl Fn(usize, usize) -> f64) -> Vec<u8> {
    let mut out = String::from("solid wobbly\n");
    for (f, t) in mesh.triangles.iter().enumerate() {
        out.push_str("facet normal 0 0 0\nouter loop\n");
        for (i, &v) in t.iter().enumerate() {
            let p = mesh.positions[v as usize].map(|c| c + wobble(f, i));
            out.push_str(&format!("vertex {:e} {:e} {:e}\n", p[0], p[1], p[2]));
        }
        out.push_str("endloop\nendfacet\n");
    }
    out.push_str("endsolid wobbly\n");
    out.into_bytes()
}

#[test]
fn an_stl_whose_corners_an_exporter_rounded_apart_reads_as_the_closed_solid() {
    let ball = sphere(1.0, [0.3, -0.2, 0.1], 12.0);
    let truth = MeshReport::new(&ball);
    assert!(truth.watertight && truth.genus == vec![Some(0)]);
    // Every third corner moved by 1e-12 (far below 1e-8 of the diagonal).
    let stl = ascii_stl(&ball, |f, i| if (f + i) % 3 == 0 { 1e-12 } else { 0.0 });
    let read = read_mesh_bytes(&stl, Format::Stl).unwrap();
    assert!(
        !MeshReport::new(&read).watertight,
        "the reader welds exact copies only"
    );

    let prepared = prepare_input(read.clone()).unwrap();
    assert_eq!(prepared.mesh.num_vertices(), ball.num_vertices());
    assert!(prepared.mesh_report.watertight && prepared.mesh_report.genus == vec![Some(0)]);
    let note = prepared
        .notes
        .iter()
        .find(|n| n.starts_with("welded"))
        .unwrap();
    assert!(note.contains("--no-weld"), "{note}");
    // Every prepared vertex names an input vertex at its place.
    for (v, &i) in prepared.input_vertex.iter().enumerate() {
        let (p, q) = (prepared.mesh.positions[v], read.positions[i as usize]);
        assert!((0..3).all(|k| (p[k] - q[k]).abs() < 1e-11));
    }

    // Turned off: the cracks stay, and the method is told.
    let kept = prepare_input_with(read, &InputOptions { weld: None }).unwrap();
    assert!(!kept.mesh_report.watertight);
    assert!(kept.notes.iter().all(|n| !n.starts_with("welded")));
    assert!(kept.warnings.iter().any(|w| w.contains("boundary edges")));
}

#[test]
fn a_weld_tolerance_that_is_no_fraction_is_refused_in_one_line() {
    let ball = sphere(1.0, [0.0; 3], 12.0);
    for bad in [-1e-8, f64::NAN, f64::INFINITY] {
        let err = prepare_input_with(ball.clone(), &InputOptions { weld: Some(bad) }).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::InvalidArgument);
        assert!(err.to_string().contains("weld") && !err.to_string().contains('\n'));
    }
}

#[test]
fn real_files_with_split_corners_read_closed_and_touching_parts_stay_apart() {
    let dir = realworld_dir();
    if !dir.is_dir() {
        println!("SKIPPED: no real-world folder at {}", dir.display());
        return;
    }
    // (file, vertices and genus after welding as trimesh reads them, whether welding
    // merges anything).
    let cases = [
        ("tm_featuretype.STL", 1722, vec![Some(9)], true),
        ("tm_angle_block.STL", 352, vec![Some(1)], true),
        ("tm_Duck.ply", 2108, vec![Some(0)], true),
        // Two closed parts that share 59 positions where they touch: not welded.
        (
            "mf_openscad-nonmanifold-crash.obj",
            717,
            vec![Some(4), Some(0)],
            false,
        ),
        ("ps_mk3_bed.stl", 916, vec![Some(2)], false),
    ];
    for (name, vertices, genus, welds) in cases {
        let mesh = read_mesh(dir.join(name)).unwrap();
        let welded = weld_input(mesh, &InputOptions::default());
        let report = MeshReport::new(&welded.mesh);
        assert_eq!(welded.note.is_some(), welds, "{name}");
        assert_eq!((welded.welding.merged > 0), welds, "{name}");
        assert_eq!(report.vertices, vertices, "{name}");
        assert!(
            report.watertight && report.manifold,
            "{name}: {:?}",
            report.problems()
        );
        assert_eq!(report.genus, genus, "{name}");
    }
}

/// A deterministic pseudo-random number in [0, 1).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

#[test]
fn a_triangle_soup_and_open_sheets_are_refused_with_the_reason() {
    // 100 loose triangles in a unit box, as trimesh's soup.stl.
    let mut state = 7;
    let mut soup = SurfaceMesh::default();
    for i in 0..100u32 {
        for _ in 0..3 {
            soup.positions
                .push([lcg(&mut state), lcg(&mut state), lcg(&mut state)]);
        }
        soup.triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    // Two separate square panels side by side, gently bent (a pattern cut from sheet
    // material). (Panels at an angle can half-enclose a wedge, which the winding number
    // counts as solid: only the method's own judgement, the share of triangles with the
    // solid on one side, decides, as for the real chair of glued panels.)
    let sheets = SurfaceMesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.1],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.1],
            [1.5, 0.0, 0.0],
            [2.5, 0.0, 0.1],
            [2.5, 1.0, 0.0],
            [1.5, 1.0, 0.1],
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]],
    };
    for (what, mesh) in [("soup", soup), ("sheets", sheets)] {
        let err = prepare_input(mesh).unwrap_err();
        let text = err.to_string();
        assert_eq!(err.kind(), ErrorKind::InvalidMesh, "{what}");
        assert!(
            text.contains("encloses no volume") && !text.contains('\n'),
            "{what}: {text}"
        );
    }
}

#[test]
fn a_solid_with_a_hole_or_cut_at_its_seams_is_not_refused() {
    // A ball with a few triangles missing: open, but nearly all of it bounds the solid.
    let mut holed = sphere(1.0, [0.0; 3], 12.0);
    holed.triangles.truncate(holed.triangles.len() - 3);
    let prepared = prepare_input(holed).unwrap();
    assert!(!prepared.mesh_report.watertight);
    assert!(prepared
        .warnings
        .iter()
        .any(|w| w.contains("boundary edges")));
    // A ball cut at every edge (each triangle its own piece, not welded): a soup by its
    // structure, but every triangle separates in from out.
    let ball = sphere(1.0, [0.0; 3], 12.0);
    let mut pieces = SurfaceMesh::default();
    for t in &ball.triangles {
        let base = pieces.positions.len() as u32;
        pieces
            .positions
            .extend(t.map(|v| ball.positions[v as usize]));
        pieces.triangles.push([base, base + 1, base + 2]);
    }
    assert!(prepare_input_with(pieces, &InputOptions { weld: None }).is_ok());
}
