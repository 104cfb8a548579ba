//! The import rules of ARCHITECTURE.md: data modules import only data modules before
//! them (`progress` nothing), services only data, stages only data and services (never
//! another stage), only the composers (`pipeline`, `output` for the files and
//! pictures of a run, and `batch` for dataset runs above both) import stages, and each third-party crate is named only by the
//! modules allowed to.
//!
//! Paths are read from the source with comments and literals blanked out: every `use`
//! tree is expanded (grouped imports `use crate::{a::X, b::Y}` give both paths), `super::`
//! and `self::` are resolved against the file's own module, and inline paths
//! (`crate::geom::norm(..)`, `nalgebra::Matrix3::zeros()`) count too. The probes at the
//! end feed the checker sources that break each rule, so a blind spot fails the suite.

use std::collections::BTreeSet;
use std::path::Path;

const DATA: &[&str] = &["error", "file", "geom", "mesh", "tet", "progress"];
/// Shared queries over data that several stages need (imports data only).
const SERVICES: &[&str] = &["distance"];
/// Modules that may import everything; no other module imports them.
const COMPOSERS: &[&str] = &["pipeline", "output", "batch"];
const STAGES: &[&str] = &[
    "io", "shapes", "simplify", "volume", "morse", "loops", "segment", "surgery", "render",
];

/// Third-party crates and the modules that may name them, with their submodules
/// (`None`: any).
const CRATES: &[(&str, Option<&[&str]>)] = &[
    ("serde", None),
    ("rayon", None),
    ("tritet", Some(&["volume::tetgen"])),
    ("robust", Some(&["volume::delaunay", "distance::crossing"])),
    ("kiddo", Some(&["morse"])),
    ("nalgebra", Some(&["morse", "loops"])),
    ("png", Some(&["render"])),
    ("flate2", Some(&["io::vtk"])),
    ("serde_json", Some(&["output", "batch"])),
    ("sha2", Some(&["batch"])),
    ("rustc_hash", Some(&["volume", "loops::cut"])),
    ("indicatif", Some(&[])),
];

