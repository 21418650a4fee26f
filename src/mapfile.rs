//! Map files in the ROS `map_server` format: an image (PGM or PNG) plus a YAML description.
//! The one reader and writer of map files: `papillon-sim mission`/`serve --map x.yaml` and
//! plain images (`--map x.pgm`), `papillon-sim score --robot-map`, and the onboard map that
//! `papillon run --resume` reads back (`onboard::persist`) all go through here.
//!
//! Format (ROS wiki, `map_server`; nav2 `map_io`): the YAML names the `image`, its
//! `resolution` \[m/pixel\], the `origin` `[x, y, yaw]` of the lower-left pixel \[m, rad\],
//! `negate`, `occupied_thresh`, `free_thresh` and `mode`. A pixel value `v` of maximum
//! `maxval` reads as occupancy `p = (maxval - v) / maxval` (or `v / maxval` when `negate`);
//! Occupied if `p > occupied_thresh`, Free if `p < free_thresh`, Unknown otherwise. `mode:
//! trinary` (the default) and `mode: scale` read the same three classes (the grid has no
//! shades), except that under `scale` a transparent pixel (PNG alpha below full) is Unknown;
//! `mode: raw` and a rotated origin (yaw not 0) are refused with an error saying so. Written
//! maps use 254 free, 0 occupied, 205 unknown (`mode: trinary`), as `map_saver` writes. Image
//! row 0 is the north edge, grid row 0 the south edge, so rows are flipped both ways.
//!
//! Images: binary (P5) and ASCII (P2) PGM, header comments allowed (GIMP writes one), 8 or 16
//! bits; PNG in grey, grey+alpha, RGB or RGBA (colour read as its luma). P5 is written. The
//! YAML is read in the forms map_saver, hand-editing and other tools give it: one
//! `key: value` per line (block style) or the whole document as one `{key: value, ...}`
//! (flow style, over any number of lines); the origin as `[x, y, yaw]` (also over several
//! lines) or as a block list of `- x` lines; `#` comments; quoted image names; `---`. Writes
//! are atomic (temporary file, fsync, rename), image first, so a crash leaves either the old
//! map or the new one. Errors name the file (and the YAML line) and what is wrong.

use std::fmt;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::geometry::Point2;
use crate::grid::{CellClass, GridError, GridGeometry, OccupancyGrid};

/// Pixel value written for a free cell.
pub const PIXEL_FREE: u8 = 254;
/// Pixel value written for an occupied cell.
pub const PIXEL_OCCUPIED: u8 = 0;
/// Pixel value written for an unknown cell.
pub const PIXEL_UNKNOWN: u8 = 205;

/// Finest cell size a map file may give \[m\].
pub const MIN_RESOLUTION_M: f32 = 0.001;
/// Coarsest cell size a map file may give \[m\]: a cell wider than 1 m is coarser than the
/// robot itself (0.5 m).
pub const MAX_RESOLUTION_M: f32 = 1.0;
/// Farthest a map's origin may lie from the map frame's \[m\] (beyond, a 32-bit float no longer
/// resolves centimetres).
pub const MAX_ORIGIN_M: f32 = 100_000.0;

/// A map read from (or to be written to) a file: geometry and one class per cell, in flat-index
/// order (row 0 south).
#[derive(Clone, Debug, PartialEq)]
pub struct MapImage {
    /// Size, resolution and origin.
    pub geometry: GridGeometry,
    /// Class of every cell, `geometry.cell_count()` of them.
    pub cells: Vec<CellClass>,
}

/// What went wrong reading or writing a map file; every variant names the file.
#[derive(Debug)]
#[non_exhaustive]
pub enum MapFileError {
    /// The file could not be read, written or renamed.
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A required YAML key is absent.
    MissingKey {
        /// The YAML file.
        path: PathBuf,
        /// The key.
        key: &'static str,
    },
    /// A YAML value could not be understood.
    BadValue {
        /// The YAML file.
        path: PathBuf,
        /// Line number (1-based).
        line: usize,
        /// The key.
        key: String,
        /// The text found.
        found: String,
        /// What was expected.
        expected: &'static str,
    },
    /// A YAML line is not `key: value`.
    BadLine {
        /// The YAML file.
        path: PathBuf,
        /// Line number (1-based).
        line: usize,
        /// The text found.
        found: String,
    },
    /// The image does not start with `P5` or `P2`.
    BadMagic {
        /// The image file.
        path: PathBuf,
        /// The first bytes found.
        found: String,
    },
    /// The PGM header is malformed.
    BadHeader {
        /// The image file.
        path: PathBuf,
        /// Byte offset of the problem.
        offset: usize,
        /// What was expected there.
        expected: &'static str,
    },
    /// The pixel data ends early.
    Truncated {
        /// The image file.
        path: PathBuf,
        /// Pixels the header announces.
        expected_pixels: usize,
        /// Pixels present.
        found_pixels: usize,
    },
    /// A P2 pixel is not a number or exceeds maxval.
    BadPixel {
        /// The image file.
        path: PathBuf,
        /// Byte offset of the pixel.
        offset: usize,
    },
    /// A PNG that cannot be decoded, or is too large.
    BadImage {
        /// The image file.
        path: PathBuf,
        /// Why.
        what: String,
    },
    /// Something valid in ROS but not supported here (rotated origin, raw mode).
    Unsupported {
        /// The YAML file.
        path: PathBuf,
        /// What.
        what: String,
    },
    /// The size, resolution or origin do not make a grid.
    BadGeometry {
        /// The YAML file.
        path: PathBuf,
        /// Why.
        source: GridError,
    },
}

