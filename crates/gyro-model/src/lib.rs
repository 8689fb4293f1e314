//! gyro-model: the physics of gyrocompasses.
//!
//! It owns the Earth and its frames (`earth`), designs as kinematic chains of bodies and hinges
//! (`design`), the Lagrangian engine that derives equations of motion from kinematics and
//! energies by exact automatic differentiation on dual numbers (`dual`): once in world axes as
//! the plain reference (`reference_engine`), and again in each body's own axes as the model
//! evaluates it (`body_axes`, held to the reference by the tests); the compiled model that a
//! scene's effects and a fidelity select (`model`, with the `gyroscopic` fidelity's reductions in
//! `gyroscopic`), its equations recorded once as straight-line programs (`tape`) and, for the
//! shipped designs, compiled ahead of time (`native`); and the closed-form theory of the
//! reference texts that tests hold the engine to (`theory`).
//!
//! Public are the modules other crates read (`constants`, `earth`, `error`, `linalg`, `theory`)
//! and the items re-exported below; the engine's internals stay inside the crate.
//!
//! It knows nothing of files other than the TOML text of a design, nothing of recordings,
//! integrators or viewers: the simulation crate drives it through [`CompiledModel::rhs`] and
//! [`CompiledModel::jacobian`], and a ship-motion program enters through the [`ShipMotion`] trait.
//! Everything is SI; angles in radians; the world frame is North–West–Up (Beghin's).

// Numerical kernels index several parallel arrays with one loop variable (rows, columns, dual
// directions); iterator chains would hide the formulas. NaN-rejecting checks are written
// `!(x > 0.0)` on purpose.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

mod body_axes;
pub mod constants;
mod design;
mod dual;
pub mod earth;
pub mod error;
mod expr;
mod force_elements;
mod gyroscopic;
pub mod linalg;
mod model;
mod native;
mod reference_engine;
mod tape;
pub mod theory;

pub use design::{
    Compartment, CoordinateRole, CoordinateUnit, Design, Force, Linkage, Pots, Root, Shape,
    SpinMode, Tank, Valves,
};
pub use dual::{Jet, Real, sin_cos};
pub use earth::{BaseEffects, Moored, ShipKinematics, ShipMotion};
pub use error::InputError;
pub use model::{
    BodyPose, CompiledModel, EFFECT_NAMES, Effects, Energetics, Fidelity, InitialCondition,
    ModelError, ModelOptions, Readout, TapeSize, native_source,
};
