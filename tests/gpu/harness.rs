//! The one headless app every GPU test uses: build a scene, render a few frames on whatever
//! adapter wgpu finds (lavapipe on CI), read the AO buffer, the ND-buffer and the lit image back.

use std::sync::{Arc, Mutex, OnceLock, RwLock, RwLockReadGuard, RwLockWriteGuard};

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy::render::{
    gpu_readback::{Readback, ReadbackComplete},
    render_resource::TextureFormat,
    renderer::RenderDevice,
    settings::{RenderCreation, WgpuLimits, WgpuSettings},
    view::screenshot::{Screenshot, ScreenshotCaptured},
};
use bevy::shader::Shader;
use bevy_dynamic_ao::geometry::{bvh::Bvh, triangles::TriangleScene};
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    ground_truth::{GroundTruthSettings, ground_truth_visibility},
    nd_buffer::{NdBuffer, NdTexel, ViewMatrices},
};

use crate::common;

/// Bevy 0.19's SSAO radius is fixed in its shader (0.5 × 1.457 m, falling off over its outer
/// 60%); every comparison with it uses the same ground-truth radius.
pub const BEVY_SSAO_RADIUS: f32 = 0.73;

/// Image size of every GPU test (pixels): small, so lavapipe stays quick.
pub const WIDTH: u32 = 160;
pub const HEIGHT: u32 = 120;

/// Frames [`Gpu::frame_of`] renders at most, once asked, until the AO of the camera's technique
/// comes back: loading the shaders takes longer while other tests load models on the same task
/// pool.
const READBACK_FRAMES: u32 = 600;

/// A scene: meshes with their placement, a camera, and the lights.
#[derive(Clone)]
pub struct SceneSpec {
    pub meshes: Vec<(Mesh, Transform)>,
    pub camera: Transform,
    /// Brightness of the camera's ambient light (Bevy's units).
    pub ambient: f32,
    /// Illuminance of a directional light shining along this transform's forward, if any.
    pub sun: Option<(Transform, f32)>,
    /// Meshes (by index into `meshes`) that carry a sphere occluder.
    pub occluders: Vec<(usize, SphereOccluder)>,
    /// Meshes (by index into `meshes`) that carry an AO field.
    pub fields: Vec<(usize, AoField)>,
    /// Whether the meshes' material is double-sided (no face culled), as glTF models' often are.
    pub two_sided: bool,
}

impl SceneSpec {
    pub fn new(camera: Transform) -> Self {
        Self {
            meshes: Vec::new(),
            camera,
            ambient: 500.0,
            sun: None,
            occluders: Vec::new(),
            fields: Vec::new(),
            two_sided: false,
        }
    }

    /// The same scene with a double-sided material on every mesh.
    pub fn two_sided(self) -> Self {
        Self {
            two_sided: true,
            ..self
        }
    }

    pub fn with(mut self, mesh: impl Into<Mesh>, transform: Transform) -> Self {
        self.meshes.push((mesh.into(), transform));
        self
    }

    /// Adds a mesh that casts far-field occlusion through `occluder`.
    pub fn with_occluder(
        mut self,
        mesh: impl Into<Mesh>,
        transform: Transform,
        occluder: SphereOccluder,
    ) -> Self {
        self.occluders.push((self.meshes.len(), occluder));
        self.with(mesh, transform)
    }

    /// The same triangles for the CPU ray tracer.
    pub fn bvh(&self) -> Bvh {
        let mut scene = TriangleScene::default();
        for (mesh, transform) in &self.meshes {
            scene.add_mesh(mesh, transform.compute_affine());
        }
        Bvh::new(scene.triangles)
    }
}

/// What one frame gave back.
pub struct Frame {
    pub visibility: Vec<f32>,
    pub nd: NdBuffer,
    pub view: ViewMatrices,
}

impl Frame {
    /// Pixels where the front layer saw geometry.
    pub fn geometry_mask(&self) -> Vec<bool> {
        self.nd.front.iter().map(|t| t.depth > 0.0).collect()
    }

    /// The visibility of the pixels where the front layer saw geometry.
    pub fn geometry_visibility(&self) -> Vec<f32> {
        self.visibility
            .iter()
            .zip(&self.nd.front)
            .filter(|(_, t)| t.depth > 0.0)
            .map(|(v, _)| *v)
            .collect()
    }

