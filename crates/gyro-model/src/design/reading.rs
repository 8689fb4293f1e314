//! The `[reading]` table: the body and axis that define the indicated North.

use super::SourceText;
use crate::error::InputError;
use serde::Deserialize;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ReadingFile {
    /// The body whose axis defines the indicated North (usually the gyro case or float).
    body: String,
    /// That axis in the body's frame.
    axis: [f64; 3],
}

/// The reading body's index and the unit reading axis.
pub(super) fn reading(
    r: &ReadingFile,
    body_names: &[String],
    src: &SourceText,
) -> Result<(usize, [f64; 3]), InputError> {
    let reading_body = body_names
        .iter()
        .position(|n| *n == r.body)
        .ok_or_else(|| {
            src.err(
                Some("[reading]"),
                "body",
                "reading.body".into(),
                format!(
                    "unknown body `{}` (allowed: {})",
                    r.body,
                    body_names.join(", ")
                ),
            )
        })?;
    let ra = r.axis;
    let rn = (ra[0] * ra[0] + ra[1] * ra[1] + ra[2] * ra[2]).sqrt();
    if !(rn > 0.0 && rn.is_finite()) {
        return Err(src.err(
            Some("[reading]"),
            "axis",
            "reading.axis".into(),
            "must be a non-zero finite vector".into(),
        ));
    }
    Ok((reading_body, ra.map(|x| x / rn)))
}
