//! Small rotation arithmetic on `[x, y, z, w]` quaternions (the recording's convention) and the
//! tilt exaggeration that makes arc-minutes visible.

/// A unit quaternion `[x, y, z, w]`.
pub(crate) type Quat = [f64; 4];

pub(crate) const IDENTITY: Quat = [0.0, 0.0, 0.0, 1.0];

/// `a * b`: first rotate by `b`, then by `a`.
pub(crate) fn mul(a: Quat, b: Quat) -> Quat {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

pub(crate) fn conj(q: Quat) -> Quat {
    [-q[0], -q[1], -q[2], q[3]]
}

/// The unit quaternion along `q`, or the identity when `q` is zero or not finite (untrusted input).
pub(crate) fn normalize(q: Quat) -> Quat {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if n.is_finite() && n > 1e-12 {
        [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
    } else {
        IDENTITY
    }
}

pub(crate) fn rotate(q: Quat, v: [f64; 3]) -> [f64; 3] {
    let p = mul(mul(q, [v[0], v[1], v[2], 0.0]), conj(q));
    [p[0], p[1], p[2]]
}

/// Rotation by `angle_rad` about the unit `axis`.
pub(crate) fn axis_angle(axis: [f64; 3], angle_rad: f64) -> Quat {
    let (s, c) = (0.5 * angle_rad).sin_cos();
    [axis[0] * s, axis[1] * s, axis[2] * s, c]
}

pub(crate) fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The shortest rotation taking the unit vector `from` to the unit vector `to`.
pub(crate) fn rotation_between(from: [f64; 3], to: [f64; 3]) -> Quat {
    let c = [
        from[1] * to[2] - from[2] * to[1],
        from[2] * to[0] - from[0] * to[2],
        from[0] * to[1] - from[1] * to[0],
    ];
    let s = norm(c);
    let d = from[0] * to[0] + from[1] * to[1] + from[2] * to[2];
    if s < 1e-12 {
        if d > 0.0 {
            return IDENTITY;
        }
        // Opposite: half a turn about any axis normal to `from`.
        let helper = if from[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let a = [
            from[1] * helper[2] - from[2] * helper[1],
            from[2] * helper[0] - from[0] * helper[2],
            from[0] * helper[1] - from[1] * helper[0],
        ];
        let n = norm(a);
        return axis_angle([a[0] / n, a[1] / n, a[2] / n], std::f64::consts::PI);
    }
    axis_angle([c[0] / s, c[1] / s, c[2] / s], s.atan2(d))
}

/// Tilts larger than this are not exaggerated further: the map saturates smoothly towards it.
pub const TILT_SATURATION_RAD: f64 = 80.0 * std::f64::consts::PI / 180.0;

/// Exaggerates tilts away from the local vertical (earth frame z = Up) by a factor, leaving
/// azimuth alone: a tilt θ about a horizontal axis is shown as
/// `TILT_SATURATION_RAD · tanh(k·θ / TILT_SATURATION_RAD)` about the same axis, i.e. k·θ for small
/// tilts, never more than 80°. A factor of 1 is the identity.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TiltExaggeration {
    factor: f64,
}

impl TiltExaggeration {
    pub(crate) fn new(factor: f64) -> Self {
        Self { factor }
    }

    pub(crate) fn is_identity(&self) -> bool {
        (self.factor - 1.0).abs() < 1e-12
    }

    pub(crate) fn angle(&self, tilt_rad: f64) -> f64 {
        if self.is_identity() {
            tilt_rad
        } else {
            TILT_SATURATION_RAD * (self.factor * tilt_rad / TILT_SATURATION_RAD).tanh()
        }
    }

    /// The extra rotation (in the earth frame) that exaggerates the tilt of `up_in_earth`, the
    /// direction a body's reference-vertical axis points to.
    pub(crate) fn correction(&self, up_in_earth: [f64; 3]) -> Quat {
        if self.is_identity() {
            return IDENTITY;
        }
        // axis = Up × w, |Up × w| = sin θ, Up·w = cos θ.
        let a = [-up_in_earth[1], up_in_earth[0], 0.0];
        let s = norm(a);
        if s < 1e-15 || !s.is_finite() {
            return IDENTITY;
        }
        let theta = s.atan2(up_in_earth[2]);
        axis_angle([a[0] / s, a[1] / s, 0.0], self.angle(theta) - theta)
    }

    /// `earth_from_body` with its tilt exaggerated; `up_in_body` is the body axis that points Up
    /// when the body is level.
    pub(crate) fn apply(&self, earth_from_body: Quat, up_in_body: [f64; 3]) -> Quat {
        if self.is_identity() {
            return earth_from_body;
        }
        mul(
            self.correction(rotate(earth_from_body, up_in_body)),
            earth_from_body,
        )
    }

    /// A direction in the earth frame (e.g. the apparent vertical) with its tilt exaggerated.
    pub(crate) fn vector(&self, v: [f64; 3]) -> [f64; 3] {
        let n = norm(v);
        if self.is_identity() || n < 1e-300 || !n.is_finite() {
            return v;
        }
        let u = [v[0] / n, v[1] / n, v[2] / n];
        let r = rotate(self.correction(u), u);
        [r[0] * n, r[1] * n, r[2] * n]
    }
}

/// The body axis (±x, ±y, ±z) closest to the direction `v` given in body coordinates.
pub(crate) fn nearest_axis(v: [f64; 3]) -> [f64; 3] {
    let mut best = [0.0, 0.0, 1.0];
    let mut best_dot = f64::NEG_INFINITY;
    for i in 0..3 {
        for sign in [1.0, -1.0] {
            let d = sign * v[i];
            if d > best_dot {
                best_dot = d;
                best = [0.0; 3];
                best[i] = sign;
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < tol)
    }

    #[test]
    fn rotate_about_z_takes_north_to_west() {
        let q = axis_angle([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2);
        assert!(close(rotate(q, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], 1e-12));
    }

    #[test]
    fn rotation_between_maps_vectors() {
        let from = [0.0, 0.0, 1.0];
        let to = [0.6, 0.0, 0.8];
        assert!(close(rotate(rotation_between(from, to), from), to, 1e-12));
        let q = rotation_between(from, [0.0, 0.0, -1.0]);
        assert!(close(rotate(q, from), [0.0, 0.0, -1.0], 1e-12));
    }

    #[test]
    fn factor_one_is_identity() {
        let e = TiltExaggeration::new(1.0);
        let q = normalize([0.1, -0.2, 0.3, 0.9]);
        assert_eq!(e.apply(q, [0.0, 0.0, 1.0]), q);
        assert_eq!(e.vector([0.1, 0.2, 9.8]), [0.1, 0.2, 9.8]);
    }

    #[test]
    fn small_tilt_is_multiplied_and_azimuth_kept() {
        let e = TiltExaggeration::new(100.0);
        // Heading 30° (about Up), then a tilt of 1 arc-minute about the body's y axis.
        let tilt = 1.0_f64.to_radians() / 60.0;
        let q = mul(
            axis_angle([0.0, 0.0, 1.0], 30f64.to_radians()),
            axis_angle([0.0, 1.0, 0.0], tilt),
        );
        let shown = e.apply(q, [0.0, 0.0, 1.0]);
        let up = rotate(shown, [0.0, 0.0, 1.0]);
        let shown_tilt = norm([up[0], up[1], 0.0]).atan2(up[2]);
        // k·θ up to the saturation map's curvature (relative (kθ/80°)²/3 ≈ 1.5e-4 here).
        assert!(
            (shown_tilt / tilt / 100.0 - 1.0).abs() < 2e-4,
            "{shown_tilt}"
        );
        // The tilt stays in the same vertical plane, and the heading of the x axis is unchanged.
        let up0 = rotate(q, [0.0, 0.0, 1.0]);
        assert!((up[1].atan2(up[0]) - up0[1].atan2(up0[0])).abs() < 1e-9);
        let x = rotate(shown, [1.0, 0.0, 0.0]);
        assert!((x[1].atan2(x[0]) - 30f64.to_radians()).abs() < 1e-6);
    }

    #[test]
    fn large_tilts_saturate() {
        let e = TiltExaggeration::new(1000.0);
        let v = e.vector([1.0, 0.0, 1.0]);
        let t = v[0].atan2(v[2]);
        assert!(t <= TILT_SATURATION_RAD + 1e-12 && t > 79f64.to_radians());
        assert!((norm(v) - 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn nearest_axis_snaps() {
        assert_eq!(nearest_axis([0.1, -0.9, 0.2]), [0.0, -1.0, 0.0]);
        assert_eq!(nearest_axis([0.0, 0.0, 0.0]), [1.0, 0.0, 0.0]);
    }
}
