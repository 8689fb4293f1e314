//! Damped sinusoids with known answers: period within 0.1 % and decrement within 1 % where the
//! data allow it, an honest uncertainty everywhere, and a refusal where they do not.
#![allow(clippy::unwrap_used)]

use crate::common;

use std::f64::consts::PI;

use common::Noise;
use gyro_analysis::fit::{FitOptions, Quality, fit_damped_sinusoid};

struct Case {
    period_s: f64,
    log_decrement: f64,
    cycles: f64,
    /// Initial amplitude over the noise σ per sample (1 Hz).
    snr: f64,
    drift_per_s: f64,
}

fn signal(c: &Case, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let duration = c.cycles * c.period_s;
    let n = duration as usize + 1;
    let sigma = c.log_decrement / c.period_s;
    let amp = 0.05;
    let noise = amp / c.snr;
    let mut rng = Noise::new(seed);
    let t: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let x = t
        .iter()
        .map(|&t| {
            0.01 + c.drift_per_s * t
                + amp * (-sigma * t).exp() * (2.0 * PI * t / c.period_s + 0.7).cos()
                + noise * rng.gauss()
        })
        .collect();
    (t, x)
}

#[test]
fn period_and_decrement_where_the_data_allow() {
    let (mut checked, mut allowed_t, mut allowed_l) = (0, 0, 0);
    for &period_s in &[3600.0, 4110.0] {
        for &log_decrement in &[0.0, 0.1, 0.7, 1.5] {
            for &cycles in &[3.0, 8.0, 24.0] {
                for &snr in &[1e4, 100.0, 20.0] {
                    for &drift in &[0.0, 2e-8] {
                        let case = Case {
                            period_s,
                            log_decrement,
                            cycles,
                            snr,
                            drift_per_s: drift,
                        };
                        let (t, x) = signal(&case, checked as u64 + 1);
                        let fit = fit_damped_sinusoid(&t, &x, &FitOptions::default());
                        let label = format!(
                            "T {period_s}, Λ {log_decrement}, {cycles} cycles, SNR {snr}, drift {drift}: {}",
                            fit.message
                        );
                        assert_eq!(fit.quality, Quality::Ok, "{label}");
                        let p = fit.period_s.unwrap();
                        let l = fit.log_decrement.unwrap();
                        // "Where the data allow it": the fit's own 1-σ is within a third of the
                        // requirement; then the error must meet the requirement. Clean data
                        // (SNR ≥ 100 with 8 or more cycles) must always allow it.
                        let rel_t = (p.value - period_s).abs() / period_s;
                        let t_allowed = p.sigma / period_s < 1e-3 / 3.0;
                        let l_allowed = log_decrement > 0.0 && l.sigma / log_decrement < 1e-2 / 3.0;
                        let clean = snr >= 100.0 && cycles >= 8.0;
                        if clean {
                            assert!(t_allowed, "clean data, σ_T {:.2e}: {label}", p.sigma);
                        }
                        if t_allowed {
                            assert!(rel_t < 1e-3, "period off by {rel_t:.2e}: {label}");
                            allowed_t += 1;
                        }
                        // Honest uncertainty: the error within 5 σ.
                        assert!(
                            (p.value - period_s).abs() < 5.0 * p.sigma + 1e-9 * period_s,
                            "period error {:.3e} vs σ {:.3e}: {label}",
                            p.value - period_s,
                            p.sigma
                        );
                        assert!(
                            (l.value - log_decrement).abs() < 5.0 * l.sigma + 1e-9,
                            "decrement error {:.3e} vs σ {:.3e}: {label}",
                            l.value - log_decrement,
                            l.sigma
                        );
                        if clean && log_decrement >= 0.1 {
                            assert!(l_allowed, "clean data, σ_Λ {:.2e}: {label}", l.sigma);
                        }
                        if l_allowed {
                            let rel_l = (l.value - log_decrement).abs() / log_decrement;
                            assert!(rel_l < 1e-2, "decrement off by {rel_l:.2e}: {label}");
                            allowed_l += 1;
                        }
                        if log_decrement == 0.0 && snr >= 100.0 {
                            assert!(l.value.abs() < 2e-3, "decrement {}: {label}", l.value);
                        }
                        let zeta = fit.damping_ratio.unwrap();
                        let want = log_decrement / (4.0 * PI * PI + log_decrement.powi(2)).sqrt();
                        assert!(
                            (zeta.value - want).abs() < 1e-2 * want + 5.0 * zeta.sigma,
                            "ζ {zeta:?}: {label}"
                        );
                        checked += 1;
                    }
                }
            }
        }
    }
    assert_eq!(checked, 2 * 4 * 3 * 3 * 2);
    // The requirement is met, not dodged: most cases are ones where the data allow it.
    println!(
        "period checked to 0.1 % in {allowed_t} of {checked}, decrement to 1 % in {allowed_l} of {}",
        checked * 3 / 4
    );
    assert!(allowed_t >= checked * 3 / 4, "{allowed_t} of {checked}");
    assert!(
        allowed_l >= checked / 2,
        "{allowed_l} of {}",
        checked * 3 / 4
    );
}

