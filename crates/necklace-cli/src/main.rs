//! `necklace`: the command-line tool. It parses flags, builds library options, calls the
//! library and prints; every algorithm lives in the `necklace` library crate.
//!
//! Exit status: 0 on success, 2 for bad input (unreadable or malformed file, bad
//! argument), 1 for any other failure. Errors are one line on stderr.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;
use flags::{Cli, Command};
use necklace::batch::BatchOptions;
use necklace::error::printable;
use necklace::file::{check_output_file, check_output_folder};
use necklace::morse::MorseOptions;
use necklace::output::OutputOptions;
use necklace::pipeline::{self, InputOptions};
use necklace::render::RenderOptions;
use necklace::shapes::Shape;
use necklace::volume::VolumeOptions;
use necklace::Side;
use necklace::{io, MeshReport};
use progress::Bars;

mod batch;
mod bench;
mod demo;
mod flags;
mod print;
mod progress;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => return print::argument_error(&err),
    };
    let ui = Ui {
        bars: Bars::new(!cli.quiet),
        verbose: cli.verbose,
    };
    // A panic is our bug: one line naming where, status 1 (never a backtrace dump).
    std::panic::set_hook(Box::new(|info| {
        let message = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        let place = info
            .location()
            .map_or(String::new(), |l| format!(" at {}:{}", l.file(), l.line()));
        eprintln!(
            "necklace: internal error{place}: {}; please report it",
            printable(&message)
        );
    }));
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(cli.command, &ui)));
    let Ok(outcome) = outcome else {
        return ExitCode::from(1);
    };
    match outcome {
        Ok(text) => print::stdout(&text),
        Err(err) => {
            eprintln!("necklace: {}", printable(&format!("{err:#}")));
            // Errors about the input, the arguments or the files named: status 2;
            // anything else is ours: 1.
            let input = err
                .downcast_ref::<necklace::Error>()
                .is_some_and(necklace::Error::is_input_error);
            ExitCode::from(if input { 2 } else { 1 })
        }
    }
}

/// What every command may use to talk to the user besides its output.
pub struct Ui {
    /// Progress bars (hidden unless stderr is a terminal and not --quiet).
    pub bars: Bars,
    /// -v: stage timings on stderr.
    pub verbose: bool,
}

