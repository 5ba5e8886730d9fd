//! The catalogue of parametric models: ids, classes, nominal sizes and their generators.

pub mod appliances;
pub mod builder;
pub mod perceived;
pub mod seating;
pub mod storage;
pub mod tables;
pub mod tabletop;

use glam::Vec3;

use crate::cad::model::CadModel;

/// Builds a model with the given id at the given overall size (metres, canonical frame).
pub type ModelBuilder = fn(&str, Vec3) -> CadModel;

/// One catalogue entry.
#[derive(Clone, Copy)]
pub struct LibraryEntry {
    pub id: &'static str,
    pub class: &'static str,
    /// The size the model is exported at and used with when a scene gives none.
    pub nominal_size: Vec3,
    pub build: ModelBuilder,
}

impl LibraryEntry {
    pub fn model(&self) -> CadModel {
        (self.build)(self.id, self.nominal_size)
    }

    /// The model scaled by construction (boards keep their thickness) to `size`. A size other
    /// than the nominal one gives a model of its own, so its id says the size
    /// ([`sized_model_id`]): a scene folder that records it (`gt/cad`) never stands for the
    /// nominal model of the same name.
    pub fn model_sized(&self, size: Vec3) -> CadModel {
        let differs = (size - self.nominal_size).abs().max_element() > SIZE_TOLERANCE;
        let id = if differs {
            sized_model_id(self.id, size)
        } else {
            self.id.to_string()
        };
        (self.build)(&id, size)
    }
}

/// Sizes closer than this to the nominal one build the nominal model.
const SIZE_TOLERANCE: f32 = 5e-4;

/// The id of library model `base` built to `size`: `table_01.1100x570x500` (millimetres).
pub fn sized_model_id(base: &str, size: Vec3) -> String {
    let mm = |v: f32| (v * 1000.0).round() as i64;
    format!("{base}.{}x{}x{}", mm(size.x), mm(size.y), mm(size.z))
}

/// The library model a model id was built from: `table_01` for `table_01.1100x570x500`, the id
/// itself otherwise.
pub fn library_model_id(id: &str) -> &str {
    match id.rsplit_once('.') {
        Some((base, suffix))
            if suffix.split('x').count() == 3
                && suffix
                    .split('x')
                    .all(|n| !n.is_empty() && n.chars().all(|c| c.is_ascii_digit())) =>
        {
            base
        }
        _ => id,
    }
}

/// The model a sized id names, built by its library entry: `table_01.1100x570x500` is `table_01`
/// built to 1.1 x 0.57 x 0.5 m. `None` for any other id.
pub fn build_sized_model(id: &str) -> Option<CadModel> {
    let base = library_model_id(id);
    let entry = ParametricLibrary::get(base)?;
    let mm: Vec<f32> = id
        .get(base.len() + 1..)?
        .split('x')
        .map(|n| n.parse::<u32>().ok().map(|v| v as f32 / 1000.0))
        .collect::<Option<_>>()?;
    let size = Vec3::new(*mm.first()?, *mm.get(1)?, *mm.get(2)?);
    (size.min_element() > 0.0).then(|| entry.model_sized(size))
}

const fn entry(
    id: &'static str,
    class: &'static str,
    size: [f32; 3],
    build: ModelBuilder,
) -> LibraryEntry {
    LibraryEntry {
        id,
        class,
        nominal_size: Vec3::new(size[0], size[1], size[2]),
        build,
    }
}

