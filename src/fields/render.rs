//! Render-world side of the AO fields: every field asset in one storage buffer, one instance per
//! occluder, the box pipeline and the per-view bind groups.

use bevy::asset::{AssetId, Assets, load_embedded_asset};
use bevy::camera::visibility::InheritedVisibility;
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::ecs::prelude::*;
use bevy::math::{Affine3A, Mat4, Vec3, Vec4};
use bevy::prelude::GlobalTransform;
use bevy::render::{
    Extract,
    extract_component::ComponentUniforms,
    render_resource::{
        binding_types::{
            storage_buffer_read_only_sized, texture_2d, texture_depth_2d, uniform_buffer,
        },
        *,
    },
    renderer::{RenderDevice, RenderQueue},
    view::{ViewUniform, ViewUniforms},
};
use bevy::utils::default;
use bytemuck::{Pod, Zeroable};

use super::format::AoFieldData;
use super::systems::ActiveAoField;
use crate::settings::FieldShading;
use crate::view::{
    DynamicAoTextures, DynamicAoUniform, DynamicAoView, FAR_OCCLUSION_FORMAT, FarTerm,
};

/// One occluder as `fields.wgsl` reads it.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct FieldInstance {
    world_from_box: Mat4,
    grid_from_world: Mat4,
    world_from_mesh: [Vec4; 3],
    resolution: [u32; 3],
    offset: u32,
    /// x: where the fade of the object's own surface ends, mesh units (half a cell).
    params: Vec4,
}

impl FieldInstance {
    /// The instance of `field` placed by `world_from_mesh`; `None` for a transform that cannot be
    /// inverted (zero scale, NaN).
    pub fn new(field: &AoFieldData, world_from_mesh: Affine3A, offset: u32) -> Option<Self> {
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
            params: Vec4::new(field.own_surface_fade(), 0.0, 0.0, 0.0),
        })
    }
}

/// Every field in use and every occluder this frame.
#[derive(Resource)]
pub(crate) struct FieldBuffers {
    /// Field assets in `cells`, in order, with their first cell.
    layout: Vec<(AssetId<AoFieldData>, u32)>,
    /// Three vec4 per cell: far occlusion and direction, near occlusion and direction, signed
    /// distance and mean offset to the near hits.
    cells: RawBufferVec<Vec4>,
    instances: RawBufferVec<FieldInstance>,
    /// `cells` changed and must be written again.
    dirty: bool,
    /// Occluders to draw.
    pub count: u32,
}

