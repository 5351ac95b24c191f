//! Velocity and acceleration estimators (skeleton; see issue 4).
#![no_std]
#![forbid(unsafe_code)]
