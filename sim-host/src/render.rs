//! Pictures of exploration maps, like the thesis's figures (Bendahmane 2023): the robot's map
//! with free cells white, unknown grey and occupied black, each robot's trajectory drawn in
//! its own colour and the targets it chose marked with a small ring in that colour.
//!
//! One cell is `scale` x `scale` pixels; the top image row is the map's north edge. Lines are
//! drawn with Bresenham's algorithm (Bresenham, "Algorithm for computer control of a digital
//! plotter", IBM Systems Journal 4(1), 1965); anything outside the image is clipped.

use std::path::Path;

use image::{Rgb, RgbImage};
use papillon::geometry::Point2;
use papillon::grid::{CellClass, GridGeometry, OccupancyGrid};

/// Colour of a free cell.
pub const FREE: Rgb<u8> = Rgb([255, 255, 255]);
/// Colour of an unknown cell.
pub const UNKNOWN: Rgb<u8> = Rgb([160, 160, 160]);
/// Colour of an occupied cell.
pub const OCCUPIED: Rgb<u8> = Rgb([0, 0, 0]);

/// Robot colours, in robot order (repeating after the last).
pub const ROBOT_COLOURS: [Rgb<u8>; 8] = [
    Rgb([220, 30, 30]),
    Rgb([30, 90, 230]),
    Rgb([20, 160, 60]),
    Rgb([240, 140, 0]),
    Rgb([150, 40, 200]),
    Rgb([0, 170, 190]),
    Rgb([200, 0, 130]),
    Rgb([120, 90, 30]),
];

/// The colour of robot `index`.
pub fn robot_colour(index: usize) -> Rgb<u8> {
    ROBOT_COLOURS[index % ROBOT_COLOURS.len()]
}

/// What to draw for one robot, in the map frame \[m\].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Track {
    /// Positions visited, oldest first.
    pub trajectory: Vec<Point2>,
    /// Targets chosen.
    pub targets: Vec<Point2>,
}

/// Renders a classification (one class per cell, flat-index order, row 0 south) with tracks.
/// Cells beyond `classes`' length are drawn unknown.
pub fn render_classes(
    geometry: &GridGeometry,
    classes: impl Fn(usize) -> CellClass,
    tracks: &[Track],
    scale: u32,
) -> RgbImage {
    let scale = scale.max(1);
    let (w, h) = (geometry.width as u32, geometry.height as u32);
    let mut img = RgbImage::new(w * scale, h * scale);
    for row in 0..h {
        for col in 0..w {
            let i = row as usize * geometry.width + col as usize;
            let colour = match classes(i) {
                CellClass::Free => FREE,
                CellClass::Occupied => OCCUPIED,
                CellClass::Unknown => UNKNOWN,
            };
            let y0 = (h - 1 - row) * scale;
            for dy in 0..scale {
                for dx in 0..scale {
                    img.put_pixel(col * scale + dx, y0 + dy, colour);
                }
            }
        }
    }
    let to_px = |p: Point2| -> (i64, i64) {
        let x = (p.x - geometry.origin.x) / geometry.resolution_m * scale as f32;
        let y = (p.y - geometry.origin.y) / geometry.resolution_m * scale as f32;
        (x.floor() as i64, (h * scale) as i64 - 1 - y.floor() as i64)
    };
    for (k, track) in tracks.iter().enumerate() {
        let colour = robot_colour(k);
        for pair in track.trajectory.windows(2) {
            line(&mut img, to_px(pair[0]), to_px(pair[1]), colour);
        }
        if let [only] = track.trajectory[..] {
            put(&mut img, to_px(only), colour);
        }
        let radius = (2 * scale as i64).max(3);
        for &t in &track.targets {
            ring(&mut img, to_px(t), radius, colour);
        }
    }
    img
}

/// Renders a core occupancy grid with tracks.
pub fn render_grid<const N: usize>(
    grid: &OccupancyGrid<N>,
    tracks: &[Track],
    scale: u32,
) -> RgbImage {
    render_classes(grid.geometry(), |i| grid.class(i), tracks, scale)
}

/// Writes an image as PNG; the error names the file.
pub fn save_png(img: &RgbImage, path: &Path) -> Result<(), String> {
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| format!("{}: cannot write PNG: {e}", path.display()))
}

fn put(img: &mut RgbImage, (x, y): (i64, i64), colour: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, colour);
    }
}

fn line(img: &mut RgbImage, a: (i64, i64), b: (i64, i64), colour: Rgb<u8>) {
    let Some(((x0, y0), (x1, y1))) = clip(a, b, img.width() as i64, img.height() as i64) else {
        return;
    };
    let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
    let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
    let (mut x, mut y, mut err) = (x0, y0, dx + dy);
    loop {
        put(img, (x, y), colour);
        if x == x1 && y == y1 {
            break;
        }
        let e2 = 2 * err;
        if e2 >= dy {
            err += dy;
            x += sx;
        }
        if e2 <= dx {
            err += dx;
            y += sy;
        }
    }
}

