//! Pipelines and bind groups of the blur.

use crate::nd_buffer::FrontLayer;
use bevy::asset::load_embedded_asset;
use bevy::ecs::prelude::*;
use bevy::render::{
    render_resource::{
        binding_types::{texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::RenderDevice,
    view::ViewUniform,
};
use bevy::utils::default;

use crate::view::{
    DynamicAoTextures, DynamicAoUniform, DynamicAoView, OCCLUSION_FORMAT, ViewBindings,
};

/// The blur and upsampling pipelines for one kind of occlusion buffer.
pub(crate) struct FilterPipelines {
    pub layout: BindGroupLayoutDescriptor,
    pub x: CachedComputePipelineId,
    pub y: CachedComputePipelineId,
    pub upsample_layout: BindGroupLayoutDescriptor,
    pub upsample: CachedComputePipelineId,
}

impl FilterPipelines {
    /// Every pipeline of the set has compiled.
    pub fn ready(&self, cache: &PipelineCache) -> bool {
        [self.x, self.y, self.upsample]
            .into_iter()
            .all(|id| cache.get_compute_pipeline(id).is_some())
    }
}

/// Filters for one-channel occlusion (the image-space techniques) and for two-channel far-field
/// occlusion (voxel volumes: the near field's share and the rest, see `FarFieldBlend`).
#[derive(Resource)]
pub(crate) struct BlurPipelines {
    pub one: FilterPipelines,
    pub two: FilterPipelines,
}

/// Format of two-channel occlusion buffers.
pub(crate) const OCCLUSION_PAIR_FORMAT: TextureFormat = TextureFormat::Rg32Float;

fn filter_pipelines(world: &mut World, two_channels: bool) -> FilterPipelines {
    let (format, shader_defs, suffix): (_, Vec<bevy::shader::ShaderDefVal>, _) = if two_channels {
        (OCCLUSION_PAIR_FORMAT, vec!["TWO_CHANNELS".into()], "_pair")
    } else {
        (OCCLUSION_FORMAT, Vec::new(), "")
    };
    let layout = BindGroupLayoutDescriptor::new(
        format!("dynamic_ao_blur{suffix}_layout"),
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer::<ViewUniform>(true),
                uniform_buffer::<DynamicAoUniform>(true),
                texture_depth_2d(),
                texture_2d(TextureSampleType::Float { filterable: false }),
                texture_storage_2d(format, StorageTextureAccess::WriteOnly),
            ),
        ),
    );
    let upsample_layout = BindGroupLayoutDescriptor::new(
        format!("dynamic_ao_upsample{suffix}_layout"),
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer::<ViewUniform>(true),
                uniform_buffer::<DynamicAoUniform>(true),
                texture_depth_2d(),
                texture_2d(TextureSampleType::Float { filterable: false }),
                texture_2d(TextureSampleType::Float { filterable: false }),
                texture_storage_2d(format, StorageTextureAccess::WriteOnly),
            ),
        ),
    );
    let blur = load_embedded_asset!(world, "blur.wgsl");
    let upsample = load_embedded_asset!(world, "upsample.wgsl");
    let cache = world.resource::<PipelineCache>();
    let pipeline = |label: String, layout: &BindGroupLayoutDescriptor, shader, entry: &str| {
        cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some(label.into()),
            layout: vec![layout.clone()],
            shader,
            shader_defs: shader_defs.clone(),
            entry_point: Some(entry.to_string().into()),
            ..default()
        })
    };
    FilterPipelines {
        x: pipeline(
            format!("dynamic_ao_blur_x{suffix}_pipeline"),
            &layout,
            blur.clone(),
            "blur_x",
        ),
        y: pipeline(
            format!("dynamic_ao_blur_y{suffix}_pipeline"),
            &layout,
            blur,
            "blur_y",
        ),
        upsample: pipeline(
            format!("dynamic_ao_upsample{suffix}_pipeline"),
            &upsample_layout,
            upsample,
            "upsample",
        ),
        layout,
        upsample_layout,
    }
}

