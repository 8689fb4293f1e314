//! The rotating Earth and the frames the compass lives in.
//!
//! World frame: the local level frame at the compass pivot, X North, Y West, Z up (Beghin's).
//! It moves with the ship over a spherical Earth and turns with it; its absolute angular
//! velocity is the Earth rate plus the transport rate, ε(cos L, 0, sin L) + λ̇(cos L, 0, sin L) +
//! (0, L̇, 0) with longitude rate λ̇ = v_E/(R cos L) and L̇ = v_N/R. So the gyrocompass effect,
//! the speed error and the Coriolis terms come out of kinematics, not special formulas.
//!
//! The ship frame: x forward (bow), y port, z up; world_from_ship = R_z(−heading) R_x(roll)
//! R_y(pitch), heading navigational (clockwise from true North), roll positive starboard down,
//! pitch positive bow down. The pivot sits at `pivot_m` from the roll centre in ship axes.
//!
//! Apparent gravity at the pivot: g_app = −g·Z − a_pivot, with a_pivot the pivot's acceleration
//! relative to the Earth-fixed point under it (centrifugal of the Earth's rotation is in g)
//! plus the Coriolis term 2ε×v. The compass then moves about a pivot fixed in a translating
//! frame, under the weight of its bodies in g_app.

use crate::constants::{EARTH_RADIUS_M, EARTH_RATE_RAD_PER_S, STANDARD_GRAVITY_M_PER_S2};
use crate::dual::{Jet, M3, Real, V3, rot_axis};

/// Where the ship is and how it moves at one instant. Generic so the engine can differentiate
/// it in time exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShipKinematics<T> {
    pub latitude_rad: T,
    /// Navigational heading, clockwise from true North.
    pub heading_rad: T,
    /// Speed over the ground along the heading.
    pub speed_m_per_s: T,
    /// Roll about the ship's fore-aft axis, positive starboard down.
    pub roll_rad: T,
    /// Pitch about the athwartship axis, positive bow down.
    pub pitch_rad: T,
}

/// A ship-motion program: kinematics at any time, as smooth functions between breakpoints.
/// Implementations must satisfy dL/dt = v cos(heading)/R (the program integrates its own track).
pub trait ShipMotion: Sync {
    fn kinematics<T: Real>(&self, t: T) -> ShipKinematics<T>;
    /// Times where the motion is not smooth (manoeuvre starts and ends).
    fn breakpoints(&self) -> Vec<f64>;
    /// True when the ship never moves, turns or rolls (a harbour): the model then reads the
    /// constant kinematics once and compiles no ship-motion terms.
    fn is_stationary(&self) -> bool;
    /// The largest |latitude| reached over [0, t_end] (checked against the pole).
    fn max_abs_latitude_rad(&self, t_end: f64) -> f64;
}

/// The ship at rest at a given latitude and heading (a harbour).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moored {
    pub latitude_rad: f64,
    pub heading_rad: f64,
}

impl ShipMotion for Moored {
    fn kinematics<T: Real>(&self, _t: T) -> ShipKinematics<T> {
        ShipKinematics {
            latitude_rad: T::cst(self.latitude_rad),
            heading_rad: T::cst(self.heading_rad),
            speed_m_per_s: T::zero(),
            roll_rad: T::zero(),
            pitch_rad: T::zero(),
        }
    }
    fn breakpoints(&self) -> Vec<f64> {
        Vec::new()
    }
    fn is_stationary(&self) -> bool {
        true
    }
    fn max_abs_latitude_rad(&self, _t_end: f64) -> f64 {
        self.latitude_rad.abs()
    }
}

/// Which terms of the base motion are compiled in. Absent terms are never evaluated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BaseEffects {
    pub earth_rotation: bool,
    pub transport_rate: bool,
    pub ship_acceleration: bool,
    pub turn_rate: bool,
    pub roll_pitch: bool,
    pub base_coriolis: bool,
}

/// Velocity components (North, West) of a ship state.
pub fn velocity_nw<T: Real>(k: &ShipKinematics<T>) -> (T, T) {
    let (s, c) = k.heading_rad.sin_cos();
    (k.speed_m_per_s * c, -(k.speed_m_per_s * s))
}

/// Absolute angular velocity of the local North–West–Up frame, in its own axes.
pub fn frame_rate<T: Real>(k: &ShipKinematics<T>, fx: &BaseEffects) -> V3<T> {
    let (sl, cl) = k.latitude_rad.sin_cos();
    let mut polar = T::zero();
    let mut west = T::zero();
    if fx.earth_rotation {
        polar += T::cst(EARTH_RATE_RAD_PER_S);
    }
    if fx.transport_rate {
        let (vn, vw) = velocity_nw(k);
        polar += -vw / (cl * EARTH_RADIUS_M);
        west += vn / EARTH_RADIUS_M;
    }
    V3([polar * cl, west, polar * sl])
}

/// world_from_ship.
pub fn world_from_ship<T: Real>(k: &ShipKinematics<T>, fx: &BaseEffects) -> M3<T> {
    let r = rot_axis(2, -k.heading_rad);
    if fx.roll_pitch {
        r.rotate_about_axis(0, k.roll_rad)
            .rotate_about_axis(1, k.pitch_rad)
    } else {
        r
    }
}

