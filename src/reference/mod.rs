//! CPU reference: the plugin's formulas evaluated on the CPU, a BVH ray tracer for ground
//! truth, image metrics and 16-bit PNG output. No GPU needed; tests, benchmarks and tools use it.
//!
//! - [`nd_buffer`]: an ND-buffer read back from the GPU and the camera that made it.
//! - [`near_field`]: Shanmugam & Arikan eq. 2–4 exactly as `near_field.wgsl` evaluates them.
//! - [`horizon`]: horizon-based AO (Bavoil & Sainz 2008) exactly as `horizon.wgsl` runs it.
//! - [`ray_march`]: the ray-marched reference exactly as `march.wgsl` runs it.
//! - [`fields`]: AO field occlusion exactly as `fields/fields.wgsl` evaluates it.
//! - [`spheres`]: the far field of sphere occluders exactly as `spheres/splat.wgsl` adds it.
//! - [`filter`]: the cross-bilateral blur exactly as `filter/blur.wgsl` runs it.
//! - [`fine_detail`]: the fine-detail term exactly as the ray march, the blur and the upsampling
//!   add it.
//! - [`crate::geometry`] holds the triangles, BVH, hash and cap occlusion these share with the
//!   plugin.
//! - [`posed`]: the triangles a Bevy world draws this frame, skinned and morphed meshes posed.
//! - [`ground_truth`]: ray-traced ambient occlusion, cosine-weighted over the hemisphere,
//!   binary hits within a distance R, 1 = open (eq. 1 of the papers).
//! - [`metrics`]: RMSE and mean bias between two AO images.
//! - [`png16`]: 16-bit grayscale PNG files of visibility.

pub mod fields;
pub mod filter;
pub mod fine_detail;
pub mod ground_truth;
pub mod horizon;
pub mod metrics;
pub mod nd_buffer;
pub mod near_field;
pub mod png16;
pub mod posed;
#[cfg(test)]
mod proxy_cast;
pub mod ray_march;
pub mod sampling;
pub mod spheres;
pub mod voxels;
