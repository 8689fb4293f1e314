//! gyro-sim's integration tests, one module per file, linked into one test binary: one
//! link of the crate's dependency tree instead of one per file. Run one file's tests with
//! `cargo test --release -p gyro-sim --test integration FILE::`.

mod support;

mod accuracy;
mod anschutz;
mod bad_input;
mod effects_motor;
mod engine_agreement;
mod handwritten;
mod hard_cases;
mod interop_recording;
mod jacobi;
mod modes_and_stiffness;
mod native_code;
mod record_stats;
mod ship;
mod slough;
mod solvers;
mod solvers_alloc;
mod sperry;
mod three_gyro;
mod twin_gyro;
mod villarceau;
