//! `necklace demo`: the whole method on built-in shapes that show every feature — a
//! chain of balls (genus-0 necks), a varying torus (a handle and a tunnel), a genus-3
//! pretzel — with a table per shape and each run's files and picture in a subfolder.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use necklace::output::{write_run, OutputOptions};
use necklace::pipeline::{find_necks_with_progress, NeckOptions};
use necklace::render::RenderOptions;
use necklace::shapes::{Shape, ShapeKind};
use necklace::{io, MeshReport, Side};

use crate::Ui;

/// The demo's shapes, in the order they run.
const SHAPES: [ShapeKind; 3] = [
    ShapeKind::Chain,
    ShapeKind::VaryingTorus,
    ShapeKind::Pretzel,
];

pub fn run(dir: &Path, ui: &Ui) -> Result<String> {
    let mut out = String::new();
    for kind in SHAPES {
        let shape = Shape::new(kind);
        let surface = shape.mesh()?;
        let report = find_necks_with_progress(&surface, &NeckOptions::default(), &ui.bars)?;
        if ui.verbose {
            eprint!("{}", crate::print::stage_timings(&report));
        }
        let folder = dir.join(kind.name());
        let files = OutputOptions {
            picture: Some(RenderOptions::default()),
            volume: false,
            html: true,
        };
        write_run(&folder, &surface, &report, &files, None)?;
        io::write_mesh(folder.join("surface.obj"), &surface)?;

        let expected = shape.expected_necks();
        let count = |side: Side| {
            let found = report.loops.iter().filter(|l| l.kind == side).count();
            let wanted = expected.iter().filter(|n| n.kind == side).count();
            format!("{found} {}s (expected {wanted})", side.neck_name())
        };
        let _ = writeln!(
            out,
            "{}: genus {}, {} vertices: {}, {}; {:.1} s -> {}",
            kind.name(),
            shape.genus(),
            MeshReport::new(&surface).vertices,
            count(Side::Inside),
            count(Side::Outside),
            report.timings.total.total,
            folder.join("view.png").display()
        );
        let _ = writeln!(out, "    #  kind    length     expected   centre");
        for (i, l) in report.loops.iter().enumerate() {
            // The expected neck of the same kind whose length is closest.
            let closest = expected
                .iter()
                .filter(|n| n.kind == l.kind)
                .filter_map(|n| n.length)
                .min_by(|a, b| (a - l.length).abs().total_cmp(&(b - l.length).abs()));
            let _ = writeln!(
                out,
                "  {i:>3}  {:<6}  {:<9.5}  {:<9}  ({:.3}, {:.3}, {:.3})",
                l.kind.neck_name(),
                l.length,
                closest.map_or("-".to_string(), |c| format!("{c:.5}")),
                l.center[0],
                l.center[1],
                l.center[2]
            );
        }
        if !report.dropped.is_empty() {
            let _ = writeln!(
                out,
                "  {} saddles gave no loop (see loops.json)",
                report.dropped.len()
            );
        }
    }
    Ok(out)
}
