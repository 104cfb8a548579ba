//! Sizing features: where the domain asks for lattice cells finer than `h`.
//!
//! A [`SizingFeature`] is a triangle (a segment or a point when corners repeat) with a
//! spacing and a reach: every octree cell that comes within `reach` of the triangle must
//! be no larger than `spacing`. A feature may face one way (`toward`): then the reach
//! holds on that side and one cell (`spacing`) on the other. The domain derives them
//! from the thickness of its parts and gaps (a thin plate asks for fine cells over its
//! whole area, reaching into the plate toward its middle), and the caller adds more
//! where a first mesh showed a feature below the resolution.
//!
//! The octree is refined level by level; each cell inherits from its parent the list of
//! features that reach the parent and keeps those that reach it, so a query costs only
//! the features nearby.

use rayon::prelude::*;
use rustc_hash::FxHashMap as HashMap;

use super::octree::Cell;
use super::{StuffingOptions, TETS_PER_LEAF};
use crate::geom::{closest_on_triangle, dot, sub};

/// A place that asks for a lattice spacing below `h` (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SizingFeature {
    /// The triangle's corners (repeat a corner for a segment or a point).
    pub corners: [[f64; 3]; 3],
    /// Largest cell size wanted within `reach`, in the domain's units.
    pub spacing: f64,
    /// How far from the triangle the spacing applies (on the `toward` side).
    pub reach: f64,
    /// A unit vector: the reach holds where `(x − closest point) · toward ≥ 0`, and only
    /// `spacing` elsewhere. Zero: the reach holds all round.
    pub toward: [f64; 3],
}

impl SizingFeature {
    /// Spacing wanted within `reach` of the point `p`.
    pub fn point(p: [f64; 3], spacing: f64, reach: f64) -> SizingFeature {
        SizingFeature {
            corners: [p; 3],
            spacing,
            reach,
            toward: [0.0; 3],
        }
    }

    /// Whether the feature is usable: finite corners, positive finite spacing, finite
    /// non-negative reach.
    pub fn is_valid(&self) -> bool {
        self.corners.iter().flatten().all(|c| c.is_finite())
            && self.spacing.is_finite()
            && self.spacing > 0.0
            && self.reach.is_finite()
            && self.reach >= 0.0
            && self.toward.iter().all(|c| c.is_finite())
    }

    /// The volume of space the feature asks to refine, for the tet-count estimate
    /// before meshing: the slab within reach of a triangle (the features of a surface
    /// share their edges, so the edges' and corners' round parts are not counted), the
    /// tube around a segment, the ball around a point (halves when one-sided).
    pub(crate) fn region_volume(&self) -> f64 {
        use crate::geom::{cross, norm};
        use std::f64::consts::PI;
        let [a, b, c] = self.corners;
        let one_sided = self.toward != [0.0; 3];
        let far = self.reach + self.spacing;
        let near = if one_sided { 2.0 * self.spacing } else { far };
        let area = 0.5 * norm(cross(sub(b, a), sub(c, a)));
        let length = norm(sub(b, a)).max(norm(sub(c, b))).max(norm(sub(a, c)));
        let half = |r: f64| {
            if area > 0.0 {
                r * area
            } else if length > 0.0 {
                0.5 * PI * r * r * length
            } else {
                2.0 / 3.0 * PI * r * r * r
            }
        };
        half(far) + half(near)
    }

    /// Whether a ball of radius `radius` round `p` comes within reach.
    fn reaches(&self, p: [f64; 3], radius: f64) -> bool {
        let [a, b, c] = self.corners;
        let q = closest_on_triangle(p, a, b, c);
        let d = sub(p, q);
        // The ball is on the `toward` side if any of it is (conservative for a parent
        // cell, whose children may lie on either side).
        let reach = if dot(d, self.toward) >= -radius {
            self.reach
        } else {
            self.spacing
        };
        let r = radius + reach;
        dot(d, d) <= r * r
    }
}

/// The features that reach each cell of the current octree level.
pub(crate) struct FeatureLists<'a> {
    features: &'a [SizingFeature],
    /// The lists of the previous level's cells (only cells with a list).
    parents: HashMap<Cell, Vec<u32>>,
}

impl<'a> FeatureLists<'a> {
    /// All features reach the root (a feature with spacing ≥ `coarsest` never refines
    /// anything and is left out).
    pub fn new(features: &'a [SizingFeature], root: Cell, coarsest: f64) -> Self {
        let all: Vec<u32> = (0..features.len() as u32)
            .filter(|&i| features[i as usize].spacing < coarsest)
            .collect();
        // The root's lists live under a virtual parent twice its size.
        let parent_size = 2 * root.size;
        let parent = Cell {
            origin: root.origin.map(|o| o - o.rem_euclid(parent_size)),
            size: parent_size,
        };
        let mut parents = HashMap::default();
        if !all.is_empty() {
            parents.insert(parent, all);
        }
        FeatureLists { features, parents }
    }

