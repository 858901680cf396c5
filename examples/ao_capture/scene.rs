//! Loading the scene: the glTF file's first camera becomes the capture's, with the AO settings
//! the options ask for, every mesh an occluder of the chosen far-field term, and the first
//! animation posed at `--time`.

use bevy::camera::RenderTarget;
use bevy::gltf::{Gltf, GltfAssetLabel};
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::world_serialization::{WorldAssetRoot, WorldInstanceReady};
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::settings::DEFAULT_SMALL_VIEWPORT_PIXELS;

use crate::options::FarTerm;
use crate::{Capture, Stage, compare, undrawable};

pub fn load_scene(mut commands: Commands, assets: Res<AssetServer>, mut capture: ResMut<Capture>) {
    capture.gltf = assets.load(capture.file.clone());
    capture.scene = assets.load(GltfAssetLabel::Scene(0).from_asset(capture.file.clone()));
    let root = commands
        .spawn(WorldAssetRoot(capture.scene.clone()))
        .observe(scene_ready)
        .id();
    capture.root = Some(root);
}

/// Once the scene is spawned: pick its first camera, point it at our image, pose the animation.
fn scene_ready(
    ready: On<WorldInstanceReady>,
    mut commands: Commands,
    mut capture: ResMut<Capture>,
    children: Query<&Children>,
    cameras: Query<Option<&Projection>, With<Camera3d>>,
    transforms: Query<(&Transform, Option<&ChildOf>)>,
    meshes: Query<(
        &Mesh3d,
        Option<&Name>,
        Has<bevy::mesh::skinning::SkinnedMesh>,
    )>,
    mesh_assets: Res<Assets<Mesh>>,
    players: Query<Entity, With<AnimationPlayer>>,
    gltfs: Res<Assets<Gltf>>,
    mut graphs: ResMut<Assets<AnimationGraph>>,
    mut images: ResMut<Assets<Image>>,
) {
    // Depth-first in node order: the first camera of the glTF file.
    let mut stack = vec![ready.entity];
    let mut found = Vec::new();
    while let Some(entity) = stack.pop() {
        if cameras.contains(entity) {
            found.push(entity);
        }
        if let Ok(kids) = children.get(entity) {
            stack.extend(kids.iter().rev());
        }
    }
    let Some((&camera, others)) = found.split_first() else {
        capture.failure = Some(format!("{} has no camera", capture.options.scene.display()));
        return;
    };
    if undrawable::unplaceable(camera, &transforms) {
        capture.failure = Some(format!(
            "{}: the first camera's node has a zero scale or a value that is not finite in its \
             transform (or in an ancestor's), so it has no view direction",
            capture.options.scene.display()
        ));
        return;
    }
    undrawable::leave_out_undrawable(
        &mut commands,
        ready.entity,
        &children,
        &meshes,
        &mesh_assets,
    );
    for &other in others {
        commands.entity(other).insert(Camera {
            is_active: false,
            ..default()
        });
    }
    let options = &capture.options;
    let size = UVec2::new(options.width, options.height);
    let target = images.add(Image::new_target_texture(
        size.x,
        size.y,
        TextureFormat::Rgba8UnormSrgb,
        None,
    ));
    let readback = AoReadback::new(&mut images, size);
    if let Some(out) = options.compare.clone() {
        let projection = cameras
            .get(camera)
            .ok()
            .flatten()
            .cloned()
            .unwrap_or_default();
        capture.compare = Some(compare::Compare::spawn_peers(
            &mut commands,
            &mut images,
            camera,
            projection,
            target.clone(),
            size,
            compare::lit(),
            out,
        ));
    }
    let options = &capture.options;
    commands.entity(camera).insert((
        compare::lit(),
        RenderTarget::Image(target.into()),
        Msaa::from_samples(options.msaa),
        DynamicAo {
            technique: options.technique,
            radius: options.radius,
            blur: AoBlur {
                radius: options.blur,
                accumulated_radius: options.accumulated_blur,
                voxel_accumulated_radius: options.voxel_accumulated_blur,
                sharpness: options.blur_sharpness,
                normal_sharpness: options.blur_normal_sharpness,
                detail_reach: options.blur_detail,
            },
            ray_march: RayMarchParams {
                thickness: options.thickness,
                ..options.preset.ray_march()
            },
            half_resolution: options.half_resolution
                || (options.default_technique && options.preset.half_resolution()),
            // `--half-res` asks for it at every size; the default keeps small viewports at full
            // resolution, as `DynamicAo::default()` does.
            small_viewport_pixels: if options.half_resolution {
                0
            } else {
                DEFAULT_SMALL_VIEWPORT_PIXELS
            },
            spheres: options.far == Some(FarTerm::Spheres),
            fields: options.far == Some(FarTerm::Fields),
            voxels: options.far == Some(FarTerm::Voxels),
            far_field_blend: options.far_blend,
            near_field_radius: options.near_field_radius,
            temporal: options.temporal,
            coarse_back_faces: !options.full_back_faces,
            // Every technique's budget at the chosen level.
            ..DynamicAo::from_preset(options.preset)
        },
        readback.clone(),
    ));
    if let Some(term @ (FarTerm::Fields | FarTerm::Spheres)) = options.far {
        // Every mesh of the scene an occluder (fields are baked on load, or read from the disk
        // cache, each in its mesh's own space).
        let scene_meshes: Vec<Entity> = children
            .iter_descendants(ready.entity)
            .filter(|e| {
                meshes.get(*e).is_ok_and(|(mesh, _, _)| {
                    mesh_assets
                        .get(&mesh.0)
                        .is_none_or(|m| undrawable::why_undrawable(m).is_none())
                })
            })
            .collect();
        term.attach(&mut commands, &scene_meshes, (Vec3::ZERO, Vec3::ZERO), 0.0);
    }
    capture.readback = Some(readback);

    if let Some(clip) = gltfs
        .get(&capture.gltf)
        .and_then(|gltf| gltf.animations.first().cloned())
    {
        let (graph, node) = AnimationGraph::from_clip(clip);
        let graph = graphs.add(graph);
        let time = capture.options.time;
        for player in &players {
            commands
                .entity(player)
                .insert(AnimationGraphHandle(graph.clone()));
            commands.queue(move |world: &mut World| {
                if let Some(mut player) = world.get_mut::<AnimationPlayer>(player) {
                    player.play(node).seek_to(time).pause();
                }
            });
        }
    }
    capture.stage = Stage::Rendering { until: None };
    capture.stage_start = capture.frames;
}
