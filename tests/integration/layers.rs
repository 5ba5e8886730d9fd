//! The top-level modules of `src/` form layers: no module reaches, directly or through others,
//! back into a module that uses it. A cycle makes every module in it depend on all the others,
//! so this test names the modules of any cycle that comes back and the uses that make it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use crate::common::root;

/// The text of a file without its test module (tests may reach anywhere).
fn code_without_tests(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    match text.find("#[cfg(test)]") {
        Some(k) => text[..k].to_string(),
        None => text,
    }
}

fn rust_files(path: &Path, files: &mut Vec<std::path::PathBuf>) {
    if path.is_dir() {
        for entry in std::fs::read_dir(path).expect("read src").flatten() {
            rust_files(&entry.path(), files);
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        files.push(path.to_path_buf());
    }
}

/// Module -> the top-level modules it names as `crate::X` (alone or in `use crate::{X, ...}`),
/// with one file that does, for the message.
fn uses(src: &Path) -> BTreeMap<String, BTreeMap<String, String>> {
    let modules: BTreeSet<String> = std::fs::read_dir(src)
        .expect("read src")
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let module = name.strip_suffix(".rs").unwrap_or(&name).to_string();
            (e.path().is_dir() || name.ends_with(".rs")).then_some(module)
        })
        .filter(|m| !["lib", "main", "bin"].contains(&m.as_str()))
        .collect();
    let mut edges: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    for module in &modules {
        let mut files = Vec::new();
        let file = src.join(format!("{module}.rs"));
        let folder = src.join(module);
        rust_files(if file.is_file() { &file } else { &folder }, &mut files);
        for file in files {
            let code = code_without_tests(&file);
            let mut named = BTreeSet::new();
            for (k, _) in code.match_indices("crate::") {
                let rest = &code[k + "crate::".len()..];
                if let Some(group) = rest.strip_prefix('{') {
                    let group = &group[..group.find('}').unwrap_or(group.len())];
                    named.extend(
                        group
                            .split([',', '\n', ' '])
                            .map(|p| p.split("::").next().unwrap_or_default().trim().to_string()),
                    );
                } else {
                    let end = rest
                        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                        .unwrap_or(rest.len());
                    named.insert(rest[..end].to_string());
                }
            }
            for other in named {
                if modules.contains(&other) && &other != module {
                    edges
                        .entry(module.clone())
                        .or_default()
                        .entry(other)
                        .or_insert_with(|| file.display().to_string());
                }
            }
        }
    }
    edges
}

/// The modules that reach themselves again through their uses.
fn modules_in_cycles(edges: &BTreeMap<String, BTreeMap<String, String>>) -> BTreeSet<String> {
    let reaches = |from: &str| {
        let mut seen = BTreeSet::new();
        let mut pending: Vec<&str> = edges
            .get(from)
            .into_iter()
            .flatten()
            .map(|(m, _)| m.as_str())
            .collect();
        while let Some(m) = pending.pop() {
            if seen.insert(m.to_string()) {
                pending.extend(edges.get(m).into_iter().flatten().map(|(n, _)| n.as_str()));
            }
        }
        seen
    };
    edges
        .keys()
        .filter(|m| reaches(m).contains(*m))
        .cloned()
        .collect()
}

#[test]
fn no_top_level_module_depends_on_itself_through_others() {
    let edges = uses(&root().join("src"));
    assert!(
        edges.len() > 10,
        "the scan found too few modules: {edges:?}"
    );
    let cyclic = modules_in_cycles(&edges);
    let why: Vec<String> = cyclic
        .iter()
        .flat_map(|m| {
            edges[m]
                .iter()
                .filter(|(n, _)| cyclic.contains(*n))
                .map(move |(n, file)| format!("{m} -> {n} ({file})"))
        })
        .collect();
    assert!(
        cyclic.is_empty(),
        "modules in a cycle: {cyclic:?}\n{}",
        why.join("\n")
    );
}

#[test]
fn the_scan_sees_a_cycle_when_there_is_one() {
    let dir = tempfile::tempdir().expect("tempdir");
    let src = dir.path();
    std::fs::write(src.join("a.rs"), "use crate::b::X;").expect("a");
    std::fs::create_dir(src.join("b")).expect("b");
    std::fs::write(src.join("b/mod.rs"), "pub mod inner;").expect("b");
    std::fs::write(src.join("b/inner.rs"), "use crate::{c::Y, geometry};").expect("inner");
    std::fs::write(
        src.join("c.rs"),
        "fn f() { crate::a::g() }\n#[cfg(test)]\nuse crate::d;",
    )
    .expect("c");
    std::fs::write(src.join("d.rs"), "use crate::a;").expect("d");
    let edges = uses(src);
    let cyclic: Vec<String> = modules_in_cycles(&edges).into_iter().collect();
    assert_eq!(cyclic, ["a", "b", "c"], "{edges:?}");
}