    /// For each cell of one level (all of one size, children of cells of the previous
    /// call): the smallest spacing of the features that reach it (`f64::INFINITY` for
    /// none). `to_point` maps integer keys to space, `unit` is the length of one key
    /// step. Keeps the lists for the next level's cells.
    pub fn level(
        &mut self,
        cells: &[Cell],
        to_point: &(dyn Fn([i64; 3]) -> [f64; 3] + Sync),
        unit: f64,
    ) -> Vec<f64> {
        let Some(size) = cells.first().map(|c| c.size) else {
            return Vec::new();
        };
        if self.parents.is_empty() {
            return vec![f64::INFINITY; cells.len()];
        }
        let parent_size = 2 * size;
        let half_diagonal = 0.5 * 3f64.sqrt() * size as f64 * unit;
        let features = self.features;
        let parents = &self.parents;
        let lists: Vec<(f64, Vec<u32>)> = cells
            .par_iter()
            .map(|cell| {
                let parent = Cell {
                    origin: cell.origin.map(|o| o - o.rem_euclid(parent_size)),
                    size: parent_size,
                };
                let Some(candidates) = parents.get(&parent) else {
                    return (f64::INFINITY, Vec::new());
                };
                let centre = to_point(cell.center());
                let mut smallest = f64::INFINITY;
                let mut kept = Vec::new();
                for &i in candidates {
                    let f = &features[i as usize];
                    if f.reaches(centre, half_diagonal) {
                        smallest = smallest.min(f.spacing);
                        kept.push(i);
                    }
                }
                (smallest, kept)
            })
            .collect();
        let cell_size = size as f64 * unit;
        let mut next: HashMap<Cell, Vec<u32>> = HashMap::default();
        let mut out = Vec::with_capacity(cells.len());
        for (cell, (smallest, mut kept)) in cells.iter().zip(lists) {
            out.push(smallest);
            // Children (half this size) only care for features finer than themselves.
            kept.retain(|&i| features[i as usize].spacing < 0.5 * cell_size);
            if !kept.is_empty() {
                next.insert(*cell, kept);
            }
        }
        self.parents = next;
        out
    }
}

/// The tets the features ask for, were no spacing finer than `floor`: the volume each
/// refines divided by its cells' volume. About half of those cells are inside, but the
/// octree's grading around them adds about as many again, and the tree's own guard
/// counts leaves (see `build_octree`), so the estimate counts all of them.
pub(super) fn feature_estimate(features: &[SizingFeature], floor: f64) -> f64 {
    features
        .iter()
        .map(|f| {
            let clamped = SizingFeature {
                spacing: f.spacing.max(floor),
                ..*f
            };
            TETS_PER_LEAF * clamped.region_volume() / clamped.spacing.powi(3)
        })
        .sum()
}

/// The smallest spacing sizing features may ask for within the budget
/// ([`StuffingOptions::max_tets`]; `None`: no floor needed), found by bisection on a
/// log scale between their finest spacing and `h`. [`stuff_volume`](super::stuff_volume) applies it; a
/// caller may ask first, to see which parts the budget leaves unresolved.
pub fn spacing_floor(features: &[SizingFeature], options: &StuffingOptions) -> Option<f64> {
    spacing_floor_scaled(features, options, 1.0)
}

/// [`spacing_floor`] with the features' estimate multiplied by `scale` (what an octree
/// counted against it: `volume::calibrated_floor`).
pub(super) fn spacing_floor_scaled(
    features: &[SizingFeature],
    options: &StuffingOptions,
    scale: f64,
) -> Option<f64> {
    let (budget, h) = (options.max_tets() as f64, options.h);
    let features: Vec<SizingFeature> = features
        .iter()
        .filter(|f| f.is_valid() && f.spacing < h)
        .copied()
        .collect();
    let features = &features[..];
    let estimate = |floor: f64| scale * feature_estimate(features, floor);
    if features.is_empty() || estimate(0.0) <= budget {
        return None;
    }
    let finest = features.iter().map(|f| f.spacing).fold(h, f64::min);
    if estimate(h) > budget {
        return Some(h);
    }
    let (mut lo, mut hi) = (finest.ln(), h.ln());
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if estimate(mid.exp()) > budget {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(hi.exp())
}

/// The features with no spacing below `floor` (all of them as they are without one).
pub(super) fn clamp_spacing(features: &[SizingFeature], floor: Option<f64>) -> Vec<SizingFeature> {
    match floor {
        None => features.to_vec(),
        Some(floor) => features
            .iter()
            .map(|f| SizingFeature {
                spacing: f.spacing.max(floor),
                ..*f
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_one_sided_feature_reaches_far_on_its_side_and_a_cell_on_the_other() {
        let plate = SizingFeature {
            corners: [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            spacing: 0.1,
            reach: 0.5,
            toward: [0.0, 0.0, -1.0],
        };
        // Below the triangle (its side) within 0.5; above within one cell (0.1).
        assert!(plate.reaches([0.2, 0.2, -0.45], 0.0));
        assert!(!plate.reaches([0.2, 0.2, -0.65], 0.0));
        assert!(plate.reaches([0.2, 0.2, 0.09], 0.0));
        assert!(!plate.reaches([0.2, 0.2, 0.2], 0.0));
        // A cell straddling the plane counts as on the far side (its children may be).
        assert!(plate.reaches([0.2, 0.2, 0.2], 0.3));
        // All round without a direction.
        let point = SizingFeature::point([0.0; 3], 0.1, 0.5);
        assert!(point.reaches([0.0, 0.0, 0.45], 0.0) && point.reaches([0.0, 0.0, -0.45], 0.0));
        assert!(point.is_valid());
        assert!(!SizingFeature {
            spacing: 0.0,
            ..point
        }
        .is_valid());
    }
}
