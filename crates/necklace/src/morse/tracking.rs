//! Tracking critical points from one smoothing step to the next (paper sec. 4.2,
//! "evolution-based selection").
//!
//! After each classified step, the critical points of each type are matched to the
//! tracks alive at the previous step by nearest neighbour (a k-d tree per type): every
//! pair closer than the new point's matching radius is a candidate, and candidates are
//! taken greedily, closest first (ties by vertex, then track), each point and track at
//! most once. A matched track *moves* when its vertex changes; an unmatched point starts
//! a track (*birth*); an unmatched track ends (*death*). Two tracks of index k and k + 1
//! dying at the same step within matching distance of each other *cancel* (again
//! greedily, closest first). Persistence of a track = the number of steps it survived:
//! `last step alive − step born`. Everything is sequential or sorted, so the result does
//! not depend on the thread count. Entry point: [`Tracker::advance`].

use std::collections::HashMap;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use serde::{Deserialize, Serialize};

use super::critical::VertexType;

/// A critical point at one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CriticalPoint {
    /// Its vertex.
    pub vertex: u32,
    /// Its type (not `Regular` or `Boundary`).
    pub kind: VertexType,
    /// The vertex position.
    pub position: [f64; 3],
    /// How far it may have moved since the previous step and still be the same point.
    pub radius: f64,
}

/// The life of one critical point over the smoothing steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Track {
    /// Its type.
    pub kind: VertexType,
    /// First step it was seen.
    pub born: usize,
    /// Last step it was seen (the current step while alive).
    pub last_seen: usize,
    /// Whether it was seen at the latest step.
    pub alive: bool,
    /// Vertex where it was last seen.
    pub vertex: u32,
    /// Position where it was last seen.
    pub position: [f64; 3],
    /// Its matching radius where it was last seen.
    pub radius: f64,
    /// How many steps it changed vertex.
    pub moves: usize,
    /// The track it cancelled with when it died, if any.
    pub cancelled_with: Option<usize>,
}

impl Track {
    /// Steps survived: `last_seen − born`.
    pub fn persistence(&self) -> usize {
        self.last_seen - self.born
    }
}

/// What happened between two classified steps.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StepEvents {
    /// New tracks (every point, at the first step).
    pub births: usize,
    /// Tracks that ended.
    pub deaths: usize,
    /// Tracks that changed vertex.
    pub moves: usize,
    /// Pairs of index k and k + 1 that died together.
    pub cancellations: usize,
}

/// All tracks so far.
#[derive(Debug, Clone, Default)]
pub struct Tracker {
    /// Every track ever started, in order of birth (then vertex).
    pub tracks: Vec<Track>,
}

/// Morse index of a type, for cancellations (`None` for degenerate points).
fn index(kind: VertexType) -> Option<u8> {
    match kind {
        VertexType::Minimum => Some(0),
        VertexType::Saddle1 => Some(1),
        VertexType::Saddle2 => Some(2),
        VertexType::Maximum => Some(3),
        _ => None,
    }
}

const KINDS: [VertexType; 5] = [
    VertexType::Minimum,
    VertexType::Saddle1,
    VertexType::Saddle2,
    VertexType::Maximum,
    VertexType::Degenerate,
];

impl Tracker {
    /// An empty tracker.
    pub fn new() -> Tracker {
        Tracker::default()
    }

