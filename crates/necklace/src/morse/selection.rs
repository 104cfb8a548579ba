//! Step 4 of the Morse stage: which 2-saddles are necks (see the module doc). Scale
//! space: [`select_over_scales`] judges each track over its whole life; the paper's
//! schedule: [`select_at_last_step`] judges what is alive at the last step. Both merge
//! saddles closer than the matching radius ([`merge_close`]); [`barcode`] draws every
//! track's life.

use super::{
    hessian_at, mean_edge_length, newton_point, Bar, Followed, Hessian, MorseOptions, NormalSource,
    Observation, RejectReason, RejectedSaddle, Saddle, SaddleRole, Track, VertexType,
};
use crate::geom::{norm, sub};
use crate::tet::TetMesh;

/// What a selection returns.
pub(super) struct Selection {
    /// The selected saddles.
    pub saddles: Vec<Saddle>,
    /// Every other 2-saddle track, and why.
    pub rejected: Vec<RejectedSaddle>,
    /// Scale space only: the vertices that close essential cycles, cut several ways
    /// (see [`MorseResult::completions`](super::MorseResult::completions)).
    pub completions: Vec<Saddle>,
}

/// The scale-space selection (see the module doc).
pub(super) fn select_over_scales(
    mesh: &TetMesh,
    tracks: &[Track],
    observations: &[Vec<Observation>],
    (followed, levels): (&[Followed], usize),
    options: &MorseOptions,
    scale_of: &dyn Fn(usize) -> Option<f64>,
) -> Selection {
    let mut candidates = Vec::new();
    let mut rejected = Vec::new();
    for (t, track) in tracks.iter().enumerate() {
        if track.kind != VertexType::Saddle2 {
            continue;
        }
        let Some(seen) = observations.get(t).filter(|o| !o.is_empty()) else {
            continue;
        };
        let last = seen[seen.len() - 1];
        let birth_scale = scale_of(track.born).unwrap_or(0.0);
        let death_scale = if track.alive {
            None
        } else {
            scale_of(track.last_seen + 1)
        };
        let reject = |o: &Observation, reason| RejectedSaddle {
            vertex: o.vertex,
            position: o.position,
            born: track.born,
            birth_scale,
            death_scale,
            reason,
        };
        if track.persistence() + 1 < options.min_levels {
            rejected.push(reject(
                &last,
                RejectReason::ShortLived {
                    persistence: track.persistence(),
                },
            ));
            continue;
        }
        let fitted: Vec<(&Observation, Hessian)> = seen
            .iter()
            .filter_map(|o| o.hessian.filter(|h| h.is_two_saddle()).map(|h| (o, h)))
            .collect();
        if fitted.is_empty() {
            let reason = match seen.iter().rev().find_map(|o| o.hessian) {
                Some(h) => RejectReason::HessianSignature {
                    eigenvalues: h.eigenvalues,
                },
                None => RejectReason::NoFit,
            };
            rejected.push(reject(&last, reason));
            continue;
        }
        let cycle = fitted
            .iter()
            .find(|(o, _)| o.role.role == SaddleRole::CycleClosing);
        // The separating level of the largest bulge (the outer sphere's lobe counts as
        // infinitely fat), the earlier on ties.
        let widest = fitted
            .iter()
            .filter(|(o, _)| o.role.role == SaddleRole::Separating)
            .max_by(|a, b| {
                let bulge = |o: &Observation| o.role.bulge.unwrap_or(f64::INFINITY);
                bulge(a.0)
                    .total_cmp(&bulge(b.0))
                    .then(b.0.step.cmp(&a.0.step))
            });
        let widest_bulge = widest.map(|(o, _)| o.role.bulge.unwrap_or(f64::INFINITY));
        let (o, h, role) = match (cycle, widest) {
            // Cycle-closing: placed at its first fitted level, the least smoothed
            // (heat moves a window's saddle inwards as the scale grows).
            (Some(_), _) => (fitted[0].0, fitted[0].1, SaddleRole::CycleClosing),
            (None, None) => {
                rejected.push(reject(&last, RejectReason::LocalCycle));
                continue;
            }
            // Separating: placed at its level of the largest bulge. Below `min_bulge` it
            // is still a candidate, which the loop stage keeps if its loop opens out on
            // both sides (`loops::opening`); but not when its lobe is no fatter than the
            // neck at all.
            (None, Some(&(o, h))) => {
                let bulge = widest_bulge.unwrap_or(f64::INFINITY);
                if bulge <= 1.0 {
                    rejected.push(reject(o, RejectReason::LowBulge { bulge }));
                    continue;
                }
                (o, h, SaddleRole::Separating)
            }
        };
        let by_bulge = widest_bulge.is_some_and(|b| b >= options.min_bulge);
        // A neck by its shape: separating, or cycle-closing and separating with a
        // passing bulge at another level.
        let necked = widest
            .filter(|(w, _)| {
                role == SaddleRole::Separating
                    || w.role.bulge.is_some_and(|b| b >= options.min_bulge)
            })
            .map(|(w, _)| w);
        candidates.push(Saddle {
            vertex: o.vertex,
            position: newton_point(o.position, &h, o.radius),
            vertex_position: o.position,
            value: o.value,
            step: o.step,
            scale: scale_of(o.step).unwrap_or(0.0),
            born: track.born,
            persistence: track.persistence(),
            birth_scale,
            death_scale,
            role,
            bulge: necked.and_then(|w| w.role.bulge),
            by_bulge,
            lobe: necked.and_then(|w| w.lobe),
            essential: fitted.iter().any(|(o, _)| o.role.essential),
            hessian: h,
            normal: h.normal(),
            normal_from: NormalSource::Hessian,
        });
    }
    let (kept, duplicates) = merge_close(mesh, candidates, options.track_radius);
    rejected.extend(duplicates);
    Selection {
        saddles: kept,
        rejected,
        completions: cut_ways(completions(followed, levels, scale_of)),
    }
}

