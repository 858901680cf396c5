//! Procedural test scenes. Every scene's meshes are Bevy primitives, so the GPU and the CPU
//! ray tracer see exactly the same triangles.

use bevy::prelude::*;

use crate::harness::SceneSpec;

fn floor(size: f32) -> Mesh {
    Plane3d::default().mesh().size(size, size).build()
}

/// A 1 m cube standing on a floor.
pub fn cube_on_plane() -> SceneSpec {
    SceneSpec::new(
        Transform::from_xyz(2.0, 1.8, 2.8).looking_at(Vec3::new(0.0, 0.35, 0.0), Vec3::Y),
    )
    .with(floor(10.0), Transform::IDENTITY)
    .with(
        Cuboid::new(1.0, 1.0, 1.0),
        Transform::from_xyz(0.0, 0.5, 0.0),
    )
}

/// Two walls meeting a floor, with a small box in the corner.
pub fn room_corner() -> SceneSpec {
    SceneSpec::new(
        Transform::from_xyz(2.2, 1.6, 2.2).looking_at(Vec3::new(-0.5, 0.4, -0.5), Vec3::Y),
    )
    .with(floor(10.0), Transform::IDENTITY)
    .with(
        Cuboid::new(4.0, 2.5, 0.1),
        Transform::from_xyz(0.5, 1.25, -1.55),
    )
    .with(
        Cuboid::new(0.1, 2.5, 4.0),
        Transform::from_xyz(-1.55, 1.25, 0.5),
    )
    .with(
        Cuboid::new(0.5, 0.5, 0.5),
        Transform::from_xyz(-1.2, 0.25, -1.2),
    )
}

/// A ball resting on the floor close to a wall.
pub fn ball_near_wall() -> SceneSpec {
    SceneSpec::new(
        Transform::from_xyz(1.6, 1.3, 2.4).looking_at(Vec3::new(0.0, 0.4, -0.6), Vec3::Y),
    )
    .with(floor(10.0), Transform::IDENTITY)
    .with(
        Cuboid::new(5.0, 2.5, 0.1),
        Transform::from_xyz(0.0, 1.25, -1.15),
    )
    .with(
        Sphere::new(0.4).mesh().uv(48, 24),
        Transform::from_xyz(0.0, 0.4, -0.6),
    )
}

/// A camera looking straight down at a floor, with a 1 × 1.2 × 1 m box just outside the right
/// edge of its view: occlusion the depth buffer cannot see.
pub fn box_beside_view() -> SceneSpec {
    SceneSpec::new(Transform::from_xyz(0.0, 2.5, 0.0).looking_at(Vec3::ZERO, -Vec3::Z))
        .with(floor(10.0), Transform::IDENTITY)
        .with(
            Cuboid::new(1.0, 1.2, 1.0),
            Transform::from_xyz(2.0, 0.6, 0.0),
        )
}

/// [`box_beside_view`] as a model in centimetres brings it: the box's mesh 100 × 120 × 100 units
/// scaled by 0.01, the floor a 1 × 1 plane scaled to 10 × 10 m (a scale per axis).
pub fn box_beside_view_scaled() -> SceneSpec {
    SceneSpec::new(Transform::from_xyz(0.0, 2.5, 0.0).looking_at(Vec3::ZERO, -Vec3::Z))
        .with(
            floor(1.0),
            Transform::from_scale(Vec3::new(10.0, 1.0, 10.0)),
        )
        .with(
            Cuboid::new(100.0, 120.0, 100.0),
            Transform::from_xyz(2.0, 0.6, 0.0).with_scale(Vec3::splat(0.01)),
        )
}

/// The same view with a thin wall (4 m long, 1.2 m high, 10 cm thick) standing just outside the
/// right edge of the view: a large, thin occluder.
pub fn wall_beside_view() -> SceneSpec {
    SceneSpec::new(Transform::from_xyz(0.0, 2.5, 0.0).looking_at(Vec3::ZERO, -Vec3::Z))
        .with(floor(10.0), Transform::IDENTITY)
        .with(
            Cuboid::new(0.1, 1.2, 4.0),
            Transform::from_xyz(1.5, 0.6, 0.0),
        )
}

/// A room open at the front, as the Cornell box is built: a 1.6 m cube of 4 cm walls, ceiling and
/// back wall, with a tall and a short box inside, standing on a floor and seen from outside the
/// open side. Every wall a thin, large occluder; the receivers inside see walls in every
/// direction.
pub fn open_room() -> SceneSpec {
    let (size, wall) = (1.6, 0.04);
    let half = size / 2.0;
    SceneSpec::new(Transform::from_xyz(1.0, 1.5, 3.4).looking_at(Vec3::new(0.0, 0.7, 0.0), Vec3::Y))
        .with(floor(10.0), Transform::IDENTITY)
        .with(
            Cuboid::new(wall, size, size),
            Transform::from_xyz(-half, half, 0.0),
        )
        .with(
            Cuboid::new(wall, size, size),
            Transform::from_xyz(half, half, 0.0),
        )
        .with(
            Cuboid::new(size, size, wall),
            Transform::from_xyz(0.0, half, -half),
        )
        .with(
            Cuboid::new(size, wall, size),
            Transform::from_xyz(0.0, size, 0.0),
        )
        .with(
            Cuboid::new(0.45, 0.9, 0.45),
            Transform::from_xyz(-0.3, 0.45, -0.25).with_rotation(Quat::from_rotation_y(0.3)),
        )
        .with(
            Cuboid::new(0.45, 0.45, 0.45),
            Transform::from_xyz(0.3, 0.225, 0.25).with_rotation(Quat::from_rotation_y(-0.3)),
        )
}

