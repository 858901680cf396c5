//! Every documented default is the real one: for each public settings type, the test reads the
//! doc comment of every field from the source, takes what follows `Default:` and checks it
//! against the value `Default::default()` gives (through reflection), so a doc comment cannot
//! drift from the code.

use bevy::reflect::structs::Struct;
use bevy::reflect::{PartialReflect, ReflectRef};

use crate::fields::BakeSettings;
use crate::spheres::SphereOccluder;
use crate::voxels::VoxelAoVolume;

use super::*;

/// The documented default of each field of the struct `name` in `source`, in field order.
/// Panics where a public field's doc comment gives no `Default:`.
fn documented_defaults(source: &str, name: &str) -> Vec<(String, String)> {
    let start = source
        .find(&format!("pub struct {name} {{"))
        .unwrap_or_else(|| panic!("no `pub struct {name}` in its source"));
    let mut docs = String::new();
    let mut fields = Vec::new();
    for line in source[start..].lines().skip(1) {
        let line = line.trim();
        if line == "}" {
            break;
        }
        if let Some(doc) = line.strip_prefix("///") {
            docs.push(' ');
            docs.push_str(doc.trim());
        } else if let Some(field) = line.strip_prefix("pub ") {
            let field = field.split(':').next().unwrap().trim().to_string();
            let (_, after) = docs
                .split_once("Default: ")
                .unwrap_or_else(|| panic!("{name}::{field} documents no `Default: `"));
            let value = after
                .trim_start_matches('[')
                .split([']', ' ', ',', ';', '('])
                .next()
                .unwrap()
                .trim_end_matches(['.', ':', '`'])
                .trim_start_matches('`')
                .to_string();
            fields.push((field, value));
            docs.clear();
        } else if !line.starts_with("#[") && !line.is_empty() {
            docs.clear();
        }
    }
    fields
}

/// Whether `value` is what the documentation's `text` names: a number, `true`, `false`, `None`,
/// an enum variant (`Type::Variant`) or one of `named` (consts and `Type::default`).
fn matches(value: &dyn PartialReflect, text: &str, named: &[(&str, &dyn PartialReflect)]) -> bool {
    if let Some((_, named)) = named.iter().find(|(n, _)| *n == text) {
        return value.reflect_partial_eq(*named) == Some(true);
    }
    if let Ok(number) = text.parse::<f64>() {
        return [
            value.try_downcast_ref::<u32>().map(|v| *v as f64),
            value.try_downcast_ref::<usize>().map(|v| *v as f64),
            value.try_downcast_ref::<f32>().map(|v| *v as f64),
        ]
        .into_iter()
        .flatten()
        .any(|v| (v - number).abs() <= 1e-6 * number.abs().max(1.0));
    }
    if let Ok(flag) = text.parse::<bool>() {
        return value.try_downcast_ref::<bool>() == Some(&flag);
    }
    match value.reflect_ref() {
        ReflectRef::Enum(e) => {
            let variant = text.rsplit("::").next().unwrap();
            let type_name = value
                .get_represented_type_info()
                .map(|info| info.type_path_table().ident().unwrap_or_default())
                .unwrap_or_default();
            e.variant_name() == variant
                && (text == "None" || text.split("::").next() == Some(type_name))
        }
        _ => false,
    }
}

fn check<T: Struct + Default>(source: &str, name: &str, named: &[(&str, &dyn PartialReflect)]) {
    let value = T::default();
    let documented = documented_defaults(source, name);
    assert_eq!(
        documented.len(),
        value.field_len(),
        "{name}: every public field documents its default"
    );
    for (field, text) in documented {
        let actual = value
            .field(&field)
            .unwrap_or_else(|| panic!("{name} has no field {field}"));
        assert!(
            matches(actual, &text, named),
            "{name}::{field} documents `Default: {text}` but is {actual:?}"
        );
    }
}

