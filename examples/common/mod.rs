//! Shared by every example (and the GPU tests): command-line flags, the app in windowed or
//! headless form, the on-screen help line and the `--headless --frames N --out file.png` run.
#![allow(dead_code)]

use std::path::PathBuf;
use std::time::Duration;

use bevy::app::{PluginsState, ScheduleRunnerPlugin};
use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::diagnostic::FrameCount;
use bevy::prelude::*;
use bevy::render::{
    RenderPlugin,
    render_resource::TextureFormat,
    view::screenshot::{Screenshot, save_to_disk},
};
use bevy::time::TimeUpdateStrategy;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;
use bevy_dynamic_ao::{AoShown, DynamicAo, DynamicAoStatus};

/// Flags every example understands.
#[derive(Clone, Debug)]
pub struct ExampleArgs {
    /// Render without a window, to `out`.
    pub headless: bool,
    /// Frames to render in headless mode, counted from the first frame every active camera's AO is
    /// shown (`headless_capture`); the last one is captured.
    pub frames: u32,
    /// Where the headless run writes its PNG.
    pub out: Option<PathBuf>,
    /// Image size of the headless run, pixels.
    pub width: u32,
    pub height: u32,
    /// Flags the common parser did not recognise, for the example's own use.
    pub rest: Vec<String>,
}

impl ExampleArgs {
    /// Parses `std::env::args`, printing `usage` and exiting on `--help` or a bad value.
    pub fn parse(usage: &str) -> Self {
        match Self::try_parse(std::env::args().skip(1)) {
            Ok(args) => args,
            Err(message) => {
                if message.is_empty() {
                    println!("{usage}");
                    std::process::exit(0);
                }
                eprintln!("error: {message}\n{usage}");
                std::process::exit(2);
            }
        }
    }

    /// Parses flags; `Err("")` means help was asked for.
    pub fn try_parse(args: impl IntoIterator<Item = String>) -> Result<Self, String> {
        let mut parsed = ExampleArgs {
            headless: false,
            frames: 30,
            out: None,
            width: 640,
            height: 480,
            rest: Vec::new(),
        };
        let mut args = args.into_iter();
        while let Some(arg) = args.next() {
            let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
            match arg.as_str() {
                "--headless" => parsed.headless = true,
                "--frames" => parsed.frames = parse_number("--frames", &value("--frames")?, 1)?,
                "--out" => parsed.out = Some(PathBuf::from(value("--out")?)),
                "--width" => parsed.width = parse_number("--width", &value("--width")?, 1)?,
                "--height" => parsed.height = parse_number("--height", &value("--height")?, 1)?,
                "--help" | "-h" => return Err(String::new()),
                _ => parsed.rest.push(arg),
            }
        }
        if parsed.headless && parsed.out.is_none() {
            parsed.out = Some(PathBuf::from("out.png"));
        }
        Ok(parsed)
    }
}

/// Parses a whole number of at least `min`, with a one-line error naming the flag.
pub fn parse_number<T: std::str::FromStr + PartialOrd + std::fmt::Display>(
    flag: &str,
    text: &str,
    min: T,
) -> Result<T, String> {
    match text.parse::<T>() {
        Ok(v) if v >= min => Ok(v),
        _ => Err(format!(
            "{flag} takes a number of at least {min}, got '{text}'"
        )),
    }
}

/// `text` as a number from `min` to `max`, both included, or the message a user reads.
pub fn parse_between<T: std::str::FromStr + PartialOrd + std::fmt::Display>(
    flag: &str,
    text: &str,
    min: T,
    max: T,
) -> Result<T, String> {
    match text.parse::<T>() {
        Ok(v) if v >= min && v <= max => Ok(v),
        _ => Err(format!(
            "{flag} takes a number from {min} to {max}, got '{text}'"
        )),
    }
}

/// Bevy's default plugins without a window or winit; pipelines compile synchronously so the
/// first frames are deterministic. The app is driven by `app.update()` or a zero-delay loop.
pub fn headless_plugins() -> impl PluginGroup {
    DefaultPlugins
        .set(asset_plugin())
        .set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            close_when_requested: false,
            ..default()
        })
        .set(RenderPlugin {
            synchronous_pipeline_compilation: true,
            ..default()
        })
        .disable::<WinitPlugin>()
}

/// Finishes building an app that is driven by hand (`app.update()` in a loop) rather than by
/// `App::run`: waits for plugins that load asynchronously (the renderer), then runs their
/// `finish` and `cleanup`, as `App::run` would.
pub fn finish_plugins(app: &mut App) {
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
}

/// The crate's `assets/` folder, wherever the example binary is started from (Bevy's default is
/// relative to the executable unless `cargo run` sets `CARGO_MANIFEST_DIR`).
fn asset_plugin() -> AssetPlugin {
    AssetPlugin {
        file_path: concat!(env!("CARGO_MANIFEST_DIR"), "/assets").into(),
        ..default()
    }
}

