//! What one loop search hands the next on the same surface ([`LoopMemo`]): the pipeline
//! cuts a side's seeds again, keeping only curves that bound a disk, where the first
//! loops span more classes than the genus, and then cuts the completions. Those searches
//! cut the same planes and tighten the same curves as the first, with only the length a
//! tightening may shrink to changed ([`Seed::disk_only`](super::Seed::disk_only)).
//!
//! Everything remembered is what the work would give again, bit for bit, so a search
//! gives the same loops with a memo, a fresh one or another search's, whatever the
//! thread count:
//! - a tightening, by its curve (crossings and faces) and options, for every length
//!   ratio at or below its own; one that stopped only because the loop fell below its
//!   ratio is carried on from there under a smaller one ([`Tightening::resume`]);
//! - for a point and the normals of its planes, that no closed curve of those planes goes
//!   round it, with the curve counts of the first plane.
//!
//! The memo holds at most [`MAX_REMEMBERED_BYTES`] of tightenings (a cache: past it,
//! tightenings are no longer remembered and are done again where asked; no result
//! depends on it).
//!
//! Entry point: [`LoopMemo`], passed to
//! [`find_loops_with_progress`](super::find_loops_with_progress).

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use super::cut::Crossing;
use super::tighten::{tighten_resumable, SurfaceGeometry, Tightening};
use super::{LoopSurface, SurfacePoint, TightenOptions, TightenStatus, Tightened};
use crate::mesh::SurfaceMesh;

/// The bytes of remembered tightenings (curves, results and stopped states) past which
/// no more are remembered.
pub const MAX_REMEMBERED_BYTES: usize = 128 << 20;

/// A plane's closed and open curve counts.
pub(super) type CurveCounts = (usize, usize);

/// What loop searches on one surface with the same [`LoopOptions`](super::LoopOptions)
/// hand each other (see the module's documentation). A memo serves one surface: every
/// search given it must cut that surface.
#[derive(Default)]
pub struct LoopMemo {
    surface: OnceLock<LoopSurface>,
    tightened: Mutex<Tightenings>,
    no_curve: Mutex<HashMap<Vec<u64>, Option<CurveCounts>>>,
}

#[derive(Default)]
struct Tightenings {
    by_curve: HashMap<Vec<u64>, Vec<Remembered>>,
    bytes: usize,
}

/// A tightening as remembered: its result for `ratio`, and where the loop stopped
/// only because it fell below that ratio, the state to carry on from under a smaller
/// one. Without a state it ended for a reason of its own: the result stands for every
/// smaller ratio too.
struct Remembered {
    ratio: f64,
    result: Tightened,
    stopped: Option<Box<Tightening>>,
}

impl LoopMemo {
    /// The surface's topology, basis and tree, built on the first call (`surface` must be
    /// the memo's surface).
    pub(super) fn surface(&self, surface: &SurfaceMesh) -> &LoopSurface {
        self.surface.get_or_init(|| LoopSurface::new(surface))
    }

    /// [`tighten`](super::tighten::tighten) of the curve, or what an earlier call gave
    /// for it.
    pub(super) fn tighten(
        &self,
        geometry: &SurfaceGeometry,
        crossings: &[Crossing],
        faces: &[u32],
        options: &TightenOptions,
    ) -> Tightened {
        let key = curve_key(crossings, faces, options);
        let ratio = options.min_length_ratio;
        // A result to take, or a stopped state to carry on.
        let resumable = {
            let memo = self.tightened.lock().expect("memo lock");
            let mut resumable = None;
            for r in memo.by_curve.get(&key).into_iter().flatten() {
                match &r.stopped {
                    None if ratio <= r.ratio => return r.result.clone(),
                    Some(_) if ratio == r.ratio => return r.result.clone(),
                    Some(state) if ratio < r.ratio => resumable = Some(Tightening::clone(state)),
                    _ => {}
                }
            }
            resumable
        };
        let (result, stopped) = match resumable.and_then(|s| s.resume(geometry, options)) {
            Some(carried) => carried,
            None => tighten_resumable(geometry, crossings, faces, options),
        };
        debug_assert!(stopped.is_none() || result.status == TightenStatus::Collapsed);
        let size = 8 * key.len()
            + result.points.len() * size_of::<[f64; 3]>()
            + result.surface_points.len() * size_of::<SurfacePoint>()
            + stopped.as_ref().map_or(0, Tightening::bytes);
        let remembered = Remembered {
            ratio,
            result: result.clone(),
            stopped: stopped.map(Box::new),
        };
        let mut memo = self.tightened.lock().expect("memo lock");
        if memo.bytes + size <= MAX_REMEMBERED_BYTES {
            memo.bytes += size;
            memo.by_curve.entry(key).or_default().push(remembered);
        }
        result
    }

    /// Where an earlier search found no closed curve round `point` in the planes
    /// through it with these `normals`: the first plane's closed and open curve counts,
    /// if that search counted them.
    pub(super) fn no_curve_round(
        &self,
        point: [f64; 3],
        normals: &[[f64; 3]],
    ) -> Option<Option<CurveCounts>> {
        let memo = self.no_curve.lock().expect("memo lock");
        memo.get(&planes_key(point, normals)).copied()
    }

    /// No closed curve of these planes goes round `point`; the first plane has
    /// `counts` closed and open curves (`None`: not counted). Counts already known stay.
    pub(super) fn remember_no_curve(
        &self,
        point: [f64; 3],
        normals: &[[f64; 3]],
        counts: Option<CurveCounts>,
    ) {
        let mut memo = self.no_curve.lock().expect("memo lock");
        let known = memo.entry(planes_key(point, normals)).or_insert(counts);
        if known.is_none() {
            *known = counts;
        }
    }
}

/// A curve and the options (all but the length ratio) as bits.
fn curve_key(crossings: &[Crossing], faces: &[u32], options: &TightenOptions) -> Vec<u64> {
    let mut key = Vec::with_capacity(5 + 2 * crossings.len());
    key.push(crossings.len() as u64);
    key.push(faces.len() as u64);
    key.push(options.max_rounds as u64);
    key.push(options.rel_tolerance.to_bits());
    key.push(options.angle_tolerance.to_bits());
    for (c, &f) in crossings.iter().zip(faces) {
        key.push(u64::from(c.edge) << 32 | u64::from(f));
        key.push(c.t.to_bits());
    }
    key
}

/// A point and normals as bits.
fn planes_key(point: [f64; 3], normals: &[[f64; 3]]) -> Vec<u64> {
    std::iter::once(point)
        .chain(normals.iter().copied())
        .flat_map(|p| p.map(f64::to_bits))
        .collect()
}