impl fmt::Display for MapFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use MapFileError::*;
        match self {
            Io { path, source } => write!(f, "{}: {source}", path.display()),
            MissingKey { path, key } => {
                write!(f, "{}: missing key `{key}`", path.display())
            }
            BadValue {
                path,
                line,
                key,
                found,
                expected,
            } => write!(
                f,
                "{}:{line}: `{key}` is `{found}`, expected {expected}",
                path.display()
            ),
            BadLine { path, line, found } => write!(
                f,
                "{}:{line}: expected `key: value`, found `{found}`",
                path.display()
            ),
            BadMagic { path, found } => write!(
                f,
                "{}: not a PGM image: starts with `{found}`, expected `P5` or `P2` (or a PNG)",
                path.display()
            ),
            BadImage { path, what } => write!(f, "{}: not a readable PNG: {what}", path.display()),
            BadHeader {
                path,
                offset,
                expected,
            } => write!(
                f,
                "{}: byte {offset}: bad PGM header, expected {expected}",
                path.display()
            ),
            Truncated {
                path,
                expected_pixels,
                found_pixels,
            } => write!(
                f,
                "{}: truncated image: {found_pixels} of {expected_pixels} pixels",
                path.display()
            ),
            BadPixel { path, offset } => write!(
                f,
                "{}: byte {offset}: expected a pixel value not above maxval",
                path.display()
            ),
            Unsupported { path, what } => write!(f, "{}: unsupported: {what}", path.display()),
            BadGeometry { path, source } => write!(f, "{}: {source}", path.display()),
        }
    }
}

impl std::error::Error for MapFileError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            MapFileError::Io { source, .. } => Some(source),
            MapFileError::BadGeometry { source, .. } => Some(source),
            _ => None,
        }
    }
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> MapFileError + '_ {
    move |source| MapFileError::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl MapImage {
    /// The classification of a grid.
    pub fn from_grid<const N: usize>(grid: &OccupancyGrid<N>) -> Self {
        Self {
            geometry: *grid.geometry(),
            cells: (0..grid.cell_count()).map(|i| grid.class(i)).collect(),
        }
    }

    /// Resets `grid` to this map's geometry and sets every known cell at the bounds'
    /// certainty (Free at the lower bound, Occupied at the upper).
    pub fn load_into<const N: usize>(&self, grid: &mut OccupancyGrid<N>) -> Result<(), GridError> {
        grid.reset(self.geometry)?;
        for (i, &c) in self.cells.iter().enumerate() {
            if c != CellClass::Unknown {
                grid.set_class(i, c, &mut ());
            }
        }
        Ok(())
    }
}

/// Writes `grid`'s classification as `yaml_path` plus a PGM beside it (same stem, `.pgm`).
pub fn write_map<const N: usize>(
    grid: &OccupancyGrid<N>,
    yaml_path: &Path,
) -> Result<(), MapFileError> {
    write_map_image(&MapImage::from_grid(grid), yaml_path)
}

/// Writes a map image as `yaml_path` plus a PGM beside it (same stem, `.pgm`), each atomically.
pub fn write_map_image(map: &MapImage, yaml_path: &Path) -> Result<(), MapFileError> {
    let g = map.geometry;
    if map.cells.len() != g.cell_count() {
        return Err(MapFileError::BadGeometry {
            path: yaml_path.to_path_buf(),
            source: GridError::CapacityExceeded {
                needed: g.cell_count(),
                capacity: map.cells.len(),
            },
        });
    }
    let pgm_path = yaml_path.with_extension("pgm");
    write_atomically(&pgm_path, &encode_pgm(map))?;
    let image_name = pgm_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    write_atomically(yaml_path, yaml_text(&g, &image_name).as_bytes())
}

/// A map's binary PGM (P5, maxval 255): 254 free, 0 occupied, 205 unknown, first row north.
/// `map.cells` must hold `geometry.cell_count()` classes (missing ones are written unknown).
pub fn encode_pgm(map: &MapImage) -> Vec<u8> {
    let g = map.geometry;
    let mut pgm = format!("P5\n{} {}\n255\n", g.width, g.height).into_bytes();
    pgm.reserve(g.cell_count());
    for image_row in 0..g.height {
        let row = g.height - 1 - image_row;
        pgm.extend(
            (0..g.width).map(|col| match map.cells.get(row * g.width + col) {
                Some(CellClass::Free) => PIXEL_FREE,
                Some(CellClass::Occupied) => PIXEL_OCCUPIED,
                _ => PIXEL_UNKNOWN,
            }),
        );
    }
    pgm
}

/// The YAML beside a map written by [`encode_pgm`] as `image_name` (what map_saver writes).
pub fn yaml_text(g: &GridGeometry, image_name: &str) -> String {
    format!(
        "image: {image_name}\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n",
        g.resolution_m, g.origin.x, g.origin.y
    )
}

/// Temporary file beside the target, fsync, rename over the target, fsync the directory.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), MapFileError> {
    let mut tmp_name = path.file_name().unwrap_or_default().to_os_string();
    tmp_name.push(".tmp");
    let tmp = path.with_file_name(tmp_name);
    let mut file = crate::files::create_temporary(&tmp).map_err(io_err(&tmp))?;
    file.write_all(bytes).map_err(io_err(&tmp))?;
    file.sync_all().map_err(io_err(&tmp))?;
    drop(file);
    fs::rename(&tmp, path).map_err(io_err(path))?;
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        // Persist the rename; not every platform can open a directory, so this is best effort.
        if let Ok(d) = fs::File::open(dir) {
            let _ = d.sync_all();
        }
    }
    Ok(())
}

