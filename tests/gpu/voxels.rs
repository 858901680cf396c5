//! Voxel volumes: the GPU grid against a CPU triangle–cell voxelization, the GPU AO against the
//! CPU evaluation of the same rays on the same grid, occluders the depth buffer misses against
//! ground truth, stability under a moving camera, and bad volumes.

use std::sync::{Arc, Mutex};

use bevy::asset::RenderAssetUsages;
use bevy::camera::visibility::NoFrustumCulling;
use bevy::math::Affine3A;
use bevy::mesh::skinning::SkinnedMesh;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::storage::ShaderBuffer;
use bevy_dynamic_ao::geometry::{
    closed::is_closed,
    triangles::{Triangle, TriangleScene},
};
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    filter::{cross_bilateral_blur, joint_bilateral_upsample_pair},
    metrics::rmse,
    voxels::{VoxelCamera, VoxelGrid, voxel_ao_map, voxelize},
};
use bevy_dynamic_ao::voxels::{VoxelFalloff, VoxelGridInfo, VoxelGridReadback, VoxelMarch};

use crate::harness::{Frame, Gpu, SceneSpec, WIDTH, band, difference_stats, plain_ao};
use crate::scenes;
use crate::skinned::{LENGTH, column, column_bindposes};

/// Voxel volumes alone, no image-space term.
fn voxels_only() -> DynamicAo {
    DynamicAo {
        technique: AoTechnique::Off,
        spheres: false,
        fields: false,
        ..plain_ao()
    }
}

fn spawn_volume(gpu: &mut Gpu, transform: Transform, volume: VoxelAoVolume) -> Entity {
    gpu.app.world_mut().spawn((transform, volume)).id()
}

/// Every volume's grid as the GPU built it on the last frame, in entity order.
fn read_grids(gpu: &mut Gpu, volumes: &[Entity]) -> Vec<(VoxelGridInfo, VoxelGrid)> {
    gpu.update(1);
    let infos: Vec<VoxelGridInfo> = volumes
        .iter()
        .map(|&v| {
            *gpu.app
                .world()
                .get::<VoxelGridInfo>(v)
                .expect("the volume is in use")
        })
        .collect();
    // Surface bits of every grid, then interior bits.
    let words: u32 = 2 * infos
        .iter()
        .map(|i| i.offset + i.words())
        .max()
        .unwrap_or(1);
    let world = gpu.app.world_mut();
    let buffer = world
        .resource_mut::<Assets<ShaderBuffer>>()
        .add(ShaderBuffer::with_size(
            words as usize * 4,
            RenderAssetUsages::RENDER_WORLD,
        ));
    world.insert_resource(VoxelGridReadback(buffer.clone()));
    // The copy needs the buffer on the GPU first.
    gpu.update(2);
    let data: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
    let slot = data.clone();
    let reader = gpu
        .app
        .world_mut()
        .spawn(Readback::buffer(buffer))
        .observe(move |done: On<ReadbackComplete>| {
            slot.lock()
                .unwrap()
                .get_or_insert_with(|| done.data.clone());
        })
        .id();
    for _ in 0..60 {
        gpu.update(1);
        if data.lock().unwrap().is_some() {
            break;
        }
    }
    gpu.app.world_mut().despawn(reader);
    gpu.app.world_mut().remove_resource::<VoxelGridReadback>();
    let bytes = data
        .lock()
        .unwrap()
        .take()
        .expect("the grid read-back completed");
    let all: Vec<u32> = bytes
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    infos
        .into_iter()
        .map(|info| {
            let (start, solid) = (info.offset as usize, info.solid_offset as usize);
            let count = info.words() as usize;
            let grid = VoxelGrid {
                resolution: info.resolution,
                grid_from_world: info.grid_from_world,
                words: all[start..start + count].to_vec(),
                solid: all[solid..solid + count].to_vec(),
            };
            (info, grid)
        })
        .collect()
}

