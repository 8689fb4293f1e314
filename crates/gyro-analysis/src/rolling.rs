//! Rolling error: the rectified mean reading error under a sea state (Beghin §40), separated from
//! the free oscillation of the compass.
//!
//! The roll period comes from the upward zero crossings of the ship's roll; the error is
//! averaged over each whole roll period between them (which removes the oscillation at the roll
//! frequency and leaves its rectified mean); a damped sinusoid fitted to those means is the free
//! oscillation, and what remains (offset and drift, or the plain mean over whole compass periods
//! when no free oscillation stands out) is the rolling error.

use serde::{Deserialize, Serialize};

use crate::fit::{Estimate, FitOptions, OscillationFit, Quality, fit_damped_sinusoid};

/// The rolling error of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RollingError {
    pub quality: Quality,
    pub message: String,
    /// Mean roll period (upward crossing to upward crossing).
    pub roll_period_s: f64,
    /// Roll amplitude (√2 × RMS about the mean).
    pub roll_amplitude_rad: f64,
    /// Mean of the error over whole roll periods, with the free oscillation removed.
    pub mean_error: Option<Estimate>,
    /// The settled value (offset + drift at the end of the window) under rolling.
    pub settled_error: Option<Estimate>,
    /// Whole roll periods averaged.
    pub roll_periods: usize,
    /// The free oscillation fitted to the per-roll means.
    pub free_oscillation: Option<OscillationFit>,
}

/// Settings of [`rolling_error`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RollingOptions {
    /// A roll below this amplitude is no sea state (default 1e-4 rad).
    pub min_roll_amplitude_rad: f64,
    /// Only samples at or after this time (e.g. after the last manoeuvre).
    pub from_s: f64,
    pub fit: FitOptions,
}

impl Default for RollingOptions {
    fn default() -> Self {
        Self {
            min_roll_amplitude_rad: 1e-4,
            from_s: f64::NEG_INFINITY,
            fit: FitOptions::default(),
        }
    }
}

/// The rolling error of the reading error (t, error) under the ship's roll (ship_t, roll);
/// `None` when the ship does not roll. `compass_period_s`: a known compass period (used to
/// average whole periods when no free oscillation is resolved).
pub fn rolling_error(
    t: &[f64],
    error: &[f64],
    ship_t: &[f64],
    roll: &[f64],
    compass_period_s: Option<f64>,
    opts: &RollingOptions,
) -> Option<RollingError> {
    let m = ship_t.len().min(roll.len());
    let start = ship_t[..m].partition_point(|v| *v < opts.from_s);
    let (st, sr) = (&ship_t[start..m], &roll[start..m]);
    let finite: Vec<f64> = sr.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.len() < 4 {
        return None;
    }
    let mean = finite.iter().sum::<f64>() / finite.len() as f64;
    let rms = (finite.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / finite.len() as f64).sqrt();
    let amplitude = std::f64::consts::SQRT_2 * rms;
    if !crate::fit::above(amplitude, opts.min_roll_amplitude_rad) {
        return None;
    }
    // Upward crossings of the mean, linearly interpolated.
    let mut ups = Vec::new();
    for i in 1..st.len() {
        let (a, b) = (sr[i - 1] - mean, sr[i] - mean);
        if a < 0.0 && b >= 0.0 {
            let f = if b - a != 0.0 { -a / (b - a) } else { 0.0 };
            ups.push(st[i - 1] + f * (st[i] - st[i - 1]));
        }
    }
    let mut r = RollingError {
        quality: Quality::TooShort,
        message: String::new(),
        roll_period_s: f64::NAN,
        roll_amplitude_rad: amplitude,
        mean_error: None,
        settled_error: None,
        roll_periods: 0,
        free_oscillation: None,
    };
    if ups.len() < 3 {
        r.message = format!("{} upward roll crossings; at least 3 needed", ups.len());
        return Some(r);
    }
    r.roll_period_s = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
    // Mean error over each whole roll period.
    let n = t.len().min(error.len());
    let (t, error) = (&t[..n], &error[..n]);
    let mut bt = Vec::with_capacity(ups.len());
    let mut bx = Vec::with_capacity(ups.len());
    for w in ups.windows(2) {
        let (i0, i1) = (
            t.partition_point(|v| *v < w[0]),
            t.partition_point(|v| *v < w[1]),
        );
        let vals: Vec<f64> = error[i0..i1]
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        if vals.is_empty() {
            continue;
        }
        bt.push(0.5 * (w[0] + w[1]));
        bx.push(vals.iter().sum::<f64>() / vals.len() as f64);
    }
    r.roll_periods = bt.len();
    if bt.len() < 3 {
        r.message = format!("{} whole roll periods with samples", bt.len());
        return Some(r);
    }
    let fit = fit_damped_sinusoid(&bt, &bx, &opts.fit);
    let t_end = bt[bt.len() - 1];
    if fit.quality.is_ok() {
        if let Some(model) = fit.model {
            let residual: Vec<f64> = bt
                .iter()
                .zip(&bx)
                .map(|(a, b)| b - model.oscillation(*a))
                .collect();
            r.mean_error = Some(mean_estimate(&residual));
            r.settled_error = fit.settled_value(t_end);
            r.quality = Quality::Ok;
            r.message = format!(
                "{} roll periods of {:.2} s; free oscillation of {:.0} s removed",
                bt.len(),
                r.roll_period_s,
                model.period_s
            );
        }
    } else {
        // No free oscillation stands out: average whole compass periods where one is known.
        let from = match compass_period_s.filter(|p| *p > 0.0) {
            Some(p) if t_end - bt[0] >= p => {
                let whole = ((t_end - bt[0]) / p).floor() * p;
                t_end - whole
            }
            _ => bt[0],
        };
        let i0 = bt.partition_point(|v| *v < from);
        r.mean_error = Some(mean_estimate(&bx[i0..]));
        r.settled_error = r.mean_error;
        r.quality = Quality::Ok;
        r.message = format!(
            "{} roll periods of {:.2} s; no free oscillation resolved ({})",
            bt.len(),
            r.roll_period_s,
            fit.quality
        );
    }
    r.free_oscillation = Some(fit);
    Some(r)
}

fn mean_estimate(v: &[f64]) -> Estimate {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    Estimate::new(mean, (var / n).sqrt())
}
