// The back faces' depth of a mesh drawn from its coarse copy (`nd_buffer::coarse`): its vertex
// positions, mesh space, and per instance the rows of its world-from-local transform.

#import bevy_render::view::View

@group(0) @binding(0) var<uniform> view: View;

struct Vertex {
    @location(0) position: vec3<f32>,
    // Rows of the 3 × 4 world-from-local affine transform.
    @location(1) row_x: vec4<f32>,
    @location(2) row_y: vec4<f32>,
    @location(3) row_z: vec4<f32>,
}

@vertex
fn vertex(vertex: Vertex) -> @builtin(position) vec4<f32> {
    let local = vec4<f32>(vertex.position, 1.0);
    let world = vec3<f32>(dot(vertex.row_x, local), dot(vertex.row_y, local), dot(vertex.row_z, local));
    // As Bevy's `position_world_to_clip`: the same matrix, jitter included.
    return view.clip_from_world * vec4<f32>(world, 1.0);
}
