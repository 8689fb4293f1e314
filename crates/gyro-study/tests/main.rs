//! gyro-study's integration tests, one module per file, linked into one test binary. Run one
//! file's tests with `cargo test --release -p gyro-study --test integration FILE::`.

mod common;

mod comparison;
mod local;
mod shipped;
mod study_file;
