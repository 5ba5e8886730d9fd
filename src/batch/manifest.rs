//! The batch manifest: which inputs to reconstruct, with which options, and how they are shared
//! out over shards.
//!
//! ```json
//! {
//!   "defaults": {"frames": 300, "voxel": 0.02, "segmentation": "oracle"},
//!   "inputs": [
//!     {"seeds": "0:50", "style": "kitchen"},
//!     {"seed": 77, "cad": "db", "unseen": true},
//!     {"spec": "scenes/kitchen.json"},
//!     {"sequence": "/data/7scenes/redkitchen", "name": "redkitchen", "segmentation": "onnx"}
//!   ]
//! }
//! ```
//! A `seed` is a procedural room (generated, rendered, reconstructed, scored: a benchmark room),
//! a `spec` a scene specification (rendered, reconstructed, scored), a `sequence` a recorded or
//! rendered sequence folder (reconstructed; scored when it holds ground truth). Relative paths
//! are relative to the manifest. Every input resolves to a [`BatchInput`] with all its options,
//! which its status record keeps, so that an input run with other options is redone.

use std::collections::BTreeSet;
use std::fmt;
use std::path::{Path, PathBuf};

use clap::ValueEnum;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::base::InvalidValue;
use crate::error::InputError;
use crate::render::noise::NoiseChoice;
use crate::scene::generate::RoomStyle;
use crate::segmentation::SegmentationChoice;

/// Folder names inside a batch folder that no input may take.
const RESERVED_NAMES: [&str; 1] = ["slurm"];
/// Keys an input or `defaults` may set besides its source.
const OPTION_KEYS: [&str; 10] = [
    "name",
    "frames",
    "voxel",
    "segmentation",
    "cad",
    "unseen",
    "style",
    "noise",
    "evaluate",
    "robot",
];
/// Frames of a generated room when nothing says otherwise (as `iscene generate`).
const DEFAULT_GENERATED_FRAMES: usize = 300;

/// Where an input's frames come from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum InputSource {
    /// A procedural room: `iscene generate --seed`.
    Seed {
        seed: u64,
        style: String,
        noise: String,
    },
    /// A scene specification, rendered first.
    Spec { spec: PathBuf },
    /// A sequence folder (rendered or TUM).
    Sequence { sequence: PathBuf },
}

/// One input with every option resolved (defaults applied, paths absolute).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BatchInput {
    /// Its folder's name under the batch folder.
    pub name: String,
    pub source: InputSource,
    /// Frames to render (seed, spec) or to read from the start of the sequence; `None`: all.
    pub frames: Option<usize>,
    pub voxel: f32,
    pub segmentation: String,
    /// A CAD database: seeds draw models from it; the reconstruction searches it unless `unseen`.
    pub cad: Option<PathBuf>,
    pub unseen: bool,
    /// Score the reconstruction against the truth (when the input has one).
    pub evaluate: bool,
    /// The URDF of an arm: a scored room also gets a pick and place planned with it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<PathBuf>,
}

impl BatchInput {
    pub fn seed(&self) -> Option<u64> {
        match self.source {
            InputSource::Seed { seed, .. } => Some(seed),
            _ => None,
        }
    }

    /// The segmentation, checked when the manifest was read.
    pub fn segmentation_choice(&self) -> SegmentationChoice {
        SegmentationChoice::from_str(&self.segmentation, false)
            .unwrap_or(SegmentationChoice::Oracle)
    }

    /// The files and folders it reads.
    pub fn paths(&self) -> Vec<&Path> {
        let source = match &self.source {
            InputSource::Seed { .. } => None,
            InputSource::Spec { spec } => Some(spec.as_path()),
            InputSource::Sequence { sequence } => Some(sequence.as_path()),
        };
        source
            .into_iter()
            .chain(self.cad.as_deref())
            .chain(self.robot.as_deref())
            .collect()
    }

    /// The reconstruction's CAD database: the input's, unless it is unseen.
    pub fn searched_cad(&self) -> Option<PathBuf> {
        self.cad.clone().filter(|_| !self.unseen)
    }
}

/// Where a manifest came from when `iscene benchmark` wrote it: what its summary reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchmarkInfo {
    pub seeds: [u64; 2],
    pub style: String,
    pub noise: String,
    pub frames: usize,
}

