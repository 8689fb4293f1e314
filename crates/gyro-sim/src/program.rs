//! The ship-motion program: a sequence of segments (steady, speed change, turn) plus a sea state,
//! evaluated in closed form at any time.
//!
//! Over a spherical Earth the latitude obeys dL/dt = v cos(heading)/R, and within each segment
//! speed and heading are explicit functions of time, so L(t) integrates in closed form: the track
//! is exact, and so are its time derivatives, which the engine takes by dual numbers. Longitude
//! (which no physics depends on) is integrated numerically for the record only.

use gyro_model::constants::EARTH_RADIUS_M;
use gyro_model::{Real, ShipKinematics, ShipMotion};

/// What a segment does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SegmentKind {
    Steady,
    /// Constant acceleration along the heading, m/s².
    SpeedChange {
        acceleration_m_per_s2: f64,
    },
    /// Constant rate of turn, rad/s (positive = to starboard, heading increasing).
    Turn {
        rate_rad_per_s: f64,
    },
}

/// A segment with its start state (filled in when the program is built).
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    pub kind: SegmentKind,
    pub start_s: f64,
    pub duration_s: f64,
    pub latitude0_rad: f64,
    pub speed0_m_per_s: f64,
    pub heading0_rad: f64,
    /// The scene's name for the manoeuvre (`speed_change`, `turn`, `zigzag`, `steady`).
    pub manoeuvre: String,
    /// Index of the scene program entry this segment came from.
    pub entry: usize,
    pub description: String,
}

/// Rolling and pitching as sinusoids; the roll plane follows the heading.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SeaState {
    pub roll_amplitude_rad: f64,
    pub roll_period_s: f64,
    pub roll_phase_rad: f64,
    pub pitch_amplitude_rad: f64,
    pub pitch_period_s: f64,
    pub pitch_phase_rad: f64,
}

impl SeaState {
    pub fn is_calm(&self) -> bool {
        self.roll_amplitude_rad == 0.0 && self.pitch_amplitude_rad == 0.0
    }
}

/// A ship program ready to evaluate.
#[derive(Clone, Debug, PartialEq)]
pub struct ShipProgram {
    pub segments: Vec<Segment>,
    pub sea: SeaState,
    pub end_s: f64,
    /// Force the moving-ship code path even when nothing moves (tests of "absent effects cost
    /// nothing" compare the two).
    pub force_moving: bool,
}

impl ShipProgram {
    fn segment_at(&self, t: f64) -> &Segment {
        // Segments are few: a linear scan from the end is cheap and branch-predictable.
        let mut idx = 0;
        for (i, s) in self.segments.iter().enumerate() {
            if t >= s.start_s {
                idx = i;
            } else {
                break;
            }
        }
        &self.segments[idx]
    }

    /// State at the end of a segment (for chaining).
    pub fn end_state(seg: &Segment) -> (f64, f64, f64) {
        let k = eval_segment(seg, seg.duration_s);
        (k.0, k.1, k.2)
    }

    /// Whether anything moves (speed, turns, sea).
    pub fn moves(&self) -> bool {
        self.force_moving
            || !self.sea.is_calm()
            || self
                .segments
                .iter()
                .any(|s| s.speed0_m_per_s != 0.0 || !matches!(s.kind, SegmentKind::Steady))
    }
    pub fn has_turns(&self) -> bool {
        self.segments
            .iter()
            .any(|s| matches!(s.kind, SegmentKind::Turn { .. }))
    }
    pub fn has_speed(&self) -> bool {
        self.segments
            .iter()
            .any(|s| s.speed0_m_per_s != 0.0 || matches!(s.kind, SegmentKind::SpeedChange { .. }))
    }
}

/// (latitude, speed, heading) of a segment at local time τ, generic for exact derivatives.
fn eval_segment<T: Real>(s: &Segment, tau: T) -> (T, T, T) {
    let v0 = s.speed0_m_per_s;
    let h0 = s.heading0_rad;
    match s.kind {
        SegmentKind::Steady => {
            let lat = tau * (v0 * Real::cos(h0) / EARTH_RADIUS_M) + s.latitude0_rad;
            (lat, T::cst(v0), T::cst(h0))
        }
        SegmentKind::SpeedChange {
            acceleration_m_per_s2: a,
        } => {
            let dist = tau * v0 + tau * tau * (0.5 * a);
            let lat = dist * (Real::cos(h0) / EARTH_RADIUS_M) + s.latitude0_rad;
            (lat, tau * a + v0, T::cst(h0))
        }
        SegmentKind::Turn { rate_rad_per_s: r } => {
            let h = tau * r + h0;
            // ∫ v cos(h0 + rτ) dτ = (v/r)(sin(h0 + rτ) − sin h0)
            let lat = (h.sin() - Real::sin(h0)) * (v0 / (r * EARTH_RADIUS_M)) + s.latitude0_rad;
            (lat, T::cst(v0), h)
        }
    }
}

