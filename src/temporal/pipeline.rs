//! The temporal pass's pipelines (one channel for the image-space occlusion, two for the voxel
//! term) and the bind group of one accumulation.

use bevy::asset::load_embedded_asset;
use bevy::ecs::prelude::*;
use bevy::render::{
    render_resource::{
        binding_types::{texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer},
        *,
    },
    renderer::RenderDevice,
    view::{ViewUniform, ViewUniforms},
};
use bevy::shader::ShaderDefVal;
use bevy::utils::default;

use super::view::{TemporalHistory, TemporalUniform};
use crate::nd_buffer::{FrontLayer, FrontLayerViews};
use crate::view::{DynamicAoTextures, OCCLUSION_FORMAT, OCCLUSION_PAIR_FORMAT};

/// One accumulation's pipelines and their layout.
pub(crate) struct TemporalVariant {
    layout: BindGroupLayoutDescriptor,
    /// The pipeline that clamps the history (`CLAMP` in `temporal.wgsl`).
    pub clamped: CachedComputePipelineId,
    /// The image-space occlusion's pipeline for the frames without the clamp (every other one),
    /// compiled without its tile and window: a flag in the uniform spared only part of their work
    /// on lavapipe, which runs an `if`'s body under a mask (the pass about a quarter shorter this
    /// way; BENCHMARKS.md, "A temporal pipeline without the clamp").
    pub unclamped: Option<CachedComputePipelineId>,
}

impl TemporalVariant {
    /// The pipeline of a frame that clamps the history, or of one that does not.
    pub fn pipeline(&self, clamp: bool) -> CachedComputePipelineId {
        match (clamp, self.unclamped) {
            (false, Some(unclamped)) => unclamped,
            _ => self.clamped,
        }
    }
}

/// What a history accumulates: one channel or a pair.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Channels {
    /// The image-space occlusion ([`OCCLUSION_FORMAT`]).
    One,
    /// The voxel term's two channels ([`OCCLUSION_PAIR_FORMAT`]).
    Pair,
}

/// The accumulation pipelines.
#[derive(Resource)]
pub(crate) struct TemporalPipeline {
    pub one: TemporalVariant,
    pub pair: TemporalVariant,
}

impl TemporalPipeline {
    pub fn variant(&self, channels: Channels) -> &TemporalVariant {
        match channels {
            Channels::One => &self.one,
            Channels::Pair => &self.pair,
        }
    }

    /// Whether the pipelines for `channels` have compiled.
    pub fn ready(&self, cache: &PipelineCache, channels: Channels) -> bool {
        let variant = self.variant(channels);
        [Some(variant.clamped), variant.unclamped]
            .into_iter()
            .flatten()
            .all(|id| cache.get_compute_pipeline(id).is_some())
    }
}

fn variant(world: &mut World, channels: Channels) -> TemporalVariant {
    let float = || texture_2d(TextureSampleType::Float { filterable: false });
    let (format, label, shader_defs): (_, _, Vec<ShaderDefVal>) = match channels {
        Channels::One => (OCCLUSION_FORMAT, "dynamic_ao_temporal", vec![]),
        Channels::Pair => (
            OCCLUSION_PAIR_FORMAT,
            "dynamic_ao_temporal_pair",
            vec!["PAIR".into()],
        ),
    };
    let layout = BindGroupLayoutDescriptor::new(
        format!("{label}_layout"),
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer::<ViewUniform>(true),
                uniform_buffer::<TemporalUniform>(false),
                float(),
                texture_depth_2d(),
                float(),
                float(),
                texture_2d(TextureSampleType::Uint),
                texture_storage_2d(TextureFormat::Rgba32Uint, StorageTextureAccess::WriteOnly),
                texture_storage_2d(format, StorageTextureAccess::WriteOnly),
            ),
        ),
    );
    let shader = load_embedded_asset!(world, "temporal.wgsl");
    let cache = world.resource::<PipelineCache>();
    let queue = |clamp: bool| {
        let mut shader_defs = shader_defs.clone();
        let name = if clamp {
            shader_defs.push("CLAMP".into());
            format!("{label}_pipeline")
        } else {
            format!("{label}_unclamped_pipeline")
        };
        cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some(name.into()),
            layout: vec![layout.clone()],
            shader: shader.clone(),
            shader_defs,
            entry_point: Some("accumulate".into()),
            ..default()
        })
    };
    let clamped = queue(true);
    // The voxel term clamps every frame.
    let unclamped = (channels == Channels::One).then(|| queue(false));
    TemporalVariant {
        layout,
        clamped,
        unclamped,
    }
}

impl FromWorld for TemporalPipeline {
    fn from_world(world: &mut World) -> Self {
        Self {
            one: variant(world, Channels::One),
            pair: variant(world, Channels::Pair),
        }
    }
}

/// What one accumulation reads and writes besides its history.
pub(crate) struct AccumulationTextures<'a> {
    /// This frame's value, as the technique wrote it.
    pub current: &'a TextureView,
    /// The accumulated value the next passes read.
    pub output: &'a TextureView,
    pub front: FrontLayerViews<'a>,
}

impl TemporalPipeline {
    /// The bind group of one accumulation, or `None` while the uniforms are not written yet.
    pub fn bind_group(
        &self,
        device: &RenderDevice,
        cache: &PipelineCache,
        view_uniforms: &ViewUniforms,
        channels: Channels,
        history: &TemporalHistory,
        textures: AccumulationTextures,
    ) -> Option<BindGroup> {
        let front = textures.front;
        let (Some(view), Some(temporal)) =
            (view_uniforms.uniforms.binding(), history.uniform.binding())
        else {
            return None;
        };
        // Without motion vectors the history is dropped (see `TemporalHistory::advance`), so any
        // float texture stands in for them.
        let motion = front.motion_vectors.unwrap_or(textures.current);
        let (read, write) = history.views();
        Some(device.create_bind_group(
            "dynamic_ao_temporal_bind_group",
            &cache.get_bind_group_layout(&self.variant(channels).layout),
            &BindGroupEntries::sequential((
                view,
                temporal,
                textures.current,
                front.depth,
                front.normal,
                motion,
                read,
                write,
                textures.output,
            )),
        ))
    }
}

/// The image-space occlusion's accumulation of a view.
#[derive(Component)]
pub(crate) struct TemporalBindGroup(pub(super) BindGroup);

pub(crate) fn prepare_temporal_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline: Res<TemporalPipeline>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    views: Query<(Entity, &DynamicAoTextures, FrontLayer, &TemporalHistory)>,
) {
    for (entity, textures, prepass, history) in &views {
        let front = prepass.views();
        let bind_group = textures
            .raw_occlusion
            .as_ref()
            .zip(front)
            .and_then(|(raw, front)| {
                pipeline.bind_group(
                    &render_device,
                    &pipeline_cache,
                    &view_uniforms,
                    Channels::One,
                    history,
                    AccumulationTextures {
                        current: &raw.default_view,
                        output: &textures.near_occlusion.default_view,
                        front,
                    },
                )
            });
        match bind_group {
            Some(bind_group) => commands
                .entity(entity)
                .insert(TemporalBindGroup(bind_group)),
            None => commands.entity(entity).remove::<TemporalBindGroup>(),
        };
    }
}
