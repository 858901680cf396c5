//! Every model in `../shared/assets` (or `DYNAMIC_AO_SHARED_ASSETS`) through every technique
//! `ao_capture` offers, at two animation times: each model stands on a floor, every mesh a sphere
//! occluder and an AO field (and inside one voxel volume), as `ao_capture`'s far-field techniques
//! set it up. No panic, and an image that is finite, in range, not black, and shows occlusion
//! wherever a technique runs. Skipped, with a message, where the folder is absent.

use bevy::math::Vec2;
use bevy_dynamic_ao::prelude::*;

use crate::far_scenes::{FarRun, Model, model_on_floor};
use crate::far_terms::FarTerm;
use crate::models::shared_assets;

/// What `ao_capture --technique` takes, built from the same lists: the default, every
/// image-space technique (and none, and Bevy's SSAO) alone, every far-field term alone, and
/// every image-space technique with each far-field term.
fn techniques() -> Vec<(String, Option<AoTechnique>, Option<FarTerm>)> {
    let mut all = vec![("default".to_string(), None, None)];
    for (name, technique) in AoTechnique::ALL {
        all.push((name.to_string(), Some(technique), None));
    }
    for term in FarTerm::ALL {
        all.push((term.name().to_string(), Some(AoTechnique::Off), Some(term)));
    }
    for (name, technique) in AoTechnique::ALL {
        if !matches!(technique, AoTechnique::Off | AoTechnique::BevySsao) {
            for term in FarTerm::ALL {
                all.push((
                    format!("{name}+{}", term.name()),
                    Some(technique),
                    Some(term),
                ));
            }
        }
    }
    all
}

/// Every `.glb` and `.gltf` one folder down in `folder`, relative to it.
fn models(folder: &std::path::Path) -> Vec<String> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(folder).expect("the shared assets folder reads") {
        let dir = entry.expect("a folder entry").path();
        let Ok(inner) = std::fs::read_dir(&dir) else {
            continue;
        };
        for file in inner.flatten() {
            let path = file.path();
            if matches!(
                path.extension().and_then(|e| e.to_str()),
                Some("glb" | "gltf")
            ) {
                let relative = path.strip_prefix(folder).expect("inside the folder");
                files.push(relative.to_string_lossy().into_owned());
            }
        }
    }
    files.sort();
    files
}

#[test]
fn every_shared_model_goes_through_every_technique() {
    let Some(folder) = shared_assets() else {
        return;
    };
    let models = models(&folder);
    assert!(
        models.len() >= 9,
        "only {} models in {folder:?}",
        models.len()
    );
    let radius = 0.75;
    for file in &models {
        for time in [0.3, 1.1] {
            // The run's scene takes its names for the whole test.
            let file: &'static str = Box::leak(file.clone().into_boxed_str());
            let scene = model_on_floor(
                file,
                Model {
                    file,
                    animation: Some(0),
                    time,
                    height: 1.2,
                    at: Vec2::ZERO,
                },
            );
            let mut run = FarRun::new(&scene, folder.to_str());
            let mut line = format!("{file} at {time} s:");
            for (name, technique, term) in techniques() {
                run.image_space = match technique {
                    Some(technique) => DynamicAo {
                        technique,
                        ..crate::harness::plain_ao()
                    },
                    None => DynamicAo::default(),
                };
                let mut frame = run.render(
                    technique != Some(AoTechnique::Off),
                    term,
                    FarFieldBlend::CountOnce,
                    radius,
                );
                if technique.is_none() {
                    // The default runs every far-field term there are occluders for.
                    run.render(
                        true,
                        Some(FarTerm::Voxels),
                        FarFieldBlend::CountOnce,
                        radius,
                    );
                    run.gpu.set_ao(|ao| {
                        *ao = DynamicAo {
                            radius,
                            ..DynamicAo::default()
                        }
                    });
                    frame = run.gpu.frame(30);
                }
                let seen = frame.geometry_visibility();
                assert!(seen.len() > 500, "{file}, {name}: {} pixels", seen.len());
                assert!(
                    frame
                        .visibility
                        .iter()
                        .all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
                    "{file} at {time} s, {name}: a value out of range"
                );
                let mean = seen.iter().sum::<f32>() / seen.len() as f32;
                let darkest = seen.iter().copied().fold(1.0, f32::min);
                line += &format!(" {name} {mean:.2}/{darkest:.2}");
                if technique == Some(AoTechnique::Off) && term.is_none() {
                    assert!(darkest > 0.999, "{file}, none: darkened to {darkest}");
                } else {
                    assert!(mean > 0.3, "{file} at {time} s, {name}: black ({mean})");
                    assert!(
                        darkest < 0.95,
                        "{file} at {time} s, {name}: no occlusion (darkest {darkest})"
                    );
                }
            }
            println!("{line}");
        }
    }
}
