//! Period and logarithmic decrement of a settling oscillation: a damped sinusoid plus offset
//! (and drift), fitted by Levenberg–Marquardt, seeded from the extremes of the signal.
//!
//! Model, with t₀ the first sample of the window:
//! x(t) = c + d·(t − t₀) + A·e^{−σ(t − t₀)}·cos(2π(t − t₀)/T + φ).
//! Inside, time is scaled to the window (u = (t − t₀)/W) and x to its spread, and the amplitude
//! and phase are carried as the linear pair (a, b) of a·cos ωu + b·sin ωu, so every column of the
//! Jacobian is of order one. The covariance is (JᵀJ)⁻¹ at the solution times the residual
//! variance; 1-σ uncertainties of T, Λ = σT and ζ = Λ/√(4π² + Λ²) follow by linearisation.
//!
//! Seeds come from the turning points of the signal (a zig-zag with a hysteresis above the
//! noise): T from the spacing of successive extremes (twice the spacing of zero crossings of the
//! detrended signal, measured where the signal is clean), σ from the decay of successive swings.
//! Long series are first averaged in blocks to at most [`FitOptions::max_samples`] points (a block
//! of 10 s attenuates a one-hour oscillation by 10⁻⁵ and shifts neither period nor decay).
//!
//! The fit refuses, with a [`Quality`] flag and a message, when the data do not allow an answer:
//! too few samples, no oscillation above the noise, an overdamped (aperiodic) response, or fewer
//! than [`FitOptions::min_cycles`] cycles in the window.

use std::f64::consts::PI;
use std::fmt;

use serde::{Deserialize, Serialize};

/// How far a fit (or a detector built on one) could go.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quality {
    /// The estimate stands, with its uncertainty.
    Ok,
    /// Fewer than the minimum number of cycles in the window: the period is not pinned.
    TooFewCycles,
    /// No oscillation stands above the noise (and drift).
    NotOscillatory,
    /// Overdamped: the signal settles without a second extreme.
    Aperiodic,
    /// Too few samples (or too short a window) for any estimate.
    TooShort,
}

impl Quality {
    pub fn as_str(self) -> &'static str {
        match self {
            Quality::Ok => "ok",
            Quality::TooFewCycles => "too_few_cycles",
            Quality::NotOscillatory => "not_oscillatory",
            Quality::Aperiodic => "aperiodic",
            Quality::TooShort => "too_short",
        }
    }

    pub fn is_ok(self) -> bool {
        self == Quality::Ok
    }
}

impl fmt::Display for Quality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Quality {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s {
            "ok" => Quality::Ok,
            "too_few_cycles" => Quality::TooFewCycles,
            "not_oscillatory" => Quality::NotOscillatory,
            "aperiodic" => Quality::Aperiodic,
            "too_short" => Quality::TooShort,
            _ => return Err(format!("unknown quality {s:?}")),
        })
    }
}

/// A value with its 1-σ uncertainty.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    pub value: f64,
    pub sigma: f64,
}

impl Estimate {
    pub fn new(value: f64, sigma: f64) -> Self {
        Self { value, sigma }
    }
}

/// Settings of [`fit_damped_sinusoid`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Fit a linear drift d (default true).
    pub drift: bool,
    /// Longer series are block-averaged to at most this many points (default 8192: one point per
    /// ~10.5 s over a day).
    pub max_samples: usize,
    /// Fewer cycles than this in the window: [`Quality::TooFewCycles`] (default 1.5).
    pub min_cycles: f64,
    /// Fewer samples than this (after removing non-finite ones): [`Quality::TooShort`] (default 20).
    pub min_samples: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            drift: true,
            max_samples: 8192,
            min_cycles: 1.5,
            min_samples: 20,
        }
    }
}

/// The fitted curve, in physical units:
/// x(t) = offset + drift_per_s·(t − t0_s) + amplitude·e^{−decay_rate_per_s·(t − t0_s)}·cos(2π(t − t0_s)/period_s + phase_rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DampedSinusoid {
    pub t0_s: f64,
    pub offset: f64,
    pub drift_per_s: f64,
    pub amplitude: f64,
    pub decay_rate_per_s: f64,
    pub period_s: f64,
    pub phase_rad: f64,
}

