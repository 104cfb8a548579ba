//! What the benchmarks share: the list of shared meshes to run on.

use std::path::PathBuf;

/// The mesh files of the folder given as the first free argument (default
/// `../shared/data/meshes` beside the repository), sorted; with `--only NAME`, those
/// whose file name contains NAME. `None` when the folder cannot be read.
pub fn shared_meshes() -> Option<Vec<PathBuf>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let only = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|i| args.get(i + 1).cloned());
    let dir = args
        .iter()
        .find(|a| !a.starts_with('-') && Some(*a) != only.as_ref())
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/meshes")
        });
    let Ok(files) = necklace::io::mesh_files(&dir) else {
        println!("no mesh folder at {}", dir.display());
        return None;
    };
    let files = files
        .into_iter()
        .filter(|p| {
            only.as_ref().is_none_or(|o| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().contains(o.as_str()))
            })
        })
        .collect();
    Some(files)
}