/// Reads a ROS map (YAML and the image it names, relative to the YAML's folder).
pub fn read_map(yaml_path: &Path) -> Result<MapImage, MapFileError> {
    let text = crate::files::read_limited_to_string(yaml_path, crate::files::TEXT_MAX_BYTES)
        .map_err(io_err(yaml_path))?;
    parse_map(yaml_path, &text, |image_path| {
        crate::files::read_limited(image_path, crate::files::MAP_MAX_BYTES)
            .map_err(io_err(image_path))
    })
}

/// Parses a ROS map from its YAML `text` (read from `yaml_path`, which errors name and image
/// paths are relative to); `load_image` reads the image the YAML names.
pub fn parse_map(
    yaml_path: &Path,
    text: &str,
    load_image: impl FnOnce(&Path) -> Result<Vec<u8>, MapFileError>,
) -> Result<MapImage, MapFileError> {
    let path = || yaml_path.to_path_buf();
    let mut image: Option<String> = None;
    let mut resolution: Option<f32> = None;
    let mut origin: Option<[f32; 3]> = None;
    let mut negate = false;
    let mut occupied_thresh: Option<f32> = None;
    let mut free_thresh: Option<f32> = None;
    let mut scale = false;
    // The known keys seen, to refuse one given twice (the second would win silently).
    let mut seen: Vec<String> = Vec::new();
    for (line, key, value) in yaml_entries(yaml_path, text)? {
        let (key, value) = (key.as_str(), value.as_str());
        let bad = |expected| MapFileError::BadValue {
            path: path(),
            line,
            key: key.to_string(),
            found: value.to_string(),
            expected,
        };
        let number = |v: &str| v.trim().parse::<f32>().ok().filter(|x| x.is_finite());
        let known = [
            "image",
            "resolution",
            "origin",
            "negate",
            "occupied_thresh",
            "free_thresh",
            "mode",
        ];
        if known.contains(&key) {
            if seen.iter().any(|k| k == key) {
                return Err(MapFileError::BadValue {
                    path: path(),
                    line,
                    key: key.to_string(),
                    found: value.to_string(),
                    expected: "no second value (the key is already given above)",
                });
            }
            seen.push(key.to_string());
        }
        let fraction = |v: &str| number(v).filter(|x| (0.0..=1.0).contains(x));
        match key {
            "image" => {
                let v = value.trim_matches(|c| c == '"' || c == '\'');
                if v.is_empty() {
                    return Err(bad("a file name"));
                }
                image = Some(v.to_string());
            }
            "resolution" => {
                resolution = Some(
                    number(value)
                        .filter(|r| (MIN_RESOLUTION_M..=MAX_RESOLUTION_M).contains(r))
                        .ok_or_else(|| bad("a number from 0.001 to 1 (the cell size in metres)"))?,
                )
            }
            "occupied_thresh" => {
                occupied_thresh = Some(fraction(value).ok_or_else(|| bad("a number from 0 to 1"))?)
            }
            "free_thresh" => {
                free_thresh = Some(fraction(value).ok_or_else(|| bad("a number from 0 to 1"))?)
            }
            "negate" => {
                negate = match value {
                    "0" | "false" | "False" => false,
                    "1" | "true" | "True" => true,
                    _ => return Err(bad("0 or 1")),
                }
            }
            "origin" => {
                let inner = value
                    .strip_prefix('[')
                    .and_then(|v| v.strip_suffix(']'))
                    .ok_or_else(|| bad("[x, y, yaw]"))?;
                let mut parts = inner.split(',');
                let mut o = [0.0; 3];
                for slot in &mut o {
                    *slot = parts
                        .next()
                        .and_then(number)
                        .filter(|v| v.abs() <= MAX_ORIGIN_M)
                        .ok_or_else(|| bad("[x, y, yaw], each within ±100 km"))?;
                }
                if parts.next().is_some() {
                    return Err(bad("[x, y, yaw]"));
                }
                origin = Some(o);
            }
            "mode" => match value.trim_matches(|c| c == '"' || c == '\'') {
                "trinary" => scale = false,
                "scale" => scale = true,
                other => {
                    return Err(MapFileError::Unsupported {
                        path: path(),
                        what: format!("mode `{other}` (line {line})"),
                    });
                }
            },
            _ => {}
        }
    }
    let image = image.ok_or(MapFileError::MissingKey {
        path: path(),
        key: "image",
    })?;
    let resolution = resolution.ok_or(MapFileError::MissingKey {
        path: path(),
        key: "resolution",
    })?;
    let origin = origin.ok_or(MapFileError::MissingKey {
        path: path(),
        key: "origin",
    })?;
    let occupied_thresh = occupied_thresh.ok_or(MapFileError::MissingKey {
        path: path(),
        key: "occupied_thresh",
    })?;
    let free_thresh = free_thresh.ok_or(MapFileError::MissingKey {
        path: path(),
        key: "free_thresh",
    })?;
    if free_thresh > occupied_thresh {
        return Err(MapFileError::Unsupported {
            path: path(),
            what: format!(
                "free_thresh {free_thresh} above occupied_thresh {occupied_thresh} (a cell would be both)"
            ),
        });
    }
    if origin[2].abs() > 1e-6 {
        return Err(MapFileError::Unsupported {
            path: path(),
            what: format!("rotated map origin (yaw {} rad)", origin[2]),
        });
    }
    let image_path = match yaml_path.parent() {
        Some(dir) if !Path::new(&image).is_absolute() => dir.join(&image),
        _ => PathBuf::from(&image),
    };
    let bytes = load_image(&image_path)?;
    let raster = decode_image(&image_path, &bytes)?;
    let geometry = GridGeometry::new(
        raster.width,
        raster.height,
        resolution,
        Point2::new(origin[0], origin[1]),
    )
    .map_err(|source| MapFileError::BadGeometry {
        path: path(),
        source,
    })?;
    let thresholds = Thresholds {
        negate,
        occupied: occupied_thresh,
        free: free_thresh,
        scale,
    };
    Ok(MapImage {
        geometry,
        cells: classify(&raster, thresholds),
    })
}

