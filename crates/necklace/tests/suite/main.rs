//! The library's integration tests, one binary (as ripgrep and parry keep theirs): one
//! module per stage or concern, `common` for what they share (the shared real meshes,
//! analytic domains). `cargo test --release -p necklace -- loops::` runs one module.

mod architecture;
mod common;
mod critical;
mod distance;
mod fuzz;
mod input;
mod io;
mod laplacian;
mod loops;
mod mesh_report;
mod morse;
mod render;
mod segment;
mod shapes;
mod shared_meshes;
mod simplify;
mod surgery;
mod tet_io;
mod tetgen;
mod volume;
mod volume_pipeline;
mod volume_topology;
