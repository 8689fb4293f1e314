//! gyro-model's integration tests, one module per file, linked into one test binary: one
//! link of the crate's dependency tree instead of one per file. Run one file's tests with
//! `cargo test --release -p gyro-model --test integration FILE::`.

mod anschutz_statics;
mod linalg_stiff;
mod servo_plate;
mod slough_statics;
mod sperry_statics;
mod villarceau_equation;
