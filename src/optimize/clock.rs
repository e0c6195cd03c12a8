//! The wall clock that time budgets and reported times read. A platform without
//! one (WebAssembly with no host, wasm32-unknown-unknown, where
//! `std::time::Instant::now` panics) still runs the optimizer: its stamps are
//! empty, every time reads 0 s, a step takes one iteration, and a time budget is
//! refused before any work.

use crate::error::{Error, Result};
use std::time::Instant;

/// Whether this platform has a wall clock.
pub(crate) const HAS_CLOCK: bool = !cfg!(all(target_family = "wasm", target_os = "unknown"));

/// A moment on the wall clock; empty where the platform has none.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stamp(Option<Instant>);

impl Stamp {
    /// Now.
    pub(crate) fn now() -> Self {
        Self(HAS_CLOCK.then(Instant::now))
    }

    /// The moment `instant` (a caller's own clock reading).
    pub(crate) fn at(instant: Instant) -> Self {
        Self(Some(instant))
    }

    /// The moment, where the platform has a clock.
    pub(crate) fn instant(self) -> Option<Instant> {
        self.0
    }

    /// Seconds since this moment; 0 without a clock.
    pub(crate) fn seconds(self) -> f64 {
        self.0.map_or(0.0, |t| t.elapsed().as_secs_f64())
    }

    /// Seconds from `earlier` to this moment; 0 without a clock.
    pub(crate) fn seconds_since(self, earlier: Stamp) -> f64 {
        match (self.0, earlier.0) {
            (Some(t), Some(e)) => t.saturating_duration_since(e).as_secs_f64(),
            _ => 0.0,
        }
    }
}

/// An error where the platform has no clock to hold `what` to.
pub(crate) fn needs_clock(what: &str) -> Result<()> {
    match HAS_CLOCK {
        true => Ok(()),
        false => Err(Error::invalid(format!(
            "{what} needs a wall clock, and this platform has none (wasm32-unknown-unknown): \
             give a number of iterations instead"
        ))),
    }
}
