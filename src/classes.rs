//! The class table of assets/classes.json: kind, sizes, physical constants and label mappings per class.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// What role an entity of a class plays in the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EntityKind {
    /// Floor, walls, ceiling: the room itself.
    Layout,
    /// One rigid body.
    Rigid,
    /// Rigid parts joined by revolute or prismatic joints (doors, drawers).
    Articulated,
}

impl EntityKind {
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Layout => "layout",
            Self::Rigid => "rigid",
            Self::Articulated => "articulated",
        }
    }
}

/// One row of the class table.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClassInfo {
    pub kind: EntityKind,
    /// How many yaws about +z look the same: 1 (the front matters), 2 (a half turn: a
    /// rectangular table), 4 (a quarter turn), 0 (round: a cup, a bottle).
    pub yaw_symmetry: u32,
    /// Default full size in the canonical frame (x width, y depth, z height), metres.
    pub size: Vec3,
    pub size_min: Vec3,
    pub size_max: Vec3,
    /// Density of the solid in kg/m^3 (hollow furniture gets its mass from its shell mesh).
    pub density: f32,
    pub friction: f32,
    /// Movable objects get a floating joint to their support; the others a fixed one.
    pub movable: bool,
    pub coco: Vec<String>,
    pub voc: Vec<String>,
    /// Classes a segmenter confuses this one with (used by the oracle's noise model).
    pub confusable: Vec<String>,
    /// The front is one of the two long vertical faces (a microwave is always wider than deep):
    /// an object standing free, with no wall behind it, faces along its box's short axis.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub front_on_long_side: bool,
}

impl ClassInfo {
    /// The angle between two yaws (radians) up to the class's symmetry, in [0, pi].
    pub fn yaw_difference(&self, a: f32, b: f32) -> f32 {
        use std::f32::consts::TAU;
        if self.yaw_symmetry == 0 {
            return 0.0;
        }
        let period = TAU / self.yaw_symmetry as f32;
        let d = (a - b).rem_euclid(period);
        d.min(period - d)
    }
}

#[derive(Deserialize)]
struct ClassFile {
    #[serde(rename = "_doc")]
    _doc: String,
    classes: BTreeMap<String, ClassInfo>,
}

/// The class table, keyed by class name.
pub struct ClassTable {
    classes: BTreeMap<String, ClassInfo>,
}

const CLASS_TABLE_JSON: &str = include_str!("../assets/classes.json");

impl ClassTable {
    /// The table compiled in from assets/classes.json.
    pub fn builtin() -> &'static ClassTable {
        static TABLE: OnceLock<ClassTable> = OnceLock::new();
        TABLE.get_or_init(|| {
            // The file is part of the source tree and covered by tests, so a parse failure is a
            // build defect, not user input.
            #[expect(
                clippy::expect_used,
                reason = "compiled-in asset, checked by unit test"
            )]
            let file: ClassFile =
                serde_json::from_str(CLASS_TABLE_JSON).expect("assets/classes.json parses");
            ClassTable {
                classes: file.classes,
            }
        })
    }

    pub fn get(&self, class: &str) -> Option<&ClassInfo> {
        self.classes.get(class)
    }

    /// Whether `class` is room layout (floor, wall, ceiling); an unknown or missing class counts
    /// as layout, so nothing unknown is treated as an object that moves.
    pub fn is_layout(&self, class: Option<&str>) -> bool {
        class
            .and_then(|c| self.get(c))
            .is_none_or(|info| info.kind == EntityKind::Layout)
    }

    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.classes.keys().map(String::as_str)
    }

    pub fn iter(&self) -> impl Iterator<Item = (&str, &ClassInfo)> {
        self.classes.iter().map(|(k, v)| (k.as_str(), v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_differences_respect_the_class_symmetry() {
        use std::f32::consts::PI;
        let table = ClassTable::builtin();
        let chair = table.get("chair").expect("chair");
        let desk = table.get("table").expect("table");
        let cup = table.get("cup").expect("cup");
        assert!((chair.yaw_difference(0.1, 0.1 + PI) - PI).abs() < 1e-5);
        assert!((chair.yaw_difference(-3.0, 3.0) - (2.0 * PI - 6.0)).abs() < 1e-5);
        assert!(desk.yaw_difference(0.1, 0.1 + PI) < 1e-5);
        assert!((desk.yaw_difference(0.0, 0.5 * PI) - 0.5 * PI).abs() < 1e-5);
        assert_eq!(cup.yaw_difference(0.0, 2.0), 0.0);
    }

    #[test]
    fn every_design_class_is_in_the_table_and_consistent() {
        let table = ClassTable::builtin();
        for class in [
            "floor",
            "wall",
            "ceiling",
            "table",
            "chair",
            "sofa",
            "bed",
            "shelf",
            "monitor",
            "cup",
            "bottle",
            "book",
            "box",
            "bowl",
            "cabinet",
            "fridge",
            "microwave",
            "oven",
            "dishwasher",
        ] {
            let info = table
                .get(class)
                .unwrap_or_else(|| panic!("class {class} missing"));
            assert!(
                info.size_min.cmple(info.size).all() && info.size.cmple(info.size_max).all(),
                "{class} size range"
            );
            assert!(info.density > 0.0 && info.friction > 0.0, "{class} physics");
            for other in &info.confusable {
                assert!(
                    table.get(other).is_some(),
                    "{class} confusable with unknown {other}"
                );
            }
        }
    }
}
