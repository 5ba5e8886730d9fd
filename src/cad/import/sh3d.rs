//! Sweet Home 3D furniture catalogues as CAD models.
//!
//! A catalogue is a zip file: the plugin catalogues `*.sh3f` of the Debian package
//! `sweethome3d-furniture` hold `PluginFurnitureCatalog.properties`, and `sweethome3d.jar` holds
//! the default catalogue `com/eteks/sweethome3d/io/DefaultFurnitureCatalog.properties`. Each
//! entry `N` names its OBJ model (`model#N`, a path inside the zip), its real size in centimetres
//! (`width#N` along x, `depth#N` along z, `height#N` along y), its `category#N` and its
//! `name#N`; `modelRotation#N` (a row-major 3x3 matrix) turns a model that was drawn lying down
//! upright. Sweet Home 3D models stand on y up and show their front to +z; the canonical frame
//! is +z up with the front to -y, so (x, y, z) becomes (x, -z, y). The catalogue's size is the
//! size of the box after that rotation, which the mesh is scaled to.
//!
//! Only entries of a class in assets/classes.json are imported; the class comes from the name
//! (`class_words`). Doors, windows, lights, people, vehicles and outdoor things are skipped. The
//! models carry no joints: a Sweet Home 3D fridge is a rigid fridge.

use std::collections::BTreeMap;
use std::io::{BufReader, Cursor, Read, Seek};
use std::path::{Path, PathBuf};

use glam::{Affine3A, Mat3, Vec3};
use rayon::prelude::*;

use crate::base::JointSpec;
use crate::cad::import::class_words::class_of_name;
use crate::cad::import::imported_model_id;
use crate::cad::import::mesh_files::{MeshFileError, obj_groups};
use crate::cad::model::{CadModel, CadPart};
use crate::geometry::TriMesh;

/// The catalogue file inside a plugin catalogue (`*.sh3f`).
const PLUGIN_CATALOGUE: &str = "PluginFurnitureCatalog.properties";
/// The default catalogue inside `sweethome3d.jar`.
const DEFAULT_CATALOGUE: &str = "com/eteks/sweethome3d/io/DefaultFurnitureCatalog.properties";

/// Meshes are simplified to about this many cells along their longest side before they are
/// decomposed: finer than the decomposition's voxels, and it keeps a 200k-triangle sofa from
/// costing seconds there.
const SIMPLIFY_CELLS: f32 = 64.0;
/// ... but never finer than this (metres, at the catalogue's size): a 12 cm cup needs no
/// 2 mm detail either.
const MIN_CELL_M: f32 = 0.005;

/// V-HACD's voxels along the longest side, and the most convex pieces a model becomes.
const DECOMPOSITION_RESOLUTION: u32 = 64;
const MAX_CONVEX_PIECES: u32 = 24;

/// Categories whose furniture never is an object of this project's classes.
const SKIPPED_CATEGORIES: [&str; 6] = [
    "Exterior",
    "Doors and windows",
    "Lights",
    "Characters",
    "Vehicles",
    "Staircases",
];

/// The project class of a catalogue entry, from its name and category; `None` for furniture
/// outside the classes.
pub fn class_of(name: &str, category: &str) -> Option<&'static str> {
    if SKIPPED_CATEGORIES.contains(&category) {
        return None;
    }
    class_of_name(name)
}

/// One furniture entry of a catalogue.
#[derive(Clone, Debug, PartialEq)]
pub struct CatalogueEntry {
    /// `id#N`, e.g. `Blend Swap CC-0#armchair`.
    pub id: String,
    pub name: String,
    pub category: String,
    /// The OBJ file's path inside the zip.
    pub model: String,
    /// Width, depth and height in metres (Sweet Home 3D's x, z and y).
    pub size: Vec3,
    /// Turns the model as drawn into Sweet Home 3D's frame (y up, front +z).
    pub model_rotation: Mat3,
    pub door_or_window: bool,
}

/// What importing a catalogue gave.
#[derive(Debug, Default)]
pub struct ImportedCatalogue {
    pub models: Vec<CadModel>,
    /// Entries outside the classes.
    pub skipped: usize,
    /// Entries of a class whose model could not be used, with the reason.
    pub failed: Vec<String>,
}

