//! Issue 19's rule, kept true: no source file over 1,000 lines (except generated data tables)
//! and no function over 150 lines, so that every file and function is one a reader can hold in
//! their head. The test walks `crates/` and `tests/` (skipping `target/` folders and the
//! generated RGB-to-spectrum table) and names every offender.
//!
//! Functions are found by their layout, which rustfmt makes reliable: a function starts at a
//! line of optional indentation, optional `pub` or `pub(..)`, optional `const` and `unsafe`,
//! then `fn name`, not ending in `;` (a declaration without a body), and ends at the first later
//! line that is the same indentation followed by `}`. Its length counts both of those lines.

use std::path::{Path, PathBuf};

/// Most lines a source file may have.
const MAX_FILE_LINES: usize = 1000;

/// Most lines a function may have, from its `fn` line to its closing brace.
const MAX_FN_LINES: usize = 150;

/// Generated data, exempt from the file limit (relative to the workspace root).
const GENERATED: &[&str] = &["crates/pt-spectrum/src/rgb2spec/table.rs"];

/// Every `.rs` file under `dir`, skipping `target/` and hidden folders.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.unwrap().path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if path.is_dir() {
            if name != "target" && !name.starts_with('.') {
                rust_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The indentation and name of the function `line` starts, if it starts one with a body.
fn function_start(line: &str) -> Option<(&str, &str)> {
    if line.trim_end().ends_with(';') {
        return None;
    }
    let rest = line.trim_start();
    let indent = &line[..line.len() - rest.len()];
    let mut rest = rest;
    if let Some(r) = rest.strip_prefix("pub ") {
        rest = r;
    } else if let Some(r) = rest.strip_prefix("pub(") {
        let (inside, after) = r.split_once(')')?;
        if inside.is_empty() || !inside.chars().all(|c| c.is_ascii_lowercase()) {
            return None;
        }
        rest = after.strip_prefix(' ')?;
    }
    rest = rest.strip_prefix("const ").unwrap_or(rest);
    rest = rest.strip_prefix("unsafe ").unwrap_or(rest);
    let rest = rest.strip_prefix("fn ")?;
    let end = rest
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(rest.len());
    (end > 0).then(|| (indent, &rest[..end]))
}

/// The functions of `source` longer than [`MAX_FN_LINES`]: (length in lines, name).
fn long_functions(source: &str) -> Vec<(usize, String)> {
    let lines: Vec<&str> = source.split('\n').collect();
    let mut long = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some((indent, name)) = function_start(line) else {
            continue;
        };
        let close = format!("{indent}}}");
        if let Some(j) = (i + 1..lines.len()).find(|&j| lines[j] == close) {
            let n = j - i + 1;
            if n > MAX_FN_LINES {
                long.push((n, name.to_string()));
            }
        }
    }
    long
}

#[test]
fn no_file_over_1000_lines_and_no_function_over_150() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["crates", "tests"] {
        rust_files(&root.join(dir), &mut files);
    }
    files.sort();
    assert!(files.len() > 100, "found only {} source files", files.len());
    let mut offenders = Vec::new();
    for path in &files {
        let rel = path
            .strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let source = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let lines = source.lines().count();
        if lines > MAX_FILE_LINES && !GENERATED.contains(&rel.as_str()) {
            offenders.push(format!("{rel}: {lines} lines (at most {MAX_FILE_LINES})"));
        }
        for (n, name) in long_functions(&source) {
            offenders.push(format!(
                "{rel}: fn {name} has {n} lines (at most {MAX_FN_LINES})"
            ));
        }
    }
    assert!(
        offenders.is_empty(),
        "split these into modules or helpers that each do one thing (issue 19):\n{}",
        offenders.join("\n")
    );
}

#[test]
fn function_starts_are_found_as_the_rule_reads_them() {
    assert_eq!(function_start("fn a() {"), Some(("", "a")));
    assert_eq!(
        function_start("    pub(crate) const unsafe fn b_2<T>("),
        Some(("    ", "b_2"))
    );
    assert_eq!(function_start("pub fn c(x: u32) -> u32;"), None);
    assert_eq!(function_start("    fn_like_name() {"), None);
    assert_eq!(function_start("pub(in crate) fn d() {"), None);
    let source = "fn short() {\n}\n\nfn long() {\n".to_string()
        + &"    x;\n".repeat(MAX_FN_LINES - 1)
        + "}\n";
    assert_eq!(
        long_functions(&source),
        vec![(MAX_FN_LINES + 1, "long".to_string())]
    );
}
