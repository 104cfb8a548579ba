//! Surgery on a closed surface along its neck loops: removing a handle by cutting the solid
//! through its neck, or a tunnel by plugging the hole (the paper's sec. 1 names topology
//! repair among the loops' uses). This module holds the pieces of one operation;
//! `pipeline::repairing` cuts the band out (with `segment`), checks the result and chooses
//! the loops (`docs/design-repair.md`).
//!
//! - [`offset_curves`] → [`Offsets`]: the two curves at signed distance ±δ from a loop,
//!   through the surface, that bound the band a cut removes: over the faces reached from
//!   the loop while a corner lies within 1.5δ, the signed distance to the loop's polyline
//!   at their vertices (signed by the face normal × the segment's direction; along an
//!   edge, both faces' normals), marching triangles, and per sign the longest closed
//!   chain if at least half the loop long. Points are [`OnSurface`], the shape of
//!   `segment::CurvePoint`.
//! - [`refine_near`] → [`Refined`]: the surface near a loop with its edges within
//!   `reach` of it split at their midpoints in rounds until they are short against the
//!   loop (each triangle in 2, 3 or 4, so the mesh stays conforming; the input's
//!   vertices first), and the loop carried onto it with its crossings of the new edges.
//! - [`cap`] → [`Cap`]: the disk that closes a boundary left by a cut: concentric rings
//!   from the boundary to a centre, about the local edge length apart, placed on the cone
//!   from a point (the neck's saddle, as the plane-built membrane is), zipped by
//!   parameter, then faired with the boundary fixed as [`Fairing`] says
//!   ([`Fairing::MinimalArea`], the default: a uniform harmonic solve, then minimal-area
//!   steps with clamped cotangent weights, each kept only if it lowers the area;
//!   [`Fairing::Harmonic`]; [`Fairing::Cone`]); the solves are Jacobi-preconditioned
//!   conjugate gradients ([`CapOptions`]).
//!
//! Conventions: lengths in the surface's units; a cap's triangles run along its boundary
//! in the order given (the directed edge `b[i] → b[i + 1]` is in the disk), so the
//! caller orients it by the order it passes. Sequential per cap (the caps of one round
//! are independent items).

mod band;
mod cap;
mod refine;

pub use band::{offset_curves, Offsets, OnSurface};
pub use cap::{cap, Cap, CapOptions, Fairing};
pub use refine::{refine_near, Refined};
