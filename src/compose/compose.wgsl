// Combined ambient occlusion (Shanmugam & Arikan 2007, §6; Reinbothe et al. 2009, §4): the
// terms add and clamp (or, on
// request, the larger one wins), and the result is handed to Bevy's PBR lighting as visibility,
// 1 − occlusion.

#import bevy_dynamic_ao::settings::DynamicAoSettings

@group(0) @binding(0) var<uniform> settings: DynamicAoSettings;
@group(0) @binding(1) var near_occlusion: texture_2d<f32>;
@group(0) @binding(2) var far_occlusion: texture_2d<f32>;
@group(0) @binding(3) var field_visibility: texture_2d<f32>;
@group(0) @binding(4) var voxel_occlusion: texture_2d<f32>;
#ifdef VISIBILITY_R16FLOAT
@group(0) @binding(5) var visibility: texture_storage_2d<r16float, write>;
#else
@group(0) @binding(5) var visibility: texture_storage_2d<r32float, write>;
#endif

@compute @workgroup_size(8, 8, 1)
fn compose(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = textureDimensions(visibility);
    if id.x >= dims.x || id.y >= dims.y {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    var occlusion = 0.0;
    if settings.near_field != 0u {
        occlusion += textureLoad(near_occlusion, pixel, 0).r;
    }
    // The far terms: sphere occlusion adds (S&A §6); AO fields arrive as the product of their
    // occluders' visibilities (Malmer et al. §3.3.2) and join as one more far occluder.
    var far = 0.0;
    if settings.far_field != 0u {
        far += textureLoad(far_occlusion, pixel, 0).r;
    }
    if settings.fields != 0u {
        far += 1.0 - textureLoad(field_visibility, pixel, 0).r;
    }
    // Voxel volumes (Reinbothe et al. 2009) are one more far term, already filtered.
    if settings.voxels != 0u {
        far += textureLoad(voxel_occlusion, pixel, 0).r;
    }
    if settings.far_field != 0u || settings.fields != 0u || settings.voxels != 0u {
        if settings.far_field_blend == 1u {
            occlusion = max(occlusion, far);
        } else {
            occlusion += far;
        }
    }
    textureStore(visibility, pixel, vec4<f32>(1.0 - clamp(occlusion, 0.0, 1.0)));
}