/// Run a command; the text it returns goes to stdout.
fn run(command: Command, ui: &Ui) -> Result<String> {
    match command {
        Command::Info { mesh, input, json } => info(mesh, &input.options(), json),
        Command::Volume {
            mesh,
            exterior,
            input,
            h,
            max_memory,
            unchecked_min_cell,
            mesher,
            output,
            json,
        } => {
            let options = VolumeOptions {
                h,
                max_memory,
                unchecked_min_cell,
                mesher: mesher.into(),
                ..VolumeOptions::default()
            };
            volume(mesh, exterior, &input.options(), &options, output, json)
        }
        Command::Critical {
            mesh,
            exterior,
            method,
            output,
            json,
        } => critical(
            mesh,
            exterior,
            &method.input.options(),
            &method.volume(),
            &method.morse(),
            output,
            json,
        ),
        Command::Loops {
            mesh,
            neck,
            output,
            png,
            html,
            volume,
            json,
        } => {
            let options = neck.options(volume);
            let files = OutputOptions {
                picture: png.then(RenderOptions::default),
                volume,
                html,
            };
            loops(mesh, &options, output.map(|o| (o, files)), json, ui)
        }
        Command::Batch {
            inputs,
            output,
            jobs,
            timeout,
            save_runs,
            retry_failed,
            neck,
        } => {
            let options = neck.options(false);
            let defaults = BatchOptions::default();
            let batch = BatchOptions {
                jobs: jobs.unwrap_or(defaults.jobs),
                timeout,
                max_memory: Some(neck.method.max_memory),
                retry_failed,
                save_runs,
                ..defaults
            };
            batch::run(&inputs, &options, &batch, &output, ui)
        }
        Command::BatchWorker {
            mesh,
            options,
            save_run,
        } => {
            let row = necklace::batch::work(&mesh, &options, save_run.as_deref());
            Ok(necklace::batch::row_line(&row)?)
        }
        Command::Repair {
            mesh,
            output,
            genus,
            max_length,
            only,
            band,
            png,
            method,
            json,
        } => {
            let options = pipeline::RepairOptions {
                target: match max_length {
                    Some(l) => pipeline::RepairTarget::MaxLength(l),
                    None => pipeline::RepairTarget::Genus(genus.unwrap_or(0)),
                },
                only: only.map(|o| match o {
                    flags::OnlyArg::Handles => Side::Inside,
                    flags::OnlyArg::Tunnels => Side::Outside,
                }),
                band,
                necks: pipeline::NeckOptions {
                    volume: method.volume(),
                    morse: method.morse(),
                    input: method.input.options(),
                    ..pipeline::NeckOptions::default()
                },
                ..pipeline::RepairOptions::default()
            };
            repair(mesh, &options, output, png, json, ui)
        }
        Command::View { dir, mesh } => view(dir, mesh),
        Command::Segment {
            mesh,
            loops,
            chosen,
            handles,
            tunnels,
            output,
            json,
        } => {
            let options = pipeline::NeckOptions {
                handles: handles || !tunnels,
                tunnels: tunnels || !handles,
                ..pipeline::NeckOptions::default()
            };
            segment(mesh, loops, &chosen, &options, output, json, ui)
        }
        Command::Render {
            mesh,
            loops,
            critical,
            output,
            size,
            views,
            opacity,
        } => {
            let options = RenderOptions {
                size,
                views,
                opacity,
                ..RenderOptions::default()
            };
            render(mesh, loops, critical, output, &options)
        }
        Command::Demo { output } => demo::run(&output, ui),
        Command::Bench {
            dir,
            csv,
            scaling,
            no_scaling,
            schedule,
        } => bench::run(
            &dir,
            csv.as_deref(),
            (!no_scaling).then_some(scaling),
            schedule.into(),
            ui,
        ),
        Command::Shape {
            name,
            params,
            output,
            list,
        } => match (list, name, output) {
            (true, _, _) => Ok(print::list_shapes()),
            (false, Some(name), Some(output)) => shape(&name, &params, output),
            _ => unreachable!("clap requires NAME and -o unless --list"),
        },
    }
}

fn info(path: PathBuf, input: &InputOptions, json: bool) -> Result<String> {
    input.check()?;
    let welded = pipeline::weld_input(io::read_mesh(&path)?, input);
    let (welding, note) = (welded.welding, welded.note);
    let report = pipeline::inspect_surface(&welded.mesh);
    if json {
        let mut value = serde_json::to_value(&report).context("encoding the report")?;
        value["file"] = serde_json::Value::String(path.display().to_string());
        value["welded_vertices"] = welding.merged.into();
        value["welded_collapsed_faces"] = welding.collapsed_faces.into();
        Ok(serde_json::to_string_pretty(&value)? + "\n")
    } else {
        let welded = note.map_or(String::new(), |n| format!("{n}\n"));
        Ok(format!("{}\n{welded}{report}\n", path.display()))
    }
}

fn critical(
    path: PathBuf,
    exterior: bool,
    input: &InputOptions,
    volume_options: &VolumeOptions,
    options: &MorseOptions,
    output: Option<PathBuf>,
    json: bool,
) -> Result<String> {
    if let Some(output) = &output {
        io::check_point_cloud_name(output)?;
        check_output_file(output)?;
    }
    let side = if exterior {
        Side::Outside
    } else {
        Side::Inside
    };
    let run =
        pipeline::find_critical_points(io::read_mesh(&path)?, side, input, volume_options, options)
            .map_err(|e| e.in_file(&path))?;
    print::note(&path, &run.prepared.notes);
    print::warn(&run.prepared.warnings);
    print::warn(&run.volume.warnings);
    print::morse_failures(side, run.result.morse_failures());
    if let Some(output) = &output {
        let points = pipeline::tracked_points(&run.result);
        io::write_point_cloud(output, &necklace::output::critical_point_cloud(&points))?;
    }
    let report = run.report();
    print::morse_sum_note(report.surface_morse_expected, &run.result);
    if json {
        return Ok(serde_json::to_string_pretty(&report)? + "\n");
    }
    Ok(print::critical_text(
        &path,
        side,
        &run.result,
        output.as_deref(),
    ))
}

