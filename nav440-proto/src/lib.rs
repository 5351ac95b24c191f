//! Crossbow NAV440 serial protocol (skeleton; see issue 2).
#![no_std]
#![forbid(unsafe_code)]
