//! The room builder: furniture against walls, tables with chairs, doors left open and small
//! objects, each proposal kept only when the world it describes passes the checks.

use std::path::Path;

use glam::Vec3;
use rand::Rng;
use rand::seq::IndexedRandom;
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};

use super::checks::{doors_open_freely, unseen_objects};
use super::spec_file::{numbers, object_json};
use super::{
    EDGE_MARGIN, GenerateOptions, MAX_OBJECTS, RoomStyle, TRIES_PER_OBJECT, WALL_CABINET_HEIGHT,
    WALL_GAP,
};
use crate::cad::ParametricLibrary;
use crate::geometry::GravityBox;
use crate::scene::overlap::deepest_overlap_of;
use crate::scene::render_sequence::DEFAULT_FRAMES;
use crate::scene::spec::{CameraSpec, ModelSource, ObjectSpec, RoomSpec, SceneSpec};
use crate::scene::world::{SceneWorld, wall_frame, wall_length, yaw_facing};

/// How deep a generated object may stand in another, metres. Specifications may round sizes
/// into each other by up to `MAX_OVERLAP_M`; a generated room, the truth the benchmark
/// measures against, touches without standing in anything (a cup standing 3.6 mm in a book
/// moved 3.7 mm in MuJoCo at rest).
const GENERATED_OVERLAP_M: f32 = 0.0005;

/// How far (metres, 0 when not) object `index` reaches behind a wall, the floor or the ceiling.
fn reaches_past_room(world: &SceneWorld, index: usize) -> f32 {
    let room = world.room_size;
    world.objects[index]
        .world_mesh()
        .positions
        .iter()
        .map(|p| (-p.min(Vec3::ZERO)).max(*p - room).max_element())
        .fold(0.0, f32::max)
}

/// What a piece of furniture stands against.
#[derive(Clone, Copy)]
struct WallSlot {
    wall: usize,
    /// Distance of its centre along the wall from the wall's first corner.
    along: f32,
}

pub(super) struct RoomBuilder<'a> {
    pub(super) spec: SceneSpec,
    style: RoomStyle,
    /// Ids given so far per class.
    counts: std::collections::BTreeMap<String, usize>,
    source: &'a SceneSpec,
    /// Chance that a database model is used for a class both it and the library have.
    database_share: f64,
}

impl<'a> RoomBuilder<'a> {
    pub(super) fn new(
        source: &'a SceneSpec,
        style: RoomStyle,
        options: &GenerateOptions,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        let (xs, ys) = match style {
            RoomStyle::Kitchen => (3.6..6.0, 3.2..5.0),
            RoomStyle::Office => (4.0..7.0, 3.5..6.0),
            RoomStyle::Living => (4.5..7.0, 4.0..6.0),
            _ => (3.8..6.0, 3.6..5.0),
        };
        let size = [
            round_cm(rng.random_range(xs)),
            round_cm(rng.random_range(ys)),
            round_cm(rng.random_range(2.5..2.9)),
        ];
        let spec = SceneSpec {
            name: format!("generated_{}_{}", style.name(), options.seed),
            seed: options.seed,
            room: RoomSpec { size },
            objects: Vec::new(),
            camera: CameraSpec {
                frames: Some(options.frames),
                height: None,
            },
            noise: options.noise.settings(),
            cad: source.cad.clone(),
            databases: source.databases.clone(),
        };
        Self {
            spec,
            style,
            counts: Default::default(),
            source,
            database_share: if source.databases.is_empty() {
                0.0
            } else {
                0.6
            },
        }
    }

    fn room(&self) -> Vec3 {
        Vec3::from_array(self.spec.room.size)
    }

    /// The world of the specification so far (it was checked when each object was added).
    fn world(&self) -> Option<SceneWorld> {
        SceneWorld::from_spec(&self.spec, Path::new("generated.json")).ok()
    }

    fn next_id(&mut self, class: &str) -> String {
        let n = self.counts.entry(class.to_string()).or_default();
        *n += 1;
        format!("{class}_{n}")
    }