/// Why a catalogue, or a folder of them, could not be read. Each names the file; a model of the
/// catalogue that cannot be used is no error but an entry of `ImportedCatalogue::failed`.
#[derive(Debug, thiserror::Error)]
pub enum Sh3dError {
    #[error("{}: {source}", path.display())]
    Unreadable {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a zip catalogue: {source}", path.display())]
    NotAZip {
        path: PathBuf,
        source: zip::result::ZipError,
    },
    #[error("{}: holds neither {PLUGIN_CATALOGUE} nor {DEFAULT_CATALOGUE}", path.display())]
    NoCatalogue { path: PathBuf },
    #[error("{}: no Sweet Home 3D catalogue (*.sh3f, sweethome3d.jar) in this folder", path.display())]
    NoCatalogueInFolder { path: PathBuf },
    /// The catalogue's properties file could not be read out of the zip.
    #[error("{}: {problem}", path.display())]
    BadMember { path: PathBuf, problem: MemberError },
    #[error("{}: {member}: {source}", path.display())]
    BadEntry {
        path: PathBuf,
        member: &'static str,
        source: EntryError,
    },
}

/// An entry of a catalogue's properties that is not a usable furniture entry.
#[derive(Debug, thiserror::Error)]
#[error("entry #{index}: {problem}")]
pub struct EntryError {
    pub index: usize,
    pub problem: EntryProblem,
}

/// What is wrong with an entry's fields.
#[derive(Debug, thiserror::Error)]
pub enum EntryProblem {
    #[error("no {0}")]
    Missing(&'static str),
    #[error("{0} is not a number")]
    NotANumber(&'static str),
    #[error("{key} {value} is not a positive size")]
    NotAPositiveSize { key: &'static str, value: f32 },
    #[error("modelRotation {0:?} is not 9 numbers")]
    BadRotation(String),
}

/// A member of a catalogue's zip that cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum MemberError {
    #[error("{name} is not in the catalogue: {source}")]
    Absent {
        name: String,
        source: zip::result::ZipError,
    },
    #[error("{name} expands past {} MB", MAX_ENTRY_BYTES >> 20)]
    TooBig { name: String },
    #[error("reading {name}: {source}")]
    Unreadable {
        name: String,
        source: std::io::Error,
    },
}

/// Why an entry's model cannot be used: the import lists the entry with it and goes on.
#[derive(Debug, thiserror::Error)]
enum UnusableEntry {
    #[error(transparent)]
    Member(#[from] MemberError),
    #[error("its size {0:?} m is not furniture's (at most {MAX_SIZE_M} m)")]
    NotFurnitureSized([f32; 3]),
    #[error("OBJ: {0}")]
    Obj(#[from] MeshFileError),
    #[error("group {0:?} has a vertex that is not a number")]
    NotANumber(String),
    #[error("no triangles")]
    NoTriangles,
    #[error(
        "{0} triangles, more than the {MAX_TRIANGLES} an imported model may have (its convex \
         decomposition would take minutes)"
    )]
    TooManyTriangles(usize),
    #[error("no vertices")]
    NoVertices,
    #[error("no part of the model spans volume")]
    NoVolume,
    #[error("the model is flat ({0:?})")]
    Flat(Vec3),
}

/// Reads a catalogue file (`*.sh3f` or `sweethome3d.jar`) into models of the project's classes.
pub fn import_catalogue(path: &Path) -> Result<ImportedCatalogue, Sh3dError> {
    let file = std::fs::File::open(path).map_err(|source| Sh3dError::Unreadable {
        path: path.to_path_buf(),
        source,
    })?;
    let mut zip =
        zip::ZipArchive::new(BufReader::new(file)).map_err(|source| Sh3dError::NotAZip {
            path: path.to_path_buf(),
            source,
        })?;
    let name = [PLUGIN_CATALOGUE, DEFAULT_CATALOGUE]
        .into_iter()
        .find(|n| zip.index_for_name(n).is_some())
        .ok_or_else(|| Sh3dError::NoCatalogue {
            path: path.to_path_buf(),
        })?;
    let text = read_text(&mut zip, name).map_err(|problem| Sh3dError::BadMember {
        path: path.to_path_buf(),
        problem,
    })?;
    let entries = parse_catalogue(&text).map_err(|source| Sh3dError::BadEntry {
        path: path.to_path_buf(),
        member: name,
        source,
    })?;
    let mut imported = ImportedCatalogue::default();
    // The zip is read in order; the meshes are made in parallel (the decomposition is the cost).
    let mut files = Vec::new();
    for entry in entries {
        match class_of(&entry.name, &entry.category) {
            Some(class) if !entry.door_or_window => {
                let read = model_files(&mut zip, &entry);
                files.push((entry, class, read));
            }
            _ => imported.skipped += 1,
        }
    }
    // Each entry's model, or the line that lists it as failed.
    let models: Vec<_> = files
        .into_par_iter()
        .map(|(entry, class, read)| {
            read.map_err(UnusableEntry::from)
                .and_then(|(obj, materials)| entry_model(&entry, class, &obj, &materials))
                .map_err(|e| format!("{} ({}): {e}", entry.id, entry.model))
        })
        .collect();
    for model in models {
        match model {
            Ok(m) => imported.models.push(m),
            Err(e) => imported.failed.push(e),
        }
    }
    Ok(imported)
}

/// The catalogue files under `path`: the file itself, or the `*.sh3f` and `*.jar` files of a
/// folder, sorted.
pub fn catalogue_files(path: &Path) -> Result<Vec<PathBuf>, Sh3dError> {
    if path.is_file() {
        return Ok(vec![path.to_path_buf()]);
    }
    let read = std::fs::read_dir(path).map_err(|source| Sh3dError::Unreadable {
        path: path.to_path_buf(),
        source,
    })?;
    let mut files: Vec<PathBuf> = read
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "sh3f" || e == "jar"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(Sh3dError::NoCatalogueInFolder {
            path: path.to_path_buf(),
        });
    }
    Ok(files)
}

/// The entries of a catalogue's properties text, in their order.
pub fn parse_catalogue(text: &str) -> Result<Vec<CatalogueEntry>, EntryError> {
    let mut by_index: BTreeMap<usize, BTreeMap<String, String>> = BTreeMap::new();
    for (key, value) in java_properties(text) {
        let Some((field, index)) = key.split_once('#') else {
            continue;
        };
        let Ok(index) = index.parse::<usize>() else {
            continue;
        };
        by_index
            .entry(index)
            .or_default()
            .insert(field.to_string(), value);
    }
    by_index
        .into_iter()
        .map(|(index, fields)| entry_of(&fields).map_err(|problem| EntryError { index, problem }))
        .collect()
}

fn entry_of(fields: &BTreeMap<String, String>) -> Result<CatalogueEntry, EntryProblem> {
    let text = |key: &'static str| fields.get(key).cloned().ok_or(EntryProblem::Missing(key));
    let centimetres = |key: &'static str| -> Result<f32, EntryProblem> {
        let value: f32 = text(key)?
            .trim()
            .parse()
            .map_err(|_| EntryProblem::NotANumber(key))?;
        if !(value.is_finite() && value > 0.0) {
            return Err(EntryProblem::NotAPositiveSize { key, value });
        }
        Ok(value / 100.0)
    };
    let model_rotation = match fields.get("modelRotation") {
        None => Mat3::IDENTITY,
        Some(text) => {
            let values: Vec<f32> = text
                .split_whitespace()
                .map(str::parse)
                .collect::<Result<_, _>>()
                .map_err(|_| EntryProblem::BadRotation(text.clone()))?;
            let rows: [f32; 9] = values
                .try_into()
                .map_err(|_| EntryProblem::BadRotation(text.clone()))?;
            Mat3::from_cols_array(&rows).transpose()
        }
    };
    Ok(CatalogueEntry {
        id: text("id")?,
        name: text("name")?,
        category: fields.get("category").cloned().unwrap_or_default(),
        model: text("model")?,
        size: Vec3::new(
            centimetres("width")?,
            centimetres("depth")?,
            centimetres("height")?,
        ),
        model_rotation,
        door_or_window: fields.get("doorOrWindow").is_some_and(|v| v == "true"),
    })
}

/// `key=value` pairs of a Java properties text: comments, `key:value`, continuation lines and
/// `\uXXXX` escapes as java.util.Properties reads them.
fn java_properties(text: &str) -> Vec<(String, String)> {
    let mut pairs = Vec::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let mut logical = line.trim_start().to_string();
        if logical.is_empty() || logical.starts_with('#') || logical.starts_with('!') {
            continue;
        }
        while ends_in_continuation(&logical) {
            logical.pop();
            match lines.next() {
                Some(next) => logical.push_str(next.trim_start()),
                None => break,
            }
        }
        let split = separator_at(&logical);
        let (key, value) = match split {
            Some(i) => (&logical[..i], logical[i + 1..].trim_start()),
            None => (logical.as_str(), ""),
        };
        pairs.push((unescape(key.trim_end()), unescape(value)));
    }
    pairs
}

