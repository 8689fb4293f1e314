//! The `[[linkage]]` entries: the rods that tie two bodies' hinges, for the viewer to draw. A
//! linkage's kinematics are already in the hinges (a shared coordinate or a passive relation:
//! the three-gyro's G′ and G″ turn at +β and −β), so the entry says only where its rod runs,
//! from a point of one body to a point of the other, and costs the equations nothing.

use super::SourceText;
use crate::error::InputError;
use serde::Deserialize;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LinkageFile {
    name: String,
    #[serde(default)]
    description: String,
    bodies: [String; 2],
    points_m: [[f64; 3]; 2],
}

/// A rod drawn between two bodies: from `points_m[0]` in `bodies[0]`'s frame to `points_m[1]`
/// in `bodies[1]`'s.
#[derive(Clone, Debug, PartialEq)]
pub struct Linkage {
    pub name: String,
    pub description: String,
    pub bodies: [usize; 2],
    pub points_m: [[f64; 3]; 2],
}

/// The linkages in order, names unique, bodies known and distinct, points finite.
pub(super) fn linkages(
    files: &[LinkageFile],
    body_names: &[String],
    src: &SourceText,
) -> Result<Vec<Linkage>, InputError> {
    let mut out: Vec<Linkage> = Vec::new();
    for f in files {
        let bad = |key: &str, m: String| {
            src.err(
                Some(&format!("name = \"{}\"", f.name)),
                key,
                format!("linkage.{}.{key}", f.name),
                m,
            )
        };
        if out.iter().any(|l| l.name == f.name) {
            return Err(bad("name", "duplicate linkage name".into()));
        }
        let index = |b: &String| {
            body_names.iter().position(|n| n == b).ok_or_else(|| {
                bad(
                    "bodies",
                    format!("unknown body `{b}` (allowed: {})", body_names.join(", ")),
                )
            })
        };
        let bodies = [index(&f.bodies[0])?, index(&f.bodies[1])?];
        if bodies[0] == bodies[1] {
            return Err(bad(
                "bodies",
                format!(
                    "both ends on `{}` (allowed: two different bodies)",
                    f.bodies[0]
                ),
            ));
        }
        if !f.points_m.iter().flatten().all(|x| x.is_finite()) {
            return Err(bad("points_m", "attachment points must be finite".into()));
        }
        out.push(Linkage {
            name: f.name.clone(),
            description: f.description.clone(),
            bodies,
            points_m: f.points_m,
        });
    }
    Ok(out)
}
