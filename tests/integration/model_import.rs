//! Importing MJCF models (LIBERO's articulated objects in ../shared/data/cad/libero) and URDF
//! models (PyBullet's data, and an articulated one written here) into a CAD database with their
//! joints, and replacing the kitchen's articulated objects by LIBERO's (issue 5).

use std::path::{Path, PathBuf};

use crate::common;

use iscene::cad::CadModel;
use iscene::cad::db::database::CadDatabase;
use iscene::cad::db::load::read_database;
use iscene::classes::ClassTable;
use iscene::eval::evaluate_reconstruction;
use iscene::graph::ContactGraph;
use iscene::kinematics::JointKind;

fn libero() -> PathBuf {
    common::shared_data("cad/libero/articulated_objects")
}

/// `iscene cad import FORMAT SOURCE --into DB --scale S`; returns (exit code, stdout, stderr).
fn import_as(format: &str, source: &Path, db: &Path, scale: &str) -> (i32, String, String) {
    common::iscene(
        &[
            "cad",
            "import",
            format,
            source.to_str().expect("utf8"),
            "--into",
            db.to_str().expect("utf8"),
            "--scale",
            scale,
        ],
        &common::root(),
    )
}

fn run_import(source: &Path, db: &Path, scale: &str) -> (i32, String, String) {
    import_as("mjcf", source, db, scale)
}

/// The joints of a model's moving parts: (kind, lower, upper).
fn joints(model: &CadModel) -> Vec<(JointKind, f32, f32)> {
    model
        .movable_parts()
        .filter_map(|p| p.joint.limits.map(|(lo, hi)| (p.joint.kind, lo, hi)))
        .collect()
}

