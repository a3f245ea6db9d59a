//! No import circles inside a crate (ARCHITECTURE.md § Rules): for every crate's `src/`
//! and every module folder in it, the modules that a module's non-test code names
//! (`crate::m` at the crate's top level, `super::m` between siblings) form a graph
//! without cycles. A circle means two modules are one idea split in two files, or that
//! a lower layer reaches up; either way the fix is to move what both need below both.
//!
//! The scan is textual: it reads each file up to its first `#[cfg(test)]` (test modules
//! may use anything), skips comment lines, and takes the identifier after `crate::` and
//! `super::`. It cannot see a path built by a macro; the project has none.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every crate's source root, from the workspace root.
const CRATES: [&str; 8] = [
    "device/src",
    "arm/src",
    "world/src",
    "hil/src",
    "hil/session/src",
    "hil/diagnose/src",
    "hil/import/src",
    "hil/wire/src",
];

/// The identifiers that follow `prefix` in `code`.
fn names_after<'a>(code: &'a str, prefix: &'a str) -> impl Iterator<Item = String> + 'a {
    code.match_indices(prefix).filter_map(move |(i, _)| {
        // `foo_crate::x` is not `crate::x`.
        let before = code[..i].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            return None;
        }
        let rest = &code[i + prefix.len()..];
        let name: String = rest
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        (!name.is_empty()).then_some(name)
    })
}

/// A file's code outside its tests and comments.
fn code_of(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The `.rs` files under `dir`, with their path relative to it.
fn rust_files(dir: &Path) -> Vec<(PathBuf, PathBuf)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push((p.strip_prefix(dir).unwrap().to_path_buf(), p));
            }
        }
    }
    out.sort();
    out
}

/// The module of `rel` at the level of `dir` (its first component, `foo` for `foo.rs`
/// and `foo/…`), or `None` for the level's own root file.
fn module_of(rel: &Path) -> Option<String> {
    let first = rel.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    (!["lib", "main", "mod"].contains(&name)).then(|| name.to_string())
}

/// The graph of the modules directly in `dir`. At a crate's root, `crate::m` names a
/// module anywhere below; in any folder, `super::m` in a file directly in it names a
/// sibling.
fn graph(dir: &Path, crate_root: bool) -> BTreeMap<String, BTreeSet<String>> {
    let files = rust_files(dir);
    let modules: BTreeSet<String> = files.iter().filter_map(|(r, _)| module_of(r)).collect();
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (rel, path) in &files {
        let Some(m) = module_of(rel) else { continue };
        let code = code_of(path);
        let direct = rel.components().count() == 1;
        let mut uses: Vec<String> = Vec::new();
        if crate_root {
            uses.extend(names_after(&code, "crate::"));
        }
        if direct {
            uses.extend(names_after(&code, "super::"));
        }
        let entry = g.entry(m.clone()).or_default();
        entry.extend(uses.into_iter().filter(|u| *u != m && modules.contains(u)));
    }
    g
}

/// A cycle of `g`, if it has one.
fn cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        g: &BTreeMap<String, BTreeSet<String>>,
        v: &str,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|p| p == v) {
            let mut c = path[at..].to_vec();
            c.push(v.to_string());
            return Some(c);
        }
        if done.contains(v) {
            return None;
        }
        path.push(v.to_string());
        for w in g.get(v).into_iter().flatten() {
            if let Some(c) = visit(g, w, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(v.to_string());
        None
    }
    let mut done = BTreeSet::new();
    g.keys()
        .find_map(|v| visit(g, v, &mut Vec::new(), &mut done))
}

#[test]
fn no_crate_has_an_import_circle_between_its_modules() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut circles = Vec::new();
    let mut folders = 0;
    for krate in CRATES {
        let src = root.join(krate);
        let mut dirs = vec![(src.clone(), true)];
        dirs.extend(
            rust_files(&src)
                .iter()
                .filter_map(|(_, p)| p.parent().map(Path::to_path_buf))
                .filter(|d| *d != src)
                .collect::<BTreeSet<_>>()
                .into_iter()
                .map(|d| (d, false)),
        );
        for (dir, crate_root) in dirs {
            folders += 1;
            if let Some(c) = cycle(&graph(&dir, crate_root)) {
                circles.push(format!("{}: {}", dir.display(), c.join(" -> ")));
            }
        }
    }
    assert!(folders >= 20, "only {folders} module folders scanned");
    assert!(
        circles.is_empty(),
        "import circles:\n{}",
        circles.join("\n")
    );
}

/// The scan finds a circle where there is one, and none where the arrows run one way.
#[test]
fn the_scan_sees_a_circle_and_only_a_circle() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    write("lib.rs", "mod a;\nmod b;\nmod c;\n");
    write(
        "a.rs",
        "use crate::b::X;\n// use crate::c::Y; (a comment)\n",
    );
    write(
        "b.rs",
        "use super::c::Y;\n#[cfg(test)]\nmod tests { use crate::a::Z; }\n",
    );
    write("c.rs", "pub struct Y; fn f() { let _ = my_crate::a::Z; }\n");
    assert_eq!(cycle(&graph(dir.path(), true)), None);
    write("c.rs", "pub struct Y; fn f() { let _ = crate::a::Z; }\n");
    assert_eq!(
        cycle(&graph(dir.path(), true)),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
}