/// Cells set in one grid and not the other, cells set in either, and how many of the differing
/// cells have no occupied neighbour in `cpu` (a difference away from any surface).
fn compare_grids(gpu: &VoxelGrid, cpu: &VoxelGrid) -> (u32, u32, u32) {
    let n = gpu.resolution as i32;
    let (mut differ, mut union, mut interior) = (0, 0, 0);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let (g, c) = (gpu.occupied([x, y, z]), cpu.occupied([x, y, z]));
                union += u32::from(g || c);
                if g != c {
                    differ += 1;
                    let near_surface = (-1..=1).any(|dz| {
                        (-1..=1).any(|dy| {
                            (-1..=1).any(|dx| {
                                (dx, dy, dz) != (0, 0, 0) && cpu.occupied([x + dx, y + dy, z + dz])
                            })
                        })
                    });
                    interior += u32::from(!near_surface);
                }
            }
        }
    }
    (differ, union, interior)
}

/// Each mesh's world-space triangles.
fn mesh_triangles(meshes: &[(Mesh, Affine3A)]) -> Vec<Vec<Triangle>> {
    meshes
        .iter()
        .map(|(mesh, transform)| {
            let mut triangles = TriangleScene::default();
            triangles.add_mesh(mesh, *transform);
            triangles.triangles
        })
        .collect()
}

/// The CPU voxelization of `meshes` into the grid `info` describes: surfaces, and the interior
/// of the closed ones.
fn cpu_grid(meshes: &[Vec<Triangle>], info: &VoxelGridInfo) -> VoxelGrid {
    let all: Vec<Triangle> = meshes.concat();
    let mut grid = voxelize(&all, info.resolution, info.grid_from_world);
    for mesh in meshes {
        if is_closed(mesh.iter().map(|t| t.vertices)) {
            grid.fill_closed(mesh);
        }
    }
    grid
}

fn assert_grids_agree(what: &str, gpu: &VoxelGrid, cpu: &VoxelGrid) {
    let (differ, union, interior) = compare_grids(gpu, cpu);
    println!(
        "{what}: {} GPU cells, {} CPU cells, {differ} differ of {union} occupied in either",
        gpu.count(),
        cpu.count()
    );
    assert!(cpu.count() > 100, "{what}: the scene should fill cells");
    assert!(
        differ * 100 <= union,
        "{what}: {differ} of {union} cells differ"
    );
    assert_eq!(interior, 0, "{what}: differences away from any surface");
}

#[test]
fn gpu_voxelization_matches_a_cpu_triangle_cell_voxelization() {
    let scene = scenes::cube_on_plane()
        .with(
            Sphere::new(0.45).mesh().uv(32, 16),
            Transform::from_xyz(-1.2, 0.45, 0.4),
        )
        .with(
            Cuboid::new(0.6, 0.3, 0.9),
            Transform::from_xyz(1.0, 0.4, -0.8).with_rotation(Quat::from_euler(
                EulerRot::XYZ,
                0.4,
                0.7,
                0.2,
            )),
        )
        // Thin, large closed occluders that reach past both volumes: a wall across every
        // column of the grids' z axis and a slab under the floor.
        .with(
            Cuboid::new(8.0, 4.0, 0.1),
            Transform::from_xyz(0.0, 1.0, -1.3),
        )
        .with(
            Cuboid::new(8.0, 0.1, 8.0),
            Transform::from_xyz(0.0, -0.3, 0.0),
        );
    let mut gpu = Gpu::new(&scene, voxels_only());
    // A turned volume and a second, coarser one overlapping it: several grids per frame. 64³
    // layers fill whole 32-bit words and 22³ ones do not, the two ways the interior is filled.
    let turned = spawn_volume(
        &mut gpu,
        Transform::from_xyz(0.0, 0.6, 0.0).with_rotation(Quat::from_rotation_y(0.5)),
        VoxelAoVolume {
            half_extents: Vec3::new(2.0, 1.0, 1.8),
            resolution: 64,
            ..default()
        },
    );
    let coarse = spawn_volume(
        &mut gpu,
        Transform::from_xyz(0.5, 0.5, 0.5),
        VoxelAoVolume {
            half_extents: Vec3::splat(1.5),
            resolution: 22,
            ..default()
        },
    );
    // A ball that asks to stay out of the grids; the CPU voxelization leaves it out too.
    let world = gpu.app.world_mut();
    let ball = world
        .resource_mut::<Assets<Mesh>>()
        .add(Sphere::new(0.3).mesh().ico(2).unwrap());
    world.spawn((
        Mesh3d(ball),
        Transform::from_xyz(0.8, 1.2, 0.8),
        bevy_dynamic_ao::voxels::NotVoxelOccluder,
    ));
    gpu.update(2);
    let meshes = mesh_triangles(
        &scene
            .meshes
            .iter()
            .map(|(m, t)| (m.clone(), t.compute_affine()))
            .collect::<Vec<_>>(),
    );
    for (name, (info, grid)) in ["turned 64³", "coarse 22³"]
        .into_iter()
        .zip(read_grids(&mut gpu, &[turned, coarse]))
    {
        let cpu = cpu_grid(&meshes, &info);
        let surface_only = voxelize(&meshes.concat(), info.resolution, info.grid_from_world);
        assert!(
            cpu.count() > surface_only.count(),
            "{name}: closed meshes should be filled"
        );
        assert!(info.triangles > 0);
        assert_grids_agree(name, &grid, &cpu);
    }
}