impl DampedSinusoid {
    /// The whole model at `t_s`.
    pub fn eval(&self, t_s: f64) -> f64 {
        self.offset + self.drift_per_s * (t_s - self.t0_s) + self.oscillation(t_s)
    }

    /// The oscillating part only (no offset, no drift).
    pub fn oscillation(&self, t_s: f64) -> f64 {
        let dt = t_s - self.t0_s;
        self.amplitude
            * (-self.decay_rate_per_s * dt).exp()
            * (2.0 * PI * dt / self.period_s + self.phase_rad).cos()
    }

    /// The envelope offset + drift ± amplitude·e^{−σ(t − t₀)} (sign +1 or −1).
    pub fn envelope(&self, t_s: f64, sign: f64) -> f64 {
        let dt = t_s - self.t0_s;
        self.offset
            + self.drift_per_s * dt
            + sign * self.amplitude.abs() * (-self.decay_rate_per_s * dt).exp()
    }
}

/// The result of [`fit_damped_sinusoid`]. Estimates are present only when `quality` is
/// [`Quality::Ok`]; `model` is also kept for [`Quality::TooFewCycles`] (a provisional curve).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OscillationFit {
    pub quality: Quality,
    /// Why the fit refused, or a one-line summary when it stands.
    pub message: String,
    pub period_s: Option<Estimate>,
    /// Logarithmic decrement per period, Λ = σT.
    pub log_decrement: Option<Estimate>,
    /// ζ = Λ/√(4π² + Λ²).
    pub damping_ratio: Option<Estimate>,
    pub decay_rate_per_s: Option<Estimate>,
    /// Amplitude at the start of the window.
    pub amplitude: Option<Estimate>,
    /// c: the offset at the start of the window.
    pub offset: Option<Estimate>,
    /// d (zero with zero uncertainty when the drift is not fitted).
    pub drift_per_s: Option<Estimate>,
    /// Covariance of (offset, drift): [var c, cov(c, d), var d].
    pub offset_drift_cov: [f64; 3],
    pub model: Option<DampedSinusoid>,
    /// Window length over the fitted period.
    pub cycles: f64,
    /// Points the fit used (after block averaging).
    pub samples_used: usize,
    /// RMS of the residual over every finite input sample (NaN when no model).
    pub residual_rms: f64,
    /// First and last time of the window.
    pub window_s: (f64, f64),
    /// Levenberg–Marquardt iterations of the accepted solution.
    pub iterations: usize,
}

impl OscillationFit {
    fn refused(quality: Quality, message: String, window_s: (f64, f64), samples: usize) -> Self {
        Self {
            quality,
            message,
            period_s: None,
            log_decrement: None,
            damping_ratio: None,
            decay_rate_per_s: None,
            amplitude: None,
            offset: None,
            drift_per_s: None,
            offset_drift_cov: [f64::NAN; 3],
            model: None,
            cycles: f64::NAN,
            samples_used: samples,
            residual_rms: f64::NAN,
            window_s,
            iterations: 0,
        }
    }

    /// The settled value c + d·(t − t₀) at `t_s`, with its uncertainty (when the fit stands).
    pub fn settled_value(&self, t_s: f64) -> Option<Estimate> {
        let (c, d, m) = (self.offset?, self.drift_per_s?, self.model?);
        let dt = t_s - m.t0_s;
        let [vc, cd, vd] = self.offset_drift_cov;
        let var = vc + 2.0 * dt * cd + dt * dt * vd;
        Some(Estimate::new(c.value + d.value * dt, var.max(0.0).sqrt()))
    }
}

/// a > b, false when either is NaN (so `!above(..)` reads "not known to be above").
pub(crate) fn above(a: f64, b: f64) -> bool {
    a > b
}

/// Block means: at most `max_samples` points, each the mean time and value of ⌈n/max⌉
/// consecutive samples. Non-finite samples are dropped first.
pub fn decimate(t: &[f64], x: &[f64], max_samples: usize) -> (Vec<f64>, Vec<f64>) {
    let (t, x): (Vec<f64>, Vec<f64>) = t
        .iter()
        .zip(x)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .unzip();
    let n = t.len();
    let k = n.div_ceil(max_samples.max(1)).max(1);
    if k == 1 {
        return (t, x);
    }
    let mut out_t = Vec::with_capacity(n / k + 1);
    let mut out_x = Vec::with_capacity(n / k + 1);
    for (bt, bx) in t.chunks(k).zip(x.chunks(k)) {
        // A short last block would be noisier than the others; fold it away when tiny.
        if bt.len() * 2 < k && !out_t.is_empty() {
            break;
        }
        let m = bt.len() as f64;
        out_t.push(bt.iter().sum::<f64>() / m);
        out_x.push(bx.iter().sum::<f64>() / m);
    }
    (out_t, out_x)
}

