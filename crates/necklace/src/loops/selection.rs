//! Step 3 of the loop stage: which tightened loops are kept, one per neck
//! ([`one_per_neck`]: cycle-closing loops one per independent Z2 class, necks by shape
//! one per lobe and class), then merged when they repeat one another and ordered
//! ([`select`]). Every loop not kept is a [`DroppedLoop`] with its reason.

use super::{
    fit_lasso, membrane, Candidate, DropReason, DroppedLoop, LoopOptions, LoopResult, NeckLoop,
    Role, Seed, TightenStatus, TighteningReport,
};
use crate::geom::{add, closest_on_segment, cross, dot, norm, scale, sub};
use crate::mesh::{Side, SurfaceMesh, Z2Basis};

/// One loop per neck. Cycle-closing loops: one per independent homology class, shortest
/// first; those that separate the surface or repeat a class are dropped, unless the
/// saddle is also a neck by its bulge (a stick of a ball-and-stick model closes a
/// cycle at one scale and cuts off a ball at another). Necks by bulge: one per lobe
/// and homology class, the largest bulge first (a separating saddle's loop may go
/// around a cycle too, e.g. a stick between two balls on a cage).
pub(super) fn one_per_neck(
    seeds: &[Seed],
    kind: Side,
    candidates: Vec<(usize, Candidate)>,
    options: &LoopOptions,
    dropped: &mut Vec<DroppedLoop>,
) -> Vec<(usize, Candidate)> {
    let (mut cycles, mut rest): (Vec<_>, Vec<_>) = candidates
        .into_iter()
        .partition(|(i, _)| seeds[*i].role == Some(Role::CycleClosing));
    // Cycles that are not necks by shape claim the classes first: a neck by shape is
    // kept anyway, so it should not take the class another cycle needs.
    cycles.sort_by(|(i, a), (j, b)| {
        (seeds[*i].bulge.is_some())
            .cmp(&seeds[*j].bulge.is_some())
            .then(a.tightened.length.total_cmp(&b.tightened.length))
            .then(i.cmp(j))
    });
    // But a cycle whose saddle lives less than a quarter as long as the longest-lived
    // one claims a class only if those necks by shape do not span it either. (In the
    // wire sphere's hollow a saddle living 3 of 32 levels took a class, with a loop 5.5
    // long round the hollow, before the two windows that are also necks by bulge, which
    // are kept anyway: 97 tunnel loops for 96 windows.)
    let longest = cycles
        .iter()
        .map(|(i, _)| seeds[*i].persistence)
        .max()
        .unwrap_or(0);
    let short_lived = |i: usize| 4 * seeds[i].persistence < longest;
    let by_shape: Vec<Vec<u64>> = cycles
        .iter()
        .filter(|(i, _)| seeds[*i].bulge.is_some())
        .map(|(_, c)| c.class.clone())
        .collect();
    let mut basis = Z2Basis::default();
    let mut kept: Vec<(usize, Vec<u64>)> = Vec::new();
    let mut necks = Vec::new();
    for (i, c) in cycles {
        let length = c.tightened.length;
        let spanned_by_shape = || {
            let mut both = basis.clone();
            for class in &by_shape {
                both.insert(class);
            }
            !both.insert(&c.class)
        };
        let reason = if c.class.iter().all(|w| *w == 0) {
            Some(DropReason::NotEssential { length })
        } else if short_lived(i) && seeds[i].bulge.is_none() && spanned_by_shape() {
            Some(DropReason::SameCycle { of: None, length })
        } else if basis.insert(&c.class) {
            None
        } else {
            Some(DropReason::SameCycle {
                of: kept.iter().find(|(_, k)| *k == c.class).map(|(j, _)| *j),
                length,
            })
        };
        match reason {
            Some(_) if seeds[i].bulge.is_some() => rest.push((i, c)),
            Some(reason) => dropped.push(DroppedLoop::new(kind, seeds, i, reason)),
            None => {
                kept.push((i, c.class.clone()));
                necks.push((i, c));
            }
        }
    }
    // Separating saddles that are not necks by their bulge must cut off a lobe fatter
    // than the neck (bulge > 1: not a bump whose top is the saddle's neighbour), and
    // open out on both sides round a roundish neck.
    let (rest, flat): (Vec<_>, Vec<_>) = rest.into_iter().partition(|(i, c)| {
        !seeds[*i].needs_opening
            || (seeds[*i].bulge.is_some_and(|b| b > 1.0)
                && c.opening.is_some_and(|o| o[0] >= options.min_opening)
                && c.flatness.is_some_and(|f| f <= options.max_flatness))
    });
    for (i, c) in flat {
        let reason = DropReason::NotANeck {
            bulge: seeds[i].bulge,
            opening: c.opening.map(|o| o[0]),
            flatness: c.flatness,
            length: c.tightened.length,
        };
        dropped.push(DroppedLoop::new(kind, seeds, i, reason));
    }
    // Necks by shape: one per (lobe, class), the largest bulge first.
    let mut rest = rest;
    rest.sort_by(|(i, _), (j, _)| {
        let bulge = |k: usize| seeds[k].bulge.unwrap_or(f64::INFINITY);
        bulge(*j).total_cmp(&bulge(*i)).then(i.cmp(j))
    });
    let mut by_lobe: Vec<(usize, usize, Vec<u64>)> = Vec::new();
    for (i, c) in rest {
        let same = seeds[i].lobe.and_then(|lobe| {
            by_lobe
                .iter()
                .find(|(l, _, class)| *l == lobe && *class == c.class)
                .map(|(_, j, _)| *j)
        });
        match same {
            Some(of) => dropped.push(DroppedLoop::new(
                kind,
                seeds,
                i,
                DropReason::SameLobe {
                    of,
                    length: c.tightened.length,
                },
            )),
            None => {
                if let Some(lobe) = seeds[i].lobe {
                    by_lobe.push((lobe, i, c.class.clone()));
                }
                necks.push((i, c));
            }
        }
    }
    necks
}

