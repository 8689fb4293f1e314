//! The ship's motion: speed error (Beghin §30), Schuler tuning against a 20-kn speed change
//! (§35), the quadrantal error under rolling (§40), and "absent effects cost nothing".

use crate::support;
use gyro_model::Fidelity;
use gyro_model::constants::{
    EARTH_RADIUS_M, EARTH_RATE_RAD_PER_S, KNOT_IN_M_PER_S, STANDARD_GRAVITY_M_PER_S2,
};
use gyro_model::theory::{rolling_error_magnitude_rad, speed_error_rad};
use gyro_sim::SceneOverrides;
use gyro_sim::solvers::Method;
use support::*;

fn reading_errors(sim: &gyro_sim::Simulation, out: &[(f64, Vec<f64>)]) -> Vec<(f64, f64)> {
    out.iter()
        .map(|(t, x)| (*t, sim.model.readout(*t, x).reading_error_rad))
        .collect()
}

#[test]
fn speed_error_of_a_30_kn_run_north_at_50n() {
    let mut text = scene_text("run-north-30kn");
    text = text.replace("duration_s = 14400.0", "duration_s = 1800.0");
    let sc = scene_from(&text, &SceneOverrides::default());
    let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
    let e = reading_errors(&sim, &out);
    for &(t, err) in &[e[0], e[e.len() - 1]] {
        let lat = sim.latitude_rad(t);
        let expect = speed_error_rad(30.0 * KNOT_IN_M_PER_S, 0.0, lat);
        // The damper's latitude error (eq. 18) adds to it as the ship moves north of 50°.
        let d = &sc.design;
        let l0 = d
            .parameter("compensation_latitude_deg")
            .expect("compensation_latitude_deg")
            .to_radians();
        let lat_err = d.parameter("kappa_n_m").expect("kappa_n_m") * (l0.sin() - lat.sin())
            / (d.parameter("pendulous_moment_n_m")
                .expect("pendulous_moment_n_m")
                * lat.cos());
        let rel = (err / (expect + lat_err) - 1.0).abs();
        assert!(
            rel < 0.02,
            "t = {t}: reading error {:.4}° vs speed error {:.4}° + latitude error {:.4}°",
            err.to_degrees(),
            expect.to_degrees(),
            lat_err.to_degrees()
        );
        assert!(
            err > 0.0,
            "northerly speed: the compass reads high (West of North)"
        );
    }
}

/// Runs the 20-kn stop with an undamped Anschütz of the given period at 50°N; returns the
/// residual swing about the new equilibrium after the manoeuvre, as a fraction of the shift.
fn residual_after_stop(period_s: f64) -> f64 {
    let lat = 50f64.to_radians();
    let h = 2e4 * 1e-7 / 7e-5;
    // T = 2π√(IΩ/(aP ε cos L)) → aP.
    let ap = h * (std::f64::consts::TAU / period_s).powi(2) / (EARTH_RATE_RAD_PER_S * lat.cos());
    let text = scene_text("speed-change-20kn")
        .replace(
            "[compass]\n",
            &format!(
                "[compass]\ndesign_overrides = {{ \"parameters.pendulous_moment_n_m\" = {ap} }}\n"
            ),
        )
        .replace(
            "fidelity = \"gyroscopic\"",
            "fidelity = \"gyroscopic\"\ndisable_effects = [\"damper\"]\nrtol = 1e-10\natol = 1e-13",
        )
        .replace(
            "duration_s = 18000.0",
            &format!("duration_s = {}", 3660.0 + 2.2 * period_s),
        );
    let sc = scene_from(&text, &SceneOverrides::default());
    let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-10, 1e-13));
    let e = reading_errors(&sim, &out);
    // The equilibrium before the stop is the speed error (it creeps by ~0.7 % as the ship gains
    // latitude); after it, zero (undamped: no latitude error).
    let formula = speed_error_rad(20.0 * KNOT_IN_M_PER_S, 0.0, lat);
    let shift = e
        .iter()
        .filter(|(t, _)| *t < 3600.0)
        .map(|(_, x)| *x)
        .next_back()
        .unwrap_or(f64::NAN);
    assert!(
        (shift / formula - 1.0).abs() < 0.02,
        "speed error before the stop {shift:e} vs {formula:e}"
    );
    let before = e
        .iter()
        .filter(|(t, _)| *t < 3600.0)
        .map(|(_, x)| (x - shift).abs())
        .fold(0.0, f64::max);
    assert!(
        before < 0.02 * shift,
        "the run starts on its equilibrium and stays ({before:e})"
    );
    let after = e
        .iter()
        .filter(|(t, _)| *t > 3660.0)
        .map(|(_, x)| x.abs())
        .fold(0.0, f64::max);
    after / shift
}

