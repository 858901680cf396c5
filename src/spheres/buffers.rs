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
use super::join::proxy_joins;

/// One proxy as `splat.wgsl` reads it (`Proxy`).
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(super) struct GpuSphere {
    /// Centre and bounding radius, metres.
    centre_bound: Vec4,
    /// The three half-extent vectors, metres.
    axes: [Vec4; 3],
    /// The kind (0 box, 1 sphere), eq. 5's d_far (0: the camera's radius) and how the proxy joins
    /// the others ([`ProxyJoin::gpu_form`](crate::geometry::union::ProxyJoin::gpu_form): 0
    /// independent, 1 by the union, 2 by the union outside `union_bounds`).
    kind: Vec4,
    /// The mesh's `RenderLayers` as bits (see [`layer_bits`]), then padding.
    layers: UVec4,
    /// Under [`ProxyJoin::UnionOutside`](crate::geometry::union::ProxyJoin::UnionOutside), the
    /// box's lower and upper corners, metres.
    union_bounds: [Vec4; 2],
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
    let occluders: Vec<_> = occluders.iter().collect();
    let joins = proxy_joins(occluders.iter().map(|(o, _)| *o));
    for ((occluder, layers), join) in occluders.into_iter().zip(joins) {
        let layers = layer_bits(layers).extend(0).extend(0);
        let (join, [lo, hi]) = join.gpu_form();
        let union_bounds = [lo.extend(0.0), hi.extend(0.0)];
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
                kind: Vec4::new(kind, d_far, join, 0.0),
                layers,
                union_bounds,
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
