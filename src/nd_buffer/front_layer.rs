//! The front layer of the ND-buffer as every pass reads it: single-sampled, the size of the
//! viewport, with the viewport's first pixel at texel (0, 0).
//!
//! On a camera without MSAA that renders to its whole target, Bevy's prepass is exactly that,
//! and the passes read it directly. Elsewhere it is not:
//! - on an MSAA camera the prepass is multisampled;
//! - on a camera with a viewport (split screen) it has the size of the render target, with the
//!   viewport's pixels somewhere inside it.
//!
//! There the copy pass of this file first copies the viewport's pixels into textures of its own
//! (depth, normals and, where the camera has them, motion vectors), so that no pass needs a
//! multisampled variant or a viewport offset. The passes reconstruct each pixel at its centre,
//! where no sample of a multisampled pixel lies, so of such a pixel it keeps what a
//! single-sampled prepass would show there. Which surface that is, no sample says: at a
//! silhouette the samples see two, and a triangle thinner than a pixel can cover its centre and
//! none of its samples. So on an MSAA camera the opaque meshes are first drawn again,
//! single-sampled, through the mesh phase [`CentreSample3d`]: depth and vertex normals at pixel
//! centres. The copy keeps that depth, and takes the normal (normal-mapped, as Bevy's prepass
//! draws it) and the motion vector of the sample that lies on the same surface; where none does
//! and every sample lies behind the centre's surface (a sliver in front), the centre's own
//! normal. Where a sample lies in front of it, the centre sample missed a mesh (an alpha-masked
//! one, whose discarded fragments only its material knows), and the copy falls back to the
//! samples alone: their mean where they lie on one surface (the standard sample positions are
//! centred on the pixel), and at a silhouette the surface most samples see, its depth carried to
//! the centre along its plane (an average of two surfaces would be a point on neither).
//! `front_layer.wgsl` says why a sample's own depth is not enough.

use bevy::asset::{Handle, load_embedded_asset};
use bevy::core_pipeline::FullscreenShader;
use bevy::core_pipeline::prepass::{
    MOTION_VECTOR_PREPASS_FORMAT, MotionVectorPrepass, ViewPrepassTextures,
};
use bevy::ecs::prelude::*;
use bevy::ecs::query::QueryData;
use bevy::render::{
    camera::ExtractedCamera,
    diagnostic::RecordDiagnostics,
    render_phase::{SortedRenderPhase, ViewSortedRenderPhases},
    render_resource::{
        binding_types::{
            texture_2d, texture_2d_multisampled, texture_depth_2d, texture_depth_2d_multisampled,
            uniform_buffer,
        },
        *,
    },
    renderer::{RenderContext, RenderDevice, ViewQuery},
    texture::{CachedTexture, TextureCache},
    view::{ExtractedView, Msaa, ViewUniform, ViewUniformOffset, ViewUniforms},
};
use bevy::shader::{Shader, ShaderDefVal};
use bevy::utils::default;

use super::node::{LayerTargets, cleared, draw_layer};
use super::phase::CentreSample3d;
use crate::view::{
    DEPTH_FORMAT, DynamicAoView, NORMAL_FORMAT, PendingPasses, view_size, view_texture,
};

/// The front layer a view's passes bind: Bevy's prepass, or this view's copy of it.
#[derive(QueryData)]
pub(crate) struct FrontLayer {
    prepass: &'static ViewPrepassTextures,
    copy: Option<&'static FrontLayerCopy>,
}

impl FrontLayerItem<'_, '_> {
    /// Reverse-Z depth (`Depth32Float`), `None` while there is none to read.
    pub fn depth(&self) -> Option<&TextureView> {
        match self.copy {
            Some(copy) => Some(&copy.depth.default_view),
            None => self.single_sampled().then(|| self.prepass.depth_view())?,
        }
    }

    /// World-space normals encoded as `n * 0.5 + 0.5` (`Rgb10a2Unorm`).
    pub fn normal(&self) -> Option<&TextureView> {
        match self.copy {
            Some(copy) => Some(&copy.normal.default_view),
            None => self.single_sampled().then(|| self.prepass.normal_view())?,
        }
    }

    /// Bevy's motion vectors (`Rg16Float`, UV units), where the camera has them.
    pub fn motion_vectors(&self) -> Option<&TextureView> {
        match self.copy {
            Some(copy) => copy.motion_vectors.as_ref().map(|t| &t.default_view),
            None => self
                .single_sampled()
                .then(|| self.prepass.motion_vectors_view())?,
        }
    }

