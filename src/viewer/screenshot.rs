//! Off-screen screenshots: the camera renders into an image; after the asked number of frames
//! the image is captured and written as PNG (staged, so a failed run leaves no file).

use std::path::{Path, PathBuf};

use bevy::camera::{ImageRenderTarget, RenderTarget};
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};

use crate::error::IsceneError;
use crate::io::atomic::write_file_atomically;

/// Frames to wait for the capture once asked for, before giving up.
const CAPTURE_PATIENCE_FRAMES: u32 = 120;

/// Where the screenshot goes and after how many frames.
#[derive(Resource, Clone, Debug)]
pub struct ScreenshotRequest {
    pub path: PathBuf,
    pub after_frames: u32,
    frame: u32,
}

/// The screenshot's outcome, once captured.
#[derive(Resource, Clone, Debug)]
pub struct ScreenshotDone(pub Result<(), String>);

/// The image every camera renders into when there is no window.
#[derive(Resource, Clone, Debug)]
pub struct OffscreenTarget(pub Handle<Image>);

/// Makes every camera of `app` render into a new `size` image; then finish the app and update
/// it by hand.
pub fn render_offscreen(app: &mut App, size: (u32, u32)) -> Handle<Image> {
    let target = app
        .world_mut()
        .resource_mut::<Assets<Image>>()
        .add(Image::new_target_texture(
            size.0,
            size.1,
            TextureFormat::Rgba8UnormSrgb,
            None,
        ));
    app.insert_resource(OffscreenTarget(target.clone()))
        .add_systems(Update, aim_cameras_at_target);
    target
}

/// How fast the frames after the first rendered (the first compiles the pipelines).
#[derive(Clone, Copy, Debug)]
pub struct RenderTiming {
    pub frames: u32,
    pub seconds: f64,
}

impl RenderTiming {
    pub fn frames_per_s(&self) -> f64 {
        self.frames as f64 / self.seconds.max(1e-9)
    }
}

/// Renders `frames` frames of `app` into a `size` image and writes the last one to `path`.
pub fn take(
    app: &mut App,
    path: &Path,
    frames: u32,
    size: (u32, u32),
) -> Result<RenderTiming, IsceneError> {
    render_offscreen(app, size);
    app.insert_resource(ScreenshotRequest {
        path: path.to_path_buf(),
        after_frames: frames,
        frame: 0,
    });
    app.add_systems(Update, request_capture);
    app.finish();
    app.cleanup();
    let mut since_first: Option<(std::time::Instant, u32)> = None;
    for frame in 0..frames + CAPTURE_PATIENCE_FRAMES {
        app.update();
        if let Some(done) = app.world().get_resource::<ScreenshotDone>() {
            done.0.clone().map_err(IsceneError::Internal)?;
            let (started, first) = since_first.unwrap_or((std::time::Instant::now(), frame));
            return Ok(RenderTiming {
                frames: frame - first,
                seconds: started.elapsed().as_secs_f64(),
            });
        }
        since_first.get_or_insert((std::time::Instant::now(), frame));
    }
    Err(IsceneError::Internal(format!(
        "the screenshot for {} was never captured (no GPU or software Vulkan driver? see README)",
        path.display()
    )))
}

/// Every camera renders into the off-screen image instead of a window.
fn aim_cameras_at_target(
    target: Res<OffscreenTarget>,
    mut commands: Commands,
    cameras: Query<Entity, (With<Camera>, Without<ImageTargeted>)>,
) {
    for camera in &cameras {
        commands.entity(camera).insert((
            RenderTarget::Image(ImageRenderTarget::from(target.0.clone())),
            ImageTargeted,
        ));
    }
}

/// Marks a camera already aimed at the screenshot's image.
#[derive(Component)]
struct ImageTargeted;

/// Counts frames and asks for the capture on the last one.
fn request_capture(
    mut request: ResMut<ScreenshotRequest>,
    target: Res<OffscreenTarget>,
    mut commands: Commands,
) {
    request.frame += 1;
    if request.frame != request.after_frames {
        return;
    }
    let path = request.path.clone();
    commands.spawn(Screenshot::image(target.0.clone())).observe(
        move |captured: On<ScreenshotCaptured>, mut commands: Commands| {
            let outcome = save_png(&captured.image, &path);
            commands.insert_resource(ScreenshotDone(outcome));
        },
    );
}

fn save_png(image: &Image, path: &Path) -> Result<(), String> {
    let rgb = image
        .clone()
        .try_into_dynamic()
        .map_err(|e| format!("the captured image cannot be converted: {e}"))?
        .to_rgb8();
    let mut png = Vec::new();
    rgb.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| format!("encoding {}: {e}", path.display()))?;
    write_file_atomically(path, &png).map_err(|e| format!("{e}"))
}
