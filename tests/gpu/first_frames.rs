//! A camera's first frames, while the shaders of its passes load and compile: its read-back says
//! the AO is not there yet (−1) rather than hand over what the texture holds meanwhile (zeros, or
//! Bevy's SSAO standing in), and what it reads afterwards is the camera's own AO.

use bevy::prelude::*;

use bevy_dynamic_ao::prelude::*;

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;

use crate::harness::{Frame, Gpu, HEIGHT, WIDTH, largest_difference, plain_ao};
use crate::scenes;

/// Reads a new camera's frames one by one, for at most `reads`, until one shows the scene as
/// `reference` does (the same front layer; before that, meshes whose prepass pipelines have not
/// compiled are missing from it). Each read-back says the AO is not there yet (−1 everywhere) or
/// is valid visibility; one that shows AO never holds a back-face layer that lacks meshes the
/// front layer holds; and on the first frame with the whole scene it is `reference`'s AO: never
/// the zeros of an unwritten texture, never Bevy's SSAO standing in. Returns the reads that said
/// −1 and the read that matched.
fn read_until_the_scene_is_drawn(
    gpu: &mut Gpu,
    reference: &Frame,
    reads: u32,
    what: &str,
) -> (u32, u32) {
    let mut not_yet = 0;
    for read in 1..=reads {
        let frame = gpu.frame_now();
        if frame.visibility.iter().all(|v| *v == -1.0) {
            not_yet += 1;
            continue;
        }
        assert!(
            frame.visibility.iter().all(|v| (0.0..=1.0).contains(v)),
            "{what}: read-back {read} is neither visibility nor −1"
        );
        if frame.nd.front != reference.nd.front {
            continue;
        }
        // The back-face layer is drawn by pipelines of its own, compiled apart from the front
        // layer's; the AO waits for them (`wait_for_layer_draws`). In one fresh-clone run before
        // it did, the ray march, the one technique here that reads the back layer, read 0.25 off
        // the reference on the first frame whose front layer was whole.
        assert!(
            frame.nd.back == reference.nd.back,
            "{what}: read-back {read} shows AO over a whole front layer and an incomplete back \
             layer"
        );
        let difference = largest_difference(&frame.visibility, &reference.visibility);
        println!(
            "{what}: {not_yet} read-backs said −1; the whole scene at read-back {read}, largest \
             difference from a camera whose shaders were ready {difference}"
        );
        assert!(
            difference < 1e-4,
            "{what}: the first AO of the whole scene is not the camera's: {difference}"
        );
        return (not_yet, read);
    }
    panic!("{what}: the scene was not drawn in {reads} frames");
}

/// The first frames of a new camera, its shaders loading meanwhile (how many frames that takes
/// depends on the machine's load: with other tests' apps loading models on the same task pool, it
/// took more than four).
#[test]
fn every_read_back_of_a_new_camera_is_its_ao_or_says_it_is_not_there_yet() {
    let scene = scenes::cube_on_plane();
    let reference = Gpu::new(&scene, plain_ao()).frame(8);
    let mut gpu = Gpu::new(&scene, plain_ao());
    read_until_the_scene_is_drawn(&mut gpu, &reference, 60, "loading");
}

/// In a normal app pipelines compile in the background over many frames: Bevy's own and ours, in
/// any order.
#[test]
fn every_read_back_is_valid_while_pipelines_compile_in_the_background() {
    for technique in [
        AoTechnique::NearField,
        AoTechnique::Horizon,
        AoTechnique::RayMarch,
    ] {
        let ao = plain_ao().with_technique(technique);
        let scene = scenes::cube_on_plane();
        let reference = Gpu::new(&scene, ao.clone()).frame(4);
        let mut gpu = Gpu::with_background_compilation(&scene, ao);
        read_until_the_scene_is_drawn(&mut gpu, &reference, 400, &format!("{technique:?}"));
    }
}

/// A pass whose shader is not there (taken out of its assets, as for a moment while a file
/// reloads) waits to compile rather than fail: meanwhile Bevy's SSAO fills the texture and the
/// read-back says −1; once the shader is back, so is the camera's own AO.
#[test]
fn while_a_pass_waits_for_its_shader_the_read_back_says_so_and_then_returns_the_ao() {
    let scene = scenes::cube_on_plane();
    let mut gpu = Gpu::new(&scene, plain_ao());
    let ours = gpu.frame(4);
    assert!(
        ours.visibility.iter().any(|v| *v < 0.6),
        "the scene has no dark crease"
    );
    let compose = gpu.take_shader("compose/compose.wgsl");
    gpu.update(4);
    let meanwhile = gpu.frame_now().visibility;
    assert!(
        meanwhile.iter().all(|v| *v == -1.0),
        "while compose waits, the read-back should say so: it reads {} to {}",
        meanwhile.iter().copied().fold(f32::MAX, f32::min),
        meanwhile.iter().copied().fold(f32::MIN, f32::max)
    );
    gpu.restore_shader(compose);
    let after = gpu.frame(2);
    let difference = largest_difference(&after.visibility, &ours.visibility);
    println!("with the shader back: largest difference from before {difference}");
    assert!(difference < 1e-4, "the AO did not come back: {difference}");
}