/// The completions (see [`MorseResult::completions`](super::MorseResult::completions))
/// from the closings of essential cycles followed over the levels (`record_closings`):
/// each placed at its first closing, with that closing's upper-link axis for normal;
/// its persistence is the levels it was seen at, less one. Most persistent first, then
/// by level and vertex.
fn completions(
    followed: &[Followed],
    levels: usize,
    scale_of: &dyn Fn(usize) -> Option<f64>,
) -> Vec<(Saddle, Option<[f64; 3]>)> {
    let mut out: Vec<(Saddle, Option<[f64; 3]>)> = followed
        .iter()
        .map(
            |&Followed {
                 first,
                 last_step,
                 seen,
                 ..
             }| {
                let saddle = Saddle {
                    vertex: first.vertex,
                    position: first.position,
                    vertex_position: first.position,
                    value: first.value,
                    step: first.step,
                    scale: scale_of(first.step).unwrap_or(0.0),
                    born: first.step,
                    persistence: seen - 1,
                    birth_scale: scale_of(first.step).unwrap_or(0.0),
                    death_scale: if last_step >= levels {
                        None
                    } else {
                        scale_of(last_step + 1)
                    },
                    role: SaddleRole::CycleClosing,
                    bulge: None,
                    by_bulge: false,
                    lobe: None,
                    essential: true,
                    hessian: first.hessian,
                    normal: first.axis,
                    normal_from: NormalSource::UpperLink,
                };
                (saddle, first.cycle_normal)
            },
        )
        .collect();
    out.sort_by(|(a, _), (b, _)| {
        b.persistence
            .cmp(&a.persistence)
            .then(a.step.cmp(&b.step))
            .then(a.vertex.cmp(&b.vertex))
    });
    out
}

/// Each completion cut up to five ways: along its upper link's axis, along its
/// cycle's normal where it has one, then along each of its Hessian's eigenvectors.
fn cut_ways(completions: Vec<(Saddle, Option<[f64; 3]>)>) -> Vec<Saddle> {
    completions
        .into_iter()
        .flat_map(|(c, cycle)| {
            let around = cycle.map(|normal| Saddle {
                normal,
                normal_from: NormalSource::Cycle,
                ..c
            });
            std::iter::once(c)
                .chain(around)
                .chain((0..3).map(move |k| Saddle {
                    normal: c.hessian.eigenvectors[k],
                    normal_from: NormalSource::Eigenvector { index: k },
                    ..c
                }))
        })
        .collect()
}

