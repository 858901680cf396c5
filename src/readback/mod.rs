//! Copies of a camera's AO buffer and ND-buffer into images the CPU can read back.
//!
//! Put [`AoReadback`] on a camera that has [`DynamicAo`](crate::DynamicAo), then read its images
//! with Bevy's `Readback::texture`. Tests, benchmarks and the `ao_capture` example use it to
//! compare what the GPU computed with the CPU [`reference`](crate::reference).

mod node;
mod pipeline;

use bevy::app::{App, Plugin};
use bevy::asset::{Assets, Handle, RenderAssetUsages, embedded_asset};
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::ecs::reflect::ReflectComponent;
use bevy::image::Image;
use bevy::math::UVec2;
use bevy::reflect::Reflect;
use bevy::render::{
    GpuResourceAppExt, Render,
    extract_component::{ExtractComponent, ExtractComponentPlugin},
    render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages},
};

use crate::capabilities;
use crate::schedule::{DynamicAoPrepare, DynamicAoSystems};
use crate::view::drop_without_ao;

/// Asks the plugin to copy this camera's AO buffer and both ND-buffer layers every frame.
///
/// All three images must have the camera's physical viewport size (pixels); [`AoReadback::new`]
/// makes them. Where the camera sees no geometry, visibility reads 1. On a frame where the view's
/// AO is not yet its technique's (the first frames of a camera, while the passes of that
/// technique still compile and Bevy's SSAO or nothing fills the texture in their place),
/// visibility reads −1 on every pixel: read again a frame later. Where one of the plugin's
/// pipelines failed to compile for good, the camera keeps Bevy's SSAO and the copy shows it.
#[derive(Component, ExtractComponent, Reflect, Clone, Debug)]
#[reflect(Component, Clone, Debug)]
pub struct AoReadback {
    /// Visibility (1 = open) as Bevy's PBR lighting receives it, `R32Float`; −1 on frames where the
    /// technique's passes have not compiled yet.
    pub visibility: Handle<Image>,
    /// Front layer: world-space unit normal in `rgb`, reverse-Z depth in `a` (0 = nothing),
    /// `Rgba32Float`.
    pub front: Handle<Image>,
    /// Back-face layer, same layout as `front`. All zero when the back layer is off; the normal
    /// is zero unless the near field reads it (the other techniques draw the layer's depth only).
    pub back: Handle<Image>,
}

impl AoReadback {
    /// Makes the three images for a viewport of `size` pixels. Visibility starts at −1, so that
    /// it reads "not there yet" until the first copy, which waits for its own pipeline.
    pub fn new(images: &mut Assets<Image>, size: UVec2) -> Self {
        let mut image = |format, fill: Option<f32>| {
            let extent = Extent3d {
                width: size.x.max(1),
                height: size.y.max(1),
                depth_or_array_layers: 1,
            };
            let (dimension, usage) = (TextureDimension::D2, RenderAssetUsages::RENDER_WORLD);
            let mut image = match fill {
                Some(value) => {
                    Image::new_fill(extent, dimension, &value.to_le_bytes(), format, usage)
                }
                None => Image::new_uninit(extent, dimension, format, usage),
            };
            image.texture_descriptor.usage |=
                TextureUsages::STORAGE_BINDING | TextureUsages::COPY_SRC;
            images.add(image)
        };
        Self {
            visibility: image(TextureFormat::R32Float, Some(-1.0)),
            front: image(TextureFormat::Rgba32Float, None),
            back: image(TextureFormat::Rgba32Float, None),
        }
    }
}

/// Registers the read-back copy pass.
pub struct ReadbackPlugin;

impl Plugin for ReadbackPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "readback.wgsl");
        app.add_plugins(ExtractComponentPlugin::<AoReadback>::default());
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_gpu_resource::<pipeline::ReadbackPipeline>()
            .add_systems(
                Render,
                (
                    pipeline::prepare_readback_bind_groups,
                    drop_without_ao::<pipeline::ReadbackBindGroup>,
                )
                    .in_set(DynamicAoPrepare::BindGroups),
            )
            .add_systems(Core3d, node::readback_pass.in_set(DynamicAoSystems::Debug));
    }
}
