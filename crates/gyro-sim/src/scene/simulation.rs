//! The `[simulation]` table: fidelity, integrator and tolerances, which effects are compiled in,
//! and the pose rate.

use super::SourceText;
use crate::program::ShipProgram;
use crate::scene::SceneOverrides;
use crate::solvers::{DEFAULT_JACOBIAN_REUSE_CONTRACTION, Method, Tolerances};
use gyro_model::error::InputError;
use gyro_model::{Effects, Fidelity};
use serde::Deserialize;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SimulationFile {
    #[serde(default = "default_fidelity")]
    fidelity: String,
    #[serde(default = "default_integrator")]
    integrator: String,
    /// The integrator when the scene runs at `full` fidelity (set in the file or by
    /// `--fidelity full`), if not `integrator`: `full` carries the nutation, tens of Hz and
    /// barely damped, which holds an explicit integrator that suits the slower fidelities to its
    /// stability bound (a rolling day: 96 steps per second under DOP853, 3.3 under RODAS4).
    #[serde(default)]
    full_integrator: Option<String>,
    #[serde(default = "default_rtol")]
    rtol: f64,
    #[serde(default = "default_atol")]
    atol: f64,
    #[serde(default)]
    max_step_s: Option<f64>,
    /// RADAU5 keeps its Jacobian while the Newton iteration contracts by at most this
    /// (Hairer's THET, default 0.001); ≈ 0.1 where a Jacobian costs many right-hand sides.
    #[serde(default)]
    jacobian_reuse_contraction: Option<f64>,
    /// `auto` (what the scene needs) or `all` (every effect compiled in, even at zero amplitude).
    #[serde(default = "default_effects")]
    effects: String,
    #[serde(default)]
    pub(super) disable_effects: Vec<String>,
    /// Pose messages at most this often (the state series keeps the full output rate).
    #[serde(default)]
    pose_rate_hz: Option<f64>,
    /// Record `/compass/energy` (Jacobi's integral and the servo, damper and applied powers) at
    /// every sample: three reference-engine passes per sample, so only when asked.
    #[serde(default)]
    pub(super) record_energy: bool,
    /// Project the state back onto Jacobi's integral h = T₂ − T₀ + V every few steps
    /// (`gyro_sim::solvers::PROJECTION_INTERVAL`): for a conservative `full` model on a base at
    /// rest (a harbour scene of Foucault's gyroscope), where the integrators' drift of h is what
    /// grows the phase error of a long run. Refused, with the reason, for a model that does not
    /// keep h.
    #[serde(default)]
    pub(super) keep_jacobi_integral: bool,
}

impl Default for SimulationFile {
    fn default() -> Self {
        SimulationFile {
            fidelity: default_fidelity(),
            integrator: default_integrator(),
            full_integrator: None,
            rtol: default_rtol(),
            atol: default_atol(),
            max_step_s: None,
            jacobian_reuse_contraction: None,
            effects: default_effects(),
            disable_effects: Vec::new(),
            pose_rate_hz: None,
            record_energy: false,
            keep_jacobi_integral: false,
        }
    }
}
fn default_fidelity() -> String {
    "gyroscopic".into()
}
fn default_integrator() -> String {
    "rodas4".into()
}
fn default_rtol() -> f64 {
    1e-8
}
fn default_atol() -> f64 {
    1e-10
}
fn default_effects() -> String {
    "auto".into()
}

/// `effects = "all"` (every effect compiled in) or `"auto"`.
pub(super) fn force_all(sim: &SimulationFile, src: &SourceText) -> Result<bool, InputError> {
    match sim.effects.as_str() {
        "auto" => Ok(false),
        "all" => Ok(true),
        other => Err(src.err(
            Some("[simulation]"),
            "effects",
            "simulation.effects",
            format!("unknown value `{other}` (allowed: auto, all)"),
        )),
    }
}

