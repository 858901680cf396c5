// Which far-field occluders join by their union at a receiver (`geometry::union`): the sphere
// splat's proxies and the AO fields alike. Each carries a kind and a box; compose takes the union
// of those that join by it from the splat buffers' blue (their product) and alpha (the largest).

#define_import_path bevy_dynamic_ao::union_join

// Whether an occluder of join `kind` (0 as an independent occluder, 1 by the union, 2 by the
// union where the receiver lies outside the box `lo`–`hi`) joins by the union at `p`
// (`ProxyJoin::joins_at`).
fn joins_by_union(kind: f32, lo: vec3<f32>, hi: vec3<f32>, p: vec3<f32>) -> bool {
    if kind < 1.5 {
        return kind > 0.5;
    }
    return any(p < lo) || any(p > hi);
}

// The splat's output for an occluder whose two parts of occlusion are `occlusion` (red: within
// the near field's reach, green: beyond): blue multiplies the visibilities of the occluders that
// join by their union here and alpha keeps the largest of their occlusions (blended with max).
fn union_channels(occlusion: vec2<f32>, by_union: bool) -> vec4<f32> {
    let joined = select(0.0, 1.0 - (1.0 - occlusion.x) * (1.0 - occlusion.y), by_union);
    return vec4<f32>(occlusion, joined, joined);
}
