//! Loops found on a simplified copy of a surface, carried back to the surface itself
//! (the paper's sec. 5, Fig. 16: "mapping the loops back to the original mesh is
//! performed by cutting the surface of the original mesh by the cutting planes used on
//! the simplified mesh").
//!
//! Each kept loop is rebuilt on the surface from what made it on the copy: the plane
//! through its saddle (shifted by its `plane_offset`, the narrowest place its cycle
//! slid to) cut with the surface, the curve around that plane's point; or, for a
//! membrane-built loop, the membrane of its saddle on the surface. The curve is then
//! tightened on the surface and measured there (class, areas, opening), so that every
//! figure and surface point of the result belongs to the surface. Selection is not
//! repeated: the copy's loops are the necks. A loop whose plane has no curve around
//! the saddle on the surface, or whose tightening fails there, is dropped as
//! [`DropReason::NotTransferred`]; duplicates of it follow it.

use rayon::prelude::*;

use super::tighten::tighten;
use super::{
    around_point, cutting_normals, membrane_loop, neck_loop, tightened, Initial, LoopOptions,
    LoopResult, LoopSurface, Seed,
};
use super::{DropReason, DroppedLoop, NeckLoop};
use crate::distance::SurfaceDistance;
use crate::error::{Error, Result};
use crate::geom::{add, scale};
use crate::mesh::SurfaceMesh;

/// `found`, the loop stage's result for `seeds` on a simplified copy of `surface`,
/// carried back to `surface` (see the module doc); `to` and `distance` are built from
/// `surface`. Dropped seeds stay dropped; kept loops keep their order, seeds and
/// duplicates.
pub fn transfer_loops(
    surface: &SurfaceMesh,
    to: &LoopSurface,
    distance: &SurfaceDistance,
    seeds: &[Seed],
    found: LoopResult,
    options: &LoopOptions,
) -> Result<LoopResult> {
    if !to.is_of(surface) || distance.num_triangles() != surface.num_triangles() {
        return Err(Error::invalid_argument(
            "transfer_loops: the loop surface and distance structure must be built from the surface the loops are carried to",
        ));
    }
    if let Some(l) = found.loops.iter().find(|l| l.seed >= seeds.len()) {
        return Err(Error::invalid_argument(format!(
            "transfer_loops: a loop names seed {} of {}",
            l.seed,
            seeds.len()
        )));
    }
    let geometry = to.geometry(surface);
    let measures = to.measures(surface, options);
    let carried: Vec<std::result::Result<NeckLoop, DropReason>> = found
        .loops
        .par_iter()
        .map(|l| {
            let seed = &seeds[l.seed];
            let (n, normals) = cutting_normals(seed, options);
            let not_transferred = |tightening| DropReason::NotTransferred {
                length: l.length,
                tightening,
            };
            let (t, sources) = match l.initial {
                Initial::Plane => {
                    let point = add(seed.position, scale(n, l.plane_offset));
                    let (_, curve) = around_point(surface, &to.topology, &normals, point)
                        .0
                        .ok_or(not_transferred(None))?;
                    let t = tighten(&geometry, &curve.crossings, &curve.faces, &options.tighten);
                    (t, Vec::new())
                }
                Initial::Membrane => {
                    let m = membrane_loop(
                        surface,
                        &to.topology,
                        distance,
                        seed.position,
                        n,
                        &options.membrane,
                    )
                    .map_err(|_| not_transferred(None))?;
                    let t = tighten(&geometry, &m.crossings, &m.faces, &options.tighten);
                    (t, m.sources)
                }
            };
            let status = t.status;
            let t = tightened(t).map_err(|_| not_transferred(Some(status)))?;
            let mut c = measures.candidate(t, l.plane_offset, l.initial);
            c.sources = sources;
            let inscribed = distance.distance(seed.position);
            c.flatness = (inscribed > 0.0)
                .then(|| c.tightened.length / (2.0 * std::f64::consts::PI * inscribed));
            let mut carried = neck_loop(l.kind, seed, l.seed, c, options, to.basis.len());
            carried.duplicates = l.duplicates.clone();
            carried.reason = format!(
                "{}; found on the simplified surface (length {:.6}) and cut again from the same {}",
                carried.reason,
                l.length,
                match l.initial {
                    Initial::Plane => "plane",
                    Initial::Membrane => "saddle's membrane",
                }
            );
            Ok(carried)
        })
        .collect();

    // The kept loops' new places in `loops`, for the duplicates that name them.
    let mut place = Vec::with_capacity(carried.len());
    let (mut loops, mut dropped) = (Vec::new(), found.dropped);
    for (l, outcome) in found.loops.iter().zip(carried) {
        match outcome {
            Ok(carried) => {
                place.push(Ok(loops.len()));
                loops.push(carried);
            }
            Err(reason) => {
                place.push(Err(reason));
                dropped.push(DroppedLoop {
                    kind: l.kind,
                    seed: l.seed,
                    saddle: l.saddle,
                    persistence: l.persistence,
                    reason,
                });
            }
        }
    }
    for d in &mut dropped {
        if let DropReason::Duplicate { of, .. } = d.reason {
            match place[of] {
                Ok(at) => {
                    if let DropReason::Duplicate { of, .. } = &mut d.reason {
                        *of = at;
                    }
                }
                // A duplicate of a loop that did not carry over goes with it.
                Err(reason) => d.reason = reason,
            }
        }
    }
    dropped.sort_by_key(|d| d.seed);
    Ok(LoopResult {
        loops,
        dropped,
        timings: found.timings,
    })
}
