//! Step 2 of the tightening: the shortest closed path homotopic to the strip's core.
//! [`shortest_closed_path`] reads as its three parts: choose the anchor portal
//! ([`choose_anchor`]: where the last path crossed farthest from a vertex), find the
//! anchor parameter that minimises the length (the length is convex in it: Newton steps
//! on its slope from the last round's crossing, the funnel run again only where steps
//! with its bends held settle, else a safeguarded regula falsi, `geom::illinois_root`),
//! and turn the funnel path back into one crossing per portal
//! ([`portal_crossings`]).
//!
//! Conventions: portal parameters run from the left vertex (0) to the right one (1) in
//! the unfolding, and from the edge's first stored vertex in a [`PortalCrossing`].

use super::unfold::{cross2, dist2, funnel, length_and_slope, lerp2, unfold, Apex, Portal2};
use super::{PortalCrossing, Strip, StripPath, SurfaceGeometry};
use crate::geom::{illinois_root, lerp};

/// The anchor search stops when its bracket of the strip parameter is narrower than
/// this.
const SLOPE_BRACKET: f64 = 1e-13;

/// Most evaluations of the anchor search.
const SLOPE_STEPS: usize = 100;

/// Most Newton steps from the last round's anchor parameter before the bracketed search
/// takes over.
const NEWTON_STEPS: usize = 8;

/// A crossing within this portal parameter of an endpoint is at that vertex: rounding
/// must not leave a point a hair away from a vertex the path really passes through.
const VERTEX_SNAP: f64 = 1e-9;

/// A portal's far end lies on the path's segment (the path runs along the portal's
/// edge) when its distance from the segment's line is below this fraction of the
/// lengths involved.
const ALONG_TOLERANCE: f64 = 1e-8;

/// A path segment is parallel to a portal when the cross product of their directions
/// is below this fraction of their lengths' product.
const PARALLEL_TOLERANCE: f64 = 1e-12;

/// The shortest closed path homotopic to the strip's core, with its crossings (and the
/// strip's hints updated to them). `None` when the strip cannot be unfolded.
pub(super) fn shortest_closed_path(
    geometry: &SurfaceGeometry,
    strip: &mut Strip,
) -> Option<StripPath> {
    let n = strip.portals.len();
    if n < 2 {
        return None;
    }
    let anchor = choose_anchor(strip);
    let portals = unfold(geometry, strip, anchor)?;
    // The last path's crossing of the anchor, from the left vertex.
    let guess = Some(strip.hint[anchor]).filter(|t| !t.is_nan()).map(|t| {
        let [a, _] = geometry.edge(strip.portals[anchor]);
        if portals[0].lv == a {
            t
        } else {
            1.0 - t
        }
    });
    let (t, path, length) = shortest_through(&portals, guess);
    let crossings = portal_crossings(geometry, strip, anchor, &portals, &path, t)?;
    for (i, c) in crossings.iter().enumerate() {
        strip.hint[i] = if c.vertex.is_some() { f64::NAN } else { c.t };
    }
    Some(StripPath { crossings, length })
}

/// The portal whose previous crossing is farthest from both its endpoints (the first
/// such; an unknown crossing counts as at an endpoint).
fn choose_anchor(strip: &Strip) -> usize {
    let score = |k: usize| {
        let t = strip.hint[k];
        if t.is_nan() {
            1.0
        } else {
            (t - 0.5).abs()
        }
    };
    (0..strip.portals.len())
        .min_by(|&i, &j| score(i).total_cmp(&score(j)).then(i.cmp(&j)))
        .unwrap_or(0)
}