/// Fits the damped sinusoid to (t, x); see the module docs. Never panics on any input
/// (non-finite samples are ignored; times must increase).
pub fn fit_damped_sinusoid(t: &[f64], x: &[f64], opts: &FitOptions) -> OscillationFit {
    let n_in = t.len().min(x.len());
    let (t, x) = (&t[..n_in], &x[..n_in]);
    let (td, xd) = decimate(t, x, opts.max_samples);
    let n = td.len();
    let window = match (td.first(), td.last()) {
        (Some(&a), Some(&b)) => (a, b),
        _ => (f64::NAN, f64::NAN),
    };
    if n < opts.min_samples.max(8) || !above(window.1, window.0) {
        return OscillationFit::refused(
            Quality::TooShort,
            format!(
                "{n} usable samples over {:.3} s; a fit needs at least {}",
                (window.1 - window.0).max(0.0),
                opts.min_samples.max(8)
            ),
            window,
            n,
        );
    }
    if td.windows(2).any(|w| w[1] < w[0]) {
        return OscillationFit::refused(
            Quality::TooShort,
            "times do not increase".to_owned(),
            window,
            n,
        );
    }
    let t0 = window.0;
    let w_s = window.1 - window.0;
    // Normalised data.
    let y_mean = xd.iter().sum::<f64>() / n as f64;
    let y_scale = {
        let var = xd.iter().map(|v| (v - y_mean).powi(2)).sum::<f64>() / n as f64;
        if var > 0.0 { var.sqrt() } else { 1.0 }
    };
    let u: Vec<f64> = td.iter().map(|v| (v - t0) / w_s).collect();
    let y: Vec<f64> = xd.iter().map(|v| (v - y_mean) / y_scale).collect();

    let seed = match seed(&u, &y, opts) {
        Ok(s) => s,
        Err((quality, message)) => return OscillationFit::refused(quality, message, window, n),
    };
    // A few starts around the seeded period; keep the lowest residual.
    let mut best: Option<LmSolution> = None;
    for factor in [1.0, 0.93, 1.07, 0.85, 1.18] {
        let mut q0 = seed.params.clone();
        let wi = q0.len() - 1;
        q0[wi] *= factor;
        if let Some(sol) = levenberg_marquardt(&u, &y, q0, opts.drift) {
            let better = best.as_ref().is_none_or(|b| sol.rss < b.rss);
            if better {
                best = Some(sol);
            }
        }
        // The seed alone is usually enough: stop once a start has converged cleanly.
        if best.as_ref().is_some_and(|b| b.converged) && factor == 1.0 {
            break;
        }
    }
    let Some(sol) = best else {
        return OscillationFit::refused(
            Quality::NotOscillatory,
            "the least-squares fit did not converge from the seeded period".to_owned(),
            window,
            n,
        );
    };
    finish(sol, t, x, &u, y_mean, y_scale, t0, w_s, window, n, opts)
}