/// Clips segment `a`-`b` to the rectangle `[-1, w] x [-1, h]` (Liang & Barsky, "A new concept
/// and method for line clipping", ACM TOG 3(1), 1984), so that far-off points cost nothing.
fn clip(a: (i64, i64), b: (i64, i64), w: i64, h: i64) -> Option<((i64, i64), (i64, i64))> {
    let (x0, y0) = (a.0 as f64, a.1 as f64);
    let (dx, dy) = (b.0 as f64 - x0, b.1 as f64 - y0);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, x0 + 1.0),
        (dx, w as f64 - x0),
        (-dy, y0 + 1.0),
        (dy, h as f64 - y0),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f64| ((x0 + t * dx).round() as i64, (y0 + t * dy).round() as i64);
    Some((at(t0), at(t1)))
}

fn ring(img: &mut RgbImage, (cx, cy): (i64, i64), radius: i64, colour: Rgb<u8>) {
    // Midpoint circle, two pixels thick.
    for r in [radius, radius - 1] {
        let (mut x, mut y, mut d) = (r, 0i64, 1 - r);
        while x >= y {
            for (px, py) in [
                (x, y),
                (y, x),
                (-y, x),
                (-x, y),
                (-x, -y),
                (-y, -x),
                (y, -x),
                (x, -y),
            ] {
                put(img, (cx + px, cy + py), colour);
            }
            y += 1;
            if d < 0 {
                d += 2 * y + 1;
            } else {
                x -= 1;
                d += 2 * (y - x) + 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry() -> GridGeometry {
        GridGeometry::new(20, 10, 0.5, Point2::new(-1.0, 2.0)).unwrap()
    }

    #[test]
    fn cells_have_their_colours_and_north_is_up() {
        let g = geometry();
        // Cell (0, 0) occupied, cell (19, 9) free, everything else unknown.
        let classes = |i: usize| match i {
            0 => CellClass::Occupied,
            199 => CellClass::Free,
            _ => CellClass::Unknown,
        };
        let img = render_classes(&g, classes, &[], 3);
        assert_eq!((img.width(), img.height()), (60, 30));
        // South-west cell: bottom-left 3x3 block.
        assert_eq!(*img.get_pixel(0, 29), OCCUPIED);
        assert_eq!(*img.get_pixel(2, 27), OCCUPIED);
        assert_eq!(*img.get_pixel(3, 27), UNKNOWN);
        // North-east cell: top-right block.
        assert_eq!(*img.get_pixel(59, 0), FREE);
        assert_eq!(*img.get_pixel(57, 2), FREE);
        assert_eq!(*img.get_pixel(30, 15), UNKNOWN);
    }

    #[test]
    fn trajectories_and_targets_take_the_robot_colour() {
        let g = geometry();
        let tracks = vec![
            Track {
                // Along the row of cells at y = 2.25 m (row 0), x from -0.75 to 3.75 m.
                trajectory: vec![Point2::new(-0.75, 2.25), Point2::new(3.75, 2.25)],
                targets: vec![Point2::new(6.0, 5.0)],
            },
            Track {
                trajectory: vec![Point2::new(0.25, 6.75), Point2::new(0.25, 4.25)],
                targets: vec![],
            },
        ];
        let img = render_classes(&g, |_| CellClass::Free, &tracks, 1);
        assert_eq!(*img.get_pixel(0, 9), robot_colour(0));
        assert_eq!(*img.get_pixel(9, 9), robot_colour(0));
        assert_eq!(*img.get_pixel(10, 9), FREE);
        // Robot 1: column 2, rows 4..9 from the south => image rows 0..5.
        assert_eq!(*img.get_pixel(2, 0), robot_colour(1));
        assert_eq!(*img.get_pixel(2, 5), robot_colour(1));
        assert_eq!(*img.get_pixel(2, 6), FREE);
        // Target at cell (14, 6): a ring of radius 3 around image pixel (14, 3).
        assert_eq!(*img.get_pixel(17, 3), robot_colour(0));
        assert_eq!(*img.get_pixel(14, 0), robot_colour(0));
        assert_eq!(*img.get_pixel(14, 3), FREE, "the ring is hollow");
        assert_ne!(robot_colour(0), robot_colour(1));
    }

    #[test]
    fn far_off_points_are_clipped() {
        let g = geometry();
        let tracks = [Track {
            trajectory: vec![Point2::new(-1e6, -1e6), Point2::new(1e6, 1e6)],
            targets: vec![Point2::new(1e9, 0.0)],
        }];
        let img = render_classes(&g, |_| CellClass::Unknown, &tracks, 2);
        assert_eq!((img.width(), img.height()), (40, 20));
    }

    #[test]
    fn png_files_round_trip() {
        let g = geometry();
        let img = render_classes(&g, |_| CellClass::Occupied, &[], 1);
        let p = std::env::temp_dir().join(format!("papillon-render-{}.png", std::process::id()));
        save_png(&img, &p).unwrap();
        let back = image::open(&p).unwrap().to_rgb8();
        assert_eq!(back, img);
        std::fs::remove_file(&p).unwrap();
        let e = save_png(&img, Path::new("/no/such/dir/x.png")).unwrap_err();
        assert!(e.starts_with("/no/such/dir/x.png: cannot write PNG"), "{e}");
    }
}
