//! Map-file reader (`mapfile::parse_map`, ROS map_server YAML + PGM): never panics on any YAML
//! text and image bytes; a map that parses has one cell per pixel, and an error's message can
//! be formatted.
//!
//! Input: the first byte `k` splits the rest, the YAML being the first `k * len / 256` bytes
//! (as lossy UTF-8) and the image the remainder.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use papillon::mapfile::parse_map;

fuzz_target!(|data: &[u8]| {
    let Some((&k, rest)) = data.split_first() else {
        return;
    };
    let split = usize::from(k) * rest.len() / 256;
    let (yaml, image) = rest.split_at(split);
    let yaml = String::from_utf8_lossy(yaml);
    match parse_map(Path::new("fuzz/map.yaml"), &yaml, |_| Ok(image.to_vec())) {
        Ok(map) => assert_eq!(map.cells.len(), map.geometry.cell_count()),
        Err(e) => {
            let _ = format!("{e}");
        }
    }
});
