//! One compute pipeline per image-space technique over one layout, and the bind group of each
//! view.

use crate::nd_buffer::FrontLayer;
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

use crate::settings::AoTechnique;
use crate::view::{
    BLUR_NORMAL_FORMAT, DynamicAoTextures, DynamicAoUniform, DynamicAoView, OCCLUSION_FORMAT,
    ViewBindings,
};

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
                    texture_storage_2d(BLUR_NORMAL_FORMAT, StorageTextureAccess::WriteOnly),
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
pub(crate) struct ImageSpaceBindGroup(pub(super) BindGroup);

pub(super) fn prepare_image_space_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipelines: Res<ImageSpacePipelines>,
    pipeline_cache: Res<PipelineCache>,
    bindings: ViewBindings,
    views: Query<(Entity, &DynamicAoTextures, FrontLayer), With<DynamicAoView>>,
) {
    let Some((view_binding, settings_binding)) = bindings.get() else {
        return;
    };
    for (entity, textures, prepass) in &views {
        let (Some(front_depth), Some(front_normal)) = (prepass.depth(), prepass.normal()) else {
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
                // Under temporal accumulation the temporal pass writes `near_occlusion`.
                &textures
                    .raw_occlusion
                    .as_ref()
                    .unwrap_or(&textures.near_occlusion)
                    .default_view,
                &textures.blur_normal.default_view,
            )),
        );
        commands
            .entity(entity)
            .insert(ImageSpaceBindGroup(bind_group));
    }
}