    /// Depth, normals and motion vectors together, `None` while depth or normals are missing.
    pub fn views(&self) -> Option<FrontLayerViews<'_>> {
        Some(FrontLayerViews {
            depth: self.depth()?,
            normal: self.normal()?,
            motion_vectors: self.motion_vectors(),
        })
    }

    /// A view waiting for its copy must not bind the multisampled prepass in its place: the
    /// passes' layouts are single-sampled, and wgpu stops the app on the mismatch.
    fn single_sampled(&self) -> bool {
        self.prepass
            .depth
            .as_ref()
            .is_some_and(|depth| depth.texture.texture.sample_count() == 1)
    }
}

/// The texture views of a front layer (see [`FrontLayerItem`]'s accessors for their formats).
#[derive(Clone, Copy)]
pub(crate) struct FrontLayerViews<'a> {
    pub depth: &'a TextureView,
    pub normal: &'a TextureView,
    pub motion_vectors: Option<&'a TextureView>,
}

/// A view's copy of its front layer, made where Bevy's prepass is not one the passes can read.
#[derive(Component)]
pub(crate) struct FrontLayerCopy {
    depth: CachedTexture,
    normal: CachedTexture,
    motion_vectors: Option<CachedTexture>,
    /// The opaque meshes' single-sampled depth and normals (MSAA cameras): which surface each
    /// pixel's centre shows.
    centre: Option<CentreSample>,
    pipeline: CachedRenderPipelineId,
    key: CopyKey,
}

/// Format of the centre sample's depth gradient: reverse-Z depth per pixel in x and y, to full
/// precision (the copy tells a sample on the centre's triangle from one on its neighbour by
/// differences of a millionth of the depth).
pub(crate) const DEPTH_GRADIENT_FORMAT: TextureFormat = TextureFormat::Rg32Float;

/// The textures of [`CentreSample3d`], the size of the viewport.
struct CentreSample {
    depth: CachedTexture,
    normal: CachedTexture,
    depth_gradient: CachedTexture,
}

/// What the copy pass reads.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(crate) struct CopyKey {
    /// Samples per pixel of the prepass: 1, or the MSAA sample count. A constant of the shader,
    /// so that its loops over the samples unroll and index the sample positions statically.
    samples: u32,
    /// The camera has a motion-vector prepass.
    motion_vectors: bool,
}

#[derive(Resource)]
pub(crate) struct FrontLayerCopyPipeline {
    fullscreen: FullscreenShader,
    shader: Handle<Shader>,
}

pub(crate) fn init_front_layer_copy_pipeline(
    mut commands: Commands,
    fullscreen: Res<FullscreenShader>,
    asset_server: Res<bevy::asset::AssetServer>,
) {
    commands.insert_resource(FrontLayerCopyPipeline {
        fullscreen: fullscreen.clone(),
        shader: load_embedded_asset!(asset_server.as_ref(), "front_layer.wgsl"),
    });
}

fn layout(key: CopyKey) -> BindGroupLayoutDescriptor {
    let (depth, float) = if key.samples > 1 {
        (
            texture_depth_2d_multisampled(),
            texture_2d_multisampled(TextureSampleType::Float { filterable: false }),
        )
    } else {
        (
            texture_depth_2d(),
            texture_2d(TextureSampleType::Float { filterable: false }),
        )
    };
    let mut entries = vec![
        uniform_buffer::<ViewUniform>(true).build(0, ShaderStages::FRAGMENT),
        depth.build(1, ShaderStages::FRAGMENT),
        float.build(2, ShaderStages::FRAGMENT),
    ];
    if key.motion_vectors {
        entries.push(float.build(3, ShaderStages::FRAGMENT));
    }
    if key.samples > 1 {
        entries.push(texture_depth_2d().build(4, ShaderStages::FRAGMENT));
        let float = texture_2d(TextureSampleType::Float { filterable: false });
        entries.push(float.build(5, ShaderStages::FRAGMENT));
        entries.push(float.build(6, ShaderStages::FRAGMENT));
    }
    BindGroupLayoutDescriptor::new("dynamic_ao_front_layer_copy_layout", &entries)
}

impl SpecializedRenderPipeline for FrontLayerCopyPipeline {
    type Key = CopyKey;