/// A new camera whose back-face layer cannot be drawn yet (the layer's shaders taken out, as while
/// they load) shows no AO over a back layer that lacks the scene's meshes: its read-back says
/// −1 until the shaders are back, and then it is the camera's own AO. The ray march reads the
/// back layer; the coarse copies, which have a pass of their own, are off. Before the AO waited
/// for the meshes' layer pipelines (`wait_for_layer_draws`), this camera showed the ray march
/// over an empty back layer.
#[test]
fn a_new_camera_waits_for_the_meshes_of_its_back_face_layer() {
    let scene = scenes::cube_on_plane();
    let ao = DynamicAo {
        coarse_back_faces: false,
        ..plain_ao().with_technique(AoTechnique::RayMarch)
    };
    let mut gpu = Gpu::new(&scene, ao.clone());
    let reference = gpu.frame(4);
    let shaders = [
        gpu.take_shader("nd_buffer/back_depth.wgsl"),
        gpu.take_shader("nd_buffer/layer_normals.wgsl"),
    ];
    gpu.update(2);
    let (camera, readback) = gpu.add_camera(scene.camera, ao);
    gpu.update(8);
    let meanwhile = gpu.visibility_of_each_now(&[&readback]).remove(0);
    assert!(
        meanwhile.iter().all(|v| *v == -1.0),
        "while its back layer cannot be drawn, the new camera should show no AO: it reads {} to {}",
        meanwhile.iter().copied().fold(f32::MAX, f32::min),
        meanwhile.iter().copied().fold(f32::MIN, f32::max)
    );
    for shader in shaders {
        gpu.restore_shader(shader);
    }
    let after = gpu.frame_of(camera, &readback, 2);
    assert!(
        after.nd.back == reference.nd.back,
        "the back layer did not come back"
    );
    let difference = largest_difference(&after.visibility, &reference.visibility);
    println!("with the shaders back: largest difference from the first camera {difference}");
    assert!(
        difference < 1e-4,
        "the new camera's AO is not the scene's: {difference}"
    );
}

/// A camera of its own rendering `transform` into a new target, with `ao` if given; the target.
fn spawn_lit_camera(gpu: &mut Gpu, transform: Transform, ao: Option<DynamicAo>) -> Handle<Image> {
    let world = gpu.app.world_mut();
    let target = world
        .resource_mut::<Assets<Image>>()
        .add(Image::new_target_texture(
            WIDTH,
            HEIGHT,
            bevy::render::render_resource::TextureFormat::Rgba8UnormSrgb,
            None,
        ));
    let mut camera = world.spawn((
        Camera3d::default(),
        transform,
        Msaa::Off,
        Tonemapping::None,
        RenderTarget::Image(target.clone().into()),
        AmbientLight {
            brightness: 2000.0,
            ..default()
        },
    ));
    if let Some(ao) = ao {
        camera.insert(ao);
    }
    target
}

/// Until anything writes a new camera's AO (its passes and Bevy's SSAO both waiting for their
/// shaders, as while a game loads its assets), the camera is lit as one without AO, not with its
/// ambient light gone.
#[test]
fn a_camera_whose_ao_nothing_writes_yet_is_lit_as_one_without_ao() {
    let scene = scenes::cube_on_plane();
    let mut gpu = Gpu::new(&scene, plain_ao());
    gpu.frame(4);
    // Compose's and Bevy's SSAO's shaders, kept out for the rest of the test.
    gpu.take_shader("compose/compose.wgsl");
    gpu.take_shader("ssao/ssao.wgsl");
    let with_ao = spawn_lit_camera(&mut gpu, scene.camera, Some(plain_ao()));
    let without = spawn_lit_camera(&mut gpu, scene.camera, None);
    let size = UVec2::new(WIDTH, HEIGHT);
    let lit = gpu.color_of(with_ao, size, 4);
    let reference = gpu.color_of(without, size, 0);
    let luminance = |image: &[Vec3]| image.iter().map(|c| c.y).sum::<f32>() / image.len() as f32;
    let worst = lit
        .iter()
        .zip(&reference)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0, f32::max);
    println!(
        "nothing writes the AO: mean {:.4} against {:.4} without AO, largest difference {worst:.4}",
        luminance(&lit),
        luminance(&reference)
    );
    // Measured 0; before the stand-in, 0.55 (mean luminance 0.007 against 0.403: black).
    assert!(
        worst < 1e-3,
        "the camera should be lit as without AO: largest difference {worst}"
    );
}