/// How pixels become classes (the YAML's `negate`, `occupied_thresh`, `free_thresh`, `mode`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thresholds {
    /// Whether white is occupied (`negate: 1`).
    pub negate: bool,
    /// Occupied above this occupancy.
    pub occupied: f32,
    /// Free below this occupancy.
    pub free: f32,
    /// `mode: scale`: a transparent pixel (alpha below full) is unknown.
    pub scale: bool,
}

impl Default for Thresholds {
    /// map_server's usual values (`map_saver`'s YAML): occupied above 0.65, free below 0.196,
    /// trinary.
    fn default() -> Self {
        Self {
            negate: false,
            occupied: 0.65,
            free: 0.196,
            scale: false,
        }
    }
}

/// One class per pixel, in flat-index order (grid row 0 south = the image's last row).
fn classify(raster: &Raster, t: Thresholds) -> Vec<CellClass> {
    let maxval = raster.maxval as f32;
    let mut cells = vec![CellClass::Unknown; raster.width * raster.height];
    for (k, &v) in raster.pixels.iter().enumerate() {
        let (image_row, col) = (k / raster.width, k % raster.width);
        let row = raster.height - 1 - image_row;
        let v = v as f32;
        let p = if t.negate {
            v / maxval
        } else {
            (maxval - v) / maxval
        };
        let transparent = t.scale && raster.transparent.get(k).copied().unwrap_or(false);
        cells[row * raster.width + col] = if transparent {
            CellClass::Unknown
        } else if p > t.occupied {
            CellClass::Occupied
        } else if p < t.free {
            CellClass::Free
        } else {
            CellClass::Unknown
        };
    }
    cells
}

/// Reads a map image given without a YAML (`papillon-sim mission --map plan.pgm`): one pixel
/// per cell of `resolution_m`, the south-west corner at `origin`, classified with
/// [`Thresholds::default`] (so map_saver's grey 205 is unknown, not free).
pub fn read_image(
    image_path: &Path,
    resolution_m: f32,
    origin: Point2,
) -> Result<MapImage, MapFileError> {
    let bytes = crate::files::read_limited(image_path, crate::files::MAP_MAX_BYTES)
        .map_err(io_err(image_path))?;
    decode_map_image(image_path, &bytes, resolution_m, origin)
}

/// [`read_image`] on the bytes of `image_path` (which errors name).
pub fn decode_map_image(
    image_path: &Path,
    bytes: &[u8],
    resolution_m: f32,
    origin: Point2,
) -> Result<MapImage, MapFileError> {
    let raster = decode_image(image_path, bytes)?;
    let geometry =
        GridGeometry::new(raster.width, raster.height, resolution_m, origin).map_err(|source| {
            MapFileError::BadGeometry {
                path: image_path.to_path_buf(),
                source,
            }
        })?;
    Ok(MapImage {
        geometry,
        cells: classify(&raster, Thresholds::default()),
    })
}

/// Most pixels a PNG map may have (its header is read first: a small file may decode to
/// gigabytes). 64 Mi pixels is a 400 m square at 5 cm.
pub const MAX_IMAGE_PIXELS: u64 = 64 * 1024 * 1024;

/// An image's grey values, first row north.
struct Raster {
    width: usize,
    height: usize,
    maxval: u16,
    pixels: Vec<u16>,
    /// Per pixel, whether it is transparent (alpha below full); empty without alpha.
    transparent: Vec<bool>,
}

/// A PGM (P5 or P2) or a PNG (grey, grey+alpha, RGB or RGBA; colour read as its luma, as
/// map_server averages the channels of a grey-looking map).
fn decode_image(path: &Path, bytes: &[u8]) -> Result<Raster, MapFileError> {
    const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    if !bytes.starts_with(PNG_SIGNATURE) {
        return parse_pgm(path, bytes);
    }
    let bad = |e: image::ImageError| MapFileError::BadImage {
        path: path.to_path_buf(),
        what: e.to_string(),
    };
    let reader =
        || image::ImageReader::with_format(std::io::Cursor::new(bytes), image::ImageFormat::Png);
    let (w, h) = reader().into_dimensions().map_err(bad)?;
    if u64::from(w) * u64::from(h) > MAX_IMAGE_PIXELS {
        return Err(MapFileError::BadImage {
            path: path.to_path_buf(),
            what: format!("{w} x {h} pixels, more than {MAX_IMAGE_PIXELS}"),
        });
    }
    let image = reader().decode().map_err(bad)?;
    let has_alpha = image.color().has_alpha();
    let grey = image.to_luma_alpha8();
    let (width, height) = (grey.width() as usize, grey.height() as usize);
    if width == 0 || height == 0 {
        return Err(MapFileError::BadImage {
            path: path.to_path_buf(),
            what: "the image has no pixels".into(),
        });
    }
    let pixels = grey.pixels().map(|p| u16::from(p.0[0])).collect();
    let transparent = if has_alpha {
        grey.pixels().map(|p| p.0[1] < 255).collect()
    } else {
        Vec::new()
    };
    Ok(Raster {
        width,
        height,
        maxval: 255,
        pixels,
        transparent,
    })
}

