//! Plain image maps (PGM or PNG) given without a YAML: one pixel per cell.
//!
//! The image is read by the map files' reader ([`papillon::mapfile::decode_map_image`]) with
//! map_server's usual thresholds ([`papillon::mapfile::Thresholds::default`]): a pixel of grey
//! value `v` (0..255) has occupancy `p = (255 - v) / 255`, occupied above 0.65 (`v` below
//! about 89), free below 0.196 (`v` above about 205), unknown between. As for a ROS map with
//! its YAML ([`super::rosmap`]), Occupied **and Unknown** cells are blocked, so map_saver's
//! grey 205 (unknown) is a wall, not floor. The top image row is the north edge; pixel (0,
//! bottom row) is cell (0, 0) at the map-frame origin. The cell size comes from the caller
//! (`--resolution`). The start is the default (1 m, 1 m).

use std::path::Path;

use papillon::geometry::Point2;
use papillon::grid::CellClass;
use papillon::mapfile;

use super::{World, WorldError};

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

/// Decodes image bytes (PGM or PNG, told by their content); `name` is used in errors and as
/// the world's name.
pub fn decode(bytes: &[u8], name: &str, resolution_m: f32) -> Result<World, WorldError> {
    let resolution_m = super::check_resolution(resolution_m)?;
    let map = mapfile::decode_map_image(Path::new(name), bytes, resolution_m, Point2::default())
        .map_err(|e| WorldError::Image {
            path: name.to_string(),
            message: e
                .to_string()
                .strip_prefix(&format!("{name}: "))
                .map(str::to_string)
                .unwrap_or_else(|| e.to_string()),
        })?;
    super::check_size(name, &map.geometry, "the image's width and height")?;
    let blocked = map.cells.iter().map(|&c| c != CellClass::Free).collect();
    World::from_blocked(name, map.geometry, blocked)
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::grid::Cell;

    #[test]
    fn dark_and_unknown_pixels_are_blocked_and_top_is_north() {
        // Plain PGM, 3 wide x 2 high: top row 0 255 205, bottom row 254 220 127. map_saver's
        // 205 (unknown) and the grey 127 (between the thresholds) are blocked, 220 is free.
        let pgm = b"P2\n3 2\n255\n0 255 205\n254 220 127\n";
        let w = decode(pgm, "m.pgm", 0.05).unwrap();
        assert_eq!((w.geometry().width, w.geometry().height), (3, 2));
        assert!(w.is_blocked(Cell::new(0, 1)));
        assert!(!w.is_blocked(Cell::new(1, 1)));
        assert!(w.is_blocked(Cell::new(2, 1)), "unknown 205 is blocked");
        assert!(!w.is_blocked(Cell::new(0, 0)));
        assert!(!w.is_blocked(Cell::new(1, 0)));
        assert!(w.is_blocked(Cell::new(2, 0)));
        assert_eq!(w.blocked_count(), 3);
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
        assert!(e.to_string().starts_with("bad.png: not a PGM"), "{e}");
    }
}
