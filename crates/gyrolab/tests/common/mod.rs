//! Helpers of the tests that run the `gyrolab` binary as a user would.

use std::path::PathBuf;
use std::process::{Command, Output};

/// The built `gyrolab`, run from the repository root (where `scenes/` and `designs/` are).
pub fn gyrolab() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_gyrolab"));
    c.current_dir(gyro_testkit::repo_root!());
    c
}

/// A scratch folder of its own for one test: `<temp>/gyrolab-<suite>-<pid>-<name>`.
pub fn tmp(suite: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gyrolab-{suite}-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).expect("tmp");
    d
}

/// Runs `cmd` to the end and returns its output, failing the test (with its stderr) unless it
/// exited 0.
pub fn succeed(cmd: &mut Command) -> Output {
    let out = cmd.output().expect("gyrolab starts");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}
