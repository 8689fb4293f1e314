//! The analysis of recordings of the shipped designs agrees with the closed forms of the
//! reference texts: the simulation records a scene through the same path as `gyrolab run`, the
//! analysis reads the MCAP file back and fits, and the fitted numbers are checked against
//! Beghin's formulas (`gyro_model::theory`), each to the tolerance its assertion states.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use gyro_analysis::load::SHIP_TOPIC;
use gyro_analysis::{AnalysisOptions, Quality, RunAnalysis, analyze_run, load_run};
use gyro_model::constants::{EARTH_RATE_RAD_PER_S, KNOT_IN_M_PER_S, schuler_period_s};
use gyro_model::theory::{Anschutz, foucault_villarceau, speed_error_rad};
use gyro_sim::{RecordOptions, Scene, SceneOverrides};
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gyrolab-physics-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn root() -> PathBuf {
    gyro_testkit::repo_root!()
}

/// Records `scene` to `dir/NAME.mcap` and analyses the file.
fn record_and_analyze(scene: &Scene, dir: &Path, name: &str) -> (PathBuf, RunAnalysis) {
    let path = dir.join(format!("{name}.mcap"));
    let s = gyro_sim::record(scene, &path, RecordOptions::default()).expect("records");
    assert!(s.interrupted_at_s.is_none());
    let a = analyze_run(&path, &AnalysisOptions::default()).expect("analyses");
    (path, a)
}

fn shipped(name: &str) -> Scene {
    Scene::load(name, &SceneOverrides::default()).expect("shipped scene")
}

fn scene_text(name: &str) -> String {
    std::fs::read_to_string(root().join("scenes").join(format!("{name}.toml"))).unwrap()
}

fn scene_from(text: &str, dir: &Path, name: &str) -> Scene {
    // Written beside the shipped scenes' folder layout is not needed: designs are found by name.
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    Scene::load(p.to_str().unwrap(), &SceneOverrides::default()).expect("scene")
}

fn anschutz(scene: &Scene, latitude_deg: f64) -> Anschutz {
    let d = &scene.design;
    Anschutz {
        spin_momentum: d.parameter("spin_momentum_n_m_s").unwrap(),
        pendulous_moment: d.parameter("pendulous_moment_n_m").unwrap(),
        kappa: d.parameter("kappa_n_m").unwrap(),
        // ℭ and 𝔅 move the slow roots by ~ℭaP/(IΩ)² ≈ 1e-4 only.
        inertia_vertical: 0.08,
        inertia_east_west: 0.08,
        latitude_rad: latitude_deg.to_radians(),
    }
}

/// Eq. 18: the damper's latitude error away from the compensation latitude L₀,
/// κ (sin L₀ − sin L)/(aP cos L).
fn latitude_error_rad(scene: &Scene, latitude_rad: f64) -> f64 {
    let d = &scene.design;
    let l0 = d
        .parameter("compensation_latitude_deg")
        .unwrap()
        .to_radians();
    d.parameter("kappa_n_m").unwrap() * (l0.sin() - latitude_rad.sin())
        / (d.parameter("pendulous_moment_n_m").unwrap() * latitude_rad.cos())
}

#[test]
fn fitted_period_and_decrement_of_the_anschutz_match_the_slow_roots() {
    let dir = tmp("settle");
    let scene = shipped("harbour-50n");
    let (_, a) = record_and_analyze(&scene, &dir, "harbour-50n");
    assert_eq!(a.azimuth.quality, Quality::Ok, "{}", a.azimuth.message);
    let roots = anschutz(&scene, 50.0).characteristic_roots();
    let (sigma, omega) = (-roots[0].0, roots[0].1.abs());
    let period = std::f64::consts::TAU / omega;
    let decrement = sigma * period;
    let m = &a.metrics;
    let (p, l) = (m.period_s.unwrap(), m.log_decrement.unwrap());
    println!(
        "harbour-50n: fitted period {p:.1} s, decrement {l:.4}; theory {period:.1} s, {decrement:.4}"
    );
    assert!((p / period - 1.0).abs() < 0.01, "period {p} vs {period}");
    assert!(
        (l / decrement - 1.0).abs() < 0.01,
        "decrement {l} vs {decrement}"
    );
    // Damping ratio: Schuler's 4110/3700 the design was tuned to.
    let xi = (1.0 - (3700.0f64 / 4110.0).powi(2)).sqrt();
    assert!((m.damping_ratio.unwrap() / xi - 1.0).abs() < 0.01);
    // The tilt oscillates with the same mode.
    assert!((m.tilt_period_s.unwrap() / period - 1.0).abs() < 0.01);
    // Settled on the meridian at the compensation latitude: no latitude error.
    assert!(m.steady_error_rad.unwrap().abs() < 1e-3f64.to_radians());
}

#[test]
fn latitude_error_from_analyze_matches_eq_18() {
    let dir = tmp("latitude");
    for (name, lat) in [("harbour-30n", 30.0f64), ("harbour-70n", 70.0)] {
        let scene = shipped(name);
        let (_, a) = record_and_analyze(&scene, &dir, name);
        let expect = latitude_error_rad(&scene, lat.to_radians());
        let got = a.metrics.steady_error_rad.unwrap();
        println!(
            "{name}: steady error {:.4}° vs eq. 18 {:.4}°",
            got.to_degrees(),
            expect.to_degrees()
        );
        assert!(expect.abs() > 0.1f64.to_radians(), "a visible error");
        assert!(
            (got / expect - 1.0).abs() < 0.02,
            "{name}: {got} vs {expect}"
        );
    }
}

