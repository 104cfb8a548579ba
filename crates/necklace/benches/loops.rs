//! Loop-stage benchmark (issue 5): for every shared mesh in both modes at the default
//! settings, the seconds to cut and tighten the loops of all selected 2-saddles, with
//! what became of them and the geodesic properties of the kept loops.
//!
//! Run: `cargo bench -p necklace --bench loops [-- MESH_DIR] [--only NAME]` (default
//! `../shared/data/meshes` beside the repository). The volume mesh and the Morse stage
//! run first and are not timed here (see the `volume` and `morse` benchmarks).

use std::collections::BTreeMap;

use necklace::io;
use necklace::loops::{find_loops, LoopOptions};
use necklace::morse::MorseOptions;
use necklace::pipeline::{critical_points, loop_seeds};
use necklace::volume::{volume_mesh, VolumeOptions};
use necklace::Side;

mod common;

fn main() {
    let Some(files) = common::shared_meshes() else {
        return;
    };
    println!("threads: {}", rayon::current_num_threads());
    println!(
        "| model | mode | saddles | loops | dropped | prep ms | cut + tighten ms | rounds (max) | max edge turn | min vertex angle − π | all simple | longest / initial |"
    );
    println!("|---|---|---:|---:|---|---:|---:|---:|---:|---:|---|---:|");
    for file in &files {
        let surface =
            necklace::pipeline::prepare_input(io::read_mesh(file).expect("readable mesh"))
                .expect("a usable mesh")
                .mesh;
        for side in [Side::Inside, Side::Outside] {
            let volume = volume_mesh(&surface, side, &VolumeOptions::default()).expect("meshing");
            let r = critical_points(&surface, &volume, &MorseOptions::default()).expect("morse");
            let seeds = loop_seeds(&r);
            let found = find_loops(&surface, &seeds, side, &LoopOptions::default()).expect("loops");
            let mut reasons: BTreeMap<String, usize> = BTreeMap::new();
            for d in &found.dropped {
                let v = serde_json::to_value(d).expect("json");
                *reasons
                    .entry(v["reason"].as_str().unwrap_or("?").to_string())
                    .or_default() += 1;
            }
            let dropped: Vec<String> = reasons.iter().map(|(k, v)| format!("{v} {k}")).collect();
            let t =
                |f: fn(&necklace::loops::NeckLoop) -> f64, init: f64, pick: fn(f64, f64) -> f64| {
                    found.loops.iter().map(f).fold(init, pick)
                };
            let name = file
                .file_name()
                .map_or(String::new(), |n| n.to_string_lossy().into());
            println!(
                "| {name} | {side:?} | {} | {} | {} | {:.1} | {:.1} | {} | {:.1e} | {:.1e} | {} | {:.4} |",
                seeds.len(),
                found.loops.len(),
                if dropped.is_empty() { "–".to_string() } else { dropped.join(", ") },
                1e3 * found.timings.preparation,
                1e3 * found.timings.cut_and_tighten,
                found.loops.iter().map(|l| l.tightening.rounds).max().unwrap_or(0),
                t(|l| l.tightening.max_edge_turn, 0.0, f64::max),
                t(|l| l.tightening.min_vertex_angle, std::f64::consts::PI, f64::min) - std::f64::consts::PI,
                found.loops.iter().all(|l| l.tightening.simple),
                t(|l| l.length / l.initial_length, 0.0, f64::max),
            );
        }
    }
}