#[test]
fn schuler_tuned_compass_lands_on_the_new_equilibrium() {
    let schuler = std::f64::consts::TAU * (EARTH_RADIUS_M / STANDARD_GRAVITY_M_PER_S2).sqrt();
    let tuned = residual_after_stop(schuler);
    let detuned = residual_after_stop(63.0 * 60.0);
    println!(
        "residual swing after a 20-kn stop: Schuler-tuned {:.2} %, 63-min {:.1} % of the shift",
        tuned * 100.0,
        detuned * 100.0
    );
    assert!(
        tuned < 0.05,
        "Schuler-tuned residual swing {:.2} % of the shift",
        tuned * 100.0
    );
    // Elementary theory: the 63-min compass is thrown by (T_S/T)² of the shift: 0.8 overshoot.
    assert!(
        detuned > 0.5,
        "63-min variant residual {:.1} %",
        detuned * 100.0
    );
}

fn rolling_mean_error(scene: &str) -> (f64, f64) {
    rolling_mean_error_at(scene, None)
}

fn rolling_mean_error_at(scene: &str, fidelity: Option<Fidelity>) -> (f64, f64) {
    // 4 h: the error builds up with the compass's own response (decay ≈ 25 min); the mean is
    // taken over the last 2 h (whole roll periods).
    let ov = SceneOverrides {
        duration_s: Some(4.0 * 3600.0),
        fidelity,
        ..Default::default()
    };
    let sc = scene_from(&scene_text(scene), &ov);
    let (sim, out, _) = run(&sc, sc.method, sc.tolerances);
    let e = reading_errors(&sim, &out);
    let tail: Vec<f64> = e
        .iter()
        .filter(|(t, _)| *t >= sc.duration_s - 7200.0)
        .map(|(_, x)| *x)
        .collect();
    let mean = tail.iter().sum::<f64>() / tail.len() as f64;
    let d = &sc.design;
    let h = d
        .parameter("spin_momentum_n_m_s")
        .expect("spin_momentum_n_m_s");
    let ap = d
        .parameter("pendulous_moment_n_m")
        .expect("pendulous_moment_n_m");
    let tau = h * EARTH_RATE_RAD_PER_S * sc.start_latitude_rad.cos();
    let s = std::f64::consts::TAU / sc.program.sea.roll_period_s;
    let j0 = sc.pivot_m[2] * sc.program.sea.roll_amplitude_rad.sin() * s * s;
    // Roll plane ⟂ heading: Δ = heading + 90° (azimuths West-positive: only sinΔcosΔ matters).
    let heading = sc.program.segments[0].heading0_rad;
    let delta = -heading + std::f64::consts::FRAC_PI_2;
    (
        mean,
        rolling_error_magnitude_rad(j0, delta, ap, tau).max(
            rolling_error_magnitude_rad(j0, std::f64::consts::FRAC_PI_4, ap, tau)
                * if heading == 0.0 { 0.0 } else { 1.0 },
        ),
    )
}

