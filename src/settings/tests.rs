use super::*;

#[test]
fn defaults_are_the_high_level() {
    let ao = DynamicAo::default();
    assert_eq!(ao.technique, AoTechnique::RayMarch);
    assert_eq!(ao.temporal, AoPreset::High.temporal());
    assert!(ao.half_resolution);
    assert_eq!(ao.near_field, AoPreset::High.near_field());
    assert_eq!(ao.horizon, AoPreset::High.horizon());
    assert_eq!(ao.ray_march, AoPreset::High.ray_march());
    assert_eq!(ao.horizon.sanitized(), HorizonParams::default());
    assert_eq!(AoPreset::default(), AoPreset::High);
    assert_eq!(DynamicAo::from_preset(AoPreset::High), ao);
}

#[test]
fn small_viewports_run_at_full_resolution() {
    let ao = DynamicAo::default();
    assert!(!ao.half_resolution_at(UVec2::new(160, 120)));
    assert!(!ao.half_resolution_at(UVec2::new(240, 180)));
    assert!(ao.half_resolution_at(UVec2::new(241, 180)));
    assert!(ao.half_resolution_at(UVec2::new(320, 240)));
    assert!(ao.half_resolution_at(UVec2::new(640, 480)));
    assert!(ao.half_resolution_at(UVec2::new(1920, 1080)));
    // Past u32 when multiplied.
    assert!(ao.half_resolution_at(UVec2::new(u32::MAX, u32::MAX)));
    let everywhere = DynamicAo {
        small_viewport_pixels: 0,
        ..ao.clone()
    };
    assert!(everywhere.half_resolution_at(UVec2::ONE));
    let full = DynamicAo {
        half_resolution: false,
        ..ao
    };
    assert!(!full.half_resolution_at(UVec2::new(1920, 1080)));
}

#[test]
fn each_level_picks_its_technique() {
    // Every level runs the ray march at half resolution, accumulated: without accumulation its
    // noise needs the blur, which costs more than the whole default (README, preset table).
    for preset in AoPreset::ALL {
        let ao = DynamicAo::from_preset(preset);
        assert_eq!(ao.technique, AoTechnique::RayMarch, "{preset:?}");
        assert!(ao.half_resolution, "{preset:?}");
        assert!(ao.temporal.enabled, "{preset:?}");
        assert_eq!(ao.temporal, AoTemporal::default(), "{preset:?}");
    }
}

#[test]
fn levels_grow_in_cost() {
    let samples: Vec<u32> = AoPreset::ALL
        .iter()
        .map(|p| p.near_field().max_samples)
        .collect();
    assert!(samples.windows(2).all(|w| w[0] < w[1]), "{samples:?}");
    let horizon: Vec<(u32, u32)> = AoPreset::ALL
        .iter()
        .map(|p| {
            let h = p.horizon();
            (h.directions * h.steps, h.mode.shader_index())
        })
        .collect();
    assert!(horizon.windows(2).all(|w| w[0] < w[1]), "{horizon:?}");
    let rays: Vec<u32> = AoPreset::ALL
        .iter()
        .map(|p| {
            let r = p.ray_march();
            r.directions * r.elevations * r.steps
        })
        .collect();
    assert!(rays.windows(2).all(|w| w[0] < w[1]), "{rays:?}");
}

#[test]
fn bad_values_fall_back() {
    let ao = DynamicAo {
        radius: f32::NAN,
        intensity: -1.0,
        ..default()
    };
    assert_eq!(ao.effective_radius(), DEFAULT_RADIUS);
    assert_eq!(ao.effective_intensity(), DEFAULT_INTENSITY);
    let p = NearFieldParams {
        max_samples: 0,
        min_samples: 99,
        back_layer: false,
    }
    .sanitized();
    assert_eq!((p.max_samples, p.min_samples), (1, 1));
    let blur = AoBlur {
        radius: 99,
        accumulated_radius: 99,
        voxel_accumulated_radius: 99,
        sharpness: f32::NAN,
        normal_sharpness: -1.0,
        detail_reach: 99,
    }
    .sanitized();
    assert_eq!(blur.radius, AoBlur::MAX_RADIUS);
    assert_eq!(blur.accumulated_radius, AoBlur::MAX_RADIUS);
    assert_eq!(blur.voxel_accumulated_radius, AoBlur::MAX_RADIUS);
    assert_eq!(blur.detail_reach, AoBlur::MAX_DETAIL_REACH);
    assert_eq!(blur.sharpness, DEFAULT_BLUR_SHARPNESS);
    assert_eq!(blur.normal_sharpness, DEFAULT_BLUR_NORMAL_SHARPNESS);
}

#[test]
fn names_round_trip() {
    for (name, t) in AoTechnique::ALL {
        assert_eq!(AoTechnique::from_name(name), Some(t));
        assert_eq!(t.name(), name);
    }
    for p in AoPreset::ALL {
        assert_eq!(AoPreset::from_name(p.name()), Some(p));
    }
    assert_eq!(AoTechnique::from_name("nope"), None);
    assert_eq!(AoPreset::from_name("nope"), None);
}

fn default<T: Default>() -> T {
    T::default()
}

#[test]
fn problems_name_each_bad_value_and_its_replacement() {
    assert!(DynamicAo::default().problems().is_empty());
    for preset in AoPreset::ALL {
        assert!(DynamicAo::from_preset(preset).problems().is_empty());
    }
    let bad = DynamicAo {
        radius: -2.0,
        intensity: f32::NAN,
        ray_march: RayMarchParams {
            directions: 0,
            ..default()
        },
        ..default()
    };
    assert_eq!(
        bad.problems(),
        [
            "radius -2.0 is out of range; using 0.75".to_string(),
            "intensity NaN is out of range; using 1.0".to_string(),
            format!(
                "ray_march {:?} is out of range; using {:?}",
                bad.ray_march,
                bad.ray_march.sanitized()
            ),
        ]
    );
}

#[test]
fn the_ray_marchs_thickness_is_a_share_of_r_between_0_and_1() {
    let with = |thickness| RayMarchParams {
        thickness,
        ..default()
    };
    assert_eq!(
        with(f32::NAN).sanitized().thickness,
        DEFAULT_RAY_MARCH_THICKNESS
    );
    assert_eq!(with(-0.5).sanitized().thickness, 0.0);
    assert_eq!(with(3.0).sanitized().thickness, 1.0);
    assert_eq!(with(0.3).sanitized().thickness, 0.3);
    let bad = DynamicAo::default().with_ray_march(with(f32::INFINITY));
    assert_eq!(
        bad.problems(),
        [format!(
            "ray_march {:?} is out of range; using {:?}",
            bad.ray_march,
            with(1.0)
        )]
    );
}
