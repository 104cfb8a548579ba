//! Volume-meshing benchmark: every shared mesh in both modes at the default spacing,
//! then a series at three spacings on one model (cost per tet should stay flat).
//!
//! Run: `cargo bench -p necklace --bench volume [-- MESH_DIR] [--only NAME]` (default
//! `../shared/data/meshes` beside the repository).

use std::time::Instant;

use necklace::pipeline::{orient_for_volume, volume_mesh, Side, VolumeOptions};
use necklace::{io, SurfaceMesh};

fn run(surface: &SurfaceMesh, side: Side, h: Option<f64>) -> (usize, usize, f64) {
    let options = VolumeOptions {
        h,
        ..VolumeOptions::default()
    };
    let start = Instant::now();
    let v = volume_mesh(surface, side, &options).expect("meshing succeeds");
    (
        v.mesh.num_vertices(),
        v.mesh.num_tets(),
        start.elapsed().as_secs_f64(),
    )
}

mod common;

fn main() {
    let Some(files) = common::shared_meshes() else {
        return;
    };
    println!("threads: {}", rayon::current_num_threads());
    println!("| model | mode | vertices | tets | seconds |");
    println!("|---|---|---:|---:|---:|");
    for file in &files {
        let (surface, _, _) = orient_for_volume(io::read_mesh(file).expect("readable mesh"));
        for side in [Side::Inside, Side::Outside] {
            let (v, t, s) = run(&surface, side, None);
            let name = file
                .file_name()
                .map_or(String::new(), |n| n.to_string_lossy().into());
            println!("| {name} | {side:?} | {v} | {t} | {s:.2} |");
        }
    }

    let model = files.iter().find(|f| f.ends_with("bunny.off"));
    if let Some(mesh) = model.and_then(|m| io::read_mesh(m).ok()) {
        let (surface, _, _) = orient_for_volume(mesh);
        let diagonal = surface.bbox_diagonal();
        println!("\nseries on bunny.off (outside shell):");
        println!("| h | vertices | tets | seconds | microseconds per tet |");
        println!("|---|---:|---:|---:|---:|");
        for divisions in [32.0, 64.0, 128.0] {
            let h = diagonal / divisions;
            let (v, t, s) = run(&surface, Side::Outside, Some(h));
            println!(
                "| diag/{divisions} | {v} | {t} | {s:.2} | {:.2} |",
                1e6 * s / t as f64
            );
        }
    }
}