    fn specialize(&self, key: Self::Key) -> RenderPipelineDescriptor {
        let mut shader_defs = Vec::new();
        let target = |format| {
            Some(ColorTargetState {
                format,
                blend: None,
                write_mask: ColorWrites::ALL,
            })
        };
        let mut targets = vec![target(NORMAL_FORMAT)];
        if key.samples > 1 {
            shader_defs.push("MULTISAMPLED".into());
            shader_defs.push(ShaderDefVal::UInt("SAMPLES".into(), key.samples));
        }
        if key.motion_vectors {
            shader_defs.push("MOTION_VECTORS".into());
            targets.push(target(MOTION_VECTOR_PREPASS_FORMAT));
        }
        RenderPipelineDescriptor {
            label: Some("dynamic_ao_front_layer_copy_pipeline".into()),
            layout: vec![layout(key)],
            vertex: self.fullscreen.to_vertex_state(),
            fragment: Some(FragmentState {
                shader: self.shader.clone(),
                shader_defs,
                targets,
                ..default()
            }),
            depth_stencil: Some(DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(CompareFunction::Always),
                stencil: default(),
                bias: default(),
            }),
            ..default()
        }
    }
}

/// Whether the passes of a view can read Bevy's prepass as it is.
fn prepass_is_readable(camera: &ExtractedCamera, msaa: &Msaa) -> bool {
    let whole_target = camera.viewport.as_ref().is_none_or(|viewport| {
        viewport.physical_position == bevy::math::UVec2::ZERO
            && Some(viewport.physical_size) == camera.physical_target_size
    });
    msaa.samples() == 1 && whole_target
}

/// Gives each view whose prepass the passes cannot read its copy's textures and pipeline, and
/// takes them from the others.
pub(crate) fn prepare_front_layer_copies(
    mut commands: Commands,
    mut texture_cache: ResMut<TextureCache>,
    render_device: Res<RenderDevice>,
    pipeline_cache: Res<PipelineCache>,
    mut pipelines: ResMut<SpecializedRenderPipelines<FrontLayerCopyPipeline>>,
    pipeline: Res<FrontLayerCopyPipeline>,
    views: Query<(Entity, &ExtractedCamera, &Msaa, Has<MotionVectorPrepass>), With<DynamicAoView>>,
) {
    for (entity, camera, msaa, motion_vectors) in &views {
        let size = view_size(camera);
        let (false, Some(size)) = (prepass_is_readable(camera, msaa), size) else {
            commands.entity(entity).remove::<FrontLayerCopy>();
            continue;
        };
        let key = CopyKey {
            samples: msaa.samples(),
            motion_vectors,
        };
        let usage = TextureUsages::RENDER_ATTACHMENT | TextureUsages::TEXTURE_BINDING;
        let mut texture = |label, format| {
            view_texture(
                &mut texture_cache,
                &render_device,
                label,
                size,
                format,
                usage,
            )
        };
        commands.entity(entity).insert(FrontLayerCopy {
            depth: texture("dynamic_ao_front_depth_copy", DEPTH_FORMAT),
            normal: texture("dynamic_ao_front_normal_copy", NORMAL_FORMAT),
            motion_vectors: motion_vectors.then(|| {
                texture(
                    "dynamic_ao_motion_vectors_copy",
                    MOTION_VECTOR_PREPASS_FORMAT,
                )
            }),
            centre: (key.samples > 1).then(|| CentreSample {
                depth: texture("dynamic_ao_centre_depth", DEPTH_FORMAT),
                normal: texture("dynamic_ao_centre_normal", NORMAL_FORMAT),
                depth_gradient: texture("dynamic_ao_centre_depth_gradient", DEPTH_GRADIENT_FORMAT),
            }),
            pipeline: pipelines.specialize(&pipeline_cache, &pipeline, key),
            key,
        });
    }
}

/// A view with a copy counts until the copy's pipeline has compiled.
pub(crate) fn wait_for_front_layer_copy(
    pipeline_cache: Res<PipelineCache>,
    mut views: Query<(&FrontLayerCopy, &mut PendingPasses)>,
) {
    for (copy, mut pending) in &mut views {
        pending.wait_for(pipeline_cache.get_render_pipeline(copy.pipeline).is_some());
    }
}

#[derive(Component)]
pub(crate) struct FrontLayerCopyBindGroup(BindGroup);