#[test]
fn a_skinned_mesh_is_voxelized_in_its_pose() {
    let mut gpu = Gpu::new(
        &SceneSpec::new(Transform::from_xyz(0.0, 0.7, 2.2)),
        voxels_only(),
    );
    let world = gpu.app.world_mut();
    let bindposes = column_bindposes(world);
    let mesh = column();
    let handle = world.resource_mut::<Assets<Mesh>>().add(mesh.clone());
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    let bend = Quat::from_rotation_z(-0.8);
    let root = world.spawn(Transform::IDENTITY).id();
    let elbow = world
        .spawn((
            Transform::from_xyz(0.0, LENGTH / 2.0, 0.0).with_rotation(bend),
            ChildOf(root),
        ))
        .id();
    world.spawn((
        Mesh3d(handle),
        MeshMaterial3d(material),
        SkinnedMesh {
            inverse_bindposes: bindposes,
            joints: vec![root, elbow],
        },
        NoFrustumCulling,
        Transform::IDENTITY,
    ));
    let volume = spawn_volume(
        &mut gpu,
        Transform::from_xyz(0.3, 0.7, 0.0),
        VoxelAoVolume {
            half_extents: Vec3::new(0.8, 0.8, 0.4),
            resolution: 48,
            ..default()
        },
    );
    gpu.update(3);
    let (info, grid) = read_grids(&mut gpu, &[volume]).remove(0);
    // The pose, worked out by hand: the upper half turns about the elbow.
    let elbow_pose = Affine3A::from_translation(Vec3::Y * (LENGTH / 2.0))
        * Affine3A::from_quat(bend)
        * Affine3A::from_translation(-Vec3::Y * (LENGTH / 2.0));
    let mut posed = mesh.clone();
    if let Some(bevy::mesh::VertexAttributeValues::Float32x3(positions)) =
        posed.attribute_mut(Mesh::ATTRIBUTE_POSITION)
    {
        for p in positions.iter_mut() {
            if p[1] > LENGTH / 2.0 + 1e-4 {
                *p = elbow_pose.transform_point3(Vec3::from(*p)).to_array();
            }
        }
    }
    let cpu = cpu_grid(&mesh_triangles(&[(posed, Affine3A::IDENTITY)]), &info);
    let unbent = cpu_grid(&mesh_triangles(&[(mesh, Affine3A::IDENTITY)]), &info);
    assert_grids_agree("bent column", &grid, &cpu);
    let (differ_rest, ..) = compare_grids(&grid, &unbent);
    assert!(
        differ_rest > 100,
        "the grid should follow the bend, not the rest pose ({differ_rest} cells differ)"
    );
}

/// The CPU twin of the whole voxel path for one frame: sampling on the GPU's own grids,
/// upsampling, blur, and visibility as compose writes it.
fn cpu_voxel_visibility(
    frame: &Frame,
    grids: &[(VoxelGridInfo, VoxelGrid)],
    ao: &DynamicAo,
) -> Vec<f32> {
    let volumes: Vec<_> = grids
        .iter()
        .map(|(info, grid)| (grid.clone(), info.rays))
        .collect();
    // The voxels alone count every hit within the camera's radius: all in the second channel.
    let camera = VoxelCamera {
        radius: ao.effective_radius(),
        count_once: None,
    };
    let low = voxel_ao_map(&frame.nd, &frame.view, &volumes, &camera);
    let full = joint_bilateral_upsample_pair(&low, &frame.nd, &frame.view, ao.effective_radius());
    let rest: Vec<f32> = full.iter().map(|[_, rest]| *rest).collect();
    let blur = ao.blur.sanitized();
    let filtered = if blur.radius > 0 {
        cross_bilateral_blur(&rest, &frame.nd, &frame.view, blur.radius, blur.sharpness)
    } else {
        rest
    };
    filtered.iter().map(|o| 1.0 - o.clamp(0.0, 1.0)).collect()
}

