//! Initial conditions (stub).