/// `text` with comments, string and character literals replaced by spaces (line
/// structure kept), so that only code is searched for paths.
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    let blank = |out: &mut Vec<u8>, bytes: &[u8]| {
        out.extend(bytes.iter().map(|&c| if c == b'\n' { b'\n' } else { b' ' }));
    };
    while i < b.len() {
        let rest = &b[i..];
        if rest.starts_with(b"//") {
            let end = rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
            blank(&mut out, &rest[..end]);
            i += end;
        } else if rest.starts_with(b"/*") {
            let mut depth = 0;
            let mut j = 0;
            while j < rest.len() {
                if rest[j..].starts_with(b"/*") {
                    depth += 1;
                    j += 2;
                } else if rest[j..].starts_with(b"*/") {
                    depth -= 1;
                    j += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    j += 1;
                }
            }
            blank(&mut out, &rest[..j]);
            i += j;
        } else if rest[0] == b'"' || rest.starts_with(b"r\"") || rest.starts_with(b"r#") {
            // A string: plain with escapes, or raw with n hashes.
            let (hashes, open) = if rest[0] == b'r' {
                let h = rest[1..].iter().take_while(|&&c| c == b'#').count();
                (h, 1 + h + 1)
            } else {
                (0, 1)
            };
            let mut j = open;
            while j < rest.len() {
                if rest[0] != b'r' && rest[j] == b'\\' {
                    j += 2;
                    continue;
                }
                if rest[j] == b'"' && rest[j + 1..].iter().take(hashes).all(|&c| c == b'#') {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            let j = j.min(rest.len());
            blank(&mut out, &rest[..j]);
            i += j;
        } else if rest[0] == b'\'' && (rest.get(1) == Some(&b'\\') || rest.get(2) == Some(&b'\'')) {
            // A character literal ('x' or '\n'); a lifetime ('a) has no closing quote.
            let end = rest[1..]
                .iter()
                .skip(1)
                .position(|&c| c == b'\'')
                .map_or(rest.len(), |p| p + 3);
            blank(&mut out, &rest[..end.min(rest.len())]);
            i += end.min(rest.len());
        } else {
            out.push(rest[0]);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The full paths of a `use` tree (its text after `use`, without the `;`), as
/// segments: `crate::{a::X, b::{c, d}}` gives `crate::a::X`, `crate::b::c`,
/// `crate::b::d`.
fn expand_use(tree: &str) -> Vec<Vec<String>> {
    // Drop `as alias`, then the whitespace.
    let spaced: String = tree
        .chars()
        .flat_map(|c| {
            if "{},".contains(c) {
                vec![' ', c, ' ']
            } else {
                vec![c]
            }
        })
        .collect();
    let mut kept = Vec::new();
    let mut words = spaced.split_whitespace();
    while let Some(w) = words.next() {
        if w == "as" {
            words.next();
        } else {
            kept.push(w);
        }
    }
    let tree: String = kept.concat();
    let mut out = Vec::new();
    expand_into(&tree, &mut Vec::new(), &mut out);
    out
}

fn expand_into(tree: &str, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    let tree = tree.trim_start_matches("::");
    if let Some(inner) = tree.strip_prefix('{') {
        let inner = inner.strip_suffix('}').unwrap_or(inner);
        // Split at top-level commas.
        let (mut depth, mut start) = (0, 0);
        let bytes = inner.as_bytes();
        for (k, &c) in bytes.iter().enumerate() {
            match c {
                b'{' => depth += 1,
                b'}' => depth -= 1,
                b',' if depth == 0 => {
                    expand_into(&inner[start..k], &mut prefix.clone(), out);
                    start = k + 1;
                }
                _ => {}
            }
        }
        if start < inner.len() {
            expand_into(&inner[start..], &mut prefix.clone(), out);
        }
        return;
    }
    let head: String = tree
        .chars()
        .take_while(|&c| is_ident(c) || c == '*')
        .collect();
    if head.is_empty() {
        if !prefix.is_empty() {
            out.push(prefix.clone());
        }
        return;
    }
    prefix.push(head.clone());
    let rest = &tree[head.len()..];
    if rest.starts_with("::") {
        expand_into(rest, prefix, out);
    } else {
        // `as alias` or the end.
        out.push(prefix.clone());
    }
}

/// Every path in `code` with where it starts: expanded `use` trees, and inline paths
/// (two or more segments joined by `::`) that start a path (not after another `::` or
/// an identifier).
fn paths(code: &str) -> Vec<(usize, Vec<String>)> {
    let mut out = Vec::new();
    let chars: Vec<char> = code.chars().collect();
    let text: String = chars.iter().collect();
    // `use` trees (`text` is ASCII where it matters: byte and char offsets agree up to
    // the first non-ASCII character, which only comments and strings hold).
    let mut search = 0;
    while let Some(found) = text[search..].find("use ") {
        let at = search + found;
        search = at + 4;
        let before = text[..at].chars().next_back();
        if before.is_some_and(is_ident) {
            continue;
        }
        let Some(end) = text[at..].find(';') else {
            break;
        };
        let position = text[..at].chars().count();
        out.extend(
            expand_use(&text[at + 4..at + end])
                .into_iter()
                .map(|p| (position, p)),
        );
        search = at + end;
    }
    // Inline paths.
    let mut i = 0;
    while i < chars.len() {
        let starts =
            is_ident(chars[i]) && (i == 0 || !(is_ident(chars[i - 1]) || chars[i - 1] == ':'));
        if !starts {
            i += 1;
            continue;
        }
        let mut segments = Vec::new();
        let mut j = i;
        loop {
            let start = j;
            while j < chars.len() && is_ident(chars[j]) {
                j += 1;
            }
            segments.push(chars[start..j].iter().collect::<String>());
            if j + 2 < chars.len()
                && chars[j] == ':'
                && chars[j + 1] == ':'
                && is_ident(chars[j + 2])
            {
                j += 2;
            } else {
                break;
            }
        }
        if segments.len() >= 2 {
            out.push((i, segments));
        }
        i = j.max(i + 1);
    }
    out
}

/// The inline modules (`mod tests { .. }`) open at each point of `code`: a list of
/// (position where the scope starts, module names from the file's module).
fn inline_scopes(code: &str) -> Vec<(usize, Vec<String>)> {
    let chars: Vec<char> = code.chars().collect();
    let mut out = vec![(0, Vec::new())];
    let mut stack: Vec<(usize, String)> = Vec::new();
    let mut depth = 0usize;
    let mut pending: Option<String> = None;
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c == '{' {
            depth += 1;
            if let Some(name) = pending.take() {
                stack.push((depth, name));
                out.push((i, stack.iter().map(|s| s.1.clone()).collect()));
            }
        } else if c == '}' {
            if stack.last().is_some_and(|s| s.0 == depth) {
                stack.pop();
                out.push((i, stack.iter().map(|s| s.1.clone()).collect()));
            }
            depth = depth.saturating_sub(1);
        } else if c == ';' {
            pending = None;
        } else if is_ident(c) && (i == 0 || !is_ident(chars[i - 1])) {
            let start = i;
            while i < chars.len() && is_ident(chars[i]) {
                i += 1;
            }
            let word: String = chars[start..i].iter().collect();
            if word == "mod" {
                let mut j = i;
                while j < chars.len() && chars[j].is_whitespace() {
                    j += 1;
                }
                let name_start = j;
                while j < chars.len() && is_ident(chars[j]) {
                    j += 1;
                }
                pending = Some(chars[name_start..j].iter().collect());
                i = j;
            }
            continue;
        }
        i += 1;
    }
    out
}

/// The paths of a file with the module each one is written in.
fn scoped_paths(module: &[String], text: &str) -> Vec<(Vec<String>, Vec<String>)> {
    let code = code_only(text);
    let scopes = inline_scopes(&code);
    paths(&code)
        .into_iter()
        .map(|(at, path)| {
            let inner = scopes
                .iter()
                .take_while(|(start, _)| *start <= at)
                .last()
                .map_or(Vec::new(), |s| s.1.clone());
            ([module.to_vec(), inner].concat(), path)
        })
        .collect()
}

/// The top-level module (or third-party crate, `Err`) a path in module `module` (its
/// segments from the crate root) refers to; `None` for paths inside the module itself,
/// `std`, and local names.
fn target(module: &[String], path: &[String]) -> Option<Result<String, String>> {
    let first = path.first()?.as_str();
    match first {
        "crate" => path.get(1).map(|m| Ok(m.clone())),
        "super" | "self" => {
            let mut at: Vec<String> = module.to_vec();
            let mut rest = path;
            while let Some(seg) = rest.first() {
                match seg.as_str() {
                    "super" => {
                        at.pop();
                    }
                    "self" => {}
                    _ => break,
                }
                rest = &rest[1..];
            }
            at.first().or(rest.first()).map(|m| Ok(m.clone()))
        }
        name if CRATES.iter().any(|(c, _)| *c == name) => Some(Err(name.to_string())),
        _ => None,
    }
}

/// What `name`'s files break: one line per violation. `files` are (module path from
/// the crate root, source text).
fn violations(name: &str, files: &[(Vec<String>, String)]) -> Vec<String> {
    let allowed: Vec<&str> = if let Some(pos) = DATA.iter().position(|d| *d == name) {
        if name == "progress" {
            Vec::new()
        } else {
            DATA[..pos].to_vec()
        }
    } else if SERVICES.contains(&name) {
        DATA.to_vec()
    } else if STAGES.contains(&name) {
        [DATA, SERVICES].concat()
    } else if COMPOSERS.contains(&name) {
        let mut all = [DATA, SERVICES, STAGES].concat();
        if name == "output" {
            all.push("pipeline");
        }
        if name == "batch" {
            all.extend(["pipeline", "output"]);
        }
        all
    } else {
        return vec![format!(
            "module {name} is neither data, a service, a stage nor a composer: add it to ARCHITECTURE.md and this test"
        )];
    };
    let mut out = BTreeSet::new();
    for (module, text) in files {
        for (scope, path) in scoped_paths(module, text) {
            match target(&scope, &path) {
                Some(Ok(m)) if m != name && !allowed.contains(&m.as_str()) => {
                    out.insert(format!(
                        "module {name} names crate::{m} ({}), which ARCHITECTURE.md does not allow",
                        path.join("::")
                    ));
                }
                Some(Err(krate)) => {
                    let rule = CRATES.iter().find(|(c, _)| *c == krate).and_then(|r| r.1);
                    let here = module.join("::");
                    let within = |m: &&str| here == *m || here.starts_with(&format!("{m}::"));
                    if rule.is_some_and(|mods| !mods.iter().any(within)) {
                        out.insert(format!(
                            "module {here} names the crate {krate}, which stays behind {:?}",
                            rule.unwrap_or_default()
                        ));
                    }
                }
                _ => {}
            }
        }
    }
    out.into_iter().collect()
}

/// The `.rs` files of a top-level module (a file or a folder), with their module paths.
fn module_files(path: &Path, module: Vec<String>) -> Vec<(Vec<String>, String)> {
    if path.is_dir() {
        let mut out = Vec::new();
        let mut entries: Vec<_> = std::fs::read_dir(path)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for p in entries {
            let stem = p.file_stem().unwrap().to_str().unwrap().to_string();
            let sub = if stem == "mod" {
                module.clone()
            } else {
                [module.clone(), vec![stem]].concat()
            };
            out.extend(module_files(&p, sub));
        }
        out
    } else if path.extension().is_some_and(|e| e == "rs") {
        vec![(module, std::fs::read_to_string(path).unwrap())]
    } else {
        Vec::new()
    }
}

#[test]
fn modules_follow_the_import_rules() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut checked = 0;
    let mut broken = Vec::new();
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        if name == "lib" {
            continue;
        }
        let files = module_files(&path, vec![name.clone()]);
        broken.extend(violations(&name, &files));
        checked += 1;
    }
    assert!(checked >= 15);
    assert!(broken.is_empty(), "{}", broken.join("\n"));
}

#[test]
fn only_the_cli_progress_bars_name_indicatif() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../necklace-cli/src");
    for (module, text) in module_files(&src, Vec::new()) {
        let names = scoped_paths(&module, &text)
            .iter()
            .any(|(_, p)| p.first().is_some_and(|s| s == "indicatif"));
        assert!(
            !names || module == ["progress"],
            "{module:?} names indicatif; only the CLI's progress.rs may"
        );
    }
}