#[test]
fn gpu_voxel_ao_matches_the_cpu_evaluation_of_the_same_rays() {
    let scene = scenes::room_corner();
    for blur in [0, 4] {
        let ao = DynamicAo {
            blur: AoBlur {
                radius: blur,
                ..default()
            },
            ..voxels_only()
        };
        let mut gpu = Gpu::new(&scene, ao.clone());
        let volume = spawn_volume(
            &mut gpu,
            Transform::from_xyz(-0.5, 1.0, -0.5),
            VoxelAoVolume {
                half_extents: Vec3::new(2.0, 1.3, 2.0),
                resolution: 96,
                rays: 16,
                d_max: Some(1.5),
                ..default()
            },
        );
        gpu.update(2);
        let frame = gpu.frame(2);
        let grids = read_grids(&mut gpu, &[volume]);
        let cpu = cpu_voxel_visibility(&frame, &grids, &ao);
        let mask = frame.geometry_mask();
        let (mean, p99) = difference_stats(&frame.visibility, &cpu, &mask);
        let darkest = cpu.iter().copied().fold(1.0, f32::min);
        println!(
            "voxel AO, blur {blur}: darkest {darkest:.3}; GPU vs CPU mean |diff| {mean:.5}, 99th \
             percentile {p99:.5}"
        );
        assert!(darkest < 0.7, "the corner should be occluded");
        // A ray that grazes a cell boundary can take the other cell on one side: one ray of 16
        // is about 0.06 of a texel.
        assert!(mean < 0.003 && p99 < 0.07, "{mean} {p99}");
    }
}

/// Under temporal accumulation the voxel rays turn every frame, and the accumulated term
/// approaches the CPU evaluation of the same volume with 16 times the rays (what averaging many
/// turned 4-ray patterns estimates); a reset drops the history.
#[test]
fn the_voxel_term_accumulates_toward_many_rays() {
    let scene = scenes::room_corner();
    let ao = |temporal: AoTemporal| DynamicAo {
        blur: AoBlur::OFF,
        temporal,
        ..voxels_only()
    };
    let mut gpu = Gpu::new(&scene, ao(AoTemporal::OFF));
    let volume = spawn_volume(
        &mut gpu,
        Transform::from_xyz(-0.5, 1.0, -0.5),
        VoxelAoVolume {
            half_extents: Vec3::new(2.0, 1.3, 2.0),
            resolution: 96,
            rays: 4,
            ..default()
        },
    );
    gpu.update(2);
    let single = gpu.frame(2);
    let mut grids = read_grids(&mut gpu, &[volume]);
    grids[0].0.rays.rays = 64;
    let many = cpu_voxel_visibility(&single, &grids, &ao(AoTemporal::OFF));
    let mask = single.geometry_mask();
    let error_single = rmse(&single.visibility, &many, Some(&mask));

    gpu.set_ao(|a| *a = ao(AoTemporal::ON));
    let errors: Vec<f32> = [1, 7, 24]
        .into_iter()
        .map(|frames| rmse(&gpu.frame(frames).visibility, &many, Some(&mask)))
        .collect();
    println!(
        "voxel term, RMSE against 64 rays on the CPU: one frame of 4 rays {error_single:.4}, \
         accumulated {errors:?}"
    );
    // Measured: one frame 0.068, then 0.043, 0.013, 0.010.
    let converged = errors[2];
    assert!(errors[1] < 0.4 * errors[0], "the error falls: {errors:?}");
    assert!(
        converged < 0.2 * error_single,
        "accumulated {converged:.4} vs one frame {error_single:.4}"
    );
    gpu.set_ao(|a| a.temporal.reset = true);
    let cut = rmse(&gpu.frame(0).visibility, &many, Some(&mask));
    println!("voxel term, RMSE on the frame after a reset: {cut:.4}");
    assert!(cut > 0.8 * error_single, "after a reset {cut:.4}");
}

