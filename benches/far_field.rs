//! Far-field terms against ray-traced ground truth, on scenes set up the way a user would: every
//! mesh an occluder (as `ao_capture`'s far-field techniques do), thin and large occluders, models
//! from elsewhere standing on a floor, occluders just outside the view, at two radii.
//!
//! `cargo bench --bench far_field` prints, per scene and radius, the RMSE of visibility against
//! the CPU ray tracer (256 cosine-weighted rays per pixel, hits within R) for the near field
//! alone, each far-field term alone, and each joined to the near field; for the scenes with an
//! occluder outside the view, the occlusion the strip of floor next to it receives. Third-party
//! models come from `../shared/assets` (or `DYNAMIC_AO_SHARED_ASSETS`) and are skipped where
//! that folder is absent. `-- --scenes a,b` runs the scenes whose names contain a word of the
//! list; `-- --radii 0.75` picks radii; `-- --out DIR` writes each image as a 16-bit PNG;
//! `-- --terms voxels` picks far-field terms (`spheres`, `fields`, `voxels`);
//! `-- --proxies` also compares each model's sphere-occluder proxies with the model itself;
//! `-- --default` joins the far field to the crate's default image-space technique (the
//! accumulated ray march at half resolution, read after 30 frames) instead of the near field.

#[path = "../examples/common/mod.rs"]
mod common;
#[path = "../tests/gpu/far_scenes.rs"]
mod far_scenes;
#[path = "../examples/common/far_terms.rs"]
mod far_terms;
#[path = "../tests/gpu/harness.rs"]
#[allow(dead_code)]
mod harness;
#[path = "../tests/gpu/log_capture.rs"]
#[allow(dead_code)]
mod log_capture;
#[path = "../tests/gpu/models.rs"]
mod models;
#[path = "../tests/gpu/scenes.rs"]
#[allow(dead_code)]
mod scenes;

use std::path::PathBuf;

use bevy::prelude::*;
use bevy_dynamic_ao::geometry::bvh::Bvh;
use bevy_dynamic_ao::prelude::*;
use bevy_dynamic_ao::reference::{
    ground_truth::point_occlusion, metrics::rmse, png16::write_visibility_png,
};
use far_scenes::{FarRun, FarScene};
use far_terms::FarTerm;
use harness::{HEIGHT, WIDTH};

/// What one configuration renders: the image-space technique and the far-field term.
#[derive(Clone, Copy)]
struct Config {
    near: bool,
    far: Option<FarTerm>,
    blend: FarFieldBlend,
}

impl Config {
    fn name(&self) -> String {
        let blend = match self.blend {
            FarFieldBlend::CountOnce => "",
            FarFieldBlend::Add => " (add)",
            FarFieldBlend::Max => " (max)",
        };
        match (self.near, self.far) {
            (true, None) => "near".into(),
            (false, Some(far)) => far.name().into(),
            (true, Some(far)) => format!("near+{}{blend}", far.name()),
            (false, None) => "none".into(),
        }
    }
}

fn configs() -> Vec<Config> {
    let mut list = vec![Config {
        near: true,
        far: None,
        blend: FarFieldBlend::default(),
    }];
    for far in FarTerm::ALL {
        list.push(Config {
            near: false,
            far: Some(far),
            blend: FarFieldBlend::default(),
        });
        for blend in [
            FarFieldBlend::CountOnce,
            FarFieldBlend::Add,
            FarFieldBlend::Max,
        ] {
            list.push(Config {
                near: true,
                far: Some(far),
                blend,
            });
        }
    }
    list
}

