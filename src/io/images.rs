//! Reading colour, depth and label images with the checks DESIGN.md asks for: encoding, size,
//! and a plausible depth scale.

use std::path::Path;

use image::DynamicImage;

use crate::error::InputError;
use crate::geometry::Pinhole;

/// Median depths outside this range (metres) mean the depth scale or encoding is wrong.
const PLAUSIBLE_MEDIAN_DEPTH: std::ops::RangeInclusive<f32> = 0.1..=15.0;

fn open(path: &Path) -> Result<DynamicImage, InputError> {
    if !path.is_file() {
        return Err(InputError::missing(path, "image file not found"));
    }
    image::ImageReader::open(path)
        .map_err(|e| InputError::io(path, &e))?
        .with_guessed_format()
        .map_err(|e| InputError::io(path, &e))?
        .decode()
        .map_err(|e| InputError::invalid(path, format!("cannot decode image: {e}")))
}

fn check_size(path: &Path, width: u32, height: u32, camera: &Pinhole) -> Result<(), InputError> {
    if (width, height) != (camera.width, camera.height) {
        return Err(InputError::invalid(
            path,
            format!(
                "image is {width}x{height}, the camera is {}x{}",
                camera.width, camera.height
            ),
        ));
    }
    Ok(())
}

/// Reads a 16-bit single-channel depth image as metres (0 = no measurement). 65535 is read as
/// no measurement too, as 7-Scenes writes it.
pub fn read_depth(path: &Path, camera: &Pinhole, depth_scale: f32) -> Result<Vec<f32>, InputError> {
    let img = open(path)?;
    let DynamicImage::ImageLuma16(gray) = img else {
        return Err(InputError::invalid(
            path,
            format!(
                "depth must be a 16-bit single-channel image, found {:?}; convert it, do not pass a colour or 8-bit image",
                img.color()
            ),
        ));
    };
    check_size(path, gray.width(), gray.height(), camera)?;
    let depth: Vec<f32> = gray
        .as_raw()
        .iter()
        .map(|&v| {
            if v == 0 || v == u16::MAX {
                0.0
            } else {
                f32::from(v) / depth_scale
            }
        })
        .collect();
    // The median of every 16th valid pixel tells a wrong scale or encoding as well as the median
    // of all, at a sixteenth of the cost.
    let mut sample: Vec<f32> = depth
        .iter()
        .copied()
        .filter(|&d| d > 0.0)
        .step_by(16)
        .collect();
    if sample.len() * 16 > depth.len() / 20 {
        let mid = sample.len() / 2;
        let (_, median, _) = sample.select_nth_unstable_by(mid, f32::total_cmp);
        if !PLAUSIBLE_MEDIAN_DEPTH.contains(median) {
            return Err(InputError::invalid(
                path,
                format!(
                    "median depth {median:.2} m with depth scale {depth_scale} per metre is implausible for a room: wrong depth scale (TUM uses 5000, most others 1000) or not a depth encoding (SUN RGB-D shifts its bits)"
                ),
            ));
        }
    }
    Ok(depth)
}

/// Reads an 8-bit colour image as row-major RGB.
pub fn read_color(path: &Path, camera: &Pinhole) -> Result<Vec<u8>, InputError> {
    let img = open(path)?;
    if matches!(
        img,
        DynamicImage::ImageLuma16(_)
            | DynamicImage::ImageLumaA16(_)
            | DynamicImage::ImageRgb16(_)
            | DynamicImage::ImageRgba16(_)
    ) {
        return Err(InputError::invalid(
            path,
            format!("colour must be 8 bits per channel, found {:?}", img.color()),
        ));
    }
    let rgb = img.into_rgb8();
    check_size(path, rgb.width(), rgb.height(), camera)?;
    Ok(rgb.into_raw())
}

/// Reads a 16-bit instance label image.
pub fn read_labels(path: &Path, camera: &Pinhole) -> Result<Vec<u16>, InputError> {
    let img = open(path)?;
    let DynamicImage::ImageLuma16(gray) = img else {
        return Err(InputError::invalid(
            path,
            format!(
                "labels must be a 16-bit single-channel image, found {:?}",
                img.color()
            ),
        ));
    };
    check_size(path, gray.width(), gray.height(), camera)?;
    Ok(gray.into_raw())
}

/// Checks an image's size from its header, without decoding it.
pub fn check_header(path: &Path, camera: &Pinhole) -> Result<(), InputError> {
    if !path.is_file() {
        return Err(InputError::missing(path, "image file not found"));
    }
    let (width, height) = dimensions(path)?;
    check_size(path, width, height, camera)
}

/// Width and height from an image file's header, without decoding it.
pub fn dimensions(path: &Path) -> Result<(u32, u32), InputError> {
    image::image_dimensions(path)
        .map_err(|e| InputError::invalid(path, format!("cannot read image header: {e}")))
}
