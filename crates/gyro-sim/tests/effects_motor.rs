//! Spin-motor dynamics (effect `spin_motor`): a rotor with a motor has its spin Ω as a state,
//! dΩ/dt = (Ω_rated − Ω)/τ, and H = CΩ enters the chain's equations with the motor's reaction
//! −Ḣ ŝ on the case. Checked on the Anschütz 1906 with a motor added to its rotor:
//! - the spin follows Ω_rated − (Ω_rated − Ω₀) e^(−t/τ);
//! - the reaction heels the float about the spin axis by −CΩ̇/(its pendulous stiffness), and the
//!   heel decays with the spin-up;
//! - once spun up, the undamped period is 2π√(CΩ_rated/(aPε cos L)): it follows the rated spin
//!   (∝ √Ω_rated; a motor rated at half the speed gives a period √2 shorter);
//! - without a motor (or with the effect disabled) no motor state is compiled and the run is
//!   bit-for-bit the held-spin run.

use crate::support;
use gyro_model::constants::{EARTH_RATE_RAD_PER_S, STANDARD_GRAVITY_M_PER_S2};
use gyro_sim::solvers::Method;
use gyro_sim::{SceneOverrides, Simulation};
use std::f64::consts::TAU;
use std::path::PathBuf;
use support::*;

const HELD_ROTOR: &str = r#"spin_rpm = "= spin_rpm", spin = "held" }"#;

/// The shipped Anschütz 1906 with a motor on its rotor (rated `rated_rpm`, starting at
/// `initial_rpm`, time constant `tau_s`); the rotor's polar inertia is unchanged.
fn motor_design(name: &str, rated_rpm: f64, initial_rpm: f64, tau_s: f64) -> PathBuf {
    let text = crate::support::design_text("anschutz-1906");
    assert!(text.contains(HELD_ROTOR), "the shipped rotor line changed");
    let motor = format!(
        "spin_rpm = {rated_rpm:?}, spin = \"held\", motor = {{ spin_up_time_constant_s = {tau_s:?}, initial_spin_rpm = {initial_rpm:?} }} }}"
    );
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("effects-motor");
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text.replace(HELD_ROTOR, &motor)).expect("write design");
    path
}

fn harbour(design: &str, hours: f64, extra_sim: &str, rate_hz: f64) -> String {
    format!(
        r#"name = "motor"
duration_s = {}
output_rate_hz = {rate_hz}
[start]
latitude_deg = 50.0
[compass]
design = "{design}"
azimuth_offset_deg = 1.0
[simulation]
fidelity = "gyroscopic"
integrator = "rodas4"
{extra_sim}
"#,
        hours * 3600.0
    )
}

#[test]
fn spin_relaxes_to_rated_and_its_reaction_heels_the_float() {
    let (rated, initial, tau) = (20000.0, 10000.0, 300.0);
    let path = motor_design("spin-up", rated, initial, tau);
    let sc = scene_from(
        &harbour(&path.display().to_string(), 0.5, "", 1.0),
        &SceneOverrides::default(),
    );
    assert!(sc.effects.spin_motor, "a design with a motor asks for it");
    let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-10, 1e-12));
    let m = &sim.model;
    assert!(m.effects.names().contains(&"spin_motor"));
    assert_eq!(m.motors.len(), 1);
    let names = m.state_names();
    assert_eq!(names.last().map(String::as_str), Some("rotor_spin"));
    let spin = m.dim() - 1;
    let rpm = gyro_model::constants::RPM_IN_RAD_PER_S;
    let (wr, w0) = (rated * rpm, initial * rpm);
    let c = m.motors[0].polar_inertia_kg_m2;
    // Heel stiffness about the spin axis: the float's pendulosity with the vane hanging rigidly
    // (aP counts the vane at its hinge; about the spin axis its own lever adds).
    let d = &m.design;
    let ap = d.parameter("pendulous_moment_n_m").expect("aP");
    let k_heel = ap
        + d.parameter("vane_mass_kg").expect("vane mass")
            * STANDARD_GRAVITY_M_PER_S2
            * d.parameter("vane_cg_below_hinge_m").expect("vane cg");
    let lambda = m.design.coordinate_index("lambda").expect("heel");
    let lambda_eq = m.x_equilibrium[lambda];
    let mut worst_spin: f64 = 0.0;
    let mut worst_heel: f64 = 0.0;
    for (t, x) in &out {
        let expect = wr - (wr - w0) * (-t / tau).exp();
        worst_spin = worst_spin.max((x[spin] - expect).abs() / wr);
        if *t >= 30.0 {
            // Quasi-static heel under the reaction torque −CΩ̇ about the spin axis.
            let w_dot = (wr - expect) / tau;
            let heel = x[lambda] - lambda_eq;
            let expect_heel = -c * w_dot / k_heel;
            worst_heel = worst_heel.max((heel / expect_heel - 1.0).abs());
        }
    }
    println!(
        "spin vs closed form: {worst_spin:.1e} of rated; heel vs −CΩ̇/k: {:.3} %",
        worst_heel * 100.0
    );
    assert!(
        worst_spin < 1e-8,
        "spin departs from Ω_r − (Ω_r − Ω₀)e^(−t/τ) by {worst_spin:e} of rated"
    );
    assert!(
        worst_heel < 0.01,
        "heel departs from −CΩ̇/k by {:.2} %",
        worst_heel * 100.0
    );
}

