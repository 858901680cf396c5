//! AO field files through Bevy's asset server, and the `ao_bake` example as scripts call it.

use std::path::Path;
use std::process::Command;

use bevy::asset::LoadState;
use bevy::math::Affine3A;
use bevy::prelude::*;
use bevy_dynamic_ao::FieldShading;
use bevy_dynamic_ao::fields::join::{ProxyJoin, field_joins, object_bounds};
use bevy_dynamic_ao::fields::{AoFieldCache, AoFieldData, BakeSettings, bake};
use bevy_dynamic_ao::geometry::triangles::TriangleScene;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::fields::field_occlusion;

use crate::examples::example_binary;
use crate::far_scenes::placed_fields;
use crate::harness::{Gpu, difference_stats, gpu_turn, plain_ao};
use crate::log_capture::assert_logged_once;
use crate::scenes;

fn small_field() -> AoFieldData {
    let mut scene = TriangleScene::default();
    scene.add_mesh(&Cuboid::new(1.0, 1.0, 1.0).into(), Affine3A::IDENTITY);
    let settings = BakeSettings {
        resolution: 4,
        rays: 32,
        ..default()
    };
    bake(scene.triangles, &settings, &|_, _| {}).expect("a cube bakes")
}

#[test]
fn aofield_files_load_or_fail_with_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("dynamic_ao_fields_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let field = small_field();
    let good = field.to_bytes();
    let mut corrupt = good.clone();
    corrupt[100] ^= 0x10;
    let mut wrong_version = good.clone();
    wrong_version[8] = 9;
    let files: [(&str, Vec<u8>, Option<&str>); 5] = [
        ("good.aofield", good.clone(), None),
        ("corrupt.aofield", corrupt, Some("checksum")),
        (
            "truncated.aofield",
            good[..good.len() / 2].to_vec(),
            Some("truncated"),
        ),
        ("old.aofield", wrong_version, Some("version 9")),
        (
            "text.aofield",
            b"hello, not a field".to_vec(),
            Some("not an AO field"),
        ),
    ];
    for (name, bytes, _) in &files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let mut gpu = Gpu::with_asset_folder(
        &scenes::cube_on_plane(),
        plain_ao(),
        Some(dir.to_str().unwrap()),
    );
    let handles: Vec<Handle<AoFieldData>> = files
        .iter()
        .map(|(name, _, _)| gpu.app.world().resource::<AssetServer>().load(*name))
        .collect();
    let settled = |gpu: &Gpu| {
        let server = gpu.app.world().resource::<AssetServer>();
        handles.iter().all(|h| {
            matches!(
                server.get_load_state(h),
                Some(LoadState::Loaded | LoadState::Failed(_))
            )
        })
    };
    for _ in 0..300 {
        if settled(&gpu) {
            break;
        }
        gpu.update(1);
    }
    let server = gpu.app.world().resource::<AssetServer>();
    for ((name, _, expected), handle) in files.iter().zip(&handles) {
        match (server.get_load_state(handle), expected) {
            (Some(LoadState::Loaded), None) => {
                let loaded = gpu
                    .app
                    .world()
                    .resource::<Assets<AoFieldData>>()
                    .get(handle);
                assert_eq!(loaded, Some(&field), "{name} loads what was written");
            }
            (Some(LoadState::Failed(error)), Some(words)) => {
                let message = error.to_string();
                println!("{name}: {message}");
                assert!(
                    message.contains(words),
                    "{name}: '{message}' should say '{words}'"
                );
            }
            (state, _) => panic!("{name}: unexpected load state {state:?}"),
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn ao_bake_writes_a_loadable_field_per_mesh() {
    let binary = example_binary("ao_bake");
    let out = std::env::temp_dir().join(format!("dynamic_ao_bake_{}", std::process::id()));
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cube_on_plane.glb");
    let run = |args: &[&str]| {
        let _turn = gpu_turn();
        Command::new(&binary)
            .args(args)
            .output()
            .expect("ao_bake runs")
    };
    let result = run(&[
        "--scene",
        scene.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--resolution",
        "8",
        "--rays",
        "64",
    ]);
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "ao_bake failed:\n{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let summaries: Vec<&str> = stdout.lines().filter(|l| l.contains("-> ")).collect();
    assert_eq!(summaries.len(), 3, "one summary line per mesh:\n{stdout}");
    let mut fields = 0;
    for entry in std::fs::read_dir(&out).unwrap() {
        let bytes = std::fs::read(entry.unwrap().path()).unwrap();
        let field = AoFieldData::from_bytes(&bytes).expect("a valid field");
        // About cubic cells, within a budget of 8³.
        let r = field.resolution;
        assert!(r.max_element() <= 16 && r.x * r.y * r.z <= 600, "{r}");
        assert_eq!((field.reach, field.near_reach), (0.75, 0.5));
        assert!(
            field.cells.iter().any(|c| c[0] > 0.1),
            "the field holds occlusion"
        );
        fields += 1;
    }
    assert_eq!(fields, 3);

    let missing = run(&["--scene", "no_such.glb", "--out-dir", out.to_str().unwrap()]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("not found"));
    let bad = run(&[
        "--scene",
        scene.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
        "--resolution",
        "1",
    ]);
    assert_eq!(bad.status.code(), Some(2));
    std::fs::remove_dir_all(&out).ok();
}

/// A test field: coarse enough to bake in a moment, fine enough to be smooth.
fn quick_field() -> AoField {
    AoField::Bake(BakeSettings {
        resolution: 16,
        rays: 128,
        ..default()
    })
}

fn fields_only(shading: FieldShading) -> DynamicAo {
    DynamicAo {
        technique: AoTechnique::Off,
        spheres: false,
        field_shading: shading,
        ..plain_ao()
    }
}

/// Builds the app, bakes its fields without touching the disk and waits until every field has
/// been baked.
fn gpu_with_fields(scene: &crate::harness::SceneSpec, ao: DynamicAo) -> Gpu {
    let mut gpu = Gpu::new(scene, ao);
    gpu.app
        .world_mut()
        .insert_resource(AoFieldCache::disabled());
    for _ in 0..400 {
        gpu.update(1);
        if gpu.app.world().resource::<Assets<AoFieldData>>().len() >= scene.fields.len() {
            break;
        }
    }
    assert_eq!(
        gpu.app.world().resource::<Assets<AoFieldData>>().len(),
        scene.fields.len(),
        "every field should have been baked"
    );
    gpu
}

/// Every field occluder's data and world transform.
/// The GPU's fields against `reference::fields` on the same ND-buffer: a cube's field on the
/// plane, with both shadings, and every mesh of a frame around a box a field (the frame and the
/// box within it join by their union outside the frame's bounds, `fields::join`).
#[test]
fn gpu_fields_match_the_cpu_evaluation() {
    let mut cube = scenes::cube_on_plane();
    cube.fields.push((1, quick_field()));
    let mut nested = scenes::frame_around_box();
    nested.fields = (0..3).map(|mesh| (mesh, quick_field())).collect();
    let runs = [
        (&cube, FieldShading::Cone),
        (&cube, FieldShading::OcclusionOnly),
        (&nested, FieldShading::Cone),
    ];
    for (scene, shading) in runs {
        let mut gpu = gpu_with_fields(scene, fields_only(shading));
        let frame = gpu.frame(4);
        let placed = placed_fields(&mut gpu);
        let refs: Vec<(&AoFieldData, Affine3A)> = placed.iter().map(|(f, t)| (f, *t)).collect();
        let bounds: Vec<_> = refs.iter().map(|(f, t)| object_bounds(f, *t)).collect();
        let unions = field_joins(&bounds)
            .iter()
            .filter(|join| matches!(join, ProxyJoin::UnionOutside { .. }))
            .count();
        let expected = if std::ptr::eq(scene, &nested) { 2 } else { 0 };
        assert_eq!(unions, expected, "the frame and its box");
        // The field alone counts every occluder within the camera's radius.
        let cpu: Vec<f32> = field_occlusion(&frame.nd, &frame.view, &refs, shading, 0.0, false)
            .into_iter()
            .map(|o| 1.0 - o)
            .collect();
        let mask = frame.geometry_mask();
        let (mean, p99) = difference_stats(&frame.visibility, &cpu, &mask);
        let off = frame
            .visibility
            .iter()
            .zip(&cpu)
            .zip(&mask)
            .filter(|((g, c), m)| **m && (*g - *c).abs() > 0.004)
            .count();
        let darkest = cpu.iter().copied().fold(1.0, f32::min);
        println!(
            "fields ({shading:?}): darkest {darkest:.3}; GPU vs CPU mean |diff| {mean:.5}, 99th \
             percentile {p99:.5}, {off} pixels over 0.004"
        );
        assert!(
            darkest < 0.7,
            "the field should darken the floor by the cube"
        );
        assert!(mean < 0.002 && p99 < 0.01, "{mean} {p99}");
        assert!(off * 500 < mask.len(), "{off} pixels differ");
    }
}

/// Baking on load goes through the disk cache: the first run writes the field there, a corrupt
/// cache file is baked again and replaced (deleting the field used longest ago to stay under the
/// cache's size), and bad occluders (no triangles, a zero-scale or NaN
/// transform, a bake request without a mesh) are skipped without a panic, and without a bake for
/// the ones that cannot be placed.
#[test]
fn baked_fields_are_cached_on_disk_and_bad_occluders_are_skipped() {
    let cache = std::env::temp_dir().join(format!("dynamic_ao_field_cache_{}", std::process::id()));
    std::fs::remove_dir_all(&cache).ok();
    let run = |extra_bad: bool, max_bytes: u64| {
        let mut scene = scenes::cube_on_plane();
        scene.fields.push((1, quick_field()));
        let mut gpu = Gpu::new(&scene, fields_only(FieldShading::Cone));
        gpu.app.world_mut().insert_resource(AoFieldCache {
            folder: Some(cache.clone()),
            max_bytes,
        });
        if extra_bad {
            let world = gpu.app.world_mut();
            let empty = world.resource_mut::<Assets<Mesh>>().add(Mesh::new(
                bevy::mesh::PrimitiveTopology::TriangleList,
                bevy::asset::RenderAssetUsages::default(),
            ));
            let cube = world
                .resource_mut::<Assets<Mesh>>()
                .add(Cuboid::new(0.5, 0.5, 0.5));
            world.spawn((
                Mesh3d(empty),
                quick_field(),
                Transform::IDENTITY,
                Name::new("empty field mesh"),
            ));
            world.spawn((
                Mesh3d(cube.clone()),
                quick_field(),
                Transform::from_scale(Vec3::ZERO),
                Name::new("zero-scale field"),
            ));
            world.spawn((
                Mesh3d(cube),
                quick_field(),
                Transform::from_xyz(f32::NAN, 0.0, 0.0),
                Name::new("NaN field"),
            ));
            world.spawn((
                quick_field(),
                Transform::IDENTITY,
                Name::new("field without mesh"),
            ));
        }
        for _ in 0..400 {
            gpu.update(1);
            let world = gpu.app.world_mut();
            let active = world
                .query_filtered::<(), With<bevy_dynamic_ao::fields::ActiveAoField>>()
                .iter(world)
                .count();
            if active > 0 {
                break;
            }
        }
        // Nothing is baked, or waited for, for the occluders that cannot be placed.
        let world = gpu.app.world_mut();
        let mut bad = world.query_filtered::<(
            &Name,
            Has<bevy_dynamic_ao::fields::ActiveAoField>,
            Has<bevy_dynamic_ao::fields::PendingAoField>,
        ), With<AoField>>();
        for (name, active, pending) in bad.iter(world) {
            if ["zero-scale field", "NaN field"].contains(&name.as_str()) {
                assert!(!active && !pending, "{name} has a field or waits for one");
            }
        }
        let frame = gpu.frame(3);
        assert!(frame.visibility.iter().all(|v| v.is_finite()));
        let darkest = frame.visibility.iter().copied().fold(1.0, f32::min);
        assert!(darkest < 0.8, "the cube's field should show");
    };
    run(false, AoFieldCache::DEFAULT_MAX_BYTES);
    let files: Vec<_> = std::fs::read_dir(&cache)
        .expect("the cache folder exists")
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "one field baked, one file cached");
    let field_bytes = std::fs::read(&files[0]).unwrap();
    assert!(AoFieldData::from_bytes(&field_bytes).is_ok());
    std::fs::write(&files[0], b"garbage").unwrap();
    // A field some other mesh left in the cache, used an hour ago: with room for one field,
    // writing the cube's deletes it.
    let stale = cache.join("0123456789abcdef.aofield");
    std::fs::write(&stale, &field_bytes).unwrap();
    std::fs::File::options()
        .write(true)
        .open(&stale)
        .unwrap()
        .set_modified(std::time::SystemTime::now() - std::time::Duration::from_secs(3600))
        .unwrap();
    run(true, field_bytes.len() as u64);
    assert!(!stale.exists(), "the field used longest ago is deleted");
    assert_eq!(
        std::fs::read_dir(&cache).unwrap().count(),
        1,
        "only the cube's field is baked: none for the occluders that cannot be placed"
    );
    // Each bad occluder said why, once.
    assert_logged_once(&["'empty field mesh'", "casts no field", "no usable triangle"]);
    assert_logged_once(&["'zero-scale field'", "zero-size or not finite"]);
    assert_logged_once(&["'NaN field'", "zero-size or not finite"]);
    assert_logged_once(&["'field without mesh'", "needs a Mesh3d"]);
    let folder = cache.to_string_lossy();
    assert_logged_once(&[
        "ignoring cached",
        &folder,
        "bytes where this mesh's field takes",
    ]);
    let bytes = std::fs::read(&files[0]).unwrap();
    assert!(
        AoFieldData::from_bytes(&bytes).is_ok(),
        "the corrupt cache file is replaced"
    );
    std::fs::remove_dir_all(&cache).ok();
}