#[test]
fn rolling_gives_the_quadrantal_error_on_intercardinal_headings_only() {
    let (mean45, expect45) = rolling_mean_error("rolling-intercardinal");
    let (mean0, _) = rolling_mean_error("rolling-cardinal");
    println!(
        "rolling mean error: 045° {:.3}° (Beghin {:.3}°), 000° {:.4}°",
        mean45.to_degrees(),
        expect45.to_degrees(),
        mean0.to_degrees()
    );
    assert!(
        (mean45.abs() / expect45 - 1.0).abs() < 0.2,
        "intercardinal mean error {:.3}° vs ½ sinΔcosΔ (J₀/g)² aP/τ = {:.3}°",
        mean45.to_degrees(),
        expect45.to_degrees()
    );
    assert!(
        mean0.abs() < 0.05 * expect45,
        "cardinal mean error {:.4}°",
        mean0.to_degrees()
    );
}

/// `gyroscopic` carries the gyros at sea only where the sea turns a spin axis (gyro-model's
/// `gyroscopic` module): the Anschütz 1906's float heels about its own spin axis, so it keeps the
/// plain reduction, a quarter of the cost, and must then agree with `full` to the gyroscopic
/// model's error; the ship-rooted designs and the three-gyro (whose heel swings its side gyros)
/// are carried.
#[test]
fn only_a_sea_that_turns_a_spin_axis_carries_the_gyros() {
    let (plain, _) = rolling_mean_error_at("rolling-intercardinal", None);
    let (full, _) = rolling_mean_error_at("rolling-intercardinal", Some(Fidelity::Full));
    println!(
        "Anschütz 1906, rolling-intercardinal: gyroscopic (plain) {plain:.6e}, full {full:.6e}"
    );
    assert!(
        (plain / full - 1.0).abs() < 1e-3,
        "plain gyroscopic {plain} vs full {full}"
    );
    for (design, carried) in [
        ("anschutz-1906", false),
        ("sperry-1911", true),
        ("slough", true),
        ("sperry-twin-1918", true),
        ("anschutz-three-gyro-1912", true),
    ] {
        let ov = SceneOverrides {
            design: Some(design.into()),
            ..Default::default()
        };
        let sc = scene_from(&scene_text("compare-rolling-045"), &ov);
        let sim = gyro_sim::Simulation::new(&sc).expect("compiles");
        assert_eq!(sim.model.carries_gyros(), carried, "{design}");
        let calm = scene_from(&scene_text("compare-harbour-50n"), &ov);
        let sim = gyro_sim::Simulation::new(&calm).expect("compiles");
        assert!(!sim.model.carries_gyros(), "{design} in harbour");
    }
}

#[test]
fn absent_effects_cost_nothing_and_change_nothing() {
    let auto = scene_from(
        &scene_text("harbour-50n").replace("duration_s = 21600.0", "duration_s = 7200.0"),
        &SceneOverrides::default(),
    );
    let all_text = scene_text("harbour-50n")
        .replace("duration_s = 21600.0", "duration_s = 7200.0")
        .replace("[simulation]\n", "[simulation]\neffects = \"all\"\n");
    let all = scene_from(&all_text, &SceneOverrides::default());
    assert_eq!(
        auto.effects.names(),
        vec!["earth_rotation", "damper", "friction"],
        "a harbour compiles no ship-motion terms"
    );
    assert_eq!(all.effects.names().len(), gyro_model::EFFECT_NAMES.len());
    let (sa, oa, _) = run(&auto, Method::Rodas4, tol(1e-9, 1e-12));
    let (sb, ob, _) = run(&all, Method::Rodas4, tol(1e-9, 1e-12));
    assert!(sa.model.is_autonomous() && !sb.model.is_autonomous());
    assert_eq!(oa.len(), ob.len());
    let worst = oa
        .iter()
        .zip(&ob)
        .flat_map(|(a, b)| a.1.iter().zip(&b.1).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max);
    assert!(
        worst <= 1e-12,
        "harbour vs every effect at zero amplitude: {worst:e}"
    );
}