fn loops(
    path: PathBuf,
    options: &pipeline::NeckOptions,
    output: Option<(PathBuf, OutputOptions)>,
    json: bool,
    ui: &Ui,
) -> Result<String> {
    if let Some((dir, _)) = &output {
        check_output_folder(dir)?;
    }
    let surface = io::read_mesh(&path)?;
    let report = pipeline::find_necks_with_progress(&surface, options, &ui.bars)?;
    print::note(&path, &report.notes);
    print::warn(&report.warnings);
    for check in &report.morse {
        print::morse_failures(check.side, check.steps.iter().filter(|s| !s.morse_ok));
    }
    if ui.verbose {
        eprint!("{}", print::stage_timings(&report));
    }
    let mut written = Vec::new();
    if let Some((dir, files)) = &output {
        written = necklace::output::write_run(dir, &report.surface, &report, files, Some(&path))?;
    }
    if json {
        let value = necklace::output::report_json(&report, Some(&path))?;
        return Ok(serde_json::to_string_pretty(&value)? + "\n");
    }
    print::loops_text(&path, &report, &written)
}

fn repair(
    path: PathBuf,
    options: &pipeline::RepairOptions,
    output: PathBuf,
    png: Option<PathBuf>,
    json: bool,
    ui: &Ui,
) -> Result<String> {
    io::check_mesh_name(&output)?;
    check_output_file(&output)?;
    if let Some(dir) = &png {
        check_output_folder(dir)?;
    }
    let surface = io::read_mesh(&path)?;
    let (repaired, report) = pipeline::repair_with_progress(&surface, options, &ui.bars)
        .map_err(|e| e.in_file(&path))?;
    print::warn(&report.warnings);
    io::write_mesh(&output, &repaired)?;
    if let Some(dir) = &png {
        let picture = RenderOptions {
            size: 900,
            ..RenderOptions::default()
        };
        let name = file_name(&path);
        necklace::output::repair_picture(&name, &surface, &repaired, &report, &picture)?
            .write_png(dir.join("repair.png"))?;
    }
    if json {
        return Ok(serde_json::to_string_pretty(&report)? + "\n");
    }
    Ok(print::repair_text(&path, &report, &output))
}

/// A mesh file's name, for titles (the whole path when it has none).
fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

fn view(dir: PathBuf, mesh: Option<PathBuf>) -> Result<String> {
    let (report, input) = necklace::output::read_run_json(dir.join("loops.json"))?;
    let Some(mesh) = mesh.or(input) else {
        return Err(necklace::Error::invalid_argument(
            "the run's loops.json names no mesh: give it with --mesh",
        )
        .into());
    };
    let surface = io::read_mesh(&mesh)?;
    let curves = necklace::output::loop_curves(&report);
    necklace::output::check_overlay(&surface, &curves, &[])?;
    let page = dir.join("view.html");
    check_output_file(&page)?;
    let name = file_name(&mesh);
    let shown = necklace::output::write_html(&page, &name, &surface, &report)?;
    let decimated = if shown.shown_triangles < shown.triangles {
        format!(
            " (the surface decimated for display: {} of {} triangles)",
            shown.shown_triangles, shown.triangles
        )
    } else {
        String::new()
    };
    Ok(format!(
        "{}: {} loops{decimated} -> {}\n",
        mesh.display(),
        report.loops.len(),
        page.display()
    ))
}

