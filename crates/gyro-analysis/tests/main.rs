//! gyro-analysis's integration tests, one module per file, linked into one test binary: one
//! link of the crate's dependency tree instead of one per file. Run one file's tests with
//! `cargo test --release -p gyro-analysis --test integration FILE::`.

mod common;

mod bad_input;
mod compare;
mod fit;
mod recordings;
mod regress;