/// Occlusion a technique adds to the image columns `strip` against the columns `other`, and its
/// RMSE against ground truth.
#[derive(Clone, Copy, Debug)]
struct Measured {
    strip: f32,
    rmse: f32,
}

/// Ground truth, near field + voxels (the defaults, and the paper's Wendland falloff and
/// 8-step march), near field alone and Bevy's SSAO.
struct Comparison {
    truth: Measured,
    voxels: Measured,
    wendland: Measured,
    steps: Measured,
    near: Measured,
    bevy: Measured,
}

fn against_truth(
    scene: &SceneSpec,
    transform: Transform,
    volume: VoxelAoVolume,
    strip: std::ops::Range<u32>,
    other: std::ops::Range<u32>,
    radius: f32,
) -> Comparison {
    let mut gpu = Gpu::new(scene, plain_ao().with_radius(radius));
    let entity = spawn_volume(&mut gpu, transform, volume);
    gpu.set_ao(|ao| ao.voxels = false);
    // The first frames of an app still show Bevy's SSAO: the view's AO state is prepared from
    // the second frame on.
    let near = gpu.frame(10);
    gpu.set_ao(|ao| ao.voxels = true);
    let voxels = gpu.frame(3);
    let set = |gpu: &mut Gpu, change: fn(&mut VoxelAoVolume)| {
        change(
            &mut gpu
                .app
                .world_mut()
                .get_mut::<VoxelAoVolume>(entity)
                .unwrap(),
        );
        gpu.frame(3)
    };
    let wendland = set(&mut gpu, |v| v.falloff = VoxelFalloff::Wendland);
    let steps = set(&mut gpu, |v| {
        v.falloff = VoxelFalloff::None;
        v.march = VoxelMarch::Steps(VoxelAoVolume::PAPER_STEPS);
    });
    gpu.set_ao(|ao| ao.technique = AoTechnique::BevySsao);
    let bevy = gpu.frame(3);
    let truth = voxels.ground_truth(&scene.bvh(), radius);
    let mask = voxels.geometry_mask();
    let measure = |v: &[f32]| Measured {
        strip: band(v, strip.clone()) - band(v, other.clone()),
        rmse: rmse(v, &truth, Some(&mask)),
    };
    Comparison {
        truth: measure(&truth),
        voxels: measure(&voxels.visibility),
        wendland: measure(&wendland.visibility),
        steps: measure(&steps.visibility),
        near: measure(&near.visibility),
        bevy: measure(&bevy.visibility),
    }
}

impl Comparison {
    /// Prints the comparison and checks the defaults find the truth's occlusion within `bound`.
    fn report(&self, what: &str, bound: f32) {
        let Self {
            truth,
            voxels,
            wendland,
            steps,
            near,
            bevy,
        } = self;
        println!(
            "{what}: occlusion added to the strip: truth {:.3}, near+voxels {:.3} (Wendland \
             {:.3}, 8 steps {:.3}), near only {:.3}, Bevy SSAO {:.3}; RMSE vs truth: near+voxels \
             {:.4} (Wendland {:.4}, 8 steps {:.4}), near only {:.4}, Bevy SSAO {:.4}",
            truth.strip,
            voxels.strip,
            wendland.strip,
            steps.strip,
            near.strip,
            bevy.strip,
            voxels.rmse,
            wendland.rmse,
            steps.rmse,
            near.rmse,
            bevy.rmse
        );
        assert!(
            truth.strip > 0.05,
            "{what}: the scene should have something to find"
        );
        assert!(
            (voxels.strip - truth.strip).abs() < bound,
            "{what}: voxels {} vs truth {}",
            voxels.strip,
            truth.strip
        );
        assert!(
            voxels.rmse < near.rmse && voxels.rmse < bevy.rmse,
            "{what}: voxels should bring the image closer to the truth"
        );
        // The paper's falloff weights hits down: it finds less than ground truth counts.
        assert!(wendland.strip < voxels.strip - 0.02, "{what}: Wendland");
    }
}

