//! `iscene cad import`: third-party models into a database folder that `reconstruct --cad`
//! matches against. Models already in the folder stay; an imported model replaces one with its id.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use rayon::prelude::*;

use crate::cad::export::{IndexEntry, write_index, write_model_files};
use crate::cad::load::read_index;
use crate::cad::model::CadModel;
use crate::cad::sh3d;
use crate::error::{InputError, IsceneError};

/// What an import did, for the CLI to print.
#[derive(Debug)]
pub struct ImportSummary {
    pub into: std::path::PathBuf,
    pub catalogues: usize,
    /// Imported models per class.
    pub per_class: BTreeMap<String, usize>,
    /// Catalogue entries outside the project's classes.
    pub skipped: usize,
    /// Entries of a class whose model could not be read, with the reason.
    pub failed: Vec<String>,
    /// Models in the folder after the import.
    pub total: usize,
}

impl fmt::Display for ImportSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let imported: usize = self.per_class.values().sum();
        let classes: Vec<String> = self
            .per_class
            .iter()
            .map(|(c, n)| format!("{n} {c}"))
            .collect();
        writeln!(
            f,
            "imported {imported} models from {} catalogues ({}); {} entries of other kinds skipped",
            self.catalogues,
            classes.join(", "),
            self.skipped
        )?;
        for failure in &self.failed {
            writeln!(f, "  not imported: {failure}")?;
        }
        write!(f, "{} now holds {} models", self.into.display(), self.total)
    }
}

/// Imports the Sweet Home 3D catalogue(s) at `path` into the database folder `into`.
pub fn import_sh3d(path: &Path, into: &Path) -> Result<ImportSummary, IsceneError> {
    if !path.exists() {
        return Err(InputError::missing(path, "no such catalogue file or folder (the Debian package sweethome3d-furniture installs /usr/share/sweethome3d/furniture)").into());
    }
    let files = sh3d::catalogue_files(path).map_err(|e| InputError::invalid(path, e))?;
    let catalogues = files
        .par_iter()
        .map(|file| sh3d::import_catalogue(file).map_err(|e| InputError::invalid(file, e)))
        .collect::<Result<Vec<_>, _>>()?;
    let mut summary = ImportSummary {
        into: into.to_path_buf(),
        catalogues: files.len(),
        per_class: BTreeMap::new(),
        skipped: 0,
        failed: Vec::new(),
        total: 0,
    };
    let mut imported: Vec<CadModel> = Vec::new();
    for catalogue in catalogues {
        summary.skipped += catalogue.skipped;
        summary.failed.extend(catalogue.failed);
        imported.extend(catalogue.models);
    }
    for model in &imported {
        *summary.per_class.entry(model.class.clone()).or_default() += 1;
    }
    summary.total = merge_into(into, imported)?;
    Ok(summary)
}

/// Writes `imported` into the database folder `into` beside the models it already holds (an
/// imported model replaces one with its id; the others' files are left as they are); returns
/// how many it holds.
fn merge_into(into: &Path, imported: Vec<CadModel>) -> Result<usize, IsceneError> {
    let mut index: BTreeMap<String, IndexEntry> = BTreeMap::new();
    if into.join("index.json").exists() {
        for entry in read_index(into)?.models {
            index.insert(entry.id.clone(), entry);
        }
    }
    for model in &imported {
        write_model_files(into, model)?;
        index.insert(model.id.clone(), IndexEntry::of(model));
    }
    write_index(into, index.into_values().collect(), "iscene cad import")
}