/// (latitude, speed, heading) of a segment at local time τ with their first and second time
/// derivatives, `[value, d/dτ, d²/dτ²]`: the closed forms of [`eval_segment`] differentiated.
/// Its sines and cosines are the engine's (`Real` for f64), so both agree to the bit.
fn eval_segment_d2(s: &Segment, tau: f64) -> [[f64; 3]; 3] {
    let v0 = s.speed0_m_per_s;
    let h0 = s.heading0_rad;
    match s.kind {
        SegmentKind::Steady => {
            // Moored (v0 = 0) is the common case under a sea: no cosine for a zero rate.
            let lat_rate = if v0 == 0.0 {
                0.0
            } else {
                v0 * Real::cos(h0) / EARTH_RADIUS_M
            };
            [
                [tau * lat_rate + s.latitude0_rad, lat_rate, 0.0],
                [v0, 0.0, 0.0],
                [h0, 0.0, 0.0],
            ]
        }
        SegmentKind::SpeedChange {
            acceleration_m_per_s2: a,
        } => {
            let k = Real::cos(h0) / EARTH_RADIUS_M;
            let dist = tau * v0 + tau * tau * (0.5 * a);
            let v = tau * a + v0;
            [
                [dist * k + s.latitude0_rad, v * k, a * k],
                [v, a, 0.0],
                [h0, 0.0, 0.0],
            ]
        }
        SegmentKind::Turn { rate_rad_per_s: r } => {
            let h = tau * r + h0;
            let (sh, ch) = Real::sin_cos(h);
            let lat = (sh - Real::sin(h0)) * (v0 / (r * EARTH_RADIUS_M)) + s.latitude0_rad;
            let k = v0 / EARTH_RADIUS_M;
            [[lat, ch * k, -sh * r * k], [v0, 0.0, 0.0], [h, r, 0.0]]
        }
    }
}

/// A sinusoid a·sin(2π t/period + phase) with its first and second time derivatives.
fn sinusoid_d2(amplitude: f64, period_s: f64, phase_rad: f64, t: f64) -> [f64; 3] {
    if amplitude == 0.0 {
        return [0.0; 3];
    }
    let w = std::f64::consts::TAU / period_s;
    let (s, c) = Real::sin_cos(t * w + phase_rad);
    [amplitude * s, amplitude * w * c, -amplitude * w * w * s]
}

impl ShipMotion for ShipProgram {
    /// Closed forms: one `sin_cos` per sinusoid of the sea (and one in a turn), no dual numbers.
    fn kinematics_d2(&self, t: f64) -> ShipKinematics<[f64; 3]> {
        let s = self.segment_at(t);
        let [lat, v, h] = eval_segment_d2(s, t - s.start_s);
        let sea = &self.sea;
        ShipKinematics {
            latitude_rad: lat,
            heading_rad: h,
            speed_m_per_s: v,
            roll_rad: sinusoid_d2(
                sea.roll_amplitude_rad,
                sea.roll_period_s,
                sea.roll_phase_rad,
                t,
            ),
            pitch_rad: sinusoid_d2(
                sea.pitch_amplitude_rad,
                sea.pitch_period_s,
                sea.pitch_phase_rad,
                t,
            ),
        }
    }