#[test]
fn no_module_imports_a_composer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        if name == "lib" || COMPOSERS.contains(&name.as_str()) {
            continue;
        }
        for (module, text) in module_files(&path, vec![name.clone()]) {
            for (scope, p) in scoped_paths(&module, &text) {
                if let Some(Ok(m)) = target(&scope, &p) {
                    assert!(
                        !COMPOSERS.contains(&m.as_str()),
                        "module {name} imports the composer crate::{m}"
                    );
                }
            }
        }
    }
}

/// Each rule broken on purpose, in the ways a line scan would miss.
#[test]
fn the_checker_sees_every_kind_of_path() {
    let file = |module: &[&str], text: &str| {
        vec![(
            module.iter().map(|s| s.to_string()).collect::<Vec<_>>(),
            text.to_string(),
        )]
    };
    // A grouped import of another stage.
    let v = violations(
        "morse",
        &file(&["morse"], "use crate::{mesh::Topology, loops::Seed};"),
    );
    assert_eq!(v.len(), 1, "{v:?}");
    assert!(v[0].contains("crate::loops"), "{v:?}");
    // Nested groups, spread over lines, with an alias.
    let v = violations(
        "morse",
        &file(
            &["morse"],
            "use crate::{\n    geom::{dot, norm},\n    volume::{self as v, Domain},\n};",
        ),
    );
    assert!(
        !v.is_empty() && v.iter().all(|m| m.contains("crate::volume")),
        "{v:?}"
    );
    // `super::super::` from a nested file reaches the crate root.
    let v = violations(
        "loops",
        &file(
            &["loops", "tighten", "funnel"],
            "use super::super::super::morse::Saddle;",
        ),
    );
    assert_eq!(v.len(), 1, "{v:?}");
    assert!(v[0].contains("crate::morse"), "{v:?}");
    // ... while `super::` inside the module is the module itself, and in a test
    // module it is the file's module.
    assert!(violations("loops", &file(&["loops", "cut"], "use super::Seed;")).is_empty());
    let tests = "fn f() {}\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use super::super::Seed;\n}\nuse super::super::morse::X;";
    let v = violations("loops", &file(&["loops", "cut"], tests));
    assert_eq!(v.len(), 1, "{v:?}");
    assert!(v[0].contains("crate::morse"), "{v:?}");
    // An inline path.
    let v = violations(
        "mesh",
        &file(
            &["mesh"],
            "fn f() { crate::distance::SurfaceDistance::new(&m); }",
        ),
    );
    assert_eq!(v.len(), 1, "{v:?}");
    // Third-party crates behind their module.
    let v = violations("mesh", &file(&["mesh"], "use png::Encoder;"));
    assert!(v.len() == 1 && v[0].contains("png"), "{v:?}");
    let v = violations(
        "loops",
        &file(&["loops"], "let m = nalgebra::Matrix3::<f64>::zeros();"),
    );
    assert!(v.is_empty(), "{v:?}");
    let v = violations("volume", &file(&["volume"], "fn f() -> kiddo::KdTree { }"));
    assert!(v.len() == 1 && v[0].contains("kiddo"), "{v:?}");
    // A crate allowed in one submodule only: TetGen (AGPL) stays in `volume::tetgen`.
    let tetgen = "use tritet::Tetgen;";
    assert!(violations("volume", &file(&["volume", "tetgen"], tetgen)).is_empty());
    let v = violations("volume", &file(&["volume", "surface"], tetgen));
    assert!(v.len() == 1 && v[0].contains("volume::surface"), "{v:?}");
    // `progress` imports nothing, not even `error`.
    let v = violations(
        "progress",
        &file(&["progress"], "use crate::error::Result;"),
    );
    assert_eq!(v.len(), 1, "{v:?}");
    // Comments and strings are not code.
    let quiet =
        "// use crate::loops::X;\n/* crate::morse::Y */\nconst S: &str = \"crate::loops::Z\";";
    assert!(violations("mesh", &file(&["mesh"], quiet)).is_empty());
}
