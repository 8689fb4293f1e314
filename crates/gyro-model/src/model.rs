//! The compiled model: a design, the effects a scene calls for, a fidelity and a ship-motion
//! program, turned into a first-order system ẋ = f(t, x) with an exact Jacobian.
//!
//! Immutable after [`CompiledModel::compile`] (MuJoCo's model/data split): states are plain
//! slices the integrator owns. Stages per evaluation: base motion (only the effects compiled in)
//! → chain kinematics and energies on dual numbers, in body axes (`body_axes`; the world-axes
//! `reference_engine` is what the tests hold it to) → equations of the non-driven coordinates
//! with servo relations folded in → solve for accelerations (or precession rates).
//!
//! State layout: `full` and `linear`: [q; q̇] over the non-driven coordinates; `gyroscopic`:
//! [q; q̇ₘ] where the precessional coordinates (those the spin couples gyroscopically) have
//! first-order equations and only the others keep their rates.

use crate::body_axes::{self, BodyAxesChain};
use crate::design::{CoordinateRole, Design, Force, Root, SpinMode};
use crate::dual::{Jet, M3, Real, V3, rot_axis};
use crate::earth::{BaseEffects, ShipMotion, apparent_gravity, base_motion};
use crate::gyroscopic;
use crate::linalg::{self, solve_in_place};
use crate::reference_engine::{
    Chain, EvalInput, EvalOutput, MAX_COORDINATES, body_poses, evaluate_any,
};
use crate::tape::{self, Tape, Tr};
use std::fmt;
use std::str::FromStr;
use std::sync::OnceLock;

/// Calls `$m!(N, D)` with the dual-number width N ≥ the chain's coordinate count and the number
/// D of state directions a Jacobian pass carries, from a few buckets: one instantiation per
/// size would make the generic engine slow to compile; the waste is at most a third of the
/// derivative work.
macro_rules! by_width {
    ($n:expr, $m:ident) => {
        match $n {
            0..=2 => $m!(2, 4),
            3 => $m!(3, 6),
            4 => $m!(4, 8),
            5..=6 => $m!(6, 8),
            7..=8 => $m!(8, 8),
            9..=11 => $m!(11, 8),
            _ => $m!(15, 8),
        }
    };
}

/// Model fidelity (design.md §6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Fidelity {
    /// All inertias; nutation resolved.
    Full,
    /// Quadratic kinetic energy of the gyroscopically coupled coordinates dropped: first-order
    /// precession equations for them.
    Gyroscopic,
    /// The exact Jacobian at the equilibrium: a linear state-space model.
    Linear,
}

impl FromStr for Fidelity {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "full" => Ok(Fidelity::Full),
            "gyroscopic" => Ok(Fidelity::Gyroscopic),
            "linear" => Ok(Fidelity::Linear),
            _ => Err(format!(
                "unknown fidelity `{s}` (allowed: full, gyroscopic, linear)"
            )),
        }
    }
}

impl fmt::Display for Fidelity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Fidelity::Full => "full",
            Fidelity::Gyroscopic => "gyroscopic",
            Fidelity::Linear => "linear",
        })
    }
}

/// Every effect a scene can call for, by the name used in scene files and recordings.
pub const EFFECT_NAMES: [&str; 9] = [
    "earth_rotation",
    "transport_rate",
    "ship_acceleration",
    "turn_rate",
    "roll_pitch",
    "base_coriolis",
    "damper",
    "friction",
    "spin_motor",
];

/// The effects compiled into a model. Absent effects are never evaluated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Effects {
    pub base: BaseEffects,
    /// Circulatory damping elements of the design (air jets, generalised forces).
    pub damper: bool,
    /// Viscous friction elements of the design.
    pub friction: bool,
    /// Spin motors of the design's rotors (their spin becomes a state); without it, or without
    /// a motor in the design, every rotor's spin is held at its rated value.
    pub spin_motor: bool,
}

impl Effects {
    pub fn all() -> Effects {
        Effects {
            base: BaseEffects {
                earth_rotation: true,
                transport_rate: true,
                ship_acceleration: true,
                turn_rate: true,
                roll_pitch: true,
                base_coriolis: true,
            },
            damper: true,
            friction: true,
            spin_motor: true,
        }
    }
    pub fn get(&self, name: &str) -> Option<bool> {
        let b = &self.base;
        Some(match name {
            "earth_rotation" => b.earth_rotation,
            "transport_rate" => b.transport_rate,
            "ship_acceleration" => b.ship_acceleration,
            "turn_rate" => b.turn_rate,
            "roll_pitch" => b.roll_pitch,
            "base_coriolis" => b.base_coriolis,
            "damper" => self.damper,
            "friction" => self.friction,
            "spin_motor" => self.spin_motor,
            _ => return None,
        })
    }
    pub fn set(&mut self, name: &str, on: bool) -> Result<(), String> {
        let b = &mut self.base;
        match name {
            "earth_rotation" => b.earth_rotation = on,
            "transport_rate" => b.transport_rate = on,
            "ship_acceleration" => b.ship_acceleration = on,
            "turn_rate" => b.turn_rate = on,
            "roll_pitch" => b.roll_pitch = on,
            "base_coriolis" => b.base_coriolis = on,
            "damper" => self.damper = on,
            "friction" => self.friction = on,
            "spin_motor" => self.spin_motor = on,
            _ => {
                return Err(format!(
                    "unknown effect `{name}` (allowed: {})",
                    EFFECT_NAMES.join(", ")
                ));
            }
        }
        Ok(())
    }
    /// Names of the active effects, in the canonical order.
    pub fn names(&self) -> Vec<&'static str> {
        EFFECT_NAMES
            .iter()
            .copied()
            .filter(|n| self.get(n) == Some(true))
            .collect()
    }
    fn include_force(&self, f: &Force) -> bool {
        match f {
            Force::Damper { .. } => self.friction,
            Force::BodyForce { .. } | Force::Generalized { .. } => self.damper,
            Force::Spring { .. } | Force::LinkSpring { .. } | Force::Servo { .. } => true,
        }
    }
}

/// Where the run starts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InitialCondition {
    /// Start from the apparent equilibrium of the design at t = 0 (else from all coordinates 0).
    pub from_equilibrium: bool,
    /// Offsets added to coordinates (full index, rad).
    pub offsets_rad: Vec<(usize, f64)>,
    /// Initial rates (full index, rad/s).
    pub rates_rad_per_s: Vec<(usize, f64)>,
    /// Start the precessional coordinates at the rates their first-order (precession) equations
    /// give, instead of at rest: a `full` model then starts on the slow motion, without the
    /// nutation that releasing a held gyro excites.
    pub slow_start: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub struct ModelOptions {
    pub fidelity: Fidelity,
    pub effects: Effects,
    /// Compass pivot relative to the ship's roll centre, ship axes (x fwd, y port, z up), m.
    pub pivot_m: [f64; 3],
    pub initial: InitialCondition,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ModelError {
    TooManyCoordinates(usize),
    NoEquilibrium(String),
    Singular(String),
    Invalid(String),
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ModelError::TooManyCoordinates(n) => write!(
                f,
                "the design has {n} coordinates; the engine supports at most {MAX_COORDINATES}"
            ),
            ModelError::NoEquilibrium(s) => write!(f, "no apparent equilibrium found: {s}"),
            ModelError::Singular(s) => write!(f, "singular equations: {s}"),
            ModelError::Invalid(s) => write!(f, "{s}"),
        }
    }
}
impl std::error::Error for ModelError {}

/// The energy balance of a state (full fidelity), from the world-axes reference engine with every
/// coordinate, servo-driven ones included. On a stationary base (a harbour: the Lagrangian does
/// not depend on time) Jacobi's integral h = T₂ − T₀ + V changes only by the work of what is not
/// in the Lagrangian: dh/dt = servo + damper + applied power. T₂ is the kinetic energy of the
/// rates, T₀ that of the frame's rotation with the rotors' held momenta (−T₀ is the Earth rate's
/// directive energy), V the weight and springs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energetics {
    /// Jacobi's integral h = T₂ − T₀ + V, J.
    pub energy_j: f64,
    /// Its terms: T₂, T₀ and V, J (h is their difference: its round-off is relative to them).
    pub kinetic_j: f64,
    pub frame_kinetic_j: f64,
    pub potential_j: f64,
    /// Power the servos put in, W: each driven coordinate's equation residual (the torque its
    /// servo applies) times its rate. Beghin ch. I: d(T − U) + servo work = 0 without losses.
    pub servo_power_w: f64,
    /// Power of the dampers (≤ 0), W.
    pub damper_power_w: f64,
    /// Power of the body forces and generalised forces (air jets, circulatory torques), W.
    pub applied_power_w: f64,
}

/// What the card shows and what the chain does at one instant.
#[derive(Clone, Debug, PartialEq)]
pub struct Readout {
    /// Compass heading minus true heading, rad (positive: the card reads too high / easterly).
    pub reading_error_rad: f64,
    /// Tilt of the north-seeking axis, North end down positive, rad.
    pub tilt_rad: f64,
    pub true_heading_rad: f64,
    pub compass_heading_rad: f64,
    /// All coordinates (servo-driven included), rad.
    pub q: Vec<f64>,
    /// All rates, rad/s.
    pub qd: Vec<f64>,
    /// Every body's pose as [`CompiledModel::body_poses`] gives it (the reading needs them, so
    /// a recorder need not compute them again).
    pub poses: Vec<BodyPose>,
}

/// Where a body is at one instant: `point_in_world = world_from_body · point_in_body +
/// origin_m`, world axes (the local level frame at the pivot, North–West–Up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyPose {
    /// Rotation from the body's axes to the world's (rows are world axes).
    pub world_from_body: [[f64; 3]; 3],
    /// The body's origin relative to the pivot, world axes, metres.
    pub origin_m: [f64; 3],
}

#[derive(Clone, Debug)]
struct StationaryBase {
    r: M3<Jet<f64, 1>>,
    w: V3<Jet<f64, 1>>,
    g: [f64; 3],
}

/// A rotor whose spin is a state: dΩ/dt = (Ω_rated − Ω)/τ, H = C·Ω.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpinMotor {
    pub body: usize,
    pub polar_inertia_kg_m2: f64,
    pub rated_spin_rad_per_s: f64,
    pub time_constant_s: f64,
    pub initial_spin_rad_per_s: f64,
}

/// Most spin motors a model compiles (their states live in fixed arrays per evaluation).
pub const MAX_MOTORS: usize = 4;

/// Most states a model has: rates and coordinates of every coordinate, and the motors' spins.
const MAX_STATES: usize = 2 * MAX_COORDINATES + MAX_MOTORS;

/// Most states whose Jacobi integral's gradient [`CompiledModel::jacobi_integral`] forms.
const JACOBI_MAX_STATES: usize = 8;

/// The base's motion as the equations take it: its rotation and rate to the world, each with
/// its time derivative, the apparent gravity (world axes); then ġ, R̈ and ω̈, zero unless the
/// model carries its gyros ([`crate::gyroscopic::shifted_base`] is their only reader).
pub(crate) type Base<T> = (
    M3<Jet<T, 1>>,
    V3<Jet<T, 1>>,
    [T; 3],
    [T; 3],
    [[T; 3]; 3],
    [T; 3],
);

/// Scalars of a [`Base`] when it is a tape's input (a moving base): R and Ṙ, ω and ω̇, g, ġ,
/// R̈, ω̈.
const BASE_INPUTS: usize = 42;

/// Writes a base's scalars in the tape's input order.
fn base_scalars<T: Real>(b: &Base<T>, out: &mut [T]) {
    for i in 0..3 {
        for j in 0..3 {
            out[3 * i + j] = b.0.0[i][j].v;
            out[9 + 3 * i + j] = b.0.0[i][j].d[0];
        }
        out[18 + i] = b.1.0[i].v;
        out[21 + i] = b.1.0[i].d[0];
        out[24 + i] = b.2[i];
        out[27 + i] = b.3[i];
        for j in 0..3 {
            out[30 + 3 * i + j] = b.4[i][j];
        }
        out[39 + i] = b.5[i];
    }
}

