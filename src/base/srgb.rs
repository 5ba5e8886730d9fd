//! 8-bit sRGB to linear light: camera pixels and texture files are sRGB, link colours linear.

use std::sync::OnceLock;

/// An 8-bit sRGB channel as linear light in 0..1 (the sRGB transfer curve), from a table: the
/// colour of every surface sample goes through it.
pub fn srgb_to_linear(c: u8) -> f32 {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f32 / 255.0;
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        })
    })[usize::from(c)]
}
