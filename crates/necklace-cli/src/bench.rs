//! `necklace bench DIR`: every mesh of a folder in both modes, one row per model and
//! mode with the stage times named as in the paper's Table 1 (preprocessing = volume
//! mesh + distance, smoothing, critical points, loop computation, total), the volume
//! size and the loop count; then a series over the lattice spacing h on one model (like
//! the paper's Fig. 12), as CSV and a PNG chart. Rows are printed as they finish.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;
use necklace::morse::{MorseOptions, Schedule};
use necklace::pipeline::{self, find_necks_with_progress, NeckOptions, NeckReport};
use necklace::render::chart::{chart, Chart, Series};
use necklace::volume::VolumeOptions;
use necklace::{io, SurfaceMesh};

use crate::Ui;

/// Divisors of the bounding-box diagonal for the h series (64 is the default h).
const H_SERIES: [f64; 5] = [24.0, 32.0, 48.0, 64.0, 96.0];

struct Row {
    model: String,
    mode: &'static str,
    surface_vertices: usize,
    tets: usize,
    unknowns: usize,
    /// Preprocessing, smoothing, critical points, loop computation, total.
    seconds: [f64; 5],
    loops: usize,
    dropped: usize,
    morse_ok: bool,
}

impl Row {
    fn new(model: &str, mode: &'static str, surface: &SurfaceMesh, report: &NeckReport) -> Row {
        let t = &report.timings.total;
        Row {
            model: model.to_string(),
            mode,
            surface_vertices: surface.positions.len(),
            tets: report.sides.iter().map(|s| s.volume.tets).sum(),
            unknowns: report.sides.iter().map(|s| s.unknowns).sum(),
            seconds: [
                t.volume_mesh + t.distance,
                t.smoothing,
                t.critical_points,
                t.loops,
                t.total,
            ],
            loops: report.loops.len(),
            dropped: report.dropped.len(),
            morse_ok: report.morse.iter().all(|m| m.ok),
        }
    }

    /// The row's cells, seconds with `digits` decimals.
    fn cells(&self, digits: usize) -> Vec<String> {
        let mut cells = vec![
            self.model.clone(),
            self.mode.to_string(),
            self.surface_vertices.to_string(),
            self.tets.to_string(),
            self.unknowns.to_string(),
        ];
        cells.extend(self.seconds.iter().map(|s| format!("{s:.digits$}")));
        cells.extend([
            self.loops.to_string(),
            self.dropped.to_string(),
            if self.morse_ok { "ok" } else { "FAILED" }.to_string(),
        ]);
        cells
    }

    fn markdown(&self) -> String {
        format!("| {} |", self.cells(3).join(" | "))
    }

    fn csv(&self) -> String {
        self.cells(4).join(",")
    }
}

const HEADER: &str = "| model | mode | surface vertices | tets | unknowns | preprocessing s | smoothing s | critical points s | loop computation s | total s | loops | dropped | Morse |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|";
const CSV_HEADER: &str = "model,mode,surface_vertices,tets,unknowns,preprocessing_s,smoothing_s,critical_points_s,loop_computation_s,total_s,loops,dropped,morse";

fn print_now(line: &str) {
    let mut stdout = std::io::stdout().lock();
    let _ = writeln!(stdout, "{line}");
    let _ = stdout.flush();
}

fn model_name(path: &Path) -> String {
    path.file_stem()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned())
}

fn run_one(
    surface: &SurfaceMesh,
    handles: bool,
    h: Option<f64>,
    schedule: Schedule,
    ui: &Ui,
) -> Result<NeckReport> {
    let options = NeckOptions {
        morse: MorseOptions {
            schedule,
            ..MorseOptions::default()
        },
        handles,
        tunnels: !handles,
        volume: VolumeOptions {
            h,
            ..VolumeOptions::default()
        },
        ..NeckOptions::default()
    };
    Ok(find_necks_with_progress(surface, &options, &ui.bars)?)
}

