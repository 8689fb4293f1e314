//! gyro-sim: scenes and ship-motion programs, integrators, the run loop and the recorder.
//!
//! It owns what happens to a compass over time: a [`Scene`] (start, ship program, sea,
//! compass design with overrides, fidelity, integrator, tolerances) read from TOML; the
//! ship program that gives the ship's track in closed form; the integrators in
//! [`solvers`] (which see only an `OdeSystem` and hold no physics); the run loop in [`run`]; and
//! [`record`], which writes every run as an MCAP recording through `gyro-mcap` following
//! `docs/recordings.md`. The physics itself is `gyro-model`'s.

pub mod accuracy;
pub mod library;
mod program;
pub mod record;
pub mod run;
mod scene;
pub mod solvers;

pub use record::{RecordOptions, RecordSummary, record};
pub use run::{RunError, RunObserver, RunStats, Simulation};
pub use scene::{Scene, SceneOverrides};