/// The YAML's `key: value` entries with their line numbers, from block style (one `key: value`
/// per line; a list either `[a, b, c]`, also over several lines, or as `- a` lines under the
/// key) or flow style (the whole document one `{key: value, ...}`, over any number of lines).
/// `#` starts a comment at the start of a line or after a space, outside quotes (YAML's rule);
/// `---` and `...` (document markers) are skipped.
fn yaml_entries(path: &Path, text: &str) -> Result<Vec<(usize, String, String)>, MapFileError> {
    let lines: Vec<(usize, &str, String)> = text
        .lines()
        .enumerate()
        .map(|(n, raw)| (n + 1, raw, strip_comment(raw).trim().to_string()))
        .filter(|(_, _, c)| !c.is_empty() && c != "---" && c != "...")
        .collect();
    let bad_line = |line: usize, raw: &str| MapFileError::BadLine {
        path: path.to_path_buf(),
        line,
        found: raw.to_string(),
    };
    // Flow style: one mapping in braces.
    if let Some((first_line, _, first)) = lines.first()
        && first.starts_with('{')
    {
        let mut joined = String::new();
        let mut line_of_char = Vec::new();
        for (line, _, content) in &lines {
            for c in content.chars().chain([' ']) {
                joined.push(c);
                line_of_char.push(*line);
            }
        }
        let inner = joined.trim_end();
        let Some(inner) = inner.strip_prefix('{').and_then(|i| i.strip_suffix('}')) else {
            return Err(MapFileError::BadLine {
                path: path.to_path_buf(),
                line: *first_line,
                found: "a `{` without its closing `}`".into(),
            });
        };
        let mut entries = Vec::new();
        for (start, item) in split_top_level(inner) {
            let item_trim = item.trim();
            if item_trim.is_empty() {
                continue;
            }
            let line = line_of_char
                .get(1 + start + (item.len() - item.trim_start().len()))
                .copied()
                .unwrap_or(*first_line);
            let (key, value) = item_trim
                .split_once(':')
                .ok_or_else(|| bad_line(line, item_trim))?;
            entries.push((line, key.trim().to_string(), value.trim().to_string()));
        }
        return Ok(entries);
    }
    let mut entries: Vec<(usize, String, String)> = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let (line, raw, content) = &lines[k];
        k += 1;
        if content.starts_with('-') {
            // A `- item` with no key above it to belong to.
            return Err(bad_line(*line, raw));
        }
        let (key, value) = content
            .split_once(':')
            .ok_or_else(|| bad_line(*line, raw))?;
        let mut value = value.trim().to_string();
        if value.is_empty() {
            // A block list: the `- item` lines that follow.
            let mut items = Vec::new();
            while let Some((_, _, c)) = lines.get(k)
                && let Some(item) = c.strip_prefix('-')
            {
                items.push(item.trim().to_string());
                k += 1;
            }
            if !items.is_empty() {
                value = format!("[{}]", items.join(", "));
            }
        } else if value.starts_with('[') && !value.contains(']') {
            // A flow list over several lines.
            while let Some((_, _, c)) = lines.get(k) {
                value.push(' ');
                value.push_str(c);
                k += 1;
                if c.contains(']') {
                    break;
                }
            }
        }
        entries.push((*line, key.trim().to_string(), value));
    }
    Ok(entries)
}

/// `line` without its comment: from a `#` at the start or after whitespace, outside quotes.
fn strip_comment(line: &str) -> &str {
    let mut quote: Option<char> = None;
    let mut previous_blank = true;
    for (i, c) in line.char_indices() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None if c == '"' || c == '\'' => quote = Some(c),
            None if c == '#' && previous_blank => return &line[..i],
            None => {}
        }
        previous_blank = c.is_whitespace();
    }
    line
}

/// `text` split at the commas outside brackets and quotes, each piece with its byte offset.
fn split_top_level(text: &str) -> Vec<(usize, &str)> {
    let mut pieces = Vec::new();
    let (mut depth, mut quote, mut start) = (0i32, None::<char>, 0);
    for (i, c) in text.char_indices() {
        match (quote, c) {
            (Some(q), _) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                pieces.push((start, &text[start..i]));
                start = i + 1;
            }
            _ => {}
        }
    }
    pieces.push((start, &text[start..]));
    pieces
}

