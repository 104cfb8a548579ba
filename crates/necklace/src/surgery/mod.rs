//! Surgery on a closed surface along its neck loops: removing a handle by cutting the
//! solid through its neck, or a tunnel by plugging the hole (issue 41; the paper's
//! sec. 1 names topology repair among the loops' uses). This module holds the pieces of
//! one operation; `pipeline::repairing` cuts the band out (with `segment`), checks the
//! result and chooses the loops (`docs/design-repair.md`).
//!
//! - [`offset_curves`]: the two curves at signed distance ±δ from a loop, through the
//!   surface, that bound the band a cut removes (marching triangles over the signed
//!   distance to the loop, on the faces reached from it).
//! - [`refine_near`]: the surface near a loop with its edges split until they are
//!   short against the loop (edge bisection, conforming), and the loop carried onto it.
//! - [`cap`]: the disk that closes a boundary left by a cut: concentric rings from the
//!   boundary to a centre, about the local edge length apart, placed on the cone from a
//!   point (the neck's saddle, as the plane-built membrane is) and then faired with the
//!   boundary fixed: a harmonic solve, then minimal-area steps.
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
