//! The `necklace` binary end to end: exit codes, files written, JSON fields.

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

/// `necklace batch`.
#[path = "cli/batch.rs"]
mod batch;

/// Careless and hostile input.
#[path = "cli/hostile.rs"]
mod hostile;

fn necklace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_necklace"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// (kind, length) of every loop of a `loops --json` run.
fn loops_of(json: &Value) -> Vec<(String, f64)> {
    json["loops"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| {
            (
                l["kind"].as_str().unwrap().to_string(),
                l["length"].as_f64().unwrap(),
            )
        })
        .collect()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("necklace-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn shape_then_info_json_reports_the_generated_genus() {
    let dir = temp_dir("eight");
    let path = dir.join("eight.ply");
    let out = necklace(&[
        "shape",
        "eight",
        "--param",
        "res=40",
        "-o",
        path.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(path.exists());

    let out = necklace(&["info", path.to_str().unwrap(), "--json"]);
    assert_eq!(out.status.code(), Some(0));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "vertices",
        "faces",
        "components",
        "genus",
        "euler",
        "watertight",
        "manifold",
        "oriented",
        "outward",
        "boundary_edges",
        "bbox_min",
        "bbox_max",
    ] {
        assert!(json.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(json["genus"], serde_json::json!([2]));
    assert_eq!(json["euler"], serde_json::json!(-2));
    assert_eq!(json["watertight"], serde_json::json!(true));
    assert_eq!(json["outward"], serde_json::json!(true));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn info_text_names_the_problems_of_an_open_mesh_and_exits_0() {
    let dir = temp_dir("open");
    let path = dir.join("open.obj");
    std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let out = necklace(&["info", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("open: 3 boundary edges in 1 loops"), "{text}");
    let _ = std::fs::remove_dir_all(dir);
}

/// An ASCII STL of a tetrahedron whose shared corners an exporter wrote apart: `6e-17`
/// where it means 0, as CAD exporters do.
const ROUNDED_TETRAHEDRON: &str = "solid t
facet normal 0 0 0
outer loop
vertex 0 0 0
vertex 0 1 0
vertex 1 0 0
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 6e-17 0 0
vertex 1 0 0
vertex 0 0 1
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 0 6e-17 0
vertex 0 0 1
vertex 0 1 0
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 1 0 0
vertex 0 1 0
vertex 0 0 1
endloop
endfacet
endsolid t
";

#[test]
fn info_welds_corners_an_exporter_wrote_apart_and_says_how_many() {
    let dir = temp_dir("weld");
    let path = dir.join("t.stl");
    std::fs::write(&path, ROUNDED_TETRAHEDRON).unwrap();
    let file = path.to_str().unwrap();
    let out = necklace(&["info", file]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("welded 2 corners"), "{text}");
    assert!(
        text.contains("watertight yes") && text.contains("genus [0]"),
        "{text}"
    );
    let out = necklace(&["info", file, "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["welded_vertices"], 2);
    assert_eq!(json["watertight"], true);
    // Turned off, the cracks stay.
    let out = necklace(&["info", file, "--no-weld"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        !text.contains("welded") && text.contains("boundary edges"),
        "{text}"
    );
    let out = necklace(&["info", file, "--weld", "-1"]);
    assert_eq!(out.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_triangle_soup_is_refused_at_once_in_one_line() {
    let dir = temp_dir("soup");
    let path = dir.join("soup.obj");
    let mut obj = String::new();
    for i in 0..40 {
        let x = i as f64 * 0.37 % 1.0;
        let y = i as f64 * 0.61 % 1.0;
        let z = i as f64 * 0.83 % 1.0;
        obj.push_str(&format!(
            "v {x} {y} {z}\nv {} {z} {y}\nv {y} {x} {}\n",
            x + 0.3,
            z + 0.2
        ));
        obj.push_str(&format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3));
    }
    std::fs::write(&path, obj).unwrap();
    let out = necklace(&["loops", path.to_str().unwrap(), "-q"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("encloses no volume"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn unreadable_files_exit_2_with_one_line_on_stderr() {
    let dir = temp_dir("bad");
    let bad = dir.join("bad.off");
    std::fs::write(&bad, "OFF\n3 1 0\n0 0 0\n1 0 0\n").unwrap();
    let missing = dir.join("missing.obj");
    for path in [bad, missing] {
        let out = necklace(&["info", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(path.to_str().unwrap()), "{err}");
        assert!(out.stdout.is_empty());
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_shape_arguments_exit_2() {
    let out = necklace(&["shape", "torus", "--param", "r=2", "-o", "x.obj"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("must be < R"));
    let out = necklace(&["shape", "torus", "--param", "r", "-o", "x.obj"]);
    assert_eq!(out.status.code(), Some(2));
    let out = necklace(&["shape", "cube", "-o", "x.obj"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!PathBuf::from("x.obj").exists());
}

#[test]
fn shape_list_names_every_shape() {
    let out = necklace(&["shape", "--list"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in [
        "sphere",
        "torus",
        "varying-torus",
        "dumbbell",
        "chain",
        "eight",
        "pretzel",
    ] {
        assert!(text.contains(&format!("{name}:")), "{name} missing");
    }
}

#[test]
fn volume_json_has_the_documented_fields_and_writes_the_mesh() {
    let dir = temp_dir("volume");
    let surface = dir.join("torus.off");
    let out = necklace(&[
        "shape",
        "torus",
        "--param",
        "res=24",
        "-o",
        surface.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let vtu = dir.join("torus.vtu");
    let out = necklace(&[
        "volume",
        surface.to_str().unwrap(),
        "--exterior",
        "--h",
        "0.15",
        "-o",
        vtu.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "vertices",
        "tets",
        "interior_vertices",
        "surface_vertices",
        "outer_vertices",
        "euler_volume",
        "euler_boundary",
        "min_dihedral_deg",
        "max_dihedral_deg",
        "hausdorff_to_surface",
        "h",
        "seconds",
    ] {
        assert!(json.get(key).is_some(), "missing key {key}");
    }
    // The shell around a torus: χ = 1, boundary = sphere + torus, χ = 2.
    assert_eq!(json["euler_volume"], serde_json::json!(1));
    assert_eq!(json["euler_boundary"], serde_json::json!(2));
    assert!(json["outer_vertices"].as_u64().unwrap() > 0);
    assert!(std::fs::metadata(&vtu).unwrap().len() > 1000);

    let out = necklace(&["volume", surface.to_str().unwrap(), "--h", "-1"]);
    assert_eq!(out.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn critical_json_has_the_documented_fields_and_writes_the_points() {
    let dir = temp_dir("critical");
    let mesh = dir.join("dumbbell.obj");
    let points = dir.join("points.ply");
    let out = necklace(&["shape", "dumbbell", "-o", mesh.to_str().unwrap()]);
    assert!(out.status.success());
    let out = necklace(&[
        "critical",
        mesh.to_str().unwrap(),
        "--schedule",
        "paper",
        "--steps",
        "12",
        "--json",
        "-o",
        points.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let steps = json["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 3, "steps 10, 11, 12");
    for step in steps {
        for field in [
            "step",
            "maxima",
            "saddles1",
            "saddles2",
            "monkeys",
            "drained",
            "morse_sum",
            "morse_expected",
            "morse_ok",
        ] {
            assert!(!step[field].is_null(), "{field} in {step}");
        }
        assert_eq!(step["morse_ok"], true);
        assert_eq!(step["morse_sum"], -1, "genus 0 inside: g − 1");
    }
    let saddles = json["saddles"].as_array().unwrap();
    assert_eq!(saddles.len(), 1, "{saddles:?}");
    for field in ["position", "normal", "persistence", "hessian"] {
        assert!(!saddles[0][field].is_null(), "{field}");
    }
    assert_eq!(json["surface_morse_expected"], -1);
    // The point cloud is a PLY with the critical points (2 maxima and the saddle).
    let ply = std::fs::read(&points).unwrap();
    let header = String::from_utf8_lossy(&ply[..ply.len().min(400)]).to_string();
    assert!(
        header.starts_with("ply\n") && header.contains("element vertex 3\n"),
        "{header}"
    );
    assert!(header.contains("property double persistence"));

    let out = necklace(&["critical", mesh.to_str().unwrap(), "--steps", "5"]);
    assert_eq!(out.status.code(), Some(2), "steps below the initial 10");
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim().lines().count(),
        1
    );
}

#[test]
fn loops_json_has_the_documented_fields_and_writes_obj_and_json() {
    let dir = temp_dir("loops");
    let mesh = dir.join("dumbbell.obj");
    let out_dir = dir.join("out");
    let out = necklace(&["shape", "dumbbell", "-o", mesh.to_str().unwrap()]);
    assert!(out.status.success());
    let out = necklace(&[
        "loops",
        mesh.to_str().unwrap(),
        "--json",
        "-o",
        out_dir.to_str().unwrap(),
        "--png",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // stderr is not a terminal here: no progress bars, and nothing else to say.
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");
    for file in [
        "loops.obj",
        "loops.ply",
        "membranes.ply",
        "loops.json",
        "critical.ply",
        "view.png",
    ] {
        assert!(out_dir.join(file).is_file(), "{file}");
    }
    assert!(!out_dir.join("field.vtu").exists(), "only with --volume");
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["version"], necklace::output::JSON_VERSION);
    for field in [
        "loops", "dropped", "morse", "timings", "sides", "units", "input", "flipped",
    ] {
        assert!(!json[field].is_null(), "{field}");
    }
    let loops = json["loops"].as_array().unwrap();
    assert_eq!(loops.len(), 1, "{loops:?}");
    for field in [
        "kind",
        "points",
        "length",
        "initial_length",
        "plane_offset",
        "center",
        "normal",
        "radius",
        "saddle",
        "seed",
        "persistence",
        "duplicates",
        "surface_points",
        "tightening",
        "reason",
    ] {
        assert!(!loops[0][field].is_null(), "{field}");
    }
    assert_eq!(loops[0]["kind"], "handle");
    let morse = json["morse"].as_array().unwrap();
    assert_eq!(morse.len(), 2, "both sides by default");
    assert!(morse.iter().all(|m| m["ok"] == true));
    assert!(json["timings"]["total"]["total"].as_f64().unwrap() > 0.0);

    // loops.obj: one closed `l` polyline per loop; loops.json is what --json printed.
    let obj = std::fs::read_to_string(out_dir.join("loops.obj")).unwrap();
    let lines: Vec<&str> = obj.lines().filter(|l| l.starts_with("l ")).collect();
    assert_eq!(lines.len(), 1);
    let ids: Vec<&str> = lines[0].split_whitespace().skip(1).collect();
    assert_eq!(ids.first(), ids.last(), "closed");
    assert_eq!(ids.len(), loops[0]["points"].as_array().unwrap().len() + 1);
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("loops.json")).unwrap())
            .unwrap();
    assert_eq!(saved["loops"], json["loops"]);

    // Handles only: no tunnel side is run. Without parallel planes every loop comes
    // from the plane through its saddle.
    let out = necklace(&[
        "loops",
        mesh.to_str().unwrap(),
        "--handles",
        "--plane-offsets",
        "0",
        "--slide-steps",
        "0",
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["morse"].as_array().unwrap().len(), 1);
    let loops = json["loops"].as_array().unwrap();
    assert!(!loops.is_empty());
    assert!(loops.iter().all(|l| l["plane_offset"] == 0.0));
    let out = necklace(&["loops", mesh.to_str().unwrap(), "--slide-steps", "-1"]);
    assert_eq!(out.status.code(), Some(2));

    let out = necklace(&["loops", dir.join("missing.obj").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim().lines().count(),
        1
    );
}

#[test]
fn loops_simplifies_a_surface_above_the_flag_and_says_so() {
    let dir = temp_dir("simplify");
    let mesh = dir.join("dumbbell.obj");
    let out = necklace(&["shape", "dumbbell", "-o", mesh.to_str().unwrap()]);
    assert!(out.status.success());
    let run = |extra: &[&str]| {
        let mut args = vec!["loops", mesh.to_str().unwrap(), "--handles", "--json"];
        args.extend_from_slice(extra);
        let out = necklace(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (json, String::from_utf8_lossy(&out.stderr).to_string())
    };
    let (plain, _) = run(&[]);
    assert!(
        plain["simplified"].is_null(),
        "small surfaces are used as they are"
    );
    let (simplified, stderr) = run(&["--simplify-above", "1000", "--simplify-to", "2000"]);
    let report = &simplified["simplified"];
    assert_eq!(report["used"], true, "{stderr}");
    let [before, after] = [0, 1].map(|k| report["triangles"][k].as_u64().unwrap());
    assert!(before > 2000 && after <= before, "{report}");
    assert!(stderr.contains("simplified from"), "{stderr}");
    // The same neck, cut again and tightened on the input.
    let length = |j: &serde_json::Value| j["loops"][0]["length"].as_f64().unwrap();
    assert_eq!(simplified["loops"].as_array().unwrap().len(), 1);
    assert!((length(&simplified) - length(&plain)).abs() < 0.005 * length(&plain));
    let (off, _) = run(&["--simplify-above", "0"]);
    assert!(off["simplified"].is_null());
}

#[test]
fn render_draws_a_mesh_with_its_loops_and_rejects_bad_input() {
    let dir = temp_dir("render");
    let mesh = dir.join("torus.obj");
    let out_dir = dir.join("out");
    assert!(necklace(&[
        "shape",
        "varying-torus",
        "--param",
        "res=40",
        "-o",
        mesh.to_str().unwrap()
    ])
    .status
    .success());
    let out = necklace(&[
        "loops",
        mesh.to_str().unwrap(),
        "-o",
        out_dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = out_dir.join("loops.json");
    let png = dir.join("view.png");
    let out = necklace(&[
        "render",
        mesh.to_str().unwrap(),
        "--loops",
        json.to_str().unwrap(),
        "--critical",
        json.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        "400",
        "--views",
        "2",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    // IHDR: width and height, big-endian, at bytes 16..24.
    let width = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let height = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    // Two views of 200 pixels side by side, under the title band.
    assert_eq!(width, 400);
    assert!((210..=240).contains(&height), "{height}");

    for args in [
        vec![
            "render",
            mesh.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
            "--views",
            "7",
        ],
        vec![
            "render",
            mesh.to_str().unwrap(),
            "--loops",
            mesh.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ],
        vec![
            "render",
            dir.join("missing.obj").to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ],
    ] {
        let out = necklace(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}

#[test]
fn demo_runs_the_built_in_shapes_and_writes_pictures() {
    let dir = temp_dir("demo");
    let out = necklace(&["demo", "-o", dir.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    for shape in ["chain", "varying-torus", "pretzel"] {
        assert!(text.contains(&format!("{shape}: genus")), "{text}");
        for file in [
            "surface.obj",
            "loops.obj",
            "loops.ply",
            "loops.json",
            "critical.ply",
            "view.png",
        ] {
            assert!(dir.join(shape).join(file).is_file(), "{shape}/{file}");
        }
    }
    // The chain's two necks and the varying torus's handle and tunnel are found.
    assert!(
        text.contains("2 handles (expected 2), 0 tunnels (expected 0)"),
        "{text}"
    );
    assert!(
        text.contains("1 handles (expected 1), 1 tunnels (expected 1)"),
        "{text}"
    );
}

#[test]
fn bench_prints_a_row_per_model_and_mode_and_writes_the_csv_and_h_series() {
    let dir = temp_dir("bench");
    let models = dir.join("models");
    std::fs::create_dir_all(&models).unwrap();
    let sphere = models.join("ball.obj");
    assert!(necklace(&[
        "shape",
        "sphere",
        "--param",
        "res=20",
        "-o",
        sphere.to_str().unwrap()
    ])
    .status
    .success());
    std::fs::write(models.join("notes.txt"), "not a mesh").unwrap();
    let csv = dir.join("bench.csv");
    let out = necklace(&[
        "bench",
        models.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("| ball | handles |") && text.contains("| ball | tunnels |"),
        "{text}"
    );
    let table = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = table.lines().next().unwrap().split(',').collect();
    for column in [
        "preprocessing_s",
        "smoothing_s",
        "critical_points_s",
        "loop_computation_s",
        "total_s",
        "tets",
        "loops",
    ] {
        assert!(header.contains(&column), "{column}");
    }
    assert_eq!(table.lines().count(), 3, "{table}");
    let series = std::fs::read_to_string(dir.join("bench-scaling.csv")).unwrap();
    assert_eq!(series.lines().count(), 6, "{series}");
    // Finer h, more tets.
    let tets: Vec<u64> = series
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    assert!(tets.windows(2).all(|w| w[0] < w[1]), "{tets:?}");
    assert!(dir.join("bench-scaling.png").is_file());

    let out = necklace(&["bench", dir.join("nowhere").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
}

/// Run necklace and assert it succeeded (its stderr in the failure message).
fn succeeded(args: &[&str]) -> Output {
    let out = necklace(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Run necklace and assert it refused the input (status 2) saying `needle`.
fn refused_with(args: &[&str], needle: &str) {
    let out = necklace(args);
    assert_eq!(out.status.code(), Some(2), "{args:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(needle), "'{needle}' not in: {err}");
}

fn path(p: &std::path::Path) -> String {
    p.to_str().unwrap().to_string()
}

/// A coarse analytic dumbbell in `dir`, and a run of its handles in `dir/run` (with
/// the page when `html`).
fn dumbbell_run(dir: &std::path::Path, html: bool) -> (PathBuf, PathBuf) {
    let mesh = dir.join("dumbbell.off");
    succeeded(&["shape", "dumbbell", "--param", "res=40", "-o", &path(&mesh)]);
    let run = dir.join("run");
    let (m, r) = (path(&mesh), path(&run));
    let mut args = vec!["loops", m.as_str(), "--handles", "-q", "-o", r.as_str()];
    if html {
        args.push("--html");
    }
    succeeded(&args);
    (mesh, run)
}

#[test]
fn segment_cuts_a_dumbbell_in_two_halves_from_found_or_given_loops() {
    let dir = temp_dir("segment");
    let (mesh, run) = dumbbell_run(&dir, false);
    let (mesh, ply) = (path(&mesh), path(&dir.join("parts.ply")));
    // Loops found on the way, the table as JSON.
    let out = succeeded(&["segment", &mesh, "--handles", "-q", "-o", &ply, "--json"]);
    let table: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let segments = table["segments"].as_array().unwrap();
    assert_eq!(segments.len(), 2);
    let areas: Vec<f64> = segments
        .iter()
        .map(|s| s["area"].as_f64().unwrap())
        .collect();
    assert!((areas[0] - areas[1]).abs() < 0.01 * areas[0], "{areas:?}");
    for s in segments {
        assert_eq!(s["euler"], 1);
        assert_eq!(s["boundaries"], 1);
        assert_eq!(s["loops"], serde_json::json!([0]));
        assert!(s["volume"].as_f64().unwrap() > 0.0);
    }
    // The PLY's faces carry their segment.
    let bytes = std::fs::read(&ply).unwrap();
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(400)]).to_string();
    assert!(header.contains("property int segment"), "{header}");

    // From a run's loops.json, choosing its loop; a loop that is not there is refused.
    let json = path(&run.join("loops.json"));
    let out = succeeded(&[
        "segment", &mesh, "--loops", &json, "--loop", "0", "-o", &ply,
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("into 2 segment(s)"), "{text}");
    refused_with(
        &[
            "segment", &mesh, "--loops", &json, "--loop", "3", "-o", &ply,
        ],
        "--loop 3: there are 1 loops",
    );
    // The loops of another mesh name vertices or edges it does not have.
    let other = path(&dir.join("ball.off"));
    succeeded(&["shape", "sphere", "--param", "res=12", "-o", &other]);
    refused_with(
        &["segment", &other, "--loops", &json, "-o", &ply],
        "another mesh",
    );
}

#[test]
fn view_writes_the_page_of_a_run_and_needs_its_mesh() {
    let dir = temp_dir("view");
    let (_, run) = dumbbell_run(&dir, true);
    let page = std::fs::read_to_string(run.join("view.html")).unwrap();
    assert!(
        page.contains("dumbbell.off: "),
        "the page is titled with the mesh"
    );
    std::fs::remove_file(run.join("view.html")).unwrap();
    // Again from the run's folder: the mesh is the one loops.json names.
    let out = succeeded(&["view", &path(&run)]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("1 loops"));
    assert!(run.join("view.html").exists());
    // A mesh the loops are not on is refused.
    let ball = path(&dir.join("ball.off"));
    succeeded(&["shape", "sphere", "--param", "r=0.1", "-o", &ball]);
    refused_with(&["view", &path(&run), "--mesh", &ball], "another mesh");
}
