//! Test-only helpers shared by the workspace's integration tests: one pinned Python venv for
//! every interop test, and skips that turn into failures under CI.
//!
//! A dev-dependency only (`publish = false`, no dependencies beyond std): no library or binary
//! of the workspace links it.
//!
//! - [`venv`] makes (once) and reuses a virtual environment with pinned requirements in the
//!   target directory's `tmp/` (the folder cargo names `CARGO_TARGET_TMPDIR` for integration
//!   tests; outside the clone when `CARGO_TARGET_DIR` is, as `.ci/run` sets it), so a workspace
//!   test run downloads each package once. [`interop_python`] is that venv with [`INTEROP`], the
//!   one set every interop test uses.
//! - [`unavailable`] is how a test that cannot run here says so: a visible `SKIPPED:` line, or,
//!   with `CI=true` in the environment, a panic, so that CI never passes a test it did not run.
//! - [`manifest_dir!`] and [`repo_root!`] are where the test's crate and the repository are
//!   *now*: cargo does not rebuild a workspace member that moved (a fresh clone beside another
//!   reusing one target directory, as `.ci/run` does), so `env!("CARGO_MANIFEST_DIR")` can name
//!   the checkout that last built the test, or one that is gone. Cargo sets the variable again
//!   when it runs a test; these read that.

use std::fs::{self, OpenOptions};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

/// `mcap`, the reference Python MCAP library.
pub const MCAP: &str = "mcap==1.6.0";
/// Its protobuf decoder.
pub const MCAP_PROTOBUF_SUPPORT: &str = "mcap-protobuf-support==0.6.0";
/// The protobuf runtime `mcap-protobuf-support` decodes with.
pub const PROTOBUF: &str = "protobuf==7.36.2";
/// Rerun's Python SDK at the version of the `rerun` crate the workspace builds against.
pub const RERUN_SDK: &str = "rerun-sdk==0.36.3";

/// Ray, pinned: the engine of `gyrolab sweep run --engine ray` (its tests start a local cluster).
pub const RAY: &str = "ray==2.60.0";
/// pyarrow and pandas: a sweep's `metrics.parquet` must read there too.
pub const PYARROW: &str = "pyarrow==26.0.1";
pub const PANDAS: &str = "pandas==3.1.1";

/// Everything the sweep tests install, in one venv.
pub const SWEEP: [&str; 3] = [RAY, PYARROW, PANDAS];

/// Everything the interop tests install, in one venv.
pub const INTEROP: [&str; 4] = [MCAP, MCAP_PROTOBUF_SUPPORT, PROTOBUF, RERUN_SDK];

/// The calling crate's manifest folder as cargo gives it to the running test (see the crate
/// doc); the one compiled in when the test binary is run by hand, outside cargo.
#[macro_export]
macro_rules! manifest_dir {
    () => {
        $crate::runtime_manifest_dir(env!("CARGO_MANIFEST_DIR"))
    };
}

/// The repository's root folder (two above a crate's manifest folder: `crates/NAME`).
#[macro_export]
macro_rules! repo_root {
    () => {
        $crate::manifest_dir!().join("../..")
    };
}

#[doc(hidden)]
pub fn runtime_manifest_dir(compiled: &str) -> PathBuf {
    std::env::var_os("CARGO_MANIFEST_DIR").map_or_else(|| PathBuf::from(compiled), PathBuf::from)
}

/// Whether this is a CI run (`CI=true`, as `.ci/run`'s environment sets it).
pub fn ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v.eq_ignore_ascii_case("true") || v == "1")
}

/// A test's prerequisite is missing: under CI, panics with `why`; elsewhere prints
/// `SKIPPED: why` (stdout and stderr) and returns, for the test to return early.
#[track_caller]
pub fn unavailable(why: &str) {
    if ci() {
        panic!("{why} (CI=true: a test that cannot run fails)");
    }
    println!("SKIPPED: {why}");
    eprintln!("SKIPPED: {why}");
}

/// The python of the venv [`INTEROP`] is installed in (see [`venv`]).
#[track_caller]
pub fn interop_python() -> Option<PathBuf> {
    venv("interop-venv", &INTEROP)
}

