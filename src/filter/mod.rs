//! Filtering of the occlusion buffer.
//!
//! At half resolution, a joint bilateral upsampling first brings the occlusion back to full
//! resolution (Reinbothe, Boubekeur & Alexa 2009, §7, eq. 5–7): each pixel averages the
//! low-resolution texels of the 3 × 3 around its own that lie within 2.5 pixels of it (4 to 6 of
//! them) with the product of Wendland kernels (eq. 3) over screen distance (support 4 pixels),
//! normal difference 1 − n(x)·n(y) (support 1.5; the paper prints 1 + n(x)·n(y), which would
//! favour opposite normals), the texel's distance from the pixel's tangent plane (support two of
//! the pixel's footprints, in place of the paper's world distance with support R, which texels
//! 2.5 pixels away never leave: a fin's top took the occlusion of the gap's floor beside it); the
//! paper's fourth weight, on the difference of occlusion, kept noise and is left out. The
//! screen-distance weight of the texels farther away is under 0.03. One invocation upsamples the
//! 2 × 2 pixels of one texel, reading the eight texels they share once. Where the occlusion was
//! accumulated, the upsampling reads the temporal pass's history of this frame instead of its output: each history texel
//! carries the linear depth and normal it was computed at, so a texel costs one read instead of
//! a depth, a normal and a value read and an unprojection (the upsampling pass took about a
//! quarter less time on lavapipe; the normal is then 8-bit, which moved no visibility by more
//! than 0.001).
//!
//! A separable cross-bilateral blur (Bavoil & Sainz 2008, "Cross Bilateral Filter"): one pass
//! along X into a scratch texture, one along Y back into the occlusion buffer. Each tap is
//! weighted by a Gaussian of its pixel distance and by exp(−(sharpness · Δz / z)²), where Δz is
//! its view-depth difference from the centre pixel, so occlusion does not bleed across
//! silhouettes. Sharpness 0 gives a plain Gaussian. Pixels that show no geometry take no part.
//! The image-space occlusion's blur also weighs each tap by exp(−(normal_sharpness · (1 −
//! n·n₀))²), the angle between its front-layer normal and the centre's: across a crease, a panel
//! line or a thin part the depth hardly changes, and the depth weight alone smeared their
//! occlusion over the surfaces beside them (`AoBlur::normal_sharpness`; BENCHMARKS.md, "The
//! blur weighs by normals"). `reference::filter` is the CPU twin.
//!
//! Under temporal accumulation the image-space blur does not run by default
//! (`AoBlur::accumulated_radius`): the history averages the noise it removed, and its two
//! full-resolution passes cost more than every other pass of the default (BENCHMARKS.md, "The
//! default runs no blur").
//!
//! Without accumulation the blur's Y pass then multiplies into the ray march's occlusion a
//! fine-detail term read from the front layer at full resolution (`AoBlur::detail_reach`; under
//! accumulation the ray march adds it itself, a side a frame; `shaders/fine_detail.wgsl`): along
//! the pixel's row and column,
//! each side's highest surface within a few pixels as a horizon, occluding a cosine-weighted
//! hemisphere by the square of its elevation's sine. It is not from the papers: the ray march's
//! steps, a sixth of R apart, step over grooves and creases a pixel or two wide, which the front
//! layer holds (BENCHMARKS.md, "The blur restores fine detail").
//! `reference::fine_detail::fine_detail_sides` is the CPU twin.
//!
//! On a view without far-field terms the last of these passes (the blur's Y pass, or the
//! upsampling where the blur is off) writes the visibility Bevy's PBR reads itself, where compose
//! would only have copied it: one full-resolution pass fewer, the same values
//! (`DynamicAoView::filter_is_last`).

mod bind_groups;
mod node;
mod pipeline;
pub mod settings;

use bevy::app::{App, Plugin};
use bevy::asset::embedded_asset;
use bevy::core_pipeline::schedule::Core3d;
use bevy::ecs::prelude::*;
use bevy::render::{GpuResourceAppExt, Render, render_resource::PipelineCache};

use crate::capabilities;
use crate::schedule::{DynamicAoPrepare, DynamicAoSystems};
use crate::view::{DynamicAoView, FilterWritesVisibility, PendingPasses, drop_without_ao};

pub(crate) use bind_groups::{BlurBindGroups, FilterInputs};
pub(crate) use pipeline::BlurPipelines;

/// Registers the blur pipelines and passes.
pub struct FilterPlugin;

impl Plugin for FilterPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "blur.wgsl");
        embedded_asset!(app, "upsample.wgsl");
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = capabilities::render_app(app) else {
            return;
        };
        render_app
            .init_gpu_resource::<pipeline::BlurPipelines>()
            .add_systems(
                Render,
                (
                    bind_groups::prepare_blur_bind_groups.in_set(DynamicAoPrepare::BindGroups),
                    drop_without_ao::<(
                        BlurBindGroups,
                        bind_groups::UpsampleBindGroup,
                        bind_groups::VisibilityBindGroup,
                        FilterWritesVisibility,
                    )>
                        .in_set(DynamicAoPrepare::BindGroups),
                    wait_for_filter.in_set(DynamicAoPrepare::Readiness),
                ),
            )
            .add_systems(
                Core3d,
                (
                    node::upsample_pass.in_set(DynamicAoSystems::Upsample),
                    node::blur_pass.in_set(DynamicAoSystems::Filter),
                ),
            );
    }
}

/// A view counts its blur and upsampling passes until they have compiled.
fn wait_for_filter(
    pipeline_cache: Res<PipelineCache>,
    blur: Res<BlurPipelines>,
    mut views: Query<(&DynamicAoView, &mut PendingPasses)>,
) {
    let ready = |id| pipeline_cache.get_compute_pipeline(id).is_some();
    for (view, mut pending) in &mut views {
        pending.wait_for(view.blur_radius == 0 || (ready(blur.one.x) && ready(blur.one.y)));
        pending.wait_for(!view.half_resolution || ready(blur.one.upsample));
        // An accumulated view upsamples from its history (`pipeline::GuidedUpsample`).
        let guided = blur.one.guided.as_ref();
        pending.wait_for(
            !(view.half_resolution && view.temporal) || guided.is_none_or(|g| ready(g.pipeline)),
        );
    }
}
