//! `iscene cad import`: third-party models into a database folder that `reconstruct --cad`
//! matches against. Models already in the folder stay; an imported model replaces one with its id.

pub mod body_tree;
pub mod class_words;
pub mod mesh_files;
pub mod mjcf;
pub mod mjcf_include;
pub mod mjcf_xml;
pub mod sh3d;
pub mod urdf;

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use rayon::prelude::*;

use crate::cad::db::export::{IndexEntry, model_file_bytes, write_index, write_model_files};
use crate::cad::db::load::read_index;
use crate::cad::import::body_tree::{BodyTree, ImportScale, ModelFileError, canonical_model};
use crate::cad::import::class_words::class_of_name;
use crate::cad::import::mjcf::read_mjcf;
use crate::cad::import::urdf::read_urdf;
use crate::cad::model::CadModel;
use crate::error::{InputError, IsceneError};

/// What an import did, for the CLI to print.
#[derive(Debug)]
pub struct ImportSummary {
    pub into: std::path::PathBuf,
    /// Catalogue or model files read.
    pub files: usize,
    /// Imported models per class.
    pub per_class: BTreeMap<String, usize>,
    /// Catalogue entries or model files outside the project's classes.
    pub skipped: usize,
    /// Entries of a class whose model could not be read, with the reason.
    pub failed: Vec<String>,
    /// Models in the folder after the import.
    pub total: usize,
}

impl ImportSummary {
    fn new(into: &Path, files: usize) -> Self {
        Self {
            into: into.to_path_buf(),
            files,
            per_class: BTreeMap::new(),
            skipped: 0,
            failed: Vec::new(),
            total: 0,
        }
    }

    /// Counts `imported` per class and writes them into the database folder.
    fn write(mut self, imported: Vec<CadModel>) -> Result<Self, IsceneError> {
        for model in &imported {
            *self.per_class.entry(model.class.clone()).or_default() += 1;
        }
        self.total = merge_into(&self.into, imported)?;
        Ok(self)
    }
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
            "imported {imported} models from {} files ({}); {} of other kinds skipped",
            self.files,
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
    let files =
        sh3d::catalogue_files(path).map_err(|e| InputError::invalid(path, e.to_string()))?;
    let catalogues = files
        .par_iter()
        .map(|file| {
            sh3d::import_catalogue(file).map_err(|e| InputError::invalid(file, e.to_string()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut summary = ImportSummary::new(into, files.len());
    let mut imported: Vec<CadModel> = Vec::new();
    for catalogue in catalogues {
        summary.skipped += catalogue.skipped;
        summary.failed.extend(catalogue.failed);
        imported.extend(catalogue.models);
    }
    summary.write(imported)
}

/// The robot-description formats whose model files `iscene cad import` reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFormat {
    /// MuJoCo's MJCF (`*.xml`): LIBERO's articulated objects.
    Mjcf,
    /// URDF (`*.urdf`).
    Urdf,
}

impl ModelFormat {
    fn extension(self) -> &'static str {
        match self {
            Self::Mjcf => "xml",
            Self::Urdf => "urdf",
        }
    }

    /// Model ids start with it: `mjcf_short_fridge`.
    fn id_prefix(self) -> &'static str {
        match self {
            Self::Mjcf => "mjcf",
            Self::Urdf => "urdf",
        }
    }

    fn read(self, path: &Path) -> Result<BodyTree, ModelFileError> {
        let tree = match self {
            Self::Mjcf => read_mjcf(path),
            Self::Urdf => read_urdf(path),
        }?;
        tree.check_size()?;
        Ok(tree)
    }
}

/// Imports the model file at `path`, or every file of the format's extension in the folder
/// `path`, into the database folder `into`; a model's id is the format's prefix and its file's
/// stem. A broken file fails the import before anything is written; a file naming no class (a
/// faucet, a window) is skipped, and one using what the reader does not read is listed as not
/// imported.
pub fn import_model_files(
    path: &Path,
    into: &Path,
    format: ModelFormat,
    scale: ImportScale,
) -> Result<ImportSummary, IsceneError> {
    let files = model_files(path, format.extension())?;
    let mut summary = ImportSummary::new(into, files.len());
    let mut imported = Vec::new();
    for file in &files {
        let stem = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if matches!(format, ModelFormat::Mjcf)
            && crate::cad::import::mjcf_include::is_include_file(file)
        {
            summary.skipped += 1;
            continue;
        }
        let tree = match format.read(file) {
            Ok(tree) => tree,
            Err(ModelFileError::Unsupported(why)) => {
                summary.failed.push(format!("{}: {why}", file.display()));
                continue;
            }
            Err(ModelFileError::Malformed(why)) => {
                return Err(InputError::invalid(file, why).into());
            }
        };
        let Some(class) = class_of_name(&tree.name).or_else(|| class_of_name(&stem)) else {
            summary.skipped += 1;
            continue;
        };
        let id = imported_model_id(format.id_prefix(), &stem);
        match canonical_model(&tree, &id, class, scale) {
            Ok(m) => {
                for part in &m.parts {
                    part.joint.check().map_err(|e| {
                        InputError::invalid(file, format!("part {}: joint: {e}", part.name))
                    })?;
                }
                imported.push(m);
            }
            Err(why) => summary.failed.push(format!("{}: {why}", file.display())),
        }
    }
    summary.write(imported)
}

/// The file `path`, or the files of the folder `path` with the extension `extension`, sorted.
fn model_files(path: &Path, extension: &str) -> Result<Vec<std::path::PathBuf>, InputError> {
    if path.is_file() {
        return Ok(vec![path.to_path_buf()]);
    }
    let entries = std::fs::read_dir(path).map_err(|e| InputError::io(path, &e))?;
    let mut files: Vec<std::path::PathBuf> = entries
        .map(|e| e.map(|e| e.path()).map_err(|e| InputError::io(path, &e)))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .filter(|p| {
            p.is_file()
                && p.extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case(extension))
        })
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(InputError::invalid(
            path,
            format!("no *.{extension} model files in the folder"),
        ));
    }
    Ok(files)
}

/// `prefix` and the source's id in lowercase letters, digits and single underscores: the
/// model's id and file name in the database.
pub fn imported_model_id(prefix: &str, source_id: &str) -> String {
    let mut id = String::from(prefix);
    let mut gap = true;
    for c in source_id.chars().flat_map(char::to_lowercase) {
        if c.is_ascii_alphanumeric() {
            if gap {
                id.push('_');
            }
            id.push(c);
            gap = false;
        } else {
            gap = true;
        }
    }
    id
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
    let files = imported
        .iter()
        .map(model_file_bytes)
        .collect::<Result<Vec<_>, _>>()?;
    write_model_files(into, files)?;
    for model in &imported {
        index.insert(model.id.clone(), IndexEntry::of(model));
    }
    write_index(into, index.into_values().collect(), "iscene cad import")
}
