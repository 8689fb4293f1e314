//! Where the fitted settling curve comes from. The viewer only draws it; fitting belongs to
//! `gyro-analysis`. [`SettlingFit`] is the seam: [`default_fit`] returns the analysis crate's fit
//! once its API exists, and tests pass their own.

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

/// The fit [`crate::view`] draws: `gyro-analysis`'s damped-sinusoid fit once that crate exposes
/// one; until then none.
pub fn default_fit() -> &'static dyn SettlingFit {
    &NoFit
}