    /// World position of the front-layer surface at pixel `i` (None where empty).
    pub fn position(&self, i: usize) -> Option<Vec3> {
        let t = self.nd.front[i];
        (t.depth > 0.0).then(|| {
            let width = self.nd.width as usize;
            self.view.world_position(
                (i % width) as i32,
                (i / width) as i32,
                self.nd.width,
                self.nd.height,
                t.depth,
            )
        })
    }

    /// Ground-truth visibility of the same camera over `bvh`.
    pub fn ground_truth(&self, bvh: &Bvh, radius: f32) -> Vec<f32> {
        ground_truth(
            bvh,
            &self.view,
            &GroundTruthSettings {
                width: self.nd.width,
                height: self.nd.height,
                radius,
                rays_per_pixel: 256,
            },
        )
    }
}

/// [`ground_truth_visibility`], traced once per test run for each set of triangles, camera,
/// image size and radius (a 64-bit hash of them all is the key): a trace takes seconds on two
/// cores, and several tests check the same scenes from the same cameras.
pub fn ground_truth(bvh: &Bvh, view: &ViewMatrices, settings: &GroundTruthSettings) -> Vec<f32> {
    use std::hash::{DefaultHasher, Hash, Hasher};
    static TRACED: Mutex<Vec<(u64, Vec<f32>)>> = Mutex::new(Vec::new());
    let mut hasher = DefaultHasher::new();
    for triangle in bvh.triangles() {
        let normals = triangle.normals.unwrap_or([Vec3::NAN; 3]);
        for v in triangle.vertices.iter().chain(&normals) {
            v.to_array().map(f32::to_bits).hash(&mut hasher);
        }
    }
    for m in [
        view.world_from_clip,
        view.view_from_world,
        view.clip_from_view,
    ] {
        m.to_cols_array().map(f32::to_bits).hash(&mut hasher);
    }
    let s = settings;
    (s.width, s.height, s.radius.to_bits(), s.rays_per_pixel).hash(&mut hasher);
    let key = hasher.finish();
    let traced = || TRACED.lock().unwrap_or_else(|p| p.into_inner());
    if let Some((_, truth)) = traced().iter().find(|(k, _)| *k == key) {
        return truth.clone();
    }
    let truth = ground_truth_visibility(bvh, view, settings);
    traced().push((key, truth.clone()));
    truth
}

/// Turns at the GPU. Every test thread (libtest runs one per core) may render at once: a headless
/// frame at 160 × 120 keeps about 1.2 of two cores busy on lavapipe (measured with
/// `ao_capture`), so two at a time share that machine rather than fight over it. A test that
/// measures the process itself (the soak's memory) takes the GPU alone ([`gpu_alone`]).
static GPU_TURN: RwLock<()> = RwLock::new(());

/// A turn at the GPU, shared with the other test threads.
pub fn gpu_turn() -> RwLockReadGuard<'static, ()> {
    GPU_TURN
        .read()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The GPU alone: no other test renders until this is dropped.
pub fn gpu_alone() -> RwLockWriteGuard<'static, ()> {
    GPU_TURN
        .write()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

pub struct Gpu {
    pub app: App,
    _turn: RwLockReadGuard<'static, ()>,
    pub camera: Entity,
    pub readback: AoReadback,
    /// Cameras whose AO a read-back has shown.
    shown: Vec<Entity>,
}

impl Gpu {
    /// A headless app showing `scene` through a camera with `ao`.
    pub fn new(scene: &SceneSpec, ao: DynamicAo) -> Self {
        Self::with_asset_folder(scene, ao, None)
    }

    /// Like [`Gpu::new`], loading assets from `folder` instead of the crate's `assets/`.
    pub fn with_asset_folder(scene: &SceneSpec, ao: DynamicAo, folder: Option<&str>) -> Self {
        Self::build(scene, ao, folder, true)
    }

    /// Like [`Gpu::new`], with pipelines compiling in the background as in a normal app.
    pub fn with_background_compilation(scene: &SceneSpec, ao: DynamicAo) -> Self {
        Self::build(scene, ao, None, false)
    }

    /// Like [`Gpu::new`], with Bevy's render diagnostics: every pass's time span is reported in
    /// the `DiagnosticsStore` (see [`pass_spans`]).
    pub fn with_render_diagnostics(scene: &SceneSpec, ao: DynamicAo) -> Self {
        Self::build_with_limits(scene, ao, None, true, None, true)
    }

