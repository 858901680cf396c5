//! The bind groups of the blur and upsampling passes, made each frame for every view that
//! filters.

use bevy::ecs::prelude::*;
use bevy::pbr::ScreenSpaceAmbientOcclusionResources;
use bevy::render::{render_resource::*, renderer::RenderDevice};

use super::pipeline::{BlurPipelines, FilterPipelines, GuidedUpsample};
use crate::compose::{ParkedSsao, visibility_texture};
use crate::nd_buffer::FrontLayer;
use crate::temporal::TemporalHistory;
use crate::view::{DynamicAoTextures, DynamicAoView, FilterWritesVisibility, ViewBindings};

/// What every blur and upsampling pass of a view reads besides its occlusion buffers.
pub(crate) struct FilterInputs<'a> {
    pub view: BindingResource<'a>,
    pub settings: BindingResource<'a>,
    pub depth: &'a TextureView,
    /// The normals the blur weighs by ([`DynamicAoTextures::blur_normal`]); the voxel term's
    /// blur weighs by depth alone, and any float texture stands in.
    pub normal: &'a TextureView,
}

/// The bind group of an upsampling pass over `layout`: `low` (half size) into `full`, and where
/// `blur_normals` is given, the front layer's `normal` copied there for the blur.
fn upsample_bind_group(
    device: &RenderDevice,
    pipeline_cache: &PipelineCache,
    layout: &BindGroupLayoutDescriptor,
    label: &'static str,
    inputs: &FilterInputs,
    normal: &TextureView,
    [low, full]: [&TextureView; 2],
    blur_normals: Option<&TextureView>,
) -> BindGroup {
    let layout = pipeline_cache.get_bind_group_layout(layout);
    let mut entries = DynamicBindGroupEntries::sequential((
        inputs.view.clone(),
        inputs.settings.clone(),
        inputs.depth,
        normal,
        low,
        full,
    ));
    if let Some(blur_normals) = blur_normals {
        entries = entries.extend_sequential((blur_normals,));
    }
    device.create_bind_group(label, &layout, &entries)
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
            None,
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
                    inputs.normal,
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
        let (Some(depth), Some(front_normal)) = (prepass.depth(), prepass.normal()) else {
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
            normal: &textures.blur_normal.default_view,
        };
        let occlusion = &textures.full_occlusion.default_view;
        let half_normal = Some(front_normal).filter(|_| view.half_resolution);
        // The history the temporal pass writes this frame, where it runs (it runs wherever the
        // technique writes a raw buffer for it).
        let guide = history
            .filter(|_| view.temporal && textures.raw_occlusion.is_some())
            .map(TemporalHistory::written);
        // The bind group of an upsampling from `low` (half size) into `output` over `layout`, or,
        // where there is a guide and `guided` has compiled, of the guided one; and which it is.
        // Where `blur_normals` is given, the upsampling copies the front layer's normals there.
        let upsample = |layout,
                        guided: Option<&GuidedUpsample>,
                        low,
                        output,
                        blur_normals: Option<&TextureView>,
                        label| {
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
                    blur_normals,
                )
            });
            bind_group.map(|bind_group| (bind_group, guided.is_some()))
        };
        let low = &textures.near_occlusion.default_view;
        let one = &pipelines.one;
        let label = "dynamic_ao_upsample_bind_group";
        let blur_normals = Some(&textures.blur_normal.default_view);
        match upsample(
            &one.upsample_layout,
            one.guided.as_ref(),
            low,
            occlusion,
            blur_normals,
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
                        inputs.normal,
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
                None,
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
