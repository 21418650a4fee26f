//! Map files in the ROS `map_server` format: a PGM image plus a YAML description.
//!
//! Format (ROS wiki, `map_server`): the YAML names the `image`, its `resolution` \[m/pixel\],
//! the `origin` `[x, y, yaw]` of the lower-left pixel \[m, rad\], `negate`, `occupied_thresh`,
//! `free_thresh` and `mode`. A pixel value `v` of maximum `maxval` reads as occupancy
//! `p = (maxval - v) / maxval` (or `v / maxval` when `negate`); Occupied if
//! `p > occupied_thresh`, Free if `p < free_thresh`, Unknown otherwise. Written maps use 254
//! free, 0 occupied, 205 unknown (`mode: trinary`). Image row 0 is the north edge, grid row 0
//! the south edge, so rows are flipped both ways.
//!
//! Both binary (P5) and ASCII (P2) PGM are read; P5 is written. The YAML subset (one
//! `key: value` per line, `#` comments, the origin as a `[a, b, c]` list) is parsed here.
//! Writes are atomic (temporary file, fsync, rename), image first, so a crash leaves either the
//! old map or the new one. Errors name the file and what is wrong.

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
                "{}: not a PGM image: starts with `{found}`, expected `P5` or `P2`",
                path.display()
            ),
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
    let mut pgm = format!("P5\n{} {}\n255\n", g.width, g.height).into_bytes();
    pgm.reserve(g.cell_count());
    for image_row in 0..g.height {
        let row = g.height - 1 - image_row;
        pgm.extend(
            map.cells[row * g.width..(row + 1) * g.width]
                .iter()
                .map(|c| match c {
                    CellClass::Free => PIXEL_FREE,
                    CellClass::Occupied => PIXEL_OCCUPIED,
                    CellClass::Unknown => PIXEL_UNKNOWN,
                }),
        );
    }
    write_atomically(&pgm_path, &pgm)?;
    let image_name = pgm_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let yaml = format!(
        "image: {image_name}\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n",
        g.resolution_m, g.origin.x, g.origin.y
    );
    write_atomically(yaml_path, yaml.as_bytes())
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
    // The known keys seen, to refuse one given twice (the second would win silently).
    let mut seen: Vec<String> = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let Some((key, value)) = content.split_once(':') else {
            return Err(MapFileError::BadLine {
                path: path(),
                line,
                found: raw.to_string(),
            });
        };
        let (key, value) = (key.trim(), value.trim());
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
            "mode" => match value {
                "trinary" | "scale" => {}
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
    let pgm = parse_pgm(&image_path, &bytes)?;
    let geometry = GridGeometry::new(
        pgm.width,
        pgm.height,
        resolution,
        Point2::new(origin[0], origin[1]),
    )
    .map_err(|source| MapFileError::BadGeometry {
        path: path(),
        source,
    })?;
    let maxval = pgm.maxval as f32;
    let mut cells = vec![CellClass::Unknown; geometry.cell_count()];
    for (k, &v) in pgm.pixels.iter().enumerate() {
        let (image_row, col) = (k / pgm.width, k % pgm.width);
        let row = pgm.height - 1 - image_row;
        let v = v as f32;
        let p = if negate {
            v / maxval
        } else {
            (maxval - v) / maxval
        };
        cells[row * pgm.width + col] = if p > occupied_thresh {
            CellClass::Occupied
        } else if p < free_thresh {
            CellClass::Free
        } else {
            CellClass::Unknown
        };
    }
    Ok(MapImage { geometry, cells })
}

struct Pgm {
    width: usize,
    height: usize,
    maxval: u16,
    pixels: Vec<u16>,
}

/// Parses a P5 or P2 PGM.
fn parse_pgm(path: &Path, bytes: &[u8]) -> Result<Pgm, MapFileError> {
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
    Ok(Pgm {
        width,
        height,
        maxval: maxval as u16,
        pixels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::LogOddsBounds;
    use crate::random::{below, seeded};

    fn temp_dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("papillon-mapfile-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
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
}
