//! The project speaks of the present: no line of a `.rs` file in `src/`, `tests/`, `benches/`
//! or `examples/` (nor of a `.yaml` file under `benches/`, nor of the README or a Markdown file
//! under `docs/`) names a work session, an issue number or a commit hash. A reader cannot tell whether such a reference still holds; the reason behind the code
//! is to be said as it stands now, and its history is in git.
//!
//! Matched, case-insensitively: `session` or `sessions` then a space and a number (a session),
//! `issue` or `issues` then a space, `#` or `-` and a number (an issue), and a word of 7 to 40 hex digits with
//! at least one digit and one letter a-f (a commit hash). Hex literals (`0x...`, such as the
//! trajectory hashes the bitwise tests record) are words with an `x`, so never hashes.

use std::fs;
use std::path::Path;

/// This file: it spells out the patterns it looks for.
const SELF: &str = "tests/history_free.rs";

/// The scanned files under `dir` (relative to the crate root, with `/` separators).
fn files(root: &Path, dir: &str, out: &mut Vec<String>) {
    let Ok(entries) = fs::read_dir(root.join(dir)) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let rel = format!("{dir}/{name}");
        if e.path().is_dir() {
            files(root, &rel, out);
        } else if name.ends_with(".rs")
            || (rel.starts_with("benches/") && name.ends_with(".yaml"))
            || (rel.starts_with("docs/") && name.ends_with(".md"))
        {
            out.push(rel);
        }
    }
}

/// Whether the byte at `at` of `line` starts a word: nothing alphanumeric right before it (so
/// a word such as `tissue` followed by a number is not an issue).
fn starts_word(line: &[u8], at: usize) -> bool {
    at == 0 || !line[at - 1].is_ascii_alphanumeric()
}

/// Whether `rest` (what follows `session` or `issue`) reads as a number of one: an optional
/// plural `s`, then a space and a digit (or, for an issue, `#` and a digit, or `-` and a digit).
fn numbered(rest: &[u8], issue: bool) -> bool {
    let rest = rest.strip_prefix(b"s").unwrap_or(rest);
    let digit = |s: &[u8]| s.first().is_some_and(u8::is_ascii_digit);
    if let Some(after) = rest.strip_prefix(b" ") {
        digit(after) || (issue && after.strip_prefix(b"#").is_some_and(digit))
    } else {
        issue && rest.strip_prefix(b"-").is_some_and(digit)
    }
}

/// A word of 7 to 40 hex digits with at least one digit and one letter a-f, but not the
/// fraction of a float literal with its type suffix (`0.0075` followed by `f64`).
fn commit_hash(word: &[u8]) -> bool {
    if !(7..=40).contains(&word.len()) || !word.iter().all(u8::is_ascii_hexdigit) {
        return false;
    }
    let float = [b"f32", b"f64"].iter().any(|t| {
        word.strip_suffix(&t[..])
            .is_some_and(|d| d.iter().all(u8::is_ascii_digit))
    });
    !float && word.iter().any(u8::is_ascii_digit) && word.iter().any(u8::is_ascii_alphabetic)
}

/// What a lower-cased line names, if anything.
fn history_lower(line: &[u8]) -> Option<&'static str> {
    for (key, issue, what) in [
        (&b"session"[..], false, "a session number"),
        (&b"issue"[..], true, "an issue number"),
    ] {
        let found = (0..line.len().saturating_sub(key.len() - 1)).any(|at| {
            line[at..].starts_with(key)
                && starts_word(line, at)
                && numbered(&line[at + key.len()..], issue)
        });
        if found {
            return Some(what);
        }
    }
    let hash = line
        .split(|c| !(c.is_ascii_alphanumeric() || *c == b'_'))
        .any(|w| !w.starts_with(b"0x") && commit_hash(w));
    hash.then_some("a commit hash")
}

/// What a line names, if anything.
fn history(line: &str) -> Option<&'static str> {
    history_lower(line.to_ascii_lowercase().as_bytes())
}

#[test]
fn no_line_names_a_session_an_issue_or_a_commit() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut all = Vec::new();
    for dir in ["src", "tests", "benches", "examples", "docs"] {
        files(root, dir, &mut all);
    }
    all.push("README.md".to_string());
    all.sort();
    assert!(all.len() > 100, "only {} files found", all.len());
    let mut found = Vec::new();
    for rel in all.iter().filter(|r| r.as_str() != SELF) {
        let text = fs::read_to_string(root.join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let lower = text.to_ascii_lowercase();
        for (i, (line, low)) in text.lines().zip(lower.lines()).enumerate() {
            if let Some(what) = history_lower(low.as_bytes()) {
                found.push(format!("{rel}:{}: {what}: {}", i + 1, line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "{} lines speak of the past (say what the code does and why, now):\n{}",
        found.len(),
        found.join("\n")
    );
}

#[test]
fn the_scan_tells_history_from_numbers() {
    // Spelled in pieces, so that a plain grep of the tree for history finds none here.
    for line in [
        concat!("// sess", "ion 24: measured"),
        concat!("// Sess", "ions 3 and 4"),
        concat!("// (iss", "ue 18)"),
        concat!("// Iss", "ue #7"),
        concat!("// the iss", "ue-15 redesign"),
        concat!("// iss", "ues 16 and 20"),
        concat!("// main at 50c", "56f8"),
        concat!("// on simcol at 8F9", "87F2."),
    ] {
        assert!(history(line).is_some(), "missed: {line}");
    }
    for line in [
        "// the issue's material",
        concat!("// a tiss", "ue 3 mm thick"),
        "// the session's log",
        "    (\"crumple16_self\", 0x8adab6bcd159ea8e),",
        "// 4294967295 and 6364136223846793005",
        "// deadbeef and cafebabe",
        "// abc1234_x and x_abc1234",
        concat!("// 1.5707963267948966 and 0.0", "075f64"),
        "// sha256 e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
    ] {
        assert!(history(line).is_none(), "false alarm: {line}");
    }
}