/// Parses a P5 or P2 PGM.
fn parse_pgm(path: &Path, bytes: &[u8]) -> Result<Raster, MapFileError> {
    let p = || path.to_path_buf();
    let ascii = match bytes.get(..2) {
        Some(b"P5") => false,
        Some(b"P2") => true,
        _ => {
            return Err(MapFileError::BadMagic {
                path: p(),
                found: String::from_utf8_lossy(&bytes[..bytes.len().min(2)]).into_owned(),
            });
        }
    };
    let mut pos = 2;
    // Skips whitespace and comments, then reads an unsigned decimal.
    let header_number = |pos: &mut usize, expected: &'static str| {
        loop {
            match bytes.get(*pos) {
                Some(b) if b.is_ascii_whitespace() => *pos += 1,
                Some(b'#') => {
                    while let Some(&b) = bytes.get(*pos) {
                        *pos += 1;
                        if b == b'\n' {
                            break;
                        }
                    }
                }
                _ => break,
            }
        }
        let start = *pos;
        while bytes.get(*pos).is_some_and(u8::is_ascii_digit) {
            *pos += 1;
        }
        std::str::from_utf8(&bytes[start..*pos])
            .ok()
            .and_then(|s| s.parse::<usize>().ok())
            .filter(|&v| v > 0)
            .ok_or(MapFileError::BadHeader {
                path: p(),
                offset: start,
                expected,
            })
    };
    let width = header_number(&mut pos, "the image width")?;
    let height = header_number(&mut pos, "the image height")?;
    let maxval = header_number(&mut pos, "maxval (1 to 65535)")?;
    if maxval > 65535 {
        return Err(MapFileError::BadHeader {
            path: p(),
            offset: pos,
            expected: "maxval (1 to 65535)",
        });
    }
    let count = width.checked_mul(height).ok_or(MapFileError::BadHeader {
        path: p(),
        offset: pos,
        expected: "a width and height whose product fits in memory",
    })?;
    let mut pixels = Vec::new();
    if ascii {
        let mut rest = &bytes[pos..];
        let mut offset = pos;
        while pixels.len() < count {
            let skip = rest.iter().take_while(|b| b.is_ascii_whitespace()).count();
            rest = &rest[skip..];
            offset += skip;
            if rest.is_empty() {
                break;
            }
            let len = rest.iter().take_while(|b| !b.is_ascii_whitespace()).count();
            let v = std::str::from_utf8(&rest[..len])
                .ok()
                .and_then(|s| s.parse::<u32>().ok())
                .filter(|&v| v as usize <= maxval)
                .ok_or(MapFileError::BadPixel { path: p(), offset })?;
            pixels.push(v as u16);
            rest = &rest[len..];
            offset += len;
        }
    } else {
        // Exactly one whitespace byte ends the header.
        if !bytes.get(pos).is_some_and(u8::is_ascii_whitespace) {
            return Err(MapFileError::BadHeader {
                path: p(),
                offset: pos,
                expected: "one whitespace byte before the pixels",
            });
        }
        let data = &bytes[pos + 1..];
        let wide = maxval > 255;
        let per = if wide { 2 } else { 1 };
        let available = data.len() / per;
        pixels.extend(data.chunks_exact(per).take(count).map(|c| {
            if wide {
                u16::from_be_bytes([c[0], c[1]])
            } else {
                c[0] as u16
            }
        }));
        if available >= count
            && let Some(k) = pixels.iter().position(|&v| v as usize > maxval)
        {
            return Err(MapFileError::BadPixel {
                path: p(),
                offset: pos + 1 + k * per,
            });
        }
    }
    if pixels.len() < count {
        return Err(MapFileError::Truncated {
            path: p(),
            expected_pixels: count,
            found_pixels: pixels.len(),
        });
    }
    Ok(Raster {
        width,
        height,
        maxval: maxval as u16,
        pixels,
        transparent: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::LogOddsBounds;
    use crate::random::{below, seeded};

    /// A directory of the test's own under the system's temporary directory, removed with
    /// what the test wrote into it when the test ends (passed or failed).
    struct TempDir(PathBuf);

    impl core::ops::Deref for TempDir {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    fn temp_dir(name: &str) -> TempDir {
        let d =
            std::env::temp_dir().join(format!("papillon-mapfile-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        TempDir(d)
    }

    #[test]
    fn round_trip_preserves_every_cell() {
        let dir = temp_dir("round");
        let geom = GridGeometry::new(37, 23, 0.05, Point2::new(-1.3, 2.7)).unwrap();
        let mut g = OccupancyGrid::<{ 37 * 23 }>::new(geom, LogOddsBounds::default()).unwrap();
        let mut rng = seeded(5);
        for i in 0..geom.cell_count() {
            let c = [CellClass::Free, CellClass::Unknown, CellClass::Occupied][below(&mut rng, 3)];
            g.set_class(i, c, &mut ());
        }
        // A weakly known cell must still read back with its class.
        g.set_log_odds(0, 0.01, &mut ());
        let yaml = dir.join("map.yaml");
        write_map(&g, &yaml).unwrap();
        let m = read_map(&yaml).unwrap();
        assert_eq!(m.geometry, geom);
        assert_eq!(m, MapImage::from_grid(&g));
        let mut back = OccupancyGrid::<{ 37 * 23 }>::new(geom, LogOddsBounds::default()).unwrap();
        m.load_into(&mut back).unwrap();
        for i in 0..geom.cell_count() {
            assert_eq!(back.class(i), g.class(i));
        }
        assert_eq!(back.counts(), g.counts());
        // Row 0 of the image is the north edge.
        let bytes = fs::read(dir.join("map.pgm")).unwrap();
        let header = "P5\n37 23\n255\n".len();
        let north_west = g.class(geom.index(crate::grid::Cell::new(0, 22)).unwrap());
        let want = match north_west {
            CellClass::Free => PIXEL_FREE,
            CellClass::Occupied => PIXEL_OCCUPIED,
            CellClass::Unknown => PIXEL_UNKNOWN,
        };
        assert_eq!(bytes[header], want);
        assert!(!dir.join("map.pgm.tmp").exists() && !dir.join("map.yaml.tmp").exists());
    }

    #[test]
    fn ascii_pgm_negate_and_thresholds_are_honoured() {
        let dir = temp_dir("ascii");
        // 3 x 2, maxval 100, comment in the header; negate: p = v / maxval.
        fs::write(
            dir.join("w.pgm"),
            "P2\n# a comment\n3 2\n100\n0 50 100\n10 90 64\n",
        )
        .unwrap();
        fs::write(
            dir.join("w.yaml"),
            "image: w.pgm\nresolution: 0.5\norigin: [1.0, -2, 0.0]\nnegate: 1\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
        )
        .unwrap();
        let m = read_map(&dir.join("w.yaml")).unwrap();
        use CellClass::*;
        // Image row 0 (north) is grid row 1.
        assert_eq!(m.cells, [Free, Occupied, Unknown, Free, Unknown, Occupied]);
        assert_eq!(m.geometry.origin, Point2::new(1.0, -2.0));
        assert_eq!(m.geometry.resolution_m, 0.5);
    }

    fn error_of(yaml: &str, pgm: &[u8]) -> String {
        static CASE: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let case = CASE.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = temp_dir(&format!("bad{case}"));
        fs::write(dir.join("m.pgm"), pgm).unwrap();
        fs::write(dir.join("m.yaml"), yaml).unwrap();
        read_map(&dir.join("m.yaml")).unwrap_err().to_string()
    }

    const GOOD_YAML: &str = "image: m.pgm\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n";

    #[test]
    fn broken_files_give_errors_naming_the_file_and_the_fault() {
        let e = error_of(GOOD_YAML, b"P6\n2 2\n255\n\0\0\0\0");
        assert!(e.contains("m.pgm") && e.contains("`P6`"), "{e}");
        let e = error_of(GOOD_YAML, b"P5\n2 2\n255\n\0\0\0");
        assert!(
            e.contains("m.pgm") && e.contains("truncated") && e.contains("3 of 4"),
            "{e}"
        );
        let e = error_of(GOOD_YAML, b"P5\n2 x\n255\n\0\0\0\0");
        assert!(
            e.contains("m.pgm") && e.contains("byte 5") && e.contains("height"),
            "{e}"
        );
        let e = error_of(
            &GOOD_YAML.replace("resolution: 0.1\n", ""),
            b"P5\n1 1\n255\n\0",
        );
        assert!(
            e.contains("m.yaml") && e.contains("missing key `resolution`"),
            "{e}"
        );
        let e = error_of(&GOOD_YAML.replace("0.1", "ten cm"), b"P5\n1 1\n255\n\0");
        assert!(
            e.contains("m.yaml:2") && e.contains("`ten cm`") && e.contains("a number"),
            "{e}"
        );
        let e = error_of(
            &GOOD_YAML.replace("[0.0, 0.0, 0.0]", "[0.0, 0.0]"),
            b"P5\n1 1\n255\n\0",
        );
        assert!(e.contains("m.yaml:3") && e.contains("origin"), "{e}");
        let e = error_of(GOOD_YAML, b"P2\n2 1\n255\n3 300\n");
        assert!(e.contains("m.pgm") && e.contains("maxval"), "{e}");
        let e = error_of(GOOD_YAML, b"");
        assert!(e.contains("m.pgm") && e.contains("not a PGM"), "{e}");
        let dir = temp_dir("missing");
        let e = read_map(&dir.join("none.yaml")).unwrap_err().to_string();
        assert!(e.contains("none.yaml"), "{e}");
    }

    /// A small map with every class, written by [`write_map_image`].
    fn sample(dir: &Path) -> MapImage {
        let geometry = GridGeometry::new(5, 4, 0.05, Point2::new(-10.0, -7.5)).unwrap();
        use CellClass::*;
        let cells = [Free, Occupied, Unknown]
            .iter()
            .cycle()
            .take(geometry.cell_count() + 1)
            .skip(1)
            .copied()
            .collect();
        let map = MapImage { geometry, cells };
        write_map_image(&map, &dir.join("map.yaml")).unwrap();
        map
    }

    /// The written PGM's grey values, first row north.
    fn written_pixels(dir: &Path) -> (usize, usize, Vec<u8>) {
        let bytes = fs::read(dir.join("map.pgm")).unwrap();
        let raster = parse_pgm(Path::new("map.pgm"), &bytes).unwrap();
        let pixels = raster.pixels.iter().map(|&v| v as u8).collect();
        (raster.width, raster.height, pixels)
    }

    #[test]
    fn map_saver_files_read_back() {
        let dir = temp_dir("map-saver");
        let map = sample(&dir);
        let (w, h, pixels) = written_pixels(&dir);
        // ROS 1 map_saver: a creator comment in the PGM header, six-decimal numbers, no mode.
        let mut pgm =
            format!("P5\n# CREATOR: map_saver.cpp 0.050 m/pix\n{w} {h}\n255\n").into_bytes();
        pgm.extend(&pixels);
        fs::write(dir.join("ros1.pgm"), pgm).unwrap();
        fs::write(
            dir.join("ros1.yaml"),
            "image: ros1.pgm\nresolution: 0.050000\norigin: [-10.000000, -7.500000, 0.000000]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n\n",
        )
        .unwrap();
        assert_eq!(read_map(&dir.join("ros1.yaml")).unwrap(), map);
        // Mode first, integers in the origin, a PNG (nav2's map_saver can write one).
        let png = image::GrayImage::from_raw(w as u32, h as u32, pixels.clone()).unwrap();
        png.save(dir.join("nav2.png")).unwrap();
        fs::write(
            dir.join("nav2.yaml"),
            "image: nav2.png\nmode: trinary\nresolution: 0.05\norigin: [-10, -7.5, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
        )
        .unwrap();
        assert_eq!(read_map(&dir.join("nav2.yaml")).unwrap(), map);
        // nav2's default free_thresh 0.25 is above the occupancy of the grey 205 (0.196): the
        // thresholds are honoured, unknown reads free.
        let yaml = fs::read_to_string(dir.join("nav2.yaml")).unwrap();
        fs::write(dir.join("nav2.yaml"), yaml.replace("0.196", "0.25")).unwrap();
        let loose = read_map(&dir.join("nav2.yaml")).unwrap();
        assert!(!loose.cells.contains(&CellClass::Unknown));
        assert_eq!(
            loose
                .cells
                .iter()
                .filter(|&&c| c == CellClass::Occupied)
                .count(),
            map.cells
                .iter()
                .filter(|&&c| c == CellClass::Occupied)
                .count()
        );
    }

    #[test]
    fn gimp_edits_read_back() {
        let dir = temp_dir("gimp");
        let map = sample(&dir);
        let (w, h, pixels) = written_pixels(&dir);
        let yaml = fs::read_to_string(dir.join("map.yaml")).unwrap();
        // GIMP's PNM export: its comment line, then the same pixels.
        let mut pgm = format!("P5\n# Created by GIMP version 2.10.38 PNM plug-in\n{w} {h}\n255\n")
            .into_bytes();
        pgm.extend(&pixels);
        fs::write(dir.join("map.pgm"), pgm).unwrap();
        assert_eq!(read_map(&dir.join("map.yaml")).unwrap(), map);
        // GIMP's PNG export of the same image in colour with an opaque alpha channel.
        let rgba = image::RgbaImage::from_fn(w as u32, h as u32, |x, y| {
            let v = pixels[y as usize * w + x as usize];
            image::Rgba([v, v, v, 255])
        });
        rgba.save(dir.join("map.png")).unwrap();
        fs::write(dir.join("png.yaml"), yaml.replace("map.pgm", "map.png")).unwrap();
        assert_eq!(read_map(&dir.join("png.yaml")).unwrap(), map);
        // Under `mode: scale` a transparent pixel (erased in GIMP) is unknown; under trinary
        // alpha is ignored.
        let mut erased = rgba.clone();
        erased.put_pixel(0, 0, image::Rgba([254, 254, 254, 0]));
        erased.save(dir.join("map.png")).unwrap();
        let trinary = read_map(&dir.join("png.yaml")).unwrap();
        let north_west = (h - 1) * w;
        assert_eq!(trinary.cells[north_west], CellClass::Free);
        fs::write(
            dir.join("png.yaml"),
            yaml.replace("map.pgm", "map.png")
                .replace("mode: trinary", "mode: scale"),
        )
        .unwrap();
        let scale = read_map(&dir.join("png.yaml")).unwrap();
        assert_eq!(scale.cells[north_west], CellClass::Unknown);
        assert_eq!(scale.cells[..north_west], map.cells[..north_west]);
        // A 16-bit PGM (maxval 65535) of the same map.
        let mut wide = format!("P5\n{w} {h}\n65535\n").into_bytes();
        for &v in &pixels {
            wide.extend((u16::from(v) * 257).to_be_bytes());
        }
        fs::write(dir.join("map.pgm"), wide).unwrap();
        assert_eq!(read_map(&dir.join("map.yaml")).unwrap(), map);
    }

    #[test]
    fn hand_edited_yaml_reads_back() {
        let dir = temp_dir("hand");
        let map = sample(&dir);
        let (w, h, pixels) = written_pixels(&dir);
        let read = |name: &str, text: &str| {
            fs::write(dir.join(name), text).unwrap();
            read_map(&dir.join(name))
        };
        // Block style with comments, a quoted image name, a block-list origin, `---`.
        let block = "---\n# the lab, saved by hand\nimage: \"map.pgm\"   # the picture\nresolution: 0.05\norigin:\n  - -10.0\n  - -7.5\n  - 0.0\nnegate: false\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
        assert_eq!(read("block.yaml", block).unwrap(), map);
        // Flow style, over several lines, keys in another order.
        let flow = "{resolution: 0.05, image: map.pgm,\n  origin: [-10.0, -7.5, 0.0], # south-west\n  negate: 0, occupied_thresh: 0.65, free_thresh: 0.196, mode: trinary}\n";
        assert_eq!(read("flow.yaml", flow).unwrap(), map);
        // An origin list over several lines.
        let multi = "image: map.pgm\nresolution: 0.05\norigin: [-10.0,\n         -7.5, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
        assert_eq!(read("multi.yaml", multi).unwrap(), map);
        // negate 1 with the image inverted (white walls on black floor) is the same map.
        let mut inverted = format!("P5\n{w} {h}\n255\n").into_bytes();
        inverted.extend(pixels.iter().map(|v| 255 - v));
        fs::write(dir.join("inv.pgm"), inverted).unwrap();
        let negated = "image: inv.pgm\nresolution: 0.05\norigin: [-10.0, -7.5, 0.0]\nnegate: 1\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
        assert_eq!(read("neg.yaml", negated).unwrap(), map);
        // Thresholds are honoured: with free_thresh above 205's occupancy (0.196), the
        // unknown grey reads free.
        let loose = block.replace("free_thresh: 0.196", "free_thresh: 0.2");
        let m = read("loose.yaml", &loose).unwrap();
        assert!(!m.cells.contains(&CellClass::Unknown));
        // What is not supported is a clear error naming the file and line.
        let rotated = block.replace("  - 0.0", "  - 1.57");
        let e = read("rot.yaml", &rotated).unwrap_err().to_string();
        assert!(e.contains("rot.yaml") && e.contains("rotated"), "{e}");
        let raw = format!("{block}mode: raw\n");
        let e = read("raw.yaml", &raw).unwrap_err().to_string();
        assert!(e.contains("raw.yaml") && e.contains("mode `raw`"), "{e}");
        let e = read("open.yaml", "{image: map.pgm, resolution: 0.05\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("open.yaml:1") && e.contains("`}`"), "{e}");
        let e = read("dash.yaml", "- image: map.pgm\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("dash.yaml:1"), "{e}");
    }

    #[test]
    fn a_plain_image_reads_unknown_grey_as_unknown() {
        let m = decode_map_image(
            Path::new("plain.pgm"),
            b"P2\n3 1\n255\n0 205 254\n",
            0.1,
            Point2::default(),
        )
        .unwrap();
        use CellClass::*;
        assert_eq!(m.cells, [Occupied, Unknown, Free]);
        let e = decode_map_image(
            Path::new("x.png"),
            b"\x89PNG\r\n\x1a\nbroken",
            0.1,
            Point2::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("x.png: not a readable PNG"), "{e}");
    }
}
