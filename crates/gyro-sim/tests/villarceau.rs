//! Foucault's gyroscope simulated by the engine against Villarceau's exact results: the period
//! (quadrature of eq. 47, with δ) at small, large and near-separatrix amplitude, the first
//! integral over 100 periods, and the reversed spin oscillating about γ = π.

use crate::support;
use gyro_model::theory::{Villarceau, foucault_villarceau};
use gyro_sim::solvers::{Method, OutputGrid};
use gyro_sim::{SceneOverrides, Simulation};
use std::ops::ControlFlow;
use support::*;

struct Case {
    v: Villarceau,
    /// (t, γ − centre, γ̇)
    samples: Vec<(f64, f64, f64)>,
    period_exact: f64,
}

/// Runs a Foucault scene released at rest `amplitude_deg` from the centre for `periods` periods.
fn villarceau_case(
    scene: &str,
    design_overrides: &str,
    amplitude_deg: f64,
    periods: f64,
    rtol: f64,
) -> Case {
    let mut text = scene_text(scene);
    if !design_overrides.is_empty() {
        text = text.replace(
            "[compass]\n",
            &format!("[compass]\ndesign_overrides = {{ {design_overrides} }}\n"),
        );
        text = text.replace(
            "design_overrides = { \"parameters.ring_axis_elevation_deg\" = 0.0 }\n",
            "",
        );
    }
    let mut sc = scene_from(&text, &SceneOverrides::default());
    let lat = sc.start_latitude_rad;
    let gi = sc.design.coordinate_index("gamma").expect("gamma");
    let probe = Simulation::new(&sc).expect("compiles");
    let torus = probe.model.design.body_index("torus").expect("torus");
    let (v0, offset) =
        foucault_villarceau(&probe.model.design, probe.model.spin_momentum[torus], lat)
            .expect("villarceau");
    let centre = v0.centre();
    sc.initial.offsets_rad = vec![(gi, offset + centre + amplitude_deg.to_radians())];
    let mut sim = Simulation::new(&sc).expect("compiles");
    // n = w + ω cos θ₀ depends on the start: take Villarceau's constants from this model.
    let (v, _) = foucault_villarceau(&sim.model.design, sim.model.spin_momentum[torus], lat)
        .expect("villarceau");
    let period_exact = v.period(amplitude_deg.to_radians());
    sim.grid = OutputGrid {
        t0: 0.0,
        dt: period_exact / 400.0,
        t_end: periods * period_exact + period_exact / 4.0,
    };
    let mut samples = Vec::new();
    sim.run(Method::Dop853, &tol(rtol, rtol * 1e-2), |t, x| {
        samples.push((t, x[0] - offset - centre, x[1]));
        ControlFlow::Continue(())
    })
    .expect("runs");
    Case {
        v,
        samples,
        period_exact,
    }
}

fn measured_period(c: &Case) -> f64 {
    let t: Vec<f64> = c.samples.iter().map(|s| s.0).collect();
    let y: Vec<f64> = c.samples.iter().map(|s| s.1).collect();
    let yd: Vec<f64> = c.samples.iter().map(|s| s.2).collect();
    mean_period(&upward_crossings(&t, &y, &yd))
}

fn assert_period(scene: &str, ov: &str, amplitude_deg: f64) {
    let c = villarceau_case(scene, ov, amplitude_deg, 20.0, 1e-13);
    let m = measured_period(&c);
    let rel = (m / c.period_exact - 1.0).abs();
    assert!(
        rel < 1e-8,
        "{scene} {ov} amplitude {amplitude_deg}°: period {m} s vs Villarceau {} s (rel. {rel:e})",
        c.period_exact
    );
}

#[test]
fn azimuth_gyroscope_period_at_10_90_170_degrees() {
    for a in [10.0, 90.0, 170.0] {
        assert_period("foucault-azimuth-45n", "", a);
    }
}

#[test]
fn latitude_gyroscope_period_at_10_90_170_degrees() {
    for a in [10.0, 90.0, 170.0] {
        assert_period(
            "foucault-latitude-45n",
            "\"parameters.ring_axis_elevation_deg\" = 0.0",
            a,
        );
    }
}

#[test]
fn first_integral_drifts_less_than_1e_10_over_100_periods() {
    let c = villarceau_case("foucault-azimuth-45n", "", 90.0, 100.0, 1e-13);
    let e0 = c.v.first_integral(c.samples[0].1, c.samples[0].2);
    // Relative to the size of its terms, 2|g/a|.
    let scale = 2.0 * c.v.g_over_a.abs();
    let worst = c
        .samples
        .iter()
        .map(|s| (c.v.first_integral(s.1, s.2) - e0).abs() / scale)
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-10,
        "first integral drift {worst:e} of 2g/a over 100 periods"
    );
}

#[test]
fn reversed_spin_oscillates_about_pi() {
    let c = villarceau_case(
        "foucault-azimuth-45n",
        "\"body.torus.rotor.spin_rpm\" = -9000.0",
        30.0,
        5.0,
        1e-12,
    );
    assert!(c.v.g_over_a < 0.0, "n < 0 must give a negative g/a");
    // Measured relative to π, the swing stays within ±30° and crosses the centre.
    let max = c.samples.iter().map(|s| s.1.abs()).fold(0.0, f64::max);
    assert!(
        (max - 30f64.to_radians()).abs() < 1e-6,
        "amplitude about π: {}°",
        max.to_degrees()
    );
    let m = measured_period(&c);
    assert!((m / c.period_exact - 1.0).abs() < 1e-8);
}