/// The base read back from a tape's inputs (the inverse of [`base_scalars`]).
fn base_from_scalars<T: Real>(s: &[T]) -> Base<T> {
    (
        M3(std::array::from_fn(|i| {
            std::array::from_fn(|j| Jet {
                v: s[3 * i + j],
                d: [s[9 + 3 * i + j]],
            })
        })),
        V3(std::array::from_fn(|i| Jet {
            v: s[18 + i],
            d: [s[21 + i]],
        })),
        [s[24], s[25], s[26]],
        [s[27], s[28], s[29]],
        std::array::from_fn(|i| std::array::from_fn(|j| s[30 + 3 * i + j])),
        [s[39], s[40], s[41]],
    )
}

/// A design compiled for a scene: immutable; evaluate it with any state.
#[derive(Clone, Debug)]
pub struct CompiledModel<M: ShipMotion> {
    pub design: Design,
    pub chain: Chain,
    pub motion: M,
    pub fidelity: Fidelity,
    pub effects: Effects,
    pub pivot_m: [f64; 3],
    /// Full indices of the non-driven coordinates.
    pub independent: Vec<usize>,
    /// q_full = S q_ind + s0.
    servo_s: Vec<f64>,
    servo_s0: Vec<f64>,
    /// Per independent coordinate: precessional (first-order in `gyroscopic` fidelity).
    pub precessional: Vec<bool>,
    /// Independent indices of the precessional coordinates, and of the others.
    precessional_rows: Vec<usize>,
    inertial_rows: Vec<usize>,
    drop_full: Vec<bool>,
    /// `gyroscopic` fidelity carries the precessional coordinates along the inertial ones (the
    /// slow manifold to first order, [`crate::gyroscopic::carried_rates`]): on a rolling base,
    /// for designs with both kinds of coordinate.
    carried: bool,
    /// The chain compiled for evaluation in body axes (what `rhs` and `jacobian` use).
    body_axes: BodyAxesChain,
    /// No servo relation: the reduced equations are the chain's own.
    no_servo: bool,
    /// Spin motors compiled in: their spins are the last states of every layout.
    pub motors: Vec<SpinMotor>,
    pub spin_momentum: Vec<f64>,
    stationary: Option<StationaryBase>,
    /// `linear` fidelity: A (dim×dim) about x_eq, row-major, and the transpose of its rows
    /// from `linear_kinematic` on (the right-hand side runs down A's columns).
    linear_a: Vec<f64>,
    linear_at: Vec<f64>,
    /// Leading rows of A that are q̇ = v exactly (row i the unit vector at column m + i; 0 if
    /// they are not): the right-hand side copies them instead of summing a row of zeros.
    linear_kinematic: usize,
    /// Apparent equilibrium state (full-fidelity layout).
    pub x_equilibrium: Vec<f64>,
    /// Initial state in this model's layout.
    pub x0: Vec<f64>,
    /// The equations recorded once per fidelity evaluated (`tape`): what `rhs` and `jacobian`
    /// run. Inputs: the state, then the base's scalars when it moves.
    tapes: Vec<(Fidelity, Tape)>,
    /// Whether `rhs` runs the running fidelity's tape or the engine (see [`rhs_tape_pays`]).
    rhs_by_tape: bool,
    /// The running fidelity's Jacobian as tapes of [`tape::JET_WIDTH`] columns each, recorded
    /// at first use (explicit integrators never ask); `None` inside if not recorded.
    jacobian_tapes: OnceLock<Option<JacobianTapes>>,
    /// Jacobi's integral and its gradient as one tape (outputs h, ∂h/∂x), recorded at first use
    /// by [`Self::jacobi_integral`]; `None` inside for a model that does not keep the integral.
    jacobi_tape: OnceLock<Option<Tape>>,
}

/// The running fidelity's Jacobian tapes and whether `jacobian` runs them (decided once, when
/// they are recorded: [`jacobian_tape_pays`]).
#[derive(Clone, Debug)]
struct JacobianTapes {
    blocks: Vec<Tape>,
    used: bool,
}

/// Sizes of a recorded tape against the engine it replaces ([`CompiledModel::tape_size`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TapeSize {
    /// Operations on the tape (after folding, sharing and dead-code removal; a dense solve
    /// counts one).
    pub ops: usize,
    /// Arithmetic the generic engine performs for the same outputs (a dense solve by its
    /// elimination's count).
    pub engine_ops: usize,
    /// Whether the model evaluates by the tape ([`rhs_tape_pays`], [`jacobian_tape_pays`]).
    pub used: bool,
    /// Whether the tape runs as native code generated ahead of time (`crate::native`; all of
    /// a Jacobian's tapes, for a Jacobian).
    pub native: bool,
}

/// The text of `gyro-model/src/native/generated.rs` for these models: native code for every
/// right-hand side they record, and their Jacobians where the flag says so, one function per
/// distinct shape. The generator behind `tests/native_code.rs` in `gyro-sim`; see
/// `crate::native`.
pub fn native_source<M: ShipMotion>(models: &[(&CompiledModel<M>, bool)]) -> String {
    let tapes: Vec<&Tape> = models
        .iter()
        .flat_map(|&(m, jacobian)| m.all_tapes(jacobian))
        .collect();
    crate::native::source(&tapes)
}

/// How many of the engine's operations one Jacobian tape operation must replace before the
/// tape is the faster way. An interpreted operation (a dispatch, loads, a store) costs ≈ 2 ns
/// here, an engine operation 0.12–0.23 ns (the engine runs eight dual-number lanes at once and
/// skips zeros the recording cannot prove zero). Measured, not guessed: `cargo bench -p gyro-sim
/// --bench handwritten` prints both times and both counts for ten models. The counts do not
/// separate them perfectly (the tape ran faster at 16.2 engine operations per tape operation,
/// slower at 14.9 and at 21.0); at 16 the rule picks the faster side in nine of ten, and the
/// tenth (the Sperry 1911 on a moving base, gyroscopic) runs the tape 7 % slower.
const JACOBIAN_TAPE_MIN_RATIO: f64 = 16.0;

/// Whether Jacobian tapes of these sizes run faster than the engine. A rule on the counts,
/// not a timing: the tapes agree with the engine to 1e-13, not to the bit, and a run must not
/// depend on how busy the machine was when it compiled.
fn jacobian_tape_pays(tape_ops: usize, engine_ops: usize) -> bool {
    engine_ops as f64 >= JACOBIAN_TAPE_MIN_RATIO * tape_ops as f64
}

/// Whether the right-hand side's tape runs faster than the engine, timed at compile (best of
/// seven rounds each, alternated, a fraction of a millisecond to a few). The counts do not
/// decide it (the twin-gyro's tape ties the engine at 11 engine operations per tape operation,
/// the Anschütz 1906's loses 1.6× at 7 and the three-gyro's wins 1.3× at 30); a timing may,
/// because the tape's result equals the engine's to the bit: whichever runs, the run is the
/// same.
fn rhs_tape_pays(mut tape: impl FnMut(), mut engine: impl FnMut()) -> bool {
    const CALLS: usize = 16;
    let mut best = [f64::INFINITY; 2];
    for _ in 0..7 {
        for (k, f) in [&mut tape as &mut dyn FnMut(), &mut engine]
            .into_iter()
            .enumerate()
        {
            let start = std::time::Instant::now();
            for _ in 0..CALLS {
                f();
            }
            best[k] = best[k].min(start.elapsed().as_secs_f64());
        }
    }
    best[0] < best[1]
}

/// The spin motors a run simulates (none unless the effect is on): one per rotor with a motor.
fn spin_motors(design: &Design, on: bool) -> Result<Vec<SpinMotor>, ModelError> {
    if !on {
        return Ok(Vec::new());
    }
    let motors: Vec<SpinMotor> = design
        .bodies
        .iter()
        .enumerate()
        .filter_map(|(bi, b)| {
            let r = b.rotor.as_ref()?;
            let m = r.motor?;
            Some(SpinMotor {
                body: bi,
                polar_inertia_kg_m2: r.polar_inertia_kg_m2,
                rated_spin_rad_per_s: r.spin_rad_per_s,
                time_constant_s: m.time_constant_s,
                initial_spin_rad_per_s: m.initial_spin_rad_per_s,
            })
        })
        .collect();
    if motors.len() > MAX_MOTORS {
        return Err(ModelError::Invalid(format!(
            "the design has {} spin motors; at most {MAX_MOTORS} are supported",
            motors.len()
        )));
    }
    Ok(motors)
}

/// The servo relations as an affine map from the independent coordinates to all of them:
/// q = S q_ind + s0.
struct ServoSubstitution {
    /// The design coordinates no servo drives, in order (the state's coordinates).
    independent: Vec<usize>,
    /// S, row-major, n × n_ind.
    s: Vec<f64>,
    /// s0, n.
    s0: Vec<f64>,
}

fn servo_substitution(design: &Design) -> Result<ServoSubstitution, ModelError> {
    let n = design.coordinates.len();
    let independent: Vec<usize> = (0..n)
        .filter(|&i| design.coordinates[i].servo.is_none())
        .collect();
    let ni = independent.len();
    let mut servo_s = vec![0.0; n * ni];
    let mut servo_s0 = vec![0.0; n];
    for (col, &i) in independent.iter().enumerate() {
        servo_s[i * ni + col] = 1.0;
    }
    for (i, c) in design.coordinates.iter().enumerate() {
        if let Some(rel) = &c.servo {
            servo_s0[i] = rel.constant;
            for &(j, a) in &rel.linear {
                let col = independent.iter().position(|&x| x == j).ok_or_else(|| {
                    ModelError::Invalid(format!(
                        "servo relation of `{}` reads a driven coordinate",
                        c.name
                    ))
                })?;
                servo_s[i * ni + col] += a;
            }
        }
    }
    Ok(ServoSubstitution {
        independent,
        s: servo_s,
        s0: servo_s0,
    })
}

impl<M: ShipMotion> CompiledModel<M> {
    pub fn compile(design: Design, motion: M, opts: ModelOptions) -> Result<Self, ModelError> {
        let n = design.coordinates.len();
        if n > MAX_COORDINATES {
            return Err(ModelError::TooManyCoordinates(n));
        }
        let mut effects = opts.effects;
        let motors = spin_motors(&design, effects.spin_motor)?;
        // Reported effects are what is compiled: no motor state without a motor.
        effects.spin_motor = !motors.is_empty();
        let chain = Chain::from_design(&design, |f| effects.include_force(f));
        let body_axes = BodyAxesChain::from_design(&design, |f| effects.include_force(f));
        let ServoSubstitution {
            independent,
            s: servo_s,
            s0: servo_s0,
        } = servo_substitution(&design)?;
        let ni = independent.len();
        let stationary = if motion.is_stationary() {
            let (r, w) = base_motion(&motion, design.root == Root::Ship, &effects.base, 0.0f64);
            Some(StationaryBase {
                r,
                w,
                g: apparent_gravity(&motion, &effects.base, opts.pivot_m, 0.0),
            })
        } else {
            None
        };
        let spin_momentum = design
            .bodies
            .iter()
            .map(|b| {
                b.rotor
                    .as_ref()
                    .map_or(0.0, |r| r.polar_inertia_kg_m2 * r.spin_rad_per_s)
            })
            .collect();
        let mut model = CompiledModel {
            design,
            chain,
            motion,
            fidelity: Fidelity::Full,
            effects,
            pivot_m: opts.pivot_m,
            independent,
            servo_s,
            servo_s0,
            precessional: vec![false; ni],
            precessional_rows: Vec::new(),
            inertial_rows: (0..ni).collect(),
            drop_full: Vec::new(),
            carried: false,
            body_axes,
            no_servo: ni == n,
            motors,
            spin_momentum,
            stationary,
            linear_a: Vec::new(),
            linear_at: Vec::new(),
            linear_kinematic: 0,
            x_equilibrium: Vec::new(),
            x0: Vec::new(),
            tapes: Vec::new(),
            rhs_by_tape: false,
            jacobian_tapes: OnceLock::new(),
            jacobi_tape: OnceLock::new(),
        };
        let mut x = model.initial_state(&opts.initial)?;
        model.classify_precessional(&x);
        if opts.initial.slow_start {
            model.slow_start(&mut x);
        }
        model.set_fidelity(opts.fidelity, x)?;
        model.record_tapes();
        Ok(model)
    }