/// The anchor parameter `t` of the shortest path from the first portal to its image on
/// the last, the funnel path there and its length. The length is convex in `t`. From
/// `guess` (the last round's crossing: the path moves little between rounds), Newton
/// steps on the slope ([`newton`]); where they do not settle, regula falsi (Illinois)
/// on the slope over the bracket they left, or an end of `[0, 1]` where the slope does
/// not change sign.
fn shortest_through(portals: &[Portal2], guess: Option<f64>) -> (f64, Vec<Apex>, f64) {
    let n = portals.len() - 1;
    let (p0, pn) = (portals[0], portals[n]);
    let ds = [p0.right[0] - p0.left[0], p0.right[1] - p0.left[1]];
    let dg = [pn.right[0] - pn.left[0], pn.right[1] - pn.left[1]];
    let eval = |t: f64| {
        let (s, g, end_vertex) = if t == 0.0 {
            (p0.left, pn.left, Some(p0.lv))
        } else if t == 1.0 {
            (p0.right, pn.right, Some(p0.rv))
        } else {
            (
                lerp2(p0.left, p0.right, t),
                lerp2(pn.left, pn.right, t),
                None,
            )
        };
        let path = funnel(s, g, portals, end_vertex);
        let (len, slope, curvature) = length_and_slope(&path, ds, dg);
        (path, len, slope, curvature)
    };
    // The bracket: a parameter of negative slope (or 0) and one of positive slope (or
    // 1), with the slope where it has been evaluated.
    let mut lo: (f64, Option<f64>) = (0.0, None);
    let mut hi: (f64, Option<f64>) = (1.0, None);
    if let Some(t) = guess.filter(|t| *t > 0.0 && *t < 1.0) {
        if let Some(found) = newton(&eval, (p0, pn), t, &mut lo, &mut hi) {
            return found;
        }
    }
    let s0 = match lo.1 {
        Some(slope) => slope,
        None => {
            let (path, length, slope, _) = eval(0.0);
            if slope >= 0.0 {
                return (0.0, path, length);
            }
            slope
        }
    };
    let s1 = match hi.1 {
        Some(slope) => slope,
        None => {
            let (path, length, slope, _) = eval(1.0);
            if slope <= 0.0 {
                return (1.0, path, length);
            }
            slope
        }
    };
    // The search ends on the parameter it evaluated last: that funnel is the answer.
    let (start, width) = (lo.0, hi.0 - lo.0);
    let mut last = None;
    let search = |u: f64| {
        let t = start + u * width;
        let (path, length, slope, _) = eval(t);
        last = Some((t, path, length));
        slope
    };
    let u = illinois_root(search, s0, s1, 0.0, SLOPE_BRACKET / width, SLOPE_STEPS);
    let t = start + u * width;
    match last {
        Some((at, path, length)) if at == t => (t, path, length),
        _ => {
            let (path, length, _, _) = eval(t);
            (t, path, length)
        }
    }
}

/// Newton steps on the slope of a convex length from `t` inside `(0, 1)`: the parameter
/// where a step is below [`SLOPE_BRACKET`] (or the slope is zero), with its path and
/// length. Every evaluation narrows the bracket `lo`, `hi` (a negative slope moves
/// `lo`, a positive one `hi`). `None` where a step leaves that bracket (the minimum at
/// an end, or a step past a change of the funnel's bends), the curvature is not
/// positive, or [`NEWTON_STEPS`] evaluations do not settle.
///
/// Between two runs of the funnel, the steps go on with the last path's bends held
/// ([`held_slope`]: only its two end segments move with `t`), which is what the funnel
/// would give again wherever the bends stay; the funnel runs once more where those
/// steps settle, to confirm the bends or to go on from the new ones.
fn newton(
    eval: &impl Fn(f64) -> (Vec<Apex>, f64, f64, f64),
    ends: (Portal2, Portal2),
    mut t: f64,
    lo: &mut (f64, Option<f64>),
    hi: &mut (f64, Option<f64>),
) -> Option<(f64, Vec<Apex>, f64)> {
    for _ in 0..NEWTON_STEPS {
        let (path, length, slope, curvature) = eval(t);
        if slope == 0.0 {
            return Some((t, path, length));
        }
        if slope < 0.0 {
            *lo = (t, Some(slope));
        } else {
            *hi = (t, Some(slope));
        }
        if curvature.is_nan() || curvature <= 0.0 {
            return None;
        }
        let (mut u, mut slope, mut curvature) = (t, slope, curvature);
        for _ in 0..HELD_STEPS {
            let next = u - slope / curvature;
            if (next - u).abs() <= SLOPE_BRACKET || !(next > lo.0 && next < hi.0) {
                break;
            }
            u = next;
            (slope, curvature) = held_slope(&path, ends, u);
            if slope == 0.0 || curvature.is_nan() || curvature <= 0.0 {
                break;
            }
        }
        if u == t {
            // Settled (or left the bracket) from the evaluated parameter itself.
            let next = t - slope / curvature;
            return ((next - t).abs() <= SLOPE_BRACKET).then_some((t, path, length));
        }
        t = u;
    }
    None
}