/// A box just outside the view of a camera looking down at the floor.
#[test]
fn an_off_screen_occluder_darkens_the_floor_like_ground_truth() {
    let scene = scenes::box_beside_view();
    let comparison = against_truth(
        &scene,
        Transform::from_xyz(1.0, 0.8, 0.0),
        VoxelAoVolume {
            half_extents: Vec3::new(2.5, 1.0, 2.5),
            resolution: 128,
            ..default()
        },
        WIDTH * 9 / 10..WIDTH,
        0..WIDTH / 10,
        2.0,
    );
    comparison.report("off-screen box", 0.02);
    let Comparison { near, bevy, .. } = comparison;
    assert!(
        near.strip.abs() < 0.02 && bevy.strip.abs() < 0.02,
        "screen space cannot see the box"
    );
}

/// A wall under a floating plate, seen from above: the plate hides the wall from the camera, so
/// the depth buffer holds only the plate, yet the wall darkens the visible floor beside it.
#[test]
fn a_hidden_occluder_darkens_the_floor_like_ground_truth() {
    let scene = SceneSpec::new(Transform::from_xyz(0.0, 3.0, 0.0).looking_at(Vec3::ZERO, -Vec3::Z))
        .with(
            Plane3d::default().mesh().size(10.0, 10.0),
            Transform::IDENTITY,
        )
        .with(
            Cuboid::new(0.9, 0.05, 4.0),
            Transform::from_xyz(-0.6, 1.05, 0.0),
        )
        .with(
            Cuboid::new(0.5, 1.0, 4.0),
            Transform::from_xyz(-0.6, 0.5, 0.0),
        );
    let comparison = against_truth(
        &scene,
        Transform::from_xyz(-0.3, 0.8, 0.0),
        VoxelAoVolume {
            half_extents: Vec3::new(2.2, 1.0, 2.2),
            resolution: 128,
            ..default()
        },
        WIDTH * 44 / 100..WIDTH * 56 / 100,
        WIDTH * 9 / 10..WIDTH,
        1.0,
    );
    comparison.report("wall hidden under a plate", 0.03);
}

/// A slow orbit around a static scene: the jitter is tied to world positions, so frame-to-frame
/// change stays small.
#[test]
fn voxel_ao_is_stable_under_a_slow_orbit() {
    let scene = scenes::room_corner();
    let mut gpu = Gpu::new(&scene, voxels_only());
    spawn_volume(
        &mut gpu,
        Transform::from_xyz(-0.5, 1.0, -0.5),
        VoxelAoVolume {
            half_extents: Vec3::new(2.0, 1.3, 2.0),
            resolution: 128,
            ..default()
        },
    );
    gpu.update(3);
    let start = scene.camera;
    let mut previous: Option<Frame> = None;
    let mut changes = Vec::new();
    for step in 0..6 {
        let angle = step as f32 * 0.5f32.to_radians();
        let camera = Transform::from_translation(Quat::from_rotation_y(angle) * start.translation)
            .looking_at(Vec3::new(-0.5, 0.4, -0.5), Vec3::Y);
        let id = gpu.camera;
        *gpu.app.world_mut().get_mut::<Transform>(id).unwrap() = camera;
        let frame = gpu.frame(2);
        if let Some(previous) = previous {
            let (mut sum, mut n) = (0.0, 0);
            for i in 0..frame.visibility.len() {
                if frame.nd.front[i].depth > 0.0 && previous.nd.front[i].depth > 0.0 {
                    sum += (frame.visibility[i] - previous.visibility[i]).abs();
                    n += 1;
                }
            }
            changes.push(sum / n as f32);
        }
        previous = Some(frame);
    }
    let worst = changes.iter().copied().fold(0.0, f32::max);
    let occlusion = previous
        .map(|f| 1.0 - f.visibility.iter().sum::<f32>() / f.visibility.len() as f32)
        .unwrap_or(0.0);
    println!(
        "orbit 0.5° per frame: mean |Δ visibility| per frame {changes:?}, mean occlusion \
         {occlusion:.4}"
    );
    assert!(occlusion > 0.02, "the scene should be occluded somewhere");
    assert!(
        worst < 0.005 && worst < 0.2 * occlusion,
        "frame-to-frame change {worst}"
    );
}

