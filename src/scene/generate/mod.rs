//! `iscene generate`: a procedural room, the same for the same seed, after the room rules of
//! ProcTHOR (Deitke et al., 2022): furniture stands with its back to a wall, facing into the room,
//! with the clearance its doors and drawers need; tables stand free with chairs around them
//! facing them; wall cabinets hang above; small objects stand on tables, counters and shelves
//! and in open containers; some doors and drawers are left open. Every proposal is checked by
//! building the world it describes (the same checks a hand-written specification gets: no
//! overlaps past 5 mm, inside the room, supported), and the finished room is rendered at low
//! resolution along the default camera path so that every object is seen.

use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand::seq::IndexedRandom;
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

use crate::base::stable_hash;
use crate::error::InputError;
use crate::render::noise::NoiseChoice;
use crate::scene::spec::{CameraSpec, RoomSpec, SceneSpec};

mod checks;
mod room;
mod spec_file;

pub use checks::{doors_open_freely, unseen_objects};
use room::RoomBuilder;
pub use spec_file::write_generated;

/// The kinds of room `generate` makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RoomStyle {
    Kitchen,
    Office,
    Living,
    Bedroom,
    /// One of the others, chosen by the seed.
    Any,
}

impl RoomStyle {
    pub fn name(self) -> &'static str {
        match self {
            Self::Kitchen => "kitchen",
            Self::Office => "office",
            Self::Living => "living",
            Self::Bedroom => "bedroom",
            Self::Any => "any",
        }
    }
}

/// What `generate` is asked for.
#[derive(Clone, Debug)]
pub struct GenerateOptions {
    pub seed: u64,
    pub style: RoomStyle,
    /// CAD databases whose models the room may use, as given on the command line.
    pub cad: Vec<PathBuf>,
    /// Depth, segmentation and pose noise of the rendering.
    pub noise: NoiseChoice,
    pub frames: usize,
}

/// A room has this many objects, at least and at most.
pub const MIN_OBJECTS: usize = 8;
pub const MAX_OBJECTS: usize = 30;
/// Rooms tried (each from its own stream of the seed) before giving up.
const ATTEMPTS: u64 = 20;
/// Placements tried per proposed object.
pub(super) const TRIES_PER_OBJECT: usize = 12;
/// Visibility: frames of the default path rendered at a quarter of the resolution, and the
/// pixels an object needs in one of them (a 4x4 patch at full resolution is 1 pixel here).
pub(super) const VISIBILITY_FRAMES: usize = 60;
pub(super) const MIN_VISIBLE_PIXELS: usize = 12;
/// Gap between a wall and the back of the furniture against it, metres.
pub(super) const WALL_GAP: std::ops::Range<f32> = 0.01..0.04;
/// Bottom of wall cabinets above the floor, metres.
pub(super) const WALL_CABINET_HEIGHT: std::ops::Range<f32> = 1.4..1.6;
/// Small objects keep this far from the edge of what they stand on, metres.
pub(super) const EDGE_MARGIN: f32 = 0.03;

/// A generated specification as JSON, and the room it describes.
pub struct Generated {
    pub json: Value,
    pub objects: usize,
    pub style: RoomStyle,
}

/// Generates the room of `options`. `out` is where the specification will be written: the
/// databases of `--cad` are named relative to its folder.
pub fn generate(options: &GenerateOptions, out: &Path) -> Result<Generated, InputError> {
    // The databases, named as the specification will name them, read once.
    let mut source = SceneSpec {
        name: String::new(),
        seed: options.seed,
        room: RoomSpec {
            size: [4.0, 4.0, 2.6],
        },
        objects: Vec::new(),
        camera: CameraSpec::default(),
        noise: options.noise.settings(),
        cad: resolve_databases(&options.cad, out)?,
        databases: Vec::new(),
    };
    let base = out.parent().unwrap_or(Path::new("."));
    source
        .read_databases(&base.join("generated.json"))
        .map_err(|e| match e {
            InputError::Missing { path, what } => InputError::Missing {
                path,
                what: format!("--cad: {what}"),
            },
            e => e,
        })?;
    for attempt in 0..ATTEMPTS {
        let mut rng =
            ChaCha8Rng::seed_from_u64(stable_hash(options.seed, &format!("room-{attempt}")));
        let style = match options.style {
            RoomStyle::Any => *[
                RoomStyle::Kitchen,
                RoomStyle::Office,
                RoomStyle::Living,
                RoomStyle::Bedroom,
            ]
            .choose(&mut rng)
            .unwrap_or(&RoomStyle::Kitchen),
            s => s,
        };
        let mut room = RoomBuilder::new(&source, style, options, &mut rng);
        room.furnish(&mut rng);
        room.keep_visible();
        if room.spec.objects.len() >= MIN_OBJECTS {
            return Ok(Generated {
                objects: room.spec.objects.len(),
                json: room.to_json(options),
                style,
            });
        }
    }
    Err(InputError::invalid(
        "--seed",
        format!(
            "no room of {MIN_OBJECTS} or more visible objects came out of {ATTEMPTS} attempts for seed {}",
            options.seed
        ),
    ))
}

/// The `--cad` folders as the specification names them: relative to its folder where both are
/// relative, else absolute.
fn resolve_databases(cad: &[PathBuf], out: &Path) -> Result<Vec<String>, InputError> {
    let base = out.parent().unwrap_or(Path::new(""));
    cad.iter()
        .map(|db| {
            let absolute = std::fs::canonicalize(db).map_err(|e| InputError::io(db, &e))?;
            let relative = std::fs::canonicalize(if base.as_os_str().is_empty() {
                Path::new(".")
            } else {
                base
            })
            .ok()
            .and_then(|b| absolute.strip_prefix(b).ok().map(Path::to_path_buf));
            let name = relative.unwrap_or(absolute);
            name.to_str()
                .map(str::to_string)
                .ok_or_else(|| InputError::invalid(db, "the path is not UTF-8"))
        })
        .collect()
}
