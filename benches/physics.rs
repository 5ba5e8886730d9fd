//! Physics validation of a 50-object scene (issue 6's goal: 2 s simulated in under 1 s on 2
//! cores): ten library tables on a floor, four library cups on each, every object a dynamic
//! rapier body with its compound convex collider, rested for 2 s at 1/120 s with 4 substeps.
//! The verdicts are printed once before timing: a scene that falls apart is not a benchmark.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Affine3A, Vec3};
use iscene::cad::ParametricLibrary;
use iscene::geometry::TriMesh;
use iscene::kinematics::JointSpec;
use iscene::kinematics::tree::{KinematicTree, TreeLink};
use iscene::systems::physics_validation::validate_physics;

/// A library model's mesh at closed joints, with its bottom at z = 0.
fn standing_mesh(class: &str) -> TriMesh {
    let entry = ParametricLibrary::variants(class)
        .next()
        .unwrap_or_else(|| panic!("no {class} in the library"));
    let mesh = entry.model().merged_mesh(&[]);
    let (lo, _) = mesh.bounds().expect("a mesh");
    mesh.transformed(&Affine3A::from_translation(Vec3::new(0.0, 0.0, -lo.z)))
}

fn fifty_object_scene() -> KinematicTree {
    let table = standing_mesh("table");
    let cup = standing_mesh("cup");
    let top = table.bounds().expect("table").1.z;
    let mut links = vec![
        TreeLink::root(),
        TreeLink::body(
            "floor",
            "floor",
            0,
            JointSpec::FIXED,
            Affine3A::IDENTITY,
            TriMesh::cuboid(Vec3::new(-1.5, -1.5, -0.1), Vec3::new(11.5, 5.5, 0.0)),
        ),
    ];
    for t in 0..10 {
        let at = Vec3::new(2.2 * (t % 5) as f32, 2.5 * (t / 5) as f32, 0.0);
        let table_link = links.len();
        links.push(TreeLink::body(
            &format!("table_{}", t + 1),
            "table",
            1,
            JointSpec::FIXED,
            Affine3A::from_translation(at),
            table.clone(),
        ));
        for (c, (dx, dy)) in [(-0.3, -0.15), (0.3, -0.15), (-0.3, 0.15), (0.3, 0.15)]
            .into_iter()
            .enumerate()
        {
            links.push(TreeLink::body(
                &format!("cup_{}", 4 * t + c + 1),
                "cup",
                table_link,
                JointSpec::FLOATING,
                Affine3A::from_translation(Vec3::new(dx, dy, top)),
                cup.clone(),
            ));
        }
    }
    KinematicTree { links }
}

fn physics(c: &mut Criterion) {
    let tree = fifty_object_scene();
    tree.check().expect("a valid tree");
    let report = validate_physics(&tree);
    eprintln!(
        "{} objects, stable {:.3}, rest simulation {:.3} s wall",
        report.objects.len(),
        report.stable_fraction,
        report.rest_wall_s
    );
    let mut group = c.benchmark_group("physics");
    group.sample_size(10);
    group.bench_function("validate_50_objects_2s", |b| {
        b.iter(|| validate_physics(&tree))
    });
    group.finish();
}

criterion_group!(benches, physics);
criterion_main!(benches);
