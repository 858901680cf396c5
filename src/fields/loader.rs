//! The Bevy asset loader for `.aofield` files.

use bevy::asset::{AssetLoader, LoadContext, io::Reader};
use bevy::reflect::TypePath;

use super::format::{AoFieldData, AoFieldError};

/// Loads `.aofield` files into [`AoFieldData`] assets. A corrupt, truncated or wrong-version
/// file fails to load with an [`AoFieldError`] that says which; nothing panics.
#[derive(Default, TypePath)]
pub struct AoFieldLoader;

impl AssetLoader for AoFieldLoader {
    type Asset = AoFieldData;
    type Settings = ();
    type Error = AoFieldError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        _load_context: &mut LoadContext<'_>,
    ) -> Result<AoFieldData, AoFieldError> {
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).await?;
        AoFieldData::from_bytes(&bytes)
    }

    fn extensions(&self) -> &[&str] {
        &["aofield"]
    }
}
