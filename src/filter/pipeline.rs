//! The pipelines of the blur and upsampling passes (their bind groups: `bind_groups.rs`).

use bevy::asset::Handle;
use bevy::asset::load_embedded_asset;
use bevy::ecs::prelude::*;
use bevy::render::{
    render_resource::{
        binding_types::{texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::RenderAdapter,
    view::ViewUniform,
};
use bevy::shader::{Shader, ShaderDefVal};
use bevy::utils::default;

use crate::compose::bevy_ssao_format;
use crate::view::{BLUR_NORMAL_FORMAT, DynamicAoUniform, OCCLUSION_FORMAT, OCCLUSION_PAIR_FORMAT};

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
/// `format`; with `normals`, the upsampling also writes the normals the blur weighs by
/// ([`BLUR_NORMAL_FORMAT`]).
fn layouts(format: TextureFormat, suffix: &str, normals: bool) -> [BindGroupLayoutDescriptor; 3] {
    let blur = BindGroupLayoutDescriptor::new(
        format!("dynamic_ao_blur{suffix}_layout"),
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
    let upsample = |label: String, low: TextureSampleType| {
        let mut entries = DynamicBindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer::<ViewUniform>(true),
                uniform_buffer::<DynamicAoUniform>(true),
                texture_depth_2d(),
                texture_2d(TextureSampleType::Float { filterable: false }),
                texture_2d(low),
                texture_storage_2d(format, StorageTextureAccess::WriteOnly),
            ),
        );
        if normals {
            entries = entries.extend_sequential((texture_storage_2d(
                BLUR_NORMAL_FORMAT,
                StorageTextureAccess::WriteOnly,
            ),));
        }
        BindGroupLayoutDescriptor::new(label, &entries)
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
/// it, the suffix of its labels, and whether its upsampling also writes the normals the blur
/// weighs by (`WRITE_NORMALS`, a binding more in its layouts).
struct Variant {
    format: TextureFormat,
    shader_defs: Vec<ShaderDefVal>,
    suffix: &'static str,
    writes_normals: bool,
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
        if entry == "upsample" && self.writes_normals {
            shader_defs.push("WRITE_NORMALS".into());
        }
        // Where `output` sits in the layout (`shaders/filter_output.wgsl`): after the five
        // bindings the blur and the upsampling each read.
        shader_defs.push(ShaderDefVal::UInt("OUTPUT_BINDING".into(), 5));
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
        // The voxel term's blur weighs by depth alone.
        Variant {
            format: OCCLUSION_PAIR_FORMAT,
            shader_defs: vec!["TWO_CHANNELS".into()],
            suffix: "_pair",
            writes_normals: false,
        }
    } else {
        Variant {
            format: OCCLUSION_FORMAT,
            shader_defs: Vec::new(),
            suffix: "",
            writes_normals: true,
        }
    };
    let [layout, upsample_layout, guided_layout] =
        layouts(variant.format, variant.suffix, variant.writes_normals);
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
        // The upsampling writes visibility only where no blur follows, which needs no normals.
        let variant = Variant {
            format,
            shader_defs,
            suffix: "_visibility",
            writes_normals: false,
        };
        let [layout, upsample_layout, guided_layout] =
            layouts(format, variant.suffix, variant.writes_normals);
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
