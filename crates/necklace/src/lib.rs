//! # necklace
//!
//! Finds the *neck loops* of a closed triangle mesh: loops that lasso the narrow parts of
//! the solid (handles) and of the space around it (tunnels), following
//! "Fast Computation of Neck-like Features" (see `ARCHITECTURE.md` for the stage diagram).
//!
//! ## Tour
//! - [`mesh`]: [`SurfaceMesh`], the plain data every stage starts from, its topology and
//!   its validity report ([`MeshReport`]).
//! - [`io`]: reading OBJ, OFF, PLY and STL; writing OBJ, OFF and binary PLY (meshes and
//!   point clouds); tet meshes in TetGen, Medit, Gmsh and VTU formats.
//! - [`tet`]: [`TetMesh`], the volume mesh every volume stage passes along.
//! - [`distance`]: exact distance, winding number and rays against a surface.
//! - [`volume`]: isosurface stuffing (Labelle & Shewchuk 2007) of an implicit region on
//!   a graded BCC lattice; the paper's "preprocessing" (sec. 4) without TetGen.
//! - [`morse`]: the smoothed distance field on a tet mesh, its critical points by link
//!   classification (with the Morse check), their tracking under smoothing, and the
//!   2-saddles that mark necks with their Hessian and cutting-plane normal (sec. 4.1–4.2).
//! - [`loops`]: the neck loops on the surface: plane cut through each saddle, geodesic
//!   tightening (strip unfolding and funnel), selection with reasons (sec. 4.3).
//! - [`shapes`]: analytic test shapes (signed distance functions meshed by marching
//!   tetrahedra) with their known necks: the ground truth of the test suite.
//! - [`pipeline`]: the only module that composes the others.
//!
//! Every fallible call returns [`Result`] with the one [`Error`] type, whose message is a
//! single line naming the file and the line or byte where the problem is.

pub mod distance;
pub mod error;
mod geom;
pub mod io;
pub mod loops;
pub mod mesh;
pub mod morse;
pub mod output;
pub mod pipeline;
pub mod progress;
pub mod render;
pub mod shapes;
pub mod tet;
#[cfg(feature = "tetgen")]
pub mod tetgen;
pub mod volume;

pub use error::{Error, ErrorKind, Location, Result};
pub use mesh::{MeshReport, SurfaceMesh};
pub use tet::{TetMesh, VertexKind};