#[test]
fn heavy_damping_with_few_cycles_still_resolves_when_clean() {
    // Λ = 3 (ζ ≈ 0.43, Beghin's Anschütz damped case): the swing falls 20-fold per period.
    let case = Case {
        period_s: 4110.0,
        log_decrement: 3.0,
        cycles: 4.0,
        snr: 1e4,
        drift_per_s: 0.0,
    };
    let (t, x) = signal(&case, 7);
    let fit = fit_damped_sinusoid(&t, &x, &FitOptions::default());
    assert_eq!(fit.quality, Quality::Ok, "{}", fit.message);
    let p = fit.period_s.unwrap().value;
    let l = fit.log_decrement.unwrap().value;
    assert!((p - 4110.0).abs() / 4110.0 < 1e-3, "{p}");
    assert!((l - 3.0).abs() / 3.0 < 1e-2, "{l}");
}

#[test]
fn low_snr_reports_a_wide_but_honest_uncertainty() {
    // SNR 2 per sample over 3 cycles: the fit stands, and its σ covers its error.
    let case = Case {
        period_s: 3600.0,
        log_decrement: 0.3,
        cycles: 3.0,
        snr: 2.0,
        drift_per_s: 0.0,
    };
    let mut covered = 0;
    for seed in 0..20 {
        let (t, x) = signal(&case, 100 + seed);
        let fit = fit_damped_sinusoid(&t, &x, &FitOptions::default());
        if let Some(p) = fit.period_s
            && (p.value - 3600.0).abs() < 3.0 * p.sigma
        {
            covered += 1;
        }
    }
    assert!(
        covered >= 18,
        "3σ covered the error in {covered} of 20 runs"
    );
}

/// A release damped at ζ = 0.5–0.7 overshoots once and turns a second time under 3 % of the
/// swing: the fit still finds its period and decrement (clean data), as Beghin's damped
/// compasses at high latitude need.
#[test]
fn fits_a_heavily_damped_release() {
    let t: Vec<f64> = (0..21_600).map(|i| i as f64).collect();
    for zeta in [0.5, 0.6, 0.7] {
        let period = 5000.0;
        let w = std::f64::consts::TAU / period;
        let sigma = zeta * w / (1.0 - zeta * zeta).sqrt();
        // Released from rest: x(0) = A, ẋ(0) = 0.
        let x: Vec<f64> = t
            .iter()
            .map(|&t| {
                -0.02 + 0.08 * (-sigma * t).exp() * ((w * t).cos() + sigma / w * (w * t).sin())
            })
            .collect();
        let fit = fit_damped_sinusoid(&t, &x, &FitOptions::default());
        assert_eq!(fit.quality, Quality::Ok, "ζ = {zeta}: {}", fit.message);
        let p = fit.period_s.expect("period").value;
        let decrement = fit.log_decrement.expect("decrement").value;
        assert!((p / period - 1.0).abs() < 1e-3, "ζ = {zeta}: period {p}");
        assert!(
            (decrement / (sigma * period) - 1.0).abs() < 1e-3,
            "ζ = {zeta}: decrement {decrement}"
        );
    }
}