/// An odd number of trailing backslashes continues the line.
fn ends_in_continuation(line: &str) -> bool {
    line.chars().rev().take_while(|c| *c == '\\').count() % 2 == 1
}

/// The byte index of the first unescaped `=` or `:`.
fn separator_at(line: &str) -> Option<usize> {
    let mut escaped = false;
    for (i, c) in line.char_indices() {
        match c {
            '\\' if !escaped => escaped = true,
            '=' | ':' if !escaped => return Some(i),
            _ => escaped = false,
        }
    }
    None
}

fn unescape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        match chars.next() {
            Some('u') => {
                let hex: String = chars.by_ref().take(4).collect();
                match u32::from_str_radix(&hex, 16).ok().and_then(char::from_u32) {
                    Some(u) => out.push(u),
                    None => out.push_str(&hex),
                }
            }
            Some('n') => out.push('\n'),
            Some('t') => out.push('\t'),
            Some(other) => out.push(other),
            None => {}
        }
    }
    out
}

/// The text file `name` of the zip.
fn read_text<R: Read + Seek>(
    zip: &mut zip::ZipArchive<R>,
    name: &str,
) -> Result<String, MemberError> {
    let bytes = read_bytes(zip, name)?;
    // The catalogues are ISO 8859-1 with \u escapes for anything else; Latin-1 maps byte to
    // code point.
    Ok(bytes.iter().map(|&b| char::from(b)).collect())
}

