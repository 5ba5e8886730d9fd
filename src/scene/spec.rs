//! The scene specification of DESIGN.md (`scenes/*.json`), parsed strictly: unknown keys, unknown
//! classes, dangling references and impossible sizes are errors that name the key.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use crate::base::InvalidValue;
use crate::cad::db::load::read_database;
use crate::cad::library::LibraryEntry;
use crate::cad::{CadModel, ParametricLibrary};
use crate::classes::{ClassTable, EntityKind};
use crate::error::InputError;
use crate::render::noise::NoiseSettings;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub name: String,
    #[serde(default)]
    pub seed: u64,
    pub room: RoomSpec,
    pub objects: Vec<ObjectSpec>,
    #[serde(default)]
    pub camera: CameraSpec,
    #[serde(default)]
    pub noise: NoiseSettings,
    /// CAD database folders (written by `iscene cad import`), relative to the specification:
    /// `objects[].model` may name their models.
    #[serde(default)]
    pub cad: Vec<String>,
    /// The databases of `cad`, read when the specification is parsed.
    #[serde(skip)]
    pub databases: Vec<SpecDatabase>,
}

/// One database of a specification's `"cad"`, read.
#[derive(Clone, Debug)]
pub struct SpecDatabase {
    pub dir: PathBuf,
    pub models: Vec<CadModel>,
}

/// Where an object's model comes from.
#[derive(Clone, Copy)]
pub enum ModelSource<'a> {
    /// The parametric library, built at any size of its class.
    Parametric(&'static LibraryEntry),
    /// A database of the specification's `"cad"`, at the size its author gave it.
    Database(&'a CadModel),
}

impl ModelSource<'_> {
    pub fn class(&self) -> &str {
        match self {
            Self::Parametric(e) => e.class,
            Self::Database(m) => &m.class,
        }
    }

    /// The size the model has when a specification gives none.
    pub fn nominal_size(&self) -> Vec3 {
        match self {
            Self::Parametric(e) => e.nominal_size,
            Self::Database(m) => m.size,
        }
    }

    /// The model, built to `size` where its source allows.
    pub fn build(&self, size: Option<Vec3>) -> CadModel {
        match (self, size) {
            (Self::Parametric(e), Some(s)) => e.model_sized(s),
            (Self::Parametric(e), None) => e.model(),
            (Self::Database(m), _) => (*m).clone(),
        }
    }
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomSpec {
    /// x, y extent and height in metres; the floor spans `[0, x] x [0, y]` at z = 0.
    pub size: [f32; 3],
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    pub id: String,
    pub class: String,
    /// x, y on the floor (room frame).
    pub position: Option<[f32; 2]>,
    /// Id of the supporting object, or `wall_0..3` for an object hung on a wall.
    pub on: Option<String>,
    /// Id of a container the object stands in, on its lowest inner surface under the middle.
    #[serde(rename = "in")]
    pub inside: Option<String>,
    /// On an object: x, y in the parent's box frame. On a wall: distance along the wall from its
    /// first corner and the height of the object's bottom.
    pub offset: Option<[f32; 2]>,
    /// World yaw in degrees; objects on objects default to their parent's yaw, objects on walls
    /// always face into the room.
    pub yaw_deg: Option<f32>,
    pub size: Option<[f32; 3]>,
    /// A model id of the parametric library (default: a variant picked by the scene's seed).
    pub model: Option<String>,
    /// Joint values by part name (radians or metres), e.g. `{"door": 0.4}`; default closed.
    #[serde(default)]
    pub joints: BTreeMap<String, f32>,
}

/// The camera path. The default is a loop through the room that sees every object.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    pub frames: Option<usize>,
    /// Camera height above the floor, metres (default 1.45).
    pub height: Option<f32>,
}

/// Where an object rests, after validation.
#[derive(Clone, Debug, PartialEq)]
pub enum Placement {
    Floor {
        x: f32,
        y: f32,
    },
    OnObject {
        parent: String,
        offset: [f32; 2],
    },
    InObject {
        parent: String,
        offset: [f32; 2],
    },
    OnWall {
        wall: usize,
        along: f32,
        height: f32,
    },
}

/// The most objects a specification may place.
pub const MAX_OBJECTS: usize = 500;
/// The most frames a rendering may have (`camera.frames`, `render --frames`): 10 minutes at 15
/// frames/s, about 4 GB of PNGs.
pub const MAX_FRAMES: usize = 10_000;