    /// Like [`Gpu::new`] on a device whose `max_storage_buffer_binding_size` is `bytes`, every
    /// other limit the adapter's.
    pub fn with_storage_binding_limit(scene: &SceneSpec, ao: DynamicAo, bytes: u64) -> Self {
        static ADAPTER_LIMITS: OnceLock<WgpuLimits> = OnceLock::new();
        let mut limits = ADAPTER_LIMITS
            .get_or_init(|| {
                let probe = Self::new(&SceneSpec::new(scene.camera), plain_ao());
                probe.app.world().resource::<RenderDevice>().limits()
            })
            .clone();
        limits.max_storage_buffer_binding_size = bytes;
        Self::build_with_limits(scene, ao, None, true, Some(limits), false)
    }

    fn build(scene: &SceneSpec, ao: DynamicAo, folder: Option<&str>, synchronous: bool) -> Self {
        Self::build_with_limits(scene, ao, folder, synchronous, None, false)
    }

    fn build_with_limits(
        scene: &SceneSpec,
        ao: DynamicAo,
        folder: Option<&str>,
        synchronous: bool,
        limits: Option<WgpuLimits>,
        diagnostics: bool,
    ) -> Self {
        let turn = gpu_turn();
        let mut app = App::new();
        let plugins = common::headless_plugins()
            .set(bevy::render::RenderPlugin {
                synchronous_pipeline_compilation: synchronous,
                render_creation: RenderCreation::Automatic(Box::new(WgpuSettings {
                    constrained_limits: limits,
                    ..default()
                })),
                ..default()
            })
            .set(crate::log_capture::log_plugin());
        match folder {
            Some(folder) => app.add_plugins((
                plugins.set(bevy::asset::AssetPlugin {
                    file_path: folder.into(),
                    ..default()
                }),
                DynamicAoPlugin,
            )),
            None => app.add_plugins((plugins, DynamicAoPlugin)),
        };
        if diagnostics {
            app.add_plugins(bevy::render::diagnostic::RenderDiagnosticsPlugin);
        }
        common::finish_plugins(&mut app);

        let world = app.world_mut();
        let material = world
            .resource_mut::<Assets<StandardMaterial>>()
            .add(StandardMaterial {
                base_color: Color::srgb(0.8, 0.8, 0.8),
                perceptual_roughness: 1.0,
                reflectance: 0.0,
                double_sided: scene.two_sided,
                cull_mode: (!scene.two_sided).then_some(bevy::render::render_resource::Face::Back),
                ..default()
            });
        for (i, (mesh, transform)) in scene.meshes.iter().enumerate() {
            let mesh = world.resource_mut::<Assets<Mesh>>().add(mesh.clone());
            let mut entity =
                world.spawn((Mesh3d(mesh), MeshMaterial3d(material.clone()), *transform));
            if let Some((_, occluder)) = scene.occluders.iter().find(|(k, _)| *k == i) {
                entity.insert(*occluder);
            }
            if let Some((_, field)) = scene.fields.iter().find(|(k, _)| *k == i) {
                entity.insert(field.clone());
            }
        }
        if let Some((transform, illuminance)) = scene.sun {
            world.spawn((
                DirectionalLight {
                    illuminance,
                    shadow_maps_enabled: false,
                    ..default()
                },
                transform,
            ));
        }
        let mut gpu = Self {
            app,
            _turn: turn,
            camera: Entity::PLACEHOLDER,
            readback: AoReadback {
                visibility: Handle::default(),
                front: Handle::default(),
                back: Handle::default(),
            },
            shown: Vec::new(),
        };
        let (camera, readback) = gpu.add_camera(scene.camera, ao);
        gpu.app.world_mut().entity_mut(camera).insert(AmbientLight {
            brightness: scene.ambient,
            ..default()
        });
        gpu.camera = camera;
        gpu.readback = readback;
        gpu
    }

    /// Sets the quality level of the Bevy SSAO the camera carries (under
    /// `AoTechnique::BevySsao` it is Bevy's own pass that runs).
    pub fn set_bevy_ssao_level(
        &mut self,
        level: bevy::pbr::ScreenSpaceAmbientOcclusionQualityLevel,
    ) {
        let camera = self.camera;
        self.app
            .world_mut()
            .get_mut::<bevy::pbr::ScreenSpaceAmbientOcclusion>(camera)
            .expect("DynamicAo brings Bevy's SSAO component")
            .quality_level = level;
    }