/// Most Newton steps with a path's bends held between two runs of the funnel.
const HELD_STEPS: usize = 16;

/// The slope and curvature of the length at parameter `t` of the path through the bends
/// of `path` (its two end segments moved to the anchor and its image at `t`): what
/// [`length_and_slope`] reads of a path, its first and last bend apart from its ends.
fn held_slope(path: &[Apex], (p0, pn): (Portal2, Portal2), t: f64) -> (f64, f64) {
    let ds = [p0.right[0] - p0.left[0], p0.right[1] - p0.left[1]];
    let dg = [pn.right[0] - pn.left[0], pn.right[1] - pn.left[1]];
    let end = |pos| Apex {
        pos,
        vertex: None,
        index: 0,
    };
    let (s, g) = (path[0].pos, path[path.len() - 1].pos);
    let mut inner = path[1..path.len() - 1]
        .iter()
        .filter(|a| a.pos != s && a.pos != g);
    let mut moved = Vec::with_capacity(4);
    moved.push(end(lerp2(p0.left, p0.right, t)));
    if let Some(&first) = inner.next() {
        moved.push(first);
        if let Some(&last) = inner.next_back() {
            moved.push(last);
        }
    }
    moved.push(end(lerp2(pn.left, pn.right, t)));
    let (_, slope, curvature) = length_and_slope(&moved, ds, dg);
    (slope, curvature)
}

