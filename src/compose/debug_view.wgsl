// Debug view: the AO buffer (visibility, white = open) over the whole viewport.

#import bevy_core_pipeline::fullscreen_vertex_shader::FullscreenVertexOutput

@group(0) @binding(0) var visibility: texture_2d<f32>;

@fragment
fn fragment(in: FullscreenVertexOutput) -> @location(0) vec4<f32> {
    let v = textureLoad(visibility, vec2<i32>(in.position.xy), 0).r;
    return vec4<f32>(v, v, v, 1.0);
}
