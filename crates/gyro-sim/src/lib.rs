//! gyro-sim: scenes and ship-motion programs, integrators, the run loop.
pub mod solvers;
