//! The distance field, its heat smoothing and the critical points of the volume
//! (paper sections 3 and 4.1–4.2). **In progress (issue 4)**: so far the finite-element
//! operators ([`laplacian`]), the implicit heat step ([`smoothing`]) and the link
//! classification with its Morse check ([`critical`]).
//!
//! Conventions: the stiffness matrix `L` is positive semidefinite (`l = −Δf`, so the
//! implicit heat step is `(M + τL) F' = M F`), `M` is the lumped mass (a quarter of each
//! tet's volume to each of its vertices); lengths in the mesh's units.

pub mod critical;
pub mod laplacian;
pub mod smoothing;

pub use critical::{classify, Classification, VertexClass, VertexType};
pub use laplacian::{cotangent_stiffness, lumped_mass, SparseMatrix};
pub use smoothing::{implicit_step, SolverOptions, StepReport};
