//! The pass that runs the image-space technique of each view: [`near_field`](crate::near_field),
//! [`horizon`](crate::horizon) or [`ray_march`](crate::ray_march). All three read the same
//! bindings (view, settings, both ND-buffer layers) and write the same occlusion buffer, so they
//! share one layout, one bind group per view and one pass; only the shader differs.

use bevy::app::{App, Plugin};
use bevy::core_pipeline::{prepass::ViewPrepassTextures, schedule::Core3d};
use bevy::ecs::prelude::*;
use bevy::render::{
    GpuResourceAppExt, Render, RenderSystems,
    camera::ExtractedCamera,
    extract_component::{ComponentUniforms, DynamicUniformIndex},
    render_resource::{
        binding_types::{texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::{RenderContext, RenderDevice, ViewQuery},
    view::{ViewUniform, ViewUniformOffset, ViewUniforms},
};
use bevy::utils::default;

use crate::capabilities;
use crate::dispatch::{ComputeStep, record_passes};
use crate::schedule::{DynamicAoPrepare, DynamicAoSystems};
use crate::settings::AoTechnique;
use crate::view::{
    DynamicAoTextures, DynamicAoUniform, DynamicAoView, OCCLUSION_FORMAT, PendingPasses,
};

/// Registers the shared pipelines, bind groups and pass of the image-space techniques.
pub(crate) struct ImageSpacePlugin;

impl Plugin for ImageSpacePlugin {
    fn build(&self, _app: &mut App) {}

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_gpu_resource::<ImageSpacePipelines>()
            .add_systems(
                Render,
                (
                    prepare_image_space_bind_groups.in_set(RenderSystems::PrepareBindGroups),
                    wait_for_image_space.in_set(DynamicAoPrepare::Readiness),
                ),
            )
            .add_systems(Core3d, image_space_pass.in_set(DynamicAoSystems::NearField));
    }
}

/// The view's image-space technique counts until its pipeline has compiled. `Off` has none to
/// wait for; under Bevy's SSAO ours never take over.
fn wait_for_image_space(
    pipeline_cache: Res<PipelineCache>,
    pipelines: Res<ImageSpacePipelines>,
    mut views: Query<(&DynamicAoView, &mut PendingPasses)>,
) {
    for (view, mut pending) in &mut views {
        let ready = match view.technique() {
            AoTechnique::Off => true,
            AoTechnique::BevySsao => false,
            technique => pipelines
                .pipeline(technique)
                .is_some_and(|id| pipeline_cache.get_compute_pipeline(id).is_some()),
        };
        pending.wait_for(ready);
    }
}

/// One compute pipeline per image-space technique, over one layout.
#[derive(Resource)]
pub(crate) struct ImageSpacePipelines {
    layout: BindGroupLayoutDescriptor,
    near_field: CachedComputePipelineId,
    horizon: CachedComputePipelineId,
    ray_march: CachedComputePipelineId,
}

impl ImageSpacePipelines {
    /// The pipeline of `technique`, if it is an image-space one.
    pub fn pipeline(&self, technique: AoTechnique) -> Option<CachedComputePipelineId> {
        match technique {
            AoTechnique::NearField => Some(self.near_field),
            AoTechnique::Horizon => Some(self.horizon),
            AoTechnique::RayMarch => Some(self.ray_march),
            AoTechnique::Off | AoTechnique::BevySsao => None,
        }
    }
}

impl FromWorld for ImageSpacePipelines {
    fn from_world(world: &mut World) -> Self {
        let float = || texture_2d(TextureSampleType::Float { filterable: false });
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_image_space_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    uniform_buffer::<ViewUniform>(true),
                    uniform_buffer::<DynamicAoUniform>(true),
                    texture_depth_2d(),
                    float(),
                    texture_depth_2d(),
                    float(),
                    texture_storage_2d(OCCLUSION_FORMAT, StorageTextureAccess::WriteOnly),
                ),
            ),
        );
        let shaders = [
            (
                "dynamic_ao_near_field_pipeline",
                crate::near_field::shader(world),
            ),
            ("dynamic_ao_horizon_pipeline", crate::horizon::shader(world)),
            (
                "dynamic_ao_ray_march_pipeline",
                crate::ray_march::shader(world),
            ),
        ];
        let cache = world.resource::<PipelineCache>();
        let [near_field, horizon, ray_march] = shaders.map(|(label, shader)| {
            cache.queue_compute_pipeline(ComputePipelineDescriptor {
                label: Some(label.into()),
                layout: vec![layout.clone()],
                shader,
                ..default()
            })
        });
        Self {
            layout,
            near_field,
            horizon,
            ray_march,
        }
    }
}

#[derive(Component)]
pub(crate) struct ImageSpaceBindGroup(BindGroup);

fn prepare_image_space_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipelines: Res<ImageSpacePipelines>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    settings: Res<ComponentUniforms<DynamicAoUniform>>,
    views: Query<(Entity, &DynamicAoTextures, &ViewPrepassTextures), With<DynamicAoView>>,
) {
    let (Some(view_binding), Some(settings_binding)) =
        (view_uniforms.uniforms.binding(), settings.binding())
    else {
        return;
    };
    for (entity, textures, prepass) in &views {
        let (Some(front_depth), Some(front_normal)) = (prepass.depth_view(), prepass.normal_view())
        else {
            continue;
        };
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_image_space_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipelines.layout),
            &BindGroupEntries::sequential((
                view_binding.clone(),
                settings_binding.clone(),
                front_depth,
                front_normal,
                &textures.back_depth.default_view,
                &textures.back_normal.default_view,
                &textures.near_occlusion.default_view,
            )),
        );
        commands
            .entity(entity)
            .insert(ImageSpaceBindGroup(bind_group));
    }
}

fn image_space_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &DynamicAoView,
        &ImageSpaceBindGroup,
        &ViewUniformOffset,
        &DynamicUniformIndex<DynamicAoUniform>,
    )>,
    pipelines: Res<ImageSpacePipelines>,
    pipeline_cache: Res<PipelineCache>,
    mut ctx: RenderContext,
) {
    let (camera, ao_view, bind_group, view_offset, settings_index) = view.into_inner();
    let (Some(size), Some(compute_pipeline)) = (
        camera.physical_viewport_size,
        pipelines
            .pipeline(ao_view.technique())
            .and_then(|id| pipeline_cache.get_compute_pipeline(id)),
    ) else {
        return;
    };
    let label = match ao_view.technique() {
        AoTechnique::Horizon => "dynamic_ao_horizon",
        AoTechnique::RayMarch => "dynamic_ao_ray_march",
        _ => "dynamic_ao_near_field",
    };
    // One invocation per texel of the occlusion buffer (half size at half resolution).
    let scale = if ao_view.half_resolution { 2 } else { 1 };
    let step = ComputeStep {
        label,
        pipeline: compute_pipeline,
        bind_group: &bind_group.0,
        offsets: &[view_offset.offset, settings_index.index()],
        texels: (size + (scale - 1)) / scale,
    };
    record_passes(&mut ctx, label, true, &[step]);
}
