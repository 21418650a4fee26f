//! The project's shared data folder (`shared/`, beside the checkout: thesis maps, the Moving AI
//! benchmark), which a plain checkout does not have. Tests that read it find it here and skip
//! with a message when it is absent.

use std::path::{Path, PathBuf};

/// Where `shared/` is looked for, in order: beside the repository this crate was built from
/// (`CARGO_MANIFEST_DIR/../../shared`), then `../shared` from the current directory.
pub fn candidates() -> [PathBuf; 2] {
    [
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared"),
        PathBuf::from("../shared"),
    ]
}

/// `relative` (e.g. `data/movingai/arena.map`) inside the first shared folder that has it.
pub fn locate(relative: impl AsRef<Path>) -> Option<PathBuf> {
    candidates()
        .into_iter()
        .map(|dir| dir.join(relative.as_ref()))
        .find(|p| p.exists())
}

/// [`locate`], or `None` after printing on standard error that `test` is skipped because
/// `relative` is absent (and where it was looked for).
pub fn locate_or_skip(test: &str, relative: impl AsRef<Path>) -> Option<PathBuf> {
    let relative = relative.as_ref();
    let found = locate(relative);
    if found.is_none() {
        let places: Vec<String> = candidates()
            .iter()
            .map(|d| d.join(relative).display().to_string())
            .collect();
        eprintln!(
            "skipping {test}: shared data {} not found (looked in {})",
            relative.display(),
            places.join(", ")
        );
    }
    found
}
