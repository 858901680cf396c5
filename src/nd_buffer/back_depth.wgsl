// The vertex stage of the back faces' depth (`LayerDraw::BackDepth`): the clip position alone.
//
// Bevy's mesh vertex shader also transforms normals, tangents and UVs for the fragment stage this
// draw does not have, and on lavapipe the pass's cost follows the vertices more than the pixels
// (with that shader a 60,000-triangle model took 4.5 ms at 320×240 and 6.4 ms at 640×480; with
// this one the pass takes 0.8–0.9× the time). The position goes through the same morph, skin
// and transform functions as Bevy's, so the layer deforms exactly like the prepass.

#import bevy_pbr::{
    forward_io::Vertex,
    mesh_functions,
    skinning,
    view_transformations::position_world_to_clip,
}
#ifdef MORPH_TARGETS
#import bevy_pbr::{mesh_bindings::mesh, morph}
#endif

@vertex
fn vertex(vertex: Vertex) -> @builtin(position) vec4<f32> {
    var position = vertex.position;
#ifdef MORPH_TARGETS
    // Each target's weighted position offset, as the mesh vertex shader adds them.
    let index = vertex.index - mesh[vertex.instance_index].first_vertex_index;
    for (var i = 0u; i < morph::layer_count(vertex.instance_index); i++) {
        let weight = morph::weight_at(i, vertex.instance_index);
        if weight != 0.0 {
            position += weight * morph::morph_position(index, i, vertex.instance_index);
        }
    }
#endif
#ifdef SKINNED
    let world_from_local = skinning::skin_model(
        vertex.joint_indices,
        vertex.joint_weights,
        vertex.instance_index,
    );
#else
    let world_from_local = mesh_functions::get_world_from_local(vertex.instance_index);
#endif
    let world = mesh_functions::mesh_position_local_to_world(world_from_local, vec4(position, 1.0));
    return position_world_to_clip(world.xyz);
}