    /// A model of `class`: from the databases with `database_share`, else a library variant.
    fn pick_model(&self, class: &str, rng: &mut ChaCha8Rng) -> Option<String> {
        let imported: Vec<&str> = self
            .source
            .databases
            .iter()
            .flat_map(|db| &db.models)
            .filter(|m| m.class == class)
            .map(|m| m.id.as_str())
            .collect();
        if !imported.is_empty() && rng.random_bool(self.database_share) {
            return imported.choose(rng).map(|s| s.to_string());
        }
        let variants: Vec<&str> = ParametricLibrary::variants(class).map(|e| e.id).collect();
        variants.choose(rng).map(|s| s.to_string())
    }

    /// Adds `object` when the world stays valid and every door and drawer (its own and the
    /// others') can open all the way; returns whether it was added.
    fn try_add(&mut self, object: ObjectSpec) -> bool {
        self.spec.objects.push(object);
        let ok = self.spec.validate().is_ok()
            && self.world().is_some_and(|w| {
                let last = w.objects.len() - 1;
                deepest_overlap_of(&w, last) <= GENERATED_OVERLAP_M
                    && reaches_past_room(&w, last) <= GENERATED_OVERLAP_M
                    && doors_open_freely(&w, last)
            });
        if !ok {
            self.spec.objects.pop();
        }
        ok
    }

    pub(super) fn furnish(&mut self, rng: &mut ChaCha8Rng) {
        match self.style {
            RoomStyle::Kitchen => {
                let wall = rng.random_range(0..4);
                self.counter_run(wall, rng);
                if rng.random_bool(0.5) {
                    self.along_wall(
                        (wall + 1 + 2 * rng.random_range(0..2)) % 4,
                        &["shelf", "cabinet"],
                        2,
                        rng,
                    );
                }
                self.dining_table(rng);
            }
            RoomStyle::Office => {
                let desks = rng.random_range(1..=3);
                for _ in 0..desks {
                    let wall = rng.random_range(0..4);
                    self.desk(wall, rng);
                }
                let wall = rng.random_range(0..4);
                self.along_wall(wall, &["shelf", "cabinet", "shelf"], 3, rng);
            }
            RoomStyle::Living => {
                let wall = rng.random_range(0..4);
                self.sofa_corner(wall, rng);
                self.along_wall((wall + 2) % 4, &["cabinet", "shelf"], 2, rng);
                self.along_wall((wall + 1) % 4, &["chair", "shelf", "box"], 2, rng);
            }
            _ => {
                let wall = rng.random_range(0..4);
                self.bed(wall, rng);
                self.along_wall((wall + 2) % 4, &["cabinet", "shelf"], 2, rng);
                self.desk((wall + 1 + 2 * rng.random_range(0..2)) % 4, rng);
            }
        }
        self.open_some_doors(rng);
        let target = rng.random_range(12..=MAX_OBJECTS);
        self.small_objects(target, rng);
    }

    /// Proposes a piece of furniture of `class` with its back to `wall` at `along`.
    fn wall_object(
        &mut self,
        class: &str,
        model: Option<String>,
        size: Option<[f32; 3]>,
        slot: WallSlot,
        rng: &mut ChaCha8Rng,
    ) -> Option<String> {
        let model = model.or_else(|| self.pick_model(class, rng))?;
        let source = self.source.model_source(&model)?;
        let dims = size.map_or(source.nominal_size(), Vec3::from_array);
        let room = self.room();
        let (start, dir, inward) = wall_frame(room, slot.wall);
        let gap = rng.random_range(WALL_GAP);
        let p = start + dir * slot.along + inward * (0.5 * dims.y + gap);
        let id = self.next_id(class);
        let object = object_spec(
            &id,
            class,
            Some(model),
            size.filter(|_| matches!(source, ModelSource::Parametric(_))),
        )
        .at(p.x, p.y, yaw_facing(inward).to_degrees());
        if self.try_add(object) {
            Some(id)
        } else {
            self.release_id(class);
            None
        }
    }

    fn release_id(&mut self, class: &str) {
        if let Some(n) = self.counts.get_mut(class) {
            *n -= 1;
        }
    }