/// A parsed, validated manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub inputs: Vec<BatchInput>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub benchmark: Option<BenchmarkInfo>,
}

/// Shard `index` of `count` (0-based, as Slurm's array task ids and Kubernetes' completion
/// indices): inputs `index`, `index + count`, `index + 2 count`, ... of the manifest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// `I/N` with `0 <= I < N`.
    pub fn parse(text: &str) -> Result<Self, InvalidValue> {
        let (i, n) = text
            .split_once('/')
            .ok_or_else(|| InvalidValue::whole(format!("{text:?} is not I/N")))?;
        let index: usize = i
            .trim()
            .parse()
            .map_err(|_| InvalidValue::whole(format!("{i:?} in {text:?} is not a shard index")))?;
        let count: usize = n
            .trim()
            .parse()
            .map_err(|_| InvalidValue::whole(format!("{n:?} in {text:?} is not a shard count")))?;
        if count == 0 || index >= count {
            return Err(InvalidValue::whole(format!(
                "{text:?}: the index counts from 0 and must be below the count"
            )));
        }
        Ok(Self { index, count })
    }

    /// Whether input `k` of the manifest is this shard's: a stable assignment by index.
    pub fn holds(&self, k: usize) -> bool {
        k % self.count == self.index
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Manifest {
    pub fn load(path: &Path) -> Result<Self, InputError> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
        let value: Value = serde_json::from_str(&text)
            .map_err(|e| InputError::invalid(path, format!("not valid JSON: {e}")))?;
        let base = path
            .parent()
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
        Self::from_value(&value, &base).map_err(|problem| InputError::invalid(path, problem))
    }

    /// Parses a manifest whose relative paths are relative to `base`.
    pub fn from_value(value: &Value, base: &Path) -> Result<Self, InvalidValue> {
        let object = value
            .as_object()
            .ok_or_else(|| InvalidValue::whole("the manifest is not a JSON object"))?;
        check_keys(object, &["inputs", "defaults", "benchmark"], "")?;
        let empty = Map::new();
        let defaults = match object.get("defaults") {
            None => &empty,
            Some(Value::Object(d)) => d,
            Some(_) => return Err(InvalidValue::at("defaults", "not an object")),
        };
        check_keys(defaults, &OPTION_KEYS, "defaults")?;
        if defaults.contains_key("name") {
            return Err(InvalidValue::at(
                "defaults.name",
                "a default cannot set a name: names are per input",
            ));
        }
        let raw = object
            .get("inputs")
            .and_then(Value::as_array)
            .ok_or_else(|| InvalidValue::at("inputs", "missing or not a list"))?;
        let mut inputs = Vec::new();
        for (i, entry) in raw.iter().enumerate() {
            let context = format!("inputs[{i}]");
            let entry = entry
                .as_object()
                .ok_or_else(|| InvalidValue::at(&context, "not an object"))?;
            inputs.extend(resolve_entry(entry, defaults, base, &context)?);
        }
        if inputs.is_empty() {
            return Err(InvalidValue::at("inputs", "lists nothing to run"));
        }
        let mut names = BTreeSet::new();
        for input in &inputs {
            if !names.insert(input.name.as_str()) {
                return Err(InvalidValue::at(
                    "inputs",
                    format!(
                        "two inputs are named {:?}: give one a \"name\" of its own",
                        input.name
                    ),
                ));
            }
        }
        let benchmark = match object.get("benchmark") {
            None => None,
            Some(b) => Some(
                serde_json::from_value(b.clone())
                    .map_err(|e| InvalidValue::at("benchmark", e.to_string()))?,
            ),
        };
        Ok(Self { inputs, benchmark })
    }

    /// The indices of the inputs that `shard` runs.
    pub fn share(&self, shard: Shard) -> Vec<usize> {
        (0..self.inputs.len()).filter(|&k| shard.holds(k)).collect()
    }
}

/// Refuses a key of `map` (the object at `context`) that is not `allowed`.
fn check_keys(
    map: &Map<String, Value>,
    allowed: &[&str],
    context: &str,
) -> Result<(), InvalidValue> {
    match map.keys().find(|k| !allowed.contains(&k.as_str())) {
        Some(key) => Err(InvalidValue::at(
            context,
            format!("unknown key {key:?} (allowed: {})", allowed.join(", ")),
        )),
        None => Ok(()),
    }
}

