//! A mask: the optimized tile's samples and what made them.

use crate::core::rng::{derive, seed_key, Stream};
use crate::core::tile::Tile;

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
    pub fn white(tile: Tile, seed: u64) -> Self {
        let mut rng = Stream::new(derive(seed_key(seed), 0x0417e));
        let samples = (0..tile.values()).map(|_| rng.next_f32()).collect();
        Self {
            tile,
            samples,
            meta: vec![("method".into(), "white".into()), ("seed".into(), seed.to_string())],
        }
    }

    /// Sample `s` of pixel (x, y) in frame t.
    pub fn sample(&self, x: usize, y: usize, t: usize, s: usize) -> &[f32] {
        let i = (self.tile.pixel_index(x, y, t) * self.tile.spp + s) * self.tile.dims;
        &self.samples[i..i + self.tile.dims]
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