#[allow(clippy::too_many_arguments)]
fn finish(
    sol: LmSolution,
    t: &[f64],
    x: &[f64],
    u: &[f64],
    y_mean: f64,
    y_scale: f64,
    t0: f64,
    w_s: f64,
    window: (f64, f64),
    n: usize,
    opts: &FitOptions,
) -> OscillationFit {
    let drift = opts.drift;
    let p = sol.q.len();
    let (ic, id, ia, ib, is, iw) = if drift {
        (0, Some(1), 2, 3, 4, 5)
    } else {
        (0, None, 1, 2, 3, 4)
    };
    let q = &sol.q;
    let dof = (u.len() as f64 - p as f64).max(1.0);
    let s2 = sol.rss / dof;
    let cov = |i: usize, j: usize| sol.cov_unscaled[i * p + j] * s2;
    let (a, mut b, s, mut w) = (q[ia], q[ib], q[is], q[iw]);
    let mut sign_w = 1.0;
    if w < 0.0 {
        // cos(−ωu) = cos(ωu), sin(−ωu) = −sin(ωu).
        w = -w;
        b = -b;
        sign_w = -1.0;
    }
    let period_s = 2.0 * PI * w_s / w;
    let cycles = w_s / period_s;
    let var_w = cov(iw, iw);
    let var_s = cov(is, is);
    let cov_sw = cov(is, iw) * sign_w;
    let amp_n = a.hypot(b);
    let model = DampedSinusoid {
        t0_s: t0,
        offset: y_mean + y_scale * q[ic],
        drift_per_s: id.map_or(0.0, |i| y_scale * q[i] / w_s),
        amplitude: y_scale * amp_n,
        decay_rate_per_s: s / w_s,
        period_s,
        phase_rad: -b.atan2(a),
    };
    let residual_rms = {
        let (mut ss, mut m) = (0.0, 0usize);
        for (ti, xi) in t.iter().zip(x) {
            if ti.is_finite() && xi.is_finite() {
                ss += (xi - model.eval(*ti)).powi(2);
                m += 1;
            }
        }
        if m > 0 {
            (ss / m as f64).sqrt()
        } else {
            f64::NAN
        }
    };
    let sigma_t = 2.0 * PI * w_s / (w * w) * var_w.max(0.0).sqrt();
    let lambda = 2.0 * PI * s / w;
    let (gs, gw) = (2.0 * PI / w, -2.0 * PI * s / (w * w));
    let var_lambda = gs * gs * var_s + 2.0 * gs * gw * cov_sw + gw * gw * var_w;
    let sigma_lambda = var_lambda.max(0.0).sqrt();
    let k = 4.0 * PI * PI + lambda * lambda;
    let zeta = lambda / k.sqrt();
    let sigma_zeta = 4.0 * PI * PI / k.powf(1.5) * sigma_lambda;
    let var_a = {
        let (va, vb, cab) = (cov(ia, ia), cov(ib, ib), cov(ia, ib) * sign_w);
        if amp_n > 0.0 {
            (a * a * va + 2.0 * a * b * cab + b * b * vb) / (amp_n * amp_n)
        } else {
            va + vb
        }
    };
    let sigma_amp = y_scale * var_a.max(0.0).sqrt();
    let offset_drift_cov = [
        y_scale * y_scale * cov(ic, ic),
        id.map_or(0.0, |i| y_scale * y_scale * cov(ic, i) / w_s),
        id.map_or(0.0, |i| y_scale * y_scale * cov(i, i) / (w_s * w_s)),
    ];

    let mut fit = OscillationFit::refused(Quality::Ok, String::new(), window, n);
    fit.model = Some(model);
    fit.cycles = cycles;
    fit.residual_rms = residual_rms;
    fit.iterations = sol.iterations;

    let finite = [period_s, lambda, sigma_t, sigma_lambda, model.amplitude]
        .iter()
        .all(|v| v.is_finite());
    if !finite || w <= 0.0 {
        fit.quality = Quality::NotOscillatory;
        fit.message = "the fit gave no finite period".to_owned();
        fit.model = None;
        return fit;
    }
    if cycles < opts.min_cycles {
        fit.quality = Quality::TooFewCycles;
        fit.message = format!(
            "{cycles:.2} cycles of a {period_s:.4e} s period in the window; at least {} needed",
            opts.min_cycles
        );
        return fit;
    }
    // An amplitude within a few sigma of zero, or a period known to worse than 20 %, is noise.
    if model.amplitude < 5.0 * sigma_amp || sigma_t > 0.2 * period_s {
        fit.quality = Quality::NotOscillatory;
        fit.message = format!(
            "no oscillation above the noise (amplitude {:.3e} ± {sigma_amp:.1e}, period {period_s:.4e} ± {sigma_t:.1e} s)",
            model.amplitude
        );
        fit.model = None;
        return fit;
    }
    fit.period_s = Some(Estimate::new(period_s, sigma_t));
    fit.log_decrement = Some(Estimate::new(lambda, sigma_lambda));
    fit.damping_ratio = Some(Estimate::new(zeta, sigma_zeta));
    fit.decay_rate_per_s = Some(Estimate::new(
        model.decay_rate_per_s,
        var_s.max(0.0).sqrt() / w_s,
    ));
    fit.amplitude = Some(Estimate::new(model.amplitude, sigma_amp));
    fit.offset = Some(Estimate::new(
        model.offset,
        offset_drift_cov[0].max(0.0).sqrt(),
    ));
    fit.drift_per_s = Some(Estimate::new(
        model.drift_per_s,
        offset_drift_cov[2].max(0.0).sqrt(),
    ));
    fit.offset_drift_cov = offset_drift_cov;
    fit.message = format!(
        "T = {period_s:.6e} ± {sigma_t:.1e} s, Λ = {lambda:.5} ± {sigma_lambda:.1e} over {cycles:.1} cycles"
    );
    fit
}