/// The app of an example: a window titled `title`, or headless when `--headless` was given.
pub fn example_app(title: &str, args: &ExampleArgs) -> App {
    let mut app = App::new();
    if args.headless {
        app.add_plugins((
            headless_plugins(),
            ScheduleRunnerPlugin::run_loop(Duration::ZERO),
        ));
        // Time stands still until the AO is shown, then each frame advances it by 1/30 s (see
        // `headless_capture`): a capture shows the same moment on every machine, however slowly
        // it renders and however late its shaders load.
        app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::ZERO))
            .insert_resource(HeadlessRun {
                frames: args.frames,
                out: args.out.clone().unwrap_or_else(|| PathBuf::from("out.png")),
                size: UVec2::new(args.width, args.height),
                target: None,
                done: false,
                first_shown: None,
            })
            .add_systems(Update, headless_capture);
    } else {
        app.add_plugins(DefaultPlugins.set(asset_plugin()).set(WindowPlugin {
            primary_window: Some(Window {
                title: title.into(),
                ..default()
            }),
            ..default()
        }))
        .add_systems(Update, exit_on_escape);
    }
    app
}

/// Spawns an example's camera with `ao` on it: at `eye`, looking at `look_at`, with `Msaa::Off`
/// (the plugin needs it), ACES tonemapping and ambient light of `ambient` brightness (the light
/// AO darkens), rendering into the headless run's image when there is one; and the help line
/// beside it. Returns the camera.
pub fn spawn_ao_camera(
    world: &mut World,
    eye: Vec3,
    look_at: Vec3,
    ao: DynamicAo,
    ambient: f32,
) -> Entity {
    let target = camera_target(world);
    let mut commands = world.commands();
    let mut camera = commands.spawn((
        Camera3d::default(),
        Transform::from_translation(eye).looking_at(look_at, Vec3::Y),
        Msaa::Off,
        Tonemapping::AcesFitted,
        ao,
        AmbientLight {
            brightness: ambient,
            ..default()
        },
    ));
    if let Some(target) = target {
        camera.insert(target);
    }
    let camera = camera.id();
    spawn_help_line(&mut commands);
    world.flush();
    camera
}

/// Where a camera should render: an image in headless mode (`None` means the window).
pub fn camera_target(world: &mut World) -> Option<RenderTarget> {
    let size = world.get_resource::<HeadlessRun>()?.size;
    let image = Image::new_target_texture(size.x, size.y, TextureFormat::Rgba8UnormSrgb, None);
    let handle = world.resource_mut::<Assets<Image>>().add(image);
    world.resource_mut::<HeadlessRun>().target = Some(handle.clone());
    Some(RenderTarget::Image(handle.into()))
}

/// State of a headless run.
#[derive(Resource)]
pub struct HeadlessRun {
    pub frames: u32,
    pub out: PathBuf,
    pub size: UVec2,
    pub target: Option<Handle<Image>>,
    pub done: bool,
    /// The app frame on which a camera's AO was first seen shown (`DynamicAoStatus`).
    pub first_shown: Option<u32>,
}

/// App frames a headless run waits for its cameras' AO to be shown before it gives up.
const SHOWN_TIMEOUT_FRAMES: u32 = 1200;

/// Counts the headless run's frames from the first one on which every active camera's AO is shown
/// and the example's [`RequiredAsset`] has loaded (until then shaders and models load and Bevy's
/// SSAO stands in, for as many frames as the machine's load makes it), and captures the last.
/// There the accumulating cameras start their history over and time starts moving, so every run
/// of the same flags captures the same frames.
#[allow(clippy::too_many_arguments)]
fn headless_capture(
    mut commands: Commands,
    mut run: ResMut<HeadlessRun>,
    frame: Res<FrameCount>,
    mut cameras: Query<(&DynamicAoStatus, &mut DynamicAo, &Camera)>,
    required: Option<Res<RequiredAsset>>,
    assets: Res<AssetServer>,
    mut time: ResMut<TimeUpdateStrategy>,
    mut exit: MessageWriter<AppExit>,
) {
    if run.first_shown.is_none() {
        // Every camera that renders (the showcase turns off the views it does not lay out).
        let mut rendering = cameras.iter().filter(|(.., camera)| camera.is_active);
        let shown = rendering.clone().next().is_some()
            && rendering.all(|(status, ..)| status.shown != AoShown::Pending);
        let loaded = required.is_none_or(|r| assets.is_loaded_with_dependencies(&r.handle));
        if shown && loaded {
            run.first_shown = Some(frame.0);
            for (_, mut ao, _) in &mut cameras {
                if ao.temporal.enabled {
                    ao.temporal.reset = true;
                }
            }
            *time = TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(1.0 / 30.0));
        } else if frame.0 > SHOWN_TIMEOUT_FRAMES {
            eprintln!(
                "error: within {SHOWN_TIMEOUT_FRAMES} frames not every camera's ambient occlusion \
                 was shown (shown: {shown}) or the example's asset did not load (loaded: {loaded})"
            );
            exit.write(AppExit::error());
        }
    }
    let last = run.first_shown.map(|first| first + run.frames - 1);
    if Some(frame.0) == last {
        let Some(target) = run.target.clone() else {
            eprintln!("error: the example spawned no camera for the headless run");
            exit.write(AppExit::error());
            return;
        };
        let out = run.out.clone();
        commands
            .spawn(Screenshot::image(target))
            .observe(save_to_disk(out.clone()))
            .observe(
                move |_: On<bevy::render::view::screenshot::ScreenshotCaptured>,
                      mut run: ResMut<HeadlessRun>| {
                    run.done = true;
                },
            );
    }
    if run.done && run.out.exists() {
        println!("wrote {}", run.out.display());
        exit.write(AppExit::Success);
    } else if last.is_some_and(|last| frame.0 > last + 120) {
        eprintln!("error: the screenshot never arrived");
        exit.write(AppExit::error());
    }
}