/// Order by persistence then length, and merge duplicates into the first of them.
pub(super) fn select(
    surface: &SurfaceMesh,
    seeds: &[Seed],
    kind: Side,
    mut candidates: Vec<(usize, Candidate)>,
    options: &LoopOptions,
    basis_len: usize,
    dropped: &mut Vec<DroppedLoop>,
) -> Vec<NeckLoop> {
    candidates.sort_by(|(i, a), (j, b)| {
        seeds[*j]
            .persistence
            .cmp(&seeds[*i].persistence)
            .then(a.tightened.length.total_cmp(&b.tightened.length))
            .then(i.cmp(j))
    });
    let diagonal = surface.bbox_diagonal();
    let mut loops: Vec<NeckLoop> = Vec::new();
    for (i, c) in candidates {
        let t = &c.tightened;
        let center = centroid(&t.points);
        let homology = class_string(&c.class, basis_len);
        let radius = t.length / (2.0 * std::f64::consts::PI);
        let duplicate_of = loops.iter().position(|l| {
            let close = norm(sub(l.center, center)) <= options.merge_distance * diagonal
                && (l.length - t.length).abs() <= options.merge_length * l.length.max(t.length);
            // The same neck reached from two saddles: the same class, and each loop
            // within half a radius of the other everywhere.
            let tolerance = options.merge_overlap * l.radius.min(radius);
            close
                || (l.homology == homology
                    && norm(sub(l.center, center)) <= l.radius + radius
                    && within(&l.points, &t.points, tolerance)
                    && within(&t.points, &l.points, tolerance))
        });
        if let Some(of) = duplicate_of {
            loops[of].duplicates.push(i);
            dropped.push(DroppedLoop::new(
                kind,
                seeds,
                i,
                DropReason::Duplicate {
                    of,
                    length: t.length,
                },
            ));
            continue;
        }
        loops.push(neck_loop(kind, &seeds[i], i, c, options, basis_len));
    }
    loops
}

