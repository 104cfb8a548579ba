//! Pictures and run files: a rendered dumbbell shows the handle colour where its neck
//! projects and not at its balls; projections frame the box; charts draw their series;
//! `write_run` writes every file, readable back with the documented fields.

use necklace::io;
use necklace::output::{self, OutputOptions, HANDLE_COLOR};
use necklace::pipeline::{find_necks, NeckOptions};
use necklace::render::chart::{chart, Chart, Series};
use necklace::render::{render, Curve, Image, Mark, Projection, RenderOptions, Scene, View};
use necklace::shapes::{Shape, ShapeKind};

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("necklace-render-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn close(a: [u8; 3], b: [u8; 3], tolerance: i32) -> bool {
    (0..3).all(|k| (i32::from(a[k]) - i32::from(b[k])).abs() <= tolerance)
}

/// Pixels within `r` of (x, y) whose colour is within `tolerance` of `color`.
fn count_near(image: &Image, at: [f64; 2], r: f64, color: [u8; 3], tolerance: i32) -> usize {
    let mut n = 0;
    for y in (at[1] - r).max(0.0) as u32..(at[1] + r) as u32 {
        for x in (at[0] - r).max(0.0) as u32..(at[0] + r) as u32 {
            if image
                .pixel(x, y)
                .is_some_and(|c| close(c, color, tolerance))
            {
                n += 1;
            }
        }
    }
    n
}

#[test]
fn a_rendered_dumbbell_shows_the_handle_colour_at_its_neck_and_not_at_its_balls() {
    // The neck is the circle of radius 0.15 around the x axis at x = 0; balls at x = ±0.9.
    let shape = Shape::new(ShapeKind::Dumbbell).with("res", 40.0).unwrap();
    let surface = shape.mesh().unwrap();
    let options = NeckOptions {
        tunnels: false,
        ..NeckOptions::default()
    };
    let report = find_necks(&surface, &options).unwrap();
    assert_eq!(report.loops.len(), 1);

    let dir = temp_dir("dumbbell");
    let files = OutputOptions {
        picture: Some(RenderOptions {
            size: 800,
            ..RenderOptions::default()
        }),
        volume: false,
        html: false,
    };
    let written = output::write_run(&dir, &surface, &report, &files, None).unwrap();
    assert!(written.contains(&dir.join("view.png")));
    let image = Image::read_png(dir.join("view.png")).unwrap();
    // Two by two views of 400 pixels under a title band.
    assert_eq!(image.width, 800);
    assert!((820..=860).contains(&image.height), "{}", image.height);

    // Where each view put the neck, found by rendering the same scene again (the
    // saddles as dots: the picture's are the loops' saddles).
    let curves = output::loop_curves(&report);
    let saddles: Vec<[f64; 3]> = report.loops.iter().map(|l| l.saddle).collect();
    let scene = output::loop_scene("surface", &surface, &curves, &saddles);
    let rendered = render(&scene, files.picture.as_ref().unwrap()).unwrap();
    assert_eq!(rendered.image, image);
    // The title names the mesh and its counts, in dark text above the first view.
    let title = scene.title.as_deref().unwrap();
    assert!(
        title.starts_with("surface: ") && title.contains("1 handle, 0 tunnels"),
        "{title}"
    );
    let band = rendered.tiles[0].origin[1];
    assert!(band > 0);
    let dark_in_band = (0..band)
        .flat_map(|y| (0..image.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            image
                .pixel(x, y)
                .is_some_and(|c| c.iter().all(|&v| v < 100))
        })
        .count();
    assert!(dark_in_band > 50, "{dark_in_band}");
    // The legend explains the loops' colour and the dots.
    let marks: Vec<(&str, Mark)> = scene
        .legend
        .iter()
        .map(|e| (e.text.as_str(), e.mark))
        .collect();
    assert_eq!(marks[0], ("handle loop", Mark::Line));
    assert_eq!(marks[1].1, Mark::Dot);
    assert!(marks[1].0.starts_with("saddle"));
    let front = rendered
        .tiles
        .iter()
        .position(|t| t.view == View::Front)
        .unwrap();
    let neck = rendered.pixel_of(front, [0.0, 0.0, 0.0]);
    let ball = rendered.pixel_of(front, [0.9, 0.0, 0.0]);
    // Visible, shaded tube pixels are the handle colour darkened by at most ~45 %.
    let hits = |at| {
        (0..=10)
            .map(|k| {
                let c = HANDLE_COLOR.map(|v| (f64::from(v) * (1.0 - 0.045 * f64::from(k))) as u8);
                count_near(&image, at, 12.0, c, 18)
            })
            .sum::<usize>()
    };
    assert!(
        hits(neck) > 10,
        "handle pixels near the neck at {neck:?}: {}",
        hits(neck)
    );
    assert_eq!(hits(ball), 0, "handle pixels at a ball centre {ball:?}");
    // The background stays white in the corners of the tile.
    let corner = rendered.tiles[front].origin;
    assert_eq!(
        image.pixel(corner[0] + 790 / 2 - 5, corner[1] + 390),
        Some([255; 3])
    );
}

