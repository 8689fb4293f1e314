//! gyro-mcap (placeholder until its issue lands)
