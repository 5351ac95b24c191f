//! Firmware example (skeleton; see issue 3).
#![no_std]
#![no_main]
