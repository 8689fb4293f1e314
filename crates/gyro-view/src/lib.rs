//! gyro-view (placeholder until its issue lands)
