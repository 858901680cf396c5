//! Geometry every technique and the CPU reference share, with no rendering in it: a mesh's
//! rest-pose data and its deformation into world space, world-space triangles, a BVH over them,
//! closedness, the share of ambient light a cone of directions blocks, the integer hash
//! behind every pseudo-random pattern, and which far-field occluders join by their union.
//!
//! - [`rest_mesh`]: positions, normals, skin and morph targets copied out of a Bevy mesh once.
//! - [`deform`]: the mesh in one pose (morph targets, then linear blend skinning), and the pose
//!   a Bevy world draws it in this frame.
//! - [`triangles`]: world-space triangles of Bevy meshes.
//! - [`bvh`]: a bounding volume hierarchy over triangles, for rays and nearest points.
//! - [`closed`]: whether a triangle soup encloses a volume (within a rounding, or exactly).
//! - [`cap`]: the share of ambient light a cone of directions blocks (T_clip, sphere caps), as
//!   `shaders/cap_occlusion.wgsl` evaluates it.
//! - [`simplify`]: fewer triangles for the same surface, by vertex clustering.
//! - [`hash`]: the PCG hash, bit-identical on the CPU and in WGSL.
//! - [`union`]: which far-field occluders join by their union at a receiver.

pub mod bvh;
pub mod cap;
pub mod closed;
pub mod deform;
pub mod hash;
pub mod rest_mesh;
pub mod simplify;
pub mod triangles;
pub mod union;
