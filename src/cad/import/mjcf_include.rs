//! MJCF `<include>`: the included files spliced into the model's text as MuJoCo reads them,
//! and include files (root `<mujocoinclude>`) told apart from models.

use std::path::Path;

use crate::cad::import::body_tree::ModelFileError;
use crate::cad::import::mjcf_xml::at;
use crate::file_name::inside_folder;

/// Includes nest at most this deep, and a model with its includes is at most this long (bytes).
const MAX_INCLUDE_DEPTH: usize = 8;
pub(crate) const MAX_INCLUDED_BYTES: usize = 64 << 20;

/// Whether the MJCF file at `path` is an include file (root `<mujocoinclude>`), which a folder
/// import passes over: it is read through the model that includes it.
pub fn is_include_file(path: &Path) -> bool {
    std::fs::read_to_string(path).is_ok_and(|text| {
        roxmltree::Document::parse(&text)
            .is_ok_and(|d| d.root_element().tag_name().name() == "mujocoinclude")
    })
}

/// The text of the MJCF file at `path` with every `<include file="..."/>` replaced by what the
/// included file's root element holds, as MuJoCo reads it: files are named relative to the
/// model's folder `folder` and must lie inside it; includes nest up to `MAX_INCLUDE_DEPTH`, and
/// `budget` bytes of text are left for the whole model.
pub(crate) fn expanded_text(
    path: &Path,
    folder: &Path,
    depth: usize,
    budget: &mut usize,
) -> Result<String, ModelFileError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    *budget = budget.checked_sub(text.len()).ok_or_else(|| {
        ModelFileError::Malformed(format!(
            "the model with its includes is longer than {MAX_INCLUDED_BYTES} bytes"
        ))
    })?;
    let document = roxmltree::Document::parse(&text).map_err(|e| {
        if depth == 0 {
            format!("not XML: {e}")
        } else {
            format!("{}: not XML: {e}", path.display())
        }
    })?;
    let includes: Vec<(std::ops::Range<usize>, String)> = document
        .descendants()
        .filter(|n| n.is_element() && n.tag_name().name() == "include")
        .map(|n| {
            let file = n.attribute("file").ok_or_else(|| {
                ModelFileError::Malformed(format!("{}: <include> without a file", at(n)))
            })?;
            Ok((n.range(), file.to_string()))
        })
        .collect::<Result<_, ModelFileError>>()?;
    if includes.is_empty() {
        return Ok(text);
    }
    if depth >= MAX_INCLUDE_DEPTH {
        return Err(ModelFileError::Malformed(format!(
            "{}: includes nest deeper than {MAX_INCLUDE_DEPTH}",
            path.display()
        )));
    }
    let mut expanded = String::with_capacity(text.len());
    let mut copied = 0;
    for (range, file) in includes {
        let included = inside_folder(folder, Path::new(&file))
            .map_err(|e| ModelFileError::Malformed(format!("<include file={file:?}>: {e}")))?;
        let inner = expanded_text(&included, folder, depth + 1, budget)?;
        let inner_document = roxmltree::Document::parse(&inner)
            .map_err(|e| format!("{}: not XML: {e}", included.display()))?;
        let root = inner_document.root_element();
        let body = match (root.first_child(), root.last_child()) {
            (Some(first), Some(last)) => &inner[first.range().start..last.range().end],
            _ => "",
        };
        // Nested includes sit inside earlier ones' ranges only if an include has children,
        // which MJCF does not allow; ranges come in document order.
        if range.start < copied {
            continue;
        }
        expanded.push_str(&text[copied..range.start]);
        expanded.push_str(body);
        copied = range.end;
    }
    expanded.push_str(&text[copied..]);
    Ok(expanded)
}
