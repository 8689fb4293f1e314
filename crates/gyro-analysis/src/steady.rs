//! The steady reading error: the value a settling signal settles to (with its drift), as the
//! offset-and-drift line of a damped-sinusoid fit where that fit stands, else as a straight line
//! fitted over the tail of the window (trimmed to whole periods when the period is known, so a
//! residual oscillation averages out).

use serde::{Deserialize, Serialize};

use crate::fit::{Estimate, OscillationFit, Quality, line_fit};

/// How the steady value was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SteadyMethod {
    /// c + d·(t − t₀) of a damped-sinusoid fit that stands.
    OscillationFit,
    /// A line fitted over the tail of the window.
    TailLine,
}

/// The settled value and its drift.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SteadyError {
    pub quality: Quality,
    pub message: String,
    /// The settled value at `at_time_s` (the end of the window).
    pub value: Option<Estimate>,
    /// Its drift per second.
    pub drift_per_s: Option<Estimate>,
    pub at_time_s: f64,
    pub method: SteadyMethod,
    /// The samples the estimate rests on.
    pub window_s: (f64, f64),
}

/// Settings of [`steady_error`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyOptions {
    /// Fraction of the window (at its end) used by the tail line (default 0.25).
    pub tail_fraction: f64,
    /// Fewest samples in the tail (default 10).
    pub min_samples: usize,
}

impl Default for SteadyOptions {
    fn default() -> Self {
        Self {
            tail_fraction: 0.25,
            min_samples: 10,
        }
    }
}

/// The steady value of (t, x). `fit` is a damped-sinusoid fit of the same window (used when it
/// stands); `period_s` a known period (whole periods are kept in the tail).
pub fn steady_error(
    t: &[f64],
    x: &[f64],
    fit: Option<&OscillationFit>,
    period_s: Option<f64>,
    opts: &SteadyOptions,
) -> SteadyError {
    let n = t.len().min(x.len());
    let (t, x) = (&t[..n], &x[..n]);
    let t_end = t.last().copied().unwrap_or(f64::NAN);
    let t_start = t.first().copied().unwrap_or(f64::NAN);
    if let Some(f) = fit.filter(|f| f.quality.is_ok())
        && let (Some(v), Some(d)) = (f.settled_value(t_end), f.drift_per_s)
    {
        return SteadyError {
            quality: Quality::Ok,
            message: "offset and drift of the damped-sinusoid fit".to_owned(),
            value: Some(v),
            drift_per_s: Some(d),
            at_time_s: t_end,
            method: SteadyMethod::OscillationFit,
            window_s: f.window_s,
        };
    }
    let refuse = |message: String| SteadyError {
        quality: Quality::TooShort,
        message,
        value: None,
        drift_per_s: None,
        at_time_s: t_end,
        method: SteadyMethod::TailLine,
        window_s: (t_start, t_end),
    };
    if n < opts.min_samples || !crate::fit::above(t_end, t_start) {
        return refuse(format!(
            "{n} samples; a steady value needs at least {}",
            opts.min_samples
        ));
    }
    let span = t_end - t_start;
    let mut from = t_end - opts.tail_fraction.clamp(0.01, 1.0) * span;
    if let Some(p) = period_s.filter(|p| *p > 0.0 && p.is_finite()) {
        // Whole periods: at least one, as many as fit in the tail.
        let periods = ((t_end - from) / p).floor().max(1.0);
        if periods * p <= span {
            from = t_end - periods * p;
        }
    }
    let start = t.partition_point(|v| *v < from);
    let (tt, xx): (Vec<f64>, Vec<f64>) = t[start..]
        .iter()
        .zip(&x[start..])
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a - t_end, *b))
        .unzip();
    if tt.len() < opts.min_samples {
        return refuse(format!(
            "{} finite samples in the tail; a steady value needs at least {}",
            tt.len(),
            opts.min_samples
        ));
    }
    // Line about the window end: intercept = value at t_end.
    let (c, d) = line_fit(&tt, &xx);
    let m = tt.len() as f64;
    let mean_t = tt.iter().sum::<f64>() / m;
    let stt: f64 = tt.iter().map(|v| (v - mean_t).powi(2)).sum();
    let rss: f64 = tt
        .iter()
        .zip(&xx)
        .map(|(a, b)| (b - c - d * a).powi(2))
        .sum();
    let s2 = rss / (m - 2.0).max(1.0);
    let var_d = if stt > 0.0 { s2 / stt } else { f64::NAN };
    let var_c = s2 / m + mean_t * mean_t * var_d;
    SteadyError {
        quality: Quality::Ok,
        message: format!("line over the last {:.4e} s ({} samples)", -tt[0], tt.len()),
        value: Some(Estimate::new(c, var_c.max(0.0).sqrt())),
        drift_per_s: Some(Estimate::new(d, var_d.max(0.0).sqrt())),
        at_time_s: t_end,
        method: SteadyMethod::TailLine,
        window_s: (tt[0] + t_end, t_end),
    }
}