/// Seeded parameters in normalised units: [c, (d), a, b, s, w].
struct Seed {
    params: Vec<f64>,
}

/// Robust noise level from second differences (a smooth signal sampled finely contributes
/// little to them): MAD / 0.6745 / √6.
pub(crate) fn noise_sigma(y: &[f64]) -> f64 {
    if y.len() < 3 {
        return 0.0;
    }
    let mut d2: Vec<f64> = y
        .windows(3)
        .map(|w| (w[2] - 2.0 * w[1] + w[0]).abs())
        .collect();
    let mid = d2.len() / 2;
    let (_, m, _) = d2.select_nth_unstable_by(mid, f64::total_cmp);
    *m / 0.6745 / 6f64.sqrt()
}

/// Least-squares line through (u, y): (intercept, slope).
pub(crate) fn line_fit(u: &[f64], y: &[f64]) -> (f64, f64) {
    let n = u.len() as f64;
    if n < 2.0 {
        return (y.first().copied().unwrap_or(0.0), 0.0);
    }
    let mu = u.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let (mut suu, mut suy) = (0.0, 0.0);
    for (a, b) in u.iter().zip(y) {
        suu += (a - mu) * (a - mu);
        suy += (a - mu) * (b - my);
    }
    let slope = if suu > 0.0 { suy / suu } else { 0.0 };
    (my - slope * mu, slope)
}

