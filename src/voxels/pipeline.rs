//! The pipelines of the voxelization and sampling passes and their per-view bind groups.

use crate::nd_buffer::{FrontLayer, FrontLayerViews};
use bevy::asset::load_embedded_asset;
use bevy::ecs::prelude::*;
use bevy::render::{
    render_resource::{
        binding_types::{
            storage_buffer_read_only_sized, storage_buffer_sized, texture_2d, texture_depth_2d,
            texture_storage_2d, uniform_buffer,
        },
        *,
    },
    renderer::RenderDevice,
    view::{ViewUniform, ViewUniforms},
};
use bevy::utils::default;

use super::buffers::{VoxelBuffers, VoxelParams};
use super::view::{VoxelHistory, VoxelTextures};
use crate::filter::{BlurBindGroups, BlurPipelines, FilterInputs};
use crate::temporal::{AccumulationTextures, Channels, TemporalPipeline};
use crate::view::OCCLUSION_PAIR_FORMAT;
use crate::view::{
    DynamicAoTextures, DynamicAoUniform, DynamicAoView, FarFieldOutputs, FarTerm, ViewBindings,
};

/// The voxelization and sampling pipelines.
#[derive(Resource)]
pub(crate) struct VoxelPipelines {
    voxelize_layout: BindGroupLayoutDescriptor,
    sample_layout: BindGroupLayoutDescriptor,
    pub voxelize: CachedComputePipelineId,
    /// Carries the interior flips of closed meshes up their columns (`voxelize.wgsl`).
    pub fill_interior: CachedComputePipelineId,
    /// Sets the bits of the bricks that hold an occupied cell (`voxelize.wgsl`).
    pub mark_bricks: CachedComputePipelineId,
    pub sample: CachedComputePipelineId,
}

impl FromWorld for VoxelPipelines {
    fn from_world(world: &mut World) -> Self {
        let voxelize_layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_voxelize_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    storage_buffer_read_only_sized(false, None),
                    storage_buffer_read_only_sized(false, None),
                    storage_buffer_sized(false, None),
                    uniform_buffer::<VoxelParams>(false),
                ),
            ),
        );
        let sample_layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_voxel_ao_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    uniform_buffer::<ViewUniform>(true),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    storage_buffer_read_only_sized(false, None),
                    storage_buffer_read_only_sized(false, None),
                    texture_storage_2d(OCCLUSION_PAIR_FORMAT, StorageTextureAccess::WriteOnly),
                    uniform_buffer::<VoxelParams>(false),
                    uniform_buffer::<DynamicAoUniform>(true),
                    texture_depth_2d(),
                ),
            ),
        );
        let cache = world.resource::<PipelineCache>();
        // Two entry points of one shader on the same bindings.
        let voxelize_step = |label: &str, entry: &str| {
            cache.queue_compute_pipeline(ComputePipelineDescriptor {
                label: Some(label.to_string().into()),
                layout: vec![voxelize_layout.clone()],
                shader: load_embedded_asset!(world, "voxelize.wgsl"),
                entry_point: Some(entry.to_string().into()),
                ..default()
            })
        };
        let voxelize = voxelize_step("dynamic_ao_voxelize_pipeline", "voxelize");
        let fill_interior = voxelize_step("dynamic_ao_fill_interior_pipeline", "fill_interior");
        let mark_bricks = voxelize_step("dynamic_ao_mark_bricks_pipeline", "mark_bricks");
        let sample = cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some("dynamic_ao_voxel_ao_pipeline".into()),
            layout: vec![sample_layout.clone()],
            shader: load_embedded_asset!(world, "voxel_ao.wgsl"),
            ..default()
        });
        Self {
            voxelize_layout,
            sample_layout,
            voxelize,
            fill_interior,
            mark_bricks,
            sample,
        }
    }
}