pub fn run(
    dir: &Path,
    csv: Option<&Path>,
    scaling: Option<Option<String>>,
    schedule: Schedule,
    ui: &Ui,
) -> Result<String> {
    if let Some(path) = csv {
        necklace::file::check_output_file(path)?;
    }
    let files = io::mesh_files(dir)?;
    if files.is_empty() {
        return Err(necklace::Error::invalid_argument(format!(
            "no mesh files in {}",
            dir.display()
        ))
        .into());
    }
    print_now(&format!(
        "necklace bench: {} models, {} threads, default settings (h = diagonal / 64), {}",
        files.len(),
        available_threads(),
        match schedule {
            Schedule::ScaleSpace => "scale space (32 levels)",
            Schedule::Paper => "the paper's schedule (20 steps)",
        }
    ));
    print_now(HEADER);
    let mut csv_text = format!("{CSV_HEADER}\n");
    let mut slowest = (0.0f64, String::new());
    for file in &files {
        let name = model_name(file);
        let surface = match io::read_mesh(file) {
            Ok(mesh) => match pipeline::prepare_input(mesh) {
                Ok(prepared) => prepared.mesh,
                Err(e) => {
                    print_now(&format!("| {name} | – | error: {e} |"));
                    continue;
                }
            },
            Err(e) => {
                print_now(&format!("| {name} | – | error: {e} |"));
                continue;
            }
        };
        for (mode, handles) in [("handles", true), ("tunnels", false)] {
            match run_one(&surface, handles, None, schedule, ui) {
                Ok(report) => {
                    let row = Row::new(&name, mode, &surface, &report);
                    if row.seconds[4] > slowest.0 {
                        slowest = (row.seconds[4], format!("{name} {mode}"));
                    }
                    print_now(&row.markdown());
                    let _ = writeln!(csv_text, "{}", row.csv());
                }
                Err(e) => print_now(&format!("| {name} | {mode} | error: {e:#} |")),
            }
        }
    }
    let mut out = format!("slowest: {} ({:.2} s)\n", slowest.1, slowest.0);
    if let Some(path) = csv {
        necklace::file::write_atomic(path, csv_text.as_bytes())?;
        let _ = writeln!(out, "table -> {}", path.display());
    }
    if let Some(model) = scaling {
        out += &h_series(&files, model.as_deref(), csv, schedule, ui)?;
    }
    Ok(out)
}

fn available_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The h series on one model (inside), written as CSV and PNG.
fn h_series(
    files: &[PathBuf],
    model: Option<&str>,
    csv: Option<&Path>,
    schedule: Schedule,
    ui: &Ui,
) -> Result<String> {
    let wanted = model.unwrap_or("bunny");
    let file = files
        .iter()
        .find(|f| model_name(f).contains(wanted))
        .or(if model.is_none() { files.first() } else { None })
        .ok_or_else(|| {
            necklace::Error::invalid_argument(format!(
                "no model named like '{wanted}' for the h series (--scaling)"
            ))
        })?;
    let name = model_name(file);
    let surface = pipeline::prepare_input(io::read_mesh(file)?)?.mesh;
    let diagonal = surface.bbox_diagonal();
    print_now(&format!("\nh series on {name} (handles):"));
    print_now("| h = diagonal / k | tets | unknowns | preprocessing s | smoothing s | critical points s | loop computation s | total s | loops |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut text = String::from("k,h,tets,unknowns,preprocessing_s,smoothing_s,critical_points_s,loop_computation_s,total_s,loops\n");
    let mut series: Vec<Series> = [
        "preprocessing",
        "smoothing",
        "critical points",
        "loop computation",
        "total",
    ]
    .iter()
    .zip([
        [230, 159, 0],
        [0, 114, 178],
        [0, 158, 115],
        [204, 121, 167],
        [40, 40, 40],
    ])
    .map(|(n, color)| Series {
        name: n.to_string(),
        color,
        points: Vec::new(),
    })
    .collect();
    for k in H_SERIES {
        let report = run_one(&surface, true, Some(diagonal / k), schedule, ui)?;
        let row = Row::new(&name, "handles", &surface, &report);
        let s = row.seconds;
        print_now(&format!(
            "| {k} | {} | {} | {:.2} | {:.2} | {:.2} | {:.3} | {:.2} | {} |",
            row.tets, row.unknowns, s[0], s[1], s[2], s[3], s[4], row.loops
        ));
        let _ = writeln!(
            text,
            "{k},{:.6e},{},{},{:.4},{:.4},{:.4},{:.4},{:.4},{}",
            diagonal / k,
            row.tets,
            row.unknowns,
            s[0],
            s[1],
            s[2],
            s[3],
            s[4],
            row.loops
        );
        for (series, seconds) in series.iter_mut().zip(s) {
            series.points.push([row.tets as f64, seconds]);
        }
    }
    let stem = match csv {
        Some(path) => {
            let stem = path
                .file_stem()
                .map_or("bench".into(), |s| s.to_string_lossy().into_owned());
            path.with_file_name(format!("{stem}-scaling"))
        }
        None => PathBuf::from("necklace-bench-scaling"),
    };
    let csv_path = stem.with_extension("csv");
    let png_path = stem.with_extension("png");
    necklace::file::write_atomic(&csv_path, text.as_bytes())?;
    let figure = Chart {
        title: format!("{name}: seconds per stage against volume size"),
        x_label: "tetrahedra".into(),
        y_label: "seconds".into(),
        series,
    };
    chart(&figure, 1000, 650)?.write_png(&png_path)?;
    Ok(format!(
        "h series -> {}, {}\n",
        csv_path.display(),
        png_path.display()
    ))
}