/// A room open at the front built as the CornellBox is: a 1 m ceiling and three walls, each one
/// polygon with a double-sided material, a tall and a short box inside, on a floor, and the
/// camera above the ceiling's height looking in. The ceiling hides the upper walls from the
/// camera, and both ND-buffer layers hold it at one depth.
pub fn sheet_room() -> SceneSpec {
    let wall = |normal: Dir3| Plane3d::new(*normal, Vec2::splat(0.5)).mesh().build();
    SceneSpec::new(Transform::from_xyz(0.0, 1.5, 3.6).looking_at(Vec3::new(0.0, 0.5, 0.0), Vec3::Y))
        .with(floor(10.0), Transform::IDENTITY)
        .with(wall(Dir3::X), Transform::from_xyz(-0.5, 0.5, 0.0))
        .with(wall(Dir3::NEG_X), Transform::from_xyz(0.5, 0.5, 0.0))
        .with(wall(Dir3::Z), Transform::from_xyz(0.0, 0.5, -0.5))
        .with(wall(Dir3::NEG_Y), Transform::from_xyz(0.0, 1.0, 0.0))
        .with(
            Cuboid::new(0.3, 0.6, 0.3),
            Transform::from_xyz(-0.17, 0.3, -0.15).with_rotation(Quat::from_rotation_y(0.3)),
        )
        .with(
            Cuboid::new(0.3, 0.3, 0.3),
            Transform::from_xyz(0.17, 0.15, 0.15).with_rotation(Quat::from_rotation_y(-0.3)),
        )
        .two_sided()
}

/// `mesh` seen from inside: its triangles wound the other way and its normals reversed, the inner
/// surface of a shell.
fn inside_out(mesh: impl Into<Mesh>) -> Mesh {
    let mut mesh = mesh
        .into()
        .with_inverted_winding()
        .expect("a primitive's mesh is an indexed triangle list");
    if let Some(bevy::mesh::VertexAttributeValues::Float32x3(normals)) =
        mesh.attribute_mut(Mesh::ATTRIBUTE_NORMAL)
    {
        for n in normals.iter_mut() {
            *n = (-Vec3::from(*n)).to_array();
        }
    }
    mesh
}

/// A hollow ball (0.45 m) and a hollow box (0.7 m) on a floor, each an outer surface and an inner
/// one 2 cm inside it, as game models are built (DamagedHelmet's shell is a few millimetres
/// thick): the back-face layer holds the inner surface just behind the outer one, not the far
/// side of the model. The ball's lower half overhangs the floor around it.
pub fn shells_on_floor() -> SceneSpec {
    let wall = 0.02;
    SceneSpec::new(
        Transform::from_xyz(1.4, 1.5, 2.6).looking_at(Vec3::new(0.1, 0.35, 0.0), Vec3::Y),
    )
    .with(floor(10.0), Transform::IDENTITY)
    .with(
        Sphere::new(0.45).mesh().uv(48, 24),
        Transform::from_xyz(-0.4, 0.45, 0.0),
    )
    .with(
        inside_out(Sphere::new(0.45 - wall).mesh().uv(48, 24)),
        Transform::from_xyz(-0.4, 0.45, 0.0),
    )
    .with(
        Cuboid::new(0.7, 0.7, 0.7),
        Transform::from_xyz(0.6, 0.35, -0.3).with_rotation(Quat::from_rotation_y(0.5)),
    )
    .with(
        inside_out(Cuboid::new(
            0.7 - 2.0 * wall,
            0.7 - 2.0 * wall,
            0.7 - 2.0 * wall,
        )),
        Transform::from_xyz(0.6, 0.35, -0.3).with_rotation(Quat::from_rotation_y(0.5)),
    )
}

/// The camera of [`plate_by_the_edge`] and [`heat_sink`]: above and in front of the objects,
/// which stand towards the right edge of the view.
fn heat_sink_camera() -> Transform {
    Transform::from_xyz(0.7, 0.8, 1.2).looking_at(Vec3::new(-0.15, 0.1, 0.1), Vec3::Y)
}