/// The kept loop of seed `i` from its candidate; `basis_len` is the number of basis
/// cycles its class is written with.
pub(super) fn neck_loop(
    kind: Side,
    seed: &Seed,
    i: usize,
    c: Candidate,
    options: &LoopOptions,
    basis_len: usize,
) -> NeckLoop {
    let t = c.tightened;
    let membrane = membrane::spanning_disk(seed.position, seed.normal, &c.sources, &t.points);
    let homology = class_string(&c.class, basis_len);
    let how = match t.status {
        TightenStatus::Converged => "a closed geodesic",
        _ => "a loop whose last round no longer shortened it",
    };
    let reason = format!(
        "saddle persistence {}; tightened in {} rounds from {:.6} to {:.6}, {}; shorter than {} x diagonal",
        seed.persistence, t.rounds, t.initial_length, t.length, how, options.max_length
    );
    let center = centroid(&t.points);
    let normal = best_fit_normal(&t.points, center);
    NeckLoop {
        kind,
        lasso: Some(fit_lasso(&t.points, center, normal)),
        normal,
        center,
        radius: t.length / (2.0 * std::f64::consts::PI),
        saddle: seed.position,
        seed: i,
        persistence: seed.persistence,
        duplicates: Vec::new(),
        role: seed.role,
        birth_scale: seed.scales.0,
        death_scale: seed.scales.1,
        bulge: seed.bulge,
        separating: c.class.iter().all(|w| *w == 0),
        homology,
        areas: c.areas,
        opening: c.opening,
        flatness: c.flatness,
        reason,
        tightening: TighteningReport {
            status: t.status,
            rounds: t.rounds,
            updates: t.updates,
            max_edge_turn: t.max_edge_turn,
            min_vertex_angle: t.min_vertex_angle,
            simple: t.simple,
        },
        length: t.length,
        initial_length: t.initial_length,
        initial: c.initial,
        membrane,
        plane_offset: c.offset,
        points: t.points,
        surface_points: t.surface_points,
    }
}

/// Whether every point of `a` lies within `tolerance` of the closed polyline `b`.
fn within(a: &[[f64; 3]], b: &[[f64; 3]], tolerance: f64) -> bool {
    let n = b.len();
    a.iter().all(|&p| {
        (0..n).any(|i| norm(sub(p, closest_on_segment(p, b[i], b[(i + 1) % n]))) <= tolerance)
    })
}

/// A class as one `0`/`1` character per basis cycle.
fn class_string(class: &[u64], len: usize) -> String {
    (0..len)
        .map(|g| {
            if class[g / 64] >> (g % 64) & 1 == 1 {
                '1'
            } else {
                '0'
            }
        })
        .collect()
}

/// Length-weighted centroid of a closed polyline (each segment counts at its midpoint).
pub fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len();
    let mut sum = [0.0; 3];
    let mut total = 0.0;
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        let w = norm(sub(b, a));
        sum = add(sum, scale(add(a, b), 0.5 * w));
        total += w;
    }
    if total > 0.0 {
        scale(sum, 1.0 / total)
    } else {
        points.first().copied().unwrap_or([0.0; 3])
    }
}

/// Unit normal of the least-squares plane through the points (smallest principal axis of
/// their covariance), oriented along the loop's vector area.
pub fn best_fit_normal(points: &[[f64; 3]], center: [f64; 3]) -> [f64; 3] {
    let mut cov = nalgebra::Matrix3::<f64>::zeros();
    for p in points {
        let d = nalgebra::Vector3::from(sub(*p, center));
        cov += d * d.transpose();
    }
    let eig = nalgebra::SymmetricEigen::new(cov);
    let k = eig.eigenvalues.imin();
    let e = eig.eigenvectors.column(k);
    let mut normal = [e[0], e[1], e[2]];
    let n = points.len();
    let mut area = [0.0; 3];
    for i in 0..n {
        area = add(
            area,
            cross(sub(points[i], center), sub(points[(i + 1) % n], center)),
        );
    }
    if dot(area, normal) < 0.0 {
        normal = scale(normal, -1.0);
    }
    let l = norm(normal);
    if l > 0.0 {
        scale(normal, 1.0 / l)
    } else {
        normal
    }
}