/// Checks a frame count of a rendering.
pub fn check_frame_count(frames: usize) -> Result<(), InvalidValue> {
    if !(1..=MAX_FRAMES).contains(&frames) {
        return Err(InvalidValue::whole(format!(
            "{frames} frames is outside 1..{MAX_FRAMES}"
        )));
    }
    Ok(())
}

impl SceneSpec {
    /// Reads and validates a specification file.
    pub fn load(path: &Path) -> Result<SceneSpec, InputError> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
        Self::parse(&text, path)
    }

    /// Parses and validates `text`; `path` is only used to name the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<SceneSpec, InputError> {
        let mut de = serde_json::Deserializer::from_str(text);
        let mut spec: SceneSpec = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let key = e.path().to_string();
            InputError::invalid(
                path,
                format!("invalid scene specification at {key}: {}", e.into_inner()),
            )
        })?;
        spec.read_databases(path)?;
        spec.validate()
            .map_err(|problem| InputError::invalid(path, problem))?;
        Ok(spec)
    }

    /// Reads the databases of `"cad"`, relative to the specification's folder.
    pub(crate) fn read_databases(&mut self, path: &Path) -> Result<(), InputError> {
        let base = path.parent().unwrap_or(Path::new("."));
        for (k, name) in self.cad.iter().enumerate() {
            let dir = base.join(name);
            if !dir.join("index.json").is_file() {
                return Err(InputError::missing(
                    dir.join("index.json"),
                    format!(
                        "cad[{k}] of {}: {name:?} is not a CAD database (`iscene cad import` writes one)",
                        path.display()
                    ),
                ));
            }
            let models = read_database(&dir)?;
            self.databases.push(SpecDatabase { dir, models });
        }
        let mut seen: HashMap<&str, &Path> = HashMap::new();
        for db in &self.databases {
            for m in &db.models {
                if ParametricLibrary::get(&m.id).is_some() {
                    return Err(InputError::invalid(
                        &db.dir,
                        format!("model {:?} has the id of a built-in model", m.id),
                    ));
                }
                if let Some(other) = seen.insert(&m.id, &db.dir) {
                    return Err(InputError::invalid(
                        &db.dir,
                        format!("model {:?} is also in {}", m.id, other.display()),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The model `id`: a built-in one or one of the specification's databases.
    pub fn model_source(&self, id: &str) -> Option<ModelSource<'_>> {
        ParametricLibrary::get(id)
            .map(ModelSource::Parametric)
            .or_else(|| {
                self.databases
                    .iter()
                    .flat_map(|db| &db.models)
                    .find(|m| m.id == id)
                    .map(ModelSource::Database)
            })
    }

    pub(crate) fn validate(&self) -> Result<(), InvalidValue> {
        let [rx, ry, rz] = self.room.size;
        if !(rx.is_finite() && ry.is_finite() && rz.is_finite())
            || rx < 1.0
            || ry < 1.0
            || rz < 1.8
            || rx > 30.0
            || ry > 30.0
            || rz > 6.0
        {
            return Err(InvalidValue::at(
                "room.size",
                format!(
                    "{:?} is not a room (x, y in 1..30 m, height in 1.8..6 m)",
                    self.room.size
                ),
            ));
        }
        if self.objects.is_empty() {
            return Err(InvalidValue::at(
                "objects",
                "a scene needs at least one object",
            ));
        }
        if self.objects.len() > MAX_OBJECTS {
            return Err(InvalidValue::at(
                "objects",
                format!(
                    "{} objects, more than the {MAX_OBJECTS} a room may hold",
                    self.objects.len()
                ),
            ));
        }
        if let Some(pose) = self.noise.pose_model() {
            pose.check()?;
        }
        if let Some(frames) = self.camera.frames {
            check_frame_count(frames).map_err(|e| e.under("camera.frames"))?;
        }
        if let Some(h) = self.camera.height
            && !(0.3..rz).contains(&h)
        {
            return Err(InvalidValue::at(
                "camera.height",
                format!("{h} is outside the room (0.3..{rz} m)"),
            ));
        }
        let classes = ClassTable::builtin();
        let mut index: HashMap<&str, usize> = HashMap::new();
        for (i, o) in self.objects.iter().enumerate() {
            let key = format!("objects[{i}]");
            if o.id.is_empty()
                || !o
                    .id
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            {
                return Err(InvalidValue::at(
                    format!("{key}.id"),
                    format!(
                        "{:?} must be non-empty ASCII letters, digits, '_' or '-'",
                        o.id
                    ),
                ));
            }
            if is_layout_id(&o.id) {
                return Err(InvalidValue::at(
                    format!("{key}.id"),
                    format!("{:?} is reserved for the room's layout", o.id),
                ));
            }
            if index.insert(o.id.as_str(), i).is_some() {
                return Err(InvalidValue::at(
                    format!("{key}.id"),
                    format!("duplicate id {:?}", o.id),
                ));
            }
            let Some(info) = classes.get(&o.class) else {
                let known: Vec<_> = classes
                    .iter()
                    .filter(|(_, c)| c.kind != EntityKind::Layout)
                    .map(|(n, _)| n)
                    .collect();
                return Err(InvalidValue::at(
                    format!("{key}.class"),
                    format!("unknown class {:?} (known: {})", o.class, known.join(", ")),
                ));
            };
            if info.kind == EntityKind::Layout {
                return Err(InvalidValue::at(
                    format!("{key}.class"),
                    format!(
                        "{:?} is layout; the room makes its own floor, walls and ceiling",
                        o.class
                    ),
                ));
            }
            if let Some(size) = o.size {
                let ok = size.iter().enumerate().all(|(k, s)| {
                    s.is_finite() && *s >= info.size_min[k] && *s <= info.size_max[k]
                });
                if !ok {
                    return Err(InvalidValue::at(
                        format!("{key}.size"),
                        format!(
                            "{size:?} outside the {} range {} .. {}",
                            o.class, info.size_min, info.size_max
                        ),
                    ));
                }
            }
            if let Some(model) = &o.model {
                match self.model_source(model) {
                    None if self.cad.is_empty() => {
                        return Err(InvalidValue::at(
                            format!("{key}.model"),
                            format!("unknown model {model:?}"),
                        ));
                    }
                    None => {
                        return Err(InvalidValue::at(
                            format!("{key}.model"),
                            format!(
                                "unknown model {model:?} (neither built in nor in the databases of \"cad\": {})",
                                self.cad.join(", ")
                            ),
                        ));
                    }
                    Some(e) if e.class() != o.class => {
                        return Err(InvalidValue::at(
                            format!("{key}.model"),
                            format!("{model:?} is a {}, not a {}", e.class(), o.class),
                        ));
                    }
                    Some(ModelSource::Database(_)) if o.size.is_some() => {
                        return Err(InvalidValue::at(
                            format!("{key}.size"),
                            format!(
                                "{model:?} is a database model and keeps the size its author gave it"
                            ),
                        ));
                    }
                    Some(_) => {}
                }
            }
            if let Some(y) = o.yaw_deg
                && !y.is_finite()
            {
                return Err(InvalidValue::at(
                    format!("{key}.yaw_deg"),
                    "not a finite number",
                ));
            }
            for (name, value) in &o.joints {
                if !value.is_finite() {
                    return Err(InvalidValue::at(
                        format!("{key}.joints.{name}"),
                        "not a finite number",
                    ));
                }
            }
            self.placement(i).map_err(|e| e.under(&key))?;
        }
        // References must resolve and the support relation must be a tree.
        for (i, o) in self.objects.iter().enumerate() {
            let mut seen = vec![i];
            let mut current = o;
            while let Some(parent) = current.on.as_deref().or(current.inside.as_deref()) {
                if is_layout_id(parent) {
                    break;
                }
                let Some(&p) = index.get(parent) else {
                    let key = if current.on.is_some() { "on" } else { "in" };
                    return Err(InvalidValue::at(
                        format!("objects[{}].{key}", seen[seen.len() - 1]),
                        format!("no object with id {parent:?}"),
                    ));
                };
                if seen.contains(&p) {
                    return Err(InvalidValue::at(
                        format!("objects[{i}].on"),
                        format!("support cycle through {parent:?}"),
                    ));
                }
                seen.push(p);
                current = &self.objects[p];
            }
        }
        Ok(())
    }

    /// The validated placement of object `i`; errors name the offending key.
    pub fn placement(&self, i: usize) -> Result<Placement, InvalidValue> {
        let o = &self.objects[i];
        let offset = o.offset.unwrap_or([0.0, 0.0]);
        if !offset.iter().all(|v| v.is_finite()) {
            return Err(InvalidValue::at("offset", "not finite"));
        }
        match (&o.position, &o.on, &o.inside) {
            (Some(p), None, None) => {
                let [rx, ry, _] = self.room.size;
                if !(p[0].is_finite() && p[1].is_finite())
                    || p[0] <= 0.0
                    || p[1] <= 0.0
                    || p[0] >= rx
                    || p[1] >= ry
                {
                    return Err(InvalidValue::at(
                        "position",
                        format!("{p:?} is outside the floor [0, {rx}] x [0, {ry}]"),
                    ));
                }
                if o.offset.is_some() {
                    return Err(InvalidValue::at(
                        "offset",
                        "only for objects given with \"on\" or \"in\"",
                    ));
                }
                Ok(Placement::Floor { x: p[0], y: p[1] })
            }
            (None, Some(parent), None) => match wall_index(parent) {
                Some(wall) if wall < 4 => {
                    let Some([along, height]) = o.offset else {
                        return Err(InvalidValue::at(
                            "offset",
                            "an object on a wall needs [distance along the wall, height of its bottom]",
                        ));
                    };
                    Ok(Placement::OnWall {
                        wall,
                        along,
                        height,
                    })
                }
                Some(_) => Err(InvalidValue::at(
                    "on",
                    format!("{parent:?}: the room has walls wall_0..wall_3"),
                )),
                None if is_layout_id(parent) => Err(InvalidValue::at(
                    "on",
                    format!("{parent:?}: give floor objects a \"position\" instead"),
                )),
                None => Ok(Placement::OnObject {
                    parent: parent.clone(),
                    offset,
                }),
            },
            (None, None, Some(parent)) if !is_layout_id(parent) => Ok(Placement::InObject {
                parent: parent.clone(),
                offset,
            }),
            (None, None, Some(parent)) => Err(InvalidValue::at(
                "in",
                format!("{parent:?} is not an object"),
            )),
            (None, None, None) => Err(InvalidValue::at(
                "position",
                "give either \"position\", \"on\" or \"in\"",
            )),
            _ => Err(InvalidValue::at(
                "position",
                "give only one of \"position\", \"on\" and \"in\"",
            )),
        }
    }
}

pub fn is_layout_id(id: &str) -> bool {
    id == "floor" || id == "ceiling" || wall_index(id).is_some()
}

/// `wall_3` -> 3.
pub fn wall_index(id: &str) -> Option<usize> {
    id.strip_prefix("wall_").and_then(|n| n.parse().ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(json: &str) -> Result<SceneSpec, String> {
        SceneSpec::parse(json, Path::new("test.json")).map_err(|e| e.to_string())
    }

    const MINIMAL: &str = r#"{"name": "t", "room": {"size": [4, 3, 2.5]},
        "objects": [{"id": "table_1", "class": "table", "position": [2, 1.5]},
                    {"id": "cup_1", "class": "cup", "on": "table_1", "offset": [0.1, 0]}]}"#;

    #[test]
    fn minimal_spec_parses() {
        let spec = parse(MINIMAL).expect("valid");
        assert_eq!(
            spec.placement(1),
            Ok(Placement::OnObject {
                parent: "table_1".into(),
                offset: [0.1, 0.0]
            })
        );
    }

    #[test]
    fn errors_name_the_key() {
        let cases = [
            (
                MINIMAL
                    .replace("\"seed\"", "x")
                    .replace("\"name\": \"t\"", "\"name\": \"t\", \"colour\": 1"),
                "colour",
            ),
            (
                MINIMAL.replace("\"class\": \"cup\"", "\"class\": \"teapot\""),
                "objects[1].class",
            ),
            (
                MINIMAL.replace("\"on\": \"table_1\"", "\"on\": \"table_9\""),
                "objects[1].on",
            ),
            (
                MINIMAL.replace("[2, 1.5]", "[7, 1.5]"),
                "objects[0].position",
            ),
            (
                MINIMAL.replace("\"id\": \"cup_1\"", "\"id\": \"table_1\""),
                "duplicate id",
            ),
            (
                MINIMAL.replace("\"offset\": [0.1, 0]", "\"size\": [3, 3, 3]"),
                "objects[1].size",
            ),
            (
                MINIMAL.replace("\"offset\": [0.1, 0]", "\"model\": \"chair_01\""),
                "objects[1].model",
            ),
            (MINIMAL.replace("[4, 3, 2.5]", "[4, 3]"), "room"),
        ];
        for (json, key) in cases {
            let err = parse(&json).expect_err(key);
            assert!(
                err.contains(key) && err.contains("test.json"),
                "error {err:?} should name {key}"
            );
        }
    }

    #[test]
    fn support_cycles_are_rejected() {
        let json = r#"{"name": "t", "room": {"size": [4, 3, 2.5]},
            "objects": [{"id": "a", "class": "box", "on": "b"}, {"id": "b", "class": "box", "on": "a"}]}"#;
        assert!(parse(json).expect_err("cycle").contains("cycle"));
    }
}