/// The paper's selection: the 2-saddle tracks alive at the last step.
pub(super) fn select_at_last_step(
    mesh: &TetMesh,
    f: &[f64],
    tracks: &[Track],
    observations: &[Vec<Observation>],
    min_persistence: usize,
    (track_radius, min_bulge): (f64, f64),
    scale_of: &dyn Fn(usize) -> Option<f64>,
) -> Selection {
    let mut saddles = Vec::new();
    let mut rejected = Vec::new();
    for (t, track) in tracks
        .iter()
        .enumerate()
        .filter(|(_, t)| t.alive && t.kind == VertexType::Saddle2)
    {
        let birth_scale = scale_of(track.born).unwrap_or(0.0);
        let reject = |reason| RejectedSaddle {
            vertex: track.vertex,
            position: track.position,
            born: track.born,
            birth_scale,
            death_scale: None,
            reason,
        };
        if track.persistence() < min_persistence {
            rejected.push(reject(RejectReason::ShortLived {
                persistence: track.persistence(),
            }));
            continue;
        }
        let last = observations.get(t).and_then(|o| o.last());
        match hessian_at(mesh, f, track.vertex) {
            None => rejected.push(reject(RejectReason::NoFit)),
            Some(h) if !h.is_two_saddle() => {
                rejected.push(reject(RejectReason::HessianSignature {
                    eigenvalues: h.eigenvalues,
                }))
            }
            Some(h) => saddles.push(Saddle {
                vertex: track.vertex,
                position: newton_point(track.position, &h, track.radius),
                vertex_position: track.position,
                value: f[track.vertex as usize],
                step: track.last_seen,
                scale: scale_of(track.last_seen).unwrap_or(0.0),
                born: track.born,
                persistence: track.persistence(),
                birth_scale,
                death_scale: None,
                role: last.map_or(SaddleRole::CycleClosing, |o| o.role.role),
                bulge: last.and_then(|o| o.role.bulge),
                by_bulge: last
                    .and_then(|o| o.role.bulge)
                    .is_some_and(|b| b >= min_bulge),
                lobe: last.and_then(|o| o.lobe),
                essential: last.is_some_and(|o| o.role.essential),
                hessian: h,
                normal: h.normal(),
                normal_from: NormalSource::Hessian,
            }),
        }
    }
    let (kept, duplicates) = merge_close(mesh, saddles, track_radius);
    rejected.extend(duplicates);
    Selection {
        saddles: kept,
        rejected,
        completions: Vec::new(),
    }
}

/// Saddles within the matching radius of a more persistent one (then one with a
/// shorter Newton step; a neck by its cycle or bulge before one the loop stage still
/// judges) are duplicates of it. Returns the kept ones in that order, and the
/// duplicates.
pub(super) fn merge_close(
    mesh: &TetMesh,
    mut saddles: Vec<Saddle>,
    track_radius: f64,
) -> (Vec<Saddle>, Vec<RejectedSaddle>) {
    let step = |s: &Saddle| norm(sub(s.position, s.vertex_position));
    // A saddle that is a neck already (by its cycle or its bulge) before one that the
    // loop stage still has to judge.
    let pending = |s: &Saddle| s.role == SaddleRole::Separating && !s.by_bulge;
    saddles.sort_by(|a, b| {
        pending(a)
            .cmp(&pending(b))
            .then(b.persistence.cmp(&a.persistence))
            .then(step(a).total_cmp(&step(b)))
            .then(a.vertex.cmp(&b.vertex))
            .then(a.step.cmp(&b.step))
    });
    let mut kept: Vec<Saddle> = Vec::new();
    let mut rejected = Vec::new();
    for s in saddles {
        let radius = track_radius * mean_edge_length(mesh, s.vertex as usize);
        match kept
            .iter()
            .find(|k| norm(sub(k.position, s.position)) <= radius)
        {
            Some(k) => rejected.push(s.rejected(RejectReason::Duplicate { of: k.vertex })),
            None => kept.push(s),
        }
    }
    (kept, rejected)
}

/// One bar per 2-saddle track that was observed, by birth scale.
pub(super) fn barcode(
    tracks: &[Track],
    observations: &[Vec<Observation>],
    saddles: &[Saddle],
    scale_of: &dyn Fn(usize) -> Option<f64>,
) -> Vec<Bar> {
    let mut bars: Vec<Bar> = tracks
        .iter()
        .enumerate()
        .filter(|(t, track)| {
            track.kind == VertexType::Saddle2 && observations.get(*t).is_some_and(|o| !o.is_empty())
        })
        .map(|(t, track)| {
            let seen = &observations[t];
            let saddle = saddles.iter().position(|s| {
                s.born == track.born
                    && seen
                        .iter()
                        .any(|o| o.vertex == s.vertex && o.step == s.step)
            });
            Bar {
                birth_scale: scale_of(track.born).unwrap_or(0.0),
                death_scale: if track.alive {
                    None
                } else {
                    scale_of(track.last_seen + 1)
                },
                cycle_closing: seen.iter().any(|o| o.role.role == SaddleRole::CycleClosing),
                vertex: track.vertex,
                selected: saddle.is_some(),
                saddle,
            }
        })
        .collect();
    bars.sort_by(|a, b| {
        a.birth_scale
            .total_cmp(&b.birth_scale)
            .then(a.vertex.cmp(&b.vertex))
    });
    bars
}