impl Default for FieldBuffers {
    fn default() -> Self {
        // A binding needs a buffer even before the first field exists; nothing reads this cell.
        let mut cells = RawBufferVec::new(BufferUsages::STORAGE);
        cells.extend([Vec4::ZERO; 3]);
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
        )>,
    >,
    fields: Extract<Res<Assets<AoFieldData>>>,
) {
    let buffers = buffers.as_mut();
    let mut used: Vec<AssetId<AoFieldData>> = Vec::new();
    for (field, _, visibility) in &occluders {
        let id = field.field.id();
        if visibility.is_none_or(|v| v.get()) && fields.contains(id) && !used.contains(&id) {
            used.push(id);
        }
    }
    if used.len() != buffers.layout.len()
        || used
            .iter()
            .any(|id| !buffers.layout.iter().any(|(l, _)| l == id))
    {
        buffers.layout.clear();
        buffers.cells.clear();
        for id in used {
            let field = fields.get(id).expect("checked above");
            buffers.layout.push((id, buffers.cells.len() as u32 / 3));
            for ((far, near), distances) in field
                .cells
                .iter()
                .zip(&field.near_cells)
                .zip(&field.distances)
            {
                buffers.cells.extend([
                    Vec4::from_array(*far),
                    Vec4::from_array(*near),
                    Vec4::from_array(*distances),
                ]);
            }
        }
        if buffers.cells.is_empty() {
            buffers.cells.extend([Vec4::ZERO; 3]);
        }
        buffers.dirty = true;
    }
    buffers.instances.clear();
    for (field, transform, visibility) in &occluders {
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
        if let Some(instance) = FieldInstance::new(data, world_from_field, *offset) {
            buffers.instances.push(instance);
        }
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
) {
    let buffers = buffers.as_mut();
    if buffers.dirty || buffers.cells.buffer().is_none() {
        buffers.cells.write_buffer(&device, &queue);
        buffers.dirty = false;
    }
    buffers.instances.write_buffer(&device, &queue);
}

/// The box pipelines: occlusion only (§3.2) and cone (§3.3.1).
#[derive(Resource)]
pub(crate) struct FieldPipelines {
    layout: BindGroupLayoutDescriptor,
    occlusion_only: CachedRenderPipelineId,
    cone: CachedRenderPipelineId,
}

impl FieldPipelines {
    /// The pipeline that shades fields as `shading` says.
    pub fn for_shading(&self, shading: FieldShading) -> CachedRenderPipelineId {
        match shading {
            FieldShading::Cone => self.cone,
            FieldShading::OcclusionOnly => self.occlusion_only,
        }
    }
}

impl FromWorld for FieldPipelines {
    fn from_world(world: &mut World) -> Self {
        let storage = || storage_buffer_read_only_sized(false, None);
        let layout = BindGroupLayoutDescriptor::new(
            "dynamic_ao_fields_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::VERTEX_FRAGMENT,
                (
                    uniform_buffer::<ViewUniform>(true),
                    storage(),
                    storage(),
                    texture_depth_2d(),
                    texture_2d(TextureSampleType::Float { filterable: false }),
                    texture_depth_2d(),
                    uniform_buffer::<DynamicAoUniform>(true),
                ),
            ),
        );
        let shader = load_embedded_asset!(world, "fields.wgsl");
        // dst × (1 − src): occluders multiply their visibilities (§3.3.2).
        let multiply = BlendComponent {
            src_factor: BlendFactor::Zero,
            dst_factor: BlendFactor::OneMinusSrc,
            operation: BlendOperation::Add,
        };
        let cache = world.resource::<PipelineCache>();
        let [occlusion_only, cone] = [Vec::new(), vec!["CONE".into()]].map(|shader_defs| {
            cache.queue_render_pipeline(RenderPipelineDescriptor {
                label: Some("dynamic_ao_fields_pipeline".into()),
                layout: vec![layout.clone()],
                vertex: VertexState {
                    shader: shader.clone(),
                    shader_defs: shader_defs.clone(),
                    ..default()
                },
                fragment: Some(FragmentState {
                    shader: shader.clone(),
                    shader_defs,
                    targets: vec![Some(ColorTargetState {
                        format: FAR_OCCLUSION_FORMAT,
                        blend: Some(BlendState {
                            color: multiply,
                            alpha: multiply,
                        }),
                        write_mask: ColorWrites::RED | ColorWrites::GREEN,
                    })],
                    ..default()
                }),
                // The back faces of each grid box: each pixel once, even from inside the box.
                primitive: PrimitiveState {
                    cull_mode: Some(Face::Front),
                    ..default()
                },
                ..default()
            })
        });
        Self {
            layout,
            occlusion_only,
            cone,
        }
    }
}

#[derive(Component)]
pub(crate) struct FieldBindGroup(pub BindGroup);

pub(crate) fn prepare_field_bind_groups(
    mut commands: Commands,
    render_device: Res<RenderDevice>,
    pipelines: Res<FieldPipelines>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    settings: Res<ComponentUniforms<DynamicAoUniform>>,
    buffers: Res<FieldBuffers>,
    views: Query<(
        Entity,
        &DynamicAoView,
        &DynamicAoTextures,
        &ViewPrepassTextures,
    )>,
) {
    let (Some(view_binding), Some(instances), Some(cells), Some(settings_binding)) = (
        view_uniforms.uniforms.binding(),
        buffers.instances.binding(),
        buffers.cells.binding(),
        settings.binding(),
    ) else {
        return;
    };
    for (entity, view, textures, prepass) in &views {
        let (true, Some(depth), Some(normal)) = (
            view.has(FarTerm::Fields),
            prepass.depth_view(),
            prepass.normal_view(),
        ) else {
            commands.entity(entity).remove::<FieldBindGroup>();
            continue;
        };
        let bind_group = render_device.create_bind_group(
            "dynamic_ao_fields_bind_group",
            &pipeline_cache.get_bind_group_layout(&pipelines.layout),
            &BindGroupEntries::sequential((
                view_binding.clone(),
                instances.clone(),
                cells.clone(),
                depth,
                normal,
                &textures.back_depth.default_view,
                settings_binding.clone(),
            )),
        );
        commands.entity(entity).insert(FieldBindGroup(bind_group));
    }
}
