//! gyro-sim (placeholder until its issue lands)
