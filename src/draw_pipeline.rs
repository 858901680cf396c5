//! What more than one of the plugin's draw pipelines share: the blends with which far-field
//! occluders combine, and the full-screen overlays drawn over a view's image.

use bevy::asset::Handle;
use bevy::core_pipeline::FullscreenShader;
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, BlendComponent, BlendFactor, BlendOperation, BlendState,
    ColorTargetState, ColorWrites, FragmentState, RenderPipelineDescriptor, TextureFormat,
};
use bevy::shader::Shader;
use bevy::utils::default;

/// dst × (1 − src): each occluder's occlusion multiplies the visibility the others left
/// (Malmer et al. 2005, §3.3.2, for fields; the sphere proxies blend the same way, see `spheres`).
pub(crate) const MULTIPLY_VISIBILITY: BlendComponent = BlendComponent {
    src_factor: BlendFactor::Zero,
    dst_factor: BlendFactor::OneMinusSrc,
    operation: BlendOperation::Add,
};

/// max(dst, src): the largest single occlusion among the occluders that join by their union
/// (`geometry::union`), for the union compose takes (the sphere splat's and the fields' alpha).
pub(crate) const LARGEST_OCCLUSION: BlendComponent = BlendComponent {
    src_factor: BlendFactor::One,
    dst_factor: BlendFactor::One,
    operation: BlendOperation::Max,
};

/// A full-screen pass that draws `shader`'s fragment stage into a view's image of `format`,
/// blended as `blend`: the debug views.
pub(crate) fn overlay_pipeline(
    label: &'static str,
    layout: &BindGroupLayoutDescriptor,
    fullscreen: &FullscreenShader,
    shader: &Handle<Shader>,
    format: TextureFormat,
    blend: Option<BlendState>,
) -> RenderPipelineDescriptor {
    RenderPipelineDescriptor {
        label: Some(label.into()),
        layout: vec![layout.clone()],
        vertex: fullscreen.to_vertex_state(),
        fragment: Some(FragmentState {
            shader: shader.clone(),
            targets: vec![Some(ColorTargetState {
                format,
                blend,
                write_mask: ColorWrites::ALL,
            })],
            ..default()
        }),
        ..default()
    }
}
