//! Helpers shared by the generator's integration tests: fresh scratch directories, running
//! the binary, and finding external tools (missing tools fail the test when `CI` is set and
//! skip it loudly otherwise, the repo's convention).

#![allow(dead_code, reason = "each test file uses a different subset")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh, empty directory named after the test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("scatter-gen-tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}

/// Runs `scatter-gen` with `args`.
pub fn scatter_gen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_scatter-gen"))
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("running scatter-gen: {e}"))
}

/// stdout and stderr as text.
pub fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Whether an external tool runs (`tool --version` or `tool -v` succeeds).
pub fn have(tool: &str) -> bool {
    ["--version", "-v"].iter().any(|flag| {
        Command::new(tool)
            .arg(flag)
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// `true` when `tool` is available; otherwise panics under `CI` or prints a loud skip
/// message and returns `false`.
pub fn require(tool: &str, package: &str, test: &str) -> bool {
    if have(tool) {
        return true;
    }
    let message =
        format!("`{tool}` not found (Debian package `{package}`; scripts/test.sh installs it)");
    assert!(std::env::var_os("CI").is_none(), "{test}: {message}");
    eprintln!("\n!!! SKIPPED {test}: {message} !!!\n");
    false
}

/// Every file in `dir` (not recursive), sorted by name, with its bytes.
pub fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| {
            let e = e.unwrap_or_else(|e| panic!("{e}"));
            let name = e.file_name().to_string_lossy().into_owned();
            let bytes = std::fs::read(e.path()).unwrap_or_else(|e| panic!("{name}: {e}"));
            (name, bytes)
        })
        .collect();
    out.sort();
    out
}
