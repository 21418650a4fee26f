//! Layers only point down (developers' guide): `src/wire` knows bytes, not the rest of the
//! crate, and the core (everything under `src/` but `src/onboard/` and `src/main.rs`) never
//! reaches up into the onboard runtime. This test reads the sources and names every line
//! that breaks either rule.
//!
//! Comments are skipped. In `src/wire`, code may name `crate::wire` only; its test module
//! (from the first `#[cfg(test)]` line on) may also use `crate::random`, the seeded RNG every
//! test draws from.

use std::fs;
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The code of a line: without its `//` comment (string contents are not told apart; no
/// source line here puts `//` in a string before a path).
fn code(line: &str) -> &str {
    match line.find("//") {
        Some(i) => &line[..i],
        None => line,
    }
}

/// The top-level module of every `crate::` path in `code` (each member of a
/// `crate::{a::x, b}` group counts).
fn crate_paths(code: &str) -> Vec<String> {
    let ident = |s: &str| {
        let end = s
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(s.len());
        s[..end].to_owned()
    };
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        // A preceding identifier character means another word (`my_crate::`).
        let own = !rest[..i]
            .chars()
            .next_back()
            .is_some_and(|c| c.is_alphanumeric() || c == '_');
        let after = &rest[i + "crate::".len()..];
        if own {
            if let Some(group) = after.strip_prefix('{') {
                // Members at depth 0 of the group.
                let mut depth = 0;
                let mut start = 0;
                for (j, c) in group.char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => {
                            out.push(ident(group[start..j].trim()));
                            break;
                        }
                        '}' => depth -= 1,
                        ',' if depth == 0 => {
                            out.push(ident(group[start..j].trim()));
                            start = j + 1;
                        }
                        _ => {}
                    }
                }
            } else {
                out.push(ident(after));
            }
        }
        rest = after;
    }
    out.retain(|m| !m.is_empty());
    out
}

/// Lines of `src/wire` that name another part of the crate.
fn wire_violations(root: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(&root.join("src/wire"), &mut files);
    let mut out = Vec::new();
    for file in files {
        let text = fs::read_to_string(&file).expect("a readable source file");
        let mut in_tests = false;
        for (n, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("#[cfg(test)]") {
                in_tests = true;
            }
            for module in crate_paths(code(line)) {
                let allowed = module == "wire" || (in_tests && module == "random");
                if !allowed {
                    out.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
                }
            }
        }
    }
    out
}

/// Lines of the core that name the onboard runtime.
fn core_violations(root: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    let onboard = root.join("src/onboard");
    let main = root.join("src/main.rs");
    let mut out = Vec::new();
    for file in files {
        if file.starts_with(&onboard) || file == main {
            continue;
        }
        let text = fs::read_to_string(&file).expect("a readable source file");
        for (n, line) in text.lines().enumerate() {
            let code = code(line);
            let names_onboard = crate_paths(code).iter().any(|m| m == "onboard")
                || code.contains("papillon::onboard")
                || code.contains("super::onboard");
            if names_onboard {
                out.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
            }
        }
    }
    out
}

#[test]
fn wire_formats_import_nothing_else_of_the_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let bad = wire_violations(root);
    assert!(
        bad.is_empty(),
        "src/wire may only name crate::wire:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_core_never_imports_the_onboard_runtime() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let bad = core_violations(root);
    assert!(
        bad.is_empty(),
        "the core may not name the onboard runtime:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_checks_see_a_planted_violation() {
    assert_eq!(crate_paths("use crate::sensor::{Beam, Scan};"), ["sensor"]);
    assert_eq!(
        crate_paths("use crate::{wire::{a, b}, units::mm_to_m};"),
        ["wire", "units"]
    );
    assert_eq!(
        crate_paths("let x = my_crate::onboard::y;"),
        Vec::<&str>::new()
    );
    assert_eq!(
        code("use crate::wire::x; // crate::sensor"),
        "use crate::wire::x; "
    );
}
