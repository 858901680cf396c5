// Second layer of the ND-buffer: the nearest back faces (Shanmugam & Arikan 2007, §4.2).
//
// The vertex stage is Bevy's own mesh vertex shader (skinning and morph targets included), so
// this layer deforms exactly like the front layer of the depth/normal prepass. The normal is
// stored with the prepass encoding, `n * 0.5 + 0.5`, and keeps the outward orientation of the
// surface, which for a back face points away from the camera.

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::view

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    var n = in.world_normal;
    if dot(n, n) < 1e-12 {
        // Mesh without normals: fall back to the face normal, turned away from the camera.
        let p = in.world_position.xyz;
        n = cross(dpdx(p), dpdy(p));
        if dot(n, view.world_position - p) > 0.0 {
            n = -n;
        }
    }
    // A degenerate triangle has no normal at all; it is stored as zero, which readers skip.
    n = n * inverseSqrt(max(dot(n, n), 1e-30));
    return vec4<f32>(n * 0.5 + 0.5, 1.0);
}
