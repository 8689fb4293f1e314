//! The `[sea]` table: the ship's roll and pitch.

use super::SourceText;
use crate::program::SeaState;
use gyro_model::error::InputError;
use serde::Deserialize;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SeaFile {
    #[serde(default)]
    roll_amplitude_deg: f64,
    #[serde(default = "ten")]
    roll_period_s: f64,
    #[serde(default)]
    pitch_amplitude_deg: f64,
    #[serde(default = "ten")]
    pitch_period_s: f64,
}

fn ten() -> f64 {
    10.0
}

/// The sea state (calm when the table is absent).
pub(super) fn sea_state(sea: Option<&SeaFile>, src: &SourceText) -> Result<SeaState, InputError> {
    let Some(sf) = sea else {
        return Ok(SeaState::default());
    };
    if !(sf.roll_amplitude_deg.abs() < 60.0
        && sf.pitch_amplitude_deg.abs() < 30.0
        && sf.roll_period_s > 0.5
        && sf.pitch_period_s > 0.5)
    {
        return Err(src.err(
            Some("[sea]"),
            "roll_amplitude_deg",
            "sea",
            "out of range (allowed: |roll| < 60°, |pitch| < 30°, periods > 0.5 s)".into(),
        ));
    }
    Ok(SeaState {
        roll_amplitude_rad: sf.roll_amplitude_deg.to_radians(),
        roll_period_s: sf.roll_period_s,
        roll_phase_rad: 0.0,
        pitch_amplitude_rad: sf.pitch_amplitude_deg.to_radians(),
        pitch_period_s: sf.pitch_period_s,
        pitch_phase_rad: 0.0,
    })
}
