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

use super::cut::Crossing;
use super::membrane::{dual_path, shared_edge, without_backtracking, DualGraph};
use super::tighten::tighten;
use super::{
    around_point, centroid, cutting_normals, membrane_loop, neck_loop, tightened, tightening,
    Initial, LoopOptions, LoopResult, LoopSurface, Seed,
};
use super::{DropReason, DroppedLoop, LoopMemo, NeckLoop};
use crate::distance::SurfaceDistance;
use crate::error::{Error, Result};
use crate::geom::{add, norm, scale, sub};
use crate::mesh::{SurfaceMesh, Topology};

/// A loop carried back may be longer or shorter than the copy's by this fraction.
pub const SAME_LENGTH: f64 = 0.05;

/// ... and its centre this many of the copy loop's radii away from the copy's.
pub const SAME_CENTER: f64 = 0.5;

/// How a loop is rebuilt on the surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Way {
    /// As on the copy: the same plane, or the saddle's membrane.
    Same,
    /// The faces under the copy's loop, joined by shortest face paths.
    Traced,
    /// The best-fit plane of the copy's loop.
    LoopPlane,
}

/// The strip of faces of `surface` under the closed polyline `points` (a loop on a copy
/// of it): each point's closest face, consecutive ones joined by shortest face paths,
/// steps straight back removed; with the edges it crosses (at their midpoints), as the
/// tightening takes an initial loop. `None` where two faces are not joined within the
/// membrane's search limit or the strip closes on itself.
fn traced(
    (topology, dual): (&Topology, &DualGraph),
    distance: &SurfaceDistance,
    points: &[[f64; 3]],
    options: &LoopOptions,
) -> Option<(Vec<Crossing>, Vec<u32>)> {
    let mut faces: Vec<u32> = points
        .iter()
        .map(|&p| distance.closest_point(p).face)
        .collect();
    faces.dedup();
    if faces.first() == faces.last() && faces.len() > 1 {
        faces.pop();
    }
    let mut cycle = Vec::new();
    for (i, &f) in faces.iter().enumerate() {
        let g = faces[(i + 1) % faces.len()];
        let path = dual_path(dual, f, g, options.membrane.max_settled)?;
        cycle.extend_from_slice(&path[..path.len() - 1]);
    }
    let cycle = without_backtracking(cycle);
    let mut seen = cycle.clone();
    seen.sort_unstable();
    seen.dedup();
    if cycle.len() < 3 || seen.len() < cycle.len() {
        return None;
    }
    let crossings = (0..cycle.len())
        .map(|i| {
            let prev = cycle[(i + cycle.len() - 1) % cycle.len()];
            shared_edge(topology, prev, cycle[i]).map(|edge| Crossing { edge, t: 0.5 })
        })
        .collect::<Option<Vec<_>>>()?;
    Some((crossings, cycle))
}

/// Whether a loop (`points`, `length`) is the neck of the copy's loop `l`.
fn same_neck(points: &[[f64; 3]], length: f64, l: &NeckLoop) -> bool {
    (length - l.length).abs() <= SAME_LENGTH * l.length
        && norm(sub(centroid(points), l.center)) <= SAME_CENTER * l.radius
}

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
    let cutter = to.cutter(surface);
    // The input's planes (a memo serves one surface).
    let memo = LoopMemo::default();
    let carried: Vec<std::result::Result<NeckLoop, DropReason>> = found
        .loops
        .par_iter()
        .map(|l| {
            let seed = &seeds[l.seed];
            let (n, normals) = cutting_normals(seed, options);
            let (mut status, mut other) = (None, None);
            for way in [Way::Same, Way::Traced, Way::LoopPlane] {
                let start = match (way, l.initial) {
                    (Way::Same, Initial::Plane) => {
                        let point = add(seed.position, scale(n, l.plane_offset));
                        around_point(
                            &cutter,
                            &memo,
                            &normals,
                            point,
                            seed.disk_only.then_some(l.kind),
                            false,
                        )
                        .0
                        .map(|(_, c)| (c.crossings, c.faces, Vec::new()))
                    }
                    (Way::Same, Initial::Membrane) => membrane_loop(
                        surface,
                        &to.topology,
                        &to.dual,
                        distance,
                        seed.position,
                        n,
                        &options.membrane,
                    )
                    .ok()
                    .map(|m| (m.crossings, m.faces, m.sources)),
                    // The turned plane's direction was the simplified surface's choice:
                    // the faces under the loop and its best-fit plane carry it over.
                    // A linked loop is made on the input, never carried.
                    (Way::Same, Initial::TurnedPlane | Initial::Linked) => None,
                    (Way::Traced, _) => {
                        traced((&to.topology, &to.dual), distance, &l.points, options)
                            .map(|(crossings, faces)| (crossings, faces, Vec::new()))
                    }
                    (Way::LoopPlane, _) => around_point(
                        &cutter,
                        &memo,
                        &[l.normal],
                        l.center,
                        seed.disk_only.then_some(l.kind),
                        false,
                    )
                    .0
                    .map(|(_, c)| (c.crossings, c.faces, Vec::new())),
                };
                let Some((crossings, faces, sources)) = start else {
                    continue;
                };
                let t = tighten(&geometry, &crossings, &faces, &tightening(seed, options));
                status = Some(t.status);
                let Ok(t) = tightened(t) else { continue };
                if !same_neck(&t.points, t.length, l) {
                    other = Some(t.length);
                    continue;
                }
                let mut c = measures.candidate(t, l.plane_offset, l.initial, true);
                c.sources = sources;
                let inscribed = distance.distance(seed.position);
                c.flatness = (inscribed > 0.0)
                    .then(|| c.tightened.length / (2.0 * std::f64::consts::PI * inscribed));
                let mut carried = neck_loop(l.kind, seed, l.seed, c, options, to.basis.len());
                carried.duplicates = l.duplicates.clone();
                carried.reason = format!(
                    "{}; found on the simplified surface (length {:.6}) and cut again from {}",
                    carried.reason,
                    l.length,
                    match (way, l.initial) {
                        (Way::Same, Initial::Plane) => "the same plane",
                        (Way::Same, Initial::Membrane) => "the saddle's membrane",
                        (Way::Same, Initial::TurnedPlane) => "a turned plane",
                        (Way::Same, Initial::Linked) => "the linked search",
                        (Way::Traced, _) => "the faces under that loop",
                        (Way::LoopPlane, _) => "the best-fit plane of that loop",
                    }
                );
                return Ok(carried);
            }
            Err(DropReason::NotTransferred {
                length: l.length,
                other,
                tightening: status,
            })
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
