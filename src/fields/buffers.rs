//! Every field asset in use in one storage buffer and one instance per occluder, extracted and
//! uploaded every frame.

use bevy::asset::{AssetEvent, AssetId, Assets};
use bevy::camera::visibility::{InheritedVisibility, RenderLayers};
use bevy::ecs::message::MessageReader;
use bevy::ecs::prelude::*;
use bevy::log::warn;
use bevy::math::{Affine3A, Mat4, UVec4, Vec3, Vec4};
use bevy::platform::collections::HashSet;
use bevy::prelude::GlobalTransform;
use bevy::render::{
    Extract,
    render_resource::*,
    renderer::{RenderDevice, RenderQueue},
};
use bytemuck::{Pod, Zeroable};

use super::format::{AoFieldData, CELL_FLOATS};
use super::join::{ProxyJoin, field_joins, object_bounds};
use super::systems::ActiveAoField;
use crate::capabilities::cap_to_storage_binding;
use crate::memory::DynamicAoGpuMemory;
use crate::view::layer_bits;

/// One occluder as `fields.wgsl` reads it.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct FieldInstance {
    world_from_box: Mat4,
    grid_from_world: Mat4,
    world_from_mesh: [Vec4; 3],
    resolution: [u32; 3],
    offset: u32,
    /// x: where the fade of the object's own surface ends, mesh units (half a cell); yzw: grid
    /// units per mesh unit along each axis, for the signed distance's gradient.
    params: Vec4,
    /// xy: the occluder's `RenderLayers` as bits (see [`layer_bits`]).
    layers: UVec4,
    /// How the field joins the others ([`ProxyJoin::gpu_form`]): the lower corner of the box of
    /// `UnionOutside` with the kind in w, then its upper corner (world space, metres).
    union_bounds: [Vec4; 2],
}

impl FieldInstance {
    /// The instance of `field` placed by `world_from_mesh`, cast on views that share a layer with
    /// `layers`; `None` for a transform that cannot be inverted (zero scale, NaN).
    pub fn new(
        field: &AoFieldData,
        world_from_mesh: Affine3A,
        offset: u32,
        layers: Option<&RenderLayers>,
    ) -> Option<Self> {
        let mesh_from_box = Affine3A::from_scale_rotation_translation(
            field.half_extent,
            Default::default(),
            field.center,
        );
        let world_from_box = world_from_mesh * mesh_from_box;
        let determinant = world_from_box.matrix3.determinant();
        if !world_from_box.is_finite() || !determinant.is_finite() || determinant.abs() < 1e-12 {
            return None;
        }
        // Box [-1, 1]³ to grid [0, 1]³.
        let grid_from_box = Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.5),
            Default::default(),
            Vec3::splat(0.5),
        );
        let grid_from_world = grid_from_box * world_from_box.inverse();
        let m = world_from_mesh.matrix3;
        let grid_scale = field.resolution.as_vec3() / (2.0 * field.half_extent);
        Some(Self {
            world_from_box: Mat4::from(world_from_box),
            grid_from_world: Mat4::from(grid_from_world),
            world_from_mesh: [
                m.x_axis.extend(0.0),
                m.y_axis.extend(0.0),
                m.z_axis.extend(0.0),
            ],
            resolution: field.resolution.to_array(),
            offset,
            params: Vec4::new(
                field.own_surface_fade(),
                grid_scale.x,
                grid_scale.y,
                grid_scale.z,
            ),
            layers: layer_bits(layers).extend(0).extend(0),
            union_bounds: [Vec4::ZERO; 2],
        })
    }

    /// Sets how the field joins the others.
    fn join(&mut self, join: ProxyJoin) {
        let (kind, [lo, hi]) = join.gpu_form();
        self.union_bounds = [lo.extend(kind), hi.extend(0.0)];
    }
}

/// `vec4<f32>` per cell on the GPU (`fields.wgsl` reads them at this stride).
const CELL_VEC4S: usize = CELL_FLOATS / 4;
/// Bytes one cell takes on the GPU.
const CELL_BYTES: usize = CELL_VEC4S * 16;

/// Most bytes every field in use may take together: the device's storage binding limit, and at
/// most 512 MiB (a 256³ field alone takes 1879 MB).
fn field_budget(max_storage_binding: u64) -> u64 {
    max_storage_binding.min(512 << 20)
}

/// Every field in use and every occluder this frame.
#[derive(Resource)]
pub(crate) struct FieldBuffers {
    /// Field assets in `cells`, in order, with their first cell.
    layout: Vec<(AssetId<AoFieldData>, u32)>,
    /// Seven vec4 per cell: far occlusion and direction, near occlusion and direction, signed
    /// distance and mean offset to the near hits, the own surface's share beyond the near reach
    /// and its normal, and the cone's axis corrections (`AoFieldData::axes`, four per vec4).
    pub(super) cells: RawBufferVec<Vec4>,
    pub(super) instances: RawBufferVec<FieldInstance>,
    /// `cells` changed and must be written again.
    dirty: bool,
    /// Occluders to draw.
    pub count: u32,
}