#[test]
fn libero_objects_import_with_their_joints_facing_front_at_furniture_size() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let db = tmp.path().join("db");
    let (code, stdout, stderr) = run_import(&libero(), &db, "class");
    assert_eq!(code, 0, "{stdout}{stderr}");
    eprint!("{stdout}");
    // Faucets, the basin faucet, the flat stove and the window name no class of the project.
    assert!(
        stdout.contains("imported 6 models from 10 files"),
        "{stdout}"
    );
    assert!(stdout.contains("4 of other kinds skipped"), "{stdout}");
    assert!(!stdout.contains("not imported"), "{stdout}");

    let models = read_database(&db).expect("the database reads back");
    let model = |id: &str| {
        models
            .iter()
            .find(|m| m.id == id)
            .unwrap_or_else(|| panic!("{id} imported"))
    };
    // The joints as the files give them; prismatic ranges scale with the model.
    let microwave = model("mjcf_microwave");
    assert_eq!(microwave.class, "microwave");
    let [(kind, lo, hi)] = joints(microwave)[..] else {
        panic!("one door: {:?}", joints(microwave))
    };
    assert!(kind == JointKind::Revolute && (lo + 2.094).abs() < 1e-4 && hi == 0.0);
    let fridge = model("mjcf_short_fridge");
    assert_eq!(fridge.class, "fridge");
    let [(kind, lo, hi)] = joints(fridge)[..] else {
        panic!("one door: {:?}", joints(fridge))
    };
    assert!(kind == JointKind::Revolute && lo == 0.0 && (hi - 2.7).abs() < 1e-4);
    for id in [
        "mjcf_short_cabinet",
        "mjcf_white_cabinet",
        "mjcf_wooden_cabinet",
    ] {
        let cabinet = model(id);
        assert_eq!(cabinet.class, "cabinet");
        let drawers = joints(cabinet);
        assert_eq!(drawers.len(), 3, "{id}: three drawers");
        assert!(drawers.iter().all(|j| j.0 == JointKind::Prismatic), "{id}");
    }
    let slide = model("mjcf_slide_cabinet");
    assert_eq!(joints(slide).len(), 1);
    assert_eq!(joints(slide)[0].0, JointKind::Prismatic);

    for m in &models {
        // At its class's size (uniformly: the proportions are the file's), standing on z = 0,
        // centred, its size that of its closed mesh.
        let typical = ClassTable::builtin().get(&m.class).expect("class").size;
        let ratio = typical / m.size;
        let mean = (ratio.x * ratio.y * ratio.z).cbrt();
        assert!((mean - 1.0).abs() < 1e-3, "{}: {ratio}", m.id);
        let (min, max) = m.merged_mesh(&[]).bounds().expect("mesh");
        assert!(
            (max - min - m.size).abs().max_element() < 1e-4
                && min.z.abs() < 1e-4
                && (min.x + max.x).abs() < 1e-4
                && (min.y + max.y).abs() < 1e-4,
            "{}: {min} {max} {}",
            m.id,
            m.size
        );
        // Every part keeps the file's visual meshes beside its collision pieces, in the same
        // frame: closed, they cover about the same box (LIBERO's visuals are finer, not
        // elsewhere; a part's alone may differ, a fridge's frame reaching around its door).
        let mut visual = iscene::geometry::TriMesh::default();
        for (part, pose) in m.parts.iter().zip(m.model_from_parts(&[])) {
            let mesh = part
                .visual
                .as_ref()
                .unwrap_or_else(|| panic!("{} {}: no visual mesh", m.id, part.name));
            visual.append(&mesh.transformed(&pose));
        }
        let (vmin, vmax) = visual.bounds().expect("visual");
        let slack = 0.1 * m.size.max_element();
        assert!(
            (vmin - min).abs().max_element() < slack && (vmax - max).abs().max_element() < slack,
            "{}: visual {vmin} {vmax}, collision {min} {max}",
            m.id
        );
        // Doors and drawers open out of the front (-y): opened to the end of their range
        // farthest from zero, each reaches out in front of the closed model. The slide
        // cabinet's door slides sideways across its front instead.
        for part in m.movable_parts() {
            let (lo, hi) = part.joint.limits.expect("limits");
            let open = if lo.abs() > hi.abs() { lo } else { hi };
            let opened = m.merged_mesh(&[(part.name.clone(), open)]);
            let (omin, omax) = opened.bounds().expect("opened");
            if m.id == "mjcf_slide_cabinet" {
                assert!(omax.x > max.x + 0.1 * m.size.x, "{}: {omax}", m.id);
            } else {
                assert!(
                    omin.y < min.y - 0.15 * m.size.y,
                    "{} {}: opened to {open} reaches {omin}, the front is at {}",
                    m.id,
                    part.name,
                    min.y
                );
            }
        }
    }

    // `--scale 1` keeps the file's metres: LIBERO's fridge is a tabletop toy.
    let toy = tmp.path().join("toy");
    let fridge_file = libero().join("short_fridge.xml");
    let (code, stdout, stderr) = run_import(&fridge_file, &toy, "1");
    assert_eq!(code, 0, "{stdout}{stderr}");
    let toy_fridge = read_database(&toy).expect("reads").remove(0);
    assert!(toy_fridge.size.max_element() < 0.3, "{}", toy_fridge.size);
    assert!(
        (toy_fridge.size * (fridge.size.x / toy_fridge.size.x) - fridge.size)
            .abs()
            .max_element()
            < 1e-3,
        "the same shape: {} {}",
        toy_fridge.size,
        fridge.size
    );
}

#[test]
fn a_malformed_mjcf_file_is_refused_with_its_name_and_line() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let cases = [
        ("not_xml.xml", "<mujoco><worldbody>", "not XML"),
        (
            "bad_number.xml",
            "<mujoco>\n<worldbody>\n<body name=\"b\" pos=\"0 0 zero\">\n<geom type=\"box\" size=\"1 1 1\"/>\n</body>\n</worldbody>\n</mujoco>",
            "line 3",
        ),
        (
            "missing_mesh.xml",
            "<mujoco><asset><mesh name=\"m\" file=\"nowhere.stl\"/></asset><worldbody><body name=\"cabinet\"><geom type=\"mesh\" mesh=\"m\"/></body></worldbody></mujoco>",
            "nowhere.stl",
        ),
        ("not_mujoco.xml", "<robot name=\"r\"/>", "<mujoco>"),
    ];
    for (file, text, problem) in cases {
        let path = tmp.path().join(file);
        std::fs::write(&path, text).expect("write");
        let db = tmp.path().join(format!("db_{file}"));
        let (code, stdout, stderr) = run_import(&path, &db, "class");
        assert_eq!(code, 2, "{file}: {stdout}{stderr}");
        assert!(
            stderr.contains(file) && stderr.contains(problem),
            "{file}: {stderr}"
        );
        assert!(!db.exists(), "{file}: nothing written");
    }
}