/// One entry of `inputs`: a seed, a range of seeds, a specification or a sequence.
fn resolve_entry(
    entry: &Map<String, Value>,
    defaults: &Map<String, Value>,
    base: &Path,
    context: &str,
) -> Result<Vec<BatchInput>, InvalidValue> {
    const SOURCES: [&str; 4] = ["seed", "seeds", "spec", "sequence"];
    let sources: Vec<&str> = SOURCES
        .into_iter()
        .filter(|k| entry.contains_key(*k))
        .collect();
    let [source] = sources[..] else {
        return Err(InvalidValue::at(
            context,
            "name exactly one of \"seed\", \"seeds\", \"spec\" and \"sequence\"",
        ));
    };
    let at = |key: &str, problem: String| InvalidValue::at(format!("{context}.{key}"), problem);
    let allowed: Vec<&str> = OPTION_KEYS.iter().copied().chain([source]).collect();
    check_keys(entry, &allowed, context)?;
    let option = |key: &str| entry.get(key).or_else(|| defaults.get(key));
    let options = Options::read(&option, base, context)?;
    let path = |key: &str| -> Result<PathBuf, InvalidValue> {
        let text = entry[key]
            .as_str()
            .ok_or_else(|| at(key, "not a path".into()))?;
        let path = base.join(text);
        let exists = if key == "spec" {
            path.is_file()
        } else {
            path.is_dir()
        };
        if !exists {
            return Err(at(
                key,
                format!(
                    "{} is missing ({text:?}, relative to the manifest)",
                    path.display()
                ),
            ));
        }
        std::path::absolute(&path).map_err(|e| at(key, format!("{}: {e}", path.display())))
    };
    let name = |default: String| -> Result<String, InvalidValue> {
        let name = match entry.get("name") {
            Some(n) => n
                .as_str()
                .ok_or_else(|| at("name", "not a string".into()))?
                .to_string(),
            None => default,
        };
        crate::file_name::check_file_name(&name).map_err(|e| at("name", e.to_string()))?;
        if RESERVED_NAMES.contains(&name.as_str()) {
            return Err(at("name", format!("{name:?} is the batch folder's own")));
        }
        Ok(name)
    };
    let stem = |p: &Path| {
        p.file_stem()
            .map_or("input".into(), |s| s.to_string_lossy().into_owned())
    };
    let seeds = match source {
        "seed" => {
            let seed = entry["seed"]
                .as_u64()
                .ok_or_else(|| at("seed", "not a whole number".into()))?;
            seed..seed + 1
        }
        "seeds" => {
            if entry.contains_key("name") {
                return Err(at(
                    "name",
                    "a range of seeds is named seed_N, one name per seed".into(),
                ));
            }
            parse_seed_range(entry["seeds"].as_str().unwrap_or_default())
                .map_err(|e| e.under(&format!("{context}.seeds")))?
        }
        "spec" => {
            let spec = path("spec")?;
            return Ok(vec![
                options.input(name(stem(&spec))?, InputSource::Spec { spec }),
            ]);
        }
        _ => {
            let sequence = path("sequence")?;
            return Ok(vec![options.input(
                name(stem(&sequence))?,
                InputSource::Sequence { sequence },
            )]);
        }
    };
    let frames = options.frames.unwrap_or(DEFAULT_GENERATED_FRAMES);
    crate::scene::spec::check_frame_count(frames)
        .map_err(|e| e.under(&format!("{context}.frames")))?;
    seeds
        .map(|seed| {
            Ok(BatchInput {
                frames: Some(frames),
                ..options.input(
                    name(format!("seed_{seed}"))?,
                    InputSource::Seed {
                        seed,
                        style: options.style.name().into(),
                        noise: options.noise.name().into(),
                    },
                )
            })
        })
        .collect()
}

/// `A:B`, B excluded and greater than A.
pub fn parse_seed_range(text: &str) -> Result<std::ops::Range<u64>, InvalidValue> {
    let (a, b) = text
        .split_once(':')
        .ok_or_else(|| InvalidValue::whole(format!("{text:?} is not A:B")))?;
    let a: u64 = a
        .parse()
        .map_err(|e| InvalidValue::whole(format!("{a:?}: {e}")))?;
    let b: u64 = b
        .parse()
        .map_err(|e| InvalidValue::whole(format!("{b:?}: {e}")))?;
    if b <= a || b - a > 10_000 {
        return Err(InvalidValue::whole(format!(
            "{text:?}: B must be greater than A, by at most 10000"
        )));
    }
    Ok(a..b)
}

