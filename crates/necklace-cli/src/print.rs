//! What the commands print: tables and one-line messages. Everything here formats
//! library results; nothing computes.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use necklace::error::printable;
use necklace::morse::{MorseResult, NormalSource, StepSummary};
use necklace::pipeline::NeckReport;
use necklace::shapes::ShapeKind;
use necklace::volume::VolumeReport;
use necklace::Side;

/// Print warnings to stderr, one line each.
pub fn warn(warnings: &[String]) {
    for w in warnings {
        eprintln!("necklace: warning: {}", printable(w));
    }
}

/// Print what was done to an input file, one line each.
pub fn note(path: &std::path::Path, notes: &[String]) {
    for n in notes {
        eprintln!("necklace: note: {}: {}", path.display(), printable(n));
    }
}

/// Print the levels whose Morse sum is not what the mesh's topology predicts, one line
/// each, in the one format every command uses.
pub fn morse_failures<'a>(side: Side, steps: impl Iterator<Item = &'a StepSummary>) {
    for s in steps {
        eprintln!(
            "necklace: MORSE CHECK FAILED ({side:?}) at step {}: sum {} != expected {} ({} maxima, {} 1-saddles, {} 2-saddles, {} monkeys)",
            s.step, s.morse_sum, s.morse_expected, s.maxima, s.saddles1, s.saddles2, s.monkeys
        );
    }
}

/// Seconds per stage and side (for -v).
pub fn stage_timings(report: &NeckReport) -> String {
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
pub fn loops_table(report: &NeckReport) -> Result<String> {
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
            l.kind.neck_name(),
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
                d.kind, d.seed, d.saddle[0], d.saddle[1], d.saddle[2], d.reason
            );
        }
    }
    Ok(out)
}

/// The note when the surface's genus and the volume mesh's topology predict different
/// Morse sums.
pub fn morse_sum_note(surface_expected: Option<i64>, result: &MorseResult) {
    let mesh = result.morse_expected;
    if let Some(expected) = surface_expected.filter(|&e| e != mesh.sum) {
        eprintln!(
            "necklace: note: the surface's genus predicts a Morse sum of {expected}, the volume mesh's topology {}: chi of its surface part {}, of all but the outer sphere {} (thin parts without interior vertices, or sub-resolution features; --h smaller may help)",
            mesh.sum, mesh.surface_part_euler, mesh.inner_part_euler
        );
    }
}

/// The text `necklace critical` prints.
pub fn critical_text(
    path: &Path,
    side: Side,
    result: &MorseResult,
    output: Option<&Path>,
) -> String {
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
        "step  maxima  1-saddles  2-saddles  monkeys  drained  morse sum (expected)  essential cycles ({})",
        result.cycle_rank
    );
    for s in &result.steps {
        let _ = writeln!(
            out,
            "{:>4}  {:>6}  {:>9}  {:>9}  {:>7}  {:>7}  {:>4} ({}){}  {:>4}{}",
            s.step,
            s.maxima,
            s.saddles1,
            s.saddles2,
            s.monkeys,
            s.drained,
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
    let _ = writeln!(
        out,
        "{} completions (closers of essential cycles; `loops` cuts them only for classes of the genus the necks miss)",
        result
            .completions
            .iter()
            .filter(|c| c.normal_from == NormalSource::UpperLink)
            .count()
    );
    let _ = writeln!(out, "{} 2-saddles not selected:", result.rejected.len());
    for r in &result.rejected {
        let _ = writeln!(
            out,
            "  at ({:.4}, {:.4}, {:.4})  {}",
            r.position[0], r.position[1], r.position[2], r.reason
        );
    }
    if let Some(output) = output {
        let _ = writeln!(out, "critical points -> {}", output.display());
    }
    out
}

/// The text `necklace loops` prints.
pub fn loops_text(path: &Path, report: &NeckReport, written: &[PathBuf]) -> Result<String> {
    let mut out = format!("{}: {} loops\n", path.display(), report.loops.len());
    out += &loops_table(report)?;
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
        "seconds: input {:.2}, surface survey {:.2}; summed over the sides: volume mesh {:.2}, distance {:.2}, smoothing {:.2}, critical points {:.2}, loops {:.3}, sides {:.2}; the whole run {:.2} (the sides ran at the same time unless --one-side-at-a-time)",
        report.timings.input,
        report.timings.survey,
        t.volume_mesh,
        t.distance,
        t.smoothing,
        t.critical_points,
        t.loops,
        t.total,
        report.timings.seconds
    );
    for file in written {
        let _ = writeln!(out, "-> {}", file.display());
    }
    Ok(out)
}