/// The kitchen reconstructed (every second frame, realistic noise) with the imported Sweet
/// Home 3D models and the LIBERO objects: its fridge, cabinets and microwave become LIBERO's
/// articulated models (Sweet Home 3D's are rigid), every object still gets a model of its class,
/// and the models interpenetrate by at most 1 cm.
#[test]
fn articulated_objects_get_articulated_models() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let db = tmp.path().join("db");
    copy_folder(&crate::cad_import::imported_database(), &db);
    let (code, stdout, stderr) = run_import(&libero(), &db, "class");
    assert_eq!(code, 0, "{stdout}{stderr}");

    let (seq, _) = common::shared_noisy_map("kitchen");
    let out = tmp.path().join("kitchen");
    common::map_every_second_frame(&seq, &out, Some(db.clone()));
    let graph = ContactGraph::load(&out.join("contact_graph.json")).expect("graph");
    let scene_db = CadDatabase::for_scene(&out).expect("the scene's models");
    let mut articulated = 0;
    for node in &graph.nodes {
        let Some(cad) = &node.cad else { continue };
        let model = &scene_db.get(&cad.model).expect("copied").model;
        eprintln!("{} ({}): {}", node.id, node.class, model.id);
        if ["fridge", "cabinet", "microwave"].contains(&node.class.as_str()) {
            // LIBERO's, or one built from the parts perceived on it where no LIBERO model's
            // handle is where the camera saw one (issue 36): articulated either way.
            assert!(
                model.is_articulated()
                    && (model.id.starts_with("mjcf_") || model.id.starts_with("perceived_")),
                "{} has {}",
                node.id,
                model.id
            );
            articulated += 1;
        }
    }
    assert!(articulated >= 3, "{articulated} articulated objects");
    // The exported URDF draws the fridge with LIBERO's visual mesh, not its collision boxes.
    let fridge = graph.node("fridge_1").expect("the fridge");
    let model = &scene_db
        .get(&fridge.cad.as_ref().expect("replaced").model)
        .expect("copied")
        .model;
    let visual_obj = std::fs::read_to_string(out.join("meshes").join("fridge_1.obj"))
        .expect("the fridge's visual mesh");
    let faces = visual_obj.lines().filter(|l| l.starts_with("f ")).count();
    let expected = model.parts[0]
        .visual
        .as_ref()
        .expect("visual")
        .triangles
        .len();
    assert_eq!(faces, expected);
    assert_ne!(faces, model.parts[0].mesh.triangles.len());
    let eval = evaluate_reconstruction(&out, &seq).expect("eval");
    let cad = eval.cad.expect("CAD metrics");
    let right = cad.objects.iter().filter(|o| o.class_correct).count();
    eprintln!(
        "class right {right} of {}; mean AE {:?}; deepest penetration {:?}",
        cad.objects.len(),
        cad.mean_alignment_error_m,
        cad.max_penetration_m
    );
    assert!(right * 100 >= cad.objects.len() * 95);
    assert!(cad.max_penetration_m.is_some_and(|d| d <= 0.01));
    assert_eq!(
        cad.supports_passing, cad.supports_tested,
        "every support holds"
    );
}

/// PyBullet's data folder (the validators' virtual environment has PyBullet).
fn pybullet_data() -> PathBuf {
    let lib = common::validator(".venv-validators/lib");
    std::fs::read_dir(&lib)
        .expect("lib")
        .filter_map(Result::ok)
        .map(|e| e.path().join("site-packages/pybullet_data"))
        .find(|p| p.is_dir())
        .unwrap_or_else(|| panic!("no pybullet_data under {}", lib.display()))
}