    /// Records the equations the run evaluates: its fidelity's, or for a `linear` model on a
    /// moving base the `full` ones that give its forcing. A tape that does not reproduce the
    /// generic evaluation at the recording state to the bit is not kept (the generic path then
    /// runs; `tests/tape.rs` makes sure that never happens for a shipped scene).
    fn record_tapes(&mut self) {
        let Some((fidelity, at, inputs)) = self.recording_point() else {
            return;
        };
        let dim = at.len();
        let tape = tape::on_large_stack(|| {
            tape::record(&inputs, dim, |inp, out| {
                let base = if self.stationary.is_some() {
                    self.base_at(Tr::cst(0.0))
                } else {
                    base_from_scalars(&inp[dim..])
                };
                macro_rules! go {
                    ($n:literal, $d:literal) => {
                        self.rhs_n::<Tr, $n>(fidelity, &base, &inp[..dim], out)
                    };
                }
                by_width!(self.chain.n, go);
            })
        });
        let (mut by_tape, mut generic) = (vec![0.0; dim], vec![0.0; dim]);
        let ok_tape = tape.eval(&inputs, &mut by_tape);
        let ok_generic = self.rhs_generic(fidelity, 0.0, &at, &mut generic);
        let same = by_tape
            .iter()
            .zip(&generic)
            .all(|(a, b)| a.to_bits() == b.to_bits() || a == b);
        debug_assert!(
            ok_tape == ok_generic && same,
            "tape differs from the engine: {by_tape:?} vs {generic:?}"
        );
        if ok_tape == ok_generic && same {
            let mut dx = vec![0.0; dim];
            self.rhs_by_tape = rhs_tape_pays(
                || {
                    std::hint::black_box(tape.eval(std::hint::black_box(&inputs), &mut dx));
                },
                || {
                    let mut dx = [0.0; MAX_STATES];
                    std::hint::black_box(self.rhs_generic(
                        fidelity,
                        0.0,
                        std::hint::black_box(&at),
                        &mut dx[..dim],
                    ));
                },
            );
            self.tapes.push((fidelity, tape));
        }
    }

    /// The fidelity whose equations are recorded, the state they are recorded at (t = 0) and
    /// the tape's inputs there; `None` for a `linear` model on a stationary base.
    fn recording_point(&self) -> Option<(Fidelity, Vec<f64>, Vec<f64>)> {
        let (fidelity, at) = match self.fidelity {
            Fidelity::Linear if self.stationary.is_some() => return None,
            Fidelity::Linear => (Fidelity::Full, self.x_equilibrium.clone()),
            f => (f, self.x0.clone()),
        };
        let dim = self.dim_at(fidelity);
        let mut inputs = at.clone();
        if self.stationary.is_none() {
            inputs.resize(dim + BASE_INPUTS, 0.0);
            base_scalars(&self.equation_base_at(0.0), &mut inputs[dim..]);
        }
        Some((fidelity, at, inputs))
    }

    /// Records the running fidelity's Jacobian, [`tape::JET_WIDTH`] columns a tape, from the
    /// engine on dual numbers over the recording scalar. Kept only if it reproduces the
    /// engine's dual-number Jacobian at the recording state to 1e-12 of its largest entry.
    fn record_jacobian(&self) -> Option<Vec<Tape>> {
        if self.fidelity == Fidelity::Linear {
            return None;
        }
        self.recorded_tape(self.fidelity)?;
        let (fidelity, at, inputs) = self.recording_point()?;
        let dim = at.len();
        let blocks = tape::on_large_stack(|| self.record_jacobian_blocks(fidelity, dim, &inputs));
        let mut by_tape = vec![0.0; dim * dim];
        let mut generic = vec![0.0; dim * dim];
        if !Self::run_jacobian(&blocks, &inputs, dim, &mut by_tape) {
            return None;
        }
        self.jacobian_at(fidelity, 0.0, &at, &mut generic);
        let scale = generic.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = by_tape
            .iter()
            .zip(&generic)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        debug_assert!(
            worst <= 1e-12 * scale,
            "Jacobian tape differs from the engine by {worst:e} (scale {scale:e})"
        );
        (worst <= 1e-12 * scale).then_some(blocks)
    }

    /// The recorded Jacobian tapes, recording them (and deciding whether they run) on first use.
    fn recorded_jacobian(&self) -> Option<&JacobianTapes> {
        self.jacobian_tapes
            .get_or_init(|| {
                let blocks = self.record_jacobian()?;
                let ops = blocks.iter().map(Tape::len).sum();
                let engine_ops = blocks.iter().map(Tape::raw_len).sum();
                // Native code runs fewer operations than the engine, each as fast.
                let used =
                    blocks.iter().all(Tape::is_native) || jacobian_tape_pays(ops, engine_ops);
                Some(JacobianTapes { blocks, used })
            })
            .as_ref()
    }

    /// The Jacobian tapes if `jacobian` runs them.
    fn jacobian_by_tape(&self) -> Option<&[Tape]> {
        self.recorded_jacobian()
            .filter(|j| j.used)
            .map(|j| &j.blocks[..])
    }

    /// The Jacobian's tapes, [`tape::JET_WIDTH`] state directions each.
    fn record_jacobian_blocks(&self, fidelity: Fidelity, dim: usize, inputs: &[f64]) -> Vec<Tape> {
        const W: usize = tape::JET_WIDTH;
        let mut blocks = Vec::new();
        let mut first = 0;
        while first < dim {
            let cols = W.min(dim - first);
            blocks.push(tape::record(inputs, dim * cols, |inp, out| {
                let zero = Jet::<Tr, W>::constant(Tr::cst(0.0));
                let mut x = [zero; MAX_STATES];
                for i in 0..dim {
                    x[i] = if i >= first && i - first < W {
                        Jet::variable(inp[i], i - first)
                    } else {
                        Jet::constant(inp[i])
                    };
                }
                let base = if self.stationary.is_some() {
                    self.base_at(Jet::<Tr, W>::cst(0.0))
                } else {
                    let lifted: [Jet<Tr, W>; BASE_INPUTS] =
                        std::array::from_fn(|k| Jet::constant(inp[dim + k]));
                    base_from_scalars(&lifted)
                };
                let mut dx = [zero; MAX_STATES];
                macro_rules! go {
                    ($n:literal, $d:literal) => {
                        self.rhs_n::<Jet<Tr, W>, $n>(fidelity, &base, &x[..dim], &mut dx[..dim])
                    };
                }
                by_width!(self.chain.n, go);
                for row in 0..dim {
                    out[row * cols..(row + 1) * cols].copy_from_slice(&dx[row].d[..cols]);
                }
            }));
            first += W;
        }
        blocks
    }

    /// Runs Jacobian tapes at `inputs` into `jac` (dim×dim). False if a solve is singular.
    /// Block b holds columns b·W.. of every row (row-major, dim × its column count); a single
    /// block is the whole Jacobian and writes it in place.
    fn run_jacobian(blocks: &[Tape], inputs: &[f64], dim: usize, jac: &mut [f64]) -> bool {
        const W: usize = tape::JET_WIDTH;
        if let [block] = blocks {
            return block.eval(inputs, jac);
        }
        let mut out = [0.0; MAX_STATES * W];
        for (b, block) in blocks.iter().enumerate() {
            let first = b * W;
            let cols = W.min(dim - first);
            if !block.eval(inputs, &mut out[..dim * cols]) {
                return false;
            }
            for row in 0..dim {
                jac[row * dim + first..row * dim + first + cols]
                    .copy_from_slice(&out[row * cols..(row + 1) * cols]);
            }
        }
        true
    }

    /// Sizes of the running fidelity's Jacobian tapes, recording them if not yet done; `None`
    /// if they cannot be recorded (a `linear` model, or one whose equations are not recorded).
    pub fn jacobian_tape_size(&self) -> Option<TapeSize> {
        let j = self.recorded_jacobian()?;
        Some(TapeSize {
            ops: j.blocks.iter().map(Tape::len).sum(),
            engine_ops: j.blocks.iter().map(Tape::raw_len).sum(),
            used: j.used,
            native: j.blocks.iter().all(Tape::is_native),
        })
    }

    /// The recorded equations of a fidelity, whether or not `rhs` runs them.
    fn recorded_tape(&self, fidelity: Fidelity) -> Option<&Tape> {
        self.tapes
            .iter()
            .find(|(f, _)| *f == fidelity)
            .map(|(_, t)| t)
    }

    /// The equations `rhs_at` runs by tape for a fidelity, if it does.
    fn tape(&self, fidelity: Fidelity) -> Option<&Tape> {
        self.recorded_tape(fidelity).filter(|_| self.rhs_by_tape)
    }

    /// Sizes of the recorded equations of a fidelity, if they are recorded.
    pub fn tape_size(&self, fidelity: Fidelity) -> Option<TapeSize> {
        self.recorded_tape(fidelity).map(|t| TapeSize {
            ops: t.len(),
            engine_ops: t.raw_len(),
            used: self.tape(fidelity).is_some(),
            native: t.is_native(),
        })
    }

