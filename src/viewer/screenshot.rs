//! Off-screen screenshots: the camera renders into an image; after the asked number of frames
//! the image is captured and written as PNG (staged, so a failed run leaves no file); a replay
//! is captured at several clock positions, as numbered PNGs or one animated GIF.

use std::path::Path;

use bevy::camera::{ImageRenderTarget, RenderTarget};
use bevy::image::IntoDynamicImageError;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};

use crate::error::IsceneError;
use crate::io::atomic::write_file_atomically;

/// Frames to wait for a capture once asked for, before giving up.
const CAPTURE_PATIENCE_FRAMES: u32 = 120;

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

/// Aims `app`'s cameras at a new `size` image, finishes the app and renders its first frame
/// (the one that compiles the pipelines, left out of the timings).
fn start_offscreen(app: &mut App, size: (u32, u32)) {
    render_offscreen(app, size);
    app.finish();
    app.cleanup();
    app.update();
}

/// Renders `frames` frames of `app` into a `size` image and writes the last one to `path`.
pub fn take(
    app: &mut App,
    path: &Path,
    frames: u32,
    size: (u32, u32),
) -> Result<RenderTiming, IsceneError> {
    start_offscreen(app, size);
    let started = std::time::Instant::now();
    for _ in 1..frames {
        app.update();
    }
    let timing = RenderTiming {
        frames: frames - 1,
        seconds: started.elapsed().as_secs_f64(),
    };
    let picture = capture(app, path)?;
    save_png(&picture, path)?;
    Ok(timing)
}

/// `shots` pictures of a replay, its clock set evenly from the first of its `frames` to the
/// last: `path` ending in .gif gets one animated GIF, any other `path` numbered PNGs beside it
/// (`replay.png` gives `replay_00.png`, `replay_01.png`, ...). Nothing is written unless every
/// picture was captured.
pub fn take_replay(
    app: &mut App,
    path: &Path,
    shots: u32,
    frames: u32,
    size: (u32, u32),
) -> Result<RenderTiming, IsceneError> {
    start_offscreen(app, size);
    let started = std::time::Instant::now();
    let shots = shots.max(1);
    let mut pictures = Vec::with_capacity(shots as usize);
    for k in 0..shots {
        let at = if shots == 1 {
            frames.saturating_sub(1)
        } else {
            k * frames.saturating_sub(1) / (shots - 1)
        };
        app.world_mut()
            .resource_mut::<crate::viewer::ReplayClock>()
            .seek(at as f32);
        // One frame applies the clock to the meshes, the next renders them settled.
        app.update();
        app.update();
        pictures.push(capture(app, path)?);
    }
    let timing = RenderTiming {
        frames: 3 * shots,
        seconds: started.elapsed().as_secs_f64(),
    };
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gif"))
    {
        save_gif(&pictures, path)?;
    } else {
        let stem = path
            .file_stem()
            .map_or("replay".into(), |s| s.to_string_lossy().into_owned());
        let extension = path
            .extension()
            .map_or("png".into(), |e| e.to_string_lossy().into_owned());
        for (k, picture) in pictures.iter().enumerate() {
            save_png(
                picture,
                &path.with_file_name(format!("{stem}_{k:02}.{extension}")),
            )?;
        }
    }
    Ok(timing)
}

/// Renders one more frame of `app` and returns it, as RGB.
fn capture(app: &mut App, path: &Path) -> Result<image::RgbImage, IsceneError> {
    app.world_mut().remove_resource::<Captured>();
    let target = app.world().resource::<OffscreenTarget>().0.clone();
    app.world_mut().spawn(Screenshot::image(target)).observe(
        |captured: On<ScreenshotCaptured>, mut commands: Commands| {
            let picture = captured
                .image
                .clone()
                .try_into_dynamic()
                .map(|d| d.to_rgb8());
            commands.insert_resource(Captured(picture));
        },
    );
    for _ in 0..CAPTURE_PATIENCE_FRAMES {
        app.update();
        if let Some(captured) = app.world_mut().remove_resource::<Captured>() {
            return captured.0.map_err(|e| {
                IsceneError::Internal(format!("the captured image cannot be converted: {e}"))
            });
        }
    }
    Err(IsceneError::Internal(format!(
        "the screenshot for {} was never captured (no GPU or software Vulkan driver? see README)",
        path.display()
    )))
}

/// A captured picture.
#[derive(Resource)]
struct Captured(Result<image::RgbImage, IntoDynamicImageError>);

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

fn save_png(picture: &image::RgbImage, path: &Path) -> Result<(), IsceneError> {
    let mut png = Vec::new();
    picture
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| IsceneError::Internal(format!("encoding {}: {e}", path.display())))?;
    write_file_atomically(path, &png)
}

/// Replay frames shown this long each in the GIF, milliseconds.
const GIF_FRAME_MS: u32 = 400;

fn save_gif(pictures: &[image::RgbImage], path: &Path) -> Result<(), IsceneError> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let encode_error =
        |e: image::ImageError| IsceneError::Internal(format!("encoding {}: {e}", path.display()));
    let mut gif = Vec::new();
    {
        let mut encoder = GifEncoder::new_with_speed(&mut gif, 10);
        encoder.set_repeat(Repeat::Infinite).map_err(encode_error)?;
        for picture in pictures {
            let rgba = image::DynamicImage::ImageRgb8(picture.clone()).to_rgba8();
            let delay = image::Delay::from_numer_denom_ms(GIF_FRAME_MS, 1);
            encoder
                .encode_frame(image::Frame::from_parts(rgba, 0, 0, delay))
                .map_err(encode_error)?;
        }
    }
    write_file_atomically(path, &gif)
}
