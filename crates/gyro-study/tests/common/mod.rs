//! Helpers of gyro-study's tests.

use gyro_study::{Plan, Study};
use std::path::PathBuf;

/// A scratch folder of its own for one test (emptied first).
pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gyro-study-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp");
    d
}

/// A study from text, as if read from `file` (relative paths resolve from the repository root).
pub fn study(text: &str) -> Result<Plan, gyro_model::InputError> {
    let file = gyro_testkit::repo_root!().join("sweeps/test.toml");
    Plan::new(Study::from_toml(&file.to_string_lossy(), text)?)
}

/// The error of a study that must be refused.
#[track_caller]
pub fn refused(text: &str) -> gyro_model::InputError {
    match study(text) {
        Ok(p) => panic!("accepted a bad study ({} runs)", p.total_runs()),
        Err(e) => e,
    }
}

/// A small, fast study: the Anschütz in harbour for three hours at two latitudes and two offsets.
pub const HARBOUR: &str = r#"
name = "harbour-small"
scenes = ["harbour-50n"]

[[axis]]
key = "duration_s"
values = [10800.0]

[[axis]]
key = "start.latitude_deg"
values = [30.0, 50.0]

[[axis]]
key = "compass.azimuth_offset_deg"
from = 2.0
to = 6.0
count = 3
"#;
