//! Isosurface stuffing proper (Labelle & Shewchuk 2007, sec. 3): cut points, warping and
//! the stencils that fill each background tetrahedron with the part of it inside the
//! domain.
//!
//! Signs: a lattice vertex is `−` (inside, value < 0), `0` or `+`. A *cut point* lies on
//! every background edge whose ends have strictly opposite signs, at the root of the
//! domain function along the edge. A cut point closer than `α · |edge|` to an end
//! *violates* that end; each violated vertex is *warped* onto its closest violating cut
//! point and becomes `0`, which removes the cut points of its edges. The caller gives α
//! per edge ([`ALPHA_LONG`] for axis-parallel edges, [`ALPHA_SHORT`] for the others,
//! less in refined thin parts). Then each background tet is filled:
//! - no `−` vertex: nothing (also when all four are `0`: such a tet lies along the
//!   boundary, and keeping it makes edges shared by unconnected tets);
//! - no `+` vertex: the tet itself;
//! - one `−`: one tet, with `+` vertices replaced by their cut points;
//! - two `−`, one `0`, one `+`: a pyramid, two tets;
//! - two `−`, two `+`, or three `−`, one `+`: a prism, three tets.
//!
//! Quadrilaterals on background faces are split by the diagonal through the vertex with
//! the smallest key (lattice vertices before cut points, then by index), a rule both
//! neighbours see the same way, so the output is conforming; a prism whose quads all
//! follow one total order can always be cut into three tets (Dompierre et al. 1999).

use rayon::prelude::*;

use crate::geom::{cross, dot, illinois_root, lerp, norm, sub};
use crate::mesh::Csr;

/// Edge-length fractions below which a cut point warps a vertex (the paper's values for
/// dihedral angles between 10.7° and 164.8°).
pub(crate) const ALPHA_LONG: f64 = 0.24999;
pub(crate) const ALPHA_SHORT: f64 = 0.41189;
/// A warp may shrink no background tet around the warped vertex below this fraction of
/// its lattice volume.
const WARP_GUARD: f64 = 0.1;
/// Secant/bisection steps when locating a cut point on an edge.
const ROOT_STEPS: usize = 30;

/// Result of stuffing: the filled tets over lattice vertices and cut points.
pub(crate) struct Stuffed {
    /// Positions: lattice vertices (warped where warped) then cut points.
    pub positions: Vec<[f64; 3]>,
    /// Sign of each position after warping: −1, 0 or +1 (cut points are 0).
    pub signs: Vec<i8>,
    /// Output tets, positively oriented, over `positions`.
    pub tets: Vec<[u32; 4]>,
    /// Number of lattice vertices warped onto the surface.
    pub warped: usize,
    /// Violated vertices left unwarped because every warp would flatten a background
    /// tet around them.
    pub refused_warps: usize,
    /// Number of cut points used.
    pub cut_points: usize,
    /// Output tets whose volume is not positive after warping (0 when the method's
    /// guarantees hold).
    pub inverted: usize,
}