fn segment(
    path: PathBuf,
    loops: Option<PathBuf>,
    chosen: &[usize],
    options: &pipeline::NeckOptions,
    output: PathBuf,
    json: bool,
    ui: &Ui,
) -> Result<String> {
    check_output_file(&output)?;
    let surface = io::read_mesh(&path)?;
    let report = match &loops {
        Some(file) => necklace::output::read_report_json(file)?,
        None => pipeline::find_necks_with_progress(&surface, options, &ui.bars)?,
    };
    let picked: Vec<&necklace::loops::NeckLoop> = if chosen.is_empty() {
        report.loops.iter().collect()
    } else {
        chosen
            .iter()
            .map(|&i| {
                report.loops.get(i).ok_or_else(|| {
                    necklace::Error::invalid_argument(format!(
                        "--loop {i}: there are {} loops",
                        report.loops.len()
                    ))
                })
            })
            .collect::<necklace::Result<_>>()?
    };
    let segmentation = pipeline::segment_along_loops(&surface, &picked)?;
    necklace::output::write_segmentation(&output, &segmentation)?;
    if json {
        let value = necklace::output::segments_json(&segmentation)?;
        return Ok(serde_json::to_string_pretty(&value)? + "\n");
    }
    Ok(print::segments_text(
        &path,
        picked.len(),
        &segmentation,
        &output,
    ))
}

fn render(
    mesh: PathBuf,
    loops: Option<PathBuf>,
    critical: Option<PathBuf>,
    output: PathBuf,
    options: &RenderOptions,
) -> Result<String> {
    necklace::render::check_png_name(&output)?;
    check_output_file(&output)?;
    let surface = io::read_mesh(&mesh)?;
    let curves = match &loops {
        Some(path) => necklace::output::read_loops_json(path)?,
        None => Vec::new(),
    };
    let saddles = match &critical {
        Some(path) => necklace::output::read_points_json(path)?,
        None => Vec::new(),
    };
    necklace::output::check_overlay(&surface, &curves, &saddles)?;
    let name = file_name(&mesh);
    let scene = necklace::output::loop_scene(&name, &surface, &curves, &saddles);
    let rendered = necklace::render::render(&scene, options)?;
    rendered.image.write_png(&output)?;
    Ok(format!(
        "{}: {} loops, {} saddles, {} x {} pixels -> {}\n",
        mesh.display(),
        curves.len(),
        saddles.len(),
        rendered.image.width,
        rendered.image.height,
        output.display()
    ))
}

/// Read a mesh and prepare it for the method (`pipeline::prepare_input`), printing
/// what was repaired and what is unusual about it.
fn read_prepared(
    path: &std::path::Path,
    input: &InputOptions,
) -> Result<pipeline::PreparedSurface> {
    let prepared =
        pipeline::prepare_input_with(io::read_mesh(path)?, input).map_err(|e| e.in_file(path))?;
    print::note(path, &prepared.notes);
    for w in &prepared.warnings {
        eprintln!("necklace: warning: {}: {}", path.display(), printable(w));
    }
    Ok(prepared)
}

fn volume(
    path: PathBuf,
    exterior: bool,
    input: &InputOptions,
    options: &VolumeOptions,
    output: Option<PathBuf>,
    json: bool,
) -> Result<String> {
    if let Some(output) = &output {
        io::check_tet_mesh_name(output)?;
        check_output_file(output)?;
    }
    // The distance structure built while preparing serves the mesher too.
    let prepared = read_prepared(&path, input)?;
    let side = if exterior {
        Side::Outside
    } else {
        Side::Inside
    };
    let result =
        necklace::volume::volume_mesh_with(&prepared.mesh, &prepared.distance, side, options)?;
    print::warn(&result.warnings);
    if let Some(output) = &output {
        io::write_tet_mesh(output, &result.mesh, &[])?;
    }
    let report = result.report();
    if json {
        return Ok(serde_json::to_string_pretty(&report)? + "\n");
    }
    Ok(print::volume_text(&path, &report, output.as_deref()))
}

fn shape(name: &str, params: &[(String, f64)], output: PathBuf) -> Result<String> {
    io::check_mesh_name(&output)?;
    check_output_file(&output)?;
    let shape = Shape::from_name(name, params)?;
    let mesh = shape.mesh()?;
    io::write_mesh(&output, &mesh)?;
    let report = MeshReport::new(&mesh);
    let params: Vec<String> = shape
        .params()
        .iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    Ok(format!(
        "{} ({}): {} vertices, {} faces, genus {} -> {}\n",
        shape.kind(),
        params.join(" "),
        report.vertices,
        report.faces,
        shape.genus(),
        output.display()
    ))
}