const ENTRIES: &[LibraryEntry] = &[
    entry(
        "chair_01",
        "chair",
        [0.45, 0.48, 0.9],
        seating::chair_classic,
    ),
    entry("chair_02", "chair", [0.7, 0.7, 0.85], seating::chair_arm),
    entry("chair_03", "chair", [0.4, 0.4, 0.75], seating::chair_stool),
    entry(
        "chair_04",
        "chair",
        [0.62, 0.62, 1.05],
        seating::chair_office,
    ),
    entry(
        "chair_05",
        "chair",
        [0.44, 0.44, 0.95],
        seating::chair_ladder,
    ),
    entry("sofa_01", "sofa", [2.0, 0.9, 0.85], seating::sofa_box),
    entry("sofa_02", "sofa", [1.7, 0.85, 0.8], seating::sofa_legs),
    entry("bed_01", "bed", [1.6, 2.1, 1.0], seating::bed_headboard),
    entry("bed_02", "bed", [1.0, 2.05, 0.9], seating::bed_legs),
    entry("table_01", "table", [1.4, 0.8, 0.75], tables::table_legs),
    entry(
        "table_02",
        "table",
        [0.9, 0.9, 0.74],
        tables::table_pedestal,
    ),
    entry("table_03", "table", [1.8, 0.9, 0.76], tables::table_trestle),
    entry("table_04", "table", [1.2, 0.6, 0.73], tables::table_desk),
    entry("shelf_01", "shelf", [0.8, 0.3, 1.8], tables::shelf_bookcase),
    entry("shelf_02", "shelf", [0.9, 0.4, 1.5], tables::shelf_rack),
    entry(
        "cabinet_01",
        "cabinet",
        [0.8, 0.58, 0.88],
        storage::cabinet_two_doors,
    ),
    entry(
        "cabinet_02",
        "cabinet",
        [0.6, 0.5, 0.85],
        storage::cabinet_drawers,
    ),
    entry(
        "cabinet_03",
        "cabinet",
        [0.5, 0.58, 0.88],
        storage::cabinet_drawer_door,
    ),
    entry(
        "cabinet_04",
        "cabinet",
        [0.6, 0.35, 0.7],
        storage::cabinet_wall,
    ),
    entry(
        "fridge_01",
        "fridge",
        [0.6, 0.65, 1.5],
        appliances::fridge_single,
    ),
    entry(
        "fridge_02",
        "fridge",
        [0.7, 0.7, 1.85],
        appliances::fridge_freezer,
    ),
    entry(
        "microwave_01",
        "microwave",
        [0.5, 0.38, 0.3],
        appliances::microwave_full_door,
    ),
    entry(
        "microwave_02",
        "microwave",
        [0.48, 0.36, 0.28],
        appliances::microwave_panel,
    ),
    entry(
        "oven_01",
        "oven",
        [0.6, 0.58, 0.6],
        appliances::oven_builtin,
    ),
    entry("oven_02", "oven", [0.6, 0.6, 0.9], appliances::oven_range),
    entry(
        "dishwasher_01",
        "dishwasher",
        [0.6, 0.6, 0.85],
        appliances::dishwasher_rack,
    ),
    entry(
        "dishwasher_02",
        "dishwasher",
        [0.6, 0.58, 0.82],
        appliances::dishwasher_panel,
    ),
    entry(
        "monitor_01",
        "monitor",
        [0.55, 0.2, 0.45],
        tabletop::monitor_stand,
    ),
    entry(
        "monitor_02",
        "monitor",
        [0.6, 0.18, 0.42],
        tabletop::monitor_round_foot,
    ),
    entry("cup_01", "cup", [0.11, 0.08, 0.1], tabletop::cup_mug),
    entry("cup_02", "cup", [0.075, 0.075, 0.12], tabletop::cup_tumbler),
    entry(
        "bottle_01",
        "bottle",
        [0.075, 0.075, 0.3],
        tabletop::bottle_wine,
    ),
    entry(
        "bottle_02",
        "bottle",
        [0.065, 0.065, 0.22],
        tabletop::bottle_water,
    ),
    entry(
        "book_01",
        "book",
        [0.17, 0.24, 0.03],
        tabletop::book_hardback,
    ),
    entry(
        "book_02",
        "book",
        [0.13, 0.2, 0.02],
        tabletop::book_paperback,
    ),
    entry("box_01", "box", [0.3, 0.25, 0.2], tabletop::box_carton),
    entry("box_02", "box", [0.4, 0.3, 0.25], tabletop::box_lidded),
    entry("bowl_01", "bowl", [0.15, 0.15, 0.08], tabletop::bowl_deep),
    entry(
        "bowl_02",
        "bowl",
        [0.26, 0.26, 0.07],
        tabletop::bowl_shallow,
    ),
];

/// The parametric library: every class of the class table that is not layout has variants here.
pub struct ParametricLibrary;