    /// Furniture of `classes` (in turn) along `wall`, up to `count` pieces, at free places.
    fn along_wall(&mut self, wall: usize, classes: &[&str], count: usize, rng: &mut ChaCha8Rng) {
        let length = wall_length(self.room(), wall);
        let mut placed = 0;
        for class in classes.iter().cycle().take(count * 2) {
            if placed == count {
                break;
            }
            for _ in 0..TRIES_PER_OBJECT {
                let along = rng.random_range(0.4..(length - 0.4).max(0.5));
                let size = self.furniture_size(class, rng);
                if self
                    .wall_object(class, None, size, WallSlot { wall, along }, rng)
                    .is_some()
                {
                    placed += 1;
                    break;
                }
            }
        }
    }

    /// A size for a library piece of furniture: its nominal size, varied a little.
    fn furniture_size(&self, class: &str, rng: &mut ChaCha8Rng) -> Option<[f32; 3]> {
        match class {
            "shelf" => Some([
                round_cm(rng.random_range(0.7..1.0)),
                round_cm(rng.random_range(0.3..0.4)),
                round_cm(rng.random_range(1.1..1.8)),
            ]),
            _ => None,
        }
    }

    /// Base units, appliances and a fridge side by side along `wall`, wall cabinets above some.
    fn counter_run(&mut self, wall: usize, rng: &mut ChaCha8Rng) {
        let length = wall_length(self.room(), wall);
        let mut along = rng.random_range(0.05..0.6);
        let mut units = vec!["cabinet", "dishwasher", "oven", "cabinet", "cabinet"];
        units.truncate(rng.random_range(3..=5));
        units.insert(rng.random_range(0..=units.len()), "fridge");
        for class in units {
            let Some(model) = self.pick_model(class, rng) else {
                continue;
            };
            let Some(width) = self.source.model_source(&model).map(|s| s.nominal_size().x) else {
                continue;
            };
            // Next to the unit before; a little apart when a door of one meets the other.
            for gap in [0.01, 0.12, 0.3] {
                if along + gap + width > length - 0.05 {
                    break;
                }
                let slot = WallSlot {
                    wall,
                    along: along + gap + 0.5 * width,
                };
                if self
                    .wall_object(class, Some(model.clone()), None, slot, rng)
                    .is_some()
                {
                    if class == "cabinet" && rng.random_bool(0.6) {
                        self.wall_cabinet(slot, rng);
                    }
                    along += gap + width;
                    break;
                }
            }
        }
    }

    /// A wall cabinet centred above `slot`.
    fn wall_cabinet(&mut self, slot: WallSlot, rng: &mut ChaCha8Rng) {
        let id = self.next_id("cabinet");
        let height = round_cm(rng.random_range(WALL_CABINET_HEIGHT));
        let mut object = object_spec(&id, "cabinet", Some("cabinet_04".into()), None);
        object.on = Some(format!("wall_{}", slot.wall));
        object.offset = Some([round_cm(slot.along), height]);
        if !self.try_add(object) {
            self.release_id("cabinet");
        }
    }

    /// A table standing free with chairs around it facing it.
    fn dining_table(&mut self, rng: &mut ChaCha8Rng) -> Option<String> {
        let room = self.room();
        for _ in 0..TRIES_PER_OBJECT {
            let model = self.pick_model("table", rng)?;
            let x = rng.random_range(0.35 * room.x..0.65 * room.x);
            let y = rng.random_range(0.35 * room.y..0.65 * room.y);
            let yaw = [0.0f32, 90.0].choose(rng).copied().unwrap_or(0.0)
                + rng.random_range(-15.0f32..15.0);
            let id = self.next_id("table");
            if self.try_add(object_spec(&id, "table", Some(model), None).at(x, y, yaw)) {
                self.chairs_around(&id, rng);
                return Some(id);
            }
            self.release_id("table");
        }
        None
    }