    fn kinematics<T: Real>(&self, t: T) -> ShipKinematics<T> {
        let s = self.segment_at(t.re());
        let (lat, v, h) = eval_segment(s, t - s.start_s);
        let sea = &self.sea;
        let roll = if sea.roll_amplitude_rad != 0.0 {
            (t * (std::f64::consts::TAU / sea.roll_period_s) + sea.roll_phase_rad).sin()
                * sea.roll_amplitude_rad
        } else {
            T::zero()
        };
        let pitch = if sea.pitch_amplitude_rad != 0.0 {
            (t * (std::f64::consts::TAU / sea.pitch_period_s) + sea.pitch_phase_rad).sin()
                * sea.pitch_amplitude_rad
        } else {
            T::zero()
        };
        ShipKinematics {
            latitude_rad: lat,
            heading_rad: h,
            speed_m_per_s: v,
            roll_rad: roll,
            pitch_rad: pitch,
        }
    }
    fn breakpoints(&self) -> Vec<f64> {
        self.segments.iter().skip(1).map(|s| s.start_s).collect()
    }
    fn is_stationary(&self) -> bool {
        !self.moves()
    }
    fn rolls(&self) -> bool {
        !self.sea.is_calm()
    }
    fn max_abs_latitude_rad(&self, t_end: f64) -> f64 {
        let mut m: f64 = 0.0;
        for s in &self.segments {
            if s.start_s > t_end {
                break;
            }
            let d = s.duration_s.min(t_end - s.start_s).max(0.0);
            // Ends of the segment, plus the extreme of a turn's latitude swing.
            m = m
                .max(eval_segment(s, 0.0).0.abs())
                .max(eval_segment(s, d).0.abs());
            if let SegmentKind::Turn { rate_rad_per_s: r } = s.kind {
                m = m.max(
                    s.latitude0_rad.abs() + 2.0 * (s.speed0_m_per_s / (r * EARTH_RADIUS_M)).abs(),
                );
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gyro_model::Jet;

    fn seg(kind: SegmentKind, v0: f64, h0: f64) -> Segment {
        Segment {
            kind,
            start_s: 0.0,
            duration_s: 600.0,
            latitude0_rad: 0.5,
            speed0_m_per_s: v0,
            heading0_rad: h0,
            manoeuvre: String::new(),
            entry: 0,
            description: String::new(),
        }
    }

    #[test]
    fn closed_form_derivatives_are_the_programs_own() {
        let sea = SeaState {
            roll_amplitude_rad: 0.07,
            roll_period_s: 10.0,
            roll_phase_rad: 0.3,
            pitch_amplitude_rad: 0.02,
            pitch_period_s: 7.0,
            pitch_phase_rad: -1.0,
        };
        for kind in [
            SegmentKind::Steady,
            SegmentKind::SpeedChange {
                acceleration_m_per_s2: 0.2,
            },
            SegmentKind::Turn {
                rate_rad_per_s: 0.01,
            },
        ] {
            let mut s = seg(kind, 10.0, 0.7);
            s.start_s = 100.0;
            let p = ShipProgram {
                segments: vec![s],
                sea,
                end_s: 700.0,
                force_moving: false,
            };
            for t in [100.0, 217.0, 433.0] {
                let fast = p.kinematics_d2(t);
                let t2: Jet<Jet<f64, 1>, 1> = Jet {
                    v: Jet::variable(t, 0),
                    d: [Jet::constant(1.0)],
                };
                let k = p.kinematics(t2);
                let pairs = [
                    (fast.latitude_rad, k.latitude_rad),
                    (fast.heading_rad, k.heading_rad),
                    (fast.speed_m_per_s, k.speed_m_per_s),
                    (fast.roll_rad, k.roll_rad),
                    (fast.pitch_rad, k.pitch_rad),
                ];
                for (f, j) in pairs {
                    let exact = [j.v.v, j.v.d[0], j.d[0].d[0]];
                    for i in 0..3 {
                        assert!(
                            (f[i] - exact[i]).abs() <= 1e-14 * (1.0 + exact[i].abs()),
                            "{kind:?} t = {t}: {f:?} vs {exact:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn latitude_rate_is_v_cos_heading_over_r_in_every_segment() {
        for s in [
            seg(SegmentKind::Steady, 15.0, 0.3),
            seg(
                SegmentKind::SpeedChange {
                    acceleration_m_per_s2: 0.2,
                },
                5.0,
                -0.7,
            ),
            seg(
                SegmentKind::Turn {
                    rate_rad_per_s: 0.01,
                },
                10.0,
                1.0,
            ),
        ] {
            for tau in [0.0, 17.0, 333.0] {
                let (lat, v, h) = eval_segment(&s, Jet::<f64, 1>::variable(tau, 0));
                let expect = v.v * h.v.cos() / EARTH_RADIUS_M;
                assert!((lat.d[0] - expect).abs() < 1e-18, "{:?}", s.kind);
            }
        }
    }
}
