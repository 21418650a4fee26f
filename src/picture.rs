//! Pictures of exploration maps, like the thesis's figures (Bendahmane 2023): the robot's map
//! with free cells white, unknown grey and occupied black, each robot's trajectory drawn in
//! its own colour and the targets it chose marked with a small ring in that colour.
//!
//! One cell is `scale` x `scale` pixels; the top image row is the map's north edge. The cells
//! are filled pixel by pixel; lines, rings and text are drawn by plotters (its bitmap backend
//! on the image's own buffer). Segments are first clipped to the image (Liang & Barsky, below)
//! so that far-off points cost nothing. [`render_picture`] adds what a person needs to read
//! the map (`papillon-sim mission --png`, `--frames`, and the onboard `map.png` of `papillon
//! run`): each robot's start (a square) and last position (a filled disc), and below the map a
//! scale bar and a legend.
//!
//! Host only (feature `picture`: plotters' bitmap backend and ab_glyph with the embedded DejaVu
//! Sans Mono font, `assets/fonts`); the no_std core never imports it.

use std::path::Path;
use std::sync::Once;

use image::{Rgb, RgbImage};
use plotters::prelude::*;

use crate::geometry::Point2;
use crate::grid::{CellClass, GridGeometry, OccupancyGrid};

/// The embedded font (Bitstream Vera licence, see `assets/fonts/LICENSE-DejaVu.txt`).
pub static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSansMono.ttf");
/// The family name pictures and plots ask for.
pub const FAMILY: &str = "sans-serif";

/// Registers [`FONT`] with plotters as [`FAMILY`] (once per process).
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is valid (checked by the tests); a failure only loses the text.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

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

fn rgb(c: Rgb<u8>) -> RGBColor {
    RGBColor(c.0[0], c.0[1], c.0[2])
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
    let to_px = pixel_of(geometry, scale);
    let (iw, ih) = (img.width(), img.height());
    let radius = (2 * scale as i32).max(3);
    let area = BitMapBackend::with_buffer(&mut img, (iw, ih)).into_drawing_area();
    for (k, track) in tracks.iter().enumerate() {
        let colour = rgb(robot_colour(k));
        for pair in track.trajectory.windows(2) {
            if let Some((a, b)) = clip(to_px(pair[0]), to_px(pair[1]), iw as i64, ih as i64) {
                let _ = area.draw(&PathElement::new(
                    vec![small(a), small(b)],
                    colour.stroke_width(1),
                ));
            }
        }
        if let [only] = track.trajectory[..] {
            let _ = area.draw_pixel(small(to_px(only)), &colour);
        }
        for &t in &track.targets {
            if let Some(centre) = near(to_px(t), iw, ih, radius) {
                // Two pixels thick: radius and radius - 1.
                for r in [radius, radius - 1] {
                    let _ = area.draw(&Circle::new(centre, r, colour.stroke_width(1)));
                }
            }
        }
    }
    let _ = area.present();
    drop(area);
    img
}

/// Map frame \[m\] to image pixels (x right, y down).
fn pixel_of(geometry: &GridGeometry, scale: u32) -> impl Fn(Point2) -> (i64, i64) + '_ {
    let h = geometry.height as u32;
    move |p: Point2| {
        let x = (p.x - geometry.origin.x) / geometry.resolution_m * scale as f32;
        let y = (p.y - geometry.origin.y) / geometry.resolution_m * scale as f32;
        (x.floor() as i64, (h * scale) as i64 - 1 - y.floor() as i64)
    }
}

/// A clipped point as plotters' coordinates (clipped points fit in an `i32`).
fn small((x, y): (i64, i64)) -> (i32, i32) {
    (
        x.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
        y.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
    )
}

/// `p` when a mark of `radius` around it can touch the `w` x `h` image.
fn near((x, y): (i64, i64), w: u32, h: u32, radius: i32) -> Option<(i32, i32)> {
    let r = radius as i64;
    (x >= -r && y >= -r && x < w as i64 + r && y < h as i64 + r).then(|| small((x, y)))
}

/// Pixels per cell for a picture of a map of geometry `g`: up to 4, so that the map is about
/// 600 pixels across at most (at least 1).
pub fn picture_scale(g: &GridGeometry) -> u32 {
    (600 / g.width.max(g.height).max(1) as u32).clamp(1, 4)
}

/// Height of the band under the map with the scale bar and the legend \[px\].
pub const LEGEND_HEIGHT: u32 = 46;
/// Narrowest picture \[px\]: the legend's width.
pub const MIN_PICTURE_WIDTH: u32 = 600;

