//! # necklace
//!
//! Finds the *neck loops* of a closed triangle mesh: loops that lasso the narrow parts of
//! the solid (handles) and of the space around it (tunnels), following "Fast Computation
//! of Neck-like Features" (the paper; see `ARCHITECTURE.md` for the stage diagram).
//!
//! ```no_run
//! # fn main() -> necklace::Result<()> {
//! let surface = necklace::io::read_mesh("fertility.off")?;
//! let report = necklace::find_necks(&surface, &necklace::Options::default())?;
//! for (i, l) in report.loops.iter().enumerate() {
//!     println!("{i}: {:?} of length {:.4} around {:?}", l.kind, l.length, l.center);
//! }
//! # Ok(())
//! # }
//! ```
//!
//! ## Entry point
//! [`find_necks`]`(&SurfaceMesh, &Options) -> Result<NeckReport>` runs the whole method:
//! for each side asked for, volume mesh → distance field → smoothing and critical points
//! → loops. [`Options`] (`pipeline::NeckOptions`) holds every stage's options with
//! documented defaults; [`NeckReport`] carries the loops, every saddle that gave no loop
//! with its reason, the Morse check and the seconds per stage.
//! [`pipeline::find_necks_with_progress`] reports progress through [`progress::Progress`];
//! [`output::write_run`] writes a run's files (`loops.obj`, `loops.ply`, `loops.json`,
//! `critical.ply`, `view.png`, `field.vtu`); `examples/find_necks.rs` does it in 15 lines.
//!
//! ## The stages, in the order they run
//! - [`volume`] (paper sec. 4, "preprocessing"): isosurface stuffing (Labelle & Shewchuk
//!   2007) of the inside, and of the shell between the surface and a bounding sphere, on
//!   a graded BCC lattice; our replacement for TetGen (optional `tetgen` feature).
//! - [`distance`] (service): exact distance, winding number and rays against the surface;
//!   the Morse function is the exact distance (the paper used fast marching).
//! - [`morse`] (sec. 3, 4.1–4.2): heat smoothing (M + τL)F' = MF, link classification with
//!   the Morse check, tracking under smoothing, and the 2-saddles that mark necks with
//!   their Hessian and cutting-plane normal.
//! - [`loops`] (sec. 4.3): plane cut through each saddle, geodesic tightening (strip
//!   unfolding and funnel), selection with a reason for every drop.
//! - [`segment`] (after the method; sec. 1 names it as the loops' use): cut the surface
//!   along loops into parts, with their areas, volumes and topology
//!   ([`pipeline::segment_along_loops`]).
//! - [`surgery`] (after the method): removing handles and tunnels along
//!   their loops: the band's curves round a loop and the caps that close a cut;
//!   [`pipeline::repair`] (`necklace repair`) composes them with `segment`.
//! - [`pipeline`] composes them; [`output`] writes their results; [`render`] draws
//!   pictures (not in the paper).
//! - [`batch`] runs the method over a dataset: a worker process per mesh under a time and
//!   a memory limit, one resumable JSON row per mesh (`necklace batch`, `necklace.batch`).
//!
//! ## Data and services
//! - [`mesh`]: [`SurfaceMesh`], its topology and validity report ([`MeshReport`]).
//! - [`tet`]: [`TetMesh`], the volume mesh passed between volume stages.
//! - [`io`]: OBJ, OFF, PLY and STL meshes; point clouds and polylines; tet meshes in
//!   TetGen, Medit, Gmsh and VTU formats.
//! - [`shapes`]: analytic test shapes with their known necks: the ground truth of the
//!   tests and the shapes of `necklace demo`.
//!
//! Conventions: coordinates in the input's units and frame; triangles counter-clockwise
//! seen from outside (inward input is flipped and reported). Every fallible call returns
//! [`Result`] with the one [`Error`] type, whose message is a single line naming the file
//! and the line or byte where the problem is. Results do not depend on the thread count.

pub mod batch;
pub mod distance;
pub mod error;
pub mod file;
mod geom;
pub mod io;
pub mod loops;
pub mod mesh;
pub mod morse;
pub mod output;
pub mod pipeline;
pub mod progress;
pub mod render;
pub mod segment;
pub mod shapes;
pub mod simplify;
pub mod surgery;
pub mod tet;
pub mod volume;

pub use error::{Error, ErrorKind, Location, Result};
pub use mesh::{MeshReport, Side, SurfaceMesh};
pub use pipeline::{find_necks, NeckOptions as Options, NeckReport};
pub use tet::{TetMesh, VertexKind};