/// Loops for the homology classes the selected saddles' loops miss: `extra` (found from
/// the Morse stage's completions, seeds numbered from `offset` on in the run) is added
/// to `found`, each loop only where its class is independent of every loop there and
/// of those added before it, shortest first, after the loops of `found`. A loop of
/// `extra` whose class is exactly that of a longer cycle-closing loop of `found` that
/// is not a neck by its bulge takes that loop's place (one loop per class, shortest
/// first, as among the selected saddles' own loops): the class stays spanned, by the
/// shorter loop. Every other loop of `extra`, and every loop replaced, is dropped as
/// the same cycle; seeds and references are renumbered into the run's.
pub fn complete_classes(found: &mut LoopResult, extra: LoopResult, offset: usize) {
    let mut basis = Z2Basis::default();
    // The classes of `found`'s loops, kept in step with them (each is parsed once).
    let mut classes: Vec<Vec<u64>> = found.loops.iter().map(NeckLoop::class).collect();
    for class in &classes {
        basis.insert(class);
    }
    let mut order: Vec<usize> = (0..extra.loops.len()).collect();
    order.sort_by(|&a, &b| {
        extra.loops[a]
            .length
            .total_cmp(&extra.loops[b].length)
            .then(a.cmp(&b))
    });
    // Per loop of `extra`: its index in `found` once kept.
    let mut placed = vec![None; extra.loops.len()];
    let mut loops: Vec<Option<NeckLoop>> = extra.loops.into_iter().map(Some).collect();
    for k in order {
        let Some(mut l) = loops[k].take() else {
            continue;
        };
        l.seed += offset;
        l.duplicates.iter_mut().for_each(|d| *d += offset);
        let class = l.class();
        if !l.separating && basis.insert(&class) {
            l.reason = format!(
                "completes the genus: its vertex closes a class of it that no selected saddle's loop reaches, and its plane's curve bounds a disk; {}",
                l.reason
            );
            placed[k] = Some(found.loops.len());
            found.loops.push(l);
            classes.push(class);
            continue;
        }
        let of = classes.iter().position(|kept| *kept == class);
        if let Some(j) = of.filter(|&j| !l.separating && replaceable(&found.loops[j], &l)) {
            let replaced = std::mem::replace(&mut found.loops[j], l);
            let kept = &mut found.loops[j];
            kept.reason = format!(
                "a shorter loop of the class of seed {}'s loop ({:.5} long), which it replaces: its vertex closes that class, and its plane's curve bounds a disk; {}",
                replaced.seed, replaced.length, kept.reason
            );
            placed[k] = Some(j);
            let (seed, length) = (kept.seed, replaced.length);
            // The replaced loop's duplicates, and loops dropped as its class, now
            // name the loop kept in its place.
            for d in &mut found.dropped {
                d.reason = match d.reason {
                    DropReason::Duplicate { of, length } if of == j => DropReason::SameCycle {
                        of: Some(seed),
                        length,
                    },
                    DropReason::SameCycle {
                        of: Some(of),
                        length,
                    } if of == replaced.seed => DropReason::SameCycle {
                        of: Some(seed),
                        length,
                    },
                    reason => reason,
                };
            }
            found.dropped.push(DroppedLoop {
                kind: replaced.kind,
                seed: replaced.seed,
                saddle: replaced.saddle,
                persistence: replaced.persistence,
                reason: DropReason::SameCycle {
                    of: Some(seed),
                    length,
                },
            });
            continue;
        }
        let reason = if l.separating {
            DropReason::NotEssential { length: l.length }
        } else {
            DropReason::SameCycle {
                of: of.map(|j| found.loops[j].seed),
                length: l.length,
            }
        };
        // Its duplicates are in `extra.dropped`, renumbered below.
        found.dropped.push(DroppedLoop {
            kind: l.kind,
            seed: l.seed,
            saddle: l.saddle,
            persistence: l.persistence,
            reason,
        });
    }
    for mut d in extra.dropped {
        d.seed += offset;
        d.reason = match d.reason {
            DropReason::SameCycle { of, length } => DropReason::SameCycle {
                of: of.map(|s| s + offset),
                length,
            },
            DropReason::Duplicate { of, length } => match placed.get(of).copied().flatten() {
                Some(kept) => DropReason::Duplicate { of: kept, length },
                None => DropReason::SameCycle { of: None, length },
            },
            reason => reason,
        };
        found.dropped.push(d);
    }
    found.dropped.sort_by_key(|d| d.seed);
    found.timings.preparation += extra.timings.preparation;
    found.timings.cut_and_tighten += extra.timings.cut_and_tighten;
    found.timings.selection += extra.timings.selection;
}

/// Whether `shorter`, a completion's loop of exactly `kept`'s class, takes its place:
/// `kept` closes a cycle, is not a neck by its bulge (those are kept for their lobe),
/// and is longer.
fn replaceable(kept: &NeckLoop, shorter: &NeckLoop) -> bool {
    kept.role == Some(Role::CycleClosing) && kept.bulge.is_none() && shorter.length < kept.length
}
