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

/// One compute pipeline per image-space technique and resolution, over one layout. All six are
/// compiled when the renderer starts (a fraction of a second on a CPU rasterizer), so that a
/// camera switching technique or resolution at run time has its pipeline at once: one compiling
/// meanwhile would leave the view's passes off for those frames, and its history stale.
#[derive(Resource)]
pub(crate) struct ImageSpacePipelines {
    layout: BindGroupLayoutDescriptor,
    /// Near field, horizon and ray march, each at full and at half resolution.
    pipelines: [[CachedComputePipelineId; 2]; 3],
}

/// The image-space techniques, in the order of [`ImageSpacePipelines`].
const TECHNIQUES: [(AoTechnique, &str); 3] = [
    (AoTechnique::NearField, "near_field"),
    (AoTechnique::Horizon, "horizon"),
    (AoTechnique::RayMarch, "ray_march"),
];

impl ImageSpacePipelines {
    /// The pipeline of `technique` with an occlusion buffer at half the view's resolution or at
    /// full, if the technique is an image-space one. At half resolution (`HALF_RESOLUTION` in
    /// `shaders/image_space_bindings.wgsl`) the receivers' pixels follow from a constant and the
    /// copies of the normals for the blur, which the upsampling writes then, are compiled out:
    /// behind a flag in the uniform, lavapipe ran their reads and stores under a mask on every
    /// texel (the ray march about 4% shorter without them; BENCHMARKS.md, "The resolution
    /// compiled in").
    pub fn pipeline(
        &self,
        technique: AoTechnique,
        half_resolution: bool,
    ) -> Option<CachedComputePipelineId> {
        let index = TECHNIQUES.iter().position(|(t, _)| *t == technique)?;
        Some(self.pipelines[index][usize::from(half_resolution)])
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
            crate::near_field::shader(world),
            crate::horizon::shader(world),
            crate::ray_march::shader(world),
        ];
        let cache = world.resource::<PipelineCache>();
        let pipelines = std::array::from_fn(|t| {
            let (_, name) = TECHNIQUES[t];
            [(false, ""), (true, "_half_resolution")].map(|(half, resolution)| {
                cache.queue_compute_pipeline(ComputePipelineDescriptor {
                    label: Some(format!("dynamic_ao_{name}{resolution}_pipeline").into()),
                    layout: vec![layout.clone()],
                    shader: shaders[t].clone(),
                    shader_defs: if half {
                        vec!["HALF_RESOLUTION".into()]
                    } else {
                        vec![]
                    },
                    ..default()
                })
            })
        });
        Self { layout, pipelines }
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