/// A cabinet whose door hangs on a revolute joint, in URDF: the carcass's back and sides are
/// collision boxes, the door one more, and legs only visual.
const CABINET_URDF: &str = r#"<robot name="bathroom_cabinet">
  <material name="oak"><color rgba="0.6 0.4 0.2 1"/></material>
  <link name="carcass">
    <collision><origin xyz="0 0.19 0.5"/><geometry><box size="0.6 0.02 0.6"/></geometry></collision>
    <collision><origin xyz="-0.29 0 0.5"/><geometry><box size="0.02 0.4 0.6"/></geometry></collision>
    <collision><origin xyz="0.29 0 0.5"/><geometry><box size="0.02 0.4 0.6"/></geometry></collision>
    <collision><origin xyz="0 0 0.21"/><geometry><box size="0.6 0.4 0.02"/></geometry></collision>
    <collision><origin xyz="0 0 0.79"/><geometry><box size="0.6 0.4 0.02"/></geometry></collision>
    <visual><origin xyz="0 0 0.5"/><geometry><box size="0.6 0.4 0.6"/></geometry><material name="oak"/></visual>
    <visual><origin xyz="-0.27 -0.17 0.1"/><geometry><cylinder radius="0.02" length="0.2"/></geometry></visual>
    <visual><origin xyz="0.27 -0.17 0.1"/><geometry><cylinder radius="0.02" length="0.2"/></geometry></visual>
    <visual><origin xyz="-0.27 0.17 0.1"/><geometry><cylinder radius="0.02" length="0.2"/></geometry></visual>
    <visual><origin xyz="0.27 0.17 0.1"/><geometry><cylinder radius="0.02" length="0.2"/></geometry></visual>
  </link>
  <link name="door">
    <collision><origin xyz="0.3 -0.01 0"/><geometry><box size="0.6 0.02 0.6"/></geometry></collision>
    <visual><origin xyz="0.3 -0.01 0"/><geometry><box size="0.6 0.02 0.6"/></geometry><material name="oak"/></visual>
  </link>
  <joint name="door_hinge" type="revolute">
    <parent link="carcass"/><child link="door"/>
    <origin xyz="-0.3 -0.2 0.5" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-1.9" upper="0" effort="10" velocity="1"/>
  </joint>
</robot>
"#;

#[test]
fn urdf_models_import_at_their_real_size_with_their_joints() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let db = tmp.path().join("db");
    let data = pybullet_data();
    // PyBullet's table gives only its top a collision box: its legs come from its visuals.
    for file in ["table/table.urdf", "objects/mug.urdf"] {
        let (code, stdout, stderr) = import_as("urdf", &data.join(file), &db, "1");
        assert_eq!(code, 0, "{file}: {stdout}{stderr}");
    }
    let cabinet_file = tmp.path().join("bathroom_cabinet.urdf");
    std::fs::write(&cabinet_file, CABINET_URDF).expect("write");
    // URDF is imported at its own size unless told otherwise.
    let (code, stdout, stderr) = common::iscene(
        &[
            "cad",
            "import",
            "urdf",
            cabinet_file.to_str().expect("utf8"),
            "--into",
            db.to_str().expect("utf8"),
        ],
        &common::root(),
    );
    assert_eq!(code, 0, "{stdout}{stderr}");
    let models = read_database(&db).expect("reads back");
    let model = |id: &str| {
        models.iter().find(|m| m.id == id).unwrap_or_else(|| {
            panic!(
                "{id} among {:?}",
                models.iter().map(|m| &m.id).collect::<Vec<_>>()
            )
        })
    };
    let table = model("urdf_table");
    assert_eq!(table.class, "table");
    // The top is 1.5 x 1 m at 0.6 m +- 2.5 cm; the legs reach the floor.
    assert!(
        (table.size - glam::Vec3::new(1.5, 1.0, 0.625))
            .abs()
            .max_element()
            < 0.01,
        "{}",
        table.size
    );
    let mug = model("urdf_mug");
    assert_eq!(mug.class, "cup");
    assert!(mug.size.max_element() < 0.2, "{}", mug.size);

    let cabinet = model("urdf_bathroom_cabinet");
    assert_eq!(cabinet.class, "cabinet");
    assert!(
        (cabinet.size - glam::Vec3::new(0.6, 0.42, 0.8))
            .abs()
            .max_element()
            < 0.01,
        "legs and door inside the size: {}",
        cabinet.size
    );
    let [(kind, lo, hi)] = joints(cabinet)[..] else {
        panic!("one door: {:?}", joints(cabinet))
    };
    assert!(kind == JointKind::Revolute && (lo + 1.9).abs() < 1e-5 && hi == 0.0);
    let door = &cabinet.parts[1];
    assert_eq!(door.name, "door");
    assert!((door.color[0] - 0.6).abs() < 1e-4, "{:?}", door.color);
    // Opened, the door swings out in front.
    let (min, _) = cabinet.merged_mesh(&[]).bounds().expect("closed");
    let (omin, _) = cabinet
        .merged_mesh(&[("door".into(), -1.5)])
        .bounds()
        .expect("open");
    assert!(omin.y < min.y - 0.4, "{omin} {min}");

    // A broken URDF is refused with its name; a joint type the importer does not model is
    // reported and the rest imported.
    let broken = tmp.path().join("broken_table.urdf");
    std::fs::write(&broken, "<robot name=\"t\"><link name=\"a\"><collision><geometry><box size=\"1 x 1\"/></geometry></collision></link></robot>").expect("write");
    let fresh = tmp.path().join("fresh");
    let (code, _, stderr) = import_as("urdf", &broken, &fresh, "1");
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("broken_table.urdf"), "{stderr}");
    assert!(!fresh.exists());
    let ball = tmp.path().join("ball_table.urdf");
    std::fs::write(
        &ball,
        CABINET_URDF.replace("type=\"revolute\"", "type=\"spherical\""),
    )
    .expect("write");
    let (code, stdout, stderr) = import_as("urdf", &ball, &fresh, "1");
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("not imported") && stdout.contains("Spherical"),
        "{stdout}"
    );
}