    /// Match the critical points of `step` to the tracks alive at the previous one.
    pub fn advance(&mut self, step: usize, points: &[CriticalPoint]) -> StepEvents {
        let mut events = StepEvents::default();
        let mut dying: Vec<usize> = Vec::new();
        for kind in KINDS {
            let new: Vec<&CriticalPoint> = points.iter().filter(|p| p.kind == kind).collect();
            let old: Vec<usize> = (0..self.tracks.len())
                .filter(|&t| self.tracks[t].alive && self.tracks[t].kind == kind)
                .collect();
            let queries: Vec<_> = new.iter().map(|p| (p.position, p.radius)).collect();
            let targets: Vec<_> = old.iter().map(|&t| self.tracks[t].position).collect();
            let (matches, new_taken, old_taken) = greedy_matching(&queries, &targets);
            for (i, j) in matches {
                let track = &mut self.tracks[old[j]];
                if track.vertex != new[i].vertex {
                    track.moves += 1;
                    events.moves += 1;
                }
                track.vertex = new[i].vertex;
                track.position = new[i].position;
                track.radius = new[i].radius;
                track.last_seen = step;
            }
            dying.extend(
                old.iter()
                    .zip(&old_taken)
                    .filter(|(_, &taken)| !taken)
                    .map(|(&t, _)| t),
            );
            let mut born: Vec<&CriticalPoint> = new
                .iter()
                .zip(&new_taken)
                .filter(|(_, &taken)| !taken)
                .map(|(&p, _)| p)
                .collect();
            born.sort_by_key(|p| p.vertex);
            events.births += born.len();
            self.tracks.extend(born.into_iter().map(|p| Track {
                kind,
                born: step,
                last_seen: step,
                alive: true,
                vertex: p.vertex,
                position: p.position,
                radius: p.radius,
                moves: 0,
                cancelled_with: None,
            }));
        }
        for &t in &dying {
            self.tracks[t].alive = false;
        }
        events.deaths = dying.len();
        events.cancellations = self.cancel(&dying);
        events
    }

    /// Pair dying tracks of index k and k + 1 that were within matching distance.
    fn cancel(&mut self, dying: &[usize]) -> usize {
        let mut cancellations = 0;
        for k in 0..3u8 {
            let lower: Vec<usize> = dying
                .iter()
                .copied()
                .filter(|&t| index(self.tracks[t].kind) == Some(k))
                .collect();
            let upper: Vec<usize> = dying
                .iter()
                .copied()
                .filter(|&t| index(self.tracks[t].kind) == Some(k + 1))
                .collect();
            let track = |t: usize| &self.tracks[t];
            let queries: Vec<_> = lower
                .iter()
                .map(|&t| (track(t).position, track(t).radius))
                .collect();
            let targets: Vec<_> = upper.iter().map(|&t| track(t).position).collect();
            for (i, j) in greedy_matching(&queries, &targets).0 {
                self.tracks[lower[i]].cancelled_with = Some(upper[j]);
                self.tracks[upper[j]].cancelled_with = Some(lower[i]);
                cancellations += 1;
            }
        }
        cancellations
    }
}

/// Match queries to targets one to one, closest pairs first (see [`close_pairs`]):
/// the matched `(query, target)` pairs and which queries and targets were matched.
///
/// Most critical points stay at their vertex from one level to the next. A query at
/// the very place of a target, where no other query and no other target is, takes
/// that target first (the pair is at distance 0, and no other pair at distance 0 can
/// claim either), so only the rest are searched; the matching is the same.
fn greedy_matching(
    queries: &[([f64; 3], f64)],
    targets: &[[f64; 3]],
) -> (Vec<(usize, usize)>, Vec<bool>, Vec<bool>) {
    let mut query_taken = vec![false; queries.len()];
    let mut target_taken = vec![false; targets.len()];
    let mut matches = Vec::new();
    // Places by their coordinates' bits (−0 made +0), with how many targets and
    // queries are there and the last target seen.
    let place = |p: [f64; 3]| {
        p.iter()
            .all(|x| x.is_finite())
            .then(|| p.map(|x| (x + 0.0).to_bits()))
    };
    let mut at: HashMap<[u64; 3], (usize, usize, usize)> = HashMap::new();
    for (j, &t) in targets.iter().enumerate() {
        if let Some(key) = place(t) {
            let entry = at.entry(key).or_insert((0, 0, j));
            (entry.0, entry.2) = (entry.0 + 1, j);
        }
    }
    for &(q, _) in queries {
        if let Some(entry) = place(q).and_then(|key| at.get_mut(&key)) {
            entry.1 += 1;
        }
    }
    for (i, &(q, r)) in queries.iter().enumerate() {
        if let Some(&(1, 1, j)) = place(q).and_then(|key| at.get(&key)) {
            if r * r > 0.0 {
                query_taken[i] = true;
                target_taken[j] = true;
                matches.push((i, j));
            }
        }
    }
    // The rest, closest pairs first.
    let rest_queries: Vec<usize> = (0..queries.len()).filter(|&i| !query_taken[i]).collect();
    let rest_targets: Vec<usize> = (0..targets.len()).filter(|&j| !target_taken[j]).collect();
    let pairs = close_pairs(
        &rest_queries.iter().map(|&i| queries[i]).collect::<Vec<_>>(),
        &rest_targets.iter().map(|&j| targets[j]).collect::<Vec<_>>(),
    );
    for (_, a, b) in pairs {
        let (i, j) = (rest_queries[a], rest_targets[b]);
        if !query_taken[i] && !target_taken[j] {
            query_taken[i] = true;
            target_taken[j] = true;
            matches.push((i, j));
        }
    }
    (matches, query_taken, target_taken)
}