    /// ẋ by the recorded tape whether or not `rhs` uses it (`None` if not recorded): what the
    /// tests hold to the engine.
    pub fn rhs_tape(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Option<bool> {
        let tape = self.recorded_tape(self.running_recorded())?;
        Some(self.with_tape_inputs(t, x, |inputs| tape.eval(inputs, dx)))
    }

    /// ẋ by the recorded tape's interpreter, even where native code runs it: what the tests
    /// hold the native code to (`None` if not recorded).
    pub fn rhs_tape_interpreted(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Option<bool> {
        let tape = self.recorded_tape(self.running_recorded())?;
        Some(self.with_tape_inputs(t, x, |inputs| tape.interpret(inputs, dx)))
    }

    /// The Jacobian by the recorded tapes whether or not `jacobian` uses them; false if they
    /// are not recorded or a solve is singular at x.
    pub fn jacobian_tape(&self, t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        let Some(j) = self.recorded_jacobian() else {
            return false;
        };
        self.with_tape_inputs(t, x, |inputs| {
            Self::run_jacobian(&j.blocks, inputs, x.len(), jac)
        })
    }

    /// Every tape recorded for this model: each fidelity's right-hand side and, if asked, the
    /// running fidelity's Jacobian (recorded now if not yet). What [`native_source`] writes out.
    fn all_tapes(&self, jacobian: bool) -> Vec<&Tape> {
        let mut all: Vec<&Tape> = self.tapes.iter().map(|(_, t)| t).collect();
        if let Some(j) = self.recorded_jacobian().filter(|_| jacobian) {
            all.extend(&j.blocks);
        }
        all
    }

    /// The fidelity whose equations a run records (a `linear` model's are the `full` ones).
    fn running_recorded(&self) -> Fidelity {
        match self.fidelity {
            Fidelity::Linear => Fidelity::Full,
            f => f,
        }
    }

    /// Calls `f` with the tapes' inputs at (t, x): x itself on a stationary base, x and then
    /// the base's scalars on a moving one.
    fn with_tape_inputs<R>(&self, t: f64, x: &[f64], f: impl FnOnce(&[f64]) -> R) -> R {
        if self.stationary.is_some() {
            return f(x);
        }
        let dim = x.len();
        let mut inputs = [0.0; MAX_STATES + BASE_INPUTS];
        inputs[..dim].copy_from_slice(x);
        base_scalars(
            &self.equation_base_at(t),
            &mut inputs[dim..dim + BASE_INPUTS],
        );
        f(&inputs[..dim + BASE_INPUTS])
    }

    /// ẋ by the generic engine (not the recorded tape): what the tape is held to.
    pub fn rhs_engine(&self, t: f64, x: &[f64], dx: &mut [f64]) -> bool {
        if self.fidelity == Fidelity::Linear {
            return self.rhs_linear(t, x, dx);
        }
        self.rhs_generic(self.fidelity, t, x, dx)
    }

    /// The exact Jacobian by the generic engine (not the recorded tape).
    pub fn jacobian_engine(&self, t: f64, x: &[f64], jac: &mut [f64]) {
        if self.fidelity == Fidelity::Linear {
            jac.copy_from_slice(&self.linear_a);
            return;
        }
        self.jacobian_at(self.fidelity, t, x, jac);
    }

    /// ẋ of a fidelity: by its tape when recorded, by the generic engine otherwise.
    fn rhs_at(&self, fidelity: Fidelity, t: f64, x: &[f64], dx: &mut [f64]) -> bool {
        match self.tape(fidelity) {
            Some(tape) => self.with_tape_inputs(t, x, |inputs| tape.eval(inputs, dx)),
            None => self.rhs_generic(fidelity, t, x, dx),
        }
    }

    /// The initial state in the full layout [q; q̇; Ω of each motor]: the equilibrium at rated
    /// spin when asked for, then the start's motor spins, offsets and rates.
    fn initial_state(&mut self, initial: &InitialCondition) -> Result<Vec<f64>, ModelError> {
        let ni = self.independent.len();
        let mut x = vec![0.0; 2 * ni + self.motors.len()];
        for (k, m) in self.motors.iter().enumerate() {
            x[2 * ni + k] = m.rated_spin_rad_per_s;
        }
        self.update_free_rotors(&x);
        if initial.from_equilibrium {
            // On a ship-rooted chain the azimuth is counted from the ship's head: start the
            // search on the meridian, not on the lubber line.
            if self.design.root == Root::Ship
                && let Some(i) = self.role(CoordinateRole::Azimuth)
                && let Some(col) = self.independent.iter().position(|&j| j == i)
            {
                x[col] = self.motion.kinematics(0.0f64).heading_rad;
            }
            // The equilibrium of the mean motion: without the sea, whose phase at t = 0 is no
            // state to settle on (a ship-rooted small gyro would start deflected by the roll
            // rate's gyroscopic torque, jω·Γ̇ ≈ 0.01 N·m: a radian on the Sperry's spring).
            let sea = std::mem::replace(&mut self.effects.base.roll_pitch, false);
            let q = self.equilibrium(&x[..ni]);
            self.effects.base.roll_pitch = sea;
            let q = q?;
            x[..ni].copy_from_slice(&q);
            self.update_free_rotors(&x);
        }
        self.x_equilibrium = x.clone();
        for (k, m) in self.motors.iter().enumerate() {
            x[2 * ni + k] = m.initial_spin_rad_per_s;
        }
        for &(i, off) in &initial.offsets_rad {
            x[self.independent_column(i, "offset")?] += off;
        }
        for &(i, rate) in &initial.rates_rad_per_s {
            x[ni + self.independent_column(i, "set the rate of")?] = rate;
        }
        Ok(x)
    }

    /// The state column of design coordinate `i`, or an error naming it when a servo drives it
    /// (`what` is the verb of the message: "cannot {what} the servo-driven coordinate …").
    fn independent_column(&self, i: usize, what: &str) -> Result<usize, ModelError> {
        self.independent
            .iter()
            .position(|&j| j == i)
            .ok_or_else(|| {
                ModelError::Invalid(format!(
                    "cannot {what} the servo-driven coordinate `{}`",
                    self.design.coordinates[i].name
                ))
            })
    }

    /// Which coordinates the spin couples gyroscopically at the start `x` (full layout), and the
    /// rows that follow from that. A free rotor's absolute spin is fixed by the start first:
    /// relative spin + carrier rate.
    fn classify_precessional(&mut self, x: &[f64]) {
        let (n, ni) = (self.design.coordinates.len(), self.independent.len());
        self.update_free_rotors(x);
        self.precessional = self.find_precessional(x);
        self.precessional_rows = (0..ni).filter(|&j| self.precessional[j]).collect();
        self.inertial_rows = (0..ni).filter(|&j| !self.precessional[j]).collect();
        self.drop_full = vec![false; n];
        for (col, &i) in self.independent.iter().enumerate() {
            self.drop_full[i] = self.precessional[col];
        }
        // Only a rolling base turns fast enough for the precession equations' kept base-rate
        // terms (T₀, T₁) to matter against their dropped T₂ (docs/designs.md, "gyroscopic
        // fidelity on a rolling sea"), and only where the sea turns a spin axis: elsewhere (a
        // calm sea included) the plain reduction is kept, Lagrangian and four times cheaper.
        self.carried = self.effects.base.roll_pitch
            && self.motion.rolls()
            && !self.precessional_rows.is_empty()
            && !self.inertial_rows.is_empty()
            && self.sea_turns_spin_axes();
    }

    /// Whether the sea can turn a rotor's spin axis at its own frequency: a ship-rooted chain
    /// (the base rolls with the ship), or a hinge driven by an inertial coordinate on the way
    /// from a rotor to the base that is not provably about that rotor's own axis (the same axis
    /// with no moving hinge between). An Earth-rooted float that heels about its spin axis (the
    /// Anschütz 1906) leaves the precession axes where the Earth and the track turn them, and
    /// the carried reduction moves its rolling error by 1e-4 of itself at four times the cost.
    fn sea_turns_spin_axes(&self) -> bool {
        if self.chain.ship_root {
            return true;
        }
        let ni = self.independent.len();
        let inertial = |coordinate: usize| {
            (0..ni).any(|col| !self.precessional[col] && self.servo_s[coordinate * ni + col] != 0.0)
        };
        let bodies = &self.design.bodies;
        for (b, body) in bodies.iter().enumerate() {
            let Some(rotor) = &body.rotor else { continue };
            // The spin axis in the current body's frame while no moving hinge lies between.
            let mut axis = Some(rotor.axis);
            let mut cur = Some(b);
            while let Some(c) = cur {
                let body = &bodies[c];
                if let Some(h) = &body.hinge {
                    let swings = h.angle.coordinates().into_iter().any(inertial);
                    let about_axis = axis.is_some_and(|a| {
                        let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
                        (0..3).all(|k| k == h.axis || a[k].abs() <= 1e-12 * n)
                    });
                    if swings && !about_axis {
                        return true;
                    }
                    if !h.angle.is_constant() {
                        axis = None;
                    } else if let Some(a) = axis {
                        let r = rot_axis(h.axis, h.angle.constant);
                        axis = Some(std::array::from_fn(|i| {
                            (0..3).map(|k| r.0[i][k] * a[k]).sum()
                        }));
                    }
                }
                let j = body.joint_rotation;
                axis = axis.map(|a| std::array::from_fn(|i| (0..3).map(|k| j[i][k] * a[k]).sum()));
                cur = body.parent;
            }
        }
        false
    }

    /// The gyroscopic layout of a full-layout state: q, the rates of the inertial coordinates,
    /// the motors' spins.
    fn gyroscopic_state(&self, x: &[f64]) -> Vec<f64> {
        let ni = self.independent.len();
        let mut xg: Vec<f64> = x[..ni].to_vec();
        for col in 0..ni {
            if !self.precessional[col] {
                xg.push(x[ni + col]);
            }
        }
        xg.extend_from_slice(&x[2 * ni..]);
        xg
    }

    /// Starts the precessional coordinates at the rates the gyroscopic equations give them.
    fn slow_start(&self, x: &mut [f64]) {
        if !self.precessional.iter().any(|p| *p) {
            return;
        }
        let ni = self.independent.len();
        let xg = self.gyroscopic_state(x);
        let mut dx = vec![0.0; xg.len()];
        if self.rhs_generic(Fidelity::Gyroscopic, 0.0, &xg, &mut dx) {
            for col in 0..ni {
                if self.precessional[col] {
                    x[ni + col] = dx[col];
                }
            }
        }
    }

    /// Sets the fidelity the model runs at and its initial state `x0` in that layout (`x` is
    /// the full-layout start); the linear model's matrix is the full Jacobian at equilibrium.
    fn set_fidelity(&mut self, fidelity: Fidelity, x: Vec<f64>) -> Result<(), ModelError> {
        self.fidelity = fidelity;
        match fidelity {
            Fidelity::Full => self.x0 = x,
            Fidelity::Gyroscopic => {
                if !self.precessional.iter().any(|p| *p) {
                    // Nothing is gyroscopically coupled (e.g. a one-coordinate gyroscope):
                    // the gyroscopic model is the full one.
                    self.fidelity = Fidelity::Full;
                    self.x0 = x;
                } else {
                    self.x0 = self.gyroscopic_state(&x);
                    // Check the precessional block is solvable now rather than mid-run.
                    let mut dx = vec![0.0; self.dim()];
                    if !self.rhs_generic(Fidelity::Gyroscopic, 0.0, &self.x0, &mut dx) {
                        return Err(ModelError::Singular("the precessional equations cannot be solved for their rates (use fidelity = full)".into()));
                    }
                }
            }
            Fidelity::Linear => {
                let xe = self.x_equilibrium.clone();
                let dim = x.len();
                let mut a = vec![0.0; dim * dim];
                self.jacobian_at(Fidelity::Full, 0.0, &xe, &mut a);
                let m = kinematic_rows(&a, dim);
                let r = dim - m;
                self.linear_kinematic = m;
                self.linear_at = (0..dim * r).map(|k| a[(m + k % r) * dim + k / r]).collect();
                self.linear_a = a;
                self.x0 = x;
            }
        }
        Ok(())
    }

    pub fn dim(&self) -> usize {
        let ni = self.independent.len();
        let nm = self.motors.len();
        match self.fidelity {
            Fidelity::Gyroscopic => ni + self.precessional.iter().filter(|p| !**p).count() + nm,
            _ => 2 * ni + nm,
        }
    }

    /// Names of the state components, for recordings.
    pub fn state_names(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .independent
            .iter()
            .map(|&i| self.design.coordinates[i].name.clone())
            .collect();
        for (col, &i) in self.independent.iter().enumerate() {
            if self.fidelity != Fidelity::Gyroscopic || !self.precessional[col] {
                v.push(format!("{}_rate", self.design.coordinates[i].name));
            }
        }
        for m in &self.motors {
            v.push(format!("{}_spin", self.design.bodies[m.body].name));
        }
        v
    }

    /// The A matrix of the `linear` fidelity (empty otherwise).
    pub fn linear_matrix(&self) -> &[f64] {
        &self.linear_a
    }

    /// True when the compiled model is autonomous (nothing depends on time).
    pub fn is_autonomous(&self) -> bool {
        self.stationary.is_some()
    }

    /// ẋ = f(t, x). Returns false when the equations are singular at this state.
    pub fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> bool {
        if self.fidelity == Fidelity::Linear {
            return self.rhs_linear(t, x, dx);
        }
        self.rhs_at(self.fidelity, t, x, dx)
    }

    fn rhs_linear(&self, t: f64, x: &[f64], dx: &mut [f64]) -> bool {
        let dim = self.dim();
        let xe = &self.x_equilibrium;
        if self.stationary.is_some() {
            for i in 0..dim {
                dx[i] = 0.0;
            }
        } else {
            // The forcing of the scene, taken by the nonlinear model at the equilibrium state.
            if !self.rhs_at(Fidelity::Full, t, xe, dx) {
                return false;
            }
        }
        // A (x − x_e) down A's columns, every row's sum in its own accumulator: each row is
        // summed in the same order as a row-by-row product (the same result to the bit), but
        // the rows' chains of additions run side by side. The sizes models have are
        // monomorphised so the accumulators live in registers. The kinematic rows (q̇ = v: the
        // first n of 2n states, or of 2n + 1 with a spin motor) are copied, which is their row
        // sum to the bit (a sum of 0·yⱼ and one 1·y is y): on the engine's 8-state linear
        // Anschütz under Rodas5P at 1e-3 (97 right-hand sides) a whole run took 11.56 µs
        // against 11.87 (best of 10⁵, four alternations, 2026-12-07; the peer benchmark's case,
        // throwaway example not kept).
        macro_rules! sized {
            ($($k:literal $r:literal)*) => {
                match (dim, dim - self.linear_kinematic) {
                    $(($k, $r) => add_matvec::<$k, $r>(&self.linear_at, x, xe, dx),)*
                    _ => {
                        let (x, xe) = (&x[..dim], &xe[..dim]);
                        for (d, row) in dx[..dim].iter_mut().zip(self.linear_a.chunks_exact(dim)) {
                            let mut s = 0.0;
                            for ((a, xj), ej) in row.iter().zip(x).zip(xe) {
                                s += a * (xj - ej);
                            }
                            *d += s;
                        }
                    }
                }
            };
        }
        sized!(
            1 1 2 2 3 3 4 4 5 5 6 6 7 7 8 8 9 9 10 10 11 11 12 12 13 13 14 14 15 15 16 16
            2 1 4 2 6 3 8 4 10 5 12 6 14 7 16 8
            3 2 5 3 7 4 9 5 11 6 13 7 15 8
        );
        true
    }

    /// True when [`Self::jacobian`] is the same matrix at every t and x: a `linear` model's A.
    pub fn jacobian_is_constant(&self) -> bool {
        self.fidelity == Fidelity::Linear
    }

    /// Exact Jacobian df/dx (row-major dim×dim): forward-mode dual numbers through the
    /// recorded tape (through the generic engine if none is recorded).
    pub fn jacobian(&self, t: f64, x: &[f64], jac: &mut [f64]) {
        if self.fidelity == Fidelity::Linear {
            jac.copy_from_slice(&self.linear_a);
            return;
        }
        let Some(blocks) = self.jacobian_by_tape() else {
            return self.jacobian_at(self.fidelity, t, x, jac);
        };
        let ok = self.with_tape_inputs(t, x, |inputs| {
            Self::run_jacobian(blocks, inputs, x.len(), jac)
        });
        if !ok {
            // Singular at this state: the engine's own elimination says what it can.
            self.jacobian_at(self.fidelity, t, x, jac);
        }
    }

    /// Exact Jacobian of the equations at a given fidelity (`full` or `gyroscopic`), by dual
    /// numbers carrying several state directions at once (one pass for up to 8 states).
    pub fn jacobian_at(&self, fidelity: Fidelity, t: f64, x: &[f64], jac: &mut [f64]) {
        macro_rules! go {
            ($n:literal, $d:literal) => {
                self.jacobian_n::<$n, $d>(fidelity, t, x, jac)
            };
        }
        by_width!(self.chain.n, go)
    }

    fn jacobian_n<const N: usize, const D: usize>(
        &self,
        fidelity: Fidelity,
        t: f64,
        x: &[f64],
        jac: &mut [f64],
    ) {
        let dim = self.dim_at(fidelity);
        let base = self.equation_base_at(Jet::<f64, D>::constant(t));
        let mut xj = [Jet::<f64, D>::constant(0.0); MAX_STATES];
        let mut dxj = [Jet::<f64, D>::constant(0.0); MAX_STATES];
        let mut first = 0;
        while first < dim {
            for i in 0..dim {
                let mut d = [0.0; D];
                if i >= first && i - first < D {
                    d[i - first] = 1.0;
                }
                xj[i] = Jet { v: x[i], d };
            }
            self.rhs_n::<Jet<f64, D>, N>(fidelity, &base, &xj[..dim], &mut dxj[..dim]);
            for row in 0..dim {
                for col in first..dim.min(first + D) {
                    jac[row * dim + col] = dxj[row].d[col - first];
                }
            }
            first += D;
        }
    }

    fn dim_at(&self, fidelity: Fidelity) -> usize {
        let ni = self.independent.len();
        let nm = self.motors.len();
        if fidelity == Fidelity::Gyroscopic {
            ni + self.inertial_rows.len() + nm
        } else {
            2 * ni + nm
        }
    }

    /// Expands independent coordinates to all coordinates.
    fn expand<T: Real>(&self, q_ind: &[T], out: &mut [T], with_offset: bool) {
        let n = self.chain.n;
        let ni = self.independent.len();
        for i in 0..n {
            let mut s = if with_offset {
                T::cst(self.servo_s0[i])
            } else {
                T::zero()
            };
            for j in 0..ni {
                let a = self.servo_s[i * ni + j];
                if a != 0.0 {
                    s += q_ind[j] * a;
                }
            }
            out[i] = s;
        }
    }

    /// The base at t without the rates only the carried reduction reads (ġ, R̈, ω̈ are zero):
    /// what poses, gravity, energies and the statics need.
    fn base_at<T: Real>(&self, t: T) -> Base<T> {
        self.base_with(t, false)
    }

    /// The base at t as the equations read it: with ġ, R̈ and ω̈ when the model is carried.
    fn equation_base_at<T: Real>(&self, t: T) -> Base<T> {
        self.base_with(t, self.carried)
    }

    fn base_with<T: Real>(&self, t: T, carried: bool) -> Base<T> {
        match &self.stationary {
            Some(s) => {
                let lift = |x: Jet<f64, 1>| Jet {
                    v: T::cst(x.v),
                    d: [T::cst(x.d[0])],
                };
                (
                    M3(s.r.0.map(|r| r.map(lift))),
                    V3(s.w.0.map(lift)),
                    s.g.map(T::cst),
                    [T::zero(); 3],
                    [[T::zero(); 3]; 3],
                    [T::zero(); 3],
                )
            }
            None => {
                let (r, w) = base_motion(&self.motion, self.chain.ship_root, &self.effects.base, t);
                let gravity =
                    |t| apparent_gravity(&self.motion, &self.effects.base, self.pivot_m, t);
                let g = gravity(t.re());
                let mut g_dot = [T::zero(); 3];
                let mut r_dd = [[T::zero(); 3]; 3];
                let mut w_dd = [T::zero(); 3];
                if carried {
                    // Central difference over ±1 ms: the sea's periods are seconds, so the
                    // truncation is ~(2π·1e-3/T)²/6 < 1e-7 of ġ and the round-off ~1e-12 m/s³.
                    const H: f64 = 1e-3;
                    let (gp, gm) = (gravity(t.re() + H), gravity(t.re() - H));
                    g_dot = std::array::from_fn(|i| T::cst((gp[i] - gm[i]) / (2.0 * H)));
                    // R̈ and ω̈ exactly: the base's motion on a time jet.
                    let tj = Jet {
                        v: t.re(),
                        d: [1.0],
                    };
                    let (r2, w2) =
                        base_motion(&self.motion, self.chain.ship_root, &self.effects.base, tj);
                    r_dd = r2.0.map(|row| row.map(|x| T::cst(x.d[0].d[0])));
                    w_dd = w2.0.map(|x| T::cst(x.d[0].d[0]));
                }
                (r, w, g.map(T::cst), g_dot, r_dd, w_dd)
            }
        }
    }

    /// Forms the reduced equations with the world-axes reference engine
    /// ([`crate::reference_engine::evaluate`]): M_red (ni×ni), K_red (ni×ni), c_red (ni) at
    /// (base, q_ind, qd_ind, u_ind).
    #[allow(clippy::too_many_arguments)]
    fn reduced_reference<T: Real>(
        &self,
        drop_precessional_inertia: bool,
        base: &Base<T>,
        q_ind: &[T],
        qd_ind: &[T],
        u_ind: &[T],
        m_red: &mut [T],
        k_red: &mut [T],
        c_red: &mut [T],
    ) {
        const MX: usize = MAX_COORDINATES + 1;
        let n = self.chain.n;
        let ni = self.independent.len();
        let mut q = [T::zero(); MX];
        let mut qd = [T::zero(); MX];
        let mut u = [T::zero(); MX];
        self.expand(q_ind, &mut q[..n], true);
        self.expand(qd_ind, &mut qd[..n], false);
        self.expand(u_ind, &mut u[..n], false);
        let (r, w, g, ..) = base;
        let mut m = [T::zero(); MX * MX];
        let mut k = [T::zero(); MX * MX];
        let mut c = [T::zero(); MX];
        let inp = EvalInput {
            q: &q[..n],
            qd: &qd[..n],
            u: &u[..n],
            drop_quadratic: if drop_precessional_inertia {
                &self.drop_full
            } else {
                &[]
            },
            spin_momentum: &self.spin_momentum,
            world_from_base: r,
            base_rate: w,
            gravity: *g,
        };
        let mut out = EvalOutput {
            m: &mut m[..n * n],
            k: &mut k[..n * n],
            c: &mut c[..n],
            energies: [T::zero(); 3],
        };
        evaluate_any(&self.chain, &inp, &mut out);
        // Rows of the non-driven coordinates only; driven columns folded into their drivers.
        let s = &self.servo_s;
        for (ri, &i) in self.independent.iter().enumerate() {
            c_red[ri] = c[i];
            for cj in 0..ni {
                let mut sm = T::zero();
                let mut sk = T::zero();
                for l in 0..n {
                    let a = s[l * ni + cj];
                    if a != 0.0 {
                        sm += m[i * n + l] * a;
                        sk += k[i * n + l] * a;
                    }
                }
                m_red[ri * ni + cj] = sm;
                k_red[ri * ni + cj] = sk;
            }
        }
    }

    /// ẋ by the world-axes reference engine, an independent derivation of the same equations:
    /// tests hold [`CompiledModel::rhs`] (the body-axes engine) to it, and nested duals give its
    /// Jacobian. Generic so that nothing instantiates it unless a test calls it.
    pub fn rhs_reference<T: Real>(&self, fidelity: Fidelity, t: T, x: &[T], dx: &mut [T]) -> bool {
        const MX: usize = MAX_COORDINATES + 1;
        let ni = self.independent.len();
        let mut m = [T::zero(); MX * MX];
        let mut k = [T::zero(); MX * MX];
        let mut c = [T::zero(); MX];
        let q = &x[..ni];
        let base = self.equation_base_at(t);
        match fidelity {
            Fidelity::Gyroscopic if self.carried => {
                let eval = |drop: bool,
                            shift: f64,
                            q: &[T],
                            qd: &[T],
                            mn: &mut [[T; MX]; MX],
                            kn: &mut [[T; MX]; MX],
                            cn: &mut [T; MX]| {
                    let b = gyroscopic::shifted_base(&base, shift);
                    self.reduced_reference(
                        drop,
                        &b,
                        q,
                        qd,
                        qd,
                        &mut m[..ni * ni],
                        &mut k[..ni * ni],
                        &mut c[..ni],
                    );
                    for i in 0..ni {
                        cn[i] = c[i];
                        for j in 0..ni {
                            mn[i][j] = m[i * ni + j];
                            kn[i][j] = k[i * ni + j];
                        }
                    }
                };
                let mis: Vec<usize> = (0..ni).filter(|&j| !self.precessional[j]).collect();
                let gi: Vec<usize> = (0..ni).filter(|&j| self.precessional[j]).collect();
                gyroscopic::carried_rates::<T, MX>(&gi, &mis, q, &x[ni..ni + mis.len()], eval, dx)
            }
            Fidelity::Gyroscopic => {
                let mut qd = [T::zero(); MX];
                let mut mi = 0;
                for col in 0..ni {
                    if !self.precessional[col] {
                        qd[col] = x[ni + mi];
                        mi += 1;
                    }
                }
                let u = qd;
                self.reduced_reference(
                    true,
                    &base,
                    q,
                    &qd[..ni],
                    &u[..ni],
                    &mut m[..ni * ni],
                    &mut k[..ni * ni],
                    &mut c[..ni],
                );
                let gi: Vec<usize> = (0..ni).filter(|&j| self.precessional[j]).collect();
                let mis: Vec<usize> = (0..ni).filter(|&j| !self.precessional[j]).collect();
                let ng = gi.len();
                let mut a = [T::zero(); MX * MX];
                let mut r = [T::zero(); MX];
                for (a_r, &i) in gi.iter().enumerate() {
                    let mut s = c[i];
                    for &j in &mis {
                        s += k[i * ni + j] * qd[j];
                    }
                    r[a_r] = -s;
                    for (a_c, &j) in gi.iter().enumerate() {
                        a[a_r * ng + a_c] = k[i * ni + j];
                    }
                }
                if !solve_in_place(&mut a[..ng * ng], &mut r[..ng], ng) {
                    return false;
                }
                for (a_r, &i) in gi.iter().enumerate() {
                    qd[i] = r[a_r];
                }
                dx[..ni].copy_from_slice(&qd[..ni]);
                let nm = mis.len();
                if nm > 0 {
                    let mut mm = [T::zero(); MX * MX];
                    let mut rm = [T::zero(); MX];
                    for (a_r, &i) in mis.iter().enumerate() {
                        let mut s = c[i];
                        for j in 0..ni {
                            s += k[i * ni + j] * qd[j];
                        }
                        rm[a_r] = s;
                        for (a_c, &j) in mis.iter().enumerate() {
                            mm[a_r * nm + a_c] = m[i * ni + j];
                        }
                    }
                    if !solve_in_place(&mut mm[..nm * nm], &mut rm[..nm], nm) {
                        return false;
                    }
                    dx[ni..ni + nm].copy_from_slice(&rm[..nm]);
                }
                true
            }
            _ => {
                let qd = &x[ni..2 * ni];
                self.reduced_reference(
                    false,
                    &base,
                    q,
                    qd,
                    qd,
                    &mut m[..ni * ni],
                    &mut k[..ni * ni],
                    &mut c[..ni],
                );
                let mut r = [T::zero(); MX];
                for i in 0..ni {
                    let mut s = c[i];
                    for j in 0..ni {
                        s += k[i * ni + j] * qd[j];
                    }
                    r[i] = s;
                }
                if !solve_in_place(&mut m[..ni * ni], &mut r[..ni], ni) {
                    return false;
                }
                dx[..ni].copy_from_slice(qd);
                dx[ni..2 * ni].copy_from_slice(&r[..ni]);
                true
            }
        }
    }

    /// ẋ at any fidelity but `linear`, on any scalar (dual numbers give the Jacobian).
    pub(crate) fn rhs_generic<T: Real>(
        &self,
        fidelity: Fidelity,
        t: T,
        x: &[T],
        dx: &mut [T],
    ) -> bool {
        let base = self.equation_base_at(t);
        macro_rules! go {
            ($n:literal, $d:literal) => {
                self.rhs_n::<T, $n>(fidelity, &base, x, dx)
            };
        }
        by_width!(self.chain.n, go)
    }

    /// The reduced equations at (t, q_ind, qd_ind, u_ind): M_red, K_red (ni×ni) and c_red (ni),
    /// by the body-axes engine. Without servo relations they are the chain's own equations;
    /// otherwise the driven rows are dropped and their columns folded into their drivers'.
    #[allow(clippy::too_many_arguments)]
    fn reduced_n<T: Real, const N: usize>(
        &self,
        drop_precessional_inertia: bool,
        base: &Base<T>,
        q_ind: &[T],
        qd_ind: &[T],
        u_ind: &[T],
        spins: &[(usize, T, T)],
        m_red: &mut [[T; N]; N],
        k_red: &mut [[T; N]; N],
        c_red: &mut [T; N],
    ) {
        let n = self.chain.n;
        let ni = self.independent.len();
        let (r, w, g, ..) = base;
        let drop: &[bool] = if drop_precessional_inertia {
            &self.drop_full
        } else {
            &[]
        };
        if self.no_servo {
            let inp = EvalInput {
                q: q_ind,
                qd: qd_ind,
                u: u_ind,
                drop_quadratic: drop,
                spin_momentum: &self.spin_momentum,
                world_from_base: r,
                base_rate: w,
                gravity: *g,
            };
            body_axes::evaluate::<T, N>(&self.body_axes, &inp, spins, m_red, k_red, c_red);
            return;
        }
        let mut q = [T::zero(); N];
        let mut qd = [T::zero(); N];
        let mut u = [T::zero(); N];
        self.expand(q_ind, &mut q[..n], true);
        self.expand(qd_ind, &mut qd[..n], false);
        self.expand(u_ind, &mut u[..n], false);
        let inp = EvalInput {
            q: &q[..n],
            qd: &qd[..n],
            u: &u[..n],
            drop_quadratic: drop,
            spin_momentum: &self.spin_momentum,
            world_from_base: r,
            base_rate: w,
            gravity: *g,
        };
        let mut m = [[T::zero(); N]; N];
        let mut k = [[T::zero(); N]; N];
        let mut c = [T::zero(); N];
        body_axes::evaluate::<T, N>(&self.body_axes, &inp, spins, &mut m, &mut k, &mut c);
        let s = &self.servo_s;
        for (ri, &i) in self.independent.iter().enumerate() {
            c_red[ri] = c[i];
            for cj in 0..ni {
                let mut sm = T::zero();
                let mut sk = T::zero();
                for l in 0..n {
                    let a = s[l * ni + cj];
                    if a != 0.0 {
                        sm += m[i][l] * a;
                        sk += k[i][l] * a;
                    }
                }
                m_red[ri][cj] = sm;
                k_red[ri][cj] = sk;
            }
        }
    }

    /// The reduced `full` equations at (t, q_ind, qd_ind): M_red and r_red = c_red + K_red q̇_ind,
    /// by [`body_axes::evaluate_rates`] (K is never formed). Servo relations as in [`Self::reduced_n`].
    fn reduced_rates_n<T: Real, const N: usize>(
        &self,
        base: &Base<T>,
        q_ind: &[T],
        qd_ind: &[T],
        spins: &[(usize, T, T)],
        m_red: &mut [[T; N]; N],
        r_red: &mut [T; N],
    ) {
        let n = self.chain.n;
        let ni = self.independent.len();
        let (rb, w, g, ..) = base;
        if self.no_servo {
            let inp = EvalInput {
                q: q_ind,
                qd: qd_ind,
                u: qd_ind,
                drop_quadratic: &[],
                spin_momentum: &self.spin_momentum,
                world_from_base: rb,
                base_rate: w,
                gravity: *g,
            };
            body_axes::evaluate_rates::<T, N>(&self.body_axes, &inp, spins, m_red, r_red);
            return;
        }
        let mut q = [T::zero(); N];
        let mut qd = [T::zero(); N];
        self.expand(q_ind, &mut q[..n], true);
        self.expand(qd_ind, &mut qd[..n], false);
        let inp = EvalInput {
            q: &q[..n],
            qd: &qd[..n],
            u: &qd[..n],
            drop_quadratic: &[],
            spin_momentum: &self.spin_momentum,
            world_from_base: rb,
            base_rate: w,
            gravity: *g,
        };
        let mut m = [[T::zero(); N]; N];
        let mut r = [T::zero(); N];
        body_axes::evaluate_rates::<T, N>(&self.body_axes, &inp, spins, &mut m, &mut r);
        // q̇ = S q̇_ind, so K q̇ already is K_red q̇_ind: only M's columns are folded.
        let s = &self.servo_s;
        for (ri, &i) in self.independent.iter().enumerate() {
            r_red[ri] = r[i];
            for cj in 0..ni {
                let mut sm = T::zero();
                for l in 0..n {
                    let a = s[l * ni + cj];
                    if a != 0.0 {
                        sm += m[i][l] * a;
                    }
                }
                m_red[ri][cj] = sm;
            }
        }
    }

    fn rhs_n<T: Real, const N: usize>(
        &self,
        fidelity: Fidelity,
        base: &Base<T>,
        x: &[T],
        dx: &mut [T],
    ) -> bool {
        let ni = self.independent.len();
        let mut m = [[T::zero(); N]; N];
        let mut k = [[T::zero(); N]; N];
        let mut c = [T::zero(); N];
        let q = &x[..ni];
        // Spin motors: the last states; H = CΩ and its rate enter the chain's equations.
        let n_motors = self.motors.len();
        let mech = x.len() - n_motors;
        let mut spin_states = [(0usize, T::zero(), T::zero()); MAX_MOTORS];
        for (j, mo) in self.motors.iter().enumerate() {
            let w = x[mech + j];
            let w_dot = (T::cst(mo.rated_spin_rad_per_s) - w) / mo.time_constant_s;
            spin_states[j] = (
                mo.body,
                w * mo.polar_inertia_kg_m2,
                w_dot * mo.polar_inertia_kg_m2,
            );
            dx[mech + j] = w_dot;
        }
        let spins = &spin_states[..n_motors];
        match fidelity {
            Fidelity::Gyroscopic if self.carried => {
                let eval = |drop: bool,
                            shift: f64,
                            q: &[T],
                            qd: &[T],
                            m: &mut [[T; N]; N],
                            k: &mut [[T; N]; N],
                            c: &mut [T; N]| {
                    let mut sp = spin_states;
                    for s in &mut sp[..n_motors] {
                        s.1 += s.2 * shift;
                    }
                    let b = gyroscopic::shifted_base(base, shift);
                    self.reduced_n::<T, N>(drop, &b, q, qd, qd, &sp[..n_motors], m, k, c);
                };
                gyroscopic::carried_rates::<T, N>(
                    &self.precessional_rows,
                    &self.inertial_rows,
                    q,
                    &x[ni..ni + self.inertial_rows.len()],
                    eval,
                    dx,
                )
            }
            Fidelity::Gyroscopic => {
                let gi = &self.precessional_rows;
                let mis = &self.inertial_rows;
                let mut qd = [T::zero(); N];
                for (a, &col) in mis.iter().enumerate() {
                    qd[col] = x[ni + a];
                }
                self.reduced_n::<T, N>(
                    true,
                    base,
                    q,
                    &qd[..ni],
                    &qd[..ni],
                    spins,
                    &mut m,
                    &mut k,
                    &mut c,
                );
                if !gyroscopic::precession_rates(gi, mis, &k, &c, &mut qd) {
                    return false;
                }
                dx[..ni].copy_from_slice(&qd[..ni]);
                gyroscopic::inertial_accelerations(mis, ni, &m, &k, &c, &qd, &mut dx[ni..])
            }
            _ => {
                let qd = &x[ni..2 * ni];
                let mut r = [T::zero(); N];
                self.reduced_rates_n::<T, N>(base, q, qd, spins, &mut m, &mut r);
                // Without servo relations M is the chain's own mass matrix: symmetric
                // positive definite, so LDLᵀ (about half the cost of pivoted LU here).
                let solved = (self.no_servo && linalg::solve_spd_nested(&m, &mut r, ni))
                    || linalg::solve_nested(&mut m, &mut r, ni);
                if !solved {
                    return false;
                }
                dx[..ni].copy_from_slice(qd);
                dx[ni..2 * ni].copy_from_slice(&r[..ni]);
                true
            }
        }
    }

    /// The static equations (rates zero) at t = 0: c (the residual torques) and, if asked, K.
    fn statics(&self, q: &[f64], c_out: &mut [f64], k_out: Option<&mut [f64]>) {
        macro_rules! go {
            ($n:literal, $d:literal) => {
                self.statics_n::<$n>(q, c_out, k_out)
            };
        }
        by_width!(self.chain.n, go)
    }

    fn statics_n<const N: usize>(&self, q: &[f64], c_out: &mut [f64], k_out: Option<&mut [f64]>) {
        let ni = self.independent.len();
        let zero = [0.0; N];
        let mut m = [[0.0; N]; N];
        let mut k = [[0.0; N]; N];
        let mut c = [0.0; N];
        self.reduced_n::<f64, N>(
            false,
            &self.base_at(0.0),
            q,
            &zero[..ni],
            &zero[..ni],
            &[],
            &mut m,
            &mut k,
            &mut c,
        );
        c_out[..ni].copy_from_slice(&c[..ni]);
        if let Some(ko) = k_out {
            for i in 0..ni {
                ko[i * ni..(i + 1) * ni].copy_from_slice(&k[i][..ni]);
            }
        }
    }

    /// ∂c/∂q of the static equations at t = 0 (row-major ni×ni), by dual numbers.
    fn static_stiffness(&self, q: &[f64], jac: &mut [f64]) {
        macro_rules! go {
            ($n:literal, $d:literal) => {
                self.static_stiffness_n::<$n, $d>(q, jac)
            };
        }
        by_width!(self.chain.n, go)
    }

    fn static_stiffness_n<const N: usize, const D: usize>(&self, q: &[f64], jac: &mut [f64]) {
        let ni = self.independent.len();
        let zj = [Jet::<f64, D>::constant(0.0); N];
        let mut qj = [Jet::<f64, D>::constant(0.0); N];
        let mut first = 0;
        while first < ni {
            for i in 0..ni {
                let mut d = [0.0; D];
                if i >= first && i - first < D {
                    d[i - first] = 1.0;
                }
                qj[i] = Jet { v: q[i], d };
            }
            let mut m = [[Jet::<f64, D>::constant(0.0); N]; N];
            let mut k = [[Jet::<f64, D>::constant(0.0); N]; N];
            let mut c = [Jet::<f64, D>::constant(0.0); N];
            self.reduced_n::<Jet<f64, D>, N>(
                false,
                &self.base_at(Jet::constant(0.0)),
                &qj[..ni],
                &zj[..ni],
                &zj[..ni],
                &[],
                &mut m,
                &mut k,
                &mut c,
            );
            for row in 0..ni {
                for col in first..ni.min(first + D) {
                    jac[row * ni + col] = c[row].d[col - first];
                }
            }
            first += D;
        }
    }

    /// Newton's method on the static equations (rates zero) at t = 0, from `q_start`.
    fn equilibrium(&self, q_start: &[f64]) -> Result<Vec<f64>, ModelError> {
        let ni = self.independent.len();
        let mut q = q_start.to_vec();
        let mut c = vec![0.0; ni];
        let residual = |q: &[f64], c: &mut [f64]| self.statics(q, c, None);
        residual(&q, &mut c);
        let scale = c.iter().map(|x| x.abs()).fold(0.0, f64::max).max(1e-300);
        let mut norm = c.iter().map(|x| x * x).sum::<f64>().sqrt();
        // The stiffest restoring term, N·m/rad: a residual at its round-off (1e-12 rad of
        // displacement) is converged however small the start's residual was.
        let mut stiffness: f64 = 0.0;
        for _ in 0..60 {
            // Jacobian of the static torques by dual numbers.
            let mut jac = vec![0.0; ni * ni];
            self.static_stiffness(&q, &mut jac);
            stiffness = (0..ni)
                .map(|i| jac[i * ni + i].abs())
                .fold(stiffness, f64::max);
            let mut step: Vec<f64> = c.iter().map(|x| -x).collect();
            if !solve_in_place(&mut jac, &mut step, ni) {
                return Err(ModelError::NoEquilibrium("the static stiffness matrix is singular (is every coordinate restrained by gravity, a spring or the Earth's rotation?)".into()));
            }
            // Damped Newton: halve until the residual decreases.
            let mut lambda = 1.0;
            loop {
                let trial: Vec<f64> = q.iter().zip(&step).map(|(a, b)| a + lambda * b).collect();
                residual(&trial, &mut c);
                let tn = c.iter().map(|x| x * x).sum::<f64>().sqrt();
                if tn < norm || lambda < 1e-6 {
                    q = trial;
                    norm = tn;
                    break;
                }
                lambda *= 0.5;
            }
            if norm <= 1e-13 * scale || step.iter().all(|s| s.abs() < 1e-15) {
                return Ok(q);
            }
        }
        if norm <= 1e-9 * scale || norm <= 1e-12 * stiffness {
            Ok(q)
        } else {
            Err(ModelError::NoEquilibrium(format!(
                "Newton's method stalled with residual {norm:.3e} N·m"
            )))
        }
    }

    /// Precessional coordinates: rows of the gyroscopic (skew) part of K at rest.
    fn find_precessional(&self, x: &[f64]) -> Vec<bool> {
        let ni = self.independent.len();
        let mut k = vec![0.0; ni * ni];
        let mut c = vec![0.0; ni];
        self.statics(&x[..ni], &mut c, Some(&mut k));
        let skew = |i: usize, j: usize| 0.5 * (k[i * ni + j] - k[j * ni + i]);
        let big = (0..ni)
            .flat_map(|i| (0..ni).map(move |j| (i, j)))
            .map(|(i, j)| skew(i, j).abs())
            .fold(0.0, f64::max);
        let mut precessional = vec![false; ni];
        if big == 0.0 {
            self.first_order_levels(&mut precessional);
            return precessional;
        }
        // The precessional block must be solvable: its skew matrix nonsingular, so its
        // coordinates come in pairs. Pair greedily, the strongest couplings first, pairs of the
        // design's azimuth and tilt before others (a pendulous crosspiece tilts the spin axis as
        // the case does, and only one of the two can lose its inertia), with the
        // threshold at round-off (a small gyro's jω is ~10⁻³ of the main one's, and counts).
        let coordinate = |col: usize| &self.design.coordinates[self.independent[col]];
        let allowed = |col: usize| coordinate(col).precessional != Some(false);
        let roles = |i: usize, j: usize| {
            [i, j]
                .iter()
                .filter(|&&c| coordinate(c).role.is_some())
                .count()
        };
        let mut pairs: Vec<(usize, usize)> = (0..ni)
            .flat_map(|i| (i + 1..ni).map(move |j| (i, j)))
            .filter(|&(i, j)| allowed(i) && allowed(j) && skew(i, j).abs() > 1e-9 * big)
            .collect();
        pairs.sort_by(|a, b| {
            roles(b.0, b.1)
                .cmp(&roles(a.0, a.1))
                .then(skew(b.0, b.1).abs().total_cmp(&skew(a.0, a.1).abs()))
        });
        for (i, j) in pairs {
            if !precessional[i] && !precessional[j] {
                precessional[i] = true;
                precessional[j] = true;
            }
        }
        self.first_order_levels(&mut precessional);
        precessional
    }

    /// A tank's levels lose their flow inertia with the gyroscopic terms: their equations are
    /// Beghin's first-order ones (37), D ḣ = −∂V/∂h, solvable since D is positive definite.
    fn first_order_levels(&self, first_order: &mut [bool]) {
        for t in &self.design.tanks {
            for &l in &t.levels {
                if let Some(col) = self.independent.iter().position(|&i| i == l) {
                    first_order[col] = true;
                }
            }
        }
    }

    /// Sets the momentum of free rotors from a state: relative spin plus the carrier's rate.
    fn update_free_rotors(&mut self, x_full_layout: &[f64]) {
        let ni = self.independent.len();
        if !self
            .design
            .bodies
            .iter()
            .any(|b| b.rotor.as_ref().is_some_and(|r| r.mode == SpinMode::Free))
        {
            return;
        }
        let n = self.chain.n;
        let mut q = vec![0.0; n];
        let mut qd = vec![0.0; n];
        self.expand(&x_full_layout[..ni], &mut q, true);
        self.expand(&x_full_layout[ni..2 * ni], &mut qd, false);
        let (r, w, ..) = self.base_at(0.0f64);
        let rr = M3(r.0.map(|row| row.map(|x| x.v)));
        let wv = V3(w.0.map(|x| x.v));
        let rates =
            crate::reference_engine::body_angular_velocities(&self.chain, &q, &qd, &rr, &wv);
        for (bi, b) in self.design.bodies.iter().enumerate() {
            if let Some(rot) = &b.rotor
                && rot.mode == SpinMode::Free
            {
                let poses = body_poses(&self.chain, &q, &rr);
                let s = M3(poses[bi].0).mul_v(&V3(rot.axis));
                let carrier = s.dot(&V3(rates[bi]));
                self.spin_momentum[bi] = rot.polar_inertia_kg_m2 * (rot.spin_rad_per_s + carrier);
            }
        }
    }

    /// Rates of all independent coordinates at a state (for gyroscopic fidelity they come from
    /// the precession equations).
    pub fn rates(&self, t: f64, x: &[f64]) -> Vec<f64> {
        let mut r = [0.0; MAX_COORDINATES];
        let ni = self.rates_into(t, x, &mut r);
        r[..ni].to_vec()
    }

    /// [`Self::rates`] into `out` (no allocation); returns how many there are.
    fn rates_into(&self, t: f64, x: &[f64], out: &mut [f64; MAX_COORDINATES]) -> usize {
        let ni = self.independent.len();
        match self.fidelity {
            Fidelity::Gyroscopic => {
                let mut dx = [0.0; 2 * MAX_COORDINATES + MAX_MOTORS];
                self.rhs(t, x, &mut dx[..self.dim()]);
                out[..ni].copy_from_slice(&dx[..ni]);
            }
            _ => out[..ni].copy_from_slice(&x[ni..2 * ni]),
        }
        ni
    }

    /// All coordinates and rates (servo-driven included) at a state.
    pub fn full_coordinates(&self, t: f64, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        assert_eq!(
            x.len(),
            self.dim(),
            "a state in the model's own layout (`equilibrium_state()`, not `x_equilibrium`)"
        );
        let n = self.chain.n;
        let ni = self.independent.len();
        let mut q = vec![0.0; n];
        let mut qd = vec![0.0; n];
        self.expand(&x[..ni], &mut q, true);
        let mut r = [0.0; MAX_COORDINATES];
        self.rates_into(t, x, &mut r);
        self.expand(&r[..ni], &mut qd, false);
        (q, qd)
    }

    /// world_from_base at time t (f64).
    pub fn world_from_base(&self, t: f64) -> [[f64; 3]; 3] {
        let (r, ..) = self.base_at(t);
        r.0.map(|row| row.map(|x| x.v))
    }

    /// Apparent gravity at the pivot, world axes.
    pub fn apparent_gravity(&self, t: f64) -> [f64; 3] {
        self.base_at(t).2
    }

    /// Poses of all bodies at a state, by body index.
    pub fn body_poses(&self, t: f64, q_full: &[f64]) -> Vec<BodyPose> {
        body_poses(&self.chain, q_full, &M3(self.world_from_base(t)))
            .into_iter()
            .map(|(world_from_body, origin_m)| BodyPose {
                world_from_body,
                origin_m,
            })
            .collect()
    }

    /// The compass reading at a state.
    pub fn readout(&self, t: f64, x: &[f64]) -> Readout {
        let (q, qd) = self.full_coordinates(t, x);
        let poses = self.body_poses(t, &q);
        let s = M3(poses[self.design.reading_body].world_from_body)
            .mul_v(&V3(self.design.reading_axis));
        let err = s.0[1].atan2(s.0[0]);
        let tilt = (-s.0[2]).clamp(-1.0, 1.0).asin();
        let k = self.motion.kinematics(t);
        let true_heading = k.heading_rad.rem_euclid(std::f64::consts::TAU);
        Readout {
            reading_error_rad: err,
            tilt_rad: tilt,
            true_heading_rad: true_heading,
            compass_heading_rad: (true_heading + err).rem_euclid(std::f64::consts::TAU),
            q,
            qd,
            poses,
        }
    }

    /// The equilibrium in the model's own state layout (`x_equilibrium` is in the full one).
    pub fn equilibrium_state(&self) -> Vec<f64> {
        match self.fidelity {
            Fidelity::Gyroscopic => self.gyroscopic_state(&self.x_equilibrium),
            _ => self.x_equilibrium.clone(),
        }
    }

    /// The energy balance at (t, x) in the model's own layout ([`Energetics`]). In `gyroscopic`
    /// fidelity the model is Lagrange's for L with the precessional coordinates' quadratic kinetic
    /// energy dropped (and that of servo-driven coordinates that follow them), so its h is that
    /// L's energy function, T₂ − T₀ + V with T₂ at the inertial rates only, and the same balance
    /// holds. `None` where the equations are singular.
    pub fn energetics(&self, t: f64, x: &[f64]) -> Option<Energetics> {
        const MX: usize = MAX_COORDINATES + 1;
        let (n, ni) = (self.chain.n, self.independent.len());
        let mut dx = vec![0.0; self.dim()];
        if !self.rhs(t, x, &mut dx) {
            return None;
        }
        let (q_full, qd_full) = self.full_coordinates(t, x);
        let (mut q, mut qd, mut u, mut qdd) = ([0.0; MX], [0.0; MX], [0.0; MX], [0.0; MX]);
        q[..n].copy_from_slice(&q_full);
        qd[..n].copy_from_slice(&qd_full);
        // Which coordinates lost their quadratic kinetic energy, and the accelerations of the
        // others (from ẋ; precessional ones have none and need none).
        let gyroscopic = self.fidelity == Fidelity::Gyroscopic;
        let mut drop = vec![false; n];
        let mut qdd_ind = [0.0; MX];
        let mut inertial = 0;
        for (col, &i) in self.independent.iter().enumerate() {
            if gyroscopic && self.precessional[col] {
                drop[i] = true;
            } else {
                qdd_ind[col] = dx[ni + inertial];
                inertial += 1;
            }
        }
        for (i, c) in self.design.coordinates.iter().enumerate() {
            if let Some(rel) = &c.servo {
                drop[i] = rel.coordinates().iter().any(|&j| drop[j]);
            }
        }
        self.expand(&qdd_ind[..ni], &mut qdd[..n], false);
        for i in 0..n {
            u[i] = if drop[i] { 0.0 } else { qd[i] };
        }
        let drop_quadratic: &[bool] = if gyroscopic { &drop } else { &[] };
        let (r, w, g, ..) = self.base_at(t);
        // The equations of every coordinate, with all forces and with some only: the
        // differences are the dampers' K, the applied forces' c and a finite servo's torque.
        let eval = |chain: &Chain| {
            let (mut m, mut k, mut c) = ([0.0; MX * MX], [0.0; MX * MX], [0.0; MX]);
            let inp = EvalInput {
                q: &q[..n],
                qd: &qd[..n],
                u: &u[..n],
                drop_quadratic,
                spin_momentum: &self.spin_momentum,
                world_from_base: &r,
                base_rate: &w,
                gravity: g,
            };
            let mut out = EvalOutput {
                m: &mut m[..n * n],
                k: &mut k[..n * n],
                c: &mut c[..n],
                energies: [0.0; 3],
            };
            evaluate_any(chain, &inp, &mut out);
            let e = out.energies;
            (m, k, c, e)
        };
        let (m, k, c, [t2, t0, v]) = eval(&self.chain);
        let only = |keep: fn(&Force) -> bool| Chain {
            forces: self
                .chain
                .forces
                .iter()
                .filter(|f| keep(f))
                .cloned()
                .collect(),
            ..self.chain.clone()
        };
        let (_, k_ns, c_ns, _) = eval(&only(|f| !matches!(f, Force::Servo { .. })));
        let (_, k_c, c_c, _) = eval(&only(|f| {
            matches!(f, Force::Spring { .. } | Force::LinkSpring { .. })
        }));
        let mut e = Energetics {
            energy_j: t2 - t0 + v,
            kinetic_j: t2,
            frame_kinetic_j: t0,
            potential_j: v,
            ..Default::default()
        };
        for i in 0..n {
            let (mut kq, mut kq_ns, mut kq_c, mut mq) = (0.0, 0.0, 0.0, 0.0);
            for j in 0..n {
                kq += k[i * n + j] * qd[j];
                kq_ns += k_ns[i * n + j] * qd[j];
                kq_c += k_c[i * n + j] * qd[j];
                mq += m[i * n + j] * qdd[j];
            }
            if self.design.coordinates[i].servo.is_some() {
                // An ideal servo: the torque is whatever its equation lacks.
                e.servo_power_w += (mq - c[i] - kq) * qd[i];
            }
            // A finite-gain servo's torque is in the forces.
            e.servo_power_w += (c[i] - c_ns[i] + kq - kq_ns) * qd[i];
            e.damper_power_w += (kq_ns - kq_c) * qd[i];
            e.applied_power_w += (c_ns[i] - c_c[i]) * qd[i];
        }
        Some(e)
    }

    /// What keeps Jacobi's integral h = T₂ − T₀ + V from being a first integral of this model,
    /// or `None` when it is one: a `full` model on a base at rest on the Earth (h then has no
    /// explicit time and the Lagrangian is Beghin's ch. I one), with no servo, damper, applied
    /// force, liquid or spin motor, whose forces are springs only (potential). Harbour scenes of
    /// Foucault's gyroscope are such; every compass with a damper is not.
    pub fn jacobi_integral_broken_by(&self) -> Option<String> {
        if self.fidelity != Fidelity::Full {
            return Some(format!(
                "its `{}` fidelity (Jacobi's integral is kept in `full` only)",
                self.fidelity
            ));
        }
        if !self.is_autonomous() {
            return Some("its moving base (the ship's motion works on the compass)".into());
        }
        if !self.motors.is_empty() {
            return Some("its spin motors".into());
        }
        if let Some(c) = self.design.coordinates.iter().find(|c| c.servo.is_some()) {
            return Some(format!("the servo driving `{}`", c.name));
        }
        if let Some(f) = self
            .chain
            .forces
            .iter()
            .find(|f| !matches!(f, Force::Spring { .. } | Force::LinkSpring { .. }))
        {
            return Some(format!(
                "force `{}` (dampers, applied forces and servos are not potential)",
                f.name()
            ));
        }
        if !self.chain.pots.is_empty() || !self.chain.tanks.is_empty() {
            return Some("its liquid (the flow between pots or compartments dissipates)".into());
        }
        if self.dim() > JACOBI_MAX_STATES {
            return Some(format!(
                "its {} states (the integral's gradient is formed for up to {JACOBI_MAX_STATES})",
                self.dim()
            ));
        }
        None
    }

    /// Jacobi's integral h = T₂ − T₀ + V (J) at (t, x) and its exact gradient ∂h/∂x into
    /// `grad` (the engine's energies on dual numbers along the states, recorded once as a tape),
    /// for a model of which it is a first integral ([`Self::jacobi_integral_broken_by`] is
    /// `None`; otherwise `None`). The same energies as [`Self::energetics`]' `energy_j`, without
    /// allocating after the first call: what a projection onto the level set calls in a run.
    pub fn jacobi_integral(&self, _t: f64, x: &[f64], grad: &mut [f64]) -> Option<f64> {
        // The model is autonomous (else the integral is broken), so the tape takes x only.
        let tape = self
            .jacobi_tape
            .get_or_init(|| self.record_jacobi())
            .as_ref()?;
        let dim = self.dim();
        let mut out = [0.0; 1 + JACOBI_MAX_STATES];
        let ok = tape.eval(&x[..dim], &mut out[..1 + dim]);
        grad[..dim].copy_from_slice(&out[1..1 + dim]);
        (ok && out[..1 + dim].iter().all(|v| v.is_finite())).then_some(out[0])
    }

    fn record_jacobi(&self) -> Option<Tape> {
        self.jacobi_integral_broken_by().is_none().then_some(())?;
        let at = self.x0.clone();
        let dim = at.len();
        Some(tape::on_large_stack(|| {
            tape::record(&at, 1 + dim, |inp, out| self.jacobi_n(inp, out))
        }))
    }

    /// h and ∂h/∂x into `out` (1 + dim entries), recorded: one width of dual numbers and one
    /// scalar only, since every method of the model is compiled where the model's motion type is
    /// (in gyro-sim), and each width × scalar × chain size is a copy of the engine (four widths
    /// and two scalars made gyro-sim's library take ≈ 20 min to build).
    fn jacobi_n(&self, x: &[Tr], out: &mut [Tr]) {
        const MX: usize = MAX_COORDINATES + 1;
        const D: usize = JACOBI_MAX_STATES;
        type T = Tr;
        let (n, ni) = (self.chain.n, self.independent.len());
        let dim = 2 * ni;
        let xs: [Jet<T, D>; D] = Jet::variables(x, dim);
        let zero = Jet::<T, D>::zero();
        let (mut q, mut qd) = ([zero; MX], [zero; MX]);
        self.expand(&xs[..ni], &mut q[..n], true);
        self.expand(&xs[ni..dim], &mut qd[..n], false);
        let (r, w, g, ..) = self.base_at(Jet::<T, D>::cst(0.0));
        let (mut m, mut k, mut c) = ([zero; MX * MX], [zero; MX * MX], [zero; MX]);
        let inp = EvalInput {
            q: &q[..n],
            qd: &qd[..n],
            u: &qd[..n],
            drop_quadratic: &[],
            spin_momentum: &self.spin_momentum,
            world_from_base: &r,
            base_rate: &w,
            gravity: g,
        };
        let mut eo = EvalOutput {
            m: &mut m[..n * n],
            k: &mut k[..n * n],
            c: &mut c[..n],
            energies: [zero; 3],
        };
        evaluate_any(&self.chain, &inp, &mut eo);
        let [t2, t0, v] = eo.energies;
        let h = t2 - t0 + v;
        out[0] = h.v;
        out[1..1 + dim].copy_from_slice(&h.d[..dim]);
    }

    /// Whether `gyroscopic` fidelity runs the carried reduction here ([`crate::gyroscopic`]:
    /// a rolling sea, and both precessional and inertial coordinates).
    pub fn carries_gyros(&self) -> bool {
        self.fidelity == Fidelity::Gyroscopic && self.carried
    }

    /// Index (full) of the coordinate with a role.
    pub fn role(&self, role: CoordinateRole) -> Option<usize> {
        self.design.role_index(role)
    }

    /// Eigenvalues of the linearisation at equilibrium (full fidelity), (re, im) in 1/s.
    pub fn modes(&self) -> Vec<(f64, f64)> {
        let ni = self.independent.len();
        let dim = 2 * ni;
        let mut a = vec![0.0; dim * dim];
        self.jacobian_at(Fidelity::Full, 0.0, &self.x_equilibrium, &mut a);
        linalg::eigenvalues(&a, dim)
    }
}

/// dx += A (x − x_e) for an N-state model whose first N − R rows are kinematic (see
/// [`kinematic_rows`]), from the transpose of A's last R rows (row-major: column j of A, rows
/// N − R … N − 1), row sums in column order.
fn add_matvec<const N: usize, const R: usize>(at: &[f64], x: &[f64], xe: &[f64], dx: &mut [f64]) {
    let m = N - R;
    let mut s = [0.0; R];
    for (col, (xj, ej)) in at[..N * R].chunks_exact(R).zip(x[..N].iter().zip(&xe[..N])) {
        let y = xj - ej;
        for (si, a) in s.iter_mut().zip(col) {
            *si += a * y;
        }
    }
    let (kin, dynamic) = dx[..N].split_at_mut(m);
    for (d, (xj, ej)) in kin.iter_mut().zip(x[m..N].iter().zip(&xe[m..N])) {
        *d += xj - ej;
    }
    for (d, si) in dynamic.iter_mut().zip(s) {
        *d += si;
    }
}

/// How many leading rows of the row-major n × n `a` are kinematic: row i exactly the unit
/// vector at column m + i, m the first row's nonzero column (0 if the rows are not so). The
/// integrators' `IterationMatrix::kinematic_rows` (gyro-sim) makes the same test for their
/// own elimination; they know no model, so each crate keeps its own.
fn kinematic_rows(a: &[f64], n: usize) -> usize {
    let Some(m) = a[..n].iter().position(|&v| v != 0.0) else {
        return 0;
    };
    if m == 0 || 2 * m > n {
        return 0;
    }
    let unit = |i: usize| {
        let row = &a[i * n..(i + 1) * n];
        row[m + i] == 1.0 && row.iter().filter(|&&v| v != 0.0).count() == 1
    };
    if (0..m).all(unit) { m } else { 0 }
}

#[cfg(test)]
mod tests {
    use super::{add_matvec, kinematic_rows};

    /// A(x − x_e) row by row, each row summed left to right: what the linear right-hand side
    /// must equal to the bit.
    fn row_by_row(a: &[f64], n: usize, x: &[f64], xe: &[f64], dx: &mut [f64]) {
        for (i, d) in dx.iter_mut().enumerate() {
            let mut s = 0.0;
            for j in 0..n {
                s += a[i * n + j] * (x[j] - xe[j]);
            }
            *d += s;
        }
    }

    fn case<const N: usize, const R: usize>(seed: u64) {
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 10f64.powi((state % 7) as i32 - 3)
        };
        let m = N - R;
        let mut a = vec![0.0; N * N];
        for i in 0..N {
            for j in 0..N {
                a[i * N + j] = if i >= m {
                    next()
                } else if j == m + i {
                    1.0
                } else {
                    0.0
                };
            }
        }
        assert_eq!(kinematic_rows(&a, N), m);
        let at: Vec<f64> = (0..N * R).map(|k| a[(m + k % R) * N + k / R]).collect();
        let x: Vec<f64> = (0..N).map(|_| next()).collect();
        let mut xe: Vec<f64> = (0..N).map(|_| next()).collect();
        xe[N - 1] = x[N - 1]; // an exactly zero deviation
        let forcing: Vec<f64> = (0..N).map(|_| next()).collect();
        let (mut fast, mut slow) = (forcing.clone(), forcing);
        add_matvec::<N, R>(&at, &x, &xe, &mut fast);
        row_by_row(&a, N, &x, &xe, &mut slow);
        for (f, s) in fast.iter().zip(&slow) {
            assert_eq!(
                f.to_bits(),
                s.to_bits(),
                "N = {N}, R = {R}: {fast:?} vs {slow:?}"
            );
        }
    }

    #[test]
    fn the_split_product_is_the_row_by_row_product_to_the_bit() {
        for seed in 1..20 {
            case::<8, 4>(seed);
            case::<8, 8>(seed);
            case::<9, 5>(seed);
            case::<2, 1>(seed);
            case::<16, 8>(seed);
        }
    }

    #[test]
    fn kinematic_rows_are_found_only_where_they_are() {
        // q̇ = v over two coordinates and a spin: rows 0 and 1 are kinematic.
        let mut a = vec![0.5; 25];
        a[..10].fill(0.0);
        a[2] = 1.0;
        a[5 + 3] = 1.0;
        assert_eq!(kinematic_rows(&a, 5), 2);
        a[5 + 4] = 1e-30; // a coupling in a rate row: not kinematic
        assert_eq!(kinematic_rows(&a, 5), 0);
        a[5 + 4] = 0.0;
        a[5 + 3] = 2.0; // not a unit row
        assert_eq!(kinematic_rows(&a, 5), 0);
        assert_eq!(kinematic_rows(&[0.0; 4], 2), 0);
    }
}
