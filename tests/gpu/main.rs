//! GPU tests: whole headless apps render small scenes (on lavapipe where no GPU exists) and
//! compare what the plugin computed with the CPU reference and with ray-traced ground truth.
//! One test binary on purpose: every binary links all of Bevy.

#[path = "../../examples/common/character.rs"]
mod character;
#[path = "../../examples/common/mod.rs"]
mod common;
#[path = "../../examples/common/far_terms.rs"]
mod far_terms;
#[path = "../../examples/common/gltf_scene.rs"]
mod gltf_scene;
#[path = "../../examples/common/toasters.rs"]
mod toasters;

mod ao_capture;
mod back_layer;
mod bad_input;
mod camera_setups;
mod cameras;
mod coarse_back_faces;
mod device_limits;
mod examples;
mod far_field;
mod far_scenes;
mod fields;
mod fine_detail;
mod first_frames;
mod half_resolution;
mod harness;
mod horizon;
mod lifecycle;
mod lighting;
mod log_capture;
mod models;
mod near_field;
mod presets;
mod ray_march;
mod real_assets;
mod scenes;
mod shared_assets;
mod skinned;
mod soak;
mod spheres;
mod temporal;
mod voxels;
