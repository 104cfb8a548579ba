//! Morse-stage benchmark (issue 4): for every shared mesh in both modes at the default
//! spacing, the unknowns, CG iterations per heat step, and seconds for assembly, the 20
//! heat steps and the 11 classifications (steps 10..=20), plus classification speed.
//!
//! Run: `cargo bench -p necklace --bench morse [-- MESH_DIR] [--only NAME]` (default
//! `../shared/data/meshes` beside the repository).

use necklace::io;
use necklace::morse::MorseOptions;
use necklace::pipeline::critical_points;
use necklace::volume::{volume_mesh, VolumeOptions};
use necklace::Side;

mod common;

fn main() {
    let Some(files) = common::shared_meshes() else {
        return;
    };
    println!("threads: {}", rayon::current_num_threads());
    println!(
        "| model | mode | unknowns | CG its/step (min–max) | assembly s | 20 steps s | classify s (11×) | Mvert/s | 2-saddles (all / kept) | morse ok |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---|");
    for file in &files {
        let surface =
            necklace::pipeline::prepare_input(io::read_mesh(file).expect("readable mesh"))
                .expect("a usable mesh")
                .mesh;
        for side in [Side::Inside, Side::Outside] {
            let volume = volume_mesh(&surface, side, &VolumeOptions::default()).expect("meshing");
            let r = critical_points(&surface, &volume, &MorseOptions::default()).expect("morse");
            let its: Vec<usize> = r.solver.iter().map(|s| s.iterations).collect();
            let classified = r.steps.len() as f64 * volume.mesh.num_vertices() as f64;
            let last = r.steps.last().expect("a classified step");
            let name = file
                .file_name()
                .map_or(String::new(), |n| n.to_string_lossy().into());
            println!(
                "| {name} | {side:?} | {} | {}–{} | {:.2} | {:.2} | {:.2} | {:.1} | {} / {} | {} |",
                r.unknowns,
                its.iter().min().unwrap_or(&0),
                its.iter().max().unwrap_or(&0),
                r.timings.assembly,
                r.timings.smoothing,
                r.timings.classification,
                classified / r.timings.classification / 1e6,
                last.saddles2,
                r.saddles.len(),
                r.morse_failures().count() == 0,
            );
        }
    }
}