/// The effects the scene calls for (or everything), less those disabled. The spin motor is
/// decided later, with the design.
pub(super) fn effects(
    sim: &SimulationFile,
    program: &ShipProgram,
    force_all: bool,
    src: &SourceText,
) -> Result<Effects, InputError> {
    let mut effects = if force_all {
        gyro_model::Effects::all()
    } else {
        Effects::default()
    };
    if !force_all {
        effects.base.earth_rotation = true;
        effects.damper = true;
        effects.friction = true;
        let speed = program.has_speed();
        effects.base.transport_rate = speed;
        effects.base.ship_acceleration = speed || program.has_turns();
        effects.base.base_coriolis = speed;
        effects.base.turn_rate = program.has_turns();
        effects.base.roll_pitch = !program.sea.is_calm();
    }
    for name in &sim.disable_effects {
        effects.set(name, false).map_err(|m| {
            src.err(
                Some("[simulation]"),
                "disable_effects",
                "simulation.disable_effects",
                m,
            )
        })?;
    }
    Ok(effects)
}

/// Fidelity, integrator and its tolerances, the command line's overrides first.
pub(super) fn solver(
    sim: &SimulationFile,
    ov: &SceneOverrides,
    src: &SourceText,
) -> Result<(Fidelity, Method, Tolerances), InputError> {
    let fidelity: Fidelity = match ov.fidelity {
        Some(x) => x,
        None => sim.fidelity.parse().map_err(|m: String| {
            src.err(Some("[simulation]"), "fidelity", "simulation.fidelity", m)
        })?,
    };
    let parse = |key: &str, value: &str| -> Result<Method, InputError> {
        value.parse::<Method>().map_err(|e| {
            src.err(
                Some("[simulation]"),
                key,
                &format!("simulation.{key}"),
                e.to_string(),
            )
        })
    };
    // Both are checked whatever the fidelity: a typo fails when the file loads, not on the run
    // that first asks for `full`.
    let method = parse("integrator", &sim.integrator)?;
    let full_method = match &sim.full_integrator {
        Some(m) => Some(parse("full_integrator", m)?),
        None => None,
    };
    let method: Method = match (ov.method, full_method) {
        (Some(m), _) => m,
        (None, Some(m)) if fidelity == Fidelity::Full => m,
        _ => method,
    };
    let rtol = ov.rtol.unwrap_or(sim.rtol);
    let atol = ov.atol.unwrap_or(sim.atol);
    if !(rtol > 0.0 && rtol < 1.0 && atol > 0.0 && atol.is_finite()) {
        return Err(src.err(
            Some("[simulation]"),
            "rtol",
            "simulation.rtol",
            format!("rtol {rtol}, atol {atol} out of range (allowed: 0 < rtol < 1, atol > 0)"),
        ));
    }
    let max_step = sim.max_step_s.unwrap_or(f64::INFINITY);
    if max_step.is_nan() || max_step <= 0.0 {
        return Err(src.err(
            Some("[simulation]"),
            "max_step_s",
            "simulation.max_step_s",
            "must be > 0".into(),
        ));
    }
    let reuse = ov
        .jacobian_reuse_contraction
        .or(sim.jacobian_reuse_contraction)
        .unwrap_or(DEFAULT_JACOBIAN_REUSE_CONTRACTION);
    if !(reuse > 0.0 && reuse < 1.0) {
        return Err(src.err(
            Some("[simulation]"),
            "jacobian_reuse_contraction",
            "simulation.jacobian_reuse_contraction",
            format!("{reuse} is out of range (allowed: 0 < value < 1; RADAU5's default 0.001)"),
        ));
    }
    let tolerances = Tolerances {
        rtol,
        atol,
        max_step_s: max_step,
        initial_step_s: None,
        jacobian_reuse_contraction: reuse,
    };
    Ok((fidelity, method, tolerances))
}

/// Pose messages per second: at most the output rate and 10 Hz unless the scene says.
pub(super) fn pose_rate_hz(
    sim: &SimulationFile,
    output_rate_hz: f64,
    src: &SourceText,
) -> Result<f64, InputError> {
    let pose_rate = sim.pose_rate_hz.unwrap_or(output_rate_hz.min(10.0));
    if pose_rate.is_nan() || pose_rate <= 0.0 {
        return Err(src.err(
            Some("[simulation]"),
            "pose_rate_hz",
            "simulation.pose_rate_hz",
            "must be > 0".into(),
        ));
    }
    Ok(pose_rate)
}