/// Turning points confirmed by a retrace of more than `h` (index, value).
pub(crate) fn turning_points(y: &[f64], h: f64) -> Vec<usize> {
    let mut pivots = Vec::new();
    let Some(&first) = y.first() else {
        return pivots;
    };
    let (mut hi, mut lo) = (0usize, 0usize);
    let mut dir = 0i8;
    for i in 1..y.len() {
        let v = y[i];
        match dir {
            0 => {
                if v > y[hi] {
                    hi = i;
                }
                if v < y[lo] {
                    lo = i;
                }
                if v - y[lo] > h {
                    if lo > 0 && first - y[lo] > h {
                        pivots.push(lo);
                    }
                    dir = 1;
                    hi = i;
                } else if y[hi] - v > h {
                    if hi > 0 && y[hi] - first > h {
                        pivots.push(hi);
                    }
                    dir = -1;
                    lo = i;
                }
            }
            1 => {
                if v > y[hi] {
                    hi = i;
                } else if y[hi] - v > h {
                    pivots.push(hi);
                    dir = -1;
                    lo = i;
                }
            }
            _ => {
                if v < y[lo] {
                    lo = i;
                } else if v - y[lo] > h {
                    pivots.push(lo);
                    dir = 1;
                    hi = i;
                }
            }
        }
    }
    pivots
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

fn block_means(v: &[f64], w: usize) -> Vec<f64> {
    v.chunks(w)
        .map(|c| c.iter().sum::<f64>() / c.len() as f64)
        .collect()
}

fn seed(u_in: &[f64], y_in: &[f64], opts: &FitOptions) -> Result<Seed, (Quality, String)> {
    let noise_in = noise_sigma(y_in);
    // Turning points on ever smoother block means (noise falls as 1/√w) until two stand out.
    let mut refusal = (
        Quality::NotOscillatory,
        "no signal above the noise and drift".to_owned(),
    );
    for w in [1usize, 3, 9, 27, 81, 243] {
        if w > 1 && y_in.len() / w < 40 {
            break;
        }
        let (u, y) = if w == 1 {
            (u_in.to_vec(), y_in.to_vec())
        } else {
            (block_means(u_in, w), block_means(y_in, w))
        };
        let n = y.len();
        let noise = noise_in / (w as f64).sqrt();
        let (c_line, d_line) = line_fit(&u, &y);
        let (lo, hi) = u
            .iter()
            .zip(&y)
            .map(|(a, b)| b - c_line - d_line * a)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(v), h.max(v))
            });
        let range = hi - lo;
        if !above(range, 8.0 * noise) || range == 0.0 {
            refusal = (
                Quality::NotOscillatory,
                format!(
                    "no signal above the noise and drift (spread {:.1} noise σ)",
                    if noise > 0.0 { range / noise } else { 0.0 }
                ),
            );
            continue;
        }
        let h = (8.0 * noise).max(0.03 * range);
        let pivots = turning_points(&y, h);
        if pivots.len() >= 2 {
            return seed_from_pivots(&u, &y, &pivots, opts);
        }
        // Settled: the last eighth is nearly flat next to the steepest eighth (an exponential
        // approach; a drift is a constant slope everywhere) and quiet about its own line. An
        // overdamped response settles; a partial cycle is still moving at the end.
        let slopes: Vec<f64> = (0..8)
            .map(|k| {
                let (a, b) = (k * n / 8, ((k + 1) * n / 8).min(n));
                if b - a >= 2 {
                    line_fit(&u[a..b], &y[a..b]).1
                } else {
                    0.0
                }
            })
            .collect();
        let steepest = slopes.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let tail = (7 * n) / 8;
        let (ct, dt) = line_fit(&u[tail..], &y[tail..]);
        let tail_spread = u[tail..]
            .iter()
            .zip(&y[tail..])
            .map(|(a, b)| (b - ct - dt * a).abs())
            .fold(0.0, f64::max);
        let settled = slopes[7].abs() < 0.15 * steepest && tail_spread < 0.1 * range + 4.0 * noise;
        // A release damped past ζ ≈ 0.45 leaves one overshoot above the hysteresis and its
        // second extreme under it (under 3 % of the swing). On clean data a reversal well above
        // the noise is still a turning point: look again with the finer hysteresis before
        // calling the response aperiodic. An overdamped response has no second reversal at any
        // hysteresis, so it is still refused.
        let fine = (8.0 * noise).max(1e-3 * range);
        if settled && pivots.len() == 1 && fine < h {
            let pivots = turning_points(&y, fine);
            if pivots.len() >= 2 {
                return seed_from_pivots(&u, &y, &pivots, opts);
            }
        }
        refusal = if settled && range > 20.0 * noise {
            (
                Quality::Aperiodic,
                format!(
                    "the signal settles with {} turning point(s): overdamped, no second extreme",
                    pivots.len()
                ),
            )
        } else if pivots.len() == 1 && !settled {
            (
                Quality::TooFewCycles,
                "one turning point in the window: less than one cycle".to_owned(),
            )
        } else {
            (
                Quality::NotOscillatory,
                format!("{} turning point(s) above the noise", pivots.len()),
            )
        };
    }
    Err(refusal)
}

