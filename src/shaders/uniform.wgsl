// The per-view uniform every pass reads; `view::DynamicAoUniform` on the Rust side, field for
// field. Each field is named after the `DynamicAo` setting it comes from.

#define_import_path bevy_dynamic_ao::uniform

struct DynamicAoUniform {
    // Reach of the image-space technique, metres: R, or the near-field radius under CountOnce.
    image_space_radius: f32,
    intensity: f32,
    // Near field: most and fewest samples per receiver and layer, 1 when the near field runs
    // with the back-face layer (the one case whose layer holds normals).
    near_field_max_samples: u32,
    near_field_min_samples: u32,
    near_field_back_layer: u32,
    // 1 when an image-space technique (near field, horizon or ray march) is on.
    image_space: u32,
    // Cross-bilateral blur: half-width in pixels (0 = off), depth and normal sharpness (no unit).
    blur_radius: u32,
    blur_sharpness: f32,
    blur_normal_sharpness: f32,
    // Reach of the fine-detail term the blur's Y pass multiplies in, all four sides, without
    // temporal accumulation, pixels (0 = off).
    blur_detail_reach: u32,
    // Reach of the fine-detail term the ray march adds itself, a side a frame, under temporal
    // accumulation, pixels (0 = off).
    march_detail_reach: u32,
    // Horizon-based AO: directions, steps per direction, angle bias (radians), W0, contrast.
    horizon_directions: u32,
    horizon_steps: u32,
    horizon_angle_bias: f32,
    horizon_attenuation: f32,
    horizon_contrast: f32,
    // 0 low, 1 normal, 2 high.
    horizon_mode: u32,
    // Ray-marched reference: directions, elevations per direction, steps per ray.
    ray_march_directions: u32,
    ray_march_elevations: u32,
    ray_march_steps: u32,
    // How far behind the back-face layer a step still counts as blocked, metres.
    ray_march_thickness: f32,
    // 1 when the ray march marches one texel of two each frame, a checkerboard that alternates.
    ray_march_checkerboard: u32,
    // Pixels per texel of the sphere and field splats' buffers in each axis: 1, or 2 at half
    // resolution (compose upsamples them, `joint_upsample`).
    far_resolution_scale: u32,
    // 1 when sphere occluders take part.
    spheres: u32,
    // 0: near + far, 1: max(near, far), 2: counted once, 1 − (1 − near)(1 − far).
    far_field_blend: u32,
    // 1 when AO field occluders take part.
    fields: u32,
    // 1 when voxel volumes take part.
    voxels: u32,
    // R, metres: far-field terms count occluders within it.
    radius: f32,
    // The near field's reach under CountOnce, metres: far-field terms leave out the occluders
    // within it that the ND-buffer holds. 0 where the far field counts every occluder.
    near_field_radius: f32,
    // 1 when the back-face layer is drawn.
    seen_back_layer: u32,
    // The frame's place in the sample pattern's sequence: 0 without temporal accumulation.
    frame_index: u32,
    // Frames the temporal history averages (1 without accumulation).
    temporal_frames: f32,
    // Blur half-width of the voxel term, pixels (0 = off): the same under accumulation.
    voxel_blur_radius: u32,
    // Where the camera's viewport starts in its render target, pixels.
    viewport_origin: vec2<u32>,
    // The camera's RenderLayers as bits: layer n is bit n % 32 of word n / 32, layers past 62
    // share the last bit (`view::layers`).
    render_layers: vec2<u32>,
}

// Whether a far-field occluder on `layers` (bits as in `render_layers`) casts on this view: Bevy
// draws an entity in the views it shares a layer with.
fn seen_by_view(settings: DynamicAoUniform, layers: vec2<u32>) -> bool {
    return any((layers & settings.render_layers) != vec2<u32>(0u));
}

// The texel of the visibility texture (of size `texture_size`) that holds `pixel` of a viewport
// of `viewport_size`: the same texel where the texture has the viewport's size, the pixel at the
// viewport's place where it has the render target's (split screen, see `compose::ssao_slot`).
fn visibility_pixel(
    settings: DynamicAoUniform,
    pixel: vec2<i32>,
    texture_size: vec2<u32>,
    viewport_size: vec2<u32>,
) -> vec2<i32> {
    if all(texture_size == viewport_size) {
        return pixel;
    }
    return pixel + vec2<i32>(settings.viewport_origin);
}

// What Bevy's PBR reads for `occlusion`: visibility, 1 = open.
fn visibility_of(occlusion: f32) -> f32 {
    return 1.0 - clamp(occlusion, 0.0, 1.0);
}
