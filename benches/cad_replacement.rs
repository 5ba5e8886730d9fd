//! CAD replacement of a 20-object scene against a 200-model database (issue 5's goal: under 2 s
//! on 2 cores). Setup, untimed: render the kitchen and the living room, map every third frame,
//! build their contact graphs, take 20 of their objects; the database is the parametric library
//! at several sizes per model (pre-processing it is timed on its own). Timed: ranking every
//! object's candidates, then aligning the best ten of each (and the ICP route of
//! `--align icp`: every model of the class by a yaw sweep and ICP); and, apart, the global physical
//! check of the kitchen's aligned candidates (choice, separation, snapping, verdicts). With the
//! Sweet Home 3D catalogues unpacked (scripts/setup-sh3d.sh), the same objects against the
//! imported models as well.

use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use iscene::cad::ParametricLibrary;
use iscene::cad::db::database::CadDatabase;
use iscene::cad::replace::matching::ObservedObject;
use iscene::cad::replace::observed_objects::observed_objects;
use iscene::cad::replace::replacement::{AlignMethod, align_scene, check_and_place, rank_scene};
use iscene::graph::ContactGraph;
use iscene::graph::build::{ContactGraphParams, build_contact_graph_with_surfaces};

const OBJECTS: usize = 20;
const DATABASE_MODELS: usize = 200;

/// A scene's contact graph and each node's observed surface points.
fn mapped_scene(scene: &str, dir: &Path) -> (ContactGraph, HashMap<String, Vec<Vec3>>) {
    let (found, meshes) = common::mapped_entities(scene, dir);
    let entities = common::graph_entities(&found, &meshes);
    let built =
        build_contact_graph_with_surfaces(&entities, &ContactGraphParams::for_voxel(0.02, false));
    let points = built
        .graph
        .nodes
        .iter()
        .map(|n| n.id.clone())
        .zip(built.surfaces)
        .collect();
    (built.graph, points)
}

/// The parametric library at sizes from 85% to 120% of nominal, until `count` models.
fn sized_library(count: usize) -> Vec<iscene::cad::CadModel> {
    let factors = [1.0f32, 0.85, 1.2, 0.92, 1.1, 0.8, 1.15];
    let entries = ParametricLibrary::entries();
    (0..count)
        .map(|i| {
            let entry = &entries[i % entries.len()];
            let k = i / entries.len();
            let f = factors[k % factors.len()];
            // Stretch width and depth unevenly so the variants differ in shape, not only size.
            let size = entry.nominal_size * Vec3::new(f, 2.0 - f, 1.0 + 0.5 * (f - 1.0));
            let mut model = entry.model_sized(size);
            model.id = format!("{}_v{k}", entry.id);
            model
        })
        .collect()
}

fn cad_replacement(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tempdir");
    let scenes: Vec<_> = ["kitchen", "living_room"]
        .iter()
        .map(|s| mapped_scene(s, dir.path()))
        .collect();
    let mut objects: Vec<ObservedObject> = scenes
        .iter()
        .flat_map(|(graph, points)| observed_objects(graph, points, &HashMap::new()))
        .collect();
    objects.truncate(OBJECTS);
    assert_eq!(objects.len(), OBJECTS, "two scenes have 20 objects");
    let start = Instant::now();
    let db = CadDatabase::from_models(sized_library(DATABASE_MODELS)).expect("database");
    eprintln!(
        "pre-processing {} models: {:.3} s",
        db.len(),
        start.elapsed().as_secs_f64()
    );
    // Ranking every object's candidates, then aligning the best ten of each (LM); or every model
    // of the class by ICP.
    let mut bench_against = |db: &CadDatabase, what: &str, method: AlignMethod| {
        let route = match method {
            AlignMethod::Lm => "",
            AlignMethod::Icp => "_icp",
        };
        let name = format!(
            "cad_replacement{route}_{}_objects_{}_{what}",
            objects.len(),
            db.len()
        );
        c.bench_function(&name, |b| {
            b.iter(|| {
                let ranked = rank_scene(&objects, db, method);
                align_scene(&objects, db, &ranked, method)
            })
        });
    };
    bench_against(&db, "models", AlignMethod::Lm);
    bench_against(&db, "models", AlignMethod::Icp);

    // The same objects against the imported Sweet Home 3D catalogues (scripts/setup-sh3d.sh),
    // when they are there: real meshes, as convex pieces, instead of generated boxes.
    let sh3d = Path::new(env!("CARGO_MANIFEST_DIR")).join(".sh3d/usr/share/sweethome3d");
    if sh3d.join("sweethome3d.jar").is_file() {
        let start = Instant::now();
        let db_dir = dir.path().join("sh3d_db");
        for source in [sh3d.join("furniture"), sh3d.join("sweethome3d.jar")] {
            iscene::cad::import::import_sh3d(&source, &db_dir).expect("import");
        }
        let imported = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let db = CadDatabase::from_folder(&db_dir).expect("imported database");
        eprintln!(
            "importing Sweet Home 3D: {imported:.1} s; reading and pre-processing its {} models: {:.3} s",
            db.len(),
            start.elapsed().as_secs_f64()
        );
        bench_against(&db, "sweet_home_3d_models", AlignMethod::Lm);
    } else {
        eprintln!("no Sweet Home 3D catalogues in .sh3d: run scripts/setup-sh3d.sh to bench them");
    }

    let (kitchen, points) = &scenes[0];
    let library = CadDatabase::parametric();
    let kitchen_objects = observed_objects(kitchen, points, &HashMap::new());
    let ranked = rank_scene(&kitchen_objects, &library, AlignMethod::Lm);
    let aligned = align_scene(&kitchen_objects, &library, &ranked, AlignMethod::Lm);
    let ids: Vec<String> = kitchen_objects.iter().map(|o| o.id.to_string()).collect();
    let name = format!("physical_check_kitchen_{}_objects", ids.len());
    c.bench_function(&name, |b| {
        b.iter(|| check_and_place(kitchen, &library, &ids, &aligned, points))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = cad_replacement
}
criterion_main!(benches);
