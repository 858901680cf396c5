//! The showcase's text: a caption over each view and, at the bottom, the GPU milliseconds of
//! every AO pass (Bevy's render diagnostics, from timestamp queries) and the keys.

use bevy::diagnostic::DiagnosticsStore;
use bevy::prelude::*;
use bevy_dynamic_ao::prelude::*;

use crate::Far;
use crate::far_terms::FarTerm;
use crate::views::{Layout, Shown};

/// The caption over a view (`Some`), or the timing and key line (`None`).
#[derive(Component)]
pub struct Caption(Option<Shown>);

/// Spawns the captions and the bottom line.
pub fn spawn(mut commands: Commands) {
    for shown in Shown::ALL {
        commands.spawn(text(Some(shown), Node::default()));
    }
    commands.spawn(text(
        None,
        Node {
            bottom: px(8.0),
            left: px(0.0),
            ..default()
        },
    ));
}

fn text(
    caption: Option<Shown>,
    node: Node,
) -> (Caption, Text, TextFont, TextShadow, Node, GlobalZIndex) {
    (
        Caption(caption),
        Text::new(""),
        TextFont {
            font_size: FontSize::Px(14.0),
            ..default()
        },
        TextShadow {
            offset: Vec2::splat(1.5),
            color: Color::BLACK.with_alpha(0.8),
        },
        Node {
            position_type: PositionType::Absolute,
            top: if caption.is_some() {
                px(6.0)
            } else {
                Val::Auto
            },
            margin: UiRect::left(px(8.0)),
            ..node
        },
        // Over the row of views.
        GlobalZIndex(1),
    )
}

/// The mean GPU time of each of our passes and of Bevy's SSAO pass, ms.
fn pass_times(diagnostics: &DiagnosticsStore) -> (Vec<(String, f64)>, Option<f64>) {
    let mut ours = Vec::new();
    let mut bevy = None;
    for diagnostic in diagnostics.iter() {
        let Some(pass) = diagnostic
            .path()
            .as_str()
            .strip_prefix("render/")
            .and_then(|p| p.strip_suffix("/elapsed_gpu"))
        else {
            continue;
        };
        let Some(ms) = diagnostic.smoothed() else {
            continue;
        };
        if let Some(name) = pass.strip_prefix("dynamic_ao_") {
            ours.push((name.replace('_', " "), ms));
        } else if pass == "ssao" {
            bevy = Some(ms);
        }
    }
    (ours, bevy)
}

/// Rewrites the captions and the bottom line, and places the captions over their views.
pub fn update(
    layout: Res<Layout>,
    far: Res<Far>,
    ours: Query<&DynamicAo>,
    diagnostics: Res<DiagnosticsStore>,
    mut texts: Query<(&Caption, &mut Text, &mut Node)>,
) {
    let Ok(ao) = ours.single() else {
        return;
    };
    let preset = AoPreset::ALL
        .into_iter()
        .find(|p| {
            let preset = DynamicAo::from_preset(*p);
            preset.technique == ao.technique
                && preset.ray_march == ao.ray_march
                && preset.horizon == ao.horizon
        })
        .map_or("custom", AoPreset::name);
    let far_name = far.0.map_or("no far field", FarTerm::name);
    let (passes, bevy) = pass_times(&diagnostics);
    let timing = if passes.is_empty() && bevy.is_none() {
        "GPU times: none yet (the adapter may lack timestamp queries)".to_string()
    } else {
        let total: f64 = passes.iter().map(|(_, ms)| ms).sum();
        let each: Vec<String> = passes
            .iter()
            .map(|(name, ms)| format!("{name} {ms:.2}"))
            .collect();
        // A view off screen keeps the last time it was measured: leave it out.
        let bevy = bevy
            .filter(|_| layout.shows(Shown::BevySsao))
            .map_or(String::new(), |ms| format!(" | Bevy's SSAO {ms:.2}"));
        format!("GPU ms, ours {total:.2} ({}){bevy}", each.join(", "))
    };
    for (caption, mut text, mut node) in &mut texts {
        let Some(shown) = caption.0 else {
            text.0 =
                format!("{timing}\nC layout  1-4 presets  F far field  D debug view  Esc quit");
            continue;
        };
        text.0 = match shown {
            Shown::Ours => format!("ours: {preset}, {far_name}"),
            Shown::BevySsao => "Bevy's SSAO High".into(),
            Shown::NoAo => "no AO".into(),
        };
        let third = Shown::ALL.iter().position(|s| *s == shown).unwrap_or(0);
        let (display, left) = match *layout {
            Layout::Thirds => (Display::Flex, percent(100.0 * third as f32 / 3.0)),
            Layout::Alone(alone) if alone == shown => (Display::Flex, px(0.0)),
            Layout::Alone(_) => (Display::None, px(0.0)),
        };
        if node.display != display || node.left != left {
            node.display = display;
            node.left = left;
        }
    }
}
