//! gyro-analysis (placeholder until its issue lands)