#[test]
fn refuses_an_overdamped_response() {
    // Critically damped and overdamped: x = c + A(1 + t/τ)e^{−t/τ}, and two exponentials.
    let t: Vec<f64> = (0..20_000).map(|i| i as f64).collect();
    let crit: Vec<f64> = t
        .iter()
        .map(|&t| 0.02 + 0.1 * (1.0 + t / 1500.0) * (-t / 1500.0).exp())
        .collect();
    let over: Vec<f64> = t
        .iter()
        .map(|&t| 0.1 * (-t / 800.0).exp() - 0.04 * (-t / 3000.0).exp())
        .collect();
    for (name, x) in [("critical", crit), ("overdamped", over)] {
        let fit = fit_damped_sinusoid(&t, &x, &FitOptions::default());
        assert_eq!(fit.quality, Quality::Aperiodic, "{name}: {}", fit.message);
        assert!(fit.period_s.is_none() && fit.log_decrement.is_none());
    }
}

#[test]
fn refuses_noise_and_drift_alone() {
    let mut rng = Noise::new(3);
    let t: Vec<f64> = (0..30_000).map(|i| i as f64).collect();
    let noise: Vec<f64> = t.iter().map(|_| 1e-3 * rng.gauss()).collect();
    let drift: Vec<f64> = t.iter().map(|&t| 1e-6 * t + 1e-3 * rng.gauss()).collect();
    let flat = vec![0.25; t.len()];
    for (name, x) in [("noise", noise), ("drift", drift), ("flat", flat)] {
        let fit = fit_damped_sinusoid(&t, &x, &FitOptions::default());
        assert_eq!(
            fit.quality,
            Quality::NotOscillatory,
            "{name}: {}",
            fit.message
        );
        assert!(fit.period_s.is_none());
    }
}

#[test]
fn refuses_fewer_than_one_and_a_half_cycles() {
    for cycles in [0.6, 1.0, 1.3] {
        let case = Case {
            period_s: 3600.0,
            log_decrement: 0.1,
            cycles,
            snr: 1e4,
            drift_per_s: 0.0,
        };
        let (t, x) = signal(&case, 11);
        let fit = fit_damped_sinusoid(&t, &x, &FitOptions::default());
        assert_eq!(
            fit.quality,
            Quality::TooFewCycles,
            "{cycles} cycles: {}",
            fit.message
        );
        assert!(fit.period_s.is_none());
    }
}

#[test]
fn refuses_too_short_and_garbage_without_panicking() {
    let opts = FitOptions::default();
    assert_eq!(
        fit_damped_sinusoid(&[], &[], &opts).quality,
        Quality::TooShort
    );
    let t: Vec<f64> = (0..10).map(|i| i as f64).collect();
    assert_eq!(
        fit_damped_sinusoid(&t, &t, &opts).quality,
        Quality::TooShort
    );
    let nan = vec![f64::NAN; 1000];
    let t: Vec<f64> = (0..1000).map(|i| i as f64).collect();
    assert_eq!(
        fit_damped_sinusoid(&t, &nan, &opts).quality,
        Quality::TooShort
    );
    let backwards: Vec<f64> = (0..1000).map(|i| -(i as f64)).collect();
    assert_eq!(
        fit_damped_sinusoid(&backwards, &t, &opts).quality,
        Quality::TooShort
    );
    let inf: Vec<f64> = t
        .iter()
        .map(|&v| if v > 500.0 { f64::INFINITY } else { v.sin() })
        .collect();
    let _ = fit_damped_sinusoid(&t, &inf, &opts);
    let huge: Vec<f64> = t.iter().map(|&v| 1e300 * (v / 50.0).sin()).collect();
    let _ = fit_damped_sinusoid(&t, &huge, &opts);
    let _ = fit_damped_sinusoid(&t[..500], &t, &opts);
}