    /// Changes the camera's settings.
    pub fn set_ao(&mut self, change: impl FnOnce(&mut DynamicAo)) {
        let mut ao = self
            .app
            .world_mut()
            .get_mut::<DynamicAo>(self.camera)
            .expect("camera has DynamicAo");
        change(&mut ao);
    }

    /// Takes the shader whose path ends with `path` out of the app's assets, as for a moment
    /// while its file reloads: the pipelines that use it wait to compile until
    /// [`Gpu::restore_shader`] puts it back.
    pub fn take_shader(&mut self, path: &str) -> (AssetId<Shader>, Shader) {
        let mut shaders = self.app.world_mut().resource_mut::<Assets<Shader>>();
        let (id, shader) = shaders
            .iter()
            .find(|(_, shader)| shader.path.ends_with(path))
            .map(|(id, shader)| (id, shader.clone()))
            .unwrap_or_else(|| panic!("no shader {path} is loaded"));
        shaders.remove(id);
        (id, shader)
    }

    /// Puts back a shader [`Gpu::take_shader`] took.
    pub fn restore_shader(&mut self, (id, shader): (AssetId<Shader>, Shader)) {
        self.app
            .world_mut()
            .resource_mut::<Assets<Shader>>()
            .insert(id, shader)
            .expect("the shader's slot is live");
    }

    pub fn update(&mut self, frames: u32) {
        for _ in 0..frames {
            self.app.update();
        }
    }

    /// Renders `frames` frames, then reads the AO buffer and both ND-buffer layers back.
    pub fn frame(&mut self, frames: u32) -> Frame {
        let (camera, readback) = (self.camera, self.readback.clone());
        self.frame_of(camera, &readback, frames)
    }

    /// Adds another camera with its own settings, image target and read-back.
    pub fn add_camera(&mut self, transform: Transform, ao: DynamicAo) -> (Entity, AoReadback) {
        self.add_camera_of_size(transform, ao, UVec2::new(WIDTH, HEIGHT))
    }

    /// [`Gpu::add_camera`] rendering `size` pixels (odd sizes included).
    pub fn add_camera_of_size(
        &mut self,
        transform: Transform,
        ao: DynamicAo,
        size: UVec2,
    ) -> (Entity, AoReadback) {
        let world = self.app.world_mut();
        let target = world
            .resource_mut::<Assets<Image>>()
            .add(Image::new_target_texture(
                size.x,
                size.y,
                TextureFormat::Rgba8UnormSrgb,
                None,
            ));
        let readback = AoReadback::new(&mut world.resource_mut::<Assets<Image>>(), size);
        let camera = world
            .spawn((
                Camera3d::default(),
                transform,
                Msaa::Off,
                Tonemapping::None,
                RenderTarget::Image(target.into()),
                ao,
                readback.clone(),
            ))
            .id();
        (camera, readback)
    }

    /// Like [`Gpu::frame`], for any camera with an [`AoReadback`]. A read-back of a frame on
    /// which nothing wrote the AO yet (visibility −1: a shader still loading, which takes longer
    /// while other tests load models) is dropped and the next frame read.
    ///
    /// On a camera's first call the `frames` count from the first frame after its AO was first
    /// read back, where an accumulating camera's history starts over: it then holds the same
    /// frames, of the same sequence, however long its shaders took to load (its history starts
    /// on the first frame its AO is shown, which a read-back sees a frame or two late).
    pub fn frame_of(&mut self, camera: Entity, readback: &AoReadback, frames: u32) -> Frame {
        if !self.shown.contains(&camera) {
            self.read_until_written(readback);
            self.shown.push(camera);
            if let Some(mut ao) = self.app.world_mut().get_mut::<DynamicAo>(camera)
                && ao.temporal.enabled
            {
                ao.temporal.reset = true;
            }
        }
        self.update(frames);
        let images = self.read_until_written(readback);
        self.frame_from_bytes(camera, readback, images)
    }

    /// The first read-back of `readback` on which the AO is written.
    fn read_until_written(&mut self, readback: &AoReadback) -> [Vec<u8>; 3] {
        let mut updates = 0;
        loop {
            let images = self.read_back_once(readback, &mut updates);
            // Every pixel reads −1 then; the first says it.
            let written =
                f32::from_le_bytes([images[0][0], images[0][1], images[0][2], images[0][3]]) >= 0.0;
            if written {
                return images;
            }
            assert!(
                updates < READBACK_FRAMES,
                "nothing wrote the camera's AO in {READBACK_FRAMES} frames"
            );
        }
    }

