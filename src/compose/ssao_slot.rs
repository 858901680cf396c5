//! The texture Bevy's PBR shader reads the ambient occlusion from, on cameras where Bevy's own
//! SSAO would not provide a usable one.
//!
//! PBR reads visibility from `ScreenSpaceAmbientOcclusionResources` (mesh view binding 17), which
//! Bevy makes for views carrying `ScreenSpaceAmbientOcclusion`. Two camera setups need more:
//!
//! - **MSAA.** Bevy's SSAO refuses MSAA cameras (its extraction logs an error and skips them),
//!   and its bind groups would bind the multisampled prepass where single-sampled textures are
//!   expected, which wgpu rejects. The main world therefore keeps the component off an MSAA
//!   camera, and the render world gets it here instead, once our passes have compiled (so PBR
//!   never reads a texture nobody wrote). While Bevy makes its bind groups, the view's resources
//!   are parked in [`ParkedSsao`], so Bevy's SSAO skips the view, and are put back afterwards;
//!   the mesh view bind groups are then made again so that they include the texture.
//! - **Split screen.** PBR reads the texture at framebuffer pixels, but Bevy sizes it to the
//!   viewport, so a viewport that does not start at the target's corner reads outside it. On
//!   such a view the texture is replaced by one the size of the target, and compose writes at
//!   the viewport's place in it.
//!
//! And until anything writes a view's texture (our passes and Bevy's SSAO both still compiling,
//! which lasts while their shaders wait on the asset loader), it holds zeros, which PBR reads as
//! ambient light fully occluded: a black image. On such a frame a texture that reads 1 (open)
//! stands in; whichever pass compiles first writes into it.

use bevy::camera::{Camera, Camera3d};
use bevy::ecs::prelude::*;
use bevy::math::UVec2;
use bevy::pbr::{
    ScreenSpaceAmbientOcclusion, ScreenSpaceAmbientOcclusionResources, SsaoPipelineId,
};
use bevy::platform::collections::HashMap;
use bevy::render::{
    Extract,
    camera::ExtractedCamera,
    render_resource::{
        Extent3d, PipelineCache, TexelCopyBufferLayout, TextureFormat, TextureUsages,
    },
    renderer::{RenderAdapter, RenderDevice, RenderQueue},
    sync_world::RenderEntity,
    texture::{CachedTexture, TextureCache},
    view::Msaa,
};

use super::pipeline::bevy_ssao_format;
use crate::settings::DynamicAo;
use crate::view::{AoPassesReady, DynamicAoView, view_texture};

/// Marks a render-world view whose `ScreenSpaceAmbientOcclusion` this module inserted (an MSAA
/// camera), not Bevy's extraction.
#[derive(Component)]
pub(crate) struct MsaaSsaoSlot;

/// A view's SSAO resources, held aside while Bevy makes its SSAO bind groups.
#[derive(Component)]
pub(crate) struct ParkedSsao(ScreenSpaceAmbientOcclusionResources);

/// The texture compose writes visibility into and PBR reads it from: Bevy's, or the parked one.
pub(crate) fn visibility_texture<'a>(
    resources: Option<&'a ScreenSpaceAmbientOcclusionResources>,
    parked: Option<&'a ParkedSsao>,
) -> Option<&'a CachedTexture> {
    resources
        .or(parked.map(|parked| &parked.0))
        .map(|resources| &resources.screen_space_ambient_occlusion_texture)
}

/// Gives the render-world view of each active MSAA camera with [`DynamicAo`] Bevy's SSAO
/// component once its passes are ready, and takes it away when the camera no longer qualifies.
pub(crate) fn extract_msaa_slots(
    mut commands: Commands,
    cameras: Extract<
        Query<
            (
                RenderEntity,
                &Camera,
                Option<&DynamicAo>,
                &Msaa,
                Has<ScreenSpaceAmbientOcclusion>,
            ),
            With<Camera3d>,
        >,
    >,
    ready: Query<(), With<AoPassesReady>>,
    slots: Query<Entity, With<MsaaSsaoSlot>>,
) {
    // Render entity → whether the main world gives it Bevy's component itself.
    let mut unserved = HashMap::new();
    for (entity, camera, ao, msaa, bevy_ssao) in &cameras {
        let served =
            camera.is_active && *msaa != Msaa::Off && ao.is_some_and(DynamicAo::works_with_msaa);
        if !served {
            unserved.insert(entity, bevy_ssao);
            continue;
        }
        if slots.contains(entity) || ready.contains(entity) {
            commands
                .entity(entity)
                .insert((ScreenSpaceAmbientOcclusion::default(), MsaaSsaoSlot));
        }
    }
    for entity in &slots {
        match unserved.get(&entity) {
            // Bevy's extraction now manages the component.
            Some(true) => {
                commands.entity(entity).remove::<MsaaSsaoSlot>();
            }
            // Bevy never takes its SSAO textures off a view; left there, its SSAO bind groups
            // would be made next frame with the multisampled prepass, which fails validation.
            Some(false) => {
                commands.entity(entity).remove::<(
                    MsaaSsaoSlot,
                    ScreenSpaceAmbientOcclusion,
                    ScreenSpaceAmbientOcclusionResources,
                )>();
            }
            // The camera is gone; its render entity goes with it.
            None => {}
        }
    }
}

