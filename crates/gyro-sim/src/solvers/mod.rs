//! Integrators (owned by the solvers work).