/// The python of the venv `name` with exactly `requirements` pip-installed, made on first use
/// and reused after (a `.requirements` file in the venv lists what was installed; a different
/// list installs again). Where it cannot be had (no python3, no venv module, pip failing) it
/// calls [`unavailable`] with the reason and returns `None`, so under CI it panics.
///
/// One caller at a time makes or checks a venv, across threads and test processes (a lock file
/// beside it).
#[track_caller]
pub fn venv(name: &str, requirements: &[&str]) -> Option<PathBuf> {
    match make_venv(&cache_dir(), name, requirements) {
        Ok(python) => Some(python),
        Err(why) => {
            unavailable(&format!(
                "no Python venv `{name}` with {}: {why}",
                requirements.join(" ")
            ));
            None
        }
    }
}

/// `<target>/tmp`: the test executable runs from `<target>/<profile>/deps/`. Falls back to the
/// system's temporary folder for an executable found elsewhere.
fn cache_dir() -> PathBuf {
    let exe = std::env::current_exe().ok();
    let target = exe.as_deref().and_then(|exe| {
        let deps = exe
            .ancestors()
            .find(|p| p.file_name().is_some_and(|n| n == "deps"))?;
        Some(deps.parent()?.parent()?.to_path_buf())
    });
    match target {
        Some(t) => t.join("tmp"),
        None => std::env::temp_dir().join("gyrolab-test-venvs"),
    }
}

fn make_venv(cache: &Path, name: &str, requirements: &[&str]) -> Result<PathBuf, String> {
    static IN_PROCESS: Mutex<()> = Mutex::new(());
    let _one_thread = IN_PROCESS.lock().unwrap_or_else(|e| e.into_inner());
    fs::create_dir_all(cache).map_err(|e| format!("cannot create {}: {e}", cache.display()))?;
    let lock_path = cache.join(format!("{name}.lock"));
    let lock = OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&lock_path)
        .map_err(|e| format!("cannot open {}: {e}", lock_path.display()))?;
    lock.lock()
        .map_err(|e| format!("cannot lock {}: {e}", lock_path.display()))?;
    let result = make_venv_locked(&cache.join(name), requirements);
    drop(lock); // closing the file releases the lock
    result
}

fn make_venv_locked(venv: &Path, requirements: &[&str]) -> Result<PathBuf, String> {
    let python = venv.join("bin").join("python");
    let marker = venv.join(".requirements");
    // The marker names the venv's own folder too: a venv moved with its target directory keeps
    // console scripts (`rerun`) whose first line runs the old folder's python, so it is made anew.
    let wanted = format!("{}\n{}", venv.display(), requirements.join("\n"));
    let found = fs::read_to_string(&marker).ok();
    if python.exists() && found.as_deref() == Some(wanted.as_str()) {
        return Ok(python);
    }
    let made_here = found
        .as_deref()
        .and_then(|m| m.lines().next())
        .is_some_and(|first| Path::new(first) == venv);
    if venv.exists() && !made_here {
        fs::remove_dir_all(venv).map_err(|e| format!("cannot remove {}: {e}", venv.display()))?;
    }
    if !python.exists() {
        let out = Command::new("python3")
            .args(["-m", "venv"])
            .arg(venv)
            .output()
            .map_err(|e| format!("python3 not found ({e})"))?;
        if !out.status.success() {
            return Err(format!(
                "`python3 -m venv {}` failed:\n{}",
                venv.display(),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
    }
    let out = Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
        ])
        .args(requirements)
        .output()
        .map_err(|e| format!("cannot run {}: {e}", python.display()))?;
    if !out.status.success() {
        return Err(format!(
            "`pip install {}` failed:\n{}{}",
            requirements.join(" "),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    fs::write(&marker, wanted).map_err(|e| format!("cannot write {}: {e}", marker.display()))?;
    Ok(python)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_test_executable_caches_under_its_target_tmp() {
        let dir = cache_dir();
        assert_eq!(dir.file_name().and_then(|n| n.to_str()), Some("tmp"));
        let exe = std::env::current_exe().expect("exe");
        assert!(exe.starts_with(dir.parent().expect("target")));
    }
}