impl ParametricLibrary {
    pub fn entries() -> &'static [LibraryEntry] {
        ENTRIES
    }

    pub fn get(id: &str) -> Option<&'static LibraryEntry> {
        ENTRIES.iter().find(|e| e.id == id)
    }

    pub fn variants(class: &str) -> impl Iterator<Item = &'static LibraryEntry> + '_ {
        ENTRIES.iter().filter(move |e| e.class == class)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::JointKind;
    use crate::classes::{ClassTable, EntityKind};

    #[test]
    fn a_model_built_to_another_size_says_so_in_its_id() {
        let table = ParametricLibrary::get("table_01").expect("table_01");
        assert_eq!(table.model_sized(table.nominal_size).id, "table_01");
        let low = table.model_sized(Vec3::new(1.1, 0.57, 0.5));
        assert_eq!(low.id, "table_01.1100x570x500");
        assert!(crate::file_name::check_file_name(&low.id).is_ok());
        assert_eq!(library_model_id(&low.id), "table_01");
        assert_eq!(build_sized_model(&low.id), Some(low.clone()));
        for other in ["table_01", "table_99.1x2x3", "table_01.0x570x500", "lib.v2"] {
            assert!(build_sized_model(other).is_none(), "{other}");
        }
        for plain in ["table_01", "lib.v2", "a.1x2", "a.1x2xz", "a.x1x2"] {
            assert_eq!(library_model_id(plain), plain);
        }
    }

    #[test]
    fn every_object_class_has_variants_and_articulated_classes_move() {
        let table = ClassTable::builtin();
        for (class, info) in table.iter() {
            let count = ParametricLibrary::variants(class).count();
            match info.kind {
                EntityKind::Layout => assert_eq!(count, 0, "{class}"),
                // Counters are found from geometry and stand as their boxes: no model.
                _ if class == crate::graph::build::COUNTER_CLASS => assert_eq!(count, 0),
                _ => assert!(count >= 2, "{class} has {count} variants"),
            }
            for e in ParametricLibrary::variants(class) {
                let m = e.model();
                assert_eq!(
                    m.is_articulated(),
                    info.kind == EntityKind::Articulated,
                    "{}",
                    e.id
                );
            }
        }
        assert!(ParametricLibrary::variants("chair").count() >= 5);
        assert!(ParametricLibrary::variants("table").count() >= 4);
        assert!(ParametricLibrary::variants("cabinet").count() >= 3);
    }

    #[test]
    fn models_are_canonical_closed_and_near_their_nominal_size() {
        for e in ParametricLibrary::entries() {
            let m = e.model();
            let (lo, hi) = m.merged_mesh(&[]).bounds().expect("mesh");
            assert!(lo.z.abs() < 1e-5, "{}: bottom at {}", e.id, lo.z);
            assert!(
                (lo.x + hi.x).abs() < 1e-4 && (lo.y + hi.y).abs() < 1e-4,
                "{}: not centred",
                e.id
            );
            let err = (m.size - e.nominal_size).abs();
            // Handles stand out of fronts; everything else is built to size.
            assert!(
                err.max_element() < 0.06,
                "{}: size {} vs nominal {}",
                e.id,
                m.size,
                e.nominal_size
            );
            for part in &m.parts {
                assert!(
                    part.mesh.signed_volume() > 0.0,
                    "{}/{}: mesh not closed outward",
                    e.id,
                    part.name
                );
            }
            let mut names: Vec<_> = m.parts.iter().map(|p| p.name.as_str()).collect();
            names.sort_unstable();
            names.dedup();
            assert_eq!(names.len(), m.parts.len(), "{}: duplicate part names", e.id);
        }
    }

    #[test]
    fn opening_a_door_or_drawer_moves_it_out_of_the_front() {
        for e in ParametricLibrary::entries() {
            let m = e.model();
            for (i, part) in m.parts.iter().enumerate() {
                let Some((_, upper)) = part.joint.limits else {
                    continue;
                };
                let closed = m.model_from_parts(&[]);
                let open = m.model_from_parts(&[(part.name.clone(), upper)]);
                let centroid = |pose: glam::Affine3A| {
                    let mesh = part.mesh.transformed(&pose);
                    mesh.positions.iter().copied().sum::<Vec3>() / mesh.positions.len() as f32
                };
                let moved = centroid(open[i]) - centroid(closed[i]);
                assert!(
                    moved.y < -0.05,
                    "{}/{}: opening moves the part by {moved}, not out of the front",
                    e.id,
                    part.name
                );
                let kind = part.joint.kind;
                assert!(
                    matches!(kind, JointKind::Revolute | JointKind::Prismatic),
                    "{}/{}",
                    e.id,
                    part.name
                );
            }
        }
    }
}
