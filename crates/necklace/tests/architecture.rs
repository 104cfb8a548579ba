//! The import rules of ARCHITECTURE.md: data modules import only data modules, stages
//! import only data modules and services (never another stage), only the composers
//! (`pipeline`, and `output` for the files and pictures of a run) import stages.

use std::collections::BTreeSet;
use std::path::Path;

const DATA: &[&str] = &["error", "file", "geom", "mesh", "tet", "progress"];
/// Shared queries over data that several stages need (imports data only).
const SERVICES: &[&str] = &["distance"];
/// Modules that may import everything; no other module imports them.
const COMPOSERS: &[&str] = &["pipeline", "output"];
const STAGES: &[&str] = &[
    "io", "shapes", "volume", "morse", "loops", "render", "tetgen",
];

/// The top-level modules referenced as `crate::name` anywhere in `path` (file or dir).
fn crate_imports(path: &Path) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut files = vec![path.to_path_buf()];
    while let Some(p) = files.pop() {
        if p.is_dir() {
            for entry in std::fs::read_dir(&p).unwrap() {
                files.push(entry.unwrap().path());
            }
        } else if p.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&p).unwrap();
            for (i, _) in text.match_indices("crate::") {
                // Skip `necklace_crate::` style prefixes: require a non-identifier before.
                let before = text[..i].chars().next_back();
                if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                    continue;
                }
                let name: String = text[i + 7..]
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        }
    }
    out
}

#[test]
fn modules_follow_the_import_rules() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut checked = 0;
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        if name == "lib" || COMPOSERS.contains(&name.as_str()) {
            continue;
        }
        let imports = crate_imports(&path);
        let allowed: Vec<&str> = if let Some(pos) = DATA.iter().position(|d| *d == name) {
            DATA[..pos].to_vec()
        } else if SERVICES.contains(&name.as_str()) {
            DATA.to_vec()
        } else if STAGES.contains(&name.as_str()) {
            [DATA, SERVICES].concat()
        } else {
            panic!("module {name} is neither data, a service nor a stage: add it to ARCHITECTURE.md and this test");
        };
        for import in &imports {
            if import == &name {
                continue;
            }
            assert!(
                allowed.contains(&import.as_str()),
                "module {name} imports crate::{import}, which ARCHITECTURE.md does not allow"
            );
        }
        checked += 1;
    }
    assert!(checked >= 5);
}

#[test]
fn no_module_imports_a_composer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        if name == "lib" {
            continue;
        }
        for import in crate_imports(&path) {
            assert!(
                import == name || !COMPOSERS.contains(&import.as_str()) || name == "output",
                "module {name} imports the composer crate::{import}"
            );
        }
    }
}