/// Stuff the domain `value` (negative inside) into the background tets.
pub(crate) fn stuff(
    value: &(dyn Fn([f64; 3]) -> f64 + Sync),
    crossing: &(dyn Fn([f64; 3], [f64; 3]) -> Option<f64> + Sync),
    mut positions: Vec<[f64; 3]>,
    values: &[f64],
    alpha: &dyn Fn(u32, u32) -> f64,
    tets: &[[u32; 4]],
) -> Stuffed {
    let n = positions.len();
    let mut lattice_positions = positions.clone();
    let mut signs: Vec<i8> = values.iter().map(|&f| sign(f)).collect();

    // Edges with a sign change, and their cut points.
    let mut edges: Vec<[u32; 2]> = Vec::new();
    for t in tets {
        for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
            let (a, b) = (t[i], t[j]);
            if signs[a as usize] * signs[b as usize] < 0 {
                edges.push([a.min(b), a.max(b)]);
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    // Parameter of each cut point along its edge (from the lower index).
    let params: Vec<f64> = edges
        .par_iter()
        .map(|&[a, b]| {
            let (pa, pb) = (positions[a as usize], positions[b as usize]);
            match crossing(pa, pb) {
                Some(t) if t > 0.0 && t < 1.0 => t.clamp(1e-6, 1.0 - 1e-6),
                _ => root_on_edge(value, pa, pb, values[a as usize], values[b as usize]),
            }
        })
        .collect();

    // Warping, in vertex order: each violated vertex moves to its closest violating
    // cut point that an earlier warp has not removed, and takes every cut point of its
    // edges with it.
    let mut alive = vec![true; edges.len()];
    let incident = Csr::new(
        n,
        edges
            .iter()
            .enumerate()
            .flat_map(|(e, &[a, b])| [(a, e as u32), (b, e as u32)]),
    );
    // Background tets around each vertex that may warp (an end of a cut edge), to check
    // that a warp keeps them positive. Only those: on a thin model most of the lattice
    // lies away from the surface, and the lists of all were the stuffing's peak.
    let may_warp: Vec<bool> = (0..n).map(|v| !incident.get(v).is_empty()).collect();
    let vertex_tets = Csr::new(
        n,
        tets.iter()
            .enumerate()
            .flat_map(|(t, tet)| tet.map(|v| (v, t as u32)))
            .filter(|&(v, _)| may_warp[v as usize]),
    );
    let volume6 = |p: &[[f64; 3]], t: &[u32; 4], moved: Option<(u32, [f64; 3])>| {
        let at = |v: u32| match moved {
            Some((m, q)) if m == v => q,
            _ => p[v as usize],
        };
        let [a, b, c, d] = t.map(at);
        dot(sub(b, a), cross(sub(c, a), sub(d, a)))
    };
    let mut warped = 0;
    let mut refused_warps = 0;
    let mut candidates: Vec<(f64, usize)> = Vec::new();
    for v in 0..n {
        // Violating cut points that are still alive, closest first.
        candidates.clear();
        for &e in incident.get(v) {
            let e = e as usize;
            if !alive[e] {
                continue;
            }
            let [a, b] = edges[e];
            let t = if a as usize == v {
                params[e]
            } else {
                1.0 - params[e]
            };
            if t < alpha(a, b) {
                let len = norm(sub(positions[b as usize], positions[a as usize]));
                candidates.push((t * len, e));
            }
        }
        candidates.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        // Guard: the paper's bounds hold for BCC tets; in graded transitions a warp
        // could flatten a cone tet, so a warp must keep every background tet around v
        // at a fair fraction of its volume (otherwise the next candidate, or none).
        let choice = candidates.iter().find_map(|&(_, e)| {
            let [a, b] = edges[e];
            let q = lerp(positions[a as usize], positions[b as usize], params[e]);
            let safe = vertex_tets.get(v).iter().all(|&t| {
                let tet = &tets[t as usize];
                volume6(&positions, tet, Some((v as u32, q)))
                    >= WARP_GUARD * volume6(&lattice_positions, tet, None)
            });
            safe.then_some((e, q))
        });
        if let Some((_, q)) = choice {
            positions[v] = q;
            signs[v] = 0;
            warped += 1;
            for &e in incident.get(v) {
                alive[e as usize] = false;
            }
        } else if !candidates.is_empty() {
            refused_warps += 1;
        }
    }

    // Cut points that survive, appended after the lattice vertices.
    let mut cut_index: rustc_hash::FxHashMap<[u32; 2], u32> = Default::default();
    let mut out_positions = positions;
    for (e, &[a, b]) in edges.iter().enumerate() {
        // Both ends of a live cut edge are unwarped.
        if alive[e] && signs[a as usize] * signs[b as usize] < 0 {
            cut_index.insert([a, b], out_positions.len() as u32);
            let p = lerp(
                out_positions[a as usize],
                out_positions[b as usize],
                params[e],
            );
            out_positions.push(p);
            lattice_positions.push(p);
            signs.push(0);
        }
    }
    let cut_points = cut_index.len();
    let cut = |a: u32, b: u32| -> u32 { cut_index[&[a.min(b), a.max(b)]] };

    // Fill.
    let mut out = Vec::new();
    for t in tets {
        let (mut neg, mut zero, mut pos) = ([0u32; 4], [0u32; 4], [0u32; 4]);
        let (mut nn, mut nz, mut np) = (0, 0, 0);
        for &v in t {
            match signs[v as usize] {
                s if s < 0 => {
                    neg[nn] = v;
                    nn += 1;
                }
                0 => {
                    zero[nz] = v;
                    nz += 1;
                }
                _ => {
                    pos[np] = v;
                    np += 1;
                }
            }
        }
        match (nn, nz, np) {
            (0, _, _) => {}
            (_, _, 0) => out.push(*t),
            (1, _, _) => {
                let n0 = neg[0];
                let mut tet = *t;
                for v in tet.iter_mut() {
                    if signs[*v as usize] > 0 {
                        *v = cut(n0, *v);
                    }
                }
                out.push(tet);
            }
            (2, 1, 1) => {
                let (n1, n2, z, p) = (neg[0], neg[1], zero[0], pos[0]);
                let (c1, c2) = (cut(n1, p), cut(n2, p));
                // Base quad (n1, n2, c2, c1): the diagonal goes through the smaller key.
                if n1.min(n2) == n1 {
                    out.push([z, n1, n2, c2]);
                    out.push([z, n1, c2, c1]);
                } else {
                    out.push([z, n1, n2, c1]);
                    out.push([z, n2, c2, c1]);
                }
            }
            (2, 0, 2) => {
                let (n1, n2, p1, p2) = (neg[0], neg[1], pos[0], pos[1]);
                let prism = [n1, cut(n1, p1), cut(n1, p2), n2, cut(n2, p1), cut(n2, p2)];
                split_prism(prism, &mut out);
            }
            (3, 0, 1) => {
                let p = pos[0];
                let prism = [
                    neg[0],
                    neg[1],
                    neg[2],
                    cut(neg[0], p),
                    cut(neg[1], p),
                    cut(neg[2], p),
                ];
                split_prism(prism, &mut out);
            }
            _ => unreachable!("sign counts add up to four"),
        }
    }
    // Orient every output tet by its shape before warping (never degenerate: cut
    // points lie strictly inside their edges), then count any that warping inverted.
    let mut inverted = 0;
    for t in &mut out {
        if volume6(&lattice_positions, t, None) < 0.0 {
            t.swap(2, 3);
        }
        if volume6(&out_positions, t, None) <= 0.0 {
            inverted += 1;
        }
    }
    Stuffed {
        positions: out_positions,
        signs,
        tets: out,
        warped,
        refused_warps,
        cut_points,
        inverted,
    }
}

fn sign(f: f64) -> i8 {
    if f < 0.0 {
        -1
    } else if f > 0.0 {
        1
    } else {
        0
    }
}

/// Cut a prism (bottom `p[0..3]`, top `p[3..6]`, vertical edges `p[i]`–`p[i+3]`) into
/// three tets. Quad diagonals go through each quad's smallest index, so neighbours agree
/// (indices order lattice vertices before cut points).
fn split_prism(p: [u32; 6], out: &mut Vec<[u32; 4]>) {
    // Move the smallest vertex to bottom position 0 by the prism's symmetries.
    let m = (0..6).min_by_key(|&i| p[i]).unwrap_or(0);
    let flip = |i: usize| (i + 3) % 6;
    let rot = |i: usize, r: usize| (i / 3) * 3 + (i % 3 + r) % 3;
    let (top, r) = (m >= 3, m % 3);
    let map = |i: usize| {
        let j = rot(i, r);
        if top {
            flip(j)
        } else {
            j
        }
    };
    let q: [u32; 6] = std::array::from_fn(|i| p[map(i)]);
    out.push([q[0], q[3], q[4], q[5]]);
    // The quad opposite q[0]: (q1, q2, q5, q4).
    let smallest = [q[1], q[2], q[5], q[4]].into_iter().min().unwrap_or(q[1]);
    if smallest == q[1] || smallest == q[5] {
        out.push([q[0], q[1], q[2], q[5]]);
        out.push([q[0], q[1], q[5], q[4]]);
    } else {
        out.push([q[0], q[1], q[2], q[4]]);
        out.push([q[0], q[2], q[5], q[4]]);
    }
}

/// The parameter `t ∈ (0, 1)` of the root of `value` on the segment `a + t (b − a)`,
/// where `fa` and `fb` have opposite signs: regula falsi with the Illinois rule, stopped
/// when the value is below `1e-9 |b − a|` (a signed distance is nearly linear across a
/// single face, so this takes two or three steps).
fn root_on_edge(
    value: &(dyn Fn([f64; 3]) -> f64 + Sync),
    a: [f64; 3],
    b: [f64; 3],
    fa: f64,
    fb: f64,
) -> f64 {
    let tol = 1e-9 * norm(sub(b, a));
    let t = illinois_root(|t| value(lerp(a, b, t)), fa, fb, tol, 0.0, ROOT_STEPS);
    t.clamp(1e-6, 1.0 - 1e-6)
}
