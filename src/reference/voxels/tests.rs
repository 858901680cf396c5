use super::*;
use crate::geometry::closed::is_closed;

fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
    Triangle {
        vertices: [a.into(), b.into(), c.into()],
        normals: None,
    }
}

#[test]
fn a_triangle_in_a_grid_plane_fills_one_layer_of_cells() {
    // The plane z = 2 in a 4³ grid over [0, 4]³ touches the cells on both sides; only the
    // layer it lies in by its bounding box (cells [2, 3]) is set, as on the GPU.
    let grid = voxelize(
        &[
            tri([0.0, 0.0, 2.0], [4.0, 0.0, 2.0], [4.0, 4.0, 2.0]),
            tri([0.0, 0.0, 2.0], [4.0, 4.0, 2.0], [0.0, 4.0, 2.0]),
        ],
        4,
        Affine3A::IDENTITY,
    );
    assert_eq!(grid.count(), 16);
    assert!(grid.occupied([0, 3, 2]) && grid.occupied([3, 0, 2]));
    assert!(!grid.occupied([0, 0, 1]) && !grid.occupied([0, 0, 3]));
}

#[test]
fn a_sliver_seen_edge_on_is_kept() {
    // A triangle lying in the plane x = 1.5, edge-on to X, the case §5 worries about.
    let grid = voxelize(
        &[tri([1.5, 0.2, 0.2], [1.5, 3.8, 0.2], [1.5, 0.2, 3.8])],
        4,
        Affine3A::IDENTITY,
    );
    assert!(grid.occupied([1, 0, 0]) && grid.occupied([1, 3, 0]));
    assert!(!grid.occupied([0, 0, 0]) && !grid.occupied([2, 0, 0]));
}

#[test]
fn separated_triangles_and_cells_do_not_overlap() {
    let near = Vec3::new(0.4, 0.4, 0.4);
    assert!(triangle_overlaps_cell(near, near + Vec3::X, near + Vec3::Y));
    // The plane x + y + z = 2 passes the cell's corner (½, ½, ½) at distance > 0.
    let far = [
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, 0.0, 2.0),
    ];
    assert!(!triangle_overlaps_cell(far[0], far[1], far[2]));
}

#[test]
fn a_surface_under_a_slab_is_occluded_and_an_open_one_is_not() {
    // A slab of cells one d_max/4 above a surface point.
    let grid_from_world = Affine3A::from_scale(Vec3::splat(8.0));
    let mut grid = VoxelGrid::new(16, grid_from_world);
    for x in 0..16 {
        for y in 0..16 {
            grid.set([x, y, 3]);
        }
    }
    let volume = crate::voxels::VoxelAoVolume {
        half_extents: Vec3::ONE,
        resolution: 16,
        ..Default::default()
    };
    let rays = VoxelRays::new(&volume, grid_from_world);
    let camera = VoxelCamera {
        radius: 1.0,
        count_once: None,
    };
    let p = Vec3::new(1.0, 1.0, 0.0);
    let covered = volume_occlusion(&grid, &rays, &camera, p, Vec3::Z)[1];
    let open = volume_occlusion(&grid, &rays, &camera, p, -Vec3::Z)[1];
    // A slab 0.375 m above, wider than the reach: rays from the start point (one cell
    // diagonal up) meet it within 1 m where cos θ > its height, a share 1 − height² of the
    // cosine-weighted rays.
    let height = 0.375 - rays.bias;
    let expected = 1.0 - height * height;
    assert!((covered - expected).abs() < 0.02, "{covered} vs {expected}");
    assert_eq!(open, 0.0);
}

#[test]
fn the_cell_march_finds_a_floor_one_cell_thick_that_steps_miss() {
    // A floor of cells 1.5 cm thick under a surface point that faces it from 0.3 m above;
    // the paper's 8 steps over 1 m test it only where one lands in it.
    let grid_from_world = Affine3A::from_scale(Vec3::splat(64.0))
        * Affine3A::from_translation(Vec3::new(0.0, 0.0, 0.0));
    let mut grid = VoxelGrid::new(64, grid_from_world);
    for x in 0..64 {
        for y in 0..64 {
            grid.set([x, y, 10]);
        }
    }
    let p = Vec3::new(0.5, 0.5, 10.5 / 64.0 + 0.3);
    let camera = VoxelCamera {
        radius: 1.0,
        count_once: None,
    };
    let occlusion = |march| {
        let volume = crate::voxels::VoxelAoVolume {
            half_extents: Vec3::splat(0.5),
            resolution: 64,
            march,
            ..Default::default()
        };
        let rays = VoxelRays::new(&volume, grid_from_world);
        volume_occlusion(&grid, &rays, &camera, p, -Vec3::Z)[1]
    };
    let cells = occlusion(VoxelMarch::Cells);
    let steps = occlusion(VoxelMarch::Steps(8));
    assert!(
        cells > 0.6,
        "the floor within 1 m below covers most rays: {cells}"
    );
    assert!(steps < 0.5 * cells, "8 steps: {steps}, every cell: {cells}");
}

#[test]
fn rays_stay_in_the_cone() {
    for i in 0..32 {
        let d = ray_direction(i, 32, 0.5, 0.999, 0.3);
        assert!((d.length() - 1.0).abs() < 1e-5 && d.z >= 0.5 - 1e-6, "{d}");
    }
    let frame = tangent_frame(Vec3::new(0.0, 0.6, -0.8));
    assert!((frame * Vec3::Z - Vec3::new(0.0, 0.6, -0.8)).length() < 1e-6);
    assert!(frame.x_axis.dot(frame.y_axis).abs() < 1e-6);
}

fn cube(center: Vec3, half: f32) -> Vec<Triangle> {
    let mut scene = crate::geometry::triangles::TriangleScene::default();
    scene.add_mesh(
        &bevy::math::primitives::Cuboid::from_length(half * 2.0).into(),
        Affine3A::from_translation(center),
    );
    scene.triangles
}

#[test]
fn closed_meshes_are_filled_and_open_ones_are_not() {
    // A cube whose faces are aligned with the grid and whose face diagonals pass through
    // column centres: shared edges must count once or whole columns flip.
    let triangles = cube(Vec3::splat(4.0), 2.0);
    assert!(is_closed(triangles.iter().map(|t| t.vertices)));
    assert!(!is_closed(triangles[..10].iter().map(|t| t.vertices)));
    let mut grid = voxelize(&triangles, 8, Affine3A::IDENTITY);
    let surface = grid.count();
    grid.fill_closed(&triangles);
    for z in 0..8 {
        for y in 0..8 {
            for x in 0..8 {
                let inside = [x, y, z].iter().all(|&c| (2..6).contains(&c));
                let i = (x + 8 * (y + 8 * z)) as usize;
                let solid = grid.solid[i / 32] & (1 << (i % 32)) != 0;
                assert_eq!(solid, inside, "cell {x} {y} {z}");
            }
        }
    }
    // Cells 2..=6 along each axis: the surface shell and the filled interior.
    assert!(surface < 125);
    assert_eq!(grid.count(), 5 * 5 * 5);
}