/// The file `name` of the zip, refused past [`MAX_ENTRY_BYTES`] whatever its header claims (a
/// small archive can expand to gigabytes).
fn read_bytes<R: Read + Seek>(
    zip: &mut zip::ZipArchive<R>,
    name: &str,
) -> Result<Vec<u8>, MemberError> {
    let file = zip.by_name(name).map_err(|source| MemberError::Absent {
        name: name.to_string(),
        source,
    })?;
    let too_big = || MemberError::TooBig {
        name: name.to_string(),
    };
    if file.size() > MAX_ENTRY_BYTES {
        return Err(too_big());
    }
    let mut bytes = Vec::new();
    file.take(MAX_ENTRY_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|source| MemberError::Unreadable {
            name: name.to_string(),
            source,
        })?;
    if bytes.len() as u64 > MAX_ENTRY_BYTES {
        return Err(too_big());
    }
    Ok(bytes)
}

/// An OBJ file's bytes and those of the material files it names, by name.
type ModelFiles = (Vec<u8>, BTreeMap<String, Vec<u8>>);

/// The OBJ file of `entry` and the material files it names.
fn model_files<R: Read + Seek>(
    zip: &mut zip::ZipArchive<R>,
    entry: &CatalogueEntry,
) -> Result<ModelFiles, MemberError> {
    let obj_name = entry.model.trim_start_matches('/');
    let obj = read_bytes(zip, obj_name)?;
    let folder = Path::new(obj_name)
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let mut materials: BTreeMap<String, Vec<u8>> = BTreeMap::new();
    for line in obj.split(|b| *b == b'\n') {
        let line = String::from_utf8_lossy(line);
        if let Some(name) = line.trim().strip_prefix("mtllib ") {
            let path = folder.join(name.trim());
            let key = path.to_string_lossy().replace('\\', "/");
            if let Ok(bytes) = read_bytes(zip, &key) {
                materials.insert(name.trim().to_string(), bytes);
            }
        }
    }
    Ok((obj, materials))
}

/// The largest uncompressed file read from a catalogue, bytes.
const MAX_ENTRY_BYTES: u64 = 64 << 20;
/// The most triangles an imported model may have before its convex decomposition.
const MAX_TRIANGLES: usize = 100_000;
/// The largest size of a piece of furniture imported, metres (catalogues hold a few buildings
/// and gardens too).
const MAX_SIZE_M: f32 = 20.0;

