// The bindings every image-space technique reads (`image_space.rs` builds the layout): the view,
// the per-view settings, both ND-buffer layers and the occlusion buffer the technique writes.

#define_import_path bevy_dynamic_ao::image_space_bindings

#import bevy_render::view::View
#import bevy_dynamic_ao::settings::DynamicAoSettings

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> settings: DynamicAoSettings;
@group(0) @binding(2) var front_depth: texture_depth_2d;
@group(0) @binding(3) var front_normal: texture_2d<f32>;
@group(0) @binding(4) var back_depth: texture_depth_2d;
@group(0) @binding(5) var back_normal: texture_2d<f32>;
@group(0) @binding(6) var occlusion: texture_storage_2d<r32float, write>;
