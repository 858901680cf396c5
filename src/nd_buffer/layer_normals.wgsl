// Normals of the layers drawn with Bevy's mesh pipeline: the second layer of the ND-buffer, the
// nearest back faces (Shanmugam & Arikan 2007, §4.2), and with `FRONT_FACES` the front faces at
// pixel centres on MSAA cameras (`front_layer.rs`), the faces Bevy's prepass draws.
//
// The vertex stage is Bevy's own mesh vertex shader (skinning and morph targets included), so
// these layers deform exactly like the front layer of the depth/normal prepass. The normal is
// stored with the prepass encoding, `n * 0.5 + 0.5`, and keeps the outward orientation of the
// surface, which for a back face points away from the camera.

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::view

struct LayerOut {
    @location(0) normal: vec4<f32>,
#ifdef FRONT_FACES
    // The screen-space gradient of the depth, per pixel: the plane of the triangle at the centre.
    @location(1) depth_gradient: vec2<f32>,
#endif
}

@fragment
fn fragment(in: VertexOutput, @builtin(front_facing) is_front: bool) -> LayerOut {
    var n = in.world_normal;
#ifdef FRONT_FACES
    // The back face of a double-sided material: Bevy's prepass turns its normal to the camera.
    if !is_front {
        n = -n;
    }
#endif
    if dot(n, n) < 1e-12 {
        // Mesh without normals: fall back to the face normal, turned away from the camera (toward
        // it for front faces).
        let p = in.world_position.xyz;
        n = cross(dpdx(p), dpdy(p));
#ifdef FRONT_FACES
        let wrong_way = dot(n, view.world_position - p) < 0.0;
#else
        let wrong_way = dot(n, view.world_position - p) > 0.0;
#endif
        if wrong_way {
            n = -n;
        }
    }
    // A degenerate triangle has no normal at all; it is stored as zero, which readers skip.
    n = n * inverseSqrt(max(dot(n, n), 1e-30));
    var out: LayerOut;
    out.normal = vec4<f32>(n * 0.5 + 0.5, 1.0);
#ifdef ALPHA_MASKED
    // Marks a surface the prepass may have discarded here (see `front_layer.wgsl`).
    out.normal.a = 0.0;
#endif
#ifdef FRONT_FACES
    out.depth_gradient = vec2<f32>(dpdx(in.position.z), dpdy(in.position.z));
#endif
    return out;
}
