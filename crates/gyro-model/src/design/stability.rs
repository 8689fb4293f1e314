//! The `[[stability]]` entries: conditions a design must meet to be stable, each a margin
//! evaluated from the parameters (after the scene's latitude dial and overrides). A design with
//! a margin ≤ 0 is refused, naming the boundary it crosses, unless it says `allow_unstable = true`
//! (a scene sets that with `[compass] allow_unstable = true`, to run an unstable design on purpose).

use super::SourceText;
use crate::error::InputError;
use serde::Deserialize;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct StabilityFile {
    name: String,
    /// The boundary in words, as the reference text states it.
    boundary: String,
    /// Positive inside the stable region, dimensionless (the design divides by a scale of its
    /// own): an `"= expression"` of the parameters, already a number here.
    relative_margin: f64,
}

/// A stability condition of a design, evaluated.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityCondition {
    pub name: String,
    pub boundary: String,
    /// Positive inside the stable region (dimensionless).
    pub relative_margin: f64,
}

/// The conditions in order; an error at the first one violated unless `allow_unstable`.
pub(super) fn stability(
    entries: &[StabilityFile],
    allow_unstable: bool,
    src: &SourceText,
) -> Result<Vec<StabilityCondition>, InputError> {
    let mut out = Vec::with_capacity(entries.len());
    for e in entries {
        let anchor = format!("name = \"{}\"", e.name);
        if !e.relative_margin.is_finite() {
            return Err(src.err(
                Some(&anchor),
                "relative_margin",
                format!("stability.{}.relative_margin", e.name),
                format!(
                    "{} is not finite (allowed: a finite number, > 0 when stable)",
                    e.relative_margin
                ),
            ));
        }
        if e.relative_margin <= 0.0 && !allow_unstable {
            return Err(src.err(
                Some(&anchor),
                "relative_margin",
                format!("stability.{}", e.name),
                format!(
                    "the design is outside its stable region: it violates {} ({}), relative margin {:.4} (allowed: > 0). \
                     To run it unstable on purpose, set `allow_unstable = true` in the scene's [compass] table",
                    e.name, e.boundary, e.relative_margin
                ),
            ));
        }
        out.push(StabilityCondition {
            name: e.name.clone(),
            boundary: e.boundary.clone(),
            relative_margin: e.relative_margin,
        });
    }
    Ok(out)
}
