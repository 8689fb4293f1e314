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
//!
//! Cost: the engine reads the base once per right-hand side. [`base_motion`] and
//! [`apparent_gravity`] take the ship's angles with their first two time derivatives from
//! [`ShipMotion::kinematics_d2`] (closed forms in a ship program: one `sin_cos` per sinusoid of
//! the sea) and rotate only what they need, in f64, instead of evaluating the program on nested
//! dual numbers. Measured by `cargo bench -p gyro-sim --bench rhs -- anschutz-1906` (the rolling
//! right-hand side against the harbour's).

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
    /// The kinematics at `t` with their first and second time derivatives, `[value, d/dt,
    /// d²/dt²]` per field: what the engine reads once per right-hand side. The default
    /// differentiates [`ShipMotion::kinematics`] on second-order jets; a program whose
    /// derivatives have closed forms overrides it (it must agree to round-off).
    fn kinematics_d2(&self, t: f64) -> ShipKinematics<[f64; 3]> {
        let k = self.kinematics(Jet {
            v: Jet::variable(t, 0),
            d: [Jet::constant(1.0)],
        });
        let taylor = |x: Jet<Jet<f64, 1>, 1>| [x.v.v, x.v.d[0], x.d[0].d[0]];
        ShipKinematics {
            latitude_rad: taylor(k.latitude_rad),
            heading_rad: taylor(k.heading_rad),
            speed_m_per_s: taylor(k.speed_m_per_s),
            roll_rad: taylor(k.roll_rad),
            pitch_rad: taylor(k.pitch_rad),
        }
    }
    /// Times where the motion is not smooth (manoeuvre starts and ends).
    fn breakpoints(&self) -> Vec<f64>;
    /// True when the ship never moves, turns or rolls (a harbour): the model then reads the
    /// constant kinematics once and compiles no ship-motion terms.
    fn is_stationary(&self) -> bool;
    /// True when the ship rolls or pitches (a sea of nonzero amplitude): `gyroscopic` fidelity
    /// then carries gyros on swinging frames (`crate::gyroscopic`). Any motion by default.
    fn rolls(&self) -> bool {
        !self.is_stationary()
    }
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
///
/// When `t` is a constant (the engine's case: it differentiates in the state, never in time)
/// the base is evaluated once in f64 from [`ShipMotion::kinematics_d2`] and lifted into `T`;
/// a `t` that carries derivatives is differentiated through exactly, as before.
pub fn base_motion<T: Real, S: ShipMotion>(
    motion: &S,
    ship_root: bool,
    fx: &BaseEffects,
    t: T,
) -> (M3<Jet<T, 1>>, V3<Jet<T, 1>>) {
    if t != T::cst(t.re()) {
        return base_motion_through_t(motion, ship_root, fx, t);
    }
    let (r, w) = base_motion_f64(motion, ship_root, fx, t.re());
    let lift = |x: Jet<f64, 1>| Jet {
        v: T::cst(x.v),
        d: [T::cst(x.d[0])],
    };
    (M3(r.0.map(|row| row.map(lift))), V3(w.0.map(lift)))
}

/// `x` and its rate as a first-order time jet.
fn value_jet(x: [f64; 3]) -> Jet<f64, 1> {
    Jet { v: x[0], d: [x[1]] }
}

/// The rate of `x` and its own rate as a first-order time jet.
fn rate_jet(x: [f64; 3]) -> Jet<f64, 1> {
    Jet { v: x[1], d: [x[2]] }
}

/// `x` as a second-order time jet.
fn second_order_jet(x: [f64; 3]) -> Jet<Jet<f64, 1>, 1> {
    Jet {
        v: Jet { v: x[0], d: [x[1]] },
        d: [Jet { v: x[1], d: [x[2]] }],
    }
}

fn map_kinematics<A: Copy, B>(k: &ShipKinematics<A>, f: impl Fn(A) -> B) -> ShipKinematics<B> {
    ShipKinematics {
        latitude_rad: f(k.latitude_rad),
        heading_rad: f(k.heading_rad),
        speed_m_per_s: f(k.speed_m_per_s),
        roll_rad: f(k.roll_rad),
        pitch_rad: f(k.pitch_rad),
    }
}

/// [`base_motion`] at an f64 time: the same formulas on first-order jets built from the closed
/// derivatives, so nothing is differentiated twice.
fn base_motion_f64<S: ShipMotion>(
    motion: &S,
    ship_root: bool,
    fx: &BaseEffects,
    t: f64,
) -> (M3<Jet<f64, 1>>, V3<Jet<f64, 1>>) {
    let k2 = motion.kinematics_d2(t);
    let k = map_kinematics(&k2, value_jet);
    let mut w = frame_rate(&k, fx);
    if !ship_root {
        return (M3::identity(), w);
    }
    // world_from_ship and the axes of the roll and pitch rates, each angle's sin_cos once.
    let rz = rotated(&M3::identity(), 2, (-k.heading_rad).sin_cos());
    let mut r = rz;
    if fx.turn_rate {
        w.0[2] -= rate_jet(k2.heading_rad);
    }
    if fx.roll_pitch {
        let rzx = rotated(&rz, 0, k.roll_rad.sin_cos());
        r = if k2.pitch_rad == [0.0; 3] {
            rzx
        } else {
            rotated(&rzx, 1, k.pitch_rad.sin_cos())
        };
        let roll_axis = rz.col(0).scale(rate_jet(k2.roll_rad));
        let pitch_axis = rzx.col(1).scale(rate_jet(k2.pitch_rad));
        w = w.add(&roll_axis).add(&pitch_axis);
    }
    (r, w)
}

