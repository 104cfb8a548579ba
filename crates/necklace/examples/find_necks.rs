//! Load a mesh, find its neck loops, write them: `cargo run --release -p necklace --example
//! find_necks -- MESH [OUT_DIR]` (default: a generated varying torus into `necks/`).

fn main() -> necklace::Result<()> {
    let mut args = std::env::args().skip(1);
    let surface = match args.next() {
        Some(path) => necklace::io::read_mesh(path)?,
        None => necklace::shapes::Shape::new(necklace::shapes::ShapeKind::VaryingTorus).mesh()?,
    };
    let report = necklace::find_necks(&surface, &necklace::Options::default())?;
    for (i, l) in report.loops.iter().enumerate() {
        println!(
            "{i}: {:?}, length {:.4}, centre {:.3?}",
            l.kind, l.length, l.center
        );
    }
    let out = std::path::PathBuf::from(args.next().unwrap_or_else(|| "necks".into()));
    let files = necklace::output::OutputOptions::default();
    necklace::output::write_run(&out, &surface, &report, &files, None)?;
    println!(
        "{} loops -> {}",
        report.loops.len(),
        out.join("loops.obj").display()
    );
    Ok(())
}
