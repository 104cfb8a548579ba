//! Step 1b of the method: the surface the volume, field and saddle stages work on.
//! A surface denser than [`SimplifyOptions::above`] triangles is simplified
//! (`simplify`, the paper's sec. 5 speed-up) when it is a closed manifold that does not
//! cross itself, and the copy is used when it is one too, with the input's genus on
//! every component; otherwise the input is used and a warning says why. The loops
//! found on the copy are carried back to the input by `loops::transfer_loops`.

use super::input::{prepare_input, PreparedSurface};
use super::report::SimplifyReport;
use crate::error::Result;
use crate::mesh::MeshReport;
use crate::simplify::{simplify, SimplifyOptions, Stop};

/// The simplified copy of a dense input, and what to say about it.
pub(super) struct Working {
    /// The copy, prepared like the input; `None` when the input is used as it is.
    pub prepared: Option<PreparedSurface>,
    /// What simplification did, when it ran.
    pub report: Option<SimplifyReport>,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
}

/// The working surface of a run on `prepared` (see the module doc); `None` when the
/// input is not dense enough to be simplified.
pub(super) fn simplified_input(
    prepared: &PreparedSurface,
    options: &SimplifyOptions,
) -> Result<Option<Working>> {
    let triangles = prepared.mesh.num_triangles();
    if !options.applies_to(triangles) {
        return Ok(None);
    }
    let mut working = Working {
        prepared: None,
        report: None,
        notes: Vec::new(),
        warnings: Vec::new(),
    };
    let r = &prepared.mesh_report;
    if !(r.watertight && r.manifold && r.oriented && prepared.crossing_faces.is_empty()) {
        working.warnings.push(format!(
            "not simplified ({triangles} triangles, above {}): only a closed manifold surface that does not cross itself is; every stage works on the input",
            options.above
        ));
        return Ok(Some(working));
    }
    let simplified = simplify(&prepared.mesh, options)?;
    let diagonal = prepared.mesh.bbox_diagonal();
    let copy = prepare_input(simplified.mesh)?;
    let same_genus = genera(&copy.mesh_report) == genera(r);
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
    }
    working.report = Some(SimplifyReport {
        triangles: [before, after],
        max_error: simplified.max_error,
        stop: simplified.stop,
        used,
    });
    working.prepared = used.then_some(copy);
    Ok(Some(working))
}

/// Each component's genus, in order.
fn genera(report: &MeshReport) -> Vec<Option<i64>> {
    report.component_details.iter().map(|c| c.genus).collect()
}