#[test]
fn undamped_foucault_period_matches_villarceau() {
    let dir = tmp("foucault");
    let mut scene = shipped("foucault-azimuth-45n");
    // Released 10° from the centre of Villarceau's oscillation (the hour plane's hinge angle
    // plus the centre's offset), so the exact period is known.
    let lat = scene.start_latitude_rad;
    let gi = scene.design.coordinate_index("gamma").unwrap();
    let amplitude = 10f64.to_radians();
    let villarceau = |scene: &Scene| {
        let sim = gyro_sim::Simulation::new(scene).unwrap();
        let torus = sim.model.design.body_index("torus").unwrap();
        foucault_villarceau(&sim.model.design, sim.model.spin_momentum[torus], lat).unwrap()
    };
    let (v0, offset) = villarceau(&scene);
    scene.initial.offsets_rad = vec![(gi, offset + v0.centre() + amplitude)];
    // n = w + ω cos θ₀ depends on the start: Villarceau's constants of this start.
    let (v, _) = villarceau(&scene);
    let period = v.period(amplitude);
    let (_, a) = record_and_analyze(&scene, &dir, "foucault");
    let m = &a.metrics;
    let p = m.period_s.unwrap();
    println!("foucault: fitted period {p:.4} s vs Villarceau {period:.4} s");
    assert!((p / period - 1.0).abs() < 1e-3, "{p} vs {period}");
    // Undamped: the fitted decrement is nil to the fit's resolution.
    assert!(
        m.log_decrement.unwrap().abs() < 1e-3,
        "{:?}",
        m.log_decrement
    );
}

#[test]
fn speed_error_from_analyze_matches_beghin_30() {
    let dir = tmp("speed");
    let scene = shipped("run-north-30kn");
    let (path, a) = record_and_analyze(&scene, &dir, "run-north-30kn");
    let run = load_run(&path, &Default::default()).unwrap();
    let t = run.f64_field(SHIP_TOPIC, "time_s").unwrap();
    let lat = run.f64_field(SHIP_TOPIC, "latitude_rad").unwrap();
    // The settled value is given at the end of its window: the ship's latitude there.
    let at = a.steady.at_time_s;
    let i = t.iter().position(|&x| x >= at).unwrap_or(t.len() - 1);
    let l = lat[i];
    let expect = speed_error_rad(30.0 * KNOT_IN_M_PER_S, 0.0, l) + latitude_error_rad(&scene, l);
    let got = a.metrics.steady_error_rad.unwrap();
    println!(
        "run-north-30kn: steady error {:.4}° at {:.2}°N vs tan ζ = v cos α/(V cos L − v sin α) + eq. 18: {:.4}°",
        got.to_degrees(),
        l.to_degrees(),
        expect.to_degrees()
    );
    assert!((got / expect - 1.0).abs() < 0.02, "{got} vs {expect}");
}

/// The 20-kn stop with an undamped Anschütz of undamped period `period_s` at 50°N.
fn stop_with_period(dir: &Path, period_s: f64, name: &str) -> RunAnalysis {
    let h = 2e4 * 1e-7 / 7e-5;
    let lat = 50f64.to_radians();
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
            "fidelity = \"gyroscopic\"\ndisable_effects = [\"damper\"]",
        );
    let scene = scene_from(&text, dir, name);
    record_and_analyze(&scene, dir, name).1
}

#[test]
fn one_ballistic_row_per_speed_change_and_schuler_tuning_removes_it() {
    let dir = tmp("ballistic");
    // The shipped scene (damped Anschütz 1906): exactly one manoeuvre, one row.
    let scene = shipped("speed-change-20kn");
    let (_, a) = record_and_analyze(&scene, &dir, "speed-change-20kn");
    assert_eq!(a.ballistic.len(), 1, "{:?}", a.ballistic);
    assert_eq!(a.metrics.ballistic_events, 1);
    let b = &a.ballistic[0];
    assert_eq!(b.manoeuvre, "speed_change");
    assert!((b.start_s - 3600.0).abs() < 1e-6 && (b.end_s - 3660.0).abs() < 1e-6);
    // The shift of the equilibrium is the loss of the 20-kn speed error.
    let shift = b.speed_error_shift_rad.unwrap();
    let expect = -speed_error_rad(20.0 * KNOT_IN_M_PER_S, 0.0, 50f64.to_radians());
    assert!((shift / expect - 1.0).abs() < 0.02, "{shift} vs {expect}");

    let tuned = stop_with_period(&dir, schuler_period_s(), "tuned");
    let detuned = stop_with_period(&dir, 63.0 * 60.0, "detuned");
    for r in [&tuned, &detuned] {
        assert_eq!(r.ballistic.len(), 1);
    }
    let peak = |r: &RunAnalysis| r.ballistic[0].peak_deviation_rad.unwrap().abs();
    let (pt, pd) = (peak(&tuned), peak(&detuned));
    println!(
        "20-kn stop: peak deviation from the new equilibrium, Schuler-tuned {:.4}°, 63-min {:.4}° (expected {:.4}°)",
        pt.to_degrees(),
        pd.to_degrees(),
        detuned.ballistic[0]
            .expected_peak_deviation_rad
            .unwrap()
            .to_degrees()
    );
    assert!(pt < 0.1 * pd, "tuned {pt} vs detuned {pd}");
    assert!(pt < 0.05 * expect.abs(), "tuned {pt} vs shift {expect}");
    // Elementary theory: the detuned compass swings by (T_S²/T² − 1)·shift.
    let e = detuned.ballistic[0]
        .expected_peak_deviation_rad
        .unwrap()
        .abs();
    assert!((pd / e - 1.0).abs() < 0.1, "{pd} vs {e}");
}
