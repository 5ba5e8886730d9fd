//! The generated specification as JSON, written without overwriting what `generate` did not
//! write.

use std::path::Path;

use serde_json::{Value, json};

use crate::error::{InputError, IsceneError};
use crate::scene::spec::ObjectSpec;

/// `v` as JSON in its shortest decimal form (0.76, not 0.7599999904632568).
pub(super) fn number(v: f32) -> Value {
    json!(format!("{v}").parse::<f64>().unwrap_or(0.0))
}

pub(super) fn numbers(values: &[f32]) -> Value {
    Value::Array(values.iter().map(|v| number(*v)).collect())
}

pub(super) fn object_json(o: &ObjectSpec) -> Value {
    let mut v = serde_json::Map::new();
    v.insert("id".into(), json!(o.id));
    v.insert("class".into(), json!(o.class));
    if let Some(m) = &o.model {
        v.insert("model".into(), json!(m));
    }
    if let Some(p) = o.position {
        v.insert("position".into(), numbers(&p));
    }
    if let Some(p) = &o.on {
        v.insert("on".into(), json!(p));
    }
    if let Some(p) = &o.inside {
        v.insert("in".into(), json!(p));
    }
    if let Some(p) = o.offset {
        v.insert("offset".into(), numbers(&p));
    }
    if let Some(y) = o.yaw_deg {
        v.insert("yaw_deg".into(), number(y));
    }
    if let Some(s) = o.size {
        v.insert("size".into(), numbers(&s));
    }
    if !o.joints.is_empty() {
        let joints: serde_json::Map<String, Value> = o
            .joints
            .iter()
            .map(|(k, v)| (k.clone(), number(*v)))
            .collect();
        v.insert("joints".into(), Value::Object(joints));
    }
    Value::Object(v)
}

/// Writes a generated specification to `out`: never over a file `generate` did not write (an
/// existing file must parse as a generated specification), and atomically (a temporary file
/// renamed into place), so that an interrupted run leaves the old file or the new one.
pub fn write_generated(out: &Path, json: &Value) -> Result<(), IsceneError> {
    if out.is_dir() {
        return Err(InputError::invalid(
            out,
            "--out is a folder; name the specification file to write",
        )
        .into());
    }
    if std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(InputError::invalid(out, "--out is a symbolic link; name a plain file").into());
    }
    if out.exists() && !is_generated_spec(out) {
        return Err(InputError::invalid(
            out,
            "--out exists and is not a specification written by `iscene generate`; it is left alone (choose another path or delete it)",
        )
        .into());
    }
    let text = serde_json::to_string_pretty(json)
        .map_err(|e| IsceneError::Internal(format!("specification JSON: {e}")))?;
    let name = out
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| InputError::invalid(out, "--out names no file"))?;
    let temporary = out.with_file_name(format!(".{name}.partial-{}", std::process::id()));
    std::fs::write(&temporary, format!("{text}\n"))
        .map_err(|e| IsceneError::io(format!("writing {}", temporary.display()), e))?;
    std::fs::rename(&temporary, out).map_err(|e| {
        let _ = std::fs::remove_file(&temporary);
        IsceneError::io(format!("renaming into {}", out.display()), e)
    })
}

/// Whether `path` holds a specification `generate` wrote (its name says so and it parses).
fn is_generated_spec(path: &Path) -> bool {
    std::fs::read_to_string(path).is_ok_and(|text| {
        serde_json::from_str::<Value>(&text).is_ok_and(|v| {
            v.get("name")
                .and_then(Value::as_str)
                .is_some_and(|n| n.starts_with("generated_"))
        })
    })
}