/// One crossing per strip portal (in strip order) of the funnel `path` through the
/// unfolded `portals` (index `k` ↔ strip portal `(anchor + k) % n`), the anchor at
/// parameter `t`. A portal the path touches at an endpoint is crossed at that vertex; a
/// portal whose edge the path runs along counts as crossed where that run ends.
fn portal_crossings(
    geometry: &SurfaceGeometry,
    strip: &Strip,
    anchor: usize,
    portals: &[Portal2],
    path: &[Apex],
    t: f64,
) -> Option<Vec<PortalCrossing>> {
    let n = strip.portals.len();
    let mut by_k: Vec<Option<PortalCrossing>> = vec![None; n];
    let mk = |k: usize, s: f64, vertex: Option<u32>| {
        let pt = portals[k];
        let e = strip.portals[(anchor + k) % n];
        let [a, b] = geometry.edge(e);
        // s runs from left to right.
        let t = if pt.lv == a { s } else { 1.0 - s };
        let point = match vertex {
            Some(v) => geometry.pos(v),
            None => lerp(geometry.pos(a), geometry.pos(b), t),
        };
        let t = match vertex {
            Some(v) if v == a => 0.0,
            Some(_) => 1.0,
            None => t,
        };
        PortalCrossing { t, vertex, point }
    };
    let at_end = |s: f64, pt: Portal2| {
        if s <= VERTEX_SNAP {
            Some(pt.lv)
        } else if s >= 1.0 - VERTEX_SNAP {
            Some(pt.rv)
        } else {
            None
        }
    };
    by_k[0] = Some(mk(0, t, at_end(t, portals[0])));
    for seg in path.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        for k in a.index.max(1)..=b.index.min(n - 1) {
            if by_k[k].is_some() {
                continue;
            }
            let pt = portals[k];
            let touches = |x: &Apex| {
                x.vertex.and_then(|v| {
                    if pt.lv == v && pt.left == x.pos {
                        Some((0.0, v))
                    } else if pt.rv == v && pt.right == x.pos {
                        Some((1.0, v))
                    } else {
                        None
                    }
                })
            };
            // A portal holding both bend points is the edge the path runs along: it
            // counts as crossed where that run ends, so each vertex's run starts with
            // the edge it is entered along.
            let hit = touches(&b).or_else(|| {
                let (s, v) = touches(&a)?;
                // From `a` along this very edge: the path passes its other end too.
                let (w, wv) = if s == 0.0 {
                    (pt.right, pt.rv)
                } else {
                    (pt.left, pt.lv)
                };
                let along = cross2(a.pos, b.pos, w).abs()
                    <= ALONG_TOLERANCE * dist2(a.pos, b.pos) * dist2(a.pos, w)
                    && dist2(a.pos, w) <= dist2(a.pos, b.pos);
                Some(if along { (1.0 - s, wv) } else { (s, v) })
            });
            let c = if let Some((s, v)) = hit {
                mk(k, s, Some(v))
            } else {
                let d = [b.pos[0] - a.pos[0], b.pos[1] - a.pos[1]];
                let e = [pt.right[0] - pt.left[0], pt.right[1] - pt.left[1]];
                let den = e[0] * d[1] - e[1] * d[0];
                let scale = dist2(a.pos, b.pos) * dist2(pt.left, pt.right);
                let s = if den.abs() > PARALLEL_TOLERANCE * scale {
                    let w = [a.pos[0] - pt.left[0], a.pos[1] - pt.left[1]];
                    ((w[0] * d[1] - w[1] * d[0]) / den).clamp(0.0, 1.0)
                } else if dist2(pt.left, b.pos) <= dist2(pt.right, b.pos) {
                    // The path runs along this edge: it passes its endpoint nearer
                    // the next bend point.
                    0.0
                } else {
                    1.0
                };
                mk(k, s, at_end(s, pt))
            };
            by_k[k] = Some(c);
        }
    }
    let mut crossings = vec![
        PortalCrossing {
            t: f64::NAN,
            vertex: None,
            point: [f64::NAN; 3]
        };
        n
    ];
    for (k, c) in by_k.into_iter().enumerate() {
        crossings[(anchor + k) % n] = c?;
    }
    Some(crossings)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A corridor of `n` portals at x = 0, 1, …, each open between pseudo-random
    /// heights, closed by the first portal's image: turned by `turn` about its right
    /// end and moved to x = n, as an unfolded strip's anchor comes back.
    fn corridor(seed: u64, n: usize, turn: f64) -> Vec<Portal2> {
        // A multiplicative hash of (seed, draw) in [0, 1).
        let mut draw = 0u64;
        let mut next = || {
            draw += 1;
            ((seed * 7919 + draw) * 2_654_435_761 % 1_000_003) as f64 / 1_000_003.0
        };
        let mut portals: Vec<Portal2> = (0..n)
            .map(|i| {
                let low = next() - 1.0;
                let high = low + 0.2 + 1.5 * next();
                let x = i as f64;
                Portal2 {
                    left: [x, high],
                    right: [x, low],
                    lv: 2 * i as u32,
                    rv: 2 * i as u32 + 1,
                }
            })
            .collect();
        let first = portals[0];
        let d = [
            first.left[0] - first.right[0],
            first.left[1] - first.right[1],
        ];
        let (c, s) = (turn.cos(), turn.sin());
        let right = [n as f64, first.right[1]];
        portals.push(Portal2 {
            left: [
                right[0] + c * d[0] - s * d[1],
                right[1] + s * d[0] + c * d[1],
            ],
            right,
            lv: first.lv,
            rv: first.rv,
        });
        portals
    }

    #[test]
    fn the_anchor_search_finds_the_shortest_path_from_any_guess() {
        // Ground truth independent of both searches: the shortest of the funnel paths
        // over a fine grid of anchor parameters.
        for seed in 0..60 {
            for turn in [-0.4, 0.0, 0.4] {
                let portals = corridor(seed, 7, turn);
                let n = portals.len() - 1;
                let (p0, pn) = (portals[0], portals[n]);
                let grid = (0..=2000)
                    .map(|i| {
                        let t = f64::from(i) / 2000.0;
                        let s = lerp2(p0.left, p0.right, t);
                        let g = lerp2(pn.left, pn.right, t);
                        let path = funnel(s, g, &portals, None);
                        path.windows(2)
                            .map(|w| dist2(w[0].pos, w[1].pos))
                            .sum::<f64>()
                    })
                    .fold(f64::INFINITY, f64::min);
                let (_, _, searched) = shortest_through(&portals, None);
                assert!(searched <= grid + 1e-12, "seed {seed}: {searched} > {grid}");
                for guess in [0.02, 0.3, 0.5, 0.77, 0.98] {
                    let (t, path, length) = shortest_through(&portals, Some(guess));
                    assert!(
                        (length - searched).abs() <= 1e-12 * searched,
                        "seed {seed} turn {turn} guess {guess}: {length} against {searched}"
                    );
                    let summed: f64 = path.windows(2).map(|w| dist2(w[0].pos, w[1].pos)).sum();
                    assert_eq!(summed, length);
                    assert!((0.0..=1.0).contains(&t));
                }
            }
        }
    }
}