/// A plate 0.24 m high, 0.5 m long and 8 mm thick standing on a floor near the right edge of the
/// view, its face towards the camera: much of the floor it sees lies past the edge, where the
/// ND-buffer holds nothing.
pub fn plate_by_the_edge() -> SceneSpec {
    SceneSpec::new(heat_sink_camera())
        .with(floor(10.0), Transform::IDENTITY)
        .with(
            Cuboid::new(0.008, 0.24, 0.5),
            Transform::from_xyz(0.38, 0.12, 0.0),
        )
}

/// A counter 3.2 × 0.9 × 1 m on a floor, seen from 3 m in front and above, as
/// `assets/scenes/toasters.glb` frames its counter: the floor its front face sees runs off the
/// bottom of the view a few decimetres in front of it.
pub fn counter_on_floor() -> SceneSpec {
    SceneSpec::new(Transform::from_xyz(0.6, 2.2, 3.4).looking_at(Vec3::new(0.0, 0.9, 0.2), Vec3::Y))
        .with(floor(10.0), Transform::IDENTITY)
        .with(
            Cuboid::new(3.2, 0.9, 1.0),
            Transform::from_xyz(0.0, 0.45, 0.0),
        )
}

/// Detail finer than a half-resolution texel: a heat sink (a 0.8 × 0.5 m base 4 cm thick carrying
/// 20 fins 8 mm thick, 0.2 m tall and 4 cm apart, gaps of one to two pixels at 160 × 120) and
/// beside it a grille of 12 upright bars 1 cm square and 3 cm apart, on a floor.
/// `docs/ring_on_floor.py --fins` writes the same scene for `ao_capture`.
pub fn heat_sink() -> SceneSpec {
    let mut scene = SceneSpec::new(heat_sink_camera())
        .with(floor(10.0), Transform::IDENTITY)
        .with(
            Cuboid::new(0.8, 0.04, 0.5),
            Transform::from_xyz(0.0, 0.02, 0.0),
        );
    for k in 0..20 {
        scene = scene.with(
            Cuboid::new(0.008, 0.2, 0.5),
            Transform::from_xyz(-0.38 + 0.04 * k as f32, 0.14, 0.0),
        );
    }
    for k in 0..12 {
        scene = scene.with(
            Cuboid::new(0.01, 0.35, 0.01),
            Transform::from_xyz(-0.745 + 0.03 * k as f32, 0.175, 0.605),
        );
    }
    scene
}

/// The surface of a cube of side `size` centred on the origin with a square window of side
/// `window` in each face, no thickness: open and not a solid, as BoxAnimated's outer box is
/// built. Each face is drawn from both sides (a second triangle turned the other way), so the
/// view through one window sees the inside of the faces beyond it, which the ray tracer finds.
pub fn window_frame(size: f32, window: f32) -> Mesh {
    let (h, w) = (0.5 * size, 0.5 * window);
    // The ring of one face as four strips, (u, v) rectangles in the face's plane.
    let strips = [
        ([-h, -h], [h, -w]),
        ([-h, w], [h, h]),
        ([-h, -w], [-w, w]),
        ([w, -w], [h, w]),
    ];
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for normal in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
        // u × v = normal, so the corners in (u, v) order wind counter-clockwise seen from outside.
        let u = normal.any_orthonormal_vector();
        let v = normal.cross(u);
        for (lo, hi) in strips {
            let base = positions.len() as u32;
            for (a, b) in [
                (lo[0], lo[1]),
                (hi[0], lo[1]),
                (hi[0], hi[1]),
                (lo[0], hi[1]),
            ] {
                positions.push((normal * h + u * a + v * b).to_array());
                normals.push(normal.to_array());
            }
            indices.extend([0, 1, 2, 0, 2, 3].map(|i| base + i));
            let back = positions.len() as u32;
            positions.extend_from_within(base as usize..);
            normals.extend(std::iter::repeat_n((-normal).to_array(), 4));
            indices.extend([0, 2, 1, 0, 3, 2].map(|i| back + i));
        }
    }
    Mesh::new(
        bevy::mesh::PrimitiveTopology::TriangleList,
        bevy::asset::RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
    .with_inserted_indices(bevy::mesh::Indices::U32(indices))
}

/// A 1 m cube frame (a 0.7 m window in each face, [`window_frame`]) on a floor with a 0.67 ×
/// 1 × 0.67 m box inside it, seen from a corner: BoxAnimated's outer and inner boxes at 0 s.
pub fn frame_around_box() -> SceneSpec {
    SceneSpec::new(Transform::from_xyz(1.6, 1.3, 2.3).looking_at(Vec3::new(0.0, 0.4, 0.0), Vec3::Y))
        .with(floor(10.0), Transform::IDENTITY)
        .with(window_frame(1.0, 0.7), Transform::from_xyz(0.0, 0.5, 0.0))
        .with(
            Cuboid::new(0.67, 1.0, 0.67),
            Transform::from_xyz(0.0, 0.5, 0.0),
        )
}

/// All scenes with their names.
pub fn all() -> [(&'static str, SceneSpec); 3] {
    [
        ("cube on plane", cube_on_plane()),
        ("room corner", room_corner()),
        ("ball near wall", ball_near_wall()),
    ]
}
