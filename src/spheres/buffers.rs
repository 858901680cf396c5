//! The proxies of every occluder in one storage buffer, extracted and uploaded every frame.

use bevy::ecs::prelude::*;
use bevy::math::Vec4;
use bevy::render::{
    Extract,
    render_resource::*,
    renderer::{RenderDevice, RenderQueue},
};

use super::component::{OccluderSpheres, ProxyReach, ProxyShape, far_field_reach};

/// One proxy as `splat.wgsl` reads it: centre and bounding radius, the three half-extent vectors,
/// then the kind (0 box, 1 sphere), eq. 5's d_far (0: the camera's radius) and 1 for a proxy of
/// a skinned mesh (see [`OccluderSpheres::articulated`]).
type GpuSphere = [Vec4; 5];

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
    occluders: Extract<Query<&OccluderSpheres>>,
) {
    buffer.buffer.clear();
    for occluder in &occluders {
        for proxy in &occluder.spheres {
            let d_far = match occluder.reach {
                ProxyReach::CameraRadius => 0.0,
                ProxyReach::Epsilon(epsilon) => far_field_reach(proxy.radius, epsilon),
            };
            let kind = match proxy.shape {
                ProxyShape::Boxes => 0.0,
                ProxyShape::Spheres => 1.0,
            };
            buffer.buffer.push([
                proxy.center.extend(proxy.radius),
                proxy.axes.x_axis.extend(0.0),
                proxy.axes.y_axis.extend(0.0),
                proxy.axes.z_axis.extend(0.0),
                Vec4::new(kind, d_far, f32::from(u8::from(occluder.articulated)), 0.0),
            ]);
        }
    }
    buffer.count = buffer.buffer.len() as u32;
    if buffer.count == 0 {
        // A binding needs a buffer; nothing is drawn from it.
        buffer.buffer.push([Vec4::ZERO; 5]);
    }
}

pub(crate) fn write_sphere_buffer(
    mut buffer: ResMut<SphereBuffer>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    buffer.buffer.write_buffer(&device, &queue);
}