/// m · R_axis(angle) from the angle's (sin, cos): [`M3::rotate_about_axis`] without its sin_cos.
fn rotated<T: Real>(m: &M3<T>, axis: usize, (s, c): (T, T)) -> M3<T> {
    let (i, j) = match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let mut r = *m;
    for row in 0..3 {
        let a = m.0[row][i];
        let b = m.0[row][j];
        r.0[row][i] = a * c + b * s;
        r.0[row][j] = b * c - a * s;
    }
    r
}

/// [`base_motion`] differentiated through every dual part of `t` (the program evaluated on
/// second-order jets of `T`).
fn base_motion_through_t<T: Real, S: ShipMotion>(
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
    let k2 = motion.kinematics_d2(t);
    if fx.ship_acceleration || fx.base_coriolis {
        accelerate_with_the_track(&map_kinematics(&k2, value_jet), fx, &mut a);
    }
    if fx.roll_pitch {
        // The pivot swings about the roll centre: second time derivative of
        // R_z(−heading) R_x(roll) R_y(pitch)·pivot, the vector rotated (not the matrix formed).
        let mut p = V3::<Jet<Jet<f64, 1>, 1>>::from_f64(pivot_m);
        if k2.pitch_rad != [0.0; 3] {
            p = rotate_vector(1, second_order_jet(k2.pitch_rad), p);
        }
        p = rotate_vector(0, second_order_jet(k2.roll_rad), p);
        let h = second_order_jet(k2.heading_rad);
        p = rotate_vector(2, -h, p);
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
fn accelerate_with_the_track(k: &ShipKinematics<Jet<f64, 1>>, fx: &BaseEffects, a: &mut [f64; 3]) {
    let (vn, vw) = velocity_nw(k);
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

/// R_axis(angle)·v, with R_axis the elementary rotation of [`rot_axis`].
fn rotate_vector<T: Real>(axis: usize, angle: T, v: V3<T>) -> V3<T> {
    let (s, c) = angle.sin_cos();
    let [x, y, z] = v.0;
    V3(match axis {
        0 => [x, y * c - z * s, y * s + z * c],
        1 => [x * c + z * s, y, z * c - x * s],
        _ => [x * c - y * s, x * s + y * c, z],
    })
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

    /// Everything moves at once: latitude, heading, speed, roll and pitch, each a smooth function
    /// of time (not a consistent track: the formulas under test do not care).
    struct Tumbling;

    impl ShipMotion for Tumbling {
        fn kinematics<T: Real>(&self, t: T) -> ShipKinematics<T> {
            ShipKinematics {
                latitude_rad: (t * 1e-4).sin() * 0.3 + 0.8,
                heading_rad: t * 0.02 + 0.4,
                speed_m_per_s: t * 0.05 + 7.0,
                roll_rad: (t * 0.7 + 0.2).sin() * 0.1,
                pitch_rad: (t * 1.1 - 0.5).sin() * 0.05,
            }
        }
        fn breakpoints(&self) -> Vec<f64> {
            Vec::new()
        }
        fn is_stationary(&self) -> bool {
            false
        }
        fn max_abs_latitude_rad(&self, _t_end: f64) -> f64 {
            1.1
        }
    }

    fn close(a: f64, b: f64, what: &str) {
        assert!(
            (a - b).abs() <= 1e-13 * (1.0 + b.abs()),
            "{what}: {a} vs {b}"
        );
    }

    #[test]
    fn the_f64_base_is_the_base_differentiated_through_time() {
        let fx = BaseEffects {
            earth_rotation: true,
            transport_rate: true,
            ship_acceleration: true,
            turn_rate: true,
            roll_pitch: true,
            base_coriolis: true,
        };
        for ship_root in [false, true] {
            for t in [0.0, 3.7, 1234.5] {
                let (r, w) = base_motion(&Tumbling, ship_root, &fx, t);
                // A time jet with a derivative part takes the exact path through t.
                let tj = Jet::<f64, 1>::variable(t, 0);
                let (rj, wj) = base_motion(&Tumbling, ship_root, &fx, tj);
                for i in 0..3 {
                    close(w.0[i].v, wj.0[i].v.v, "ω");
                    close(w.0[i].d[0], wj.0[i].d[0].v, "dω/dt");
                    for j in 0..3 {
                        close(r.0[i][j].v, rj.0[i][j].v.v, "R");
                        close(r.0[i][j].d[0], rj.0[i][j].d[0].v, "dR/dt");
                    }
                }
            }
        }
    }

    #[test]
    fn apparent_gravity_is_g_less_the_second_derivative_of_the_swinging_pivot() {
        let fx = BaseEffects {
            roll_pitch: true,
            ..Default::default()
        };
        let pivot = [0.3, -0.2, 10.0];
        for t in [0.0, 3.7, 1234.5] {
            let g = apparent_gravity(&Tumbling, &fx, pivot, t);
            // The pivot's world position R_ship(t)·p on second-order jets, R formed as a matrix.
            let t2: Jet<Jet<f64, 1>, 1> = Jet {
                v: Jet::variable(t, 0),
                d: [Jet::constant(1.0)],
            };
            let p = world_from_ship(&Tumbling.kinematics(t2), &fx).mul_v(&V3::from_f64(pivot));
            let g_z = -STANDARD_GRAVITY_M_PER_S2;
            for i in 0..3 {
                let expect = if i == 2 { g_z } else { 0.0 } - p.0[i].d[0].d[0];
                close(g[i], expect, "g_app");
            }
        }
    }

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
