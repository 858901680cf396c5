//! 16-bit grayscale PNG files of linear visibility: 65535 = open, 0 = fully occluded.

use std::fs::File;
use std::io::{BufReader, BufWriter};
use std::path::Path;

/// Errors of reading or writing an AO image.
#[derive(Debug)]
pub enum Png16Error {
    /// The file could not be read or written.
    Io(std::io::Error),
    /// The PNG encoder or decoder failed.
    Encoding(String),
    /// The buffer does not hold width × height values, or the file is not 16-bit grayscale.
    Shape(String),
}

impl std::fmt::Display for Png16Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Png16Error::Io(e) => write!(f, "{e}"),
            Png16Error::Encoding(e) => write!(f, "PNG error: {e}"),
            Png16Error::Shape(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for Png16Error {}

impl From<std::io::Error> for Png16Error {
    fn from(e: std::io::Error) -> Self {
        Png16Error::Io(e)
    }
}

/// Writes `visibility` (row-major, values clamped to [0, 1], NaN as 1) as a 16-bit grayscale PNG.
pub fn write_visibility_png(
    path: &Path,
    width: u32,
    height: u32,
    visibility: &[f32],
) -> Result<(), Png16Error> {
    if visibility.len() != (width as usize) * (height as usize) || width == 0 || height == 0 {
        return Err(Png16Error::Shape(format!(
            "{} values for a {width}×{height} image",
            visibility.len()
        )));
    }
    let mut encoder = png::Encoder::new(BufWriter::new(File::create(path)?), width, height);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Sixteen);
    let mut writer = encoder
        .write_header()
        .map_err(|e| Png16Error::Encoding(e.to_string()))?;
    let data: Vec<u8> = visibility
        .iter()
        .flat_map(|v| {
            let v = if v.is_nan() { 1.0 } else { v.clamp(0.0, 1.0) };
            ((v * 65535.0).round() as u16).to_be_bytes()
        })
        .collect();
    writer
        .write_image_data(&data)
        .map_err(|e| Png16Error::Encoding(e.to_string()))
}

/// Reads a 16-bit grayscale PNG back as visibility in [0, 1]: (width, height, values).
pub fn read_visibility_png(path: &Path) -> Result<(u32, u32, Vec<f32>), Png16Error> {
    let decoder = png::Decoder::new(BufReader::new(File::open(path)?));
    let mut reader = decoder
        .read_info()
        .map_err(|e| Png16Error::Encoding(e.to_string()))?;
    let info = reader.info();
    let (width, height) = (info.width, info.height);
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Sixteen {
        return Err(Png16Error::Shape(format!(
            "expected 16-bit grayscale, found {:?} {:?}",
            info.color_type, info.bit_depth
        )));
    }
    let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
    reader
        .next_frame(&mut buf)
        .map_err(|e| Png16Error::Encoding(e.to_string()))?;
    let values = buf
        .chunks_exact(2)
        .take((width * height) as usize)
        .map(|b| u16::from_be_bytes([b[0], b[1]]) as f32 / 65535.0)
        .collect();
    Ok((width, height, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_bad_shape() {
        let dir = std::env::temp_dir().join(format!("dynamic_ao_png16_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("ao.png");
        let values = [0.0, 0.25, 1.0, f32::NAN, 2.0, -1.0];
        write_visibility_png(&path, 3, 2, &values).unwrap();
        let (w, h, back) = read_visibility_png(&path).unwrap();
        assert_eq!((w, h), (3, 2));
        let expected = [0.0, 0.25, 1.0, 1.0, 1.0, 0.0];
        for (a, b) in back.iter().zip(expected) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
        assert!(write_visibility_png(&path, 4, 2, &values).is_err());
        std::fs::write(&path, b"not a png").unwrap();
        assert!(read_visibility_png(&path).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
