//! What the loop stage keeps of a surface between seeds ([`LoopSurface`]): built once
//! per surface, by [`find_loops`](super::find_loops) for the surface it cuts, and by
//! the pipeline for the input when loops found on a simplified copy are carried back
//! ([`transfer_loops`](super::transfer_loops)).

use super::opening::Openings;
use super::tighten::SurfaceGeometry;
use super::{LoopOptions, Measures};
use crate::mesh::{HomologyBasis, SurfaceMesh, Topology};

/// What the loop stage keeps of a surface between seeds: its topology, homology basis
/// and angle defects. Built once per surface ([`LoopSurface::new`]); the pipeline
/// builds one for the input surface when loops found on a simplified copy are carried
/// back to it ([`transfer_loops`](super::transfer_loops)).
pub struct LoopSurface<'a> {
    pub(super) surface: &'a SurfaceMesh,
    pub(super) topology: Topology,
    pub(super) basis: HomologyBasis,
    openings: Openings,
    /// The total angle at each vertex ([`SurfaceGeometry::total_angles`]).
    angles: Vec<f64>,
}

impl<'a> LoopSurface<'a> {
    /// Topology, homology basis and openings of `surface`. `O(V + F)`.
    pub fn new(surface: &'a SurfaceMesh) -> Self {
        let topology = Topology::new(surface);
        let geometry = SurfaceGeometry::new(surface, &topology);
        let basis = HomologyBasis::new(surface, &topology);
        let openings = Openings::new(surface, &topology, &geometry);
        let angles = geometry.total_angles().to_vec();
        LoopSurface {
            surface,
            topology,
            basis,
            openings,
            angles,
        }
    }

    /// What tightening needs of the surface.
    pub(super) fn geometry(&self) -> SurfaceGeometry<'_> {
        SurfaceGeometry::with_angles(self.surface, &self.topology, self.angles.clone())
    }

    pub(super) fn measures(&self, options: &LoopOptions) -> Measures<'_> {
        Measures {
            surface: self.surface,
            topology: &self.topology,
            basis: &self.basis,
            openings: &self.openings,
            reach: options.opening_reach,
        }
    }
}