#[test]
fn a_projection_frames_the_box_inside_the_margin() {
    let (lo, hi) = ([-1.0, -2.0, 0.5], [3.0, 1.0, 2.0]);
    for view in View::ALL {
        let p = Projection::framed(view, lo, hi, 500.0, 0.1);
        let mut extent = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
        for corner in 0..8 {
            let c = [0, 1, 2].map(|k| if corner >> k & 1 == 1 { hi[k] } else { lo[k] });
            let q = p.project(c);
            extent = [
                extent[0].min(q[0]),
                extent[1].max(q[0]),
                extent[2].min(q[1]),
                extent[3].max(q[1]),
            ];
        }
        assert!(
            extent[0] >= 50.0 - 1e-9 && extent[1] <= 450.0 + 1e-9,
            "{view:?} {extent:?}"
        );
        assert!(
            extent[2] >= 50.0 - 1e-9 && extent[3] <= 450.0 + 1e-9,
            "{view:?} {extent:?}"
        );
        // The longer projected side fills the tile up to the margin.
        let longest = (extent[1] - extent[0]).max(extent[3] - extent[2]);
        assert!((longest - 400.0).abs() < 1e-6, "{view:?} {longest}");
    }
    // Front looks down −z with y up: +x goes right, +y goes up the picture.
    let p = Projection::framed(View::Front, lo, hi, 500.0, 0.1);
    let (a, b, c) = (
        p.project([0.0; 3]),
        p.project([1.0, 0.0, 0.0]),
        p.project([0.0, 1.0, 0.0]),
    );
    assert!(b[0] > a[0] && (b[1] - a[1]).abs() < 1e-9);
    assert!(c[1] < a[1] && (c[0] - a[0]).abs() < 1e-9);
    // Depth grows away from the viewer (who is at +z).
    assert!(p.project([0.0, 0.0, 1.0])[2] < a[2]);
}

#[test]
fn bad_render_options_and_empty_meshes_are_errors() {
    let surface = Shape::new(ShapeKind::Sphere)
        .with("res", 16.0)
        .unwrap()
        .mesh()
        .unwrap();
    let scene = Scene {
        mesh: &surface,
        curves: vec![Curve {
            points: vec![[f64::NAN, 0.0, 0.0]],
            closed: true,
            color: [0; 3],
            label: None,
        }],
        dots: vec![],
        legend: vec![],
        title: None,
    };
    assert!(render(&scene, &RenderOptions::default()).is_err());
    let scene = Scene {
        curves: vec![],
        ..scene
    };
    for options in [
        RenderOptions {
            views: 5,
            ..RenderOptions::default()
        },
        RenderOptions {
            views: 0,
            ..RenderOptions::default()
        },
        RenderOptions {
            size: 10,
            ..RenderOptions::default()
        },
        RenderOptions {
            opacity: 1.5,
            ..RenderOptions::default()
        },
    ] {
        let e = render(&scene, &options).unwrap_err();
        assert_eq!(e.kind(), necklace::ErrorKind::InvalidArgument, "{e}");
    }
    let one = render(
        &scene,
        &RenderOptions {
            views: 1,
            size: 300,
            ..RenderOptions::default()
        },
    )
    .unwrap();
    assert_eq!((one.image.width, one.image.height), (300, 300));
    let three = render(
        &scene,
        &RenderOptions {
            views: 3,
            size: 300,
            ..RenderOptions::default()
        },
    )
    .unwrap();
    assert_eq!((three.image.width, three.image.height), (300, 100));
}

