//! The paper's fixes for a field of unlimited reach (Malmer et al. 2005, §3.4), kept as options
//! ([`BakeSettings::paper`](super::BakeSettings::paper)): the interior fill and the border
//! rescale.

use bevy::math::Vec3;

use crate::fields::format::AoFieldData;

/// §3.4.2: cells inside the object (every ray blocked) take the mean of their neighbours that
/// see out, so a surface point between an inside and an outside cell interpolates sensibly.
/// One pass, as in the paper: cells deeper inside keep 1, and no surface point reads them.
pub fn fill_interior(field: &mut AoFieldData) {
    let r = field.resolution.as_ivec3();
    for layer in [&mut field.cells, &mut field.near_cells] {
        let original = layer.clone();
        let index = |x: i32, y: i32, z: i32| ((z * r.y + y) * r.x + x) as usize;
        for z in 0..r.z {
            for y in 0..r.y {
                for x in 0..r.x {
                    let i = index(x, y, z);
                    if original[i][0] < 1.0 {
                        continue;
                    }
                    let (mut sum, mut dir, mut count) = (0.0, Vec3::ZERO, 0);
                    for dz in -1..=1 {
                        for dy in -1..=1 {
                            for dx in -1..=1 {
                                let (nx, ny, nz) = (x + dx, y + dy, z + dz);
                                if nx < 0 || ny < 0 || nz < 0 || nx >= r.x || ny >= r.y || nz >= r.z
                                {
                                    continue;
                                }
                                let c = original[index(nx, ny, nz)];
                                if c[0] < 1.0 {
                                    sum += c[0];
                                    dir += Vec3::new(c[1], c[2], c[3]);
                                    count += 1;
                                }
                            }
                        }
                    }
                    if count > 0 {
                        let d = dir.normalize_or_zero();
                        layer[i] = [sum / count as f32, d.x, d.y, d.z];
                    }
                }
            }
        }
    }
}

/// Values at or below this are rescaled by §3.4.1; larger ones are kept.
const RESCALE_LIMIT: f32 = 0.3;

/// §3.4.1: with V_M the largest occlusion on the grid's boundary, every value V ≤ 0.3 becomes
/// 0.3 (V − V_M) / (0.3 − V_M) (and at least 0), so the field fades to 0 at its boundary and
/// joins the open space outside without a step. V_M is capped just below 0.3, where the formula
/// would break down (a grid far too small for its object).
pub fn rescale_border(field: &mut AoFieldData) {
    let r = field.resolution;
    let mut boundary_max = 0.0f32;
    for z in 0..r.z {
        for y in 0..r.y {
            for x in 0..r.x {
                let on_boundary =
                    x == 0 || y == 0 || z == 0 || x == r.x - 1 || y == r.y - 1 || z == r.z - 1;
                if on_boundary {
                    boundary_max = boundary_max.max(field.cells[field.index(x, y, z)][0]);
                }
            }
        }
    }
    let vm = boundary_max.min(RESCALE_LIMIT - 0.01);
    for cell in field.cells.iter_mut().chain(&mut field.near_cells) {
        if cell[0] <= RESCALE_LIMIT {
            cell[0] = (RESCALE_LIMIT * (cell[0] - vm) / (RESCALE_LIMIT - vm)).max(0.0);
        }
    }
}
