//! Ballistic deviation after each manoeuvre: for every `start`/`end` pair of events on `/events`,
//! the new equilibrium (the steady error fitted over the time after the manoeuvre, up to the next
//! manoeuvre or the end of the recording), the peak deviation from it within one period of the
//! end, the time of that peak, the time to settle within a band, and what theory expects.
//!
//! Expectations (Beghin §35, elementary): a short change of the ship's northerly speed swings the
//! card at once by δζ = (T_S²/T²)·Δζ_eq, where Δζ_eq is the shift of the speed error
//! (tan ζ = v_N/(V cos L + v_E), V = εR) and T, T_S the compass's undamped period and Schuler's
//! period (metadata `design_constants`). A Schuler-tuned compass (T = T_S) lands on its new
//! equilibrium: zero deviation from it. The deviation from the new equilibrium just after the
//! manoeuvre, and so the first peak of an undamped compass, is (T_S²/T² − 1)·Δζ_eq. All three are
//! reported beside the measurement.

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::fit::{Estimate, FitOptions, Quality, fit_damped_sinusoid};
use crate::load::{EVENTS_TOPIC, Run};
use crate::steady::{SteadyOptions, steady_error};
use gyro_mcap::contract::events as event_fields;

// Physical constants and the elementary speed error live in one place, gyro-model.
pub use gyro_model::constants::{EARTH_RADIUS_M, EARTH_RATE_RAD_PER_S, schuler_period_s};
pub use gyro_model::theory::speed_error_rad;

/// One record of `/events`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ManoeuvreEvent {
    pub time_s: f64,
    /// `start` or `end`.
    pub phase: String,
    /// `speed_change`, `turn`, `zigzag`, `steady`.
    pub manoeuvre: String,
    pub segment: u64,
    pub description: String,
    pub speed_before_m_per_s: f64,
    pub speed_after_m_per_s: f64,
    pub heading_before_rad: f64,
    pub heading_after_rad: f64,
    pub duration_s: f64,
}

/// The events of a run (empty when the recording has no `/events` channel). Fields other than
/// `time_s` and `phase` may be absent (NaN, empty, 0).
pub fn events_of(run: &Run) -> Result<Vec<ManoeuvreEvent>> {
    let Ok(frame) = run.frame(EVENTS_TOPIC) else {
        return Ok(Vec::new());
    };
    let n = frame.height();
    let time = run.f64_field(EVENTS_TOPIC, event_fields::TIME_S)?.to_vec();
    let phase = run.str_field(EVENTS_TOPIC, event_fields::PHASE)?;
    let strings = |name: &str| {
        run.str_field(EVENTS_TOPIC, name)
            .unwrap_or_else(|_| vec![String::new(); n])
    };
    let floats = |name: &str| {
        run.f64_field(EVENTS_TOPIC, name)
            .map(|s| s.to_vec())
            .unwrap_or_else(|_| vec![f64::NAN; n])
    };
    let manoeuvre = strings(event_fields::MANOEUVRE);
    let description = strings(event_fields::DESCRIPTION);
    let segment: Vec<u64> = frame
        .column(event_fields::SEGMENT)
        .ok()
        .and_then(|c| c.u64().ok())
        .map(|c| c.iter().map(|v| v.unwrap_or(0)).collect())
        .unwrap_or_else(|| vec![0; n]);
    let (sb, sa, hb, ha, du) = (
        floats(event_fields::SPEED_BEFORE_M_PER_S),
        floats(event_fields::SPEED_AFTER_M_PER_S),
        floats(event_fields::HEADING_BEFORE_RAD),
        floats(event_fields::HEADING_AFTER_RAD),
        floats(event_fields::DURATION_S),
    );
    Ok((0..n)
        .map(|i| ManoeuvreEvent {
            time_s: time[i],
            phase: phase[i].clone(),
            manoeuvre: manoeuvre[i].clone(),
            segment: segment[i],
            description: description[i].clone(),
            speed_before_m_per_s: sb[i],
            speed_after_m_per_s: sa[i],
            heading_before_rad: hb[i],
            heading_after_rad: ha[i],
            duration_s: du[i],
        })
        .collect())
}