/// `DynamicAoStatus` through a camera's life, read in the main world after each update: `Shown`
/// with one more frame each update while the AO runs; `Pending` with 0 frames while a shader is
/// out; from its return frames 1, 2, 3, … (the accumulation starts on the first frame shown); a
/// reset starts the count over; a camera that stops rendering or loses its `DynamicAo` reads
/// `Pending`, and one that renders Bevy's SSAO reads `Shown`.
#[test]
fn a_cameras_status_says_whether_its_ao_is_shown_and_for_how_many_frames() {
    let scene = scenes::cube_on_plane();
    let mut gpu = Gpu::new(&scene, DynamicAo::default());
    gpu.frame(4);
    let status = |gpu: &Gpu| {
        *gpu.app
            .world()
            .get::<DynamicAoStatus>(gpu.camera)
            .expect("the plugin puts a status on every camera with DynamicAo")
    };
    let pending = DynamicAoStatus {
        shown: AoShown::Pending,
        frames: 0,
    };
    // The frames each of `updates` updates reads, asserting that the AO is shown on each.
    let shown_frames = |gpu: &mut Gpu, updates: u32| -> Vec<u32> {
        (0..updates)
            .map(|_| {
                gpu.update(1);
                let now = status(gpu);
                assert_eq!(now.shown, AoShown::Shown, "{now:?}");
                now.frames
            })
            .collect()
    };
    let one_more_each = |frames: &[u32]| frames.windows(2).all(|w| w[1] == w[0] + 1);

    let running = shown_frames(&mut gpu, 5);
    assert!(one_more_each(&running), "running: {running:?}");

    let compose = gpu.take_shader("compose/compose.wgsl");
    gpu.update(4);
    assert_eq!(status(&gpu), pending, "while the compose shader is out");
    assert!(
        gpu.frame_now().visibility.iter().all(|v| *v == -1.0),
        "the read-back agrees: nothing the camera asked for is shown"
    );
    gpu.restore_shader(compose);
    let mut back = Vec::new();
    for _ in 0..60 {
        gpu.update(1);
        match status(&gpu) {
            now if now.shown == AoShown::Shown => back.push(now.frames),
            now => assert!(back.is_empty() && now == pending, "{now:?} after {back:?}"),
        }
        if back.len() == 6 {
            break;
        }
    }
    assert_eq!(back, [1, 2, 3, 4, 5, 6], "from the shader's return");
    assert!(
        gpu.frame_now()
            .visibility
            .iter()
            .all(|v| (0.0..=1.0).contains(v)),
        "the read-back agrees: the AO is written"
    );

    gpu.set_ao(|ao| ao.temporal.reset = true);
    let reset = shown_frames(&mut gpu, 6);
    let breaks = reset.windows(2).filter(|w| w[1] != w[0] + 1).count();
    assert!(
        breaks == 1 && reset.contains(&1),
        "a reset starts the count over once: {reset:?}"
    );

    gpu.set_ao(|ao| ao.temporal.enabled = false);
    let plain = shown_frames(&mut gpu, 6);
    assert!(
        one_more_each(&plain[2..]),
        "without accumulation, frames in a row: {plain:?}"
    );

    gpu.set_ao(|ao| ao.temporal.enabled = true);
    let again = shown_frames(&mut gpu, 6);
    assert!(
        again.contains(&1) && one_more_each(&again[again.iter().position(|f| *f == 1).unwrap()..]),
        "accumulation on again starts its count over: {again:?}"
    );

    gpu.set_ao(|ao| ao.technique = AoTechnique::BevySsao);
    gpu.update(4);
    assert_eq!(status(&gpu).shown, AoShown::Shown, "Bevy's SSAO, as asked");

    gpu.set_ao(|ao| ao.technique = AoTechnique::default());
    let camera = gpu.camera;
    let active = |gpu: &mut Gpu, active: bool| {
        let world = gpu.app.world_mut();
        world.get_mut::<Camera>(camera).unwrap().is_active = active;
    };
    active(&mut gpu, false);
    gpu.update(3);
    assert_eq!(status(&gpu), pending, "an inactive camera shows nothing");
    active(&mut gpu, true);
    gpu.update(4);
    assert_eq!(status(&gpu).shown, AoShown::Shown, "active again");

    println!(
        "status frames: running {running:?}, from the shader's return {back:?}, across a reset \
         {reset:?}, accumulation off {plain:?}, on \
         again {again:?}"
    );
    gpu.app.world_mut().entity_mut(camera).remove::<DynamicAo>();
    gpu.update(3);
    assert_eq!(status(&gpu), pending, "without DynamicAo");
}
