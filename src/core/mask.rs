//! A mask: the optimized tile's samples and what made them.

use crate::core::rng::{derive, seed_key, Stream};
use crate::core::tile::Tile;
use crate::error::{Error, Result};

/// The largest f32 below 1.
pub(crate) const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

/// The centre of stratum `rank` of `n` in [0, 1), as an f32 kept below 1 (for
/// n of 2^24 and more the last centres round to 1.0 in f32).
pub(crate) fn stratum_centre(rank: usize, n: usize) -> f32 {
    (((rank as f64 + 0.5) / n as f64) as f32).min(BELOW_ONE)
}

/// A tile's samples: `tile.spp` samples of `tile.dims` coordinates for each
/// pixel of each frame. Saved and opened by `save` and `open`; written into a
/// renderer's image by the `vulkan` feature's calls.
#[derive(Clone, Debug, PartialEq)]
pub struct Mask {
    /// The tile's size, samples per pixel and dimensions.
    pub tile: Tile,
    /// `tile.values()` coordinates in [0, 1), laid out as `tile` documents.
    pub samples: Vec<f32>,
    /// Provenance (kernel, parameters, seed, iterations, version), written into files.
    pub meta: Vec<(String, String)>,
}

impl Mask {
    /// Independent uniform samples (white noise) from a seed.
    ///
    /// # Panics
    ///
    /// For a tile `Tile::check` refuses (one whose public fields were set by
    /// hand), with its reason: such a tile may hold more values than memory.
    pub fn white(tile: Tile, seed: u64) -> Self {
        if let Err(e) = tile.check() {
            panic!("white noise of a tile out of range: {e}");
        }
        let mut rng = Stream::new(derive(seed_key(seed), 0x0417e));
        let samples = (0..tile.values()).map(|_| rng.next_f32()).collect();
        Self {
            tile,
            samples,
            meta: vec![("method".into(), "white".into()), ("seed".into(), seed.to_string())],
        }
    }

    /// An error unless the tile is one `Tile::new` makes and `samples` holds
    /// its `tile.values()` coordinates, each finite and in [0, 1): for a mask
    /// whose public fields were set by hand. Every writer (files, KTX2 bytes,
    /// a renderer's image or buffer) and `score` check the mask first.
    ///
    /// ```
    /// let mut mask = fsot::Mask::white(fsot::Tile::new(4, 4, 2, 1, 2)?, 1);
    /// assert!(mask.check().is_ok());
    /// mask.samples[3] = f32::NAN;
    /// assert!(mask.check().is_err());
    /// mask.samples.pop();
    /// assert!(mask.check().is_err());
    /// # Ok::<(), fsot::Error>(())
    /// ```
    pub fn check(&self) -> Result<()> {
        self.tile.check()?;
        if self.samples.len() != self.tile.values() {
            return Err(Error::invalid(format!(
                "a mask of {} needs {} values, it holds {}",
                self.tile.describe(),
                self.tile.values(),
                self.samples.len()
            )));
        }
        match self.samples.iter().position(|v| !(v.is_finite() && (0.0..1.0).contains(v))) {
            Some(i) => Err(Error::invalid(format!(
                "a mask's value {i} is {}, outside [0, 1)",
                self.samples[i]
            ))),
            None => Ok(()),
        }
    }

    /// Sample `s` of pixel (x, y) in frame t.
    ///
    /// # Panics
    ///
    /// Unless x < W, y < H, t < T and s < spp, or where the tile is not valid or
    /// `samples` holds fewer values than it (`check` tells).
    pub fn sample(&self, x: usize, y: usize, t: usize, s: usize) -> &[f32] {
        let tile = &self.tile;
        assert!(
            x < tile.width && y < tile.height && t < tile.frames && s < tile.spp,
            "sample ({x}, {y}, {t}, {s}) outside the tile {}",
            tile.describe()
        );
        // Checked: a tile built by hand past the largest panics here rather than
        // wrapping round to another sample.
        let i = t
            .checked_mul(tile.height)
            .and_then(|i| i.checked_add(y)?.checked_mul(tile.width))
            .and_then(|i| i.checked_add(x)?.checked_mul(tile.spp))
            .and_then(|i| i.checked_add(s)?.checked_mul(tile.dims))
            .unwrap_or_else(|| panic!("the mask's tile {} is not a valid tile", tile.describe()));
        &self.samples[i..i + tile.dims]
    }

    /// The provenance value under `key` (for example `kernel`, `seed`, `iterations`).
    pub fn meta(&self, key: &str) -> Option<&str> {
        self.meta.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    /// Sets the provenance value under `key`, replacing an earlier one.
    pub fn set_meta(&mut self, key: &str, value: impl Into<String>) {
        let value = value.into();
        match self.meta.iter_mut().find(|(k, _)| k == key) {
            Some(entry) => entry.1 = value,
            None => self.meta.push((key.to_string(), value)),
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    #[should_panic(expected = "is not a valid tile")]
    fn a_sample_of_a_tile_built_past_the_largest_panics_rather_than_wrap_to_another() {
        let tile = Tile { width: 1 << 63, height: 4, frames: 1, spp: 1, dims: 1 };
        let mask = Mask { tile, samples: vec![0.5; 4], meta: Vec::new() };
        let _ = mask.sample(0, 2, 0, 0);
    }

    use super::*;

    #[test]
    fn a_strata_centre_stays_below_one_where_f32_would_round_it_up() {
        let n = 1usize << 25;
        assert_eq!(((n as f64 - 0.5) / n as f64) as f32, 1.0, "f32 alone rounds the last centre to 1");
        assert!(stratum_centre(n - 1, n) < 1.0);
        assert_eq!(stratum_centre(0, 4), 0.125);
        assert_eq!(stratum_centre(3, 4), 0.875);
    }
}