    /// The main camera's frame as the next frame's copy holds it, visibility −1 included: what a
    /// read-back gets on a frame where the AO may not be there yet.
    pub fn frame_now(&mut self) -> Frame {
        let (camera, readback) = (self.camera, self.readback.clone());
        let images = self.read_back_once(&readback, &mut 0);
        self.frame_from_bytes(camera, &readback, images)
    }

    /// The visibility of each of `readbacks` (cameras of the harness's size) read back from one
    /// frame, −1 included where the AO is not there yet: for comparing cameras frame for frame.
    pub fn visibility_of_each_now(&mut self, readbacks: &[&AoReadback]) -> Vec<Vec<f32>> {
        let images: Vec<&Handle<Image>> = readbacks.iter().map(|r| &r.visibility).collect();
        self.read_images_once(&images, &mut 0)
            .iter()
            .map(|data| common::unpad_f32(data, WIDTH as usize, HEIGHT as usize, 1))
            .collect()
    }

    /// The read-back's bytes as a [`Frame`] of `camera`.
    fn frame_from_bytes(
        &mut self,
        camera: Entity,
        readback: &AoReadback,
        images: [Vec<u8>; 3],
    ) -> Frame {
        let [visibility, front, back] = images;
        // The read-back's own size: a camera's viewport may differ from the harness's.
        let size = self
            .app
            .world()
            .resource::<Assets<Image>>()
            .get(&readback.visibility)
            .expect("read-back image")
            .size();
        let (w, h) = (size.x as usize, size.y as usize);
        let texels = |data: &[u8]| -> Vec<NdTexel> {
            common::unpad_f32(data, w, h, 4)
                .chunks_exact(4)
                .map(|c| NdTexel::from_rgba([c[0], c[1], c[2], c[3]]))
                .collect()
        };
        Frame {
            visibility: common::unpad_f32(&visibility, w, h, 1),
            nd: NdBuffer {
                width: size.x,
                height: size.y,
                front: texels(&front),
                back: texels(&back),
            },
            view: self.view(camera),
        }
    }

    /// One read-back of `readback`'s three images, from the first frame that copies them;
    /// counts the frames it updates in `updates`.
    fn read_back_once(&mut self, readback: &AoReadback, updates: &mut u32) -> [Vec<u8>; 3] {
        let images = [&readback.visibility, &readback.front, &readback.back];
        self.read_images_once(&images, updates)
            .try_into()
            .expect("three images")
    }

    /// One read-back of each of `images`, all from the first frame that copies them; counts the
    /// frames it updates in `updates`.
    fn read_images_once(&mut self, images: &[&Handle<Image>], updates: &mut u32) -> Vec<Vec<u8>> {
        let slots: Arc<Mutex<Vec<Option<Vec<u8>>>>> =
            Arc::new(Mutex::new(vec![None; images.len()]));
        let entities: Vec<Entity> = images
            .iter()
            .enumerate()
            .map(|(slot, image)| {
                let slots = slots.clone();
                self.app
                    .world_mut()
                    .spawn(Readback::texture((*image).clone()))
                    .observe(move |done: On<ReadbackComplete>| {
                        slots.lock().unwrap()[slot].get_or_insert_with(|| done.data.clone());
                    })
                    .id()
            })
            .collect();
        while *updates < READBACK_FRAMES {
            self.app.update();
            *updates += 1;
            if slots.lock().unwrap().iter().all(Option::is_some) {
                break;
            }
        }
        for entity in entities {
            self.app.world_mut().despawn(entity);
        }
        let slots = slots.lock().unwrap().clone();
        slots
            .into_iter()
            .map(|data| {
                data.unwrap_or_else(|| {
                    panic!("the GPU read-back did not complete in {READBACK_FRAMES} frames")
                })
            })
            .collect()
    }

    /// A camera's matrices, as its view uniform holds them.
    pub fn view(&mut self, camera: Entity) -> ViewMatrices {
        let world = self.app.world_mut();
        let transform = world
            .get::<GlobalTransform>(camera)
            .expect("camera transform");
        let camera = world.get::<Camera>(camera).expect("camera");
        ViewMatrices::new(transform.to_matrix(), camera.clip_from_view())
    }

    /// The image the main camera renders to.
    fn target(&self) -> Handle<Image> {
        match self.app.world().get::<RenderTarget>(self.camera) {
            Some(RenderTarget::Image(target)) => target.handle.clone(),
            _ => panic!("the test camera renders to an image"),
        }
    }

