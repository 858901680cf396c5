//! Scenes for judging the far field the way a user would set it up: every mesh an occluder of
//! every kind (as `ao_capture`'s far-field techniques attach them), thin and large occluders,
//! occluders just outside the view, characters standing on a floor. Shared by the `far_field`
//! tests and benchmark.
#![allow(dead_code)]

use bevy::math::Affine3A;
use bevy::prelude::*;
use bevy_dynamic_ao::fields::{ActiveAoField, AoFieldData, PendingAoField};
use bevy_dynamic_ao::geometry::union::occluder_union;
use bevy_dynamic_ao::geometry::{bvh::Bvh, triangles::TriangleScene};
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    posed::{posed_triangles, posed_triangles_of},
    spheres::{ProxyCamera, far_field_occlusion, proxy_occlusion},
};
use bevy_dynamic_ao::spheres::OccluderSphere;

use crate::far_terms::{self, FarTerm};
use crate::harness::{Frame, Gpu, HEIGHT, SceneSpec, WIDTH, converged_frames, plain_ao};
use crate::{models, scenes};

/// A model file to stand on the floor: file (relative to the asset folder), animation, time
/// (seconds), height (metres) and where it stands (x, z).
#[derive(Clone, Copy)]
pub struct Model {
    pub file: &'static str,
    pub animation: Option<usize>,
    pub time: f32,
    pub height: f32,
    pub at: Vec2,
}

/// One scene of the comparison.
pub struct FarScene {
    pub name: &'static str,
    pub spec: SceneSpec,
    pub model: Option<Model>,
    /// Camera placement from the model's bounds, when the scene has a model.
    pub camera: Option<fn(Vec3, Vec3) -> Transform>,
    /// Image columns of the floor strip beside an occluder outside the view.
    pub strip: Option<std::ops::Range<u32>>,
}

fn floor() -> Mesh {
    Plane3d::default().mesh().size(20.0, 20.0).build()
}

pub fn plain(name: &'static str, spec: SceneSpec) -> FarScene {
    FarScene {
        name,
        spec,
        model: None,
        camera: None,
        strip: None,
    }
}

/// A model standing on a 20 m floor, seen from the front and a little above.
pub fn model_on_floor(name: &'static str, model: Model) -> FarScene {
    FarScene {
        name,
        spec: SceneSpec::new(Transform::default()).with(floor(), Transform::IDENTITY),
        model: Some(model),
        camera: Some(|lo, hi| {
            let centre = (lo + hi) / 2.0;
            let size = (hi - lo).max_element();
            Transform::from_translation(centre + Vec3::new(0.9, 0.55, 1.4) * size * 1.3)
                .looking_at(centre - Vec3::Y * 0.15 * size, Vec3::Y)
        }),
        strip: None,
    }
}

/// The Fox, 1.8 m high, seen from in front along its body, as `docs/model_on_floor.py --height
/// 1.8 --eye 0,1.5,3.6 --target 0,0.6,0` frames it: the view ray through its head leaves the body
/// and enters it again farther back, so the two ND layers miss the floor's shadow under the body,
/// and the proxies of its legs and chest stand right beside the receivers on them.
pub fn fox_end_on() -> FarScene {
    FarScene {
        camera: Some(|lo, hi| {
            let c = Vec3::new((lo.x + hi.x) / 2.0, 0.0, (lo.z + hi.z) / 2.0);
            Transform::from_translation(c + Vec3::new(0.0, 1.5, 3.6))
                .looking_at(c + Vec3::new(0.0, 0.6, 0.0), Vec3::Y)
        }),
        ..model_on_floor(
            "Fox end-on",
            Model {
                file: "Fox/Fox.glb",
                animation: Some(0),
                time: 0.3,
                height: 1.8,
                at: Vec2::ZERO,
            },
        )
    }
}

/// The strip of floor beside an occluder just right of the view: the last 12 columns.
pub const STRIP: std::ops::Range<u32> = WIDTH - 12..WIDTH;

/// The scenes of `tests/gpu/scenes.rs`: objects in view (the first four), and a box and a wall
/// just outside it.
pub fn procedural() -> Vec<FarScene> {
    vec![
        plain("cube on plane", scenes::cube_on_plane()),
        plain("room corner", scenes::room_corner()),
        plain("ball near wall", scenes::ball_near_wall()),
        plain("open room", scenes::open_room()),
        FarScene {
            strip: Some(STRIP),
            ..plain("box beside view", scenes::box_beside_view())
        },
        FarScene {
            strip: Some(STRIP),
            ..plain("wall beside view", scenes::wall_beside_view())
        },
    ]
}

