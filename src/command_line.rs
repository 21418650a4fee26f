//! Command-line error messages shared by the two binaries (`papillon`, `papillon-sim`; host
//! only).

/// One line for a bad command line from clap's rendered error `text`: its first paragraph (the
/// error and, for a missing argument, the flags it names) joined onto one line, then each of
/// clap's `tip:` lines in brackets (its suggestion for a near miss, `tip: a similar value
/// exists: 'xboa'`), without the `error: ` prefix.
pub fn error_line(text: &str) -> String {
    let first: Vec<&str> = text
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let mut line = first.join(" ");
    for tip in text
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("tip:"))
    {
        line.push_str(&format!(" ({tip})"));
    }
    line.strip_prefix("error: ").unwrap_or(&line).to_string()
}

#[cfg(test)]
mod tests {
    use super::error_line;

    #[test]
    fn joins_the_first_paragraph_and_keeps_the_tips() {
        let text = "error: invalid value 'xbo' for '--method <METHOD>'\n  [possible values: xboa, boa]\n\n  tip: a similar value exists: 'xboa'\n\nFor more information, try '--help'.\n";
        assert_eq!(
            error_line(text),
            "invalid value 'xbo' for '--method <METHOD>' [possible values: xboa, boa] (tip: a similar value exists: 'xboa')"
        );
    }
}
