//! Where the fitted settling curve comes from. The viewer only draws it; fitting belongs to
//! `gyro-analysis`. [`SettlingFit`] is the seam: [`default_fit`] is [`AnalysisFit`] (the analysis
//! crate's `fit_damped_sinusoid`), and tests pass their own.

/// `offset + drift·(t − t0) + amplitude · exp(−decay·(t − t0)) · cos(2π(t − t0)/period + phase)`
/// over `[start_s, end_s]`,
/// in the units of the series it was fitted to (radians for the reading error).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DampedSinusoid {
    pub offset: f64,
    pub drift_per_s: f64,
    pub amplitude: f64,
    pub decay_rate_per_s: f64,
    pub period_s: f64,
    pub phase_rad: f64,
    /// Time origin of the exponential and the phase.
    pub t0_s: f64,
    /// The window the fit covers (drawn only there).
    pub start_s: f64,
    pub end_s: f64,
}

impl DampedSinusoid {
    fn decay(&self, t_s: f64) -> f64 {
        self.amplitude * (-self.decay_rate_per_s * (t_s - self.t0_s)).exp()
    }

    fn settled(&self, t_s: f64) -> f64 {
        self.offset + self.drift_per_s * (t_s - self.t0_s)
    }

    pub fn value(&self, t_s: f64) -> f64 {
        let arg = std::f64::consts::TAU * (t_s - self.t0_s) / self.period_s + self.phase_rad;
        self.settled(t_s) + self.decay(t_s) * arg.cos()
    }

    /// Lower and upper envelope, `offset + drift·(t − t0) ∓ |amplitude|·exp(−decay·(t − t0))`.
    pub fn envelope(&self, t_s: f64) -> (f64, f64) {
        let a = self.decay(t_s).abs();
        (self.settled(t_s) - a, self.settled(t_s) + a)
    }

    /// Finite parameters with a positive period and an ordered window.
    pub fn is_drawable(&self) -> bool {
        [
            self.offset,
            self.drift_per_s,
            self.amplitude,
            self.decay_rate_per_s,
            self.period_s,
            self.phase_rad,
            self.t0_s,
            self.start_s,
            self.end_s,
        ]
        .iter()
        .all(|v| v.is_finite())
            && self.period_s > 0.0
            && self.start_s <= self.end_s
    }
}

/// Fits the settling oscillation of a series (time in seconds, values in SI). The viewer passes
/// the reading error after the last manoeuvre event ends (the whole series when there is none).
pub trait SettlingFit {
    fn fit(&self, time_s: &[f64], value: &[f64]) -> Option<DampedSinusoid>;
}

/// Draws no fit.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoFit;

impl SettlingFit for NoFit {
    fn fit(&self, _time_s: &[f64], _value: &[f64]) -> Option<DampedSinusoid> {
        None
    }
}

/// Any closure `(time_s, value) -> Option<DampedSinusoid>` is a fit.
impl<F> SettlingFit for F
where
    F: Fn(&[f64], &[f64]) -> Option<DampedSinusoid>,
{
    fn fit(&self, time_s: &[f64], value: &[f64]) -> Option<DampedSinusoid> {
        self(time_s, value)
    }
}

/// `gyro_analysis::fit_damped_sinusoid` with its default options; drawn only when the fit stands
/// (quality `ok`), over the window it fitted.
#[derive(Clone, Copy, Debug, Default)]
pub struct AnalysisFit;

impl SettlingFit for AnalysisFit {
    fn fit(&self, time_s: &[f64], value: &[f64]) -> Option<DampedSinusoid> {
        let f = gyro_analysis::fit_damped_sinusoid(
            time_s,
            value,
            &gyro_analysis::FitOptions::default(),
        );
        if !f.quality.is_ok() {
            return None;
        }
        let m = f.model?;
        Some(DampedSinusoid {
            offset: m.offset,
            drift_per_s: m.drift_per_s,
            amplitude: m.amplitude,
            decay_rate_per_s: m.decay_rate_per_s,
            period_s: m.period_s,
            phase_rad: m.phase_rad,
            t0_s: m.t0_s,
            start_s: f.window_s.0,
            end_s: f.window_s.1,
        })
    }
}

/// The fit [`crate::view`] draws: [`AnalysisFit`].
pub fn default_fit() -> &'static dyn SettlingFit {
    &AnalysisFit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analysis_fit_recovers_a_damped_sinusoid() {
        let truth = DampedSinusoid {
            offset: 0.001,
            drift_per_s: 0.0,
            amplitude: 0.02,
            decay_rate_per_s: 1.0 / 4000.0,
            period_s: 600.0,
            phase_rad: 0.3,
            t0_s: 0.0,
            start_s: 0.0,
            end_s: 6000.0,
        };
        let t: Vec<f64> = (0..6000).map(f64::from).collect();
        let y: Vec<f64> = t.iter().map(|&t| truth.value(t)).collect();
        let f = AnalysisFit.fit(&t, &y).expect("the fit stands");
        assert!((f.period_s - 600.0).abs() < 0.1, "{f:?}");
        assert!(
            (f.decay_rate_per_s - truth.decay_rate_per_s).abs() < 1e-6,
            "{f:?}"
        );
        for &s in &[100.0, 2500.0, 5900.0] {
            assert!((f.value(s) - truth.value(s)).abs() < 1e-5, "{s}: {f:?}");
        }
        assert!(AnalysisFit.fit(&t[..5], &y[..5]).is_none());
    }
}
