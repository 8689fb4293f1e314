//! The `[start]` table: where the ship is when the run starts.

use super::SourceText;
use gyro_model::error::InputError;
use serde::Deserialize;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct StartFile {
    pub(super) latitude_deg: f64,
    #[serde(default)]
    pub(super) longitude_deg: f64,
    #[serde(default)]
    pub(super) heading_deg: f64,
    #[serde(default)]
    pub(super) speed_kn: f64,
}

/// Checks the start: latitude off the poles, the rest finite and the speed not negative.
pub(super) fn check(s: &StartFile, src: &SourceText) -> Result<(), InputError> {
    if !(s.latitude_deg.is_finite() && s.latitude_deg.abs() < 90.0) {
        return Err(src.err(
            Some("[start]"),
            "latitude_deg",
            "start.latitude_deg",
            format!(
                "{} is out of range (allowed: −90 < latitude < 90; at the poles North is undefined and so is a gyrocompass)",
                s.latitude_deg
            ),
        ));
    }
    if !(s.longitude_deg.is_finite()
        && s.heading_deg.is_finite()
        && s.speed_kn.is_finite()
        && s.speed_kn >= 0.0)
    {
        return Err(src.err(
            Some("[start]"),
            "speed_kn",
            "start",
            "longitude, heading must be finite and speed ≥ 0".into(),
        ));
    }
    Ok(())
}