/// An entry's options with the defaults applied.
struct Options {
    frames: Option<usize>,
    voxel: f32,
    segmentation: SegmentationChoice,
    cad: Option<PathBuf>,
    unseen: bool,
    style: RoomStyle,
    noise: NoiseChoice,
    evaluate: bool,
    robot: Option<PathBuf>,
}

impl Options {
    fn read<'a>(
        option: &dyn Fn(&str) -> Option<&'a Value>,
        base: &Path,
        context: &str,
    ) -> Result<Self, InvalidValue> {
        let at = |key: &str, problem: String| InvalidValue::at(format!("{context}.{key}"), problem);
        let bad = |key: &str, what: &str| at(key, format!("not {what}"));
        let text = |key: &str| -> Result<Option<&'a str>, InvalidValue> {
            option(key)
                .map(|v| v.as_str().ok_or_else(|| bad(key, "a string")))
                .transpose()
        };
        let flag = |key: &str| -> Result<bool, InvalidValue> {
            option(key)
                .map(|v| v.as_bool().ok_or_else(|| bad(key, "true or false")))
                .transpose()
                .map(Option::unwrap_or_default)
        };
        let enumerated = |key: &str, values: &str| -> Result<Option<&'a str>, InvalidValue> {
            text(key).map_err(|_| bad(key, values))
        };
        let frames = option("frames")
            .map(|v| {
                v.as_u64()
                    .filter(|&n| n > 0)
                    .map(|n| n as usize)
                    .ok_or_else(|| bad("frames", "a positive whole number"))
            })
            .transpose()?;
        let voxel = option("voxel")
            .map(|v| {
                v.as_f64()
                    .filter(|x| x.is_finite() && (0.002..=0.5).contains(x))
                    .ok_or_else(|| bad("voxel", "a voxel size from 0.002 to 0.5 m"))
            })
            .transpose()?
            .unwrap_or(0.02) as f32;
        let segmentation = match enumerated("segmentation", "oracle, onnx or none")? {
            None => SegmentationChoice::Oracle,
            Some(s) => SegmentationChoice::from_str(s, false)
                .map_err(|_| bad("segmentation", "oracle, onnx or none"))?,
        };
        let style = match enumerated("style", "a room style")? {
            None => RoomStyle::Any,
            Some(s) => RoomStyle::from_str(s, false)
                .map_err(|_| bad("style", "kitchen, office, living, bedroom or any"))?,
        };
        let noise = match enumerated("noise", "realistic or clean")? {
            None => NoiseChoice::Realistic,
            Some(s) => {
                NoiseChoice::from_str(s, false).map_err(|_| bad("noise", "realistic or clean"))?
            }
        };
        let cad = match text("cad")? {
            None => None,
            Some(db) => {
                let db = base.join(db);
                if !db.join("index.json").is_file() {
                    return Err(at(
                        "cad",
                        format!(
                            "{} is not a CAD database (`iscene cad import` writes one)",
                            db.display()
                        ),
                    ));
                }
                Some(std::path::absolute(&db).map_err(|e| at("cad", e.to_string()))?)
            }
        };
        let unseen = flag("unseen")?;
        if unseen && cad.is_none() {
            return Err(at(
                "unseen",
                "needs a \"cad\" database to leave unsearched".into(),
            ));
        }
        let evaluate = option("evaluate").is_none() || flag("evaluate")?;
        let robot = match text("robot")? {
            None => None,
            Some(file) => {
                let file = base.join(file);
                if !file.is_file() {
                    return Err(at(
                        "robot",
                        format!("{} is missing (an arm's URDF file)", file.display()),
                    ));
                }
                Some(std::path::absolute(&file).map_err(|e| at("robot", e.to_string()))?)
            }
        };
        Ok(Self {
            frames,
            voxel,
            segmentation,
            cad,
            unseen,
            style,
            noise,
            evaluate,
            robot,
        })
    }

    fn input(&self, name: String, source: InputSource) -> BatchInput {
        BatchInput {
            name,
            source,
            frames: self.frames,
            voxel: self.voxel,
            segmentation: self
                .segmentation
                .to_possible_value()
                .map_or_else(|| "oracle".into(), |v| v.get_name().to_string()),
            cad: self.cad.clone(),
            unseen: self.unseen,
            evaluate: self.evaluate,
            robot: self.robot.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn manifest(value: Value) -> Result<Manifest, String> {
        Manifest::from_value(&value, Path::new(".")).map_err(|e| e.to_string())
    }

    #[test]
    fn a_range_of_seeds_takes_the_defaults_and_its_own_options() {
        let m = manifest(json!({
            "defaults": {"frames": 40, "voxel": 0.03},
            "inputs": [{"seeds": "3:5", "style": "kitchen"}, {"seed": 9, "noise": "clean"}]
        }))
        .expect("valid");
        let names: Vec<&str> = m.inputs.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["seed_3", "seed_4", "seed_9"]);
        assert_eq!(m.inputs[0].frames, Some(40));
        assert_eq!(m.inputs[2].voxel, 0.03);
        assert_eq!(
            m.inputs[1].source,
            InputSource::Seed {
                seed: 4,
                style: "kitchen".into(),
                noise: "realistic".into()
            }
        );
        assert_eq!(
            m.inputs[2].source,
            InputSource::Seed {
                seed: 9,
                style: "any".into(),
                noise: "clean".into()
            }
        );
        assert!(m.inputs.iter().all(|i| i.evaluate && !i.unseen));
    }

    #[test]
    fn a_generated_room_defaults_to_the_generators_frame_count() {
        let m = manifest(json!({"inputs": [{"seed": 1}]})).expect("valid");
        assert_eq!(m.inputs[0].frames, Some(DEFAULT_GENERATED_FRAMES));
    }

    #[test]
    fn bad_manifests_say_what_is_wrong() {
        let cases = [
            (json!([]), "not a JSON object"),
            (json!({"inputs": []}), "nothing to run"),
            (
                json!({"inputs": [{"seed": 1, "seeds": "0:2"}]}),
                "exactly one",
            ),
            (
                json!({"inputs": [{"seed": 1, "colour": "red"}]}),
                "\"colour\"",
            ),
            (json!({"inputs": [{"seed": -1}]}), "whole number"),
            (json!({"inputs": [{"seeds": "5:2"}]}), "greater"),
            (json!({"inputs": [{"seed": 1, "voxel": 0.0}]}), "voxel"),
            (json!({"inputs": [{"seed": 1, "style": "castle"}]}), "style"),
            (json!({"inputs": [{"seed": 1, "unseen": true}]}), "needs a"),
            (
                json!({"inputs": [{"seed": 1, "name": "../x"}]}),
                "plain name",
            ),
            (json!({"inputs": [{"seed": 1, "name": "slurm"}]}), "own"),
            (json!({"inputs": [{"seed": 1}, {"seed": 1}]}), "two inputs"),
            (
                json!({"inputs": [{"spec": "no/such/spec.json"}]}),
                "missing",
            ),
            (json!({"inputs": [{"seed": 1}], "extra": 1}), "\"extra\""),
            (
                json!({"defaults": {"name": "a"}, "inputs": [{"seed": 1}]}),
                "per input",
            ),
        ];
        for (value, expected) in cases {
            let err = manifest(value.clone()).expect_err(&value.to_string());
            assert!(err.contains(expected), "{value}: {err}");
        }
    }

    #[test]
    fn shards_split_the_inputs_by_index_and_cover_each_once() {
        let shards: Vec<Shard> = (0..3).map(|i| Shard { index: i, count: 3 }).collect();
        for k in 0..10 {
            assert_eq!(shards.iter().filter(|s| s.holds(k)).count(), 1, "input {k}");
        }
        assert!(shards[1].holds(4) && shards[1].holds(7));
        assert_eq!(Shard::parse("2/3"), Ok(Shard { index: 2, count: 3 }));
        assert!(Shard::parse("3/3").is_err());
        assert!(Shard::parse("1/0").is_err());
        assert!(Shard::parse("1").is_err());
        assert_eq!(Shard { index: 1, count: 4 }.to_string(), "1/4");
    }
}
