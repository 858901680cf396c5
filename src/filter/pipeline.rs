//! Pipelines and bind groups of the blur.

use crate::nd_buffer::FrontLayer;
use bevy::asset::Handle;
use bevy::asset::load_embedded_asset;
use bevy::ecs::prelude::*;
use bevy::pbr::ScreenSpaceAmbientOcclusionResources;
use bevy::render::{
    render_resource::{
        binding_types::{texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::{RenderAdapter, RenderDevice},
    view::ViewUniform,
};
use bevy::shader::{Shader, ShaderDefVal};
use bevy::utils::default;

use crate::compose::{ParkedSsao, bevy_ssao_format, visibility_texture};
use crate::temporal::TemporalHistory;
use crate::view::{
    DynamicAoTextures, DynamicAoUniform, DynamicAoView, FilterWritesVisibility, OCCLUSION_FORMAT,
    OCCLUSION_PAIR_FORMAT, ViewBindings,
};

/// The blur and upsampling pipelines for one kind of occlusion buffer.
pub(crate) struct FilterPipelines {
    pub layout: BindGroupLayoutDescriptor,
    pub x: CachedComputePipelineId,
    pub y: CachedComputePipelineId,
    pub upsample_layout: BindGroupLayoutDescriptor,
    pub upsample: CachedComputePipelineId,
    /// The upsampling of an accumulated buffer from its history (one channel only).
    pub guided: Option<GuidedUpsample>,
}

impl FilterPipelines {
    /// Every pipeline of the set has compiled.
    pub fn ready(&self, cache: &PipelineCache) -> bool {
        [self.x, self.y, self.upsample]
            .into_iter()
            .all(|id| cache.get_compute_pipeline(id).is_some())
    }
}

/// The upsampling that reads the temporal pass's history written this frame (`GUIDE_TEXELS` in
/// `upsample.wgsl`): its texels carry linear depth and normal beside the accumulated occlusion,
/// so a texel's guide costs one read instead of a depth, a normal and a value read and an
/// unprojection.
pub(crate) struct GuidedUpsample {
    pub layout: BindGroupLayoutDescriptor,
    pub pipeline: CachedComputePipelineId,
}

/// Filters for one-channel occlusion (the image-space techniques) and for two-channel far-field
/// occlusion (voxel volumes: the near field's share and the rest, see `FarFieldBlend`), and the
/// one-channel filter's last pass writing visibility.
#[derive(Resource)]
pub(crate) struct BlurPipelines {
    pub one: FilterPipelines,
    pub two: FilterPipelines,
    pub to_visibility: VisibilityPipelines,
}

/// The bind group layouts of the blur, of the upsampling and of the guided upsampling, writing
/// `format`.
fn layouts(format: TextureFormat, suffix: &str) -> [BindGroupLayoutDescriptor; 3] {
    let blur = BindGroupLayoutDescriptor::new(
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
    let upsample = |label: String, low: TextureSampleType| {
        BindGroupLayoutDescriptor::new(
            label,
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    uniform_buffer::<ViewUniform>(true),
                    uniform_buffer::<DynamicAoUniform>(true),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_2d(low),
                    texture_storage_2d(format, StorageTextureAccess::WriteOnly),
                ),
            ),
        )
    };
    [
        blur,
        upsample(
            format!("dynamic_ao_upsample{suffix}_layout"),
            TextureSampleType::Float { filterable: false },
        ),
        upsample(
            format!("dynamic_ao_upsample_guided{suffix}_layout"),
            TextureSampleType::Uint,
        ),
    ]
}

/// What a set of filter pipelines writes: its output format, the shader definitions that select
/// it, and the suffix of its labels.
struct Variant {
    format: TextureFormat,
    shader_defs: Vec<ShaderDefVal>,
    suffix: &'static str,
}

impl Variant {
    /// Queues the pipeline of entry point `entry` (`blur_x`, `blur_y` or `upsample`) of `shader`.
    fn queue(
        &self,
        world: &World,
        entry: &str,
        layout: &BindGroupLayoutDescriptor,
        shader: Handle<Shader>,
    ) -> CachedComputePipelineId {
        self.queue_with(world, entry, layout, shader, None)
    }

    /// `queue` with one more shader definition, which also names the pipeline.
    fn queue_with(
        &self,
        world: &World,
        entry: &str,
        layout: &BindGroupLayoutDescriptor,
        shader: Handle<Shader>,
        extra: Option<&'static str>,
    ) -> CachedComputePipelineId {
        let mut shader_defs = self.shader_defs.clone();
        shader_defs.extend(extra.map(ShaderDefVal::from));
        let extra = extra.map_or(String::new(), |def| format!("_{}", def.to_lowercase()));
        world
            .resource::<PipelineCache>()
            .queue_compute_pipeline(ComputePipelineDescriptor {
                label: Some(format!("dynamic_ao_{entry}{extra}{}_pipeline", self.suffix).into()),
                layout: vec![layout.clone()],
                shader,
                shader_defs,
                entry_point: Some(entry.to_string().into()),
                ..default()
            })
    }

    /// The guided upsampling of `shader` (`upsample.wgsl`) over `layout`.
    fn guided(
        &self,
        world: &World,
        layout: BindGroupLayoutDescriptor,
        shader: Handle<Shader>,
    ) -> GuidedUpsample {
        let pipeline = self.queue_with(world, "upsample", &layout, shader, Some("GUIDE_TEXELS"));
        GuidedUpsample { layout, pipeline }
    }
}

fn filter_pipelines(world: &mut World, two_channels: bool) -> FilterPipelines {
    let variant = if two_channels {
        Variant {
            format: OCCLUSION_PAIR_FORMAT,
            shader_defs: vec!["TWO_CHANNELS".into()],
            suffix: "_pair",
        }
    } else {
        Variant {
            format: OCCLUSION_FORMAT,
            shader_defs: Vec::new(),
            suffix: "",
        }
    };
    let [layout, upsample_layout, guided_layout] = layouts(variant.format, variant.suffix);
    let blur = load_embedded_asset!(world, "blur.wgsl");
    let upsample = load_embedded_asset!(world, "upsample.wgsl");
    FilterPipelines {
        x: variant.queue(world, "blur_x", &layout, blur.clone()),
        y: variant.queue(world, "blur_y", &layout, blur),
        // The voxel term's two channels are upsampled from their own map, never from a history.
        guided: (!two_channels).then(|| variant.guided(world, guided_layout, upsample.clone())),
        upsample: variant.queue(world, "upsample", &upsample_layout, upsample),
        layout,
        upsample_layout,
    }
}

/// The last filter pass of a view without far-field terms, writing the visibility Bevy's PBR
/// reads in its texture's format (`DynamicAoView::filter_is_last`): compose would only copy it
/// there, a full-resolution pass of its own.
pub(crate) struct VisibilityPipelines {
    pub layout: BindGroupLayoutDescriptor,
    pub upsample_layout: BindGroupLayoutDescriptor,
    /// The blur's Y pass.
    pub y: CachedComputePipelineId,
    /// The upsampling, where the blur is off.
    pub upsample: CachedComputePipelineId,
    /// The guided upsampling, where the blur is off.
    pub guided: GuidedUpsample,
}

impl VisibilityPipelines {
    fn new(world: &mut World) -> Self {
        let format = bevy_ssao_format(world.resource::<RenderAdapter>());
        let mut shader_defs: Vec<ShaderDefVal> = vec!["VISIBILITY".into()];
        if format == TextureFormat::R16Float {
            shader_defs.push("VISIBILITY_R16FLOAT".into());
        }
        let variant = Variant {
            format,
            shader_defs,
            suffix: "_visibility",
        };
        let [layout, upsample_layout, guided_layout] = layouts(format, variant.suffix);
        let blur = load_embedded_asset!(world, "blur.wgsl");
        let upsample = load_embedded_asset!(world, "upsample.wgsl");
        Self {
            y: variant.queue(world, "blur_y", &layout, blur),
            guided: variant.guided(world, guided_layout, upsample.clone()),
            upsample: variant.queue(world, "upsample", &upsample_layout, upsample),
            layout,
            upsample_layout,
        }
    }
}

impl FromWorld for BlurPipelines {
    fn from_world(world: &mut World) -> Self {
        Self {
            one: filter_pipelines(world, false),
            two: filter_pipelines(world, true),
            to_visibility: VisibilityPipelines::new(world),
        }
    }
}

/// What every blur and upsampling pass of a view reads besides its occlusion buffers.
pub(crate) struct FilterInputs<'a> {
    pub view: BindingResource<'a>,
    pub settings: BindingResource<'a>,
    pub depth: &'a TextureView,
}

