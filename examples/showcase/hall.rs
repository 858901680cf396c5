//! The showcase's scene, built in code: a hall with a colonnade, pilasters, a stepped dais and
//! props (creases and contact everywhere), walkers and rigid objects moving through it. What
//! moves carries a `SphereOccluder`, as a user gives the far field what the screen may miss; the
//! still architecture is left to the image-space term.

use bevy::prelude::*;
use bevy::world_serialization::WorldAssetRoot;
use bevy_dynamic_ao::prelude::*;

use crate::walking::{WalkPath, start_walking};

/// The hall's floor spans this box (metres): x and z extents, centred on `HALL_CENTRE`.
pub const HALL_SIZE: Vec2 = Vec2::new(16.0, 12.0);
pub const HALL_CENTRE: Vec3 = Vec3::new(0.0, 0.0, -1.0);
/// Height of the walls, metres.
pub const WALL_HEIGHT: f32 = 4.5;

/// A rigid object moving back and forth between two points, turning as it goes.
#[derive(Component)]
pub struct Shuttle {
    pub from: Vec3,
    pub to: Vec3,
    /// Seconds for one way.
    pub period: f32,
    /// Radians per second about the vertical axis.
    pub spin: f32,
}

/// Moves every [`Shuttle`] along its path (a smooth back and forth).
pub fn shuttle(time: Res<Time>, mut shuttles: Query<(&Shuttle, &mut Transform)>) {
    let t = time.elapsed_secs();
    for (shuttle, mut transform) in &mut shuttles {
        let s = 0.5 - 0.5 * (t * std::f32::consts::PI / shuttle.period).cos();
        transform.translation = shuttle.from.lerp(shuttle.to, s);
        transform.rotation = Quat::from_rotation_y(t * shuttle.spin);
    }
}