/// `--proxies`: the occlusion the sphere occluders' proxies of every mesh but the floor cast on
/// floor points around them (in the plugin's union and as ray-traced boxes), against a ray tracer
/// over those meshes themselves.
fn proxy_report(gpu: &mut harness::Gpu) {
    let (proxies, model) = far_scenes::model_proxies(gpu.app.world_mut());
    let bvh = Bvh::new(model.triangles.clone());
    let floor = far_scenes::floor_points_around(&model, &bvh);
    // The proxies themselves as triangles: what they block together, without the product's
    // double counting.
    let mut box_scene = bevy_dynamic_ao::geometry::triangles::TriangleScene::default();
    for proxy in &proxies {
        let m = bevy::math::Affine3A::from_mat3_translation(proxy.axes * 2.0, proxy.center);
        if m.matrix3.determinant().abs() > 1e-12 {
            box_scene.add_mesh(&Cuboid::new(1.0, 1.0, 1.0).into(), m);
        }
    }
    let boxes = Bvh::new(box_scene.triangles);
    let n = floor.len().max(1) as f32;
    for radius in [0.75f32, 2.0] {
        let mean = |f: &dyn Fn(Vec3) -> f32| floor.iter().map(|&p| f(p)).sum::<f32>() / n;
        let truth = mean(&|p| point_occlusion(&bvh, p, Vec3::Y, radius, 576));
        let traced_boxes = mean(&|p| point_occlusion(&boxes, p, Vec3::Y, radius, 576));
        let [product, largest, union] =
            [0, 1, 2].map(|k| mean(&|p| far_scenes::proxies_on_floor(&proxies, p, radius)[k]));
        println!(
            "proxies vs mesh on the floor around it, R = {radius}: mean occlusion traced {truth:.4}, \
             proxies {product:.4}, proxy boxes traced {traced_boxes:.4}"
        );
        println!("   max {largest:.4}, union (what compose takes) {union:.4}");
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let only: Option<Vec<String>> =
        value("--scenes").map(|s| s.split(',').map(str::to_string).collect());
    let radii: Vec<f32> = value("--radii")
        .map(|s| s.split(',').filter_map(|r| r.parse().ok()).collect())
        .unwrap_or_else(|| vec![0.75, 2.0]);
    let out = value("--out").map(PathBuf::from);
    if let Some(out) = &out {
        std::fs::create_dir_all(out).expect("output folder");
    }
    let shared = models::shared_assets();
    let terms: Option<Vec<FarTerm>> =
        value("--terms").map(|s| s.split(',').filter_map(FarTerm::from_name).collect());
    let configs: Vec<Config> = configs()
        .into_iter()
        .filter(|c| {
            c.far
                .is_none_or(|far| terms.as_ref().is_none_or(|t| t.contains(&far)))
        })
        .collect();

    let mut scenes: Vec<FarScene> = far_scenes::procedural();
    scenes.push(far_scenes::walker_on_floor());
    scenes.push(far_scenes::frame_on_floor());
    if shared.is_some() {
        scenes.extend(far_scenes::third_party());
    }
    for scene in scenes {
        if only
            .as_ref()
            .is_some_and(|words| !words.iter().any(|w| scene.name.contains(w.as_str())))
        {
            continue;
        }
        let folder = scene
            .model
            .filter(|m| !m.file.starts_with("characters/"))
            .and(shared.as_ref())
            .and_then(|p| p.to_str());
        let mut run = FarRun::new(&scene, folder);
        if args.iter().any(|a| a == "--default") {
            // The crate's default image-space technique in place of the near field.
            run.image_space = DynamicAo::default();
        }
        if args.iter().any(|a| a == "--proxies") {
            proxy_report(&mut run.gpu);
        }
        let bvh = run.bvh();
        println!("\n### {}\n", scene.name);
        let mut header = "| configuration |".to_string();
        let mut rule = "|---|".to_string();
        for r in &radii {
            header += &format!(" RMSE R = {r} m |");
            rule += "---:|";
            if scene.strip.is_some() {
                header += &format!(" strip R = {r} m |");
                rule += "---:|";
            }
        }
        let mut rows: Vec<String> = configs
            .iter()
            .map(|c| format!("| {} |", c.name()))
            .collect();
        let mut truth_row = "| ground truth |".to_string();
        for &radius in &radii {
            let mut truth: Option<(Vec<f32>, Vec<bool>)> = None;
            for (config, row) in configs.iter().zip(&mut rows) {
                let frame = run.render(config.near, config.far, config.blend, radius);
                let (truth, mask) = truth.get_or_insert_with(|| {
                    (frame.ground_truth(&bvh, radius), frame.geometry_mask())
                });
                let error = rmse(&frame.visibility, truth, Some(mask));
                *row += &format!(" {error:.4} |");
                if let Some(strip) = &scene.strip {
                    *row += &format!(" {:.3} |", harness::band(&frame.visibility, strip.clone()));
                }
                if let Some(out) = &out {
                    let file = format!(
                        "{}_{}_{radius}.png",
                        scene.name.replace(' ', "_"),
                        config.name().replace(['+', ' ', '(', ')'], "_")
                    );
                    write_visibility_png(&out.join(file), WIDTH, HEIGHT, &frame.visibility)
                        .expect("write png");
                }
            }
            let (truth, _) = truth.as_ref().unwrap();
            truth_row += " – |";
            if let Some(strip) = &scene.strip {
                truth_row += &format!(" {:.3} |", harness::band(truth, strip.clone()));
            }
            if let Some(out) = &out {
                let file = format!("{}_truth_{radius}.png", scene.name.replace(' ', "_"));
                write_visibility_png(&out.join(file), WIDTH, HEIGHT, truth).expect("write png");
            }
        }
        println!("{header}\n{rule}\n{truth_row}");
        for row in rows {
            println!("{row}");
        }
    }
}
