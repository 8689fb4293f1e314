//! The `[[program]]` entries: the ship's manoeuvres, turned into segments with chained start
//! states (each segment starts where the one before it ended).

use super::{SourceText, StartFile};
use crate::program::{Segment, SegmentKind, ShipProgram};
use gyro_model::constants::KNOT_IN_M_PER_S;
use gyro_model::error::InputError;
use serde::Deserialize;

#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum ProgramFile {
    Steady {
        duration_s: f64,
    },
    SpeedChange {
        to_speed_kn: f64,
        #[serde(default)]
        acceleration_m_per_s2: Option<f64>,
        #[serde(default)]
        duration_s: Option<f64>,
    },
    Turn {
        #[serde(default)]
        to_heading_deg: Option<f64>,
        #[serde(default)]
        by_deg: Option<f64>,
        #[serde(default)]
        rate_deg_per_s: Option<f64>,
        #[serde(default)]
        radius_m: Option<f64>,
    },
    /// Alternating turns about a mean course: heading swings between mean ± swing.
    Zigzag {
        mean_heading_deg: f64,
        swing_deg: f64,
        legs: u32,
        leg_duration_s: f64,
        #[serde(default)]
        rate_deg_per_s: Option<f64>,
        #[serde(default)]
        radius_m: Option<f64>,
    },
}

/// The segments built so far and the ship's state at the end of the last one.
struct Track {
    segments: Vec<Segment>,
    t: f64,
    lat: f64,
    v: f64,
    h: f64,
}

impl Track {
    fn push(
        &mut self,
        kind: SegmentKind,
        dur: f64,
        manoeuvre: &str,
        entry: usize,
        description: String,
    ) {
        let seg = Segment {
            kind,
            start_s: self.t,
            duration_s: dur,
            latitude0_rad: self.lat,
            speed0_m_per_s: self.v,
            heading0_rad: self.h,
            manoeuvre: manoeuvre.into(),
            entry,
            description,
        };
        let (l1, v1, h1) = ShipProgram::end_state(&seg);
        self.lat = l1;
        self.v = v1;
        self.h = h1;
        self.t += dur;
        self.segments.push(seg);
    }
}

/// The program's segments, from the start state to the end of the scene (the last state holds
/// to `duration`).
pub(super) fn segments(
    program: &[ProgramFile],
    start: &StartFile,
    duration: f64,
    src: &SourceText,
) -> Result<Vec<Segment>, InputError> {
    let mut track = Track {
        segments: Vec::new(),
        t: 0.0,
        lat: start.latitude_deg.to_radians(),
        v: start.speed_kn * KNOT_IN_M_PER_S,
        h: start.heading_deg.to_radians(),
    };
    for (i, p) in program.iter().enumerate() {
        match p {
            ProgramFile::Steady { duration_s } => steady(&mut track, *duration_s, i, src)?,
            ProgramFile::SpeedChange {
                to_speed_kn,
                acceleration_m_per_s2,
                duration_s,
            } => speed_change(
                &mut track,
                *to_speed_kn,
                *acceleration_m_per_s2,
                *duration_s,
                i,
                src,
            )?,
            ProgramFile::Turn {
                to_heading_deg,
                by_deg,
                rate_deg_per_s,
                radius_m,
            } => {
                let r = turn_rate(*rate_deg_per_s, *radius_m, track.v, i, src);
                turn(&mut track, *to_heading_deg, *by_deg, r, i, src)?
            }
            ProgramFile::Zigzag {
                mean_heading_deg,
                swing_deg,
                legs,
                leg_duration_s,
                rate_deg_per_s,
                radius_m,
            } => {
                let r = turn_rate(*rate_deg_per_s, *radius_m, track.v, i, src)?;
                zigzag(
                    &mut track,
                    *mean_heading_deg,
                    *swing_deg,
                    *legs,
                    *leg_duration_s,
                    r,
                    i,
                    src,
                )?
            }
        }
    }
    // The last state holds to the end of the scene.
    if track.t < duration || track.segments.is_empty() {
        let rest = (duration - track.t)
            .max(0.0)
            .max(if track.segments.is_empty() {
                duration
            } else {
                0.0
            });
        track.push(
            SegmentKind::Steady,
            rest.max(1e-9),
            "steady",
            program.len(),
            "steady to the end".into(),
        );
    }
    Ok(track.segments)
}

fn steady(
    track: &mut Track,
    duration_s: f64,
    i: usize,
    src: &SourceText,
) -> Result<(), InputError> {
    if !(duration_s > 0.0 && duration_s.is_finite()) {
        return Err(src.err(
            None,
            "duration_s",
            &format!("program.{i}.duration_s"),
            format!("{duration_s} is out of range (allowed: > 0 s)"),
        ));
    }
    let desc = format!(
        "steady {:.1} kn on {:.1}°",
        track.v / KNOT_IN_M_PER_S,
        track.h.to_degrees()
    );
    track.push(SegmentKind::Steady, duration_s, "steady", i, desc);
    Ok(())
}