/// A scale bar's length for a map drawn at `px_per_m` pixels per metre: the round length (1,
/// 2 or 5 times a power of ten, 1 cm to 5 km) nearest to 120 pixels \[m\].
pub fn scale_bar_m(px_per_m: f32) -> f32 {
    let mut best = 1.0f32;
    for exponent in -2..=3 {
        for m in [1.0f32, 2.0, 5.0] {
            let len = m * 10f32.powi(exponent);
            if ((len * px_per_m) - 120.0).abs() < ((best * px_per_m) - 120.0).abs() {
                best = len;
            }
        }
    }
    best
}

/// [`render_classes`] with what a person needs to read it: each robot's start (an outlined
/// square) and last position (a filled disc with a white rim) in its colour, and below the map
/// a band with a scale bar and a legend (free, unknown, occupied, trajectory, start, robot,
/// targets). The picture is at least [`MIN_PICTURE_WIDTH`] wide (the map on the left, white
/// beside it).
pub fn render_picture(
    geometry: &GridGeometry,
    classes: impl Fn(usize) -> CellClass,
    tracks: &[Track],
    scale: u32,
) -> RgbImage {
    let scale = scale.max(1);
    let map = render_classes(geometry, classes, tracks, scale);
    let width = map.width().max(MIN_PICTURE_WIDTH);
    let height = map.height() + LEGEND_HEIGHT;
    let mut img = RgbImage::from_pixel(width, height, FREE);
    image::imageops::replace(&mut img, &map, 0, 0);
    register_font();
    let to_px = pixel_of(geometry, scale);
    let (mw, mh) = (map.width(), map.height());
    let area = BitMapBackend::with_buffer(&mut img, (width, height)).into_drawing_area();
    let mark = (3 * scale as i32).max(5);
    for (k, track) in tracks.iter().enumerate() {
        let colour = rgb(robot_colour(k));
        if let Some(&start) = track.trajectory.first()
            && let Some((x, y)) = near(to_px(start), mw, mh, mark)
        {
            let _ = area.draw(&Rectangle::new(
                [(x - mark, y - mark), (x + mark, y + mark)],
                colour.stroke_width(2),
            ));
        }
        if let Some(&now) = track.trajectory.last()
            && let Some(centre) = near(to_px(now), mw, mh, mark)
        {
            let _ = area.draw(&Circle::new(centre, mark + 1, WHITE.filled()));
            let _ = area.draw(&Circle::new(centre, mark, colour.filled()));
        }
    }
    // The band: a rule, the scale bar, the legend.
    let top = mh as i32;
    let _ = area.draw(&PathElement::new(
        vec![(0, top), (width as i32, top)],
        BLACK.stroke_width(1),
    ));
    let font = (FAMILY, 13).into_font().color(&BLACK);
    let px_per_m = scale as f32 / geometry.resolution_m;
    let bar_m = scale_bar_m(px_per_m);
    let bar_px = (bar_m * px_per_m).round() as i32;
    let (x0, y_bar) = (10, top + 14);
    let _ = area.draw(&Rectangle::new(
        [(x0, y_bar - 2), (x0 + bar_px, y_bar + 2)],
        BLACK.filled(),
    ));
    for x in [x0, x0 + bar_px] {
        let _ = area.draw(&PathElement::new(
            vec![(x, y_bar - 6), (x, y_bar + 6)],
            BLACK.stroke_width(2),
        ));
    }
    let label = if bar_m >= 1.0 {
        format!("{bar_m} m")
    } else {
        format!("{} cm", (bar_m * 100.0).round())
    };
    let _ = area.draw(&Text::new(label, (x0, y_bar + 10), font.clone()));
    // Legend: swatches, then marks in the first robot's colour.
    let mut x = (x0 + bar_px + 30).max(120);
    let y = top + 8;
    let swatch = |x: i32, colour: RGBColor, name: &str| {
        let _ = area.draw(&Rectangle::new([(x, y), (x + 12, y + 12)], colour.filled()));
        let _ = area.draw(&Rectangle::new(
            [(x, y), (x + 12, y + 12)],
            BLACK.stroke_width(1),
        ));
        let _ = area.draw(&Text::new(name.to_string(), (x + 16, y), font.clone()));
        x + 16 + 8 * name.len() as i32 + 12
    };
    x = swatch(x, rgb(FREE), "free");
    x = swatch(x, rgb(UNKNOWN), "unknown");
    let _ = swatch(x, rgb(OCCUPIED), "occupied");
    let (mut x, y) = ((x0 + bar_px + 30).max(120), top + 27);
    let c = rgb(robot_colour(0));
    let robots = tracks.len();
    let names: [(&str, u8); 4] = [
        (
            if robots > 1 {
                "trajectories"
            } else {
                "trajectory"
            },
            0,
        ),
        ("start", 1),
        ("robot", 2),
        ("targets", 3),
    ];
    for (name, kind) in names {
        let (cx, cy) = (x + 6, y + 6);
        let _ = match kind {
            0 => area.draw(&PathElement::new(
                vec![(x, cy), (x + 12, cy)],
                c.stroke_width(2),
            )),
            1 => area.draw(&Rectangle::new(
                [(x, y), (x + 12, y + 12)],
                c.stroke_width(2),
            )),
            2 => area.draw(&Circle::new((cx, cy), 6, c.filled())),
            _ => area.draw(&Circle::new((cx, cy), 5, c.stroke_width(2))),
        };
        let _ = area.draw(&Text::new(name.to_string(), (x + 16, y), font.clone()));
        x += 16 + 8 * name.len() as i32 + 12;
    }
    if robots > 1 {
        let _ = area.draw(&Text::new(
            format!("({robots} robots)"),
            (x, y),
            font.clone(),
        ));
    }
    let _ = area.present();
    drop(area);
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

/// Renders a core occupancy grid with tracks and what a person needs to read it
/// ([`render_picture`]).
pub fn render_grid_picture<const N: usize>(
    grid: &OccupancyGrid<N>,
    tracks: &[Track],
    scale: u32,
) -> RgbImage {
    render_picture(grid.geometry(), |i| grid.class(i), tracks, scale)
}

/// Writes an image as PNG; the error names the file.
pub fn save_png(img: &RgbImage, path: &Path) -> Result<(), String> {
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| format!("{}: cannot write PNG: {e}", path.display()))
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
    #[test]
    fn a_picture_has_marks_a_scale_bar_and_a_legend() {
        let g = geometry(); // 20 x 10 cells of 0.5 m
        let tracks = vec![Track {
            trajectory: vec![Point2::new(0.25, 4.25), Point2::new(5.25, 4.25)],
            targets: vec![Point2::new(7.0, 6.0)],
        }];
        let img = render_picture(&g, |_| CellClass::Free, &tracks, 4);
        assert_eq!(
            (img.width(), img.height()),
            (MIN_PICTURE_WIDTH, 40 + LEGEND_HEIGHT)
        );
        let red = robot_colour(0);
        // The robot's last position: a filled disc in its colour.
        let (rx, ry) = (
            (5.25 + 1.0) / 0.5 * 4.0,
            40.0 - 1.0 - (4.25 - 2.0) / 0.5 * 4.0,
        );
        assert_eq!(*img.get_pixel(rx as u32, ry as u32), red);
        assert_eq!(*img.get_pixel(rx as u32 + 2, ry as u32 + 2), red);
        // The start: an outlined square (hollow) around the first position.
        let (sx, sy) = ((0.25 + 1.0) / 0.5 * 4.0, ry);
        assert_eq!(*img.get_pixel(sx as u32, sy as u32 - 12), red);
        assert_ne!(*img.get_pixel(sx as u32 - 6, sy as u32 - 6), red);
        // The scale bar: 8 px per metre, so 10 m (80 px, nearest to 120 of 5, 10, 20 m).
        assert_eq!(scale_bar_m(8.0), 10.0);
        assert_eq!(scale_bar_m(200.0), 0.5);
        let bar_y = 40 + 14;
        assert_eq!(*img.get_pixel(10 + 40, bar_y), OCCUPIED);
        assert_eq!(*img.get_pixel(10 + 80 + 5, bar_y), FREE);
        // The legend's grey swatch and some text in the band.
        let band: Vec<&Rgb<u8>> = (40..img.height())
            .flat_map(|y| (0..img.width()).map(move |x| (x, y)))
            .map(|(x, y)| img.get_pixel(x, y))
            .collect();
        assert!(band.iter().any(|&&p| p == UNKNOWN));
        assert!(band.iter().any(|&&p| p == red));
        let dark = band.iter().filter(|p| p.0[0] < 100 && p.0[1] < 100).count();
        assert!(dark > 300, "text and the bar: {dark} dark pixels");
    }
}