/// Settings of [`ballistic_deviations`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallisticOptions {
    /// Absolute settling band (default 0.1° in rad).
    pub band_rad: f64,
    /// Relative settling band, a fraction of the peak (default 0.1); the wider of the two is used.
    pub band_fraction: f64,
    /// The back-swing is measured from this long after the manoeuvre's end (default 120 s: the
    /// text's t₂, "une ou deux minutes" after the perturbation, once a liquid ballistic has
    /// followed it) …
    pub backswing_delay_s: f64,
    /// … over this window (default 360 s, short against any compass period: the initial rate).
    pub backswing_window_s: f64,
    pub fit: FitOptions,
}

impl Default for BallisticOptions {
    fn default() -> Self {
        Self {
            band_rad: 0.1_f64.to_radians(),
            band_fraction: 0.1,
            backswing_delay_s: 120.0,
            backswing_window_s: 360.0,
            fit: FitOptions::default(),
        }
    }
}

/// What the design's constants say to expect.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BallisticConstants {
    /// The compass's undamped period T (metadata `undamped_period_s`, else a fitted period).
    pub undamped_period_s: Option<f64>,
    /// Schuler's period T_S (metadata `schuler_period_s`, else [`schuler_period_s`]).
    pub schuler_period_s: f64,
    /// Latitude where the recording does not give the ship's (metadata `latitude_deg`).
    pub latitude_rad: Option<f64>,
}

/// The ballistic deviation after one manoeuvre.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BallisticDeviation {
    pub segment: u64,
    pub manoeuvre: String,
    pub description: String,
    pub start_s: f64,
    pub end_s: f64,
    pub quality: Quality,
    pub message: String,
    /// The steady error before the manoeuvre (at its start).
    pub equilibrium_before_rad: Option<f64>,
    /// The new equilibrium (steady error after the manoeuvre).
    pub equilibrium_after: Option<Estimate>,
    /// Signed error − new equilibrium at the largest deviation within one period after the end.
    pub peak_deviation_rad: Option<f64>,
    /// When that peak occurs (simulation time).
    pub peak_time_s: Option<f64>,
    /// Seconds after the end event from which |error − equilibrium| stays within the band;
    /// `None` when it does not settle before the next manoeuvre or the end of the recording.
    pub settle_time_s: Option<f64>,
    pub settle_band_rad: f64,
    /// The elementary speed-error shift Δζ_eq of the manoeuvre.
    pub speed_error_shift_rad: Option<f64>,
    /// Deviation from the new equilibrium expected of a Schuler-tuned compass: 0.
    pub expected_schuler_deviation_rad: f64,
    /// The swing the design makes at once: (T_S²/T²)·Δζ_eq.
    pub expected_ballistic_deflection_rad: Option<f64>,
    /// Deviation from the new equilibrium just after the manoeuvre: (T_S²/T² − 1)·Δζ_eq.
    pub expected_peak_deviation_rad: Option<f64>,
    /// How far the card has swung from its old equilibrium when the back-swing window opens
    /// (error at end + `backswing_delay_s` minus the equilibrium before), rad.
    pub swing_rad: Option<f64>,
    /// The card's rate over the back-swing window (least-squares slope), rad/s: Beghin §70's ζ′
    /// after a speed change, of the opposite sign to `swing_rad` when the damper drives the card
    /// back at once (the Slough's mercury, the three-gyro's oil).
    pub backswing_rate_rad_per_s: Option<f64>,
}

