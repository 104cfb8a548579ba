//! `necklace batch INPUT... -o RUNS.jsonl`: find the inputs, run the library's batch
//! with this binary (`necklace batch-worker`) as the worker, draw the bar, print the
//! summary. The batch itself (workers, limits, resuming) is `necklace::batch`.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::AtomicBool;

use anyhow::{Context, Result};
use necklace::batch::{collect_inputs, BatchOptions, Status, Worker};
use necklace::pipeline::NeckOptions;

use crate::Ui;

pub fn run(
    inputs: &[String],
    options: &NeckOptions,
    batch: &BatchOptions,
    out: &Path,
    ui: &Ui,
) -> Result<String> {
    let files = collect_inputs(inputs)?;
    let worker = Worker {
        program: std::env::current_exe().context("finding the necklace binary")?,
        args: vec!["batch-worker".to_string()],
    };
    let mut bar = None;
    let stop = AtomicBool::new(false);
    let summary = necklace::batch::run(
        &files,
        options,
        batch,
        &worker,
        out,
        &stop,
        &mut |row, progress| {
            let bar = bar.get_or_insert_with(|| ui.bars.batch(progress.total as u64));
            if let Some(bar) = bar {
                bar.set_position(progress.done as u64);
                bar.set_message(format!("{} failed", progress.failed));
            }
            if ui.verbose {
                eprintln!("{} {} {:.1} s", row.status.name(), row.path, row.seconds);
            }
        },
    )?;
    if let Some(Some(bar)) = bar {
        bar.finish_and_clear();
    }
    let mut text = format!(
        "{} meshes: {} run, {} already in {}",
        summary.meshes,
        summary.meshes - summary.skipped - summary.interrupted,
        summary.skipped,
        out.display()
    );
    let counts: Vec<String> = Status::ALL
        .iter()
        .map(|s| format!("{} {}", summary.counts.get(s).unwrap_or(&0), s.name()))
        .collect();
    let _ = writeln!(text, "; {} in {:.1} s", counts.join(", "), summary.seconds);
    if summary.interrupted > 0 {
        let _ = writeln!(text, "interrupted: {} meshes not run", summary.interrupted);
    }
    for (path, seconds, status) in &summary.slowest {
        let _ = writeln!(text, "  {seconds:8.1} s  {:8}  {path}", status.name());
    }
    Ok(text)
}
