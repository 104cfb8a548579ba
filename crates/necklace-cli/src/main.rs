//! `necklace`: the command-line tool. It parses flags, builds library options, calls the
//! library and prints; every algorithm lives in the `necklace` library crate.
//!
//! Exit status: 0 on success, 2 for bad input (unreadable or malformed file, bad
//! argument), 1 for any other failure. Errors are one line on stderr.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use necklace::error::printable;
use necklace::file::{check_output_file, check_output_folder};
use necklace::loops::LoopOptions;
use necklace::morse::{MorseOptions, Schedule};
use necklace::output::OutputOptions;
use necklace::pipeline::{self, Mesher, Side, VolumeOptions};
use necklace::render::RenderOptions;
use necklace::shapes::{Shape, ShapeKind};
use necklace::{io, MeshReport};
use progress::Bars;

mod bench;
mod demo;
mod progress;

#[derive(Parser)]
#[command(
    name = "necklace",
    version,
    about = "Neck loops (handles and tunnels) of closed triangle meshes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// No progress bars.
    #[arg(short, long, global = true)]
    quiet: bool,
    /// Print seconds per stage and side to stderr.
    #[arg(short, long, global = true)]
    verbose: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Print counts, the validity report and the genus per component of a mesh
    /// (OBJ, OFF, PLY or STL).
    Info {
        /// The mesh file.
        mesh: PathBuf,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Mesh the volume inside a surface (or, with --exterior, the shell between it and a
    /// bounding sphere) into tetrahedra.
    Volume {
        /// The closed surface mesh.
        mesh: PathBuf,
        /// Mesh the outside shell instead of the inside.
        #[arg(long)]
        exterior: bool,
        /// Lattice spacing along the surface (default: bounding-box diagonal / 64).
        #[arg(long, allow_negative_numbers = true)]
        h: Option<f64>,
        /// The most tets the volume mesh may have: a larger run is refused, and thin
        /// parts are not refined past it.
        #[arg(long, default_value_t = necklace::volume::DEFAULT_MAX_TETS, allow_negative_numbers = true)]
        max_tets: usize,
        /// The volume mesher: necklace's isosurface stuffing, or TetGen "pq1.2" (needs a
        /// build with --features tetgen, which is AGPL-3.0).
        #[arg(long, value_enum, default_value = "stuffing")]
        mesher: MesherArg,
        /// Output tet mesh (.vtu, .mesh, .node or .msh).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Find the critical points of the smoothed distance field inside a surface (or,
    /// with --exterior, in the shell around it) and the 2-saddles that mark necks.
    Critical {
        /// The closed surface mesh.
        mesh: PathBuf,
        /// Work in the outside shell (tunnels) instead of the inside (handles).
        #[arg(long)]
        exterior: bool,
        #[command(flatten)]
        method: MethodArgs,
        /// Write the critical points at step N (with type, selected, persistence and
        /// colours) as a PLY point cloud.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Find the neck loops of a closed surface: handles (around narrow parts of the
    /// solid) and tunnels (around narrow parts of the space around it); both unless one
    /// is asked for.
    Loops {
        /// The closed surface mesh.
        mesh: PathBuf,
        /// Find handle loops (inside).
        #[arg(long)]
        handles: bool,
        /// Find tunnel loops (outside).
        #[arg(long)]
        tunnels: bool,
        #[command(flatten)]
        method: MethodArgs,
        /// Where the plane through a saddle has no curve around it: parallel planes tried
        /// on each side, 0.125 % of the diagonal apart.
        #[arg(long, default_value_t = LoopOptions::default().plane_offsets, allow_negative_numbers = true)]
        plane_offsets: usize,
        /// A kept cycle-closing loop is also cut from parallel planes up to this many
        /// steps (0.5 % of the diagonal) away on each side, and the shortest loop of its
        /// class wins (0: off).
        #[arg(long, default_value_t = LoopOptions::default().slide_steps, allow_negative_numbers = true)]
        slide_steps: usize,
        /// A separating saddle below --min-bulge is a neck only if the curve one loop
        /// radius away is at least this much longer than its loop, on both sides
        /// (0: a cylinder).
        #[arg(long, default_value_t = LoopOptions::default().min_opening, allow_negative_numbers = true)]
        min_opening: f64,
        /// ... and its loop is at most this many times the circumference of the
        /// inscribed ball at the saddle (larger: a loop round a flat part).
        #[arg(long, default_value_t = LoopOptions::default().max_flatness, allow_negative_numbers = true)]
        max_flatness: f64,
        /// Write loops.obj, loops.ply, loops.json and critical.ply into this folder.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Also write view.png (a picture of the surface and its loops) into the folder.
        #[arg(long, requires = "output")]
        png: bool,
        /// Also write field.vtu (volume meshes with the smoothed field) into the folder.
        #[arg(long, requires = "output")]
        volume: bool,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Draw a mesh with loops and saddles from several directions into a PNG.
    Render {
        /// The surface mesh.
        mesh: PathBuf,
        /// loops.json written by `necklace loops -o DIR`.
        #[arg(long)]
        loops: Option<PathBuf>,
        /// Saddles to draw as dots: the JSON of `necklace critical --json`, or a loops.json.
        #[arg(long)]
        critical: Option<PathBuf>,
        /// Output picture (.png).
        #[arg(short, long)]
        output: PathBuf,
        /// Width in pixels.
        #[arg(long, default_value_t = 1200, allow_negative_numbers = true)]
        size: u32,
        /// Number of views: three-quarter, front, side, top (1 to 4).
        #[arg(long, default_value_t = 4, allow_negative_numbers = true)]
        views: usize,
        /// Opacity of the surface over loops and saddles behind it (0 to 1).
        #[arg(long, default_value_t = 0.7, allow_negative_numbers = true)]
        opacity: f64,
    },
    /// Run the whole method on built-in shapes (a chain of balls, a varying torus, a
    /// genus-3 pretzel): tables, loops and pictures; no input file needed.
    Demo {
        /// Folder for the results (one subfolder per shape).
        #[arg(short, long, default_value = "necklace-demo")]
        output: PathBuf,
    },
    /// Time every mesh of a folder in both modes (stages named as in the paper's
    /// Table 1), then a series over the lattice spacing h on one model.
    Bench {
        /// Folder of meshes (.obj, .off, .ply, .stl).
        dir: PathBuf,
        /// Also write the table as CSV; the h series goes beside it as
        /// NAME-scaling.csv and NAME-scaling.png.
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Model of the h series (part of its file name; default bunny, else the first).
        #[arg(long)]
        scaling: Option<String>,
        /// Skip the h series.
        #[arg(long)]
        no_scaling: bool,
        /// Smoothing schedule: `scales` (default) or `paper` (20 steps), to compare
        /// the two in one build.
        #[arg(long, value_enum, default_value_t = ScheduleArg::Scales)]
        schedule: ScheduleArg,
    },
    /// Generate an analytic test shape with known necks and write it as a mesh.
    Shape {
        /// One of `necklace shape --list` (sphere, ellipsoid, capsule, limb, torus,
        /// varying-torus, dumbbell, chain, satellites, eight, pretzel, buckyball).
        #[arg(required_unless_present = "list")]
        name: Option<String>,
        /// A shape parameter, `name=value` (repeatable); `--list` shows them.
        #[arg(long = "param", value_name = "K=V", value_parser = parse_param)]
        params: Vec<(String, f64)>,
        /// Output file (.obj, .off or .ply).
        #[arg(short, long, required_unless_present = "list")]
        output: Option<PathBuf>,
        /// List the shapes, their parameters and their expected necks.
        #[arg(long)]
        list: bool,
    },
}

/// The method's settings shared by `critical` and `loops`.
#[derive(clap::Args)]
struct MethodArgs {
    /// Smoothing schedule: `scales` classifies over a geometric range of heat times
    /// (from 2h to a quarter of the diagonal); `paper` takes --steps steps of --tau and
    /// classifies from step 10 on, as the paper does.
    #[arg(long, value_enum, default_value_t = ScheduleArg::Scales)]
    schedule: ScheduleArg,
    /// Scale space: classified levels.
    #[arg(long, default_value_t = 32, allow_negative_numbers = true)]
    levels: usize,
    /// Scale space: smallest bulge ratio (the lobe's largest inscribed radius / the
    /// neck's) of a neck that cuts off a part; a separating saddle below it is a neck
    /// only if its loop opens out on both sides (`loops --min-opening`).
    #[arg(long, default_value_t = 1.5, allow_negative_numbers = true)]
    min_bulge: f64,
    /// Scale space: levels a saddle must live to be a neck.
    #[arg(long, default_value_t = 3, allow_negative_numbers = true)]
    min_levels: usize,
    /// Paper schedule: last smoothing step N (classification runs from step 10 to N).
    #[arg(long, default_value_t = 20, allow_negative_numbers = true)]
    steps: usize,
    /// Paper schedule: heat time step in units where the bounding box's longest side
    /// is 1.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    tau: f64,
    /// Lattice spacing of the volume mesh (default: bounding-box diagonal / 64).
    #[arg(long, allow_negative_numbers = true)]
    h: Option<f64>,
    /// The most tets a volume mesh may have: a larger run is refused, and thin parts
    /// are not refined past it.
    #[arg(long, default_value_t = necklace::volume::DEFAULT_MAX_TETS, allow_negative_numbers = true)]
    max_tets: usize,
    /// The most heat steps (--levels, or --steps with the paper schedule) a run may
    /// take: more is refused before any work.
    #[arg(long, default_value_t = necklace::morse::DEFAULT_MAX_STEPS, allow_negative_numbers = true)]
    max_steps: usize,
}

impl MethodArgs {
    fn volume(&self) -> VolumeOptions {
        VolumeOptions {
            h: self.h,
            max_tets: self.max_tets,
            ..VolumeOptions::default()
        }
    }

    fn morse(&self) -> MorseOptions {
        MorseOptions {
            schedule: self.schedule.into(),
            levels: self.levels,
            min_bulge: self.min_bulge,
            min_levels: self.min_levels,
            steps: self.steps,
            tau: self.tau,
            max_steps: self.max_steps,
            ..MorseOptions::default()
        }
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum ScheduleArg {
    Scales,
    Paper,
}

impl From<ScheduleArg> for Schedule {
    fn from(s: ScheduleArg) -> Schedule {
        match s {
            ScheduleArg::Scales => Schedule::ScaleSpace,
            ScheduleArg::Paper => Schedule::Paper,
        }
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum MesherArg {
    Stuffing,
    Tetgen,
}

fn parse_param(s: &str) -> std::result::Result<(String, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected name=value, got '{s}'"))?;
    let v: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("'{v}' is not a number"))?;
    Ok((k.trim().to_string(), v))
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => return argument_error(&err),
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
        Ok(text) => print_stdout(&text),
        Err(err) => {
            eprintln!("necklace: {}", printable(&format!("{err:#}")));
            // Library errors are about the input, the arguments or the files named:
            // status 2; anything else is ours: 1.
            if err.downcast_ref::<necklace::Error>().is_some() {
                ExitCode::from(2)
            } else {
                ExitCode::from(1)
            }
        }
    }
}

/// Print a command's output. A closed pipe (`necklace ... | head`) is not worth a
/// message; any other failure (a full disk) is, with status 2 like every failed write.
fn print_stdout(text: &str) -> ExitCode {
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("necklace: cannot write to stdout: {e}");
            ExitCode::from(2)
        }
    }
}

/// Help and version go to stdout as clap writes them; every other argument error is one
/// line on stderr with status 2.
fn argument_error(err: &clap::Error) -> ExitCode {
    use clap::error::ErrorKind as K;
    if matches!(err.kind(), K::DisplayHelp | K::DisplayVersion) {
        let _ = err.print();
        return ExitCode::SUCCESS;
    }
    let rendered = err.render().to_string();
    let mut lines = rendered.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("bad arguments");
    let mut line = first.trim_start_matches("error: ").to_string();
    // Keep clap's tips (a similar flag), one line; drop its advice to use `--`, which
    // does not apply (negative numbers are taken as values).
    for tip in lines.filter_map(|l| l.strip_prefix("tip: ")) {
        if !tip.contains("'--") || tip.contains("similar") {
            line += &format!("; {tip}");
        }
    }
    if err.kind() == K::DisplayHelpOnMissingArgumentOrSubcommand {
        line = "a command is needed (info, volume, critical, loops, render, demo, bench, shape)"
            .into();
    }
    eprintln!("necklace: {}; see necklace --help", printable(&line));
    ExitCode::from(2)
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
        Command::Info { mesh, json } => info(mesh, json),
        Command::Volume {
            mesh,
            exterior,
            h,
            max_tets,
            mesher,
            output,
            json,
        } => {
            let options = VolumeOptions {
                h,
                max_tets,
                mesher: match mesher {
                    MesherArg::Stuffing => Mesher::Stuffing,
                    MesherArg::Tetgen => Mesher::Tetgen,
                },
                ..VolumeOptions::default()
            };
            volume(mesh, exterior, &options, output, json)
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
            &method.volume(),
            &method.morse(),
            output,
            json,
        ),
        Command::Loops {
            mesh,
            handles,
            tunnels,
            method,
            plane_offsets,
            slide_steps,
            min_opening,
            max_flatness,
            output,
            png,
            volume,
            json,
        } => {
            let options = pipeline::NeckOptions {
                loops: LoopOptions {
                    plane_offsets,
                    slide_steps,
                    min_opening,
                    max_flatness,
                    ..LoopOptions::default()
                },
                // Neither flag: both kinds.
                handles: handles || !tunnels,
                tunnels: tunnels || !handles,
                volume: method.volume(),
                morse: method.morse(),
                keep_volume: volume,
            };
            let files = OutputOptions {
                picture: png.then(RenderOptions::default),
                volume,
            };
            loops(mesh, &options, output.map(|o| (o, files)), json, ui)
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
            (true, _, _) => Ok(list_shapes()),
            (false, Some(name), Some(output)) => shape(&name, &params, output),
            _ => unreachable!("clap requires NAME and -o unless --list"),
        },
    }
}

fn info(path: PathBuf, json: bool) -> Result<String> {
    let mesh = io::read_mesh(&path)?;
    let report = pipeline::inspect_surface(&mesh);
    if json {
        let mut value = serde_json::to_value(&report).context("encoding the report")?;
        value["file"] = serde_json::Value::String(path.display().to_string());
        Ok(serde_json::to_string_pretty(&value)? + "\n")
    } else {
        Ok(format!("{}\n{report}\n", path.display()))
    }
}

fn critical(
    path: PathBuf,
    exterior: bool,
    volume_options: &VolumeOptions,
    options: &MorseOptions,
    output: Option<PathBuf>,
    json: bool,
) -> Result<String> {
    if let Some(output) = &output {
        io::check_point_cloud_name(output)?;
        check_output_file(output)?;
    }
    options.check()?;
    let surface = read_prepared(&path)?;
    let surface_report = MeshReport::new(&surface);
    let side = if exterior {
        Side::Outside
    } else {
        Side::Inside
    };
    let volume = pipeline::volume_mesh(&surface, side, volume_options)?;
    warn(&volume.warnings);
    let result = pipeline::critical_points(&surface, &volume, options)?;
    for step in result.morse_failures() {
        eprintln!(
            "necklace: MORSE CHECK FAILED at step {}: sum {} != expected {} ({} maxima, {} 1-saddles, {} 2-saddles, {} monkeys)",
            step.step, step.morse_sum, step.morse_expected, step.maxima, step.saddles1, step.saddles2, step.monkeys
        );
    }
    if let Some(output) = &output {
        io::write_point_cloud(output, &pipeline::critical_point_cloud(&result))?;
    }
    let report = pipeline::CriticalReport {
        side,
        volume: volume.report(),
        surface_morse_expected: pipeline::surface_morse_expected(&surface_report, side),
        morse: &result,
    };
    if let Some(expected) = report.surface_morse_expected {
        let mesh = result.morse_expected;
        if expected != mesh.sum {
            eprintln!(
                "necklace: note: the surface's genus predicts a Morse sum of {expected}, the volume mesh's topology {}: chi of its surface part {}, of all but the outer sphere {} (thin parts without interior vertices, or sub-resolution features; --h smaller may help)",
                mesh.sum, mesh.surface_part_euler, mesh.inner_part_euler
            );
        }
    }
    if json {
        return Ok(serde_json::to_string_pretty(&report)? + "\n");
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} ({:?}): {} unknowns, tau {:.3e}, {:.2} s assembly, {:.2} s smoothing, {:.2} s classification",
        path.display(),
        side,
        result.unknowns,
        result.tau,
        result.timings.assembly,
        result.timings.smoothing,
        result.timings.classification
    );
    let _ = writeln!(
        out,
        "step  maxima  1-saddles  2-saddles  monkeys  morse sum (expected)  essential cycles ({})",
        result.cycle_rank
    );
    for s in &result.steps {
        let _ = writeln!(
            out,
            "{:>4}  {:>6}  {:>9}  {:>9}  {:>7}  {:>4} ({}){}  {:>4}{}",
            s.step,
            s.maxima,
            s.saddles1,
            s.saddles2,
            s.monkeys,
            s.morse_sum,
            s.morse_expected,
            if s.morse_ok { "" } else { "  MISMATCH" },
            s.essential_cycles,
            if s.cycles_ok { "" } else { "  MISMATCH" }
        );
    }
    let _ = writeln!(out, "{} neck 2-saddles:", result.saddles.len());
    for s in &result.saddles {
        let _ = writeln!(
            out,
            "  at ({:.4}, {:.4}, {:.4})  normal ({:.3}, {:.3}, {:.3})  persistence {}  hessian ({:.3e}, {:.3e}, {:.3e})",
            s.position[0], s.position[1], s.position[2],
            s.normal[0], s.normal[1], s.normal[2],
            s.persistence,
            s.hessian.eigenvalues[0], s.hessian.eigenvalues[1], s.hessian.eigenvalues[2]
        );
    }
    let _ = writeln!(out, "{} 2-saddles not selected:", result.rejected.len());
    for r in &result.rejected {
        let _ = writeln!(
            out,
            "  at ({:.4}, {:.4}, {:.4})  {}",
            r.position[0],
            r.position[1],
            r.position[2],
            serde_json::to_string(&r.reason)?
        );
    }
    if let Some(output) = output {
        let _ = writeln!(out, "critical points -> {}", output.display());
    }
    Ok(out)
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
    note(&path, &report.notes);
    warn(&report.warnings);
    warn_morse_failures(&report);
    if ui.verbose {
        eprint!("{}", stage_timings(&report));
    }
    let mut written = Vec::new();
    if let Some((dir, files)) = &output {
        written = necklace::output::write_run(dir, &report.surface, &report, files, Some(&path))?;
    }
    if json {
        let value = necklace::output::report_json(&report, Some(&path))?;
        return Ok(serde_json::to_string_pretty(&value)? + "\n");
    }
    let mut out = format!("{}: {} loops\n", path.display(), report.loops.len());
    out += &loops_table(&report)?;
    for check in &report.morse {
        let _ = writeln!(
            out,
            "Morse check {:?}: {} ({} steps); essential cycles {} (H1 rank {})",
            check.side,
            if check.ok { "ok" } else { "FAILED" },
            check.steps.len(),
            if check.cycles_ok { "ok" } else { "FAILED" },
            check.cycle_rank
        );
    }
    let t = &report.timings.total;
    let _ = writeln!(
        out,
        "seconds: volume mesh {:.2}, distance {:.2}, smoothing {:.2}, critical points {:.2}, loops {:.3}, total {:.2}",
        t.volume_mesh, t.distance, t.smoothing, t.critical_points, t.loops, t.total
    );
    for file in written {
        let _ = writeln!(out, "-> {}", file.display());
    }
    Ok(out)
}

/// Print warnings to stderr, one line each.
fn warn(warnings: &[String]) {
    for w in warnings {
        eprintln!("necklace: warning: {}", printable(w));
    }
}

/// Print what was done to an input file, one line each.
fn note(path: &std::path::Path, notes: &[String]) {
    for n in notes {
        eprintln!("necklace: note: {}: {}", path.display(), printable(n));
    }
}

/// Print Morse-check failures to stderr.
fn warn_morse_failures(report: &pipeline::NeckReport) {
    for check in &report.morse {
        for step in check.steps.iter().filter(|s| !s.morse_ok) {
            eprintln!(
                "necklace: MORSE CHECK FAILED ({:?}) at step {}: sum {} != expected {}",
                check.side, step.step, step.morse_sum, step.morse_expected
            );
        }
    }
}

/// Seconds per stage and side (for -v).
pub fn stage_timings(report: &pipeline::NeckReport) -> String {
    let mut out = String::new();
    for side in &report.sides {
        let t = &side.timings;
        let _ = writeln!(
            out,
            "necklace: {:?}: {} vertices, {} tets, {} unknowns; seconds: volume mesh {:.3}, distance {:.3}, smoothing {:.3}, critical points {:.3}, loops {:.3}, total {:.3}",
            side.side, side.volume.vertices, side.volume.tets, side.unknowns,
            t.volume_mesh, t.distance, t.smoothing, t.critical_points, t.loops, t.total
        );
    }
    out
}

/// The loops and drops of a report as a text table.
pub fn loops_table(report: &pipeline::NeckReport) -> Result<String> {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "  #  kind    length      radius    centre                          role           scales             separates  persistence  tightening"
    );
    for (i, l) in report.loops.iter().enumerate() {
        let role = match l.role {
            Some(necklace::loops::Role::Separating) => "separating",
            Some(necklace::loops::Role::CycleClosing) => "cycle-closing",
            None => "-",
        };
        let scales = match l.death_scale {
            Some(d) => format!("{:.3}..{:.3}", l.birth_scale, d),
            None => format!("{:.3}..", l.birth_scale),
        };
        let _ = writeln!(
            out,
            "{i:>3}  {:<6}  {:<10.5}  {:<8.5}  ({:>8.4}, {:>8.4}, {:>8.4})  {role:<13}  {scales:<17}  {:<9}  {:>11}  {:?} in {} rounds (from {:.5})",
            format!("{:?}", l.kind).to_lowercase(),
            l.length,
            l.radius,
            l.center[0],
            l.center[1],
            l.center[2],
            if l.separating { "yes" } else { "no" },
            l.persistence,
            l.tightening.status,
            l.tightening.rounds,
            l.initial_length
        );
    }
    if !report.dropped.is_empty() {
        let _ = writeln!(out, "{} saddles gave no loop:", report.dropped.len());
        for d in &report.dropped {
            let _ = writeln!(
                out,
                "  {:?} saddle {} at ({:.4}, {:.4}, {:.4}): {}",
                d.kind,
                d.seed,
                d.saddle[0],
                d.saddle[1],
                d.saddle[2],
                serde_json::to_string(&d.reason)?
            );
        }
    }
    Ok(out)
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
    let scene = necklace::output::loop_scene(&surface, &curves, &saddles);
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
pub fn read_prepared(path: &std::path::Path) -> Result<necklace::SurfaceMesh> {
    let prepared = pipeline::prepare_input(io::read_mesh(path)?).map_err(|e| e.in_file(path))?;
    note(path, &prepared.notes);
    for w in &prepared.warnings {
        eprintln!("necklace: warning: {}: {}", path.display(), printable(w));
    }
    Ok(prepared.mesh)
}

fn volume(
    path: PathBuf,
    exterior: bool,
    options: &VolumeOptions,
    output: Option<PathBuf>,
    json: bool,
) -> Result<String> {
    if let Some(output) = &output {
        io::check_tet_mesh_name(output)?;
        check_output_file(output)?;
    }
    let surface = read_prepared(&path)?;
    let side = if exterior {
        Side::Outside
    } else {
        Side::Inside
    };
    let result = pipeline::volume_mesh(&surface, side, options)?;
    warn(&result.warnings);
    if let Some(output) = &output {
        io::write_tet_mesh(output, &result.mesh, &[])?;
    }
    let report = result.report();
    if json {
        return Ok(serde_json::to_string_pretty(&report)? + "\n");
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} ({:?}): {} vertices ({} interior, {} surface, {} outer), {} tets",
        path.display(),
        report.side,
        report.vertices,
        report.interior_vertices,
        report.surface_vertices,
        report.outer_vertices,
        report.tets
    );
    let topology = &report.topology;
    let _ = writeln!(
        out,
        "topology: {}{}",
        topology.found,
        match (&topology.expected, topology.matches) {
            (Some(_), Some(true)) => " (as the surface predicts)".to_string(),
            (Some(e), _) => format!(" (the surface predicts {e})"),
            (None, _) =>
                " (the surface predicts nothing: it crosses itself or is not a manifold)".into(),
        }
    );
    let _ = writeln!(
        out,
        "chi(volume) {}  chi(boundary) {}  dihedral {:.1}..{:.1} deg ({} tets below 10)  hausdorff {:.2e} diag",
        report.euler_volume,
        report.euler_boundary,
        report.min_dihedral_deg,
        report.max_dihedral_deg,
        report.tets_below_10_deg,
        report.hausdorff_to_surface
    );
    let _ = writeln!(
        out,
        "h {:.4e}  finest cell {:.4e}  volume {:.6e}  {:.2} s{}",
        report.h,
        report.finest_cell,
        report.volume,
        report.seconds,
        output.map_or(String::new(), |o| format!("  -> {}", o.display()))
    );
    Ok(out)
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

fn list_shapes() -> String {
    let mut out = String::new();
    for kind in ShapeKind::ALL {
        let _ = writeln!(out, "{kind}: {}", kind.description());
        for p in kind.params() {
            let _ = writeln!(out, "    {:<8} default {:<6} {}", p.name, p.default, p.doc);
        }
    }
    out
}