/// Per view: sampling into the half-size map, upsampling to full size, and the two blur passes.
#[derive(Component)]
pub(crate) struct VoxelBindGroups {
    pub sample: BindGroup,
    /// The temporal accumulation of the half-size map; `None` without it.
    pub temporal: Option<BindGroup>,
    pub upsample: BindGroup,
    /// X and Y passes; `None` when the blur is off.
    pub blur: Option<BlurBindGroups>,
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn prepare_voxel_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    mut buffers: ResMut<VoxelBuffers>,
    pipelines: Res<VoxelPipelines>,
    blur: Res<BlurPipelines>,
    pipeline_cache: Res<PipelineCache>,
    bindings: ViewBindings,
    views: Query<(
        Entity,
        &DynamicAoView,
        &DynamicAoTextures,
        (Option<&VoxelTextures>, Option<&VoxelHistory>),
        &FarFieldOutputs,
        FrontLayer,
    )>,
    temporal: (Res<TemporalPipeline>, Res<ViewUniforms>),
) {
    let (temporal_pipeline, view_uniforms) = temporal;
    let buffers = buffers.as_mut();
    let (Some(triangles), Some(volumes), Some(params), Some(grid)) = (
        buffers.triangles.buffer(),
        buffers.volumes.buffer(),
        buffers.params.binding(),
        buffers.grid.as_ref(),
    ) else {
        return;
    };
    buffers.voxelize_bind_group = Some(render_device.create_bind_group(
        "dynamic_ao_voxelize_bind_group",
        &pipeline_cache.get_bind_group_layout(&pipelines.voxelize_layout),
        &BindGroupEntries::sequential((
            triangles.as_entire_binding(),
            volumes.as_entire_binding(),
            grid.as_entire_binding(),
            params.clone(),
        )),
    ));
    let Some((view_binding, settings_binding)) = bindings.get() else {
        return;
    };
    for (entity, view, textures, (voxel_textures, history), outputs, prepass) in &views {
        let (true, Some(voxel_textures), Some(full), Some(depth), Some(normal)) = (
            view.has(FarTerm::Voxels),
            voxel_textures,
            outputs.get(FarTerm::Voxels),
            prepass.depth(),
            prepass.normal(),
        ) else {
            commands.entity(entity).remove::<VoxelBindGroups>();
            continue;
        };
        let sample = render_device.create_bind_group(
            "dynamic_ao_voxel_ao_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipelines.sample_layout),
            &BindGroupEntries::sequential((
                view_binding.clone(),
                depth,
                normal,
                volumes.as_entire_binding(),
                grid.as_entire_binding(),
                &voxel_textures.low.default_view,
                params.clone(),
                settings_binding.clone(),
                &textures.back_depth.default_view,
            )),
        );
        let temporal =
            history
                .zip(voxel_textures.accumulated.as_ref())
                .and_then(|(history, accumulated)| {
                    temporal_pipeline.bind_group(
                        &render_device,
                        &pipeline_cache,
                        &view_uniforms,
                        Channels::Pair,
                        &history.0,
                        AccumulationTextures {
                            current: &voxel_textures.low.default_view,
                            output: &accumulated.default_view,
                            front: FrontLayerViews {
                                depth,
                                normal,
                                motion_vectors: prepass.motion_vectors(),
                            },
                        },
                    )
                });
        let inputs = FilterInputs {
            view: view_binding.clone(),
            settings: settings_binding.clone(),
            depth,
            // The voxel blur weighs by depth alone: any float texture stands in for the normals.
            normal: &voxel_textures.low.default_view,
        };
        let upsample = blur.two.upsample_bind_group(
            &render_device,
            &pipeline_cache,
            "dynamic_ao_voxel_upsample_bind_group",
            &inputs,
            normal,
            [&voxel_textures.upsampled().default_view, &full.default_view],
        );
        let blur = voxel_textures.scratch.as_ref().map(|scratch| {
            blur.two.blur_bind_groups(
                &render_device,
                &pipeline_cache,
                ["dynamic_ao_voxel_blur_x", "dynamic_ao_voxel_blur_y"],
                &inputs,
                [&full.default_view, &scratch.default_view],
            )
        });
        commands.entity(entity).insert(VoxelBindGroups {
            sample,
            temporal,
            upsample,
            blur,
        });
    }
}
