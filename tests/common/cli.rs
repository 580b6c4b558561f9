//! Running the `snakegrid` command and checking how it ended.

use std::path::Path;
use std::process::{Command, Output};

pub fn snakegrid<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    Command::new(env!("CARGO_BIN_EXE_snakegrid"))
        .args(args)
        .output()
        .unwrap()
}

pub fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn assert_success(output: &Output) {
    assert!(
        output.status.success(),
        "snakegrid failed: {}\n{}",
        stderr(output),
        stdout(output)
    );
}

/// A failure with exit code `code` and a single line on stderr that names `needle`.
pub fn assert_fails(output: &Output, code: i32, needle: &str) {
    let err = stderr(output);
    assert_eq!(output.status.code(), Some(code), "stderr: {err}");
    // A progress line cut short by the error may precede the message.
    let progress = |l: &str| l.chars().all(|c| c.is_ascii_digit() || c == '.');
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| !l.trim().is_empty() && !progress(l))
        .collect();
    assert_eq!(lines.len(), 1, "expected one line, got: {err:?}");
    assert!(lines[0].starts_with("snakegrid: ERROR: "), "{err}");
    assert!(
        lines[0].contains(needle),
        "{:?} does not mention {needle:?}",
        lines[0]
    );
}