/// Latitude at `t` from the ship channel's samples, when given.
fn latitude_at(ship: Option<(&[f64], &[f64])>, t: f64) -> Option<f64> {
    let (ts, lat) = ship?;
    if ts.is_empty() {
        return None;
    }
    let i = ts.partition_point(|v| *v < t).min(ts.len() - 1);
    lat.get(i).copied().filter(|v| v.is_finite())
}

/// Least-squares slope of (t, x) over [a, b], finite samples only; `None` with fewer than 3.
pub fn slope(t: &[f64], x: &[f64], a: f64, b: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = t
        .iter()
        .zip(x)
        .filter(|(ti, xi)| **ti >= a && **ti <= b && xi.is_finite())
        .map(|(ti, xi)| (*ti, *xi))
        .collect();
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let (mt, mx) = pts
        .iter()
        .fold((0.0, 0.0), |(st, sx), (ti, xi)| (st + ti / n, sx + xi / n));
    let (sxy, sxx) = pts.iter().fold((0.0, 0.0), |(sxy, sxx), (ti, xi)| {
        (sxy + (ti - mt) * (xi - mx), sxx + (ti - mt) * (ti - mt))
    });
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The ballistic deviation after every manoeuvre of (t, error): `events` as read by
/// [`events_of`]; `ship` the ship channel's (time, latitude) when recorded; `period_hint_s` a period
/// used where a window is too short to fit one (e.g. the run's fitted or undamped period).
pub fn ballistic_deviations(
    t: &[f64],
    error: &[f64],
    events: &[ManoeuvreEvent],
    ship: Option<(&[f64], &[f64])>,
    constants: &BallisticConstants,
    period_hint_s: Option<f64>,
    opts: &BallisticOptions,
) -> Vec<BallisticDeviation> {
    let n = t.len().min(error.len());
    let (t, error) = (&t[..n], &error[..n]);
    let t_last = t.last().copied().unwrap_or(f64::NAN);
    let mut events: Vec<&ManoeuvreEvent> = events
        .iter()
        .filter(|e| e.manoeuvre != "steady" && e.time_s.is_finite())
        .collect();
    events.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    let mut out = Vec::new();
    let mut previous_end = t.first().copied().unwrap_or(0.0);
    for (i, start) in events.iter().enumerate() {
        if start.phase != event_fields::START {
            continue;
        }
        let Some(end) = events[i + 1..]
            .iter()
            .find(|e| e.phase == event_fields::END && e.segment == start.segment)
        else {
            continue; // The recording ends inside the manoeuvre.
        };
        let next_start = events
            .iter()
            .find(|e| e.phase == event_fields::START && e.time_s > end.time_s)
            .map_or(t_last, |e| e.time_s);
        out.push(one_deviation(
            t,
            error,
            start,
            end,
            previous_end,
            next_start,
            ship,
            constants,
            period_hint_s,
            opts,
        ));
        previous_end = end.time_s;
    }
    out
}

#[allow(clippy::too_many_arguments)]
fn one_deviation(
    t: &[f64],
    error: &[f64],
    start: &ManoeuvreEvent,
    end: &ManoeuvreEvent,
    previous_end: f64,
    next_start: f64,
    ship: Option<(&[f64], &[f64])>,
    constants: &BallisticConstants,
    period_hint_s: Option<f64>,
    opts: &BallisticOptions,
) -> BallisticDeviation {
    let latitude = latitude_at(ship, end.time_s).or(constants.latitude_rad);
    let shift = latitude.and_then(|lat| {
        let v = speed_error_rad(end.speed_after_m_per_s, end.heading_after_rad, lat)
            - speed_error_rad(start.speed_before_m_per_s, start.heading_before_rad, lat);
        v.is_finite().then_some(v)
    });
    let ratio = constants
        .undamped_period_s
        .or(period_hint_s)
        .filter(|p| *p > 0.0)
        .map(|p| (constants.schuler_period_s / p).powi(2));
    let mut d = BallisticDeviation {
        segment: start.segment,
        manoeuvre: start.manoeuvre.clone(),
        description: start.description.clone(),
        start_s: start.time_s,
        end_s: end.time_s,
        quality: Quality::Ok,
        message: String::new(),
        equilibrium_before_rad: None,
        equilibrium_after: None,
        peak_deviation_rad: None,
        peak_time_s: None,
        settle_time_s: None,
        settle_band_rad: opts.band_rad,
        speed_error_shift_rad: shift,
        expected_schuler_deviation_rad: 0.0,
        expected_ballistic_deflection_rad: shift.zip(ratio).map(|(s, r)| r * s),
        expected_peak_deviation_rad: shift.zip(ratio).map(|(s, r)| (r - 1.0) * s),
        swing_rad: None,
        backswing_rate_rad_per_s: None,
    };
    let range = |a: f64, b: f64| {
        (
            t.partition_point(|v| *v < a),
            t.partition_point(|v| *v <= b),
        )
    };
    let steady = |a: f64, b: f64| {
        let (i0, i1) = range(a, b);
        let (tw, xw) = (&t[i0..i1], &error[i0..i1]);
        let fit = fit_damped_sinusoid(tw, xw, &opts.fit);
        let period = fit.period_s.map(|p| p.value).or(period_hint_s);
        let s = steady_error(tw, xw, Some(&fit), period, &SteadyOptions::default());
        (s, period)
    };
    let (before, _) = steady(previous_end, start.time_s);
    d.equilibrium_before_rad = before.value.map(|v| v.value);
    let w0 = end.time_s + opts.backswing_delay_s;
    let w1 = (w0 + opts.backswing_window_s).min(next_start);
    if let Some(rate) = slope(t, error, w0, w1) {
        let (i0, _) = range(w0, w1);
        d.backswing_rate_rad_per_s = Some(rate);
        d.swing_rad = d.equilibrium_before_rad.map(|b| error[i0] - b);
    }
    let (after, period) = steady(end.time_s, next_start);
    let Some(eq) = after.value else {
        d.quality = after.quality;
        d.message = format!(
            "no new equilibrium after the manoeuvre ending at {:.1} s: {}",
            end.time_s, after.message
        );
        return d;
    };
    d.equilibrium_after = Some(eq);
    let period = period
        .or(constants.undamped_period_s)
        .unwrap_or(next_start - end.time_s);
    // Peak within one period of the end.
    let (i0, i1) = range(end.time_s, (end.time_s + period).min(next_start));
    let drift = after.drift_per_s.map_or(0.0, |d| d.value);
    let deviation = |i: usize| error[i] - (eq.value + drift * (t[i] - after.at_time_s));
    let peak = (i0..i1)
        .filter(|&i| error[i].is_finite())
        .max_by(|&a, &b| deviation(a).abs().total_cmp(&deviation(b).abs()));
    let Some(ip) = peak else {
        d.quality = Quality::TooShort;
        d.message = format!(
            "no sample after the manoeuvre ending at {:.1} s",
            end.time_s
        );
        return d;
    };
    let peak_value = deviation(ip);
    d.peak_deviation_rad = Some(peak_value);
    d.peak_time_s = Some(t[ip]);
    let band = opts.band_rad.max(opts.band_fraction * peak_value.abs());
    d.settle_band_rad = band;
    let (j0, j1) = range(end.time_s, next_start);
    let last_out = (j0..j1)
        .rev()
        .find(|&i| error[i].is_finite() && deviation(i).abs() > band);
    d.settle_time_s = match last_out {
        None => Some(0.0),
        Some(i) if i + 1 < j1 => Some(t[i + 1] - end.time_s),
        Some(_) => None,
    };
    d.message = match d.settle_time_s {
        Some(s) => format!("settles within {band:.3e} rad {s:.0} s after the end"),
        None => format!("does not settle within {band:.3e} rad before {next_start:.0} s"),
    };
    d
}