/// The entry's model in the canonical frame, at the catalogue's size.
fn entry_model(
    entry: &CatalogueEntry,
    class: &str,
    obj: &[u8],
    materials: &BTreeMap<String, Vec<u8>>,
) -> Result<CadModel, UnusableEntry> {
    if entry.size.max_element() > MAX_SIZE_M {
        return Err(UnusableEntry::NotFurnitureSized(entry.size.to_array()));
    }
    let (mesh, color) = obj_mesh(obj, materials)?;
    if mesh.triangles.len() > MAX_TRIANGLES {
        return Err(UnusableEntry::TooManyTriangles(mesh.triangles.len()));
    }
    let mesh = canonical_mesh(&mesh, entry.model_rotation, entry.size)?;
    Ok(CadModel {
        id: model_id(&entry.id),
        class: class.to_string(),
        size: entry.size,
        parts: vec![CadPart {
            name: "body".into(),
            parent: None,
            parent_from_part: Affine3A::IDENTITY,
            joint: JointSpec::FIXED,
            mesh,
            visual: None,
            color,
        }],
    })
}

/// `sh3d_` and the catalogue id in lowercase letters, digits and single underscores.
pub fn model_id(catalogue_id: &str) -> String {
    imported_model_id("sh3d", catalogue_id)
}

/// All groups of an OBJ file as one triangle mesh (in the file's units and frame), and the
/// area-weighted mean diffuse colour of its materials (grey without any).
fn obj_mesh(
    obj: &[u8],
    materials: &BTreeMap<String, Vec<u8>>,
) -> Result<(TriMesh, [f32; 3]), UnusableEntry> {
    let (groups, loaded) = obj_groups(obj, |p| {
        let name = p.to_string_lossy().into_owned();
        match materials.get(&name) {
            Some(bytes) => tobj::load_mtl_buf(&mut Cursor::new(bytes.as_slice())),
            None => Err(tobj::LoadError::OpenFileFailed),
        }
    })?;
    let mut mesh = TriMesh::default();
    let mut weighted = Vec3::ZERO;
    let mut weight = 0.0;
    for group in groups {
        if group.mesh.positions.iter().any(|p| !p.is_finite()) {
            return Err(UnusableEntry::NotANumber(group.name.clone()));
        }
        if let Some(diffuse) = group
            .material
            .and_then(|i| loaded.get(i))
            .and_then(|mat| mat.diffuse)
        {
            let area = group.mesh.area();
            weighted += Vec3::from(diffuse) * area;
            weight += area;
        }
        mesh.append(&group.mesh);
    }
    if mesh.triangles.is_empty() {
        return Err(UnusableEntry::NoTriangles);
    }
    let color = if weight > 0.0 {
        (weighted / weight).clamp(Vec3::ZERO, Vec3::ONE).to_array()
    } else {
        [0.6, 0.6, 0.6]
    };
    Ok((mesh, color))
}

