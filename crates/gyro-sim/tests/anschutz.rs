//! Anschütz 1906 simulated by the engine against Beghin's closed forms (ch. III), computed here
//! from the design's own parameters.

use crate::support;
use gyro_model::constants::EARTH_RATE_RAD_PER_S;
use gyro_model::theory::Anschutz;
use gyro_model::{Design, Fidelity};
use gyro_sim::solvers::Method;
use gyro_sim::{SceneOverrides, Simulation};
use std::f64::consts::TAU;
use support::*;

fn theory(d: &Design, lat_deg: f64) -> Anschutz {
    Anschutz {
        spin_momentum: d.parameter("spin_momentum_n_m_s").expect("IΩ"),
        pendulous_moment: d.parameter("pendulous_moment_n_m").expect("aP"),
        kappa: d.parameter("kappa_n_m").expect("κ"),
        // ℭ and 𝔅 shift the slow roots by ~ℭaP/(IΩ)² ≈ 1e-4 only.
        inertia_vertical: 0.08,
        inertia_east_west: 0.08,
        latitude_rad: lat_deg.to_radians(),
    }
}

fn harbour(lat: f64, extra_compass: &str, extra_sim: &str, hours: f64) -> String {
    format!(
        r#"name = "t"
duration_s = {}
output_rate_hz = 0.2
[start]
latitude_deg = {lat}
[compass]
design = "anschutz-1906"
{extra_compass}
[simulation]
fidelity = "gyroscopic"
integrator = "rodas4"
rtol = 1e-9
atol = 1e-12
{extra_sim}
"#,
        hours * 3600.0
    )
}

/// (t, ζ − ζ_eq, ζ̇, θ − θ_eq) samples.
fn zeta_series(sim: &Simulation, samples: &[(f64, Vec<f64>)]) -> Vec<(f64, f64, f64, f64)> {
    let xe = &sim.model.x_equilibrium;
    samples
        .iter()
        .map(|(t, x)| {
            let rates = sim.model.rates(*t, x);
            (*t, x[0] - xe[0], rates[0], x[1] - xe[1])
        })
        .collect()
}

fn crossings(s: &[(f64, f64, f64, f64)]) -> Vec<f64> {
    let t: Vec<f64> = s.iter().map(|v| v.0).collect();
    let y: Vec<f64> = s.iter().map(|v| v.1).collect();
    let yd: Vec<f64> = s.iter().map(|v| v.2).collect();
    upward_crossings(&t, &y, &yd)
}

#[test]
fn undamped_small_amplitude_period_matches_eq_10() {
    for lat in [0.0, 30.0, 50.0, 70.0] {
        let th = theory(
            &scene_from(&harbour(lat, "", "", 1.0), &SceneOverrides::default()).design,
            lat,
        );
        let text = harbour(
            lat,
            "azimuth_offset_deg = 1.0",
            "disable_effects = [\"damper\"]",
            4.5 * th.undamped_period() / 3600.0,
        );
        let sc = scene_from(&text, &SceneOverrides::default());
        let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
        let s = zeta_series(&sim, &out);
        let period = mean_period(&crossings(&s));
        let expect = th.undamped_period();
        let rel = (period / expect - 1.0).abs();
        assert!(
            rel < 0.005,
            "L = {lat}°: period {period:.1} s vs 2π√(IΩ/(aPε cos L)) = {expect:.1} s ({:.3} %)",
            rel * 100.0
        );
        // Tilt/azimuth amplitude ratio √(τ/aP).
        let zmax = s.iter().map(|v| v.1.abs()).fold(0.0, f64::max);
        let tmax = s.iter().map(|v| v.3.abs()).fold(0.0, f64::max);
        let ratio = tmax / zmax;
        let expect_ratio = (th.tau() / th.pendulous_moment).sqrt();
        assert!(
            (ratio / expect_ratio - 1.0).abs() < 0.02,
            "L = {lat}°: tilt/azimuth {ratio:.5} vs √(τ/aP) = {expect_ratio:.5}"
        );
    }
}

#[test]
fn damped_period_and_decay_match_the_slow_roots() {
    for lat in [0.0, 30.0, 50.0, 70.0] {
        let th = theory(
            &scene_from(&harbour(lat, "", "", 1.0), &SceneOverrides::default()).design,
            lat,
        );
        let roots = th.characteristic_roots();
        let (sigma, omega) = (-roots[0].0, roots[0].1.abs());
        let t_d = TAU / omega;
        let text = harbour(lat, "azimuth_offset_deg = 2.0", "", 3.2 * t_d / 3600.0);
        let sc = scene_from(&text, &SceneOverrides::default());
        let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-10, 1e-13));
        let s = zeta_series(&sim, &out);
        let c = crossings(&s);
        let period = mean_period(&c);
        assert!(
            (period / t_d - 1.0).abs() < 0.01,
            "L = {lat}°: damped period {period:.1} s vs {t_d:.1} s"
        );
        // Decay rate from the envelope: maxima of ζ one period apart.
        let peak = |from: f64| {
            s.iter()
                .filter(|v| v.0 >= from && v.0 < from + period)
                .map(|v| v.1)
                .fold(f64::MIN, f64::max)
        };
        let p1 = peak(c[0]);
        let p2 = peak(c[1]);
        let decay = (p1 / p2).ln() / period;
        assert!(
            (decay / sigma - 1.0).abs() < 0.01,
            "L = {lat}°: decay rate {decay:e} /s vs κ/(2IΩ) root {sigma:e} /s"
        );
    }
}