fn seed_from_pivots(
    u: &[f64],
    y: &[f64],
    pivots: &[usize],
    opts: &FitOptions,
) -> Result<Seed, (Quality, String)> {
    let mut gaps: Vec<f64> = pivots.windows(2).map(|w| u[w[1]] - u[w[0]]).collect();
    let half = median(&mut gaps);
    if !above(half, 0.0) {
        return Err((
            Quality::NotOscillatory,
            "turning points coincide".to_owned(),
        ));
    }
    let w0 = PI / half; // 2π / (2·half)
    // Midpoints of swings: the offset (and drift) about which the signal turns.
    let mids: Vec<(f64, f64)> = pivots
        .windows(2)
        .map(|w| (0.5 * (u[w[0]] + u[w[1]]), 0.5 * (y[w[0]] + y[w[1]])))
        .collect();
    let (c0, d0) = if mids.len() >= 3 && opts.drift {
        let (mu, my): (Vec<f64>, Vec<f64>) = mids.iter().copied().unzip();
        line_fit(&mu, &my)
    } else {
        let mut my: Vec<f64> = mids.iter().map(|m| m.1).collect();
        (median(&mut my), 0.0)
    };
    // Decay from successive swings: ln|swing| against time.
    let swings: Vec<(f64, f64)> = pivots
        .windows(2)
        .map(|w| {
            (
                0.5 * (u[w[0]] + u[w[1]]),
                (y[w[1]] - y[w[0]]).abs().max(1e-300).ln(),
            )
        })
        .collect();
    let s0 = if swings.len() >= 2 {
        let (su, sl): (Vec<f64>, Vec<f64>) = swings.iter().copied().unzip();
        -line_fit(&su, &sl).1
    } else {
        0.0
    };
    let s0 = if s0.is_finite() { s0 } else { 0.0 };
    let p0 = pivots[0];
    let amp_p = y[p0] - (c0 + d0 * u[p0]);
    let amp0 = amp_p * (s0 * u[p0]).exp();
    let (a0, b0) = (amp0 * (w0 * u[p0]).cos(), amp0 * (w0 * u[p0]).sin());
    let params = if opts.drift {
        vec![c0, d0, a0, b0, s0, w0]
    } else {
        vec![c0, a0, b0, s0, w0]
    };
    Ok(Seed { params })
}

struct LmSolution {
    q: Vec<f64>,
    rss: f64,
    /// (JᵀJ)⁻¹, row-major p×p.
    cov_unscaled: Vec<f64>,
    iterations: usize,
    converged: bool,
}

/// Residuals r = y − f and the normal equations JᵀJ, Jᵀr at `q`; returns the RSS.
fn normal_equations(
    u: &[f64],
    y: &[f64],
    q: &[f64],
    drift: bool,
    jtj: &mut [f64],
    jtr: &mut [f64],
) -> f64 {
    let p = q.len();
    jtj.iter_mut().for_each(|v| *v = 0.0);
    jtr.iter_mut().for_each(|v| *v = 0.0);
    let (c, d, a, b, s, w) = if drift {
        (q[0], q[1], q[2], q[3], q[4], q[5])
    } else {
        (q[0], 0.0, q[1], q[2], q[3], q[4])
    };
    let mut rss = 0.0;
    let mut g = [0.0f64; 6];
    for (&ui, &yi) in u.iter().zip(y) {
        let e = (-s * ui).exp();
        let (sn, cs) = (w * ui).sin_cos();
        let osc = a * cs + b * sn;
        let f = c + d * ui + e * osc;
        let r = yi - f;
        rss += r * r;
        let gs = -ui * e * osc;
        let gw = ui * e * (-a * sn + b * cs);
        if drift {
            g = [1.0, ui, e * cs, e * sn, gs, gw];
        } else {
            g[..5].copy_from_slice(&[1.0, e * cs, e * sn, gs, gw]);
        }
        for i in 0..p {
            jtr[i] += g[i] * r;
            for j in 0..=i {
                jtj[i * p + j] += g[i] * g[j];
            }
        }
    }
    for i in 0..p {
        for j in 0..i {
            jtj[j * p + i] = jtj[i * p + j];
        }
    }
    rss
}

fn rss_at(u: &[f64], y: &[f64], q: &[f64], drift: bool) -> f64 {
    let (c, d, a, b, s, w) = if drift {
        (q[0], q[1], q[2], q[3], q[4], q[5])
    } else {
        (q[0], 0.0, q[1], q[2], q[3], q[4])
    };
    u.iter()
        .zip(y)
        .map(|(&ui, &yi)| {
            let (sn, cs) = (w * ui).sin_cos();
            let f = c + d * ui + (-s * ui).exp() * (a * cs + b * sn);
            (yi - f) * (yi - f)
        })
        .sum()
}

/// In-place Cholesky of a symmetric positive definite p×p matrix (lower triangle); false when
/// it is not positive definite.
fn cholesky(m: &mut [f64], p: usize) -> bool {
    for j in 0..p {
        let mut d = m[j * p + j];
        for k in 0..j {
            d -= m[j * p + k] * m[j * p + k];
        }
        if !above(d, 0.0) || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        m[j * p + j] = d;
        for i in j + 1..p {
            let mut v = m[i * p + j];
            for k in 0..j {
                v -= m[i * p + k] * m[j * p + k];
            }
            m[i * p + j] = v / d;
        }
    }
    true
}