/// `mesh` turned upright by `model_rotation`, into the canonical axes, scaled to `size` and
/// with its origin at the bottom centre of its box; simplified to [`SIMPLIFY_CELLS`].
fn canonical_mesh(
    mesh: &TriMesh,
    model_rotation: Mat3,
    size: Vec3,
) -> Result<TriMesh, UnusableEntry> {
    // Sweet Home 3D (x, y up, z front) to canonical (x, -y front, z up).
    let to_canonical = Mat3::from_cols(Vec3::X, Vec3::Z, -Vec3::Y);
    let turned = mesh.transformed(&Affine3A::from_mat3(to_canonical * model_rotation));
    let (min, max) = turned.bounds().ok_or(UnusableEntry::NoVertices)?;
    // Simplified before it is measured, so that the box is exactly the catalogue's size.
    let cell = ((max - min).max_element() / SIMPLIFY_CELLS)
        .max(MIN_CELL_M * (max - min).max_element() / size.max_element());
    let simplified = turned.clustered(cell);
    // Closed convex pieces, which everything after import relies on: mass and inertia come
    // from a closed mesh's volume, contact queries and colliders take each connected piece as
    // convex. Catalogue meshes are neither closed nor made of convex pieces.
    let mut solid = TriMesh::default();
    for piece in simplified.convex_decomposition(DECOMPOSITION_RESOLUTION, MAX_CONVEX_PIECES) {
        solid.append(&piece);
    }
    let (min, max) = solid.bounds().ok_or(UnusableEntry::NoVolume)?;
    let extent = max - min;
    if extent.min_element() <= 0.0 {
        return Err(UnusableEntry::Flat(extent));
    }
    let scale = size / extent;
    let bottom_centre = Vec3::new((min.x + max.x) / 2.0, (min.y + max.y) / 2.0, min.z);
    Ok(solid
        .transformed(&(Affine3A::from_scale(scale) * Affine3A::from_translation(-bottom_centre))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_come_from_the_names_with_their_exceptions() {
        let cases = [
            ("Armchair", "Living room", Some("chair")),
            ("Bar stool", "Kitchen", Some("chair")),
            ("Bookcase", "Living room", Some("shelf")),
            ("Bedside table", "Bedroom", Some("cabinet")),
            ("Coffee table", "Living room", Some("table")),
            ("Wine bottle", "Kitchen", Some("bottle")),
            ("Coffee mug", "Kitchen", Some("cup")),
            ("Cup cake", "Kitchen", None),
            ("Fridge & Freezer", "Kitchen", Some("fridge")),
            ("Chest freezer", "Kitchen", None),
            ("Microwave", "Kitchen", Some("microwave")),
            ("Small oven", "Kitchen", Some("oven")),
            ("Bed 140x190", "Bedroom", Some("bed")),
            ("Sofa 3 seats", "Living room", Some("sofa")),
            ("Flat TV", "Living room", Some("monitor")),
            ("Desk lamp", "Office", None),
            ("Chair", "Exterior", None),
            ("Plant", "Living room", None),
        ];
        for (name, category, class) in cases {
            assert_eq!(class_of(name, category), class, "{name} in {category}");
        }
    }

    #[test]
    fn properties_are_read_as_java_reads_them() {
        let text = "# comment\nid=Cat\nid#1=A#one\nname#1=Bill 10\\u20ac\ncategory#1 : Kitchen\n\
                    model#1=/a/one.obj\nwidth#1=50\ndepth#1=40\nheight#1=\\\n  90\n\
                    modelRotation#1=1 0 0 0 0 1 0 -1 0\ndoorOrWindow#1=false\n";
        let entries = parse_catalogue(text).expect("parses");
        assert_eq!(entries.len(), 1);
        let e = &entries[0];
        assert_eq!(e.name, "Bill 10\u{20ac}");
        assert_eq!(e.category, "Kitchen");
        assert_eq!(e.size, Vec3::new(0.5, 0.4, 0.9));
        // Row-major: the second row (0 0 1) maps z to y.
        assert_eq!(e.model_rotation * Vec3::Z, Vec3::Y);
        assert!(!e.door_or_window);
        assert!(
            parse_catalogue("id#2=x\nname#2=y\nmodel#2=m\nwidth#2=-1\ndepth#2=1\nheight#2=1")
                .is_err()
        );
    }

    #[test]
    fn ids_are_file_names() {
        assert_eq!(
            model_id("Blend Swap CC-0#armchair"),
            "sh3d_blend_swap_cc_0_armchair"
        );
        assert_eq!(model_id("eTeks#bed140x190"), "sh3d_eteks_bed140x190");
    }

    #[test]
    fn a_chair_drawn_y_up_facing_z_stands_in_the_canonical_frame() {
        // A seat (y 0.4-0.45) and a back at the rear (z -0.25..-0.2, y up to 0.9), in
        // Sweet Home 3D's frame: the front is +z, so the back must end up at +y.
        let mut drawn = TriMesh::cuboid(Vec3::new(-0.2, 0.4, -0.25), Vec3::new(0.2, 0.45, 0.25));
        drawn.append(&TriMesh::cuboid(
            Vec3::new(-0.2, 0.45, -0.25),
            Vec3::new(0.2, 0.9, -0.2),
        ));
        drawn.append(&TriMesh::cuboid(
            Vec3::new(-0.2, 0.0, -0.25),
            Vec3::new(-0.17, 0.4, -0.22),
        ));
        let size = Vec3::new(0.8, 1.0, 1.8); // catalogue width, depth, height: scaled to it
        let mesh = canonical_mesh(&drawn, Mat3::IDENTITY, size).expect("mesh");
        let (min, max) = mesh.bounds().expect("bounds");
        assert!((max - min - size).abs().max_element() < 1e-4, "{min} {max}");
        assert!(min.z.abs() < 1e-4 && (min.x + max.x).abs() < 1e-4 && (min.y + max.y).abs() < 1e-4);
        let top: Vec<&Vec3> = mesh.positions.iter().filter(|p| p.z > 1.5).collect();
        assert!(
            !top.is_empty() && top.iter().all(|p| p.y > 0.3),
            "the back is behind"
        );
    }
}
