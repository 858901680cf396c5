//! The proxies of every occluder in one storage buffer, extracted and uploaded every frame.

use bevy::camera::visibility::RenderLayers;
use bevy::ecs::prelude::*;
use bevy::math::{UVec4, Vec4};
use bevy::render::{
    Extract,
    render_resource::*,
    renderer::{RenderDevice, RenderQueue},
};

use bytemuck::{Pod, Zeroable};

use crate::capabilities::cap_to_storage_binding;
use crate::memory::DynamicAoGpuMemory;
use crate::view::layer_bits;

use super::component::{OccluderSpheres, ProxyReach, ProxyShape, far_field_reach};

/// One proxy as `splat.wgsl` reads it (`Proxy`).
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(super) struct GpuSphere {
    /// Centre and bounding radius, metres.
    centre_bound: Vec4,
    /// The three half-extent vectors, metres.
    axes: [Vec4; 3],
    /// The kind (0 box, 1 sphere), eq. 5's d_far (0: the camera's radius) and 1 for a proxy of a
    /// skinned mesh (see [`OccluderSpheres::articulated`]).
    kind: Vec4,
    /// The mesh's `RenderLayers` as bits (see [`layer_bits`]), then padding.
    layers: UVec4,
}

/// Every sphere of every occluder this frame, in one buffer all views share.
#[derive(Resource)]
pub(crate) struct SphereBuffer {
    pub(super) buffer: RawBufferVec<GpuSphere>,
    /// Spheres to draw (the buffer holds one placeholder when there are none).
    pub count: u32,
}

impl Default for SphereBuffer {
    fn default() -> Self {
        let mut buffer = RawBufferVec::new(BufferUsages::STORAGE);
        buffer.set_label(Some("dynamic_ao_spheres"));
        Self { buffer, count: 0 }
    }
}

pub(crate) fn extract_spheres(
    mut buffer: ResMut<SphereBuffer>,
    occluders: Extract<Query<(&OccluderSpheres, Option<&RenderLayers>)>>,
) {
    buffer.buffer.clear();
    for (occluder, layers) in &occluders {
        let layers = layer_bits(layers).extend(0).extend(0);
        for proxy in &occluder.spheres {
            let d_far = match occluder.reach {
                ProxyReach::CameraRadius => 0.0,
                ProxyReach::Epsilon(epsilon) => far_field_reach(proxy.radius, epsilon),
            };
            let kind = match proxy.shape {
                ProxyShape::Boxes => 0.0,
                ProxyShape::Spheres => 1.0,
            };
            buffer.buffer.push(GpuSphere {
                centre_bound: proxy.center.extend(proxy.radius),
                axes: [
                    proxy.axes.x_axis.extend(0.0),
                    proxy.axes.y_axis.extend(0.0),
                    proxy.axes.z_axis.extend(0.0),
                ],
                kind: Vec4::new(kind, d_far, f32::from(u8::from(occluder.articulated)), 0.0),
                layers,
            });
        }
    }
    buffer.count = buffer.buffer.len() as u32;
    if buffer.count == 0 {
        // A binding needs a buffer; nothing is drawn from it.
        buffer.buffer.push(GpuSphere::zeroed());
    }
}

/// Uploads the proxies, as many as one storage binding holds (the rest are left out, with one
/// warning).
pub(crate) fn write_sphere_buffer(
    mut buffer: ResMut<SphereBuffer>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut warned: Local<bool>,
    memory: Res<DynamicAoGpuMemory>,
) {
    let max_binding = device.limits().max_storage_buffer_binding_size;
    let len = buffer.count as usize;
    let kept = cap_to_storage_binding::<GpuSphere>(
        "SphereOccluder proxies",
        len,
        max_binding,
        &mut warned,
    );
    if kept < len {
        buffer.buffer.truncate(kept.max(1));
        buffer.count = kept as u32;
    }
    buffer.buffer.write_buffer(&device, &queue);
    memory.report("spheres", buffer.buffer.buffer().map_or(0, |b| b.size()));
}
