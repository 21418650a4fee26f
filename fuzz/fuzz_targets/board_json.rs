//! Board file reader: `BoardConfig::from_json` and `validate` never panic on any bytes; a
//! board that parses is validated (every problem reported with a JSON path), and an error's
//! message can be formatted.
#![no_main]

use libfuzzer_sys::fuzz_target;
use papillon::config::BoardConfig;

fuzz_target!(|data: &[u8]| {
    match BoardConfig::from_json(data) {
        Ok(board) => {
            board.validate(|path, problem| {
                assert!(path.starts_with("$."), "problem without a JSON path: {problem}");
            });
            let _ = board.laser_config();
            let _ = board.grid.size_cells();
        }
        Err(e) => {
            let _ = format!("{e}");
        }
    }
});
