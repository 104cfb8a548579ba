//! `necklace batch`: rows against single runs, failures as rows, kill and resume, the
//! same rows whatever `--jobs` is.

use std::collections::BTreeMap;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::Value;

use super::{loops_of, necklace};

const REALWORLD: &str = "../../../shared/data/realworld";

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("necklace-batch-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Small analytic shapes (about a second each): a torus, a dumbbell, a sphere, an
/// eight.
fn shapes(dir: &Path) -> Vec<PathBuf> {
    [
        ("torus", "res=16"),
        ("dumbbell", "res=24"),
        ("sphere", "res=8"),
        ("eight", "res=24"),
    ]
    .iter()
    .map(|(name, param)| {
        let path = dir.join(format!("{name}.obj"));
        let out = necklace(&["shape", name, "--param", param, "-o", s(&path)]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        path
    })
    .collect()
}

fn rows(file: &Path) -> Vec<Value> {
    std::fs::read_to_string(file)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// A row without what the clock and the memory say (they differ from run to run).
fn result_fields(row: &Value) -> Value {
    let mut row = row.clone();
    for key in ["seconds", "timings", "peak_memory"] {
        row.as_object_mut().unwrap().remove(key);
    }
    row
}

/// `necklace batch ARGS` with a test-only trigger set (`variable` = `value`).
fn batch_with(args: &[&str], variable: &str, value: &str) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_necklace"))
        .arg("batch")
        .args(args)
        .env(variable, value)
        .output()
        .unwrap()
}

fn batch(args: &[&str]) -> String {
    let out = necklace(&[&["batch", "-q"], args].concat());
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn batch_rows_are_the_single_runs_loops_whatever_the_jobs() {
    let dir = temp_dir("rows");
    let meshes = shapes(&dir);
    let paths: Vec<&str> = meshes[..3].iter().map(|p| s(p)).collect();
    let one = dir.join("one.jsonl");
    let two = dir.join("two.jsonl");
    batch(&[&paths[..], &["-o", s(&one), "--jobs", "1"]].concat());
    let saved = dir.join("saved");
    batch(
        &[
            &paths[..],
            &["-o", s(&two), "--jobs", "2", "--save-runs", s(&saved)],
        ]
        .concat(),
    );
    for name in ["torus.obj", "dumbbell.obj", "sphere.obj"] {
        assert!(saved.join(name).join("loops.json").exists(), "{name}");
    }
    let (one, two) = (rows(&one), rows(&two));
    assert_eq!(one.len(), 3);
    assert_eq!(
        one.iter().map(result_fields).collect::<Vec<_>>(),
        two.iter().map(result_fields).collect::<Vec<_>>(),
        "the same rows with 1 and 2 jobs"
    );
    for row in &one {
        assert_eq!(row["status"], "ok", "{row}");
        let out = necklace(&["loops", row["path"].as_str().unwrap(), "--json", "-q"]);
        assert!(out.status.success());
        let single: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(loops_of(row), loops_of(&single), "{}", row["path"]);
        let handles = single["loops"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|l| l["kind"] == "handle")
            .count();
        assert_eq!(row["handles"].as_u64(), Some(handles as u64));
        assert_eq!(row["sha256"].as_str().unwrap().len(), 64);
        assert_eq!(row["options_hash"], one[0]["options_hash"]);
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn failures_are_rows_and_the_other_meshes_finish() {
    let dir = temp_dir("failures");
    let meshes = shapes(&dir);
    let garbage = dir.join("garbage.stl");
    std::fs::write(&garbage, b"solid x\nfacet normal oops\n").unwrap();
    let crash = dir.join("crash-me.obj");
    std::fs::copy(&meshes[0], &crash).unwrap();
    let soup = format!("{REALWORLD}/tm_soup.stl");
    let slow = format!("{REALWORLD}/ps_mk3_bed.stl");
    let runs = dir.join("runs.jsonl");
    let args = [
        "-q",
        "-o",
        s(&runs),
        "--jobs",
        "2",
        "--timeout",
        "10",
        s(&garbage),
        &soup,
        &slow,
        s(&crash),
        s(&meshes[0]),
        s(&meshes[1]),
    ];
    let out = batch_with(&args, necklace::batch::CRASH_VARIABLE, "crash-me");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let status: BTreeMap<String, (String, String)> = rows(&runs)
        .iter()
        .map(|r| {
            let name = Path::new(r["path"].as_str().unwrap())
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned();
            let message = r["message"].as_str().unwrap_or("").to_string();
            (name, (r["status"].as_str().unwrap().to_string(), message))
        })
        .collect();
    assert_eq!(status.len(), 6, "{status:?}");
    assert_eq!(status["garbage.stl"].0, "error", "{status:?}");
    assert_eq!(status["tm_soup.stl"].0, "error");
    assert!(
        status["tm_soup.stl"].1.contains("triangle soup"),
        "{status:?}"
    );
    assert_eq!(status["ps_mk3_bed.stl"].0, "timeout");
    assert!(status["ps_mk3_bed.stl"].1.contains("10 s"), "{status:?}");
    assert_eq!(status["crash-me.obj"].0, "crashed");
    assert!(status["crash-me.obj"].1.contains("signal 6"), "{status:?}");
    assert_eq!(status["torus.obj"].0, "ok");
    assert_eq!(status["dumbbell.obj"].0, "ok");
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(
        summary.contains("2 ok, 2 error, 1 timeout, 0 memory, 1 crashed"),
        "{summary}"
    );

    // Over the memory limit: a worker that keeps taking memory (a test-only trigger)
    // is stopped at the limit while the torus, well under it, runs.
    let hog = dir.join("hog.obj");
    std::fs::copy(&meshes[0], &hog).unwrap();
    let runs = dir.join("memory.jsonl");
    let args = [
        "-q",
        "-o",
        s(&runs),
        "--max-memory",
        "1G",
        s(&hog),
        s(&meshes[1]),
    ];
    let out = batch_with(&args, necklace::batch::HOG_VARIABLE, "hog");
    assert_eq!(out.status.code(), Some(0));
    let found = rows(&runs);
    assert_eq!(found[0]["status"], "ok", "{}", found[0]);
    assert_eq!(found[1]["status"], "memory", "{}", found[1]);
    assert!(found[1]["message"]
        .as_str()
        .unwrap()
        .contains("memory limit of 1000000000 bytes"));
    assert!(found[1]["peak_memory"].as_u64().unwrap() > 1_000_000_000);

    // A mesh whose volume mesh is estimated over the limit is refused by the estimate,
    // within seconds, and says which flag lifts it.
    let runs = dir.join("estimate.jsonl");
    batch(&[
        "-o",
        s(&runs),
        "--max-memory",
        "30M",
        &format!("{REALWORLD}/../meshes/bunny.off"),
    ]);
    let found = rows(&runs);
    assert_eq!(found[0]["status"], "memory", "{}", found[0]);
    assert!(found[0]["message"]
        .as_str()
        .unwrap()
        .contains("--max-memory"));
    let _ = std::fs::remove_dir_all(dir);
}

/// Start a batch in its own process group, wait for `rows` complete rows in `runs`,
/// then send `signal` to the group (as a terminal's Ctrl-C or a `kill -9` of the job).
fn interrupt(args: &[&str], runs: &Path, rows: usize, signal: &str) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_necklace"))
        .args(args)
        .process_group(0)
        .spawn()
        .unwrap();
    let started = Instant::now();
    loop {
        let done = std::fs::read_to_string(runs)
            .map(|t| t.matches('\n').count())
            .unwrap_or(0);
        if done >= rows || started.elapsed() > Duration::from_secs(120) {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let group = format!("-{}", child.id());
    let killed = Command::new("kill")
        .args([signal, "--", &group])
        .status()
        .unwrap();
    assert!(killed.success());
    let _ = child.wait();
}

#[test]
fn a_killed_batch_resumes_with_only_the_missing_meshes_and_one_row_each() {
    let dir = temp_dir("resume");
    let meshes = shapes(&dir);
    let paths: Vec<&str> = meshes.iter().map(|p| s(p)).collect();
    for signal in ["-KILL", "-INT"] {
        let runs = dir.join(format!("runs{signal}.jsonl"));
        let args = [&["batch", "-q", "--jobs", "1", "-o", s(&runs)], &paths[..]].concat();
        interrupt(&args, &runs, 1, signal);
        let before = rows(&runs).len();
        assert!((1..4).contains(&before), "{signal}: {before} rows");

        // A line cut short by the kill is repaired: simulate one.
        let mut text = std::fs::read_to_string(&runs).unwrap();
        text.push_str("{\"path\":\"half a li");
        std::fs::write(&runs, text).unwrap();

        let summary = batch(&[&paths[..], &["-o", s(&runs), "--jobs", "1"]].concat());
        let ran = 4 - before;
        assert!(
            summary.starts_with(&format!("4 meshes: {ran} run, {before} already in")),
            "{signal}: {summary}"
        );
        let rows = rows(&runs);
        let mut seen: Vec<&str> = rows.iter().map(|r| r["path"].as_str().unwrap()).collect();
        seen.sort_unstable();
        let mut expected = paths.clone();
        expected.sort_unstable();
        assert_eq!(seen, expected, "{signal}: one row per mesh");
        assert!(rows.iter().all(|r| r["status"] == "ok"));

        // Finished: a rerun runs nothing.
        let summary = batch(&[&paths[..], &["-o", s(&runs)]].concat());
        assert!(
            summary.starts_with("4 meshes: 0 run, 4 already in"),
            "{summary}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn retry_failed_runs_only_the_failed_meshes_again() {
    let dir = temp_dir("retry");
    let meshes = shapes(&dir);
    let runs = dir.join("runs.jsonl");
    let crash = dir.join("crash-again.obj");
    std::fs::copy(&meshes[2], &crash).unwrap();
    let args = ["-q", "-o", s(&runs), s(&crash), s(&meshes[2])];
    let out = batch_with(&args, necklace::batch::CRASH_VARIABLE, "crash-again");
    assert_eq!(out.status.code(), Some(0));
    let summary = batch(&["-o", s(&runs), s(&crash), s(&meshes[2])]);
    assert!(
        summary.starts_with("2 meshes: 0 run, 2 already"),
        "{summary}"
    );
    let summary = batch(&["-o", s(&runs), "--retry-failed", s(&crash), s(&meshes[2])]);
    assert!(
        summary.starts_with("2 meshes: 1 run, 1 already"),
        "{summary}"
    );
    let rows = rows(&runs);
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r["status"] == "ok"), "{rows:?}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn batch_refuses_bad_arguments_with_status_2() {
    let dir = temp_dir("bad");
    let runs = dir.join("runs.jsonl");
    for args in [
        vec!["batch", "/no/such/mesh.obj", "-o", s(&runs)],
        vec!["batch", REALWORLD, "-o", s(&runs), "--jobs", "0"],
        vec!["batch", REALWORLD, "-o", s(&runs), "--timeout", "-1"],
    ] {
        let out = necklace(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn repair_writes_a_genus_0_surface_and_refuses_bad_targets_in_one_line() {
    let dir = temp_dir("repair");
    let meshes = shapes(&dir);
    let out = dir.join("repaired.obj");
    let pictures = dir.join("pictures");
    let run = necklace(&[
        "repair",
        s(&meshes[0]),
        "-o",
        s(&out),
        "--png",
        s(&pictures),
        "--json",
        "-q",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(report["genus"], serde_json::json!([1, 0]));
    // Before and after side by side, each half 900 pixels wide.
    let picture = necklace::render::Image::read_png(pictures.join("repair.png")).unwrap();
    assert_eq!(picture.width, 1800);
    let info = necklace(&["info", s(&out), "--json"]);
    let info: Value = serde_json::from_slice(&info.stdout).unwrap();
    assert_eq!(info["genus"], serde_json::json!([0]));
    assert_eq!(info["watertight"], serde_json::json!(true));
    // An open surface: the first mesh less one triangle.
    let mut open = necklace::io::read_mesh(&meshes[0]).unwrap();
    open.triangles.pop();
    let open_mesh = dir.join("open.obj");
    necklace::io::write_mesh(&open_mesh, &open).unwrap();
    let bad_output = dir.join("repaired.txt");
    for args in [
        vec![s(&meshes[0]), "-o", s(&out), "--genus", "3"],
        vec![
            s(&meshes[0]),
            "-o",
            s(&out),
            "--genus",
            "0",
            "--max-length",
            "1",
        ],
        vec![s(&meshes[0]), "-o", s(&out), "--max-length", "-1"],
        vec![s(&meshes[0]), "-o", s(&bad_output)],
        vec![s(&open_mesh), "-o", s(&out)],
    ] {
        let run = necklace(&[&["repair", "-q"], &args[..]].concat());
        assert_eq!(run.status.code(), Some(2), "{args:?}");
        assert_eq!(
            String::from_utf8_lossy(&run.stderr).lines().count(),
            1,
            "{args:?}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}