pub(crate) fn prepare_front_layer_copy_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    views: Query<(Entity, &FrontLayerCopy, &ViewPrepassTextures)>,
) {
    let Some(view_binding) = view_uniforms.uniforms.binding() else {
        return;
    };
    for (entity, copy, prepass) in &views {
        let (Some(depth), Some(normal)) = (prepass.depth_view(), prepass.normal_view()) else {
            commands.entity(entity).remove::<FrontLayerCopyBindGroup>();
            continue;
        };
        let mut entries = vec![
            BindGroupEntry {
                binding: 0,
                resource: view_binding.clone(),
            },
            BindGroupEntry {
                binding: 1,
                resource: BindingResource::TextureView(depth),
            },
            BindGroupEntry {
                binding: 2,
                resource: BindingResource::TextureView(normal),
            },
        ];
        if copy.key.motion_vectors {
            let Some(motion_vectors) = prepass.motion_vectors_view() else {
                commands.entity(entity).remove::<FrontLayerCopyBindGroup>();
                continue;
            };
            entries.push(BindGroupEntry {
                binding: 3,
                resource: BindingResource::TextureView(motion_vectors),
            });
        }
        if let Some(centre) = &copy.centre {
            entries.push(BindGroupEntry {
                binding: 4,
                resource: BindingResource::TextureView(&centre.depth.default_view),
            });
            entries.push(BindGroupEntry {
                binding: 5,
                resource: BindingResource::TextureView(&centre.normal.default_view),
            });
            entries.push(BindGroupEntry {
                binding: 6,
                resource: BindingResource::TextureView(&centre.depth_gradient.default_view),
            });
        }
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_front_layer_copy_bind_group",
            &pipeline_cache.get_bind_group_layout(&layout(copy.key)),
            &entries,
        );
        commands
            .entity(entity)
            .insert(FrontLayerCopyBindGroup(bind_group));
    }
}

/// Copies the viewport's pixels of the prepass into the view's own front layer, on an MSAA
/// camera after drawing the front faces' depth at pixel centres.
pub(crate) fn front_layer_copy_pass(
    world: &World,
    view: ViewQuery<(
        &FrontLayerCopy,
        &FrontLayerCopyBindGroup,
        &ViewUniformOffset,
        &ExtractedCamera,
        &ExtractedView,
    )>,
    pipeline_cache: Res<PipelineCache>,
    centre_phases: Res<ViewSortedRenderPhases<CentreSample3d>>,
    mut ctx: RenderContext,
) {
    let view_entity = view.entity();
    let (copy, bind_group, view_offset, camera, extracted_view) = view.into_inner();
    let Some(pipeline) = pipeline_cache.get_render_pipeline(copy.pipeline) else {
        return;
    };
    if let Some(centre) = &copy.centre {
        let phase = centre_phases.get(&extracted_view.retained_view_entity);
        draw_centre_sample(&mut ctx, world, view_entity, camera, centre, phase);
    }
    let mut color_attachments = vec![cleared(&copy.normal.default_view)];
    color_attachments.extend(
        copy.motion_vectors
            .as_ref()
            .map(|texture| cleared(&texture.default_view)),
    );
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("dynamic_ao_front_layer_copy"),
        color_attachments: &color_attachments,
        depth_stencil_attachment: Some(RenderPassDepthStencilAttachment {
            view: &copy.depth.default_view,
            depth_ops: Some(Operations {
                load: LoadOp::Clear(0.0),
                store: StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let pass_span = diagnostics.pass_span(&mut pass, "dynamic_ao_front_layer_copy");
    pass.set_render_pipeline(pipeline);
    pass.set_bind_group(0, &bind_group.0, &[view_offset.offset]);
    pass.draw(0..3, 0..1);
    pass_span.end(&mut pass);
}

/// Draws the meshes of Bevy's prepass single-sampled into `target`.
fn draw_centre_sample(
    ctx: &mut RenderContext,
    world: &World,
    view_entity: Entity,
    camera: &ExtractedCamera,
    target: &CentreSample,
    phase: Option<&SortedRenderPhase<CentreSample3d>>,
) {
    draw_layer(
        ctx,
        world,
        view_entity,
        camera,
        LayerTargets {
            label: "dynamic_ao_centre_sample",
            colors: &[
                cleared(&target.normal.default_view),
                cleared(&target.depth_gradient.default_view),
            ],
            depth: &target.depth.default_view,
        },
        phase,
        |_| {},
    );
}