fn exit_on_escape(keys: Res<ButtonInput<KeyCode>>, mut exit: MessageWriter<AppExit>) {
    if keys.just_pressed(KeyCode::Escape) {
        exit.write(AppExit::Success);
    }
}

/// The value of an example's own numeric flag `flag` (the next argument), at least `min`;
/// prints `usage` and exits with status 2 when it is missing or not a number.
pub fn numeric_flag<'a>(
    rest: &mut impl Iterator<Item = &'a String>,
    flag: &str,
    min: u32,
    usage: &str,
) -> u32 {
    let value = rest.next().map(String::as_str).unwrap_or("");
    parse_number(flag, value, min).unwrap_or_else(|message| {
        eprintln!("error: {message}\n{usage}");
        std::process::exit(2);
    })
}

/// An asset the example cannot run without, and where it comes from.
#[derive(Resource)]
pub struct RequiredAsset {
    pub handle: UntypedHandle,
    pub path: &'static str,
}

/// Stops the app with a message when the [`RequiredAsset`] fails to load.
pub fn fail_without_required_asset(
    required: Res<RequiredAsset>,
    assets: Res<AssetServer>,
    mut exit: MessageWriter<AppExit>,
) {
    if let Some(bevy::asset::LoadState::Failed(error)) = assets.get_load_state(&required.handle) {
        eprintln!(
            "error: cannot load {} ({error}); run `cargo run --example generate_assets`",
            required.path
        );
        exit.write(AppExit::error());
    }
}

/// Keys the far-field examples share: N switches the image-space term (the default technique)
/// on and off, D the debug view.
pub fn near_field_and_debug_keys(keys: &ButtonInput<KeyCode>, ao: &mut DynamicAo) {
    use bevy_dynamic_ao::AoTechnique;
    if keys.just_pressed(KeyCode::KeyN) {
        ao.technique = match ao.technique {
            AoTechnique::Off => AoTechnique::default(),
            _ => AoTechnique::Off,
        };
    }
    if keys.just_pressed(KeyCode::KeyD) {
        ao.debug_view = !ao.debug_view;
    }
}

/// Keys 1–4 put the preset of that level on `ao` (`AoPreset::ALL`, low to ultra), keeping the
/// debug view as it is.
pub fn preset_keys(keys: &ButtonInput<KeyCode>, ao: &mut DynamicAo) {
    use bevy_dynamic_ao::AoPreset;
    let digits = [
        KeyCode::Digit1,
        KeyCode::Digit2,
        KeyCode::Digit3,
        KeyCode::Digit4,
    ];
    for (key, preset) in digits.into_iter().zip(AoPreset::ALL) {
        if keys.just_pressed(key) {
            *ao = DynamicAo {
                debug_view: ao.debug_view,
                ..DynamicAo::from_preset(preset)
            };
        }
    }
}

/// Marker of the on-screen help line.
#[derive(Component)]
pub struct HelpLine;

/// Spawns the help line in the top-left corner.
pub fn spawn_help_line(commands: &mut Commands) {
    commands.spawn((
        HelpLine,
        Text::new(""),
        TextFont {
            font_size: FontSize::Px(15.0),
            ..default()
        },
        Node {
            position_type: PositionType::Absolute,
            top: px(8.0),
            left: px(8.0),
            ..default()
        },
    ));
}

/// Float texels of a GPU read-back (rows padded to 256 bytes) as a dense row-major vector of
/// `channels` floats per pixel.
pub fn unpad_f32(data: &[u8], width: usize, height: usize, channels: usize) -> Vec<f32> {
    let row = width * channels * 4;
    let stride = row.div_ceil(256) * 256;
    let mut out = Vec::with_capacity(width * height * channels);
    for y in 0..height {
        let start = y * stride;
        let Some(bytes) = data.get(start..start + row) else {
            break;
        };
        out.extend(
            bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        );
    }
    out
}
