//! One entry point from a method's name and parameters to a mask, shared by the
//! command line and the evaluation: white noise, STBN, FAST, and fsot (on the CPU
//! path; a run with checkpoints, cancellation or Vulkan goes through `run::Run`).

use crate::core::mask::Mask;
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::optimize::settings::Settings;
use crate::peers::fast::{fast_mask_from, FastSpec};
use crate::peers::stbn::stbn_mask_with;
use crate::peers::swap::SwapDevice;

/// How to make a mask.
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// Independent uniform samples.
    White,
    /// Spatiotemporal blue noise: energy sigmas in pixels and frames; vector
    /// masks by `passes` passes of annealing.
    Stbn { sigma: f64, sigma_t: f64, passes: u32 },
    /// Filter-adapted masks: greedy swaps for the filter, `passes` passes.
    Fast { spec: FastSpec, passes: u32 },
    /// fsot's optimizer, to the end on the CPU path.
    Fsot(Settings),
}

impl Method {
    /// Does it search by passes of swaps (and so report each pass)?
    pub fn swaps(&self, tile: &Tile) -> bool {
        matches!(self, Method::Fast { .. }) || matches!(self, Method::Stbn { .. } if tile.dims > 1)
    }
}

/// A made mask, and what its search has to say (FAST's swap counts).
pub struct Made {
    pub mask: Mask,
    pub note: Option<String>,
}

/// Makes the mask of `method` for `tile` from `seed` (fsot: the settings' seed),
/// the swap searches on `device`; `on_pass(pass, energy)` after each pass of a
/// swap search. `start`, a mask of `tile`, is where fsot and FAST begin (FAST's
/// swaps keep its values); white noise and STBN make their masks from nothing
/// and refuse one.
pub fn make(
    method: &Method,
    tile: Tile,
    seed: u64,
    start: Option<&Mask>,
    device: &SwapDevice,
    on_pass: &mut dyn FnMut(u32, f64),
) -> Result<Made> {
    if start.is_some() && matches!(method, Method::White | Method::Stbn { .. }) {
        return Err(Error::invalid(
            "white noise and STBN make their masks from nothing: an initial mask is for fsot and FAST",
        ));
    }
    let (mask, note) = match method {
        Method::White => {
            let mut m = Mask::white(tile, seed);
            m.set_meta("version", env!("CARGO_PKG_VERSION"));
            (m, None)
        }
        Method::Stbn { sigma, sigma_t, passes } => {
            let (mask, report) =
                stbn_mask_with(tile, *sigma, *sigma_t, *passes, seed, device, &mut *on_pass)?;
            let note = report.map(|r| format!("vector stbn annealing: {}", r.describe(device)));
            (mask, note)
        }
        Method::Fast { spec, passes } => {
            let (mask, report) = fast_mask_from(tile, spec, *passes, seed, start, device, &mut *on_pass)?;
            (mask, Some(format!("{}: {}", spec.describe(), report.describe(device))))
        }
        Method::Fsot(settings) => (crate::optimize::run::optimize(tile, *settings, start)?, None),
    };
    Ok(Made { mask, note })
}
