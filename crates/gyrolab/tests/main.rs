//! gyrolab's integration tests, one module per file, linked into one test binary: one
//! link of the crate's dependency tree instead of one per file. Run one file's tests with
//! `cargo test --release -p gyrolab --test integration FILE::`.

mod common;

mod analysis_physics;
mod cli;
mod kill_recover;
mod sweep_cli;
mod sweep_ray;