    /// The lit image after `frames` more frames, as linear RGB.
    pub fn color(&mut self, frames: u32) -> Vec<Vec3> {
        let target = self.target();
        self.color_of(target, UVec2::new(WIDTH, HEIGHT), frames)
    }

    /// The lit image of any render target of `size` after `frames` more frames, as linear RGB.
    pub fn color_of(&mut self, target: Handle<Image>, size: UVec2, frames: u32) -> Vec<Vec3> {
        self.update(frames);
        let slot: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
        let store = slot.clone();
        self.app
            .world_mut()
            .spawn(Screenshot::image(target))
            .observe(move |shot: On<ScreenshotCaptured>| {
                *store.lock().unwrap() = shot.image.data.clone();
            });
        for _ in 0..60 {
            self.app.update();
            if slot.lock().unwrap().is_some() {
                break;
            }
        }
        let data = slot
            .lock()
            .unwrap()
            .take()
            .expect("the screenshot did not arrive in 60 frames");
        data.chunks_exact(4)
            .take((size.x * size.y) as usize)
            .map(|p| {
                Vec3::new(
                    srgb_to_linear(p[0]),
                    srgb_to_linear(p[1]),
                    srgb_to_linear(p[2]),
                )
            })
            .collect()
    }
}

/// How many measurements each of the plugin's pass time spans (`render/dynamic_ao_*`, CPU and
/// GPU) holds in the app's `DiagnosticsStore`, by path; `forget` clears them first. Needs
/// [`Gpu::with_render_diagnostics`].
pub fn pass_spans(gpu: &mut Gpu, forget: bool) -> Vec<(String, usize)> {
    let mut store = gpu
        .app
        .world_mut()
        .resource_mut::<bevy::diagnostic::DiagnosticsStore>();
    let mut spans = Vec::new();
    for diagnostic in store.iter_mut() {
        let path = diagnostic.path().as_str().to_owned();
        if !path.starts_with("render/dynamic_ao") {
            continue;
        }
        if forget {
            diagnostic.clear_history();
        }
        spans.push((path, diagnostic.history_len()));
    }
    spans.sort();
    spans
}

fn srgb_to_linear(v: u8) -> f32 {
    let c = v as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The largest |a − b| over two images.
pub fn largest_difference(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

/// Mean and 99th percentile of |gpu − cpu| over the masked pixels.
pub fn difference_stats(gpu: &[f32], cpu: &[f32], mask: &[bool]) -> (f32, f32) {
    let mut diffs: Vec<f32> = gpu
        .iter()
        .zip(cpu)
        .zip(mask)
        .filter(|(_, m)| **m)
        .map(|((g, c), _)| (g - c).abs())
        .collect();
    assert!(!diffs.is_empty(), "no pixel to compare");
    diffs.sort_by(f32::total_cmp);
    let mean = diffs.iter().sum::<f32>() / diffs.len() as f32;
    (mean, diffs[diffs.len() * 99 / 100])
}

/// Mean occlusion (1 − visibility) of the image columns `columns`.
pub fn band(visibility: &[f32], columns: std::ops::Range<u32>) -> f32 {
    let (mut sum, mut n) = (0.0, 0.0);
    for y in 0..HEIGHT {
        for x in columns.clone() {
            sum += 1.0 - visibility[(y * WIDTH + x) as usize];
            n += 1.0;
        }
    }
    sum / n
}

/// Index of pixel (x, y).
pub fn index(x: u32, y: u32) -> usize {
    (y * WIDTH + x) as usize
}

/// Frames after which an accumulated capture with `ao` counts as converged: twice the frames its
/// history takes to fill ([`DynamicAo::history_frames`]), and at least 4 where it does not
/// accumulate.
pub fn converged_frames(ao: &DynamicAo) -> u32 {
    (2 * ao.history_frames()).max(4)
}

/// The settings these tests were written for: the near field at full resolution, each frame on
/// its own (no accumulation), the ray march at its single-frame reference budget. The crate's
/// default (the accumulated ray march at half resolution) has tests of its own.
pub fn plain_ao() -> DynamicAo {
    DynamicAo {
        technique: AoTechnique::NearField,
        ray_march: RayMarchParams::REFERENCE,
        half_resolution: false,
        temporal: AoTemporal::OFF,
        ..DynamicAo::default()
    }
}
