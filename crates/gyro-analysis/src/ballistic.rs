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
use gyro_model::linalg::solve_in_place;

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
    /// The back-swing is read this long after the manoeuvre's end (default 60 s): Beghin §70's
    /// ζ′ "à la fin de la perturbation", which for the Slough lasts "une ou deux minutes" more,
    /// until its mercury has followed (t₂). In the Hermione trial the mercury's sloshing swings
    /// the Slough's card at up to 4e-5 rad/s in the first 30 s, against 1.3e-5 once it has
    /// followed; the three-gyro's oil has no such transient.
    pub backswing_delay_s: f64,
    /// … as the rate at its start of a least-squares parabola over this window (default 180 s;
    /// on a rate decaying as e^(−t/600 s) it reads 0.7 % low).
    /// The rate changes within minutes (the card starts off its new equilibrium): the Slough's
    /// falls from 1.3e-5 rad/s at 1 min to 0.36e-5 at 10 min, so a slope over minutes would read
    /// the rate of the window's middle, well under the text's ζ′.
    pub backswing_window_s: f64,
    pub fit: FitOptions,
}

impl Default for BallisticOptions {
    fn default() -> Self {
        Self {
            band_rad: 0.1_f64.to_radians(),
            band_fraction: 0.1,
            backswing_delay_s: 60.0,
            backswing_window_s: 180.0,
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
    /// (the error there minus the equilibrium before), rad.
    pub swing_rad: Option<f64>,
    /// The card's rate `backswing_delay_s` after the manoeuvre's end (a least-squares parabola's
    /// over `backswing_window_s`), rad/s: Beghin §70's ζ′ after a speed change, of the opposite
    /// sign to `swing_rad` when the damper drives the card back (the Slough's mercury, the
    /// three-gyro's oil).
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

/// The rate at `a` of the least-squares parabola through (t, x) over [a, b] (finite samples
/// only; `None` with fewer than 4 or a singular fit): a rate at the window's start, where a
/// slope would give the rate at its middle.
pub fn rate_at_start(t: &[f64], x: &[f64], a: f64, b: f64) -> Option<f64> {
    let w = b - a;
    if w.is_nan() || w <= 0.0 {
        return None;
    }
    // Normal equations of x = c₀ + c₁u + c₂u², u = (t − a)/w ∈ [0, 1] (well conditioned).
    let (i0, i1) = (
        t.partition_point(|v| *v < a),
        t.partition_point(|v| *v <= b),
    );
    let (mut m, mut c) = ([0.0; 9], [0.0; 3]);
    let mut count = 0;
    for (ti, xi) in t[i0..i1].iter().zip(&x[i0..i1]) {
        if !xi.is_finite() {
            continue;
        }
        let u = (ti - a) / w;
        let p = [1.0, u, u * u];
        for (i, pi) in p.iter().enumerate() {
            for (j, pj) in p.iter().enumerate() {
                m[3 * i + j] += pi * pj;
            }
            c[i] += pi * xi;
        }
        count += 1;
    }
    (count >= 4 && solve_in_place(&mut m, &mut c, 3)).then(|| c[1] / w)
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
    if let Some(rate) = rate_at_start(t, error, w0, w1) {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn events(start: f64, end: f64) -> Vec<ManoeuvreEvent> {
        [(start, event_fields::START), (end, event_fields::END)]
            .into_iter()
            .map(|(time_s, phase)| ManoeuvreEvent {
                time_s,
                phase: phase.to_owned(),
                manoeuvre: "speed_change".to_owned(),
                segment: 1,
                description: String::new(),
                speed_before_m_per_s: 5.0,
                speed_after_m_per_s: 0.0,
                heading_before_rad: 0.0,
                heading_after_rad: 0.0,
                duration_s: end - start,
            })
            .collect()
    }

    /// A card at rest swings by −s during a 60-s manoeuvre ending at 3660 s; then a liquid
    /// sloshes (a 30-s oscillation of the card dying in seconds, its rate up to 3r₀) while the
    /// damper drives the card back at r₀ e^(−t/τ). The back-swing read is the rate 60 s after
    /// the end, r₀ e^(−60/τ), within 1 %; a slope over 2–8 min would read 0.6 r₀.
    #[test]
    fn the_backswing_is_the_rate_once_the_liquid_has_followed() {
        let (end, s, r0, tau) = (3660.0, 0.012, 1.25e-5, 600.0);
        let slosh = 3.0 * r0 * 30.0 / std::f64::consts::TAU;
        let card = |ti: f64| {
            if ti <= 3600.0 {
                0.0
            } else if ti <= end {
                -s * (ti - 3600.0) / 60.0
            } else {
                let u = ti - end;
                -s + r0 * tau * (1.0 - (-u / tau).exp())
                    + slosh * (-u / 5.0).exp() * (std::f64::consts::TAU * u / 30.0).sin()
            }
        };
        let t: Vec<f64> = (0..=4 * 14_400).map(|i| f64::from(i) * 0.25).collect();
        let x: Vec<f64> = t.iter().map(|&ti| card(ti)).collect();
        let d = ballistic_deviations(
            &t,
            &x,
            &events(3600.0, end),
            None,
            &BallisticConstants::default(),
            Some(6000.0),
            &BallisticOptions::default(),
        );
        let rate = d[0].backswing_rate_rad_per_s.expect("a back-swing");
        let expect = r0 * (-60.0 / tau).exp();
        assert!((rate / expect - 1.0).abs() < 0.01, "{rate} vs {expect}");
        // The swing is read where the back-swing is, from the steady value of the first hour.
        let sw = d[0].swing_rad.expect("a swing");
        let at_t2 = -s + r0 * tau * (1.0 - (-60.0 / tau).exp());
        assert!((sw - at_t2).abs() < 1e-6, "swing {sw} vs {at_t2}");
        let old = slope(&t, &x, end + 120.0, end + 480.0).expect("slope");
        assert!(old < 0.7 * r0, "2–8 min slope {old}");
        // Within the slosh the instantaneous rate is far off: what the delay is for.
        let early = rate_at_start(&t, &x, end + 5.0, end + 20.0).expect("rate");
        assert!((early / r0 - 1.0).abs() > 0.5, "slosh rate {early}");
    }
}