/// A ring (Bevy's `Torus`, major radius 0.6 m, tube 0.25 m) on the floor, seen from above its
/// rim: one rigid mesh that encloses a volume (its seams' vertices a rounding apart) and whose
/// box proxies stand one behind another as the floor around it sees them.
pub fn ring_on_floor() -> FarScene {
    plain(
        "ring on floor",
        SceneSpec::new(
            Transform::from_xyz(2.0, 1.6, 2.4).looking_at(Vec3::new(0.0, 0.3, 0.0), Vec3::Y),
        )
        .with(floor(), Transform::IDENTITY)
        .with(
            Torus::new(0.35, 0.85)
                .mesh()
                .minor_resolution(32)
                .major_resolution(96),
            Transform::from_xyz(0.0, 0.25, 0.0),
        ),
    )
}

/// A cube frame with a box inside it on a floor ([`scenes::frame_around_box`]): one open rigid
/// mesh with several proxies, and a mesh within them.
pub fn frame_on_floor() -> FarScene {
    plain("frame on floor", scenes::frame_around_box())
}

/// The project's own skinned walker (`assets/characters/walker.glb`), mid-stride on a floor.
pub fn walker_on_floor() -> FarScene {
    model_on_floor(
        "walker on floor",
        Model {
            file: "characters/walker.glb",
            animation: Some(0),
            time: 0.3,
            height: 1.8,
            at: Vec2::ZERO,
        },
    )
}

/// Third-party models from `../shared/assets` on a floor (skinned, static and detailed, morphed),
/// and a character just outside the view.
pub fn third_party() -> Vec<FarScene> {
    let model = |file, animation, time, height| Model {
        file,
        animation,
        time,
        height,
        at: Vec2::ZERO,
    };
    vec![
        model_on_floor(
            "CesiumMan on floor",
            model("CesiumMan/CesiumMan.glb", Some(0), 0.6, 1.8),
        ),
        model_on_floor("Fox on floor", model("Fox/Fox.glb", Some(2), 0.5, 0.8)),
        model_on_floor(
            "DamagedHelmet on floor",
            model("DamagedHelmet/DamagedHelmet.glb", None, 0.0, 0.6),
        ),
        model_on_floor(
            "AnimatedMorphCube on floor",
            model("AnimatedMorphCube/AnimatedMorphCube.glb", Some(0), 0.7, 0.5),
        ),
        model_on_floor(
            "RiggedFigure on floor",
            model("RiggedFigure/rigged_figure.glb", Some(0), 0.5, 1.7),
        ),
        model_on_floor(
            "BoxAnimated on floor",
            model("BoxAnimated/BoxAnimated.glb", Some(0), 1.0, 1.0),
        ),
        model_on_floor(
            "CornellBox on floor",
            model("CornellBox/CornellBox.glb", None, 0.0, 1.5),
        ),
        FarScene {
            model: Some(Model {
                at: Vec2::new(1.9, 0.0),
                ..model("CesiumMan/CesiumMan.glb", Some(0), 0.6, 1.8)
            }),
            camera: Some(|_, _| {
                Transform::from_xyz(0.0, 2.5, 0.0).looking_at(Vec3::ZERO, -Vec3::Z)
            }),
            strip: Some(STRIP),
            ..plain(
                "CesiumMan beside view",
                SceneSpec::new(Transform::default()).with(floor(), Transform::IDENTITY),
            )
        },
    ]
}

/// A scene in a headless app, every mesh a sphere occluder and an AO field, ready to render
/// any configuration at any radius.
pub struct FarRun {
    pub gpu: Gpu,
    /// Every mesh entity.
    pub meshes: Vec<Entity>,
    /// The scene's bounds (the floor cut to 40 m).
    pub bounds: (Vec3, Vec3),
    /// The voxel volume for the radius it was placed for.
    volume: Option<(Entity, f32)>,
    /// The image-space settings `render` uses where it asks for the near field (technique,
    /// budgets, resolution, accumulation, blur): the near field by default.
    pub image_space: DynamicAo,
}

impl FarRun {
    /// Builds the app (loading models from `folder`, or the crate's `assets/`).
    pub fn new(scene: &FarScene, folder: Option<&str>) -> Self {
        let mut gpu = Gpu::with_asset_folder(&scene.spec, plain_ao(), folder);
        if let Some(model) = scene.model {
            let root = models::load_model(&mut gpu, model.file, model.animation, model.time);
            let (lo, hi) = models::stand_on_floor(&mut gpu, root, model.height, model.at);
            if let Some(camera) = scene.camera {
                let entity = gpu.camera;
                gpu.app
                    .world_mut()
                    .entity_mut(entity)
                    .insert(camera(lo, hi));
            }
        }
        // Transforms and visibility propagate on the first frame.
        gpu.update(1);
        let world = gpu.app.world_mut();
        let meshes: Vec<Entity> = world
            .query_filtered::<Entity, With<Mesh3d>>()
            .iter(world)
            .collect();
        let (lo, hi) = posed_triangles(world).bounds();
        let bounds = (lo.max(Vec3::splat(-20.0)), hi.min(Vec3::splat(20.0)));
        let mut commands = world.commands();
        FarTerm::Spheres.attach(&mut commands, &meshes, bounds, 0.0);
        FarTerm::Fields.attach(&mut commands, &meshes, bounds, 0.0);
        world.flush();
        let mut run = Self {
            gpu,
            meshes,
            bounds,
            volume: None,
            image_space: plain_ao(),
        };
        run.settle();
        run
    }