/// Every pair `(d², i, j)` with `|query_i − target_j| ≤ radius_i`, sorted by distance,
/// then `i`, then `j`.
fn close_pairs(queries: &[([f64; 3], f64)], targets: &[[f64; 3]]) -> Vec<(f64, usize, usize)> {
    let mut pairs = Vec::new();
    if queries.is_empty() || targets.is_empty() {
        return pairs;
    }
    let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(targets) else {
        // Only fails when there are more than u32::MAX targets; fall back to brute force.
        return all_close_pairs(queries, targets);
    };
    for (i, &(q, r)) in queries.iter().enumerate() {
        let found = tree
            .query(&q)
            .within::<SquaredEuclidean<f64>>(r * r)
            .execute();
        pairs.extend(found.iter().map(|n| (n.distance, i, n.item as usize)));
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    pairs
}

/// [`close_pairs`] by brute force: every query against every target.
fn all_close_pairs(queries: &[([f64; 3], f64)], targets: &[[f64; 3]]) -> Vec<(f64, usize, usize)> {
    let mut pairs = Vec::new();
    for (i, &(q, r)) in queries.iter().enumerate() {
        for (j, &t) in targets.iter().enumerate() {
            let d2 = distance2(q, t);
            if d2 <= r * r {
                pairs.push((d2, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    pairs
}

fn distance2(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]) * (a[k] - b[k])).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The greedy matching read literally: every pair within the query's radius (by
    /// brute force, not the k-d tree), closest first (then query, then target), each
    /// taken when both ends are free.
    fn literal(queries: &[([f64; 3], f64)], targets: &[[f64; 3]]) -> Vec<(usize, usize)> {
        let pairs = all_close_pairs(queries, targets);
        let (mut qt, mut tt) = (vec![false; queries.len()], vec![false; targets.len()]);
        let mut matches = Vec::new();
        for (_, i, j) in pairs {
            if !qt[i] && !tt[j] {
                (qt[i], tt[j]) = (true, true);
                matches.push((i, j));
            }
        }
        matches
    }

    #[test]
    fn points_that_stay_put_match_as_the_literal_greedy_does() {
        // Points on a coarse grid, so that many queries sit exactly on targets, some
        // places hold two targets or two queries, and distances tie; −0 beside +0.
        let mut state = 12345u64;
        let mut next = |n: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % n
        };
        for round in 0..50 {
            let draws: Vec<u64> = (0..80 * 4).map(|_| next(20)).collect();
            let coordinate = |d: u64| (d % 5) as f64 - 2.0;
            let point = |k: usize| [0, 1, 2].map(|c| coordinate(draws[4 * k + c]));
            let targets: Vec<[f64; 3]> = (0..40)
                .map(|k| {
                    let p = point(k);
                    if k % 7 == 0 {
                        p.map(|x| if x == 0.0 { -0.0 } else { x })
                    } else {
                        p
                    }
                })
                .collect();
            let queries: Vec<([f64; 3], f64)> = (40..80)
                .map(|k| {
                    (
                        point(k),
                        [0.0, 0.5, 1.0, 1.5][(draws[4 * k + 3] % 4) as usize],
                    )
                })
                .collect();
            let (matches, query_taken, target_taken) = greedy_matching(&queries, &targets);
            let mut sorted = matches.clone();
            sorted.sort_unstable();
            let mut expected = literal(&queries, &targets);
            expected.sort_unstable();
            assert_eq!(sorted, expected, "round {round}");
            for (i, taken) in query_taken.iter().enumerate() {
                assert_eq!(*taken, matches.iter().any(|m| m.0 == i));
            }
            for (j, taken) in target_taken.iter().enumerate() {
                assert_eq!(*taken, matches.iter().any(|m| m.1 == j));
            }
        }
    }
}