/// Period of the azimuth swing after the spin-up (t > 10τ), undamped.
fn spun_up_period(rated: f64) -> (f64, f64) {
    let tau = 300.0;
    let path = motor_design(&format!("rated-{rated}"), rated, rated / 2.0, tau);
    let c = {
        let sc = scene_from(
            &harbour(&path.display().to_string(), 0.1, "", 0.2),
            &SceneOverrides::default(),
        );
        Simulation::new(&sc).expect("compiles").model.motors[0].polar_inertia_kg_m2
    };
    let h = c * rated * gyro_model::constants::RPM_IN_RAD_PER_S;
    let lat = 50f64.to_radians();
    let sc0 = scene_from(
        &harbour(&path.display().to_string(), 0.1, "", 0.2),
        &SceneOverrides::default(),
    );
    let ap = sc0.design.parameter("pendulous_moment_n_m").expect("aP");
    let expect = TAU * (h / (ap * EARTH_RATE_RAD_PER_S * lat.cos())).sqrt();
    let hours = (10.0 * tau + 4.5 * expect) / 3600.0;
    let sc = scene_from(
        &harbour(
            &path.display().to_string(),
            hours,
            "disable_effects = [\"damper\"]",
            0.2,
        ),
        &SceneOverrides::default(),
    );
    let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
    let xe = &sim.model.x_equilibrium;
    let late: Vec<&(f64, Vec<f64>)> = out.iter().filter(|(t, _)| *t > 10.0 * tau).collect();
    let t: Vec<f64> = late.iter().map(|s| s.0).collect();
    let y: Vec<f64> = late.iter().map(|s| s.1[0] - xe[0]).collect();
    let yd: Vec<f64> = late
        .iter()
        .map(|(t, x)| sim.model.rates(*t, x)[0])
        .collect();
    (mean_period(&upward_crossings(&t, &y, &yd)), expect)
}

#[test]
fn spun_up_period_follows_the_rated_spin() {
    let (p_full, e_full) = spun_up_period(20000.0);
    let (p_half, e_half) = spun_up_period(10000.0);
    println!(
        "rated 20000 rpm: {p_full:.1} s (theory {e_full:.1}); 10000 rpm: {p_half:.1} s (theory {e_half:.1}); ratio {:.4}",
        p_full / p_half
    );
    for (p, e) in [(p_full, e_full), (p_half, e_half)] {
        assert!(
            (p / e - 1.0).abs() < 0.005,
            "period {p:.1} s vs 2π√(CΩ_r/(aPε cos L)) = {e:.1} s"
        );
    }
    assert!(
        (p_full / p_half / 2f64.sqrt() - 1.0).abs() < 0.005,
        "period ratio {} vs √2",
        p_full / p_half
    );
}

#[test]
fn no_motor_compiles_no_motor_state_and_changes_nothing() {
    // The shipped design has no motor: nothing is compiled for it.
    let plain = scene_from(
        &harbour("anschutz-1906", 2.0, "", 0.2),
        &SceneOverrides::default(),
    );
    assert!(!plain.effects.spin_motor);
    let (sp, op, _) = run(&plain, Method::Rodas4, tol(1e-9, 1e-12));
    assert!(sp.model.motors.is_empty());
    assert!(!sp.model.state_names().iter().any(|n| n.ends_with("_spin")));
    assert!(!sp.model.effects.names().contains(&"spin_motor"));
    // Even with every effect asked for, a motorless design compiles no motor state.
    let all = scene_from(
        &harbour("anschutz-1906", 0.1, "effects = \"all\"", 0.2),
        &SceneOverrides::default(),
    );
    let sa = Simulation::new(&all).expect("compiles");
    assert!(sa.model.motors.is_empty() && !sa.model.effects.spin_motor);
    assert_eq!(sa.model.dim(), sp.model.dim());
    // A design with a motor at rated spin, the effect disabled: the held-spin run, bit for bit.
    let path = motor_design("disabled", 20000.0, 0.0, 300.0);
    let off = scene_from(
        &harbour(
            &path.display().to_string(),
            2.0,
            "disable_effects = [\"spin_motor\"]",
            0.2,
        ),
        &SceneOverrides::default(),
    );
    assert!(!off.effects.spin_motor);
    let (so, oo, _) = run(&off, Method::Rodas4, tol(1e-9, 1e-12));
    assert!(so.model.motors.is_empty());
    assert_eq!(so.model.dim(), sp.model.dim());
    assert_eq!(oo.len(), op.len());
    assert!(
        oo.iter().zip(&op).all(|(a, b)| a == b),
        "a disabled motor changed the run"
    );
}