/// The bind group of an upsampling pass over `layout`: `low` (half size) into `full`.
fn upsample_bind_group(
    device: &RenderDevice,
    pipeline_cache: &PipelineCache,
    layout: &BindGroupLayoutDescriptor,
    label: &'static str,
    inputs: &FilterInputs,
    normal: &TextureView,
    [low, full]: [&TextureView; 2],
) -> BindGroup {
    device.create_bind_group(
        label,
        &pipeline_cache.get_bind_group_layout(layout),
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

impl FilterPipelines {
    /// The bind group of an upsampling pass: `low` (half size) into `full`.
    pub fn upsample_bind_group(
        &self,
        device: &RenderDevice,
        pipeline_cache: &PipelineCache,
        label: &'static str,
        inputs: &FilterInputs,
        normal: &TextureView,
        textures: [&TextureView; 2],
    ) -> BindGroup {
        let layout = &self.upsample_layout;
        upsample_bind_group(
            device,
            pipeline_cache,
            layout,
            label,
            inputs,
            normal,
            textures,
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
pub(crate) struct UpsampleBindGroup {
    pub bind_group: BindGroup,
    /// For the guided upsampling, reading the temporal pass's history ([`GuidedUpsample`]).
    pub guided: bool,
}

/// The bind group of the last filter pass where it writes visibility
/// ([`FilterWritesVisibility`]): the blur's Y pass (scratch → visibility), or the upsampling
/// (half-size occlusion → visibility) where the blur is off.
#[derive(Component)]
pub(crate) struct VisibilityBindGroup {
    pub bind_group: BindGroup,
    /// For the guided upsampling ([`GuidedUpsample`]).
    pub guided: bool,
}

pub(crate) fn prepare_blur_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipelines: Res<BlurPipelines>,
    pipeline_cache: Res<PipelineCache>,
    bindings: ViewBindings,
    views: Query<(
        Entity,
        &DynamicAoTextures,
        FrontLayer,
        &DynamicAoView,
        Option<&ScreenSpaceAmbientOcclusionResources>,
        Option<&ParkedSsao>,
        Option<&TemporalHistory>,
    )>,
) {
    let Some((view_binding, settings_binding)) = bindings.get() else {
        return;
    };
    let ready = |id| pipeline_cache.get_compute_pipeline(id).is_some();
    for (entity, textures, prepass, view, resources, parked, history) in &views {
        let Some(depth) = prepass.depth() else {
            commands.entity(entity).remove::<(
                UpsampleBindGroup,
                BlurBindGroups,
                VisibilityBindGroup,
                FilterWritesVisibility,
            )>();
            continue;
        };
        let inputs = FilterInputs {
            view: view_binding.clone(),
            settings: settings_binding.clone(),
            depth,
        };
        let occlusion = &textures.full_occlusion.default_view;
        let half_normal = prepass.normal().filter(|_| view.half_resolution);
        // The history the temporal pass writes this frame, where it runs (it runs wherever the
        // technique writes a raw buffer for it).
        let guide = history
            .filter(|_| view.temporal && textures.raw_occlusion.is_some())
            .map(TemporalHistory::written);
        // The bind group of an upsampling from `low` (half size) into `output` over `layout`, or,
        // where there is a guide and `guided` has compiled, of the guided one; and which it is.
        let upsample = |layout, guided: Option<&GuidedUpsample>, low, output, label| {
            let guided = guided.filter(|g| ready(g.pipeline)).zip(guide);
            let (layout, low) = guided.map_or((layout, low), |(g, history)| (&g.layout, history));
            let bind_group = half_normal.map(|normal| {
                let textures = [low, output];
                upsample_bind_group(
                    &render_device,
                    &pipeline_cache,
                    layout,
                    label,
                    &inputs,
                    normal,
                    textures,
                )
            });
            bind_group.map(|bind_group| (bind_group, guided.is_some()))
        };
        let low = &textures.near_occlusion.default_view;
        let one = &pipelines.one;
        let label = "dynamic_ao_upsample_bind_group";
        match upsample(
            &one.upsample_layout,
            one.guided.as_ref(),
            low,
            occlusion,
            label,
        ) {
            Some((bind_group, guided)) => {
                commands
                    .entity(entity)
                    .insert(UpsampleBindGroup { bind_group, guided });
            }
            None => {
                commands.entity(entity).remove::<UpsampleBindGroup>();
            }
        }
        let to_visibility = &pipelines.to_visibility;
        let visibility = visibility_texture(resources, parked)
            .filter(|_| view.filter_is_last())
            .map(|texture| &texture.default_view);
        let last = match (visibility, view.blur_radius, half_normal) {
            (Some(visibility), 1.., _) if ready(to_visibility.y) => Some(VisibilityBindGroup {
                bind_group: render_device.create_bind_group(
                    "dynamic_ao_blur_y_visibility_bind_group",
                    &pipeline_cache.get_bind_group_layout(&to_visibility.layout),
                    &BindGroupEntries::sequential((
                        inputs.view.clone(),
                        inputs.settings.clone(),
                        inputs.depth,
                        &textures.blur_scratch.default_view,
                        visibility,
                    )),
                ),
                guided: false,
            }),
            (Some(visibility), 0, Some(_)) if ready(to_visibility.upsample) => upsample(
                &to_visibility.upsample_layout,
                Some(&to_visibility.guided),
                low,
                visibility,
                "dynamic_ao_upsample_visibility_bind_group",
            )
            .map(|(bind_group, guided)| VisibilityBindGroup { bind_group, guided }),
            _ => None,
        };
        match last {
            Some(bind_group) => {
                commands
                    .entity(entity)
                    .insert((bind_group, FilterWritesVisibility));
            }
            None => {
                commands
                    .entity(entity)
                    .remove::<(VisibilityBindGroup, FilterWritesVisibility)>();
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