fn cholesky_solve(l: &[f64], p: usize, b: &mut [f64]) {
    for i in 0..p {
        let mut v = b[i];
        for k in 0..i {
            v -= l[i * p + k] * b[k];
        }
        b[i] = v / l[i * p + i];
    }
    for i in (0..p).rev() {
        let mut v = b[i];
        for k in i + 1..p {
            v -= l[k * p + i] * b[k];
        }
        b[i] = v / l[i * p + i];
    }
}

/// The inverse of a symmetric positive definite matrix, or None.
pub(crate) fn spd_inverse(m: &[f64], p: usize) -> Option<Vec<f64>> {
    let mut l = m.to_vec();
    if !cholesky(&mut l, p) {
        return None;
    }
    let mut inv = vec![0.0; p * p];
    let mut col = vec![0.0; p];
    for j in 0..p {
        col.iter_mut().for_each(|v| *v = 0.0);
        col[j] = 1.0;
        cholesky_solve(&l, p, &mut col);
        for i in 0..p {
            inv[i * p + j] = col[i];
        }
    }
    Some(inv)
}

/// Levenberg–Marquardt with Marquardt's diagonal scaling; None when it never gets a finite step.
fn levenberg_marquardt(u: &[f64], y: &[f64], mut q: Vec<f64>, drift: bool) -> Option<LmSolution> {
    let p = q.len();
    let mut jtj = vec![0.0; p * p];
    let mut jtr = vec![0.0; p];
    let mut rss = normal_equations(u, y, &q, drift, &mut jtj, &mut jtr);
    if !rss.is_finite() {
        return None;
    }
    let mut lambda = 1e-3;
    let mut converged = false;
    let mut iterations = 0;
    let mut a = vec![0.0; p * p];
    let mut step = vec![0.0; p];
    while iterations < 300 {
        iterations += 1;
        a.copy_from_slice(&jtj);
        for i in 0..p {
            a[i * p + i] += lambda * jtj[i * p + i].max(1e-12);
        }
        step.copy_from_slice(&jtr);
        if !cholesky(&mut a, p) {
            lambda *= 10.0;
            if lambda > 1e12 {
                break;
            }
            continue;
        }
        cholesky_solve(&a, p, &mut step);
        let trial: Vec<f64> = q.iter().zip(&step).map(|(a, b)| a + b).collect();
        let rss_trial = rss_at(u, y, &trial, drift);
        if rss_trial.is_finite() && rss_trial <= rss {
            let improvement = (rss - rss_trial) / rss.max(1e-300);
            let step_norm = step.iter().map(|v| v * v).sum::<f64>().sqrt();
            let q_norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
            q = trial;
            rss = normal_equations(u, y, &q, drift, &mut jtj, &mut jtr);
            lambda = (lambda / 3.0).max(1e-12);
            if improvement < 1e-13 || step_norm < 1e-11 * (1.0 + q_norm) {
                converged = true;
                break;
            }
        } else {
            lambda *= 4.0;
            if lambda > 1e12 {
                // No step lowers the residual: a minimum to working precision.
                converged = true;
                break;
            }
        }
    }
    let cov_unscaled = spd_inverse(&jtj, p)?;
    Some(LmSolution {
        q,
        rss,
        cov_unscaled,
        iterations,
        converged,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turning_points_of_a_cosine() {
        let y: Vec<f64> = (0..400)
            .map(|i| (i as f64 * 0.05).cos() * (-0.001 * i as f64).exp())
            .collect();
        let p = turning_points(&y, 0.1);
        // Extremes of cos(0.05 i) at i = 20π k ≈ 62.8 k (the start at i = 0 is not interior).
        assert_eq!(p.len(), 6, "{p:?}");
        assert!((p[0] as f64 - 62.8).abs() < 2.0);
    }

    #[test]
    fn inverse_of_spd() {
        let m = [4.0, 1.0, 1.0, 3.0];
        let inv = spd_inverse(&m, 2).unwrap_or_default();
        let det = 11.0;
        let want = [3.0 / det, -1.0 / det, -1.0 / det, 4.0 / det];
        for (a, b) in inv.iter().zip(want) {
            assert!((a - b).abs() < 1e-14);
        }
    }
}
