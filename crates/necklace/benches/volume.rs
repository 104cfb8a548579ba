//! Volume-meshing benchmark: every shared mesh in both modes at the default spacing
//! (size, topology against the surface's prediction, dihedral angles, time per tet),
//! then a series at three spacings on one model (cost per tet should stay flat).
//!
//! Run: `cargo bench -p necklace --bench volume [-- MESH_DIR] [--only NAME]` (default
//! `../shared/data/meshes` beside the repository).

use std::time::Instant;

use necklace::volume::{volume_mesh, VolumeOptions, VolumeResult};
use necklace::Side;
use necklace::{io, SurfaceMesh};

fn run(surface: &SurfaceMesh, side: Side, h: Option<f64>) -> (VolumeResult, f64) {
    let options = VolumeOptions {
        h,
        ..VolumeOptions::default()
    };
    let start = Instant::now();
    let v = volume_mesh(surface, side, &options).expect("meshing succeeds");
    let seconds = start.elapsed().as_secs_f64();
    (v, seconds)
}

mod common;

fn main() {
    let Some(files) = common::shared_meshes() else {
        return;
    };
    println!("threads: {}", rayon::current_num_threads());
    println!("| model | mode | vertices | tets | topology (χ, genus of the boundaries) | as predicted | rounds | min dihedral ° | tets < 10° | finest cell / h | seconds | µs per tet |");
    println!("|---|---|---:|---:|---|---|---:|---:|---:|---:|---:|---:|");
    let (mut all_tets, mut all_seconds) = (0usize, 0.0);
    for file in &files {
        let surface =
            necklace::pipeline::prepare_input(io::read_mesh(file).expect("readable mesh"))
                .expect("a usable mesh")
                .mesh;
        for side in [Side::Inside, Side::Outside] {
            let (v, s) = run(&surface, side, None);
            let r = v.report();
            let name = file
                .file_name()
                .map_or(String::new(), |n| n.to_string_lossy().into());
            let predicted = match r.topology.matches {
                Some(true) => "yes",
                Some(false) => "**no**",
                None => "no prediction",
            };
            println!(
                "| {name} | {side:?} | {} | {} | {} | {predicted} | {} | {:.1} | {} | 1/{:.0} | {s:.2} | {:.2} |",
                r.vertices,
                r.tets,
                r.topology.found,
                r.topology.rounds,
                r.min_dihedral_deg,
                r.tets_below_10_deg,
                r.h / r.finest_cell,
                1e6 * s / r.tets as f64
            );
            all_tets += r.tets;
            all_seconds += s;
        }
    }
    println!(
        "\nall runs: {all_tets} tets in {all_seconds:.1} s: {:.2} µs per tet",
        1e6 * all_seconds / all_tets as f64
    );

    let model = files.iter().find(|f| f.ends_with("bunny.off"));
    if let Some(mesh) = model.and_then(|m| io::read_mesh(m).ok()) {
        let surface = necklace::pipeline::prepare_input(mesh)
            .expect("a usable mesh")
            .mesh;
        let diagonal = surface.bbox_diagonal();
        println!("\nseries on bunny.off (outside shell):");
        println!("| h | vertices | tets | seconds | microseconds per tet |");
        println!("|---|---:|---:|---:|---:|");
        for divisions in [32.0, 64.0, 128.0] {
            let h = diagonal / divisions;
            let (v, s) = run(&surface, Side::Outside, Some(h));
            let t = v.mesh.num_tets();
            println!(
                "| diag/{divisions} | {} | {t} | {s:.2} | {:.2} |",
                v.mesh.num_vertices(),
                1e6 * s / t as f64
            );
        }
    }
}