impl FromWorld for BlurPipelines {
    fn from_world(world: &mut World) -> Self {
        Self {
            one: filter_pipelines(world, false),
            two: filter_pipelines(world, true),
        }
    }
}

/// What every blur and upsampling pass of a view reads besides its occlusion buffers.
pub(crate) struct FilterInputs<'a> {
    pub view: BindingResource<'a>,
    pub settings: BindingResource<'a>,
    pub depth: &'a TextureView,
}

impl FilterPipelines {
    /// The bind group of an upsampling pass: `low` (half size) into `full`.
    pub fn upsample_bind_group(
        &self,
        device: &RenderDevice,
        pipeline_cache: &PipelineCache,
        label: &'static str,
        inputs: &FilterInputs,
        normal: &TextureView,
        [low, full]: [&TextureView; 2],
    ) -> BindGroup {
        device.create_bind_group(
            label,
            &pipeline_cache.get_bind_group_layout(&self.upsample_layout),
            &BindGroupEntries::sequential((
                inputs.view.clone(),
                inputs.settings.clone(),
                inputs.depth,
                normal,
                low,
                full,
            )),
        )
    }

    /// The bind groups of the two blur passes: X from `occlusion` into `scratch`, Y back.
    pub fn blur_bind_groups(
        &self,
        device: &RenderDevice,
        pipeline_cache: &PipelineCache,
        [label_x, label_y]: [&'static str; 2],
        inputs: &FilterInputs,
        [occlusion, scratch]: [&TextureView; 2],
    ) -> BlurBindGroups {
        let layout = pipeline_cache.get_bind_group_layout(&self.layout);
        let pass = |label, input: &TextureView, output: &TextureView| {
            device.create_bind_group(
                label,
                &layout,
                &BindGroupEntries::sequential((
                    inputs.view.clone(),
                    inputs.settings.clone(),
                    inputs.depth,
                    input,
                    output,
                )),
            )
        };
        BlurBindGroups {
            x: pass(label_x, occlusion, scratch),
            y: pass(label_y, scratch, occlusion),
        }
    }
}

/// X pass: occlusion → scratch; Y pass: scratch → occlusion.
#[derive(Component)]
pub(crate) struct BlurBindGroups {
    pub x: BindGroup,
    pub y: BindGroup,
}

/// Half-size occlusion → full-size occlusion.
#[derive(Component)]
pub(crate) struct UpsampleBindGroup(pub BindGroup);

pub(crate) fn prepare_blur_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipelines: Res<BlurPipelines>,
    pipeline_cache: Res<PipelineCache>,
    bindings: ViewBindings,
    views: Query<(Entity, &DynamicAoTextures, FrontLayer, &DynamicAoView)>,
) {
    let Some((view_binding, settings_binding)) = bindings.get() else {
        return;
    };
    for (entity, textures, prepass, view) in &views {
        let Some(depth) = prepass.depth() else {
            commands
                .entity(entity)
                .remove::<(UpsampleBindGroup, BlurBindGroups)>();
            continue;
        };
        let inputs = FilterInputs {
            view: view_binding.clone(),
            settings: settings_binding.clone(),
            depth,
        };
        let occlusion = &textures.full_occlusion.default_view;
        match prepass.normal().filter(|_| view.half_resolution) {
            Some(normal) => {
                commands.entity(entity).insert(UpsampleBindGroup(
                    pipelines.one.upsample_bind_group(
                        &render_device,
                        &pipeline_cache,
                        "dynamic_ao_upsample_bind_group",
                        &inputs,
                        normal,
                        [&textures.near_occlusion.default_view, occlusion],
                    ),
                ));
            }
            None => {
                commands.entity(entity).remove::<UpsampleBindGroup>();
            }
        }
        if view.blur_radius == 0 {
            commands.entity(entity).remove::<BlurBindGroups>();
            continue;
        }
        commands
            .entity(entity)
            .insert(pipelines.one.blur_bind_groups(
                &render_device,
                &pipeline_cache,
                [
                    "dynamic_ao_blur_x_bind_group",
                    "dynamic_ao_blur_y_bind_group",
                ],
                &inputs,
                [occlusion, &textures.blur_scratch.default_view],
            ));
    }
}
