//! What the loop stage keeps of a surface between seeds ([`LoopSurface`]): built once
//! per surface, by [`find_loops`](super::find_loops) for the surface it cuts, and by
//! the pipeline for the input when loops found on a simplified copy are carried back
//! ([`transfer_loops`](super::transfer_loops)).

use super::cut::{Cutter, EdgeTree};
use super::membrane::DualGraph;
use super::opening::Openings;
use super::tighten::SurfaceGeometry;
use super::{LoopOptions, Measures};
use crate::mesh::{HomologyBasis, SurfaceMesh, Topology};

/// What the loop stage keeps of a surface between seeds: its topology, homology basis,
/// angle defects, edge tree and dual graph. Built once per surface
/// ([`LoopSurface::new`]); the pipeline builds one for the input surface when loops
/// found on a simplified copy are carried back to it
/// ([`transfer_loops`](super::transfer_loops)).
/// It does not hold the surface: each use names it again, and must name the same one
/// ([`LoopSurface::is_of`]).
pub struct LoopSurface {
    pub(super) topology: Topology,
    pub(super) basis: HomologyBasis,
    openings: Openings,
    /// Its edges' tree, for plane cuts.
    edges: EdgeTree,
    /// The total angle at each vertex ([`SurfaceGeometry::total_angles`]).
    angles: Vec<f64>,
    /// Its faces' centroids and neighbours, for membranes' and carried loops' face paths.
    pub(super) dual: DualGraph,
}

impl LoopSurface {
    /// Topology, homology basis and openings of `surface`. `O(V + F)`.
    pub fn new(surface: &SurfaceMesh) -> Self {
        // One thread: the pipeline builds it lazily for both sides (`OnceLock`), where
        // nested parallel work could run the other side's call on the waiting thread.
        let topology = Topology::new(surface);
        let geometry = SurfaceGeometry::new(surface, &topology);
        let basis = HomologyBasis::new(surface, &topology);
        let openings = Openings::new(surface, &topology, &geometry);
        let angles = geometry.total_angles().to_vec();
        let edges = EdgeTree::new(surface, &topology);
        let dual = DualGraph::new(surface, &topology);
        LoopSurface {
            dual,
            topology,
            basis,
            openings,
            edges,
            angles,
        }
    }

    /// Whether this was built from `surface` (as far as its sizes tell).
    pub fn is_of(&self, surface: &SurfaceMesh) -> bool {
        self.angles.len() == surface.num_vertices()
            && self.topology.num_faces() == surface.num_triangles()
    }

    /// What tightening needs of `surface`, the surface this was built from.
    pub(super) fn geometry<'a>(&'a self, surface: &'a SurfaceMesh) -> SurfaceGeometry<'a> {
        SurfaceGeometry::with_angles(surface, &self.topology, self.angles.clone())
    }

    /// Plane cuts of `surface`, the surface this was built from.
    pub(super) fn cutter<'a>(&'a self, surface: &'a SurfaceMesh) -> Cutter<'a> {
        Cutter {
            mesh: surface,
            topology: &self.topology,
            tree: &self.edges,
        }
    }

    /// What loops on `surface`, the surface this was built from, are measured with.
    pub(super) fn measures<'a>(
        &'a self,
        surface: &'a SurfaceMesh,
        options: &LoopOptions,
    ) -> Measures<'a> {
        Measures {
            surface,
            topology: &self.topology,
            basis: &self.basis,
            openings: &self.openings,
            reach: options.opening_reach,
        }
    }
}
