//! Golden outputs: what the reconstruction wrote for a fixed input, committed under
//! `tests/golden/`, so that a change meant to change no result (a refactoring) proves it. JSON is
//! compared as values: object keys in any order, numbers within float noise, everything else
//! (ids, models, edges and their order, counts) exactly. `ISCENE_BLESS=1` rewrites the golden
//! files from the current outputs instead; a change that means to change results does that and
//! says why in its commit.

use std::path::{Path, PathBuf};

use serde_json::Value;

/// Numbers closer than this (absolute or relative) are the same number.
const FLOAT_NOISE: f64 = 1e-4;

/// Keys of report.json that say how the run went rather than what it found: wall times, paths
/// and the output listing.
const REPORT_VOLATILE: &[&str] = &[
    "input",
    "timings",
    "outputs",
    "rest_wall_s",
    "wall_s",
    "map_memory_mb",
];

fn golden_path(name: &str) -> PathBuf {
    super::root().join("tests/golden").join(name)
}

/// Compares the JSON file `actual` with the golden file `name` (or blesses it), leaving out every
/// object key in `volatile`, at any depth.
pub fn assert_json_matches(actual: &Path, name: &str, volatile: &[&str]) {
    let text = std::fs::read_to_string(actual)
        .unwrap_or_else(|e| panic!("reading {}: {e}", actual.display()));
    let mut value: Value = serde_json::from_str(&text).expect("actual JSON");
    strip(&mut value, volatile);
    let golden = golden_path(name);
    if std::env::var_os("ISCENE_BLESS").is_some() {
        std::fs::create_dir_all(golden.parent().expect("parent")).expect("golden folder");
        let pretty = serde_json::to_string_pretty(&value).expect("serialise");
        std::fs::write(&golden, pretty + "\n").expect("write golden");
        return;
    }
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(&golden).unwrap_or_else(|e| {
            panic!(
                "reading golden {}: {e} (ISCENE_BLESS=1 writes it)",
                golden.display()
            )
        }))
        .expect("golden JSON");
    let mut differences = Vec::new();
    compare(&expected, &value, String::new(), &mut differences);
    assert!(
        differences.is_empty(),
        "{} differs from {} in {} places (the first 20 below); a change meant to change results \
         rewrites it with ISCENE_BLESS=1 and says why:\n{}",
        actual.display(),
        golden.display(),
        differences.len(),
        differences
            .iter()
            .take(20)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// A reconstruction's report.json against its golden file, without the run's own figures.
pub fn assert_report_matches(actual: &Path, name: &str) {
    assert_json_matches(actual, name, REPORT_VOLATILE);
}

fn strip(value: &mut Value, volatile: &[&str]) {
    match value {
        Value::Object(map) => {
            map.retain(|k, _| !volatile.contains(&k.as_str()));
            map.values_mut().for_each(|v| strip(v, volatile));
        }
        Value::Array(items) => items.iter_mut().for_each(|v| strip(v, volatile)),
        _ => {}
    }
}

fn compare(expected: &Value, actual: &Value, at: String, out: &mut Vec<String>) {
    match (expected, actual) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (
                a.as_f64().unwrap_or(f64::NAN),
                b.as_f64().unwrap_or(f64::NAN),
            );
            let noise = FLOAT_NOISE * a.abs().max(b.abs()).max(1.0);
            if (a - b).abs() > noise {
                out.push(format!("{at}: {a} became {b}"));
            }
        }
        (Value::Object(a), Value::Object(b)) => {
            for (k, va) in a {
                match b.get(k) {
                    Some(vb) => compare(va, vb, format!("{at}.{k}"), out),
                    None => out.push(format!("{at}.{k}: missing")),
                }
            }
            for k in b.keys().filter(|k| !a.contains_key(*k)) {
                out.push(format!("{at}.{k}: new"));
            }
        }
        (Value::Array(a), Value::Array(b)) => {
            if a.len() != b.len() {
                out.push(format!("{at}: {} items became {}", a.len(), b.len()));
            }
            for (k, (va, vb)) in a.iter().zip(b).enumerate() {
                compare(va, vb, format!("{at}[{k}]"), out);
            }
        }
        (a, b) if a == b => {}
        (a, b) => out.push(format!("{at}: {a} became {b}")),
    }
}