impl Default for FieldBuffers {
    fn default() -> Self {
        // A binding needs a buffer even before the first field exists; nothing reads this cell.
        let mut cells = RawBufferVec::new(BufferUsages::STORAGE);
        cells.extend([Vec4::ZERO; CELL_VEC4S]);
        Self {
            layout: Vec::new(),
            cells,
            instances: RawBufferVec::new(BufferUsages::STORAGE),
            dirty: true,
            count: 0,
        }
    }
}

pub(crate) fn extract_fields(
    mut buffers: ResMut<FieldBuffers>,
    occluders: Extract<
        Query<(
            &ActiveAoField,
            &GlobalTransform,
            Option<&InheritedVisibility>,
            Option<&RenderLayers>,
        )>,
    >,
    fields: Extract<Res<Assets<AoFieldData>>>,
    mut events: Extract<MessageReader<AssetEvent<AoFieldData>>>,
    device: Res<RenderDevice>,
    mut over_budget: Local<HashSet<AssetId<AoFieldData>>>,
    mut warned_instances: Local<bool>,
) {
    let buffers = buffers.as_mut();
    // A field changed in place (a `.aofield` file reloaded) keeps its id: its cells are uploaded
    // again, or the grid would be read with the new resolution over the old cells.
    let changed = events.read().any(|event| match event {
        AssetEvent::Modified { id } | AssetEvent::LoadedWithDependencies { id } => {
            buffers.layout.iter().any(|(l, _)| l == id)
        }
        _ => false,
    });
    let budget = field_budget(device.limits().max_storage_buffer_binding_size);
    let mut used: Vec<AssetId<AoFieldData>> = Vec::new();
    let mut bytes = 0u64;
    for (field, _, visibility, _) in &occluders {
        let id = field.field.id();
        if !visibility.is_none_or(|v| v.get()) || used.contains(&id) {
            continue;
        }
        let Some(data) = fields.get(id) else {
            continue;
        };
        let size = (data.cell_count() * CELL_BYTES) as u64;
        if bytes + size > budget {
            if over_budget.insert(id) {
                warn!(
                    "AoField: a field of {} cells ({size} bytes) does not fit: the fields in use \
                     may take {budget} bytes together (the device's \
                     max_storage_buffer_binding_size is {}); its occluders cast nothing. Bake it \
                     at a lower resolution",
                    data.cell_count(),
                    device.limits().max_storage_buffer_binding_size
                );
            }
            continue;
        }
        bytes += size;
        used.push(id);
    }
    if changed
        || used.len() != buffers.layout.len()
        || used
            .iter()
            .any(|id| !buffers.layout.iter().any(|(l, _)| l == id))
    {
        buffers.layout.clear();
        buffers.cells.clear();
        for id in used {
            let field = fields.get(id).expect("checked above");
            buffers
                .layout
                .push((id, (buffers.cells.len() / CELL_VEC4S) as u32));
            for values in field.cell_values() {
                buffers
                    .cells
                    .extend(values.chunks_exact(4).map(Vec4::from_slice));
            }
        }
        if buffers.cells.is_empty() {
            buffers.cells.extend([Vec4::ZERO; CELL_VEC4S]);
        }
        buffers.dirty = true;
    }
    buffers.instances.clear();
    let mut bounds = Vec::new();
    for (field, transform, visibility, layers) in &occluders {
        if !visibility.is_none_or(|v| v.get()) {
            continue;
        }
        let id = field.field.id();
        let (Some(data), Some((_, offset))) = (
            fields.get(id),
            buffers.layout.iter().find(|(l, _)| *l == id),
        ) else {
            continue;
        };
        // A baked field lies in the mesh's space scaled to the world's size.
        let world_from_field = transform.affine() * Affine3A::from_scale(field.baked_scale.recip());
        if let Some(instance) = FieldInstance::new(data, world_from_field, *offset, layers) {
            buffers.instances.push(instance);
            bounds.push(object_bounds(data, world_from_field));
        }
    }
    for (instance, join) in buffers
        .instances
        .values_mut()
        .iter_mut()
        .zip(field_joins(&bounds))
    {
        instance.join(join);
    }
    let max_binding = device.limits().max_storage_buffer_binding_size;
    let len = buffers.instances.len();
    let kept = cap_to_storage_binding::<FieldInstance>(
        "AoField occluders",
        len,
        max_binding,
        &mut warned_instances,
    );
    if kept < len {
        buffers.instances.truncate(kept);
    }
    buffers.count = buffers.instances.len() as u32;
    if buffers.count == 0 {
        buffers.instances.push(Zeroable::zeroed());
    }
}

pub(crate) fn write_field_buffers(
    mut buffers: ResMut<FieldBuffers>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    memory: Res<DynamicAoGpuMemory>,
) {
    let buffers = buffers.as_mut();
    if buffers.dirty || buffers.cells.buffer().is_none() {
        buffers.cells.write_buffer(&device, &queue);
        buffers.dirty = false;
    }
    buffers.instances.write_buffer(&device, &queue);
    memory.report(
        "fields",
        [buffers.cells.buffer(), buffers.instances.buffer()]
            .into_iter()
            .flatten()
            .map(|b| b.size())
            .sum(),
    );
}