/// On views whose viewport does not start at the target's corner, replaces the visibility
/// texture with one the size of the target.
pub(crate) fn place_split_screen_textures(
    mut texture_cache: ResMut<TextureCache>,
    render_device: Res<RenderDevice>,
    adapter: Res<RenderAdapter>,
    mut views: Query<(
        &ExtractedCamera,
        &DynamicAoView,
        &mut ScreenSpaceAmbientOcclusionResources,
    )>,
) {
    for (camera, view, mut resources) in &mut views {
        let (true, Some(viewport), Some(target)) = (
            view.replaces_bevy_ssao(),
            camera.viewport.as_ref(),
            camera.physical_target_size,
        ) else {
            continue;
        };
        if viewport.physical_position == UVec2::ZERO || target.min_element() == 0 {
            continue;
        }
        resources.screen_space_ambient_occlusion_texture = view_texture(
            &mut texture_cache,
            &render_device,
            "dynamic_ao_split_screen_visibility",
            target,
            bevy_ssao_format(&adapter),
            TextureUsages::STORAGE_BINDING | TextureUsages::TEXTURE_BINDING,
        );
    }
}

/// Whether Bevy's SSAO pass can run on a view this frame: it has the pipeline id and the pipeline
/// has compiled.
pub(crate) fn bevy_ssao_runs(id: Option<&SsaoPipelineId>, cache: &PipelineCache) -> bool {
    id.is_some_and(|id| cache.get_compute_pipeline(id.0).is_some())
}

/// Where nothing will write a view's texture this frame (see the module's docs), puts one that
/// reads 1 in its place. Our passes count as writing from the frame after they were all ready;
/// on the frame they become ready they write into the stand-in.
pub(crate) fn stand_in_open_textures(
    mut texture_cache: ResMut<TextureCache>,
    render_device: Res<RenderDevice>,
    render_queue: Res<RenderQueue>,
    pipeline_cache: Res<PipelineCache>,
    mut views: Query<(
        &DynamicAoView,
        Has<AoPassesReady>,
        Option<&SsaoPipelineId>,
        &mut ScreenSpaceAmbientOcclusionResources,
    )>,
) {
    for (view, ours_ready, bevy_ssao, mut resources) in &mut views {
        let ours = view.replaces_bevy_ssao() && ours_ready;
        if ours || bevy_ssao_runs(bevy_ssao, &pipeline_cache) {
            continue;
        }
        let texture = &resources.screen_space_ambient_occlusion_texture.texture;
        let (size, format) = (texture.size(), texture.format());
        // 1.0 as a half float is 0x3c00.
        let (f16_one, f32_one) = (0x3c00u16.to_le_bytes(), 1.0f32.to_le_bytes());
        let one: &[u8] = match format {
            TextureFormat::R16Float => &f16_one,
            _ => &f32_one,
        };
        let stand_in = view_texture(
            &mut texture_cache,
            &render_device,
            "dynamic_ao_open_visibility",
            UVec2::new(size.width, size.height),
            format,
            TextureUsages::STORAGE_BINDING
                | TextureUsages::TEXTURE_BINDING
                | TextureUsages::COPY_DST,
        );
        let texels = one.repeat((size.width * size.height) as usize);
        render_queue.write_texture(
            stand_in.texture.as_image_copy(),
            &texels,
            TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(size.width * one.len() as u32),
                rows_per_image: None,
            },
            Extent3d {
                depth_or_array_layers: 1,
                ..size
            },
        );
        resources.screen_space_ambient_occlusion_texture = stand_in;
    }
}

/// Holds the SSAO resources of MSAA views aside while Bevy makes its bind groups.
pub(crate) fn park_msaa_resources(
    world: &mut World,
    views: &mut QueryState<
        Entity,
        (
            With<MsaaSsaoSlot>,
            With<ScreenSpaceAmbientOcclusionResources>,
        ),
    >,
) {
    let views: Vec<Entity> = views.iter(world).collect();
    for entity in views {
        let mut view = world.entity_mut(entity);
        if let Some(resources) = view.take::<ScreenSpaceAmbientOcclusionResources>() {
            view.insert(ParkedSsao(resources));
        }
    }
}

/// Puts the parked resources back, for the main pass.
pub(crate) fn restore_msaa_resources(
    world: &mut World,
    views: &mut QueryState<Entity, With<ParkedSsao>>,
) {
    let views: Vec<Entity> = views.iter(world).collect();
    for entity in views {
        let mut view = world.entity_mut(entity);
        if let Some(ParkedSsao(resources)) = view.take::<ParkedSsao>() {
            view.insert(resources);
        }
    }
}

/// Whether any view's SSAO resources were parked this frame, so that the mesh view bind groups
/// must be made again.
pub(crate) fn any_msaa_slot(views: Query<(), With<MsaaSsaoSlot>>) -> bool {
    !views.is_empty()
}
