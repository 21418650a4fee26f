//! Plain image maps (PGM or PNG): one pixel per cell, dark pixels blocked.
//!
//! The image is converted to 8-bit grey (colour by luma, 16-bit scaled down, alpha ignored);
//! a pixel darker than [`BLOCKED_BELOW`] (grey value 0..255) is blocked, any other is free.
//! The top image row is the north edge; pixel (0, bottom row) is cell (0, 0) at the map-frame
//! origin. The cell size comes from the caller (`--resolution`). The start is the default
//! (1 m, 1 m).

use std::path::Path;

use papillon::geometry::Point2;
use papillon::grid::GridGeometry;

use super::{World, WorldError};

/// Grey values below this (out of 255) are blocked: the darker half of the range.
pub const BLOCKED_BELOW: u8 = 128;

/// Reads an image map file.
pub fn load(path: &Path, resolution_m: f32) -> Result<World, WorldError> {
    let name = path.display().to_string();
    let bytes =
        papillon::files::read_limited(path, papillon::files::MAP_MAX_BYTES).map_err(|e| {
            WorldError::Io {
                path: name.clone(),
                message: e.to_string(),
            }
        })?;
    decode(&bytes, &name, resolution_m)
}

/// Decodes image bytes (format guessed from the content); `name` is used in errors and as the
/// world's name.
pub fn decode(bytes: &[u8], name: &str, resolution_m: f32) -> Result<World, WorldError> {
    let resolution_m = super::check_resolution(resolution_m)?;
    let unreadable = |e: ::image::ImageError| WorldError::Image {
        path: name.to_string(),
        message: format!("not a readable PGM or PNG image: {e}"),
    };
    let reader = || {
        ::image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| unreadable(e.into()))
    };
    // The header's size first: a small file may decode to gigabytes.
    let (w, h) = reader()?.into_dimensions().map_err(unreadable)?;
    let (w, h) = (w as usize, h as usize);
    if w == 0 || h == 0 {
        return Err(WorldError::Image {
            path: name.to_string(),
            message: "image has no pixels".into(),
        });
    }
    let g = GridGeometry::new(w, h, resolution_m, Point2::default())?;
    super::check_size(name, &g, "the image's width and height")?;
    let grey = reader()?.decode().map_err(unreadable)?.to_luma8();
    if (grey.width() as usize, grey.height() as usize) != (w, h) {
        return Err(WorldError::Image {
            path: name.to_string(),
            message: "the decoded image's size differs from its header's".into(),
        });
    }
    let mut blocked = vec![false; w * h];
    for (x, y, p) in grey.enumerate_pixels() {
        let row = h - 1 - y as usize;
        blocked[row * w + x as usize] = p.0[0] < BLOCKED_BELOW;
    }
    World::from_blocked(name, g, blocked)
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::grid::Cell;

    #[test]
    fn dark_pixels_are_blocked_and_top_is_north() {
        // Plain PGM, 3 wide x 2 high: top row 0 255 127, bottom row 128 255 255.
        let pgm = b"P2\n3 2\n255\n0 255 127\n128 255 255\n";
        let w = decode(pgm, "m.pgm", 0.05).unwrap();
        assert_eq!((w.geometry().width, w.geometry().height), (3, 2));
        assert!(w.is_blocked(Cell::new(0, 1)));
        assert!(w.is_blocked(Cell::new(2, 1)));
        assert!(!w.is_blocked(Cell::new(0, 0)));
        assert_eq!(w.blocked_count(), 2);
        assert_eq!(w.geometry().resolution_m, 0.05);
    }

    #[test]
    fn png_round_trip() {
        let mut img = ::image::GrayImage::from_pixel(4, 3, ::image::Luma([255]));
        img.put_pixel(3, 2, ::image::Luma([10]));
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            ::image::ImageFormat::Png,
        )
        .unwrap();
        let w = decode(&bytes, "m.png", 0.1).unwrap();
        assert!(w.is_blocked(Cell::new(3, 0)));
        assert_eq!(w.blocked_count(), 1);
    }

    #[test]
    fn garbage_is_reported_with_the_file_name() {
        let e = decode(b"hello", "bad.png", 0.1).unwrap_err();
        assert!(e.to_string().starts_with("bad.png: not a readable"), "{e}");
    }
}