/// Orientation and absolute angular velocity of the chain's base at time `t`, as jets in time
/// (value and d/dt), in world axes.
pub fn base_motion<T: Real, S: ShipMotion>(
    motion: &S,
    ship_root: bool,
    fx: &BaseEffects,
    t: T,
) -> (M3<Jet<T, 1>>, V3<Jet<T, 1>>) {
    if !(ship_root && (fx.turn_rate || fx.roll_pitch)) {
        let k = motion.kinematics(Jet {
            v: t,
            d: [T::one()],
        });
        let frame = frame_rate(&k, fx);
        let r = if ship_root {
            world_from_ship(&k, fx)
        } else {
            M3::identity()
        };
        return (r, frame);
    }
    // The ship's own rates are derivatives of its angles, and the engine needs their time
    // derivatives too: evaluate the program on a second-order jet in time.
    let t2: Jet<Jet<T, 1>, 1> = Jet {
        v: Jet {
            v: t,
            d: [T::one()],
        },
        d: [Jet::constant(T::one())],
    };
    let k = motion.kinematics(t2);
    let first = |x: Jet<Jet<T, 1>, 1>| x.v;
    let rate = |x: Jet<Jet<T, 1>, 1>| x.d[0];
    let frame = frame_rate(&k, fx);
    let mut w = V3(frame.0.map(first));
    let r = world_from_ship(&k, fx);
    let r = M3(r.0.map(|row| row.map(first)));
    if fx.turn_rate {
        w.0[2] -= rate(k.heading_rad);
    }
    if fx.roll_pitch {
        let rz = rot_axis(2, -first(k.heading_rad));
        let roll_axis = rz.col(0).scale(rate(k.roll_rad));
        let pitch_axis = rz
            .rotate_about_axis(0, first(k.roll_rad))
            .col(1)
            .scale(rate(k.pitch_rad));
        w = w.add(&roll_axis).add(&pitch_axis);
    }
    (r, w)
}

/// Apparent gravity at the pivot (world axes), m/s².
pub fn apparent_gravity<S: ShipMotion>(
    motion: &S,
    fx: &BaseEffects,
    pivot_m: [f64; 3],
    t: f64,
) -> [f64; 3] {
    let mut g = [0.0, 0.0, -STANDARD_GRAVITY_M_PER_S2];
    if !(fx.ship_acceleration || fx.base_coriolis || fx.roll_pitch) {
        return g;
    }
    let mut a = [0.0; 3];
    if fx.ship_acceleration || fx.base_coriolis {
        accelerate_with_the_track(motion, fx, t, &mut a);
    }
    if fx.roll_pitch {
        // The pivot swings about the roll centre: second time derivative of R_ship·pivot.
        let t2: Jet<Jet<f64, 1>, 1> = Jet {
            v: Jet::variable(t, 0),
            d: [Jet::constant(1.0)],
        };
        let k2 = motion.kinematics(t2);
        let r = world_from_ship(&k2, fx);
        let p = r.mul_v(&V3::from_f64(pivot_m));
        for i in 0..3 {
            a[i] += p.0[i].d[0].d[0];
        }
    }
    for i in 0..3 {
        g[i] -= a[i];
    }
    g
}

/// The pivot's acceleration from the ship's track over the sphere (speed changes, turns and the
/// turning of the local frame) and the Coriolis acceleration of the Earth's rotation.
fn accelerate_with_the_track<S: ShipMotion>(
    motion: &S,
    fx: &BaseEffects,
    t: f64,
    a: &mut [f64; 3],
) {
    let tj = Jet::<f64, 1>::variable(t, 0);
    let k = motion.kinematics(tj);
    let (vn, vw) = velocity_nw(&k);
    if fx.ship_acceleration {
        // d/dt of the velocity components plus the turning of the local frame (transport rate).
        let (sl, cl) = k.latitude_rad.v.sin_cos();
        let lon_rate = -vw.v / (cl * EARTH_RADIUS_M);
        let lat_rate = vn.v / EARTH_RADIUS_M;
        let wt = [lon_rate * cl, lat_rate, lon_rate * sl];
        let v = [vn.v, vw.v, 0.0];
        let c = cross(wt, v);
        a[0] += vn.d[0] + c[0];
        a[1] += vw.d[0] + c[1];
        a[2] += c[2];
    }
    if fx.base_coriolis {
        let (sl, cl) = k.latitude_rad.v.sin_cos();
        let e = [EARTH_RATE_RAD_PER_S * cl, 0.0, EARTH_RATE_RAD_PER_S * sl];
        let c = cross(e, [vn.v, vw.v, 0.0]);
        for i in 0..3 {
            a[i] += 2.0 * c[i];
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_rate_at_rest_is_the_earth_rate() {
        let k = Moored {
            latitude_rad: 0.8,
            heading_rad: 0.3,
        }
        .kinematics(0.0f64);
        let fx = BaseEffects {
            earth_rotation: true,
            ..Default::default()
        };
        let w = frame_rate(&k, &fx);
        assert!((w.0[0] - EARTH_RATE_RAD_PER_S * 0.8f64.cos()).abs() < 1e-20);
        assert!(w.0[1] == 0.0);
        assert!((w.0[2] - EARTH_RATE_RAD_PER_S * 0.8f64.sin()).abs() < 1e-20);
    }
}
