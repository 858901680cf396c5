//! The three views of the showcase and how they share the screen. Each camera renders into an
//! image of its own and a UI row shows the images side by side: Bevy's SSAO does not follow a
//! camera viewport that starts away from the target's corner (it darkened the whole middle
//! third), so viewports would not compare like with like.

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::window::PrimaryWindow;
use bevy_dynamic_ao::prelude::*;

use crate::common::HeadlessRun;

/// Ambient light on every camera: most of the light, so AO shows.
const AMBIENT: f32 = 700.0;
const EYE: Vec3 = Vec3::new(4.6, 2.5, 4.6);
const LOOK_AT: Vec3 = Vec3::new(-1.2, 0.8, -2.6);

/// What a camera shows.
#[derive(Component, Clone, Copy, PartialEq, Eq, Debug)]
pub enum Shown {
    Ours,
    BevySsao,
    NoAo,
}

impl Shown {
    pub const ALL: [Self; 3] = [Self::Ours, Self::BevySsao, Self::NoAo];
}

/// Thirds (ours | Bevy's SSAO | none), or one of them alone over the whole target.
#[derive(Resource, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    Thirds,
    Alone(Shown),
}

impl Layout {
    /// Whether `shown` is on screen.
    pub fn shows(self, shown: Shown) -> bool {
        self == Layout::Thirds || self == Layout::Alone(shown)
    }

    /// The next layout, for the C key.
    pub fn next(self) -> Self {
        match self {
            Layout::Thirds => Layout::Alone(Shown::Ours),
            Layout::Alone(Shown::Ours) => Layout::Alone(Shown::BevySsao),
            Layout::Alone(Shown::BevySsao) => Layout::Alone(Shown::NoAo),
            Layout::Alone(Shown::NoAo) => Layout::Thirds,
        }
    }
}

/// The image a view's camera renders into, shown by the UI.
#[derive(Component)]
pub struct ViewImage(pub Shown);

/// Spawns the three cameras (ours with `ao`), the UI camera on the screen (or the headless
/// run's image) and the row of images.
pub fn spawn(world: &mut World, ao: DynamicAo) {
    for (order, shown) in Shown::ALL.into_iter().enumerate() {
        let mut camera = world.spawn((
            Camera3d::default(),
            Camera {
                order: order as isize,
                ..default()
            },
            Transform::from_translation(EYE).looking_at(LOOK_AT, Vec3::Y),
            Msaa::Off,
            Tonemapping::AcesFitted,
            AmbientLight {
                brightness: AMBIENT,
                ..default()
            },
            shown,
        ));
        match shown {
            Shown::Ours => {
                camera.insert(ao.clone());
            }
            Shown::BevySsao => {
                camera.insert(ScreenSpaceAmbientOcclusion::default());
            }
            Shown::NoAo => {}
        }
    }
    let target = crate::common::camera_target(world);
    let mut ui_camera = world.spawn((
        Camera2d,
        Camera {
            order: 3,
            ..default()
        },
        IsDefaultUiCamera,
    ));
    if let Some(target) = target {
        ui_camera.insert(target);
    }
    world
        .spawn(Node {
            width: percent(100.0),
            height: percent(100.0),
            flex_direction: FlexDirection::Row,
            ..default()
        })
        .with_children(|row| {
            for shown in Shown::ALL {
                row.spawn((
                    ViewImage(shown),
                    ImageNode::default(),
                    Node {
                        height: percent(100.0),
                        ..default()
                    },
                ));
            }
        });
}

/// Gives each view an image of its share of the screen (again whenever the window or the layout
/// changes), points its camera at it and shows it; views off screen stop rendering.
pub fn fit(
    layout: Res<Layout>,
    headless: Option<Res<HeadlessRun>>,
    window: Query<&Window, With<PrimaryWindow>>,
    mut images: ResMut<Assets<Image>>,
    mut cameras: Query<(Entity, &mut Camera, &Shown, Option<&RenderTarget>)>,
    mut nodes: Query<(&ViewImage, &mut ImageNode, &mut Node)>,
    mut commands: Commands,
) {
    let screen = match (&headless, window.single()) {
        (Some(run), _) => run.size,
        (None, Ok(window)) => window.physical_size(),
        (None, Err(_)) => return,
    };
    let size = match *layout {
        Layout::Thirds => UVec2::new(screen.x / 3, screen.y),
        Layout::Alone(_) => screen,
    };
    if size.x == 0 || size.y == 0 {
        return;
    }
    for (entity, mut camera, shown, target) in &mut cameras {
        let active = layout.shows(*shown);
        if camera.is_active != active {
            camera.is_active = active;
        }
        let current = match target {
            Some(RenderTarget::Image(image)) => images.get(&image.handle).map(|i| i.size()),
            _ => None,
        };
        if !active || current == Some(size) {
            continue;
        }
        let image = images.add(Image::new_target_texture(
            size.x,
            size.y,
            TextureFormat::Rgba8UnormSrgb,
            None,
        ));
        commands
            .entity(entity)
            .insert(RenderTarget::Image(image.clone().into()));
        for (view, mut node_image, _) in &mut nodes {
            if view.0 == *shown {
                node_image.image = image.clone();
            }
        }
    }
    for (view, _, mut node) in &mut nodes {
        let (display, width) = match *layout {
            Layout::Thirds => (Display::Flex, percent(100.0 / 3.0)),
            Layout::Alone(alone) if alone == view.0 => (Display::Flex, percent(100.0)),
            Layout::Alone(_) => (Display::None, percent(0.0)),
        };
        if node.display != display || node.width != width {
            node.display = display;
            node.width = width;
        }
    }
}