    /// Chairs on some sides of table `table`, facing it, pulled out far enough to stand free.
    fn chairs_around(&mut self, table: &str, rng: &mut ChaCha8Rng) {
        let Some(b) = self
            .world()
            .and_then(|w| w.object(table).map(|t| t.gravity_box()))
        else {
            return;
        };
        let chair_model = self.pick_model("chair", rng);
        let sides = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y];
        let wanted = rng.random_range(2..=4);
        let mut placed = 0;
        for side in sides {
            if placed == wanted {
                break;
            }
            let half = 0.5 * if side.x != 0.0 { b.size.x } else { b.size.y };
            let pulls = [0.1f32, 0.2, 0.32];
            if self.chair_facing(&b, side, half, &pulls, 8.0, &chair_model, rng) {
                placed += 1;
            }
        }
    }

    /// A chair `half + pull` out along `side` in `b`'s frame, facing `b`'s centre (yaw jittered
    /// by up to `jitter_deg`), at the first of `pulls` where it stands free; whether one did.
    #[allow(clippy::too_many_arguments)]
    fn chair_facing(
        &mut self,
        b: &GravityBox,
        side: Vec3,
        half: f32,
        pulls: &[f32],
        jitter_deg: f32,
        model: &Option<String>,
        rng: &mut ChaCha8Rng,
    ) -> bool {
        for &pull in pulls {
            let p = b.world_from_box().transform_point3(side * (half + pull));
            let facing = (b.center - p).with_z(0.0).normalize_or_zero();
            let yaw = yaw_facing(facing).to_degrees() + rng.random_range(-jitter_deg..jitter_deg);
            let id = self.next_id("chair");
            if self.try_add(object_spec(&id, "chair", model.clone(), None).at(p.x, p.y, yaw)) {
                return true;
            }
            self.release_id("chair");
        }
        false
    }

    /// A desk against `wall` with a chair in front of it and a monitor on it.
    fn desk(&mut self, wall: usize, rng: &mut ChaCha8Rng) {
        let length = wall_length(self.room(), wall);
        for _ in 0..TRIES_PER_OBJECT {
            let along = rng.random_range(0.7..(length - 0.7).max(0.8));
            let model = ["table_04", "table_01"].choose(rng).map(|s| s.to_string());
            let Some(desk) = self.wall_object("table", model, None, WallSlot { wall, along }, rng)
            else {
                continue;
            };
            let monitor = self.pick_model("monitor", rng);
            let id = self.next_id("monitor");
            let mut object = object_spec(&id, "monitor", monitor, None);
            object.on = Some(desk.clone());
            object.offset = Some([round_cm(rng.random_range(-0.2..0.2)), 0.12]);
            if !self.try_add(object) {
                self.release_id("monitor");
            }
            self.chairs_in_front(&desk, rng);
            return;
        }
    }

    /// One chair in front of a desk, facing it.
    fn chairs_in_front(&mut self, desk: &str, rng: &mut ChaCha8Rng) {
        let Some(b) = self
            .world()
            .and_then(|w| w.object(desk).map(|t| t.gravity_box()))
        else {
            return;
        };
        let model = self.pick_model("chair", rng);
        let pulls = [0.15f32, 0.3, 0.45];
        self.chair_facing(&b, -Vec3::Y, 0.5 * b.size.y, &pulls, 10.0, &model, rng);
    }

    /// A sofa against `wall` with a low table in front of it.
    fn sofa_corner(&mut self, wall: usize, rng: &mut ChaCha8Rng) {
        let length = wall_length(self.room(), wall);
        for _ in 0..TRIES_PER_OBJECT {
            let along = rng.random_range(1.2..(length - 1.2).max(1.3));
            let Some(sofa) = self.wall_object("sofa", None, None, WallSlot { wall, along }, rng)
            else {
                continue;
            };
            let Some(b) = self
                .world()
                .and_then(|w| w.object(&sofa).map(|t| t.gravity_box()))
            else {
                return;
            };
            let size = [
                round_cm(rng.random_range(0.9..1.2)),
                round_cm(rng.random_range(0.5..0.65)),
                round_cm(rng.random_range(0.4..0.5)),
            ];
            for pull in [0.45f32, 0.6, 0.8] {
                let p = b
                    .world_from_box()
                    .transform_point3(-Vec3::Y * (0.5 * b.size.y + pull + 0.5 * size[1]));
                let id = self.next_id("table");
                let object = object_spec(&id, "table", Some("table_01".into()), Some(size)).at(
                    p.x,
                    p.y,
                    b.yaw.to_degrees(),
                );
                if self.try_add(object) {
                    return;
                }
                self.release_id("table");
            }
            return;
        }
    }

    /// A bed with its head against `wall` and a bedside cabinet beside it.
    fn bed(&mut self, wall: usize, rng: &mut ChaCha8Rng) {
        let length = wall_length(self.room(), wall);
        for _ in 0..TRIES_PER_OBJECT {
            let along = rng.random_range(1.3..(length - 1.3).max(1.4));
            // Beds face -y like every model: the head board is their back.
            let Some(bed) = self.wall_object("bed", None, None, WallSlot { wall, along }, rng)
            else {
                continue;
            };
            let width = self
                .world()
                .and_then(|w| w.object(&bed).map(|b| b.model.size.x))
                .unwrap_or(1.6);
            for side in [-1.0f32, 1.0] {
                let slot = WallSlot {
                    wall,
                    along: along + side * (0.5 * width + 0.3),
                };
                self.wall_object(
                    "cabinet",
                    Some("cabinet_02".into()),
                    Some([0.45, 0.4, 0.55]),
                    slot,
                    rng,
                );
            }
            return;
        }
    }

    /// Opens some doors and drawers part of the way (each kept only when it still fits).
    fn open_some_doors(&mut self, rng: &mut ChaCha8Rng) {
        let Some(world) = self.world() else {
            return;
        };
        for (i, object) in world.objects.iter().enumerate() {
            for part in object.model.movable_parts() {
                let Some((_, upper)) = part.joint.limits else {
                    continue;
                };
                if !rng.random_bool(0.25) {
                    continue;
                }
                let value = round_cm(upper * rng.random_range(0.3..0.9));
                self.spec.objects[i].joints.insert(part.name.clone(), value);
                // A part left open is part of the object for every other door's clearance.
                let ok = self.spec.validate().is_ok()
                    && self.world().is_some_and(|w| doors_open_freely(&w, i));
                if !ok {
                    self.spec.objects[i].joints.remove(&part.name);
                }
            }
        }
    }

    /// Cups, bowls, books, bottles and boxes on tables, counters and cabinets, in shelves and
    /// open fridges, and a microwave on a counter, until the room holds `target` objects.
    fn small_objects(&mut self, target: usize, rng: &mut ChaCha8Rng) {
        let Some(world) = self.world() else {
            return;
        };
        // Surfaces: what stands on a top (tables, cabinets below eye height, dishwashers) and
        // what stands inside (shelves, open fridges).
        let mut tops = Vec::new();
        let mut insides = Vec::new();
        for (i, o) in world.objects.iter().enumerate() {
            // The top as "on" offsets measure it: with doors and drawers closed.
            let b = o.closed_box();
            let spec = &self.spec.objects[i];
            let on_wall = spec.on.as_deref().is_some_and(|p| p.starts_with("wall_"));
            match o.class.as_str() {
                "table" | "dishwasher" => tops.push((o.id.clone(), b.size)),
                "cabinet" if !on_wall && b.center.z + 0.5 * b.size.z < 1.2 => {
                    tops.push((o.id.clone(), b.size))
                }
                "shelf" => insides.push((o.id.clone(), b.size)),
                "fridge" if !spec.joints.is_empty() => insides.push((o.id.clone(), b.size)),
                _ => {}
            }
        }
        if tops.is_empty() && insides.is_empty() {
            return;
        }
        let classes = [
            "cup",
            "bowl",
            "book",
            "bottle",
            "box",
            "cup",
            "book",
            "microwave",
        ];
        let mut tries = 0;
        while self.spec.objects.len() < target && tries < target * TRIES_PER_OBJECT {
            tries += 1;
            let class = *classes.choose(rng).unwrap_or(&"cup");
            if class == "microwave" && self.style != RoomStyle::Kitchen {
                continue;
            }
            let inside = !insides.is_empty() && (tops.is_empty() || rng.random_bool(0.3));
            let (parent, size) = if inside {
                insides.choose(rng)
            } else {
                tops.choose(rng)
            }
            .cloned()
            .unwrap_or_default();
            if inside && matches!(class, "microwave" | "bowl") {
                continue;
            }
            let Some(model) = self.pick_model(class, rng) else {
                continue;
            };
            let Some(dims) = self.source.model_source(&model).map(|s| s.nominal_size()) else {
                continue;
            };
            let reach = |extent: f32, own: f32| (0.5 * extent - 0.5 * own - EDGE_MARGIN).max(0.0);
            let (rx, ry) = (
                reach(size.x, dims.x.max(dims.y)),
                reach(size.y, dims.x.max(dims.y)),
            );
            let offset = [
                round_cm(rng.random_range(-rx..=rx)),
                round_cm(rng.random_range(-ry..=ry) * if inside { 0.3 } else { 1.0 }),
            ];
            let id = self.next_id(class);
            let mut object = object_spec(&id, class, Some(model), None);
            if inside {
                object.inside = Some(parent.clone());
            } else {
                object.on = Some(parent.clone());
            }
            object.offset = Some(offset);
            if class != "microwave" {
                let parent_yaw = world.object(&parent).map_or(0.0, |p| p.yaw.to_degrees());
                let yaw = (parent_yaw + rng.random_range(-40.0f32..40.0) + 180.0).rem_euclid(360.0)
                    - 180.0;
                object.yaw_deg = Some((yaw * 10.0).round() / 10.0);
            }
            if !self.try_add(object) {
                self.release_id(class);
            }
        }
    }

    /// Removes objects no frame of the default camera path sees (and what stands on them).
    pub(super) fn keep_visible(&mut self) {
        loop {
            let Some(world) = self.world() else {
                return;
            };
            let unseen = unseen_objects(&world, self.spec.camera.frames.unwrap_or(DEFAULT_FRAMES));
            let Some(&first) = unseen.first() else {
                return;
            };
            let id = world.objects[first].id.clone();
            let mut removed = vec![id];
            // Children of removed objects go too.
            loop {
                let before = removed.len();
                for o in &self.spec.objects {
                    let parent = o.on.as_deref().or(o.inside.as_deref());
                    if parent.is_some_and(|p| removed.iter().any(|r| r == p))
                        && !removed.contains(&o.id)
                    {
                        removed.push(o.id.clone());
                    }
                }
                if removed.len() == before {
                    break;
                }
            }
            self.spec.objects.retain(|o| !removed.contains(&o.id));
        }
    }

    pub(super) fn to_json(&self, options: &GenerateOptions) -> Value {
        let objects: Vec<Value> = self.spec.objects.iter().map(object_json).collect();
        let mut spec = json!({
            "name": self.spec.name,
            "seed": self.spec.seed,
            "room": {"size": numbers(&self.spec.room.size)},
            "objects": objects,
            "camera": {"frames": options.frames},
            "noise": options.noise.to_json(),
        });
        if !self.spec.cad.is_empty()
            && let Some(map) = spec.as_object_mut()
        {
            map.insert("cad".into(), json!(self.spec.cad));
        }
        spec
    }
}

fn round_cm(v: f32) -> f32 {
    (v * 100.0).round() / 100.0
}

fn object_spec(id: &str, class: &str, model: Option<String>, size: Option<[f32; 3]>) -> ObjectSpec {
    ObjectSpec {
        id: id.into(),
        class: class.into(),
        position: None,
        on: None,
        inside: None,
        offset: None,
        yaw_deg: None,
        size,
        model,
        joints: Default::default(),
    }
}

impl ObjectSpec {
    /// On the floor at `x`, `y` (centimetres), turned by `yaw_deg` (degrees, rounded to a tenth).
    fn at(mut self, x: f32, y: f32, yaw_deg: f32) -> Self {
        self.position = Some([round_cm(x), round_cm(y)]);
        let yaw = (yaw_deg * 10.0).round() / 10.0;
        self.yaw_deg = Some(if yaw <= -180.0 {
            yaw + 360.0
        } else if yaw > 180.0 {
            yaw - 360.0
        } else {
            yaw
        });
        self
    }
}
