//! DeepLabV3 (MobileNet, PASCAL-VOC) as exported to ONNX from TensorFlow Lite: the NHWC input
//! tensor, and the per-pixel labels of its logits mapped back onto the camera image.

use image::RgbImage;
use image::imageops::FilterType;

/// The network's square input side.
pub const INPUT_SIDE: u32 = 257;

/// The input tensor (1 x 257 x 257 x 3, RGB scaled to [-1, 1]): the whole image stretched, as the
/// network was trained.
pub fn input(image: &RgbImage) -> Vec<f32> {
    let resized = image::imageops::resize(image, INPUT_SIDE, INPUT_SIDE, FilterType::Triangle);
    resized
        .as_raw()
        .iter()
        .map(|&v| f32::from(v) / 127.5 - 1.0)
        .collect()
}

/// Per network pixel, the label with the largest logit (`logits` is side x side x classes).
pub fn argmax(logits: &[f32], classes: usize) -> Vec<u8> {
    logits
        .chunks_exact(classes)
        .map(|c| {
            c.iter()
                .enumerate()
                .fold(
                    (0, f32::MIN),
                    |best, (i, &v)| if v > best.1 { (i, v) } else { best },
                )
                .0 as u8
        })
        .collect()
}

/// The label of every camera pixel (row-major, `width` x `height`) from the network's square
/// label map, by nearest neighbour.
pub fn to_image(labels: &[u8], side: u32, width: u32, height: u32) -> Vec<u8> {
    let (w, h) = (width as usize, height as usize);
    let s = side as usize;
    let column: Vec<usize> = (0..w)
        .map(|u| (((u as f32 + 0.5) * s as f32 / w as f32) as usize).min(s - 1))
        .collect();
    let mut out = Vec::with_capacity(w * h);
    for v in 0..h {
        let row = (((v as f32 + 0.5) * s as f32 / h as f32) as usize).min(s - 1);
        out.extend(column.iter().map(|&c| labels[row * s + c]));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn argmax_takes_the_largest_logit_per_pixel() {
        let logits = [0.1, 2.0, -1.0, 5.0, 0.0, 4.9];
        assert_eq!(argmax(&logits, 3), vec![1, 0]);
    }

    #[test]
    fn labels_stretch_back_over_the_image() {
        // A 2 x 2 label map over a 4 x 2 image: each label covers a 2 x 1 block.
        let image = to_image(&[1, 2, 3, 4], 2, 4, 2);
        assert_eq!(image, vec![1, 1, 2, 2, 3, 3, 4, 4]);
    }

    #[test]
    fn the_input_is_scaled_to_minus_one_one() {
        let image = RgbImage::from_pixel(20, 10, image::Rgb([0, 255, 0]));
        let t = input(&image);
        assert_eq!(t.len(), (INPUT_SIDE * INPUT_SIDE * 3) as usize);
        assert_eq!(&t[..3], &[-1.0, 1.0, -1.0]);
    }
}
