//! Which views a far-field occluder casts on: the ones Bevy would draw it in, by
//! [`RenderLayers`].
//!
//! The image-space terms see only what the view's prepass drew, so they follow `RenderLayers`
//! by themselves. Sphere proxies, AO fields and voxel volumes are shared by all views; each of
//! their GPU records carries its layers as bits, each view's uniform its own, and a pass skips
//! a record whose bits share none with the view's (`seen_by_view` in `uniform.wgsl`).
//!
//! Layers 0 to 62 are told apart exactly. Layers 63 and above share the last bit: two entities
//! whose only common ground is that both lie on layers past 62 count as sharing one (warned
//! once).

use std::sync::atomic::{AtomicBool, Ordering};

use bevy::camera::visibility::{DEFAULT_LAYERS, RenderLayers};
use bevy::log::warn;
use bevy::math::UVec2;

/// The bit that stands for every layer from 63 on.
const LAST_BIT: u64 = 1 << 63;

/// `layers` as the shaders compare them (low word, high word); an entity without the component
/// is on layer 0, as Bevy has it.
pub(crate) fn layer_bits(layers: Option<&RenderLayers>) -> UVec2 {
    let Some(layers) = layers else {
        return UVec2::new(1, 0);
    };
    let blocks = layers.bits();
    let mut bits = blocks.first().copied().unwrap_or(0);
    if blocks.iter().skip(1).any(|b| *b != 0) {
        bits |= LAST_BIT;
        static WARNED: AtomicBool = AtomicBool::new(false);
        if !WARNED.swap(true, Ordering::Relaxed) {
            warn!(
                "RenderLayers past 62 are one layer to far-field occluders (spheres, AO fields, \
                 voxels): {layers:?} counts as sharing a layer with every entity on a layer past 62"
            );
        }
    }
    UVec2::new(bits as u32, (bits >> 32) as u32)
}

/// Whether an entity on `outer` is on every layer of `inner` (an entity without the component is
/// on layer 0).
pub(crate) fn on_every_layer_of(
    outer: Option<&RenderLayers>,
    inner: Option<&RenderLayers>,
) -> bool {
    let outer = outer.unwrap_or(DEFAULT_LAYERS).bits();
    let inner = inner.unwrap_or(DEFAULT_LAYERS).bits();
    inner
        .iter()
        .enumerate()
        .all(|(i, bits)| bits & !outer.get(i).copied().unwrap_or(0) == 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_become_bits() {
        assert_eq!(layer_bits(None), UVec2::new(1, 0));
        assert_eq!(
            layer_bits(Some(&RenderLayers::from_layers(&[0, 5, 40]))),
            UVec2::new(1 | 1 << 5, 1 << 8)
        );
        assert_eq!(layer_bits(Some(&RenderLayers::none())), UVec2::ZERO);
        // 63 and 200 share the last bit.
        assert_eq!(
            layer_bits(Some(&RenderLayers::layer(63))),
            layer_bits(Some(&RenderLayers::from_layers(&[200])))
        );
        assert_eq!(
            layer_bits(Some(&RenderLayers::layer(62))),
            UVec2::new(0, 1 << 30)
        );
    }

    #[test]
    fn every_layer_of() {
        let both = RenderLayers::from_layers(&[0, 1]);
        let one = RenderLayers::layer(1);
        assert!(on_every_layer_of(None, None));
        assert!(on_every_layer_of(Some(&both), None));
        assert!(on_every_layer_of(Some(&both), Some(&one)));
        assert!(!on_every_layer_of(Some(&one), None));
        assert!(!on_every_layer_of(None, Some(&both)));
        assert!(!on_every_layer_of(
            Some(&both),
            Some(&RenderLayers::from_layers(&[100]))
        ));
        assert!(on_every_layer_of(None, Some(&RenderLayers::none())));
    }
}
