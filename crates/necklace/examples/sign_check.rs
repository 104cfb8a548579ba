//! Checks the signed distance's sign against the exact winding number at random points
//! near a mesh's vertices and in its bounding box, and prints how many disagree (the
//! first few with their closest face). The solid is where the exact winding number is
//! at least ½; points within ¼ of ½ in winding number, or on the surface, are skipped.
//!
//! `cargo run --release -p necklace --example sign_check -- MESH [POINTS]` (default 4000).

use necklace::pipeline::load_surface;

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next() else {
        eprintln!("usage: sign_check MESH [POINTS]");
        std::process::exit(2);
    };
    let points: usize = match args.next().map(|s| s.parse()) {
        None => 4000,
        Some(Ok(n)) => n,
        Some(Err(e)) => {
            eprintln!("sign_check: POINTS: {e}");
            std::process::exit(2);
        }
    };
    let prepared = match load_surface(&path) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("sign_check: {e}");
            std::process::exit(1);
        }
    };
    let (mesh, distance) = (&prepared.mesh, &prepared.distance);
    let Some((lo, hi)) = mesh.bounding_box() else {
        eprintln!("sign_check: {path}: no vertices");
        std::process::exit(1);
    };
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    // xorshift: the same points on every run.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut random = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut checked, mut wrong) = (0, 0);
    for i in 0..points {
        let p = if i % 2 == 0 {
            // Near a vertex: within 2 % of the diagonal, most much nearer.
            let v = mesh.positions[(random() * mesh.positions.len() as f64) as usize];
            let reach = 0.02 * diagonal * random().powi(3);
            [0, 1, 2].map(|k| v[k] + reach * (2.0 * random() - 1.0))
        } else {
            [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * random())
        };
        let winding = distance.winding_number_exact(p);
        let signed = distance.signed_distance(p);
        if (winding - 0.5).abs() < 0.25 || signed.abs() < 1e-9 * diagonal {
            continue;
        }
        checked += 1;
        if (signed < 0.0) != (winding >= 0.5) {
            wrong += 1;
            if wrong <= 3 {
                let closest = distance.closest_point(p);
                let q = closest.point;
                let next = [0, 1, 2].map(|k| q[k] + 1e-6 * (p[k] - q[k]));
                println!(
                    "  at {p:?}: signed distance {signed}, exact winding number {winding}, closest point {q:?} on face {}, winding number next to it {}",
                    closest.face,
                    distance.winding_number_exact(next)
                );
            }
        }
    }
    println!("{path}: {checked} points checked, {wrong} with the wrong sign");
}
