//! Careless and hostile input, end to end: every case either gives the right answer
//! (with a note saying what was repaired) or exits with status 2 and one line on
//! stderr that names the problem. Inputs are built here, in a temporary folder.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

use super::{loops_of, necklace};

fn temp_dir(name: &str) -> PathBuf {
    super::temp_dir(&format!("hostile-{name}"))
}

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Exit status 2 and exactly one line on stderr, starting `necklace: `, containing
/// every needle and no control character.
#[track_caller]
fn refused(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert_eq!(err.lines().count(), 1, "not one line: {err:?}");
    assert!(err.starts_with("necklace: "), "{err}");
    assert!(
        !err.trim_end().chars().any(char::is_control),
        "control characters in {err:?}"
    );
    for needle in needles {
        assert!(err.contains(needle), "'{needle}' not in: {err}");
    }
}

#[track_caller]
fn ok_json(out: &Output) -> Value {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

/// A mesh as OFF text.
fn off(positions: &[[f64; 3]], triangles: &[[usize; 3]]) -> String {
    let mut text = format!("OFF\n{} {} 0\n", positions.len(), triangles.len());
    for p in positions {
        text += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    for t in triangles {
        text += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    text
}

/// A mesh read back from OFF text written by `off` or `necklace shape`.
fn read_off(text: &str) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let mut lines = text.lines().skip(1);
    let counts: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let positions = (0..counts[0])
        .map(|_| {
            let v: Vec<f64> = lines
                .next()
                .unwrap()
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let triangles = (0..counts[1])
        .map(|_| {
            let v: Vec<usize> = lines
                .next()
                .unwrap()
                .split_whitespace()
                .skip(1)
                .map(|x| x.parse().unwrap())
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    (positions, triangles)
}

/// A torus from `necklace shape` (R = 1, r = 0.3), as positions and triangles.
fn torus(dir: &Path) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let path = dir.join("torus.off");
    let out = necklace(&["shape", "torus", "--param", "res=48", "-o", s(&path)]);
    assert!(out.status.success());
    read_off(&std::fs::read_to_string(path).unwrap())
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn count(loops: &[(String, f64)], kind: &str) -> usize {
    loops.iter().filter(|l| l.0 == kind).count()
}

const KITTEN: &str = "../../../shared/data/meshes/kitten.off";

#[test]
fn a_far_unused_vertex_changes_nothing() {
    let dir = temp_dir("far");
    let kitten = std::fs::read_to_string(KITTEN).unwrap();
    let (mut positions, triangles) = read_off(&kitten);
    let plain = ok_json(&necklace(&["loops", KITTEN, "-q", "--json"]));
    positions.push([100.0, 100.0, 100.0]);
    let far = write(&dir, "kitten-far.off", off(&positions, &triangles));
    let out = necklace(&["loops", s(&far), "-q", "--json"]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    let json = ok_json(&out);
    assert_eq!(loops_of(&json), loops_of(&plain));
    assert!(
        stderr.contains("removed 1 vertices that no face uses"),
        "{stderr}"
    );

    // A torus with far unused vertices: one volume component, one handle, one tunnel.
    let (mut positions, triangles) = torus(&dir);
    positions.extend([[50.0, 0.0, 0.0], [-50.0, 3.0, 0.0]]);
    let far = write(&dir, "torus-far.off", off(&positions, &triangles));
    let volume = ok_json(&necklace(&["volume", s(&far), "-q", "--json"]));
    assert_eq!(volume["components"], 1);
    let loops = loops_of(&ok_json(&necklace(&["loops", s(&far), "-q", "--json"])));
    assert_eq!((count(&loops, "handle"), count(&loops, "tunnel")), (1, 1));
}

#[test]
fn components_facing_the_wrong_way_are_turned_and_both_tori_kept() {
    let dir = temp_dir("two-tori");
    let (positions, triangles) = torus(&dir);
    let n = positions.len();
    let mut all = positions.clone();
    all.extend(positions.iter().map(|p| [p[0] + 4.0, p[1], p[2]]));
    let mut faces = triangles.clone();
    faces.extend(triangles.iter().map(|t| [t[0] + n, t[2] + n, t[1] + n]));
    let path = write(&dir, "two.off", off(&all, &faces));

    let info = ok_json(&necklace(&["info", s(&path), "--json"]));
    assert_eq!(info["inward_components"], 1);
    assert_eq!(info["outward"], false);
    let text = necklace(&["info", s(&path)]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("1 of 2 components face into"));

    let volume = ok_json(&necklace(&["volume", s(&path), "-q", "--json"]));
    assert_eq!(volume["components"], 2);
    let out = necklace(&["loops", s(&path), "-q", "--json"]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    let json = ok_json(&out);
    let loops = loops_of(&json);
    assert_eq!((count(&loops, "handle"), count(&loops, "tunnel")), (2, 2));
    assert_eq!(json["flipped"], true);
    assert!(stderr.contains("flipped 1 of 2 components"), "{stderr}");
}

#[test]
fn a_half_flipped_torus_and_an_inverted_one_give_the_torus_loops() {
    let dir = temp_dir("half");
    let (positions, triangles) = torus(&dir);
    let plain = write(&dir, "plain.off", off(&positions, &triangles));
    let reference = loops_of(&ok_json(&necklace(&["loops", s(&plain), "-q", "--json"])));
    assert_eq!(
        (count(&reference, "handle"), count(&reference, "tunnel")),
        (1, 1)
    );
    assert!(
        !ok_json(&necklace(&["loops", s(&plain), "-q", "--json"]))["flipped"]
            .as_bool()
            .unwrap()
    );

    let half: Vec<[usize; 3]> = triangles
        .iter()
        .map(|&t| {
            let x = (positions[t[0]][0] + positions[t[1]][0] + positions[t[2]][0]) / 3.0;
            if x > 0.0 {
                [t[0], t[2], t[1]]
            } else {
                t
            }
        })
        .collect();
    let inverted: Vec<[usize; 3]> = triangles.iter().map(|t| [t[0], t[2], t[1]]).collect();
    for (name, faces) in [("half.off", half), ("inverted.off", inverted)] {
        let path = write(&dir, name, off(&positions, &faces));
        let out = necklace(&["loops", s(&path), "-q", "--json"]);
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        let json = ok_json(&out);
        assert_eq!(json["flipped"], true, "{name}");
        let loops = loops_of(&json);
        assert_eq!(loops.len(), reference.len(), "{name}");
        for (a, b) in loops.iter().zip(&reference) {
            assert_eq!(a.0, b.0);
            assert!((a.1 - b.1).abs() < 1e-9 * b.1, "{name}: {a:?} vs {b:?}");
        }
        assert!(
            stderr.contains("turned") || stderr.contains("flipped"),
            "{name}: {stderr}"
        );
    }
}

#[test]
fn two_overlapping_balls_have_their_neck_loop_on_the_meshed_solid() {
    let dir = temp_dir("overlap");
    let sphere = dir.join("sphere.off");
    assert!(necklace(&["shape", "sphere", "-o", s(&sphere)])
        .status
        .success());
    let (positions, triangles) = read_off(&std::fs::read_to_string(&sphere).unwrap());
    let n = positions.len();
    let mut all = positions.clone();
    all.extend(positions.iter().map(|p| [p[0] + 1.8, p[1], p[2]]));
    let mut faces = triangles.clone();
    faces.extend(triangles.iter().map(|t| t.map(|v| v + n)));
    let path = write(&dir, "overlap.off", off(&all, &faces));

    let info = String::from_utf8_lossy(&necklace(&["info", s(&path)]).stdout).to_string();
    assert!(info.contains("crosses itself"), "{info}");
    // The balls (radius 1, centres 1.8 apart) meet in a circle of radius
    // sqrt(1 - 0.9²) = 0.436. The loop is tightened on the meshed solid, whose crease
    // along that circle has cells of h/4 by default (its topology is not predicted)
    // and of h/8 when the bound is lowered to the crossing curve's own cells.
    let expected = std::f64::consts::TAU * (1.0f64 - 0.81).sqrt();
    let mut stderr = String::new();
    for (bound, tolerance) in [("0.25", 0.05), ("0.125", 0.03)] {
        let out = necklace(&[
            "loops",
            s(&path),
            "-q",
            "--handles",
            "--json",
            "--unchecked-min-cell",
            bound,
        ]);
        stderr = String::from_utf8_lossy(&out.stderr).to_string();
        let loops = loops_of(&ok_json(&out));
        assert_eq!(count(&loops, "handle"), 1, "{loops:?}");
        assert!(
            (loops[0].1 / expected - 1.0).abs() < tolerance,
            "{bound}: {} vs {expected}",
            loops[0].1
        );
        assert_eq!(
            stderr.contains("unchecked_min_cell"),
            bound == "0.25",
            "{stderr}"
        );
    }
    assert!(stderr.contains("crosses itself"), "{stderr}");
    assert!(stderr.contains("volume mesh's boundary"), "{stderr}");
}

#[test]
fn a_byte_order_mark_and_old_mac_line_ends_read_as_the_same_tetrahedron() {
    let dir = temp_dir("bom");
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    let off_text = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    let cases = [
        ("bom.obj", format!("\u{feff}{obj}")),
        ("bom.off", format!("\u{feff}{off_text}")),
        ("cr.obj", obj.replace('\n', "\r")),
        ("cr.off", off_text.replace('\n', "\r")),
    ];
    for (name, text) in cases {
        let path = write(&dir, name, text);
        let json = ok_json(&necklace(&["info", s(&path), "--json"]));
        assert_eq!(json["vertices"], 4, "{name}");
        assert_eq!(json["faces"], 4, "{name}");
        assert_eq!(json["outward"], true, "{name}");
        assert_eq!(json["genus"], serde_json::json!([0]), "{name}");
    }
}

#[test]
fn nothing_to_mesh_is_an_error_not_an_empty_answer() {
    let dir = temp_dir("empty");
    let box_of = |x: f64, y: f64, z: f64| {
        let positions: Vec<[f64; 3]> = (0..8)
            .map(|i| {
                [
                    x * f64::from(i & 1),
                    y * f64::from((i >> 1) & 1),
                    z * f64::from((i >> 2) & 1),
                ]
            })
            .collect();
        let faces = [
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6],
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3],
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5],
        ];
        off(&positions, &faces)
    };
    // A plate 1e-7 thick: no cell fits.
    let plate = write(&dir, "plate.off", box_of(1.0, 1.0, 1e-7));
    refused(&necklace(&["loops", s(&plate), "-q"]), &["thinner than"]);
    // A lattice spacing larger than the shape.
    let cube = write(&dir, "cube.off", box_of(1.0, 1.0, 1.0));
    refused(
        &necklace(&["volume", s(&cube), "-q", "--h", "1e300"]),
        &["h = 1.000e300", "diagonal"],
    );
    // All vertices at one point, a doubled sheet: no volume at all.
    let point = write(&dir, "point.off", box_of(0.0, 0.0, 0.0));
    refused(&necklace(&["loops", s(&point), "-q"]), &["one point"]);
    let info = String::from_utf8_lossy(&necklace(&["info", s(&point)]).stdout).to_string();
    assert!(info.contains("all vertices are at one point"), "{info}");
    assert!(!info.contains("flip"), "{info}");
    let sheet = write(
        &dir,
        "sheet.off",
        off(
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[[0, 1, 2], [0, 2, 1]],
        ),
    );
    refused(&necklace(&["volume", s(&sheet), "-q"]), &["flat"]);
}

#[test]
fn a_volume_mesh_that_loses_volume_says_so() {
    // 400 small separate tetrahedra, far apart for the default lattice spacing.
    let dir = temp_dir("tets");
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            let b = positions.len();
            let (x, y, e) = (f64::from(i), f64::from(j), 0.02);
            positions.extend([[x, y, 0.0], [x + e, y, 0.0], [x, y + e, 0.0], [x, y, e]]);
            faces.extend([
                [b, b + 2, b + 1],
                [b, b + 1, b + 3],
                [b, b + 3, b + 2],
                [b + 1, b + 2, b + 3],
            ]);
        }
    }
    let path = write(&dir, "tets.off", off(&positions, &faces));
    let out = necklace(&["volume", s(&path), "-q", "--json"]);
    let json = ok_json(&out);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    let ratio = json["volume"].as_f64().unwrap() / (400.0 * 0.02f64.powi(3) / 6.0);
    if (ratio - 1.0).abs() > 0.05 {
        assert!(
            stderr.contains("of the volume the surface encloses"),
            "{stderr}"
        );
    }
    if json["topology"]["matches"] != true {
        assert!(stderr.contains("topology"), "{stderr}");
    }
}

#[test]
fn huge_coordinates_are_named_not_taken_for_a_flipped_mesh() {
    let dir = temp_dir("huge");
    let (positions, triangles) = torus(&dir);
    let huge: Vec<[f64; 3]> = positions.iter().map(|p| p.map(|c| c * 1e300)).collect();
    let path = write(&dir, "huge.off", off(&huge, &triangles));
    let info = String::from_utf8_lossy(&necklace(&["info", s(&path)]).stdout).to_string();
    assert!(info.contains("too large"), "{info}");
    assert!(
        !info.contains("flip") && !info.contains("zero-area"),
        "{info}"
    );
    assert!(info.lines().all(|l| l.len() < 200), "{info}");
    refused(&necklace(&["volume", s(&path), "-q"]), &["too large"]);
    refused(&necklace(&["loops", s(&path), "-q"]), &["too large"]);
}

#[test]
fn bytes_from_the_file_never_reach_the_terminal_raw() {
    let dir = temp_dir("escape");
    let clear = write(&dir, "clear.off", "OFF\n4 4 0\n0 0 0\n1 0 \x1b[2J 0\n");
    refused(&necklace(&["info", s(&clear)]), &["\\x1b[2J"]);
    let title = write(
        &dir,
        "title.ply",
        "ply\nformat \x1b]0;owned\x07 1.0\nelement vertex 0\nend_header\n",
    );
    refused(&necklace(&["info", s(&title)]), &["\\x1b]0;owned\\x07"]);
    let bom = write(&dir, "bom.off", "\u{feff}OFX\n");
    let out = necklace(&["info", s(&bom)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!String::from_utf8_lossy(&out.stderr).contains('\u{feff}'));
}

#[test]
fn argument_errors_are_one_line_and_negative_numbers_are_values() {
    let dir = temp_dir("args");
    let cube = write(
        &dir,
        "t.off",
        "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
    );
    refused(
        &necklace(&["volume", s(&cube), "--h", "-1"]),
        &["h = -1 must be positive"],
    );
    refused(
        &necklace(&["loops", s(&cube), "--schedule", "paper", "--tau", "-1"]),
        &["tau = -1 must be positive"],
    );
    refused(
        &necklace(&["loops", s(&cube), "--steps", "-1"]),
        &["'-1'", "--steps"],
    );
    refused(&necklace(&["loops", s(&cube), "--bogus"]), &["--bogus"]);
    refused(&necklace(&["lops"]), &["loops"]);
    refused(&necklace(&[]), &["command"]);
    let out = necklace(&["volume", s(&cube), "-q", "--h", "1e-300"]);
    refused(&out, &["1.000e-300"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(err.len() < 200, "{err}");
    assert!(necklace(&["--help"]).status.success());
}

#[test]
fn budgets_refuse_before_the_work() {
    let dir = temp_dir("budget");
    let tet = write(
        &dir,
        "t.off",
        "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
    );
    refused(
        &necklace(&[
            "loops",
            s(&tet),
            "-q",
            "--schedule",
            "paper",
            "--steps",
            "100000",
        ]),
        &["100000 heat steps", "--max-steps"],
    );
    refused(
        &necklace(&["critical", s(&tet), "-q", "--levels", "5000"]),
        &["5000 heat steps", "--max-steps"],
    );
    refused(
        &necklace(&["volume", KITTEN, "-q", "--h", "0.0001"]),
        &["budget", "--max-memory"],
    );
    // Only regular files are read.
    refused(&necklace(&["info", "/dev/zero"]), &["not a regular file"]);
    refused(&necklace(&["info", s(&dir)]), &["a folder"]);
}

#[cfg(unix)]
#[test]
fn a_pipe_is_refused_without_blocking() {
    let dir = temp_dir("fifo");
    let fifo = dir.join("mesh.obj");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        refused(&necklace(&["info", s(&fifo)]), &["not a regular file"]);
    }
}

#[test]
fn a_huge_polygon_is_split_in_linear_time_into_a_valid_solid() {
    // A prism whose caps are 20,000-gons: the caps' triangles must not all meet at
    // one corner (a fan), which made the run quadratic.
    let dir = temp_dir("polygon");
    let n = 20_000;
    let mut text = String::new();
    for z in [0.0, 1.0] {
        for i in 0..n {
            let a = std::f64::consts::TAU * f64::from(i) / f64::from(n);
            text += &format!("v {} {} {z}\n", a.cos(), a.sin());
        }
    }
    text += "f";
    for i in (1..=n).rev() {
        text += &format!(" {i}");
    }
    text += "\nf";
    for i in 1..=n {
        text += &format!(" {}", n + i);
    }
    text += "\n";
    for i in 1..=n {
        let j = i % n + 1;
        text += &format!("f {i} {j} {} {}\n", n + j, n + i);
    }
    let path = write(&dir, "prism.obj", text);
    let json = ok_json(&necklace(&["info", s(&path), "--json"]));
    assert_eq!(json["faces"], 4 * n - 4);
    assert_eq!(json["genus"], serde_json::json!([0]));
    assert_eq!(json["outward"], true);
    let volume = ok_json(&necklace(&["volume", s(&path), "-q", "--json"]));
    let v = volume["volume"].as_f64().unwrap();
    assert!((v / std::f64::consts::PI - 1.0).abs() < 0.01, "{v}");
}

#[test]
fn outputs_are_checked_first_and_failed_writes_leave_nothing() {
    let dir = temp_dir("outputs");
    let tet = write(
        &dir,
        "t.off",
        "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
    );
    let missing = dir.join("no/such/folder/x.vtu");
    refused(
        &necklace(&["volume", KITTEN, "-q", "-o", s(&missing)]),
        &["does not exist"],
    );
    refused(
        &necklace(&["volume", s(&tet), "-q", "-o", s(&dir.join("x.xyz"))]),
        &["format"],
    );
    refused(
        &necklace(&["critical", s(&tet), "-q", "-o", s(&dir.join("c.obj"))]),
        &["PLY"],
    );
    let blocked = write(&dir, "file", "not a folder");
    refused(
        &necklace(&["loops", KITTEN, "-q", "-o", s(&blocked.join("run"))]),
        &["cannot create the folder"],
    );
    refused(
        &necklace(&["bench", s(&dir), "--csv", s(&dir.join("no/t.csv"))]),
        &["does not exist"],
    );
    refused(
        &necklace(&["shape", "torus", "-o", s(&dir.join("t.stl"))]),
        &["STL"],
    );

    // A file the run cannot write (view.png is a folder): exit 2, no partial files.
    let run = dir.join("run");
    std::fs::create_dir_all(run.join("view.png")).unwrap();
    let out = necklace(&["loops", s(&tet), "-q", "--handles", "--png", "-o", s(&run)]);
    assert_eq!(out.status.code(), Some(2));
    for entry in std::fs::read_dir(&run).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().to_string();
        assert!(!name.ends_with(".tmp"), "left behind: {name}");
    }

    #[cfg(target_os = "linux")]
    {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full");
        if let Ok(full) = full {
            let out = Command::new(env!("CARGO_BIN_EXE_necklace"))
                .args(["info", s(&tet), "--json"])
                .stdout(full)
                .output()
                .unwrap();
            refused(&out, &["stdout"]);
        }
    }
}

#[test]
fn messages_point_at_the_real_problem() {
    let dir = temp_dir("messages");
    let ply = dir.join("sphere.ply");
    assert!(necklace(&["shape", "sphere", "-o", s(&ply)])
        .status
        .success());
    let named_obj = dir.join("sphere.obj");
    std::fs::copy(&ply, &named_obj).unwrap();
    refused(
        &necklace(&["info", s(&named_obj)]),
        &["content is PLY", ".ply"],
    );
}

#[test]
fn render_refuses_what_it_cannot_draw() {
    let dir = temp_dir("render");
    let mesh = dir.join("torus.off");
    assert!(necklace(&["shape", "torus", "-o", s(&mesh)])
        .status
        .success());
    let far = write(
        &dir,
        "far.json",
        r#"{"loops": [{"kind": "handle", "points": [[1e6, 0, 0], [1e6, 1, 0], [1e6, 0, 1]]}]}"#,
    );
    let empty = write(
        &dir,
        "empty.json",
        r#"{"loops": [{"kind": "handle", "points": []}]}"#,
    );
    // A loop floating a little above the torus (z = 1.2, the tube's radius is below
    // 0.5): within a diagonal of the box, but not on this surface.
    let above = write(
        &dir,
        "above.json",
        r#"{"loops": [{"kind": "handle", "points": [[0, 0, 1.2], [0.1, 0, 1.2], [0, 0.1, 1.2]]}]}"#,
    );
    let png = dir.join("x.png");
    refused(
        &necklace(&["render", s(&mesh), "--loops", s(&far), "-o", s(&png)]),
        &["outside the mesh"],
    );
    refused(
        &necklace(&["render", s(&mesh), "--loops", s(&above), "-o", s(&png)]),
        &["outside the mesh's bounding box", "another mesh"],
    );
    refused(
        &necklace(&["render", s(&mesh), "--loops", s(&empty), "-o", s(&png)]),
        &["0 points"],
    );
    refused(
        &necklace(&["render", s(&mesh), "-o", s(&dir.join("x.jpg"))]),
        &["PNG"],
    );
    assert!(!png.exists());
}