/// Zero-size, inverted and NaN volumes are skipped, out-of-range settings are clamped, a NaN
/// transform skips its volume; inside a volume, a mesh with a NaN transform, a line mesh and a
/// mesh of degenerate triangles are left out; the frame still renders and a good volume works.
#[test]
fn bad_volumes_are_skipped_or_clamped_without_a_panic() {
    let scene = scenes::cube_on_plane();
    let mut gpu = Gpu::new(&scene, voxels_only());
    let bad = [
        (Transform::IDENTITY, VoxelAoVolume::new(Vec3::ZERO)),
        (
            Transform::IDENTITY,
            VoxelAoVolume::new(Vec3::new(1.0, -1.0, 1.0)),
        ),
        (Transform::IDENTITY, VoxelAoVolume::new(Vec3::NAN)),
        (Transform::from_scale(Vec3::ZERO), VoxelAoVolume::default()),
        (
            Transform::from_xyz(f32::NAN, 0.0, 0.0),
            VoxelAoVolume::default(),
        ),
    ];
    let bad: Vec<Entity> = bad
        .into_iter()
        .map(|(t, v)| spawn_volume(&mut gpu, t, v))
        .collect();
    let clamped = [
        VoxelAoVolume {
            resolution: 0,
            rays: 0,
            march: VoxelMarch::Steps(0),
            spread: -1.0,
            d_max: Some(f32::NAN),
            ..default()
        },
        VoxelAoVolume {
            resolution: 100_000,
            rays: 100_000,
            march: VoxelMarch::Steps(100_000),
            spread: 7.0,
            d_max: Some(-3.0),
            ..VoxelAoVolume::new(Vec3::new(2.5, 1.0, 2.5))
        },
    ];
    // The second lies away from the scene, so its clamped 512³ grid and 256 rays cost little.
    let clamped: Vec<Entity> = clamped
        .into_iter()
        .zip([Vec3::new(0.0, 0.8, 0.0), Vec3::new(50.0, 0.0, 0.0)])
        .map(|(v, at)| spawn_volume(&mut gpu, Transform::from_translation(at), v))
        .collect();
    let world = gpu.app.world_mut();
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::default());
    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let cube = meshes.add(Cuboid::new(0.3, 0.3, 0.3));
    let lines = meshes.add(
        Mesh::new(
            bevy::mesh::PrimitiveTopology::LineList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_POSITION,
            vec![[0.0f32, 0.2, 0.0], [0.5, 0.2, 0.0]],
        ),
    );
    let flat = meshes.add(
        Mesh::new(
            bevy::mesh::PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_POSITION,
            vec![[0.0f32, 0.2, 0.0], [0.5, 0.2, 0.0], [1.0, 0.2, 0.0]],
        )
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vec![[0.0f32, 1.0, 0.0]; 3]),
    );
    world.spawn((
        Mesh3d(cube),
        MeshMaterial3d(material.clone()),
        Transform::from_xyz(f32::NAN, 0.5, 0.0),
    ));
    world.spawn((Mesh3d(lines), Transform::from_xyz(0.5, 0.0, 0.8)));
    world.spawn((
        Mesh3d(flat),
        MeshMaterial3d(material),
        Transform::from_xyz(-0.5, 0.0, 0.8),
    ));
    let frame = gpu.frame(3);
    let world = gpu.app.world();
    for entity in bad {
        assert!(world.get::<VoxelGridInfo>(entity).is_none());
    }
    let resolutions: Vec<u32> = clamped
        .iter()
        .map(|&e| {
            world
                .get::<VoxelGridInfo>(e)
                .expect("clamped, in use")
                .resolution
        })
        .collect();
    assert_eq!(
        resolutions,
        [VoxelAoVolume::MIN_RESOLUTION, VoxelAoVolume::MAX_RESOLUTION]
    );
    let rays = world.get::<VoxelGridInfo>(clamped[1]).unwrap().rays;
    assert_eq!(
        (rays.rays, rays.march, rays.d_max),
        (
            VoxelAoVolume::MAX_RAYS,
            VoxelMarch::Steps(VoxelAoVolume::MAX_STEPS),
            None
        )
    );
    assert!(frame.visibility.iter().all(|v| v.is_finite()));
    let mask = frame.geometry_mask();
    let mean = frame.visibility.iter().sum::<f32>() / frame.visibility.len() as f32;
    assert!(mean > 0.7 && mean < 1.0, "mean visibility {mean}");
    assert!(mask.iter().any(|m| *m));
}