#[test]
fn motor_options_are_checked() {
    let text = crate::support::design_text("anschutz-1906");
    let free = text.replace(
        HELD_ROTOR,
        "spin_rpm = 20000.0, spin = \"free\", motor = { spin_up_time_constant_s = 300.0, initial_spin_rpm = 0.0 } }",
    );
    let e = gyro_model::Design::from_toml("free-motor.toml", &free, &[])
        .expect_err("a motor on a free rotor is refused");
    assert!(e.to_string().contains("rotor.motor"), "{e}");
    let negative = text.replace(
        HELD_ROTOR,
        "spin_rpm = 20000.0, spin = \"held\", motor = { spin_up_time_constant_s = -1.0, initial_spin_rpm = 0.0 } }",
    );
    let e = gyro_model::Design::from_toml("negative-tau.toml", &negative, &[])
        .expect_err("a negative time constant is refused");
    assert!(e.to_string().contains("spin_up_time_constant_s"), "{e}");
}

/// The exact (dual-number) Jacobian of a model with a motor state, checked independently:
/// against central differences of the right-hand side (Richardson-extrapolated, step 1e-4 of
/// each state's scale), at states away from equilibrium in the middle of the spin-up, at both
/// nonlinear fidelities. The motor column carries the reaction −Ḣ ŝ and H = CΩ into every
/// equation of the chain, which nothing else in the test suite differentiates.
#[test]
fn motor_jacobian_matches_finite_differences() {
    let path = motor_design("jacobian", 20000.0, 12000.0, 300.0);
    for fidelity in ["full", "gyroscopic"] {
        let text = harbour(&path.display().to_string(), 0.1, "", 1.0).replace(
            "fidelity = \"gyroscopic\"",
            &format!("fidelity = \"{fidelity}\""),
        );
        let sc = scene_from(&text, &SceneOverrides::default());
        let sim = Simulation::new(&sc).expect("compiles");
        let m = &sim.model;
        let dim = m.dim();
        let spin = dim - 1;
        let mut x = m.x0.clone();
        // Off equilibrium: a few degrees on every angle, some rate on every rate.
        let ni = m.independent.len();
        for (i, xi) in x.iter_mut().enumerate().take(spin) {
            *xi += if i < ni { 0.05 } else { 1e-3 } * (1.0 + i as f64 * 0.37).sin();
        }
        let t = 60.0;
        let mut jac = vec![0.0; dim * dim];
        m.jacobian(t, &x, &mut jac);
        let f = |x: &[f64]| {
            let mut dx = vec![0.0; dim];
            assert!(m.rhs(t, x, &mut dx), "rhs singular");
            dx
        };
        let mut worst: f64 = 0.0;
        for col in 0..dim {
            let h = 1e-4 * x[col].abs().max(if col < ni { 1.0 } else { 1e-2 });
            // D(h) = (f(x+h) − f(x−h))/2h; Richardson: (4 D(h/2) − D(h))/3, error O(h⁴).
            let central = |h: f64| -> Vec<f64> {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[col] += h;
                xm[col] -= h;
                let (fp, fm) = (f(&xp), f(&xm));
                fp.iter()
                    .zip(&fm)
                    .map(|(p, q)| (p - q) / (2.0 * h))
                    .collect()
            };
            let (d1, d2) = (central(h), central(h / 2.0));
            for row in 0..dim {
                let fd = (4.0 * d2[row] - d1[row]) / 3.0;
                // Scale: the row's largest exact entry, so tiny entries are judged in context.
                let scale = (0..dim)
                    .map(|c| (jac[row * dim + c] * x[c].abs().max(1e-3)).abs())
                    .fold(0.0, f64::max)
                    .max(1e-300);
                let err = (jac[row * dim + col] - fd).abs() * x[col].abs().max(1e-3) / scale;
                worst = worst.max(err);
            }
        }
        println!("{fidelity}: motor model Jacobian vs Richardson central differences: {worst:.1e}");
        assert!(
            worst < 1e-6,
            "{fidelity}: exact Jacobian departs from finite differences by {worst:e}"
        );
        // The motor's own row is exact: ∂Ω̇/∂Ω = −1/τ, and no other state drives the spin.
        assert!((jac[spin * dim + spin] + 1.0 / 300.0).abs() < 1e-15);
        assert!((0..spin).all(|c| jac[spin * dim + c] == 0.0));
    }
}