fn copy_folder(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("create");
    for entry in std::fs::read_dir(from)
        .expect("read")
        .filter_map(Result::ok)
    {
        std::fs::copy(entry.path(), to.join(entry.file_name())).expect("copy");
    }
}

/// A model split the way MuJoCo collections publish them: the main file includes a
/// `<mujocoinclude>` of defaults and one of the body tree (with a `childclass`), from a
/// subfolder. The folder import reads the model through its includes and passes over the
/// include files; an include that leaves the model's folder is refused.
#[test]
fn mjcf_includes_are_spliced_in_and_include_files_passed_over() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let src = tmp.path().join("models");
    std::fs::create_dir_all(src.join("parts")).expect("mkdir");
    std::fs::write(
        src.join("parts/defaults.xml"),
        r#"<mujocoinclude>
  <default>
    <default class="panel"><geom type="box" rgba="0.8 0.6 0.4 1"/></default>
    <default class="hinge"><joint type="hinge" axis="0 0 1" range="0 1.6"/></default>
  </default>
</mujocoinclude>"#,
    )
    .expect("write");
    std::fs::write(
        src.join("parts/body.xml"),
        r#"<mujocoinclude>
  <body name="cabinet" childclass="panel">
    <geom size="0.3 0.25 0.02" pos="0 0 0.02"/>
    <geom size="0.3 0.25 0.02" pos="0 0 0.78"/>
    <geom size="0.02 0.25 0.4" pos="-0.28 0 0.4"/>
    <geom size="0.02 0.25 0.4" pos="0.28 0 0.4"/>
    <geom size="0.3 0.02 0.4" pos="0 0.23 0.4"/>
    <body name="door" pos="-0.3 -0.27 0.4">
      <joint name="door_hinge" class="hinge"/>
      <geom size="0.3 0.02 0.38" pos="0.3 0 0"/>
    </body>
  </body>
</mujocoinclude>"#,
    )
    .expect("write");
    std::fs::write(
        src.join("cabinet.xml"),
        r#"<mujoco model="cabinet">
  <include file="parts/defaults.xml"/>
  <worldbody>
    <include file="parts/body.xml"/>
  </worldbody>
</mujoco>"#,
    )
    .expect("write");
    // The include files sit in a subfolder: import the folder with them beside the model too.
    std::fs::copy(src.join("parts/defaults.xml"), src.join("defaults.xml")).expect("copy");
    let db = tmp.path().join("db");
    let (code, stdout, stderr) = run_import(&src, &db, "class");
    assert_eq!(code, 0, "{stdout}{stderr}");
    assert!(stdout.contains("imported 1 models"), "{stdout}");
    assert!(!stdout.contains("not imported"), "{stdout}");
    let models = read_database(&db).expect("database");
    assert_eq!(models.len(), 1);
    let kinds: Vec<JointKind> = joints(&models[0]).iter().map(|j| j.0).collect();
    assert_eq!(kinds, [JointKind::Revolute], "the included door's hinge");

    std::fs::write(
        src.join("escape.xml"),
        r#"<mujoco model="cabinet"><include file="../outside.xml"/><worldbody/></mujoco>"#,
    )
    .expect("write");
    std::fs::write(tmp.path().join("outside.xml"), "<mujocoinclude/>").expect("write");
    let db2 = tmp.path().join("db2");
    let (code, _, stderr) = run_import(&src.join("escape.xml"), &db2, "class");
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("escape.xml") && stderr.contains("outside.xml"),
        "{stderr}"
    );
    assert!(!db2.exists());
}
