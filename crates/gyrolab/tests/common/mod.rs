//! Helpers of the tests that run the `gyrolab` binary as a user would.

use std::path::PathBuf;
use std::process::Command;

/// The built `gyrolab`, run from the repository root (where `scenes/` and `designs/` are).
pub fn gyrolab() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_gyrolab"));
    c.current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
    c
}

/// A scratch folder of its own for one test: `<temp>/gyrolab-<suite>-<pid>-<name>`.
pub fn tmp(suite: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gyrolab-{suite}-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).expect("tmp");
    d
}
