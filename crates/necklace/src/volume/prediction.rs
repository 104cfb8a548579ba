//! The topology a surface predicts for each side's volume mesh (the check that tells
//! the volume stage to refine): per component of the inside, or of the shell out to
//! the bounding sphere, its χ and the χ of each boundary surface, from the surface's
//! components, their genus and how they nest (`distance::nesting`). Entry point:
//! [`expected_topology`].

use crate::distance::{nesting, SurfaceDistance};
use crate::mesh::{MeshReport, Side, SurfaceMesh};
use crate::tet::{ComponentTopology, TetTopology};

/// The topology a closed, embedded surface predicts for one side's volume: inside,
/// one component per outward-facing surface component, bounded by it and by the
/// inward-facing components (cavities) directly inside it; outside, the shell bounded
/// by the outer sphere and the outermost components, plus one component per cavity,
/// bounded by it and the components directly inside it. `None` when a component's
/// genus is undefined or the surface crosses itself.
pub fn expected_topology(surface: &SurfaceMesh, side: Side) -> Option<TetTopology> {
    let distance = SurfaceDistance::new(surface);
    if !distance.self_intersections(&surface.triangles).is_empty() {
        return None;
    }
    predict(surface, &MeshReport::new(surface), side)
}

/// [`expected_topology`] of a surface known not to cross itself, whose
/// [`MeshReport`] is `report`.
pub(super) fn predict(
    surface: &SurfaceMesh,
    report: &MeshReport,
    side: Side,
) -> Option<TetTopology> {
    let comps = &report.component_details;
    if comps.is_empty() || comps.iter().any(|c| c.genus.is_none() || c.faces == 0) {
        return None;
    }
    let parent = nesting(surface, report)?;
    let outward: Vec<bool> = comps.iter().map(|c| c.signed_volume > 0.0).collect();
    // A region of space is bounded by one "owner" component and the components whose
    // parent is that owner; inside regions are owned by outward components, outside
    // regions by cavities (and the outer sphere, owner `None`).
    let mut regions: Vec<ComponentTopology> = Vec::new();
    let owners: Vec<Option<usize>> = match side {
        Side::Inside => (0..comps.len()).filter(|&i| outward[i]).map(Some).collect(),
        Side::Outside => std::iter::once(None)
            .chain((0..comps.len()).filter(|&i| !outward[i]).map(Some))
            .collect(),
    };
    for owner in owners {
        let mut boundary: Vec<i64> = match owner {
            Some(o) => vec![comps[o].euler],
            None => vec![2],
        };
        for (i, c) in comps.iter().enumerate() {
            if parent[i] == owner && Some(i) != owner {
                // A child must face the other way from its owner (an outward solid
                // inside a cavity, a cavity inside a solid).
                if owner.is_some_and(|o| outward[o] == outward[i])
                    || (owner.is_none() && !outward[i])
                {
                    return None;
                }
                boundary.push(c.euler);
            }
        }
        let euler = boundary.iter().sum::<i64>() / 2;
        regions.push(ComponentTopology {
            euler,
            boundary_eulers: boundary,
        });
    }
    Some(TetTopology::new(regions))
}