#[test]
fn a_chart_draws_each_series_in_its_colour() {
    let figure = Chart {
        title: "test".into(),
        x_label: "x".into(),
        y_label: "y".into(),
        series: vec![
            Series {
                name: "a".into(),
                color: [200, 30, 30],
                points: vec![[0.0, 0.0], [10.0, 5.0], [20.0, 7.0]],
            },
            Series {
                name: "b".into(),
                color: [30, 30, 200],
                points: vec![[0.0, 1.0], [20.0, 1.5]],
            },
        ],
    };
    let image = chart(&figure, 600, 400).unwrap();
    let count = |c: [u8; 3]| image.pixels.iter().filter(|p| close(**p, c, 10)).count();
    assert!(count([200, 30, 30]) > 100);
    assert!(count([30, 30, 200]) > 100);
    assert!(chart(&figure, 10, 10).is_err());
}

#[test]
fn a_run_writes_every_file_with_the_documented_fields() {
    let shape = Shape::new(ShapeKind::VaryingTorus)
        .with("res", 48.0)
        .unwrap();
    let surface = shape.mesh().unwrap();
    let options = NeckOptions {
        keep_volume: true,
        ..NeckOptions::default()
    };
    let report = find_necks(&surface, &options).unwrap();
    assert!(!report.loops.is_empty());
    let dir = temp_dir("run");
    let files = OutputOptions {
        picture: None,
        volume: true,
        html: true,
    };
    output::write_run(&dir, &surface, &report, &files, None).unwrap();

    // loops.json: version 1 and the documented top-level fields; reads back.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("loops.json")).unwrap()).unwrap();
    assert_eq!(json["version"], necklace::output::JSON_VERSION);
    for key in [
        "input", "units", "flipped", "loops", "dropped", "morse", "timings", "sides",
    ] {
        assert!(json.get(key).is_some(), "{key}");
    }
    // ... and into the report itself: every field the JSON has comes back.
    let back = output::read_report_json(dir.join("loops.json")).unwrap();
    assert_eq!(
        serde_json::to_value(&back).unwrap(),
        serde_json::to_value(&report).unwrap()
    );
    assert_eq!(back.loops.len(), report.loops.len());
    for (a, b) in back.loops.iter().zip(&report.loops) {
        assert_eq!(
            (a.kind, &a.points, &a.surface_points),
            (b.kind, &b.points, &b.surface_points)
        );
    }
    let curves = output::read_loops_json(dir.join("loops.json")).unwrap();
    assert_eq!(curves, output::loop_curves(&report));
    let saddles = output::read_points_json(dir.join("loops.json")).unwrap();
    let selected: usize = report.sides.iter().map(|s| s.saddles.len()).sum();
    assert_eq!(saddles.len(), selected);

    // view.html: one page with the data in it, one row of data per loop, loading
    // nothing (the browser test in the Python suite drives it).
    let page = std::fs::read_to_string(dir.join("view.html")).unwrap();
    let start = page.find("id=\"necklace-data\">").unwrap() + "id=\"necklace-data\">".len();
    let end = start + page[start..].find("</script>").unwrap();
    let data: serde_json::Value =
        serde_json::from_str(&page[start..end].replace("<\\/", "</")).unwrap();
    assert_eq!(data["loops"].as_array().unwrap().len(), report.loops.len());
    assert!(data["note"].is_null(), "a small surface is not decimated");
    let positions = data["mesh"]["positions"].as_str().unwrap();
    assert_eq!(positions.len(), surface.num_vertices() * 12 / 3 * 4);

    // loops.ply: a closed edge loop per loop, each edge tagged with its loop.
    let ply = std::fs::read(dir.join("loops.ply")).unwrap();
    let header =
        String::from_utf8_lossy(&ply[..ply.windows(10).position(|w| w == b"end_header").unwrap()])
            .to_string();
    let points: usize = report.loops.iter().map(|l| l.points.len()).sum();
    assert!(
        header.contains(&format!("element vertex {points}")),
        "{header}"
    );
    assert!(
        header.contains(&format!("element edge {points}")),
        "{header}"
    );
    // The loop index rides on the vertices; edges are bare pairs (trimesh refuses
    // edges with more properties).
    assert!(header.contains("property int loop"));
    assert!(
        header.ends_with("property int vertex1\nproperty int vertex2\n"),
        "{header}"
    );

    // loops.vtp and loops.vtu: a polyline per loop, a line cell per segment.
    let vtp = std::fs::read(dir.join("loops.vtp")).unwrap();
    let vtp = String::from_utf8_lossy(&vtp);
    assert!(
        vtp.contains(&format!("NumberOfLines=\"{}\"", report.loops.len())),
        "{vtp}"
    );
    let vtu = std::fs::read(dir.join("loops.vtu")).unwrap();
    let vtu = String::from_utf8_lossy(&vtu);
    assert!(vtu.contains(&format!("NumberOfCells=\"{points}\"")));

    // critical.ply: every alive critical point of both sides, with a side field.
    let cloud_points: usize = report.sides.iter().map(|s| s.critical.len()).sum();
    let ply = std::fs::read(dir.join("critical.ply")).unwrap();
    let header = String::from_utf8_lossy(&ply[..200.min(ply.len())]).to_string();
    assert!(
        header.contains(&format!("element vertex {cloud_points}")),
        "{header}"
    );

    // field.vtu: both volume meshes with the field, readable as a tet mesh.
    let volume = io::read_tet_mesh(dir.join("field.vtu")).unwrap();
    let vertices: usize = report.sides.iter().map(|s| s.volume.vertices).sum();
    let tets: usize = report.sides.iter().map(|s| s.volume.tets).sum();
    assert_eq!((volume.num_vertices(), volume.tets.len()), (vertices, tets));
    let bytes = std::fs::read(dir.join("field.vtu")).unwrap();
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(2000)]).to_string();
    assert!(head.contains("Name=\"field\""), "{head}");
    assert!(head.contains("<AppendedData encoding=\"raw\">"), "{head}");
    // Compressed binary: far below the 8 bytes of each coordinate and index.
    assert!(
        bytes.len() < 8 * (3 * vertices + 4 * tets) / 2,
        "{}",
        bytes.len()
    );

    // Without the kept volume, field.vtu is refused with a reason.
    let plain = find_necks(
        &surface,
        &NeckOptions {
            tunnels: false,
            ..NeckOptions::default()
        },
    )
    .unwrap();
    let e = output::write_run(&dir, &surface, &plain, &files, None).unwrap_err();
    assert!(e.to_string().contains("keep_volume"), "{e}");
}

