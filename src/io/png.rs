//! PNG pictures: 8-bit RGB images encoded by the `png` crate (PNG specification, ISO/IEC
//! 15948:2004) with zlib compression, written whole or not at all.

use std::path::Path;

/// The PNG file of an RGB image (`rgb`: width × height × 3 bytes, rows top to bottom).
pub fn encode_rgb(width: u32, height: u32, rgb: &[u8]) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer.write_image_data(rgb).map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)?;
    Ok(out)
}

/// Writes an RGB image as a PNG file (atomically).
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> std::io::Result<()> {
    super::atomic::write_atomic(path, &encode_rgb(width, height, rgb)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2×1 image round-trips through the `png` decoder with its size and pixels.
    #[test]
    fn rgb_image_round_trips() {
        let rgb = [255u8, 0, 0, 0, 128, 255];
        let bytes = encode_rgb(2, 1, &rgb).unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height, info.color_type), (2, 1, png::ColorType::Rgb));
        assert_eq!(&buf[..6], &rgb);
    }
}