#[test]
fn latitude_error_matches_eq_18() {
    for lat in [0.0, 30.0, 70.0] {
        let sc = scene_from(&harbour(lat, "", "", 0.5), &SceneOverrides::default());
        let d = &sc.design;
        let l0 = d
            .parameter("compensation_latitude_deg")
            .expect("L0")
            .to_radians();
        let th = theory(d, lat);
        let l = lat.to_radians();
        let expect = th.kappa * (l0.sin() - l.sin()) / (th.pendulous_moment * l.cos());
        let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-10, 1e-13));
        // The run starts at the equilibrium and stays there.
        let last = &out[out.len() - 1];
        let r = sim.model.readout(last.0, &last.1);
        assert!(
            (r.reading_error_rad / expect - 1.0).abs() < 0.02,
            "L = {lat}°: latitude error {:.4}° vs eq. 18 {:.4}°",
            r.reading_error_rad.to_degrees(),
            expect.to_degrees()
        );
    }
}

#[test]
fn tilt_below_the_threshold_oscillates_and_above_it_revolves() {
    let lat = 50.0;
    let th = theory(
        &scene_from(&harbour(lat, "", "", 1.0), &SceneOverrides::default()).design,
        lat,
    );
    let (tau, ap) = (th.tau(), th.pendulous_moment);
    // Exact threshold of the elementary first integral: cos θ₀ = (aP − τ)/(aP + τ) ≈ (2√(τ/aP))².
    let theta_max = ((ap - tau) / (ap + tau)).acos();
    assert!((theta_max / th.revolution_threshold_tilt() - 1.0).abs() < 0.01);
    for (factor, revolves) in [(0.95, false), (1.05, true)] {
        let tilt_deg = factor * theta_max.to_degrees();
        let text = harbour(
            lat,
            &format!("tilt_offset_deg = {tilt_deg}"),
            "disable_effects = [\"damper\"]",
            4.0 * th.undamped_period() / 3600.0,
        );
        let sc = scene_from(&text, &SceneOverrides::default());
        let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
        let zmax = out
            .iter()
            .map(|(_, x)| (x[0] - sim.model.x_equilibrium[0]).abs())
            .fold(0.0, f64::max);
        assert_eq!(
            zmax > std::f64::consts::PI,
            revolves,
            "tilt {tilt_deg:.3}° ({factor} × threshold): max |ζ| = {:.1}°",
            zmax.to_degrees()
        );
    }
}

#[test]
fn three_fidelities_agree_to_their_model_error() {
    let lat = 50.0;
    let mut traces = Vec::new();
    for fid in ["full", "gyroscopic", "linear"] {
        let text = harbour(lat, "azimuth_offset_deg = 10.0", "", 3.0).replace(
            "fidelity = \"gyroscopic\"",
            &format!("fidelity = \"{fid}\""),
        );
        let sc = scene_from(&text, &SceneOverrides::default());
        let (sim, out, stats) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
        assert_eq!(
            sim.model.fidelity,
            fid.parse::<Fidelity>().expect("present")
        );
        let e: Vec<f64> = out
            .iter()
            .map(|(t, x)| sim.model.readout(*t, x).reading_error_rad)
            .collect();
        println!(
            "{fid}: {} steps, {} rhs",
            stats.solver.steps, stats.solver.rhs_evals
        );
        traces.push(e);
    }
    let diff = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    let amp = 10f64.to_radians();
    let full_gyro = diff(&traces[0], &traces[1]) / amp;
    let full_lin = diff(&traces[0], &traces[2]) / amp;
    println!(
        "max |full − gyroscopic| = {full_gyro:.2e} of the 10° release, |full − linear| = {full_lin:.2e}"
    );
    // Dropping the precessional inertia shifts the slow mode by ~(ℭaP + 𝔅τ)/(IΩ)² ≈ 1e-4 in ω²;
    // the linear model misses the pendulum's amplitude dependence, second order in the 10°
    // release (≈ (0.17)²/16 ≈ 2e-3 in frequency, accumulating over the run).
    assert!(full_gyro < 1e-3, "full vs gyroscopic {full_gyro:e}");
    assert!(full_lin < 5e-2, "full vs linear {full_lin:e}");
    assert!(
        full_lin > full_gyro,
        "the linear model should be the coarser one"
    );
}

#[test]
fn earth_rate_sets_the_directive_moment() {
    // τ = IΩε cos L is what the engine's slow mode sees: check through the undamped period at the
    // Equator against an independent formula.
    let sc = scene_from(&harbour(0.0, "", "", 1.0), &SceneOverrides::default());
    let h = sc.design.parameter("spin_momentum_n_m_s").expect("present");
    let ap = sc
        .design
        .parameter("pendulous_moment_n_m")
        .expect("present");
    let t = TAU * (h / (ap * EARTH_RATE_RAD_PER_S)).sqrt();
    assert!((theory(&sc.design, 0.0).undamped_period() - t).abs() < 1e-9);
}