fn speed_change(
    track: &mut Track,
    to_speed_kn: f64,
    acceleration_m_per_s2: Option<f64>,
    duration_s: Option<f64>,
    i: usize,
    src: &SourceText,
) -> Result<(), InputError> {
    let target = to_speed_kn * KNOT_IN_M_PER_S;
    if !(target >= 0.0 && target.is_finite()) {
        return Err(src.err(
            None,
            "to_speed_kn",
            &format!("program.{i}.to_speed_kn"),
            format!("{to_speed_kn} is out of range (allowed: ≥ 0 kn)"),
        ));
    }
    let dv = target - track.v;
    let dur = match (acceleration_m_per_s2, duration_s) {
        (Some(a), None) if a > 0.0 && a.is_finite() => dv.abs() / a,
        (None, Some(d)) if d > 0.0 && d.is_finite() => d,
        (Some(_), Some(_)) => {
            return Err(src.err(
                None,
                "acceleration_m_per_s2",
                &format!("program.{i}"),
                "give either acceleration_m_per_s2 or duration_s, not both (contradictory options)"
                    .into(),
            ));
        }
        _ => {
            return Err(src.err(
                None,
                "acceleration_m_per_s2",
                &format!("program.{i}"),
                "a speed change needs acceleration_m_per_s2 > 0 or duration_s > 0".into(),
            ));
        }
    };
    if dur == 0.0 {
        return Ok(());
    }
    let a = dv / dur;
    let desc = format!(
        "speed {:.1} → {:.1} kn in {:.0} s",
        track.v / KNOT_IN_M_PER_S,
        to_speed_kn,
        dur
    );
    track.push(
        SegmentKind::SpeedChange {
            acceleration_m_per_s2: a,
        },
        dur,
        "speed_change",
        i,
        desc,
    );
    Ok(())
}

/// A turn's rate, rad/s (positive), from its rate or its radius at speed `v`. Its error is
/// reported only after the turn's own keys are checked (see [`turn`]).
fn turn_rate(
    rate: Option<f64>,
    radius: Option<f64>,
    v: f64,
    entry: usize,
    src: &SourceText,
) -> Result<f64, InputError> {
    let key_anchor = None;
    match (rate, radius) {
        (Some(r), None) if r > 0.0 && r.is_finite() => Ok(r.to_radians()),
        (None, Some(rad)) if rad > 0.0 && rad.is_finite() && v > 0.0 => Ok(v / rad),
        (None, Some(_)) => Err(src.err(
            key_anchor,
            "radius_m",
            &format!("program.{entry}.radius_m"),
            "a turn by radius needs a positive radius and the ship under way (speed > 0)".into(),
        )),
        (Some(_), Some(_)) => Err(src.err(
            key_anchor,
            "rate_deg_per_s",
            &format!("program.{entry}"),
            "give either rate_deg_per_s or radius_m, not both (contradictory options)".into(),
        )),
        _ => Err(src.err(
            key_anchor,
            "rate_deg_per_s",
            &format!("program.{entry}.rate_deg_per_s"),
            "a turn needs rate_deg_per_s > 0 or radius_m > 0".into(),
        )),
    }
}

fn turn(
    track: &mut Track,
    to_heading_deg: Option<f64>,
    by_deg: Option<f64>,
    rate: Result<f64, InputError>,
    i: usize,
    src: &SourceText,
) -> Result<(), InputError> {
    let delta = match (to_heading_deg, by_deg) {
        (Some(to), None) => {
            let d = (to.to_radians() - track.h).rem_euclid(std::f64::consts::TAU);
            if d > std::f64::consts::PI {
                d - std::f64::consts::TAU
            } else {
                d
            }
        }
        (None, Some(by)) => by.to_radians(),
        _ => {
            return Err(src.err(
                None,
                "to_heading_deg",
                &format!("program.{i}"),
                "a turn needs exactly one of to_heading_deg (shorter way) or by_deg (signed, + to starboard)".into(),
            ));
        }
    };
    let r = rate?;
    if delta == 0.0 {
        return Ok(());
    }
    let desc = format!(
        "turn {:+.1}° at {:.3}°/s",
        delta.to_degrees(),
        r.to_degrees()
    );
    track.push(
        SegmentKind::Turn {
            rate_rad_per_s: r * delta.signum(),
        },
        delta.abs() / r,
        "turn",
        i,
        desc,
    );
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn zigzag(
    track: &mut Track,
    mean_heading_deg: f64,
    swing_deg: f64,
    legs: u32,
    leg_duration_s: f64,
    r: f64,
    i: usize,
    src: &SourceText,
) -> Result<(), InputError> {
    if !(legs >= 1 && leg_duration_s >= 0.0 && swing_deg.is_finite() && swing_deg > 0.0) {
        return Err(src.err(
            None,
            "legs",
            &format!("program.{i}"),
            "a zig-zag needs legs ≥ 1, leg_duration_s ≥ 0, swing_deg > 0".into(),
        ));
    }
    let mean = mean_heading_deg.to_radians();
    let swing = swing_deg.to_radians();
    for leg in 0..legs {
        let target = if leg % 2 == 0 {
            mean + swing
        } else {
            mean - swing
        };
        let d = target - track.h;
        let d = (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        if d != 0.0 {
            let desc = format!("zig-zag leg {} turn {:+.1}°", leg + 1, d.to_degrees());
            track.push(
                SegmentKind::Turn {
                    rate_rad_per_s: r * d.signum(),
                },
                d.abs() / r,
                "zigzag",
                i,
                desc,
            );
        }
        if leg_duration_s > 0.0 {
            track.push(
                SegmentKind::Steady,
                leg_duration_s,
                "steady",
                i,
                format!("zig-zag leg {} steady", leg + 1),
            );
        }
    }
    Ok(())
}
