//! gyro-model: the physics of gyrocompasses.
//!
//! It owns the Earth and its frames (`earth`), designs as kinematic chains of bodies and hinges
//! (`design`), the Lagrangian engine that derives equations of motion from kinematics and
//! energies by exact automatic differentiation (`engine`, `real`), the compiled model that a
//! scene's effects and a fidelity select (`model`), and the closed-form theory of the reference
//! texts that tests hold the engine to (`theory`).
//!
//! It knows nothing of files other than the TOML text of a design, nothing of recordings,
//! integrators or viewers: the simulation crate drives it through [`CompiledModel::rhs`] and
//! [`CompiledModel::jacobian`], and a ship-motion program enters through the [`ShipMotion`] trait.
//! Everything is SI; angles in radians; the world frame is North–West–Up (Beghin's).

// Numerical kernels index several parallel arrays with one loop variable (rows, columns, dual
// directions); iterator chains would hide the formulas. NaN-rejecting checks are written
// `!(x > 0.0)` on purpose.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod constants;
pub mod design;
pub mod earth;
pub mod engine;
pub mod error;
pub mod expr;
pub mod kinetics;
pub mod linalg;
pub mod model;
pub mod real;
pub mod theory;

pub use design::{CoordinateRole, Design, Root, Shape, SpinMode};
pub use earth::{BaseEffects, Moored, ShipKinematics, ShipMotion};
pub use error::InputError;
pub use model::{
    BodyPose, CompiledModel, EFFECT_NAMES, Effects, Fidelity, InitialCondition, ModelError,
    ModelOptions, Readout,
};
pub use real::{Jet, Real};