#[test]
fn inward_facing_input_is_flipped_and_gives_the_same_loops() {
    let mut surface = Shape::new(ShapeKind::Dumbbell)
        .with("res", 40.0)
        .unwrap()
        .mesh()
        .unwrap();
    let options = NeckOptions {
        tunnels: false,
        ..NeckOptions::default()
    };
    let outward = find_necks(&surface, &options).unwrap();
    surface.flip_orientation();
    let inward = find_necks(&surface, &options).unwrap();
    assert!(inward.flipped && !outward.flipped);
    assert_eq!(inward.loops.len(), outward.loops.len());
    assert!((inward.loops[0].length - outward.loops[0].length).abs() < 1e-9);
}

#[test]
fn a_barcode_draws_necks_in_colour_and_other_tracks_in_grey() {
    use necklace::render::barcode::{barcode, BarPanel, BarSpan};
    let panel = BarPanel {
        title: "inside".into(),
        color: [213, 62, 30],
        bars: vec![
            BarSpan {
                birth: 0.1,
                death: None,
                highlight: true,
            },
            BarSpan {
                birth: 0.2,
                death: Some(0.3),
                highlight: false,
            },
        ],
    };
    let image = barcode(std::slice::from_ref(&panel), 1.0, 600, 400).unwrap();
    let count = |c: [u8; 3]| image.pixels.iter().filter(|p| **p == c).count();
    assert!(
        count([213, 62, 30]) > 1000,
        "the neck's bar is drawn in colour"
    );
    assert!(count([184, 184, 184]) > 100, "the other bar in grey");
    assert!(barcode(std::slice::from_ref(&panel), f64::NAN, 600, 400).is_err());
    assert!(barcode(&[], 1.0, 600, 400).is_err());
    let mut bad = panel;
    bad.bars[0].birth = -1.0;
    assert!(barcode(&[bad], 1.0, 600, 400).is_err());
}
