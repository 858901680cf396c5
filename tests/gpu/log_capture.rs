//! Warnings and errors the plugin logs, kept for the tests to read: a layer on Bevy's log
//! subscriber (the first test app installs it, and every later app logs through it).

use std::sync::Mutex;

use bevy::app::App;
use bevy::log::tracing::field::{Field, Visit};
use bevy::log::tracing::{Event, Level, Subscriber};
use bevy::log::tracing_subscriber::{Layer, layer::Context};
use bevy::log::{BoxedLayer, LogPlugin};

static CAPTURED: Mutex<Vec<String>> = Mutex::new(Vec::new());

struct Capture;

struct Message(String);

impl Visit for Message {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            self.0 = format!("{value:?}");
        }
    }
}

impl<S: Subscriber> Layer<S> for Capture {
    fn on_event(&self, event: &Event<'_>, _: Context<'_, S>) {
        if *event.metadata().level() <= Level::WARN {
            let mut message = Message(String::new());
            event.record(&mut message);
            CAPTURED
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .push(message.0);
        }
    }
}

fn capture_layer(_: &mut App) -> Option<BoxedLayer> {
    Some(Box::new(Capture))
}

/// Bevy's log plugin with the capturing layer.
pub fn log_plugin() -> LogPlugin {
    LogPlugin {
        custom_layer: capture_layer,
        ..Default::default()
    }
}

/// Every warning or error logged so far that contains all of `parts`.
pub fn logged(parts: &[&str]) -> Vec<String> {
    CAPTURED
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .iter()
        .filter(|m| parts.iter().all(|p| m.contains(p)))
        .cloned()
        .collect()
}

/// Asserts that exactly one warning or error contains all of `parts` (said once, not every frame).
pub fn assert_logged_once(parts: &[&str]) {
    let found = logged(parts);
    assert_eq!(
        found.len(),
        1,
        "expected one warning containing {parts:?}, found {found:?}"
    );
}