    /// Frames until every AO field is baked for the current radius and every mesh fitted.
    pub fn settle(&mut self) {
        for _ in 0..3000 {
            self.gpu.update(1);
            let world = self.gpu.app.world_mut();
            let baking = world
                .query_filtered::<(Has<ActiveAoField>, Has<PendingAoField>), With<AoField>>()
                .iter(world)
                .any(|(active, pending)| !active || pending);
            let fitting = world
                .query::<&OccluderSpheres>()
                .iter(world)
                .any(|s| s.spheres.is_empty());
            if !baking && !fitting {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        panic!("fields or proxies were not ready in 3000 frames");
    }

    /// One volume over what occludes the surfaces the view shows within `radius`, as `ao_capture`
    /// places it (`far_terms::occluder_bounds`; the scene's bounds where nothing does).
    fn place_volume(&mut self, radius: f32) {
        if self.volume.is_some_and(|(_, r)| r == radius) {
            return;
        }
        if let Some((volume, _)) = self.volume.take() {
            self.gpu.app.world_mut().despawn(volume);
        }
        self.gpu.set_ao(|ao| FarTerm::select(None, ao));
        let seen = self.gpu.frame(2);
        let bvh = self.bvh();
        let region =
            far_terms::occluder_bounds(&bvh, &seen.nd.front, WIDTH, HEIGHT, &seen.view, radius)
                .unwrap_or(self.bounds);
        let world = self.gpu.app.world_mut();
        let mut commands = world.commands();
        let volume = FarTerm::Voxels
            .attach(
                &mut commands,
                &self.meshes,
                region,
                far_terms::VOXEL_MARGIN * radius,
            )
            .expect("a volume");
        world.flush();
        self.volume = Some((volume, radius));
    }

    /// The voxel volume, once a render with voxels placed it.
    pub fn volume(&self) -> Option<Entity> {
        self.volume.map(|(entity, _)| entity)
    }

    /// Renders the near field, or the image-space settings of `image_space` (or no image-space
    /// term), with `far` joined by `blend`, every
    /// term counting within `radius`.
    pub fn render(
        &mut self,
        near: bool,
        far: Option<FarTerm>,
        blend: FarFieldBlend,
        radius: f32,
    ) -> Frame {
        if far == Some(FarTerm::Voxels) {
            self.place_volume(radius);
        }
        let image_space = self.image_space.clone();
        self.gpu.set_ao(|ao| {
            ao.technique = if near {
                image_space.technique
            } else {
                AoTechnique::Off
            };
            ao.near_field = image_space.near_field;
            ao.horizon = image_space.horizon;
            ao.ray_march = image_space.ray_march;
            ao.half_resolution = image_space.half_resolution;
            ao.small_viewport_pixels = image_space.small_viewport_pixels;
            ao.blur = image_space.blur;
            ao.temporal = image_space.temporal;
            ao.coarse_back_faces = image_space.coarse_back_faces;
            ao.radius = radius;
            ao.far_field_blend = blend;
            FarTerm::select(far, ao);
        });
        self.settle();
        // The history starts over once every field is baked: how many frames the bakes took
        // (which depends on the machine's load) does not move where the accumulation stands.
        self.gpu.set_ao(|ao| ao.temporal.reset = true);
        // Accumulated occlusion is read once converged.
        self.gpu.frame(if near {
            converged_frames(&image_space)
        } else {
            4
        })
    }

    /// The scene's triangles as they are drawn now.
    pub fn bvh(&mut self) -> Bvh {
        Bvh::new(posed_triangles(self.gpu.app.world_mut()).triangles)
    }
}

/// Mean occlusion of `visibility` over the image columns `columns`.
pub fn strip_occlusion(visibility: &[f32], columns: std::ops::Range<u32>) -> f32 {
    crate::harness::band(visibility, columns)
}

/// The proxies of every mesh but the floor (whose proxy is larger than 5 m) as they are now, and
/// those meshes' triangles as they are drawn.
pub fn model_proxies(world: &mut World) -> (Vec<OccluderSphere>, TriangleScene) {
    let occluders: Vec<(Entity, OccluderSpheres)> = world
        .query::<(Entity, &OccluderSpheres)>()
        .iter(world)
        .map(|(e, o)| (e, o.clone()))
        .filter(|(_, o)| o.spheres.iter().all(|p| p.radius < 5.0))
        .collect();
    let keep: Vec<Entity> = occluders.iter().map(|(e, _)| *e).collect();
    let model = posed_triangles_of(world, |e| keep.contains(&e));
    let proxies = occluders.into_iter().flat_map(|(_, o)| o.spheres).collect();
    (proxies, model)
}

/// Floor points (1 mm up) on a 20 × 20 grid over the model's bounds grown by 0.5 m, less those
/// under the model: the receivers its proxies are judged on.
pub fn floor_points_around(model: &TriangleScene, bvh: &Bvh) -> Vec<Vec3> {
    let (lo, hi) = model.bounds();
    (0..400)
        .map(|i| {
            let (u, v) = ((i % 20) as f32 / 19.0, (i / 20) as f32 / 19.0);
            Vec3::new(
                lo.x - 0.5 + u * (hi.x - lo.x + 1.0),
                1e-3,
                lo.z - 0.5 + v * (hi.z - lo.z + 1.0),
            )
        })
        .filter(|&p| !bvh.any_hit(p, Vec3::Y, 0.0, f32::INFINITY))
        .collect()
}

/// The occlusion a skinned mesh's `proxies` cast within `reach` on a floor point facing up: the
/// product of their visibilities, the largest single one, and their union as compose takes it.
pub fn proxies_on_floor(proxies: &[OccluderSphere], p: Vec3, reach: f32) -> [f32; 3] {
    let (mut open, mut largest) = (1.0, 0.0f32);
    for q in proxies {
        let o = proxy_occlusion(q, p, Vec3::Y, reach).clamp(0.0, 1.0);
        open *= 1.0 - o;
        largest = largest.max(o);
    }
    [
        1.0 - open,
        largest,
        occluder_union([0.0, 1.0 - open], open, largest)[1],
    ]
}

/// Scenes for the voxel term as a user sets them up, each with the folder its model loads from:
/// the room corner, a box and a wall just off-screen, the walker on a floor, and where
/// `../shared/assets` is present CesiumMan and the CornellBox on a floor and CesiumMan just
/// outside the view.
pub fn voxel_scenes() -> Vec<(FarScene, Option<String>)> {
    let mut scenes: Vec<(FarScene, Option<String>)> = procedural()
        .into_iter()
        .filter(|s| ["room corner", "box beside view", "wall beside view"].contains(&s.name))
        .map(|s| (s, None))
        .collect();
    scenes.push((walker_on_floor(), None));
    if let Some(shared) = crate::models::shared_assets() {
        let wanted = [
            "CesiumMan on floor",
            "CornellBox on floor",
            "CesiumMan beside view",
        ];
        for scene in third_party() {
            if wanted.contains(&scene.name) {
                scenes.push((scene, shared.to_str().map(str::to_owned)));
            }
        }
    }
    scenes
}

/// Every AO field occluder's data and the transform that places it in the world.
pub fn placed_fields(gpu: &mut Gpu) -> Vec<(AoFieldData, Affine3A)> {
    let world = gpu.app.world_mut();
    let mut query = world.query::<(&ActiveAoField, &GlobalTransform)>();
    let placed: Vec<_> = query
        .iter(world)
        .map(|(active, transform)| {
            // A baked field lies in the mesh's space scaled to the world's size.
            let placement = transform.affine() * Affine3A::from_scale(active.baked_scale.recip());
            (active.field.id(), placement)
        })
        .collect();
    let fields = world.resource::<Assets<AoFieldData>>();
    placed
        .into_iter()
        .map(|(id, placement)| (fields.get(id).expect("a baked field").clone(), placement))
        .collect()
}

/// Every mesh's sphere occluders as they are now.
pub fn spheres_of(gpu: &mut Gpu) -> Vec<OccluderSpheres> {
    let world = gpu.app.world_mut();
    world
        .query::<&OccluderSpheres>()
        .iter(world)
        .cloned()
        .collect()
}

/// Visibility at every pixel of `frame` from the CPU twin of the sphere splat and compose, the
/// near field off, every proxy of `occluders` counting within `radius`.
pub fn cpu_sphere_visibility(
    frame: &Frame,
    occluders: &[OccluderSpheres],
    radius: f32,
) -> Vec<f32> {
    let camera = ProxyCamera {
        radius,
        near_radius: 0.0,
        use_back: false,
    };
    far_field_occlusion(&frame.nd, &frame.view, occluders, &camera)
        .into_iter()
        .map(|o| 1.0 - o.min(1.0))
        .collect()
}