#[test]
fn every_documented_default_is_the_real_one() {
    let near_field = NearFieldParams::default();
    let horizon = HorizonParams::default();
    let ray_march = RayMarchParams::default();
    let blur = AoBlur::default();
    let temporal = AoTemporal::default();
    let named: &[(&str, &dyn PartialReflect)] = &[
        ("DEFAULT_RADIUS", &DEFAULT_RADIUS),
        ("DEFAULT_NEAR_FIELD_RADIUS", &DEFAULT_NEAR_FIELD_RADIUS),
        ("DEFAULT_INTENSITY", &DEFAULT_INTENSITY),
        ("DEFAULT_MAX_SAMPLES", &DEFAULT_MAX_SAMPLES),
        ("DEFAULT_MIN_SAMPLES", &DEFAULT_MIN_SAMPLES),
        ("DEFAULT_BLUR_RADIUS", &DEFAULT_BLUR_RADIUS),
        (
            "DEFAULT_ACCUMULATED_BLUR_RADIUS",
            &DEFAULT_ACCUMULATED_BLUR_RADIUS,
        ),
        (
            "DEFAULT_VOXEL_ACCUMULATED_BLUR_RADIUS",
            &DEFAULT_VOXEL_ACCUMULATED_BLUR_RADIUS,
        ),
        ("DEFAULT_BLUR_SHARPNESS", &DEFAULT_BLUR_SHARPNESS),
        (
            "DEFAULT_BLUR_NORMAL_SHARPNESS",
            &DEFAULT_BLUR_NORMAL_SHARPNESS,
        ),
        ("DEFAULT_BLUR_DETAIL_REACH", &DEFAULT_BLUR_DETAIL_REACH),
        ("DEFAULT_RAY_MARCH_THICKNESS", &DEFAULT_RAY_MARCH_THICKNESS),
        (
            "DEFAULT_SMALL_VIEWPORT_PIXELS",
            &DEFAULT_SMALL_VIEWPORT_PIXELS,
        ),
        ("NearFieldParams::default", &near_field),
        ("HorizonParams::default", &horizon),
        ("RayMarchParams::default", &ray_march),
        ("AoBlur::default", &blur),
        ("AoTemporal::default", &temporal),
        ("DEFAULT_TEMPORAL_FRAMES", &DEFAULT_TEMPORAL_FRAMES),
        (
            "SphereOccluder::DEFAULT_COUNT",
            &SphereOccluder::DEFAULT_COUNT,
        ),
        (
            "VoxelAoVolume::DEFAULT_HALF_EXTENTS",
            &VoxelAoVolume::DEFAULT_HALF_EXTENTS,
        ),
        (
            "VoxelAoVolume::DEFAULT_RESOLUTION",
            &VoxelAoVolume::DEFAULT_RESOLUTION,
        ),
        ("VoxelAoVolume::DEFAULT_RAYS", &VoxelAoVolume::DEFAULT_RAYS),
        (
            "VoxelAoVolume::DEFAULT_ACCUMULATED_RAYS",
            &VoxelAoVolume::DEFAULT_ACCUMULATED_RAYS,
        ),
        (
            "VoxelAoVolume::DEFAULT_SPREAD",
            &VoxelAoVolume::DEFAULT_SPREAD,
        ),
        (
            "BakeSettings::DEFAULT_RESOLUTION",
            &BakeSettings::DEFAULT_RESOLUTION,
        ),
        ("BakeSettings::DEFAULT_RAYS", &BakeSettings::DEFAULT_RAYS),
    ];
    check::<DynamicAo>(include_str!("mod.rs"), "DynamicAo", named);
    check::<NearFieldParams>(
        include_str!("../near_field/settings.rs"),
        "NearFieldParams",
        named,
    );
    check::<HorizonParams>(
        include_str!("../horizon/settings.rs"),
        "HorizonParams",
        named,
    );
    check::<RayMarchParams>(
        include_str!("../ray_march/settings.rs"),
        "RayMarchParams",
        named,
    );
    check::<AoBlur>(include_str!("../filter/settings.rs"), "AoBlur", named);
    check::<AoTemporal>(include_str!("../temporal/settings.rs"), "AoTemporal", named);
    check::<SphereOccluder>(
        include_str!("../spheres/component.rs"),
        "SphereOccluder",
        named,
    );
    check::<VoxelAoVolume>(
        include_str!("../voxels/component.rs"),
        "VoxelAoVolume",
        named,
    );
    check::<BakeSettings>(
        include_str!("../fields/baker/mod.rs"),
        "BakeSettings",
        named,
    );
}

#[test]
fn a_wrong_documented_default_is_caught() {
    let source = "pub struct AoBlur {\n    /// Default: 5.\n    pub radius: u32,\n    \
                  /// Default: [`DEFAULT_BLUR_SHARPNESS`].\n    pub sharpness: f32,\n}\n";
    let documented = documented_defaults(source, "AoBlur");
    assert_eq!(documented[0], ("radius".into(), "5".into()));
    let blur = AoBlur::default();
    let named: &[(&str, &dyn PartialReflect)] =
        &[("DEFAULT_BLUR_SHARPNESS", &DEFAULT_BLUR_SHARPNESS)];
    assert!(!matches(blur.field("radius").unwrap(), "5", named));
    assert!(matches(
        blur.field("sharpness").unwrap(),
        &documented[1].1,
        named
    ));
}