/// Spawns the hall, its props, the movers and the walkers; `walker` is the walker's scene.
pub fn spawn(world: &mut World, walker: Handle<WorldAsset>) {
    let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
    let mut material = |r: f32, g: f32, b: f32, roughness: f32| {
        materials.add(StandardMaterial {
            base_color: Color::srgb(r, g, b),
            perceptual_roughness: roughness,
            ..default()
        })
    };
    let plaster = material(0.86, 0.84, 0.80, 0.95);
    let stone = material(0.72, 0.70, 0.66, 0.9);
    let wood = material(0.62, 0.42, 0.26, 0.8);
    let paint = material(0.30, 0.45, 0.62, 0.6);
    let clay = material(0.78, 0.38, 0.22, 0.7);

    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    let mut cuboid = |x: f32, y: f32, z: f32| meshes.add(Cuboid::new(x, y, z));
    let floor = cuboid(HALL_SIZE.x, 0.1, HALL_SIZE.y);
    let back_wall = cuboid(HALL_SIZE.x, WALL_HEIGHT, 0.3);
    let side_wall = cuboid(0.3, WALL_HEIGHT, HALL_SIZE.y);
    let dais_low = cuboid(HALL_SIZE.x, 0.2, 2.2);
    let dais_high = cuboid(HALL_SIZE.x, 0.2, 1.2);
    let plinth = cuboid(0.75, 0.25, 0.75);
    let shaft = cuboid(0.42, 3.2, 0.42);
    let lintel = cuboid(10.2, 0.4, 0.55);
    let pilaster = cuboid(0.5, WALL_HEIGHT, 0.4);
    let crate_box = cuboid(0.7, 0.7, 0.7);
    let seat = cuboid(1.6, 0.08, 0.45);
    let leg = cuboid(0.1, 0.4, 0.4);
    let screen = cuboid(1.4, 1.1, 0.08);
    let barrel = meshes.add(Cylinder::new(0.3, 0.9).mesh().resolution(32));
    let ball = meshes.add(Sphere::new(0.35).mesh().uv(48, 24));

    let mut commands = world.commands();
    let mut place = |mesh: &Handle<Mesh>, material: &Handle<StandardMaterial>, at: Transform| {
        commands
            .spawn((Mesh3d(mesh.clone()), MeshMaterial3d(material.clone()), at))
            .id()
    };
    let c = HALL_CENTRE;
    let (half_x, half_z) = (HALL_SIZE.x / 2.0, HALL_SIZE.y / 2.0);
    // Architecture.
    place(
        &floor,
        &plaster,
        Transform::from_translation(c - Vec3::Y * 0.05),
    );
    place(
        &back_wall,
        &plaster,
        Transform::from_translation(c + Vec3::new(0.0, WALL_HEIGHT / 2.0, -half_z)),
    );
    place(
        &side_wall,
        &plaster,
        Transform::from_translation(c + Vec3::new(-half_x, WALL_HEIGHT / 2.0, 0.0)),
    );
    place(
        &dais_low,
        &stone,
        Transform::from_translation(c + Vec3::new(0.0, 0.1, -half_z + 1.1)),
    );
    place(
        &dais_high,
        &stone,
        Transform::from_translation(c + Vec3::new(0.0, 0.3, -half_z + 0.6)),
    );
    for x in [-4.5, -1.5, 1.5, 4.5] {
        let base = c + Vec3::new(x, 0.0, -2.0);
        place(
            &plinth,
            &stone,
            Transform::from_translation(base + Vec3::Y * 0.125),
        );
        place(
            &shaft,
            &stone,
            Transform::from_translation(base + Vec3::Y * 1.85),
        );
        place(
            &plinth,
            &stone,
            Transform::from_translation(base + Vec3::Y * 3.575),
        );
    }
    place(
        &lintel,
        &stone,
        Transform::from_translation(c + Vec3::new(0.0, 3.9, -2.0)),
    );
    for z in [-3.5, -0.5, 2.5] {
        place(
            &pilaster,
            &plaster,
            Transform::from_translation(c + Vec3::new(-half_x + 0.35, WALL_HEIGHT / 2.0, z)),
        );
    }
    // Props standing in corners and against each other.
    let corner = c + Vec3::new(-half_x + 0.9, 0.35, -half_z + 2.9);
    place(&crate_box, &wood, Transform::from_translation(corner));
    place(
        &crate_box,
        &wood,
        Transform::from_translation(corner + Vec3::new(0.72, 0.0, 0.1)),
    );
    place(
        &crate_box,
        &wood,
        Transform::from_translation(corner + Vec3::new(0.3, 0.7, 0.05))
            .with_rotation(Quat::from_rotation_y(0.4)),
    );
    for (i, offset) in [
        Vec3::ZERO,
        Vec3::new(0.62, 0.0, 0.15),
        Vec3::new(0.25, 0.0, 0.65),
    ]
    .into_iter()
    .enumerate()
    {
        let material = if i == 1 { &clay } else { &paint };
        place(
            &barrel,
            material,
            Transform::from_translation(c + Vec3::new(5.4, 0.45, -0.8) + offset),
        );
    }
    let bench = c + Vec3::new(2.6, 0.0, 1.2);
    place(
        &seat,
        &wood,
        Transform::from_translation(bench + Vec3::Y * 0.44),
    );
    for x in [-0.65, 0.65] {
        place(
            &leg,
            &wood,
            Transform::from_translation(bench + Vec3::new(x, 0.2, 0.0)),
        );
    }
    // Rigid movers: a crate sliding past the columns, a ball rolling by the bench, a screen
    // turning in front of the dais.
    let movers = [
        (
            &crate_box,
            &clay,
            Shuttle {
                from: c + Vec3::new(-3.6, 0.35, 0.2),
                to: c + Vec3::new(-0.6, 0.35, 0.2),
                period: 5.0,
                spin: 0.3,
            },
        ),
        (
            &ball,
            &paint,
            Shuttle {
                from: c + Vec3::new(0.8, 0.35, 2.4),
                to: c + Vec3::new(4.2, 0.35, 2.4),
                period: 4.0,
                spin: 1.5,
            },
        ),
        (
            &screen,
            &wood,
            Shuttle {
                from: c + Vec3::new(0.0, 0.55, -3.4),
                to: c + Vec3::new(0.0, 0.55, -3.4),
                period: 1.0,
                spin: 0.5,
            },
        ),
    ];
    let mut moving = Vec::new();
    for (mesh, material, shuttle) in movers {
        moving.push((
            place(mesh, material, Transform::from_translation(shuttle.from)),
            shuttle,
        ));
    }
    for (entity, shuttle) in moving {
        commands
            .entity(entity)
            .insert((shuttle, SphereOccluder::default()));
    }
    // Walkers between the columns, neighbours in opposite directions.
    for (i, (centre, radius)) in [
        (Vec3::new(-3.0, 0.0, -0.9), 0.9),
        (Vec3::new(0.0, 0.0, -0.6), 1.1),
        (Vec3::new(3.0, 0.0, -0.9), 0.9),
    ]
    .into_iter()
    .enumerate()
    {
        commands
            .spawn((
                WorldAssetRoot(walker.clone()),
                SphereOccluder::default(),
                Transform::default(),
                WalkPath {
                    centre: c + centre,
                    radius,
                    speed: if i % 2 == 0 { 0.7 } else { -0.6 },
                    phase: i as f32 * 1.9,
                },
            ))
            .observe(start_walking);
    }
    commands.spawn((
        DirectionalLight {
            illuminance: 250.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(4.0, 8.0, 5.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
}

/// The box a voxel volume over the whole hall covers: floor to ceiling, wall to wall.
pub fn bounds() -> (Vec3, Vec3) {
    let half = Vec3::new(HALL_SIZE.x / 2.0, 0.0, HALL_SIZE.y / 2.0);
    (
        HALL_CENTRE - half,
        HALL_CENTRE + half + Vec3::Y * WALL_HEIGHT,
    )
}