/// The text `necklace volume` prints.
pub fn volume_text(path: &Path, report: &VolumeReport, output: Option<&Path>) -> String {
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
    out
}

/// Print a command's output. A closed pipe (`necklace ... | head`) is not worth a
/// message; any other failure (a full disk) is, with status 2 like every failed write.
pub fn stdout(text: &str) -> ExitCode {
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
pub fn argument_error(err: &clap::Error) -> ExitCode {
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

/// The shapes, their parameters and their expected necks (`shape --list`).
pub fn list_shapes() -> String {
    let mut out = String::new();
    for kind in ShapeKind::ALL {
        let _ = writeln!(out, "{kind}: {}", kind.description());
        for p in kind.params() {
            let _ = writeln!(out, "    {:<8} default {:<6} {}", p.name, p.default, p.doc);
        }
    }
    out
}

/// The table of `necklace segment`: one line per segment.
pub fn segments_text(
    path: &Path,
    loops: usize,
    segmentation: &necklace::segment::Segmentation,
    output: &Path,
) -> String {
    let mut out = format!(
        "{}: cut along {loops} loop(s) into {} segment(s)\n",
        path.display(),
        segmentation.segments.len()
    );
    out += "segment  triangles        area        volume  euler  boundaries  genus  loops\n";
    for s in &segmentation.segments {
        let volume = s.volume.map_or_else(|| "-".to_string(), significant);
        let loops: Vec<String> = s.loops.iter().map(usize::to_string).collect();
        let _ = writeln!(
            out,
            "{:>7}  {:>9}  {:>10}  {:>12}  {:>5}  {:>10}  {:>5}  {}",
            s.id,
            s.triangles,
            significant(s.area),
            volume,
            s.euler,
            s.boundaries,
            s.genus,
            if loops.is_empty() {
                "-".to_string()
            } else {
                loops.join(",")
            }
        );
    }
    let _ = writeln!(out, "-> {}", output.display());
    out
}

/// `x` to six significant digits, without an exponent for ordinary sizes.
fn significant(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let magnitude = x.abs().log10().floor() as i32;
    if (-4..9).contains(&magnitude) {
        format!("{x:.*}", (5 - magnitude).max(0) as usize)
    } else {
        format!("{x:.5e}")
    }
}

/// `necklace repair`'s text: the genus before and after, one line per operation, the
/// loops skipped with their reasons.
pub fn repair_text(
    path: &Path,
    report: &necklace::pipeline::RepairReport,
    output: &Path,
) -> String {
    // What an operation on each kind is, and the kind's name.
    let names = |kind: necklace::Side| match kind {
        necklace::Side::Inside => ("handle cut", "handle"),
        necklace::Side::Outside => ("tunnel plugged", "tunnel"),
    };
    let mut text = format!(
        "{}: genus {} -> {} in {} operations ({} loop runs, {:.1} s), Hausdorff {:.4e} -> {}\n",
        path.display(),
        report.genus[0],
        report.genus[1],
        report.operations.len(),
        report.loop_runs,
        report.seconds,
        report.hausdorff,
        output.display()
    );
    for op in &report.operations {
        let _ = writeln!(
            text,
            "  {:14} loop length {:.4e}  caps {:.4e}  volume {:+.4e}  moved {:.4e}",
            names(op.neck.kind).0,
            op.neck.loop_length,
            op.cap_area,
            op.volume_change,
            op.max_displacement
        );
    }
    for skip in &report.skipped {
        let _ = writeln!(
            text,
            "  skipped {} loop of length {:.4e}: {}",
            names(skip.neck.kind).1,
            skip.neck.loop_length,
            skip.reason
        );
    }
    text
}
