//! Physical constants and unit conversions, in one place. Everything inside gyrolab is SI.

/// Sidereal rotation rate of the Earth, rad/s (the thesis rounds it to 7e-5).
pub const EARTH_RATE_RAD_PER_S: f64 = 7.292_115e-5;
/// Mean radius of the Earth (sphere model), m. Gives a Schuler period 2π√(R/g) = 84.4 min.
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;
/// Standard gravity (plumb-line gravity, centrifugal part included), m/s².
pub const STANDARD_GRAVITY_M_PER_S2: f64 = 9.806_65;
/// One kilogram-force metre in newton metres (Beghin ch. IV–VI units).
pub const KGF_M_IN_N_M: f64 = 9.806_65;
/// One dyne centimetre in newton metres (Beghin ch. II–III and Villarceau units).
pub const DYN_CM_IN_N_M: f64 = 1.0e-7;
/// One gram square centimetre in kilogram square metres.
pub const G_CM2_IN_KG_M2: f64 = 1.0e-7;
/// One knot in m/s.
pub const KNOT_IN_M_PER_S: f64 = 1852.0 / 3600.0;
/// Revolutions per minute in rad/s.
pub const RPM_IN_RAD_PER_S: f64 = std::f64::consts::TAU / 60.0;

/// Schuler period 2π√(R/g), s.
pub fn schuler_period_s() -> f64 {
    std::f64::consts::TAU * (EARTH_RADIUS_M / STANDARD_GRAVITY_M_PER_S2).sqrt()
}
