//! Steps 1 and 1b of the method: the input prepared, and the surface the volume,
//! field and saddle stages work on.
//! A surface denser than [`SimplifyOptions::above`] triangles is simplified
//! (`simplify`, the paper's sec. 5 speed-up) when it is a closed manifold that does not
//! cross itself, and the copy is used when it is one too, with the input's genus on
//! every component; otherwise the input is used and a warning says why. The loops
//! found on the copy are carried back to the input by `loops::transfer_loops`.

use super::input::{
    add_signs, prepare, prepare_input, prepare_input_with, InputOptions, PreparedSurface, Signs,
};
use super::report::SimplifyReport;
use crate::error::Result;
use crate::mesh::{MeshReport, SurfaceMesh};
use crate::simplify::{simplify, SimplifyOptions, Stop};

/// The simplified copy of a dense input, and what to say about it.
pub(super) struct Working {
    /// The copy, prepared like the input; `None` when the input is used as it is.
    pub prepared: Option<PreparedSurface>,
    /// What simplification did, when it ran.
    pub report: Option<SimplifyReport>,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
    /// Seconds spent simplifying (at the same time as the input step).
    pub seconds: f64,
}

/// Step 1 of a run, with step 1b: the input prepared (`prepare_input`) and, where it
/// is dense enough, its simplified copy (see the module doc). Simplification starts at
/// the same time as the input step, on the input as given (the input step's checks take
/// as long, and simplifying is mostly one sequential pass); it is done again on the
/// prepared surface in the rare case that preparing changed the input (faces turned,
/// vertices removed). The input's distance structure gets its signs only where the
/// stages work on the input after all. Returns the prepared input, and the copy with
/// what to say about it (`None`: not dense enough to simplify).
pub(super) fn prepare_run(
    input: &SurfaceMesh,
    input_options: &InputOptions,
    options: &SimplifyOptions,
) -> Result<(PreparedSurface, Option<Working>)> {
    let triangles = input.num_triangles();
    if !options.applies_to(triangles) {
        return Ok((prepare_input_with(input.clone(), input_options)?, None));
    }
    let (prepared, early) = rayon::join(
        || prepare(input.clone(), input_options, Signs::Later),
        || {
            let start = std::time::Instant::now();
            (simplify(input, options), start.elapsed().as_secs_f64())
        },
    );
    let (early, mut seconds) = early;
    let mut prepared = prepared?;
    let mut working = Working {
        prepared: None,
        report: None,
        notes: Vec::new(),
        warnings: Vec::new(),
        seconds,
    };
    let r = &prepared.mesh_report;
    if !(r.watertight && r.manifold && r.oriented && prepared.crossing_faces.is_empty()) {
        working.warnings.push(format!(
            "not simplified ({triangles} triangles, above {}): only a closed manifold surface that does not cross itself is; every stage works on the input",
            options.above
        ));
        add_signs(&mut prepared);
        return Ok((prepared, Some(working)));
    }
    let simplified = if prepared.mesh == *input {
        early?
    } else {
        let start = std::time::Instant::now();
        let again = simplify(&prepared.mesh, options)?;
        seconds += start.elapsed().as_secs_f64();
        again
    };
    let diagonal = prepared.mesh.bbox_diagonal();
    let copy = prepare_input(simplified.mesh)?;
    let same_genus = genera(&copy.mesh_report) == genera(&prepared.mesh_report);
    let used = same_genus && copy.crossing_faces.is_empty();
    let (before, after) = simplified.triangles;
    let stop = match simplified.stop {
        Stop::Target => format!("the target of {} triangles", options.target),
        Stop::ErrorBound { next_error, bound } => format!(
            "the error bound {bound:.3e} ({} x diagonal; the next collapse's error {next_error:.3e})",
            options.max_error
        ),
        Stop::NoValidCollapse => "no collapse left that keeps the topology".to_string(),
    };
    if used {
        working.notes.push(format!(
            "simplified from {before} to {after} triangles for the volume mesh, distance field and saddles (stopped by {stop}; largest collapse error {:.3e}, {:.2e} x diagonal); the loops are cut again with the same planes and tightened on the input",
            simplified.max_error,
            simplified.max_error / diagonal
        ));
    } else {
        working.warnings.push(format!(
            "simplified from {before} to {after} triangles, but the copy {}: every stage works on the input",
            if same_genus {
                format!("crosses itself ({} triangles)", copy.crossing_faces.len())
            } else {
                "has another genus".to_string()
            }
        ));
        add_signs(&mut prepared);
    }
    working.report = Some(SimplifyReport {
        triangles: [before, after],
        max_error: simplified.max_error,
        stop: simplified.stop,
        used,
    });
    working.prepared = used.then_some(copy);
    working.seconds = seconds;
    Ok((prepared, Some(working)))
}

/// Each component's genus, in order.
fn genera(report: &MeshReport) -> Vec<Option<i64>> {
    report.component_details.iter().map(|c| c.genus).collect()
}
