//! The tile being optimized: W x H pixels x T frames, wrapping in x, y and t, with
//! `spp` samples of dimension `dims` per pixel and frame.
//!
//! Sample layout (everywhere in fsot: memory, files, GPU buffers): sample `s` of the
//! pixel (x, y) in frame t is point number `((t * H + y) * W + x) * spp + s`, and its
//! coordinate k is at `point * dims + k`.

use crate::error::{Error, Result};

/// Largest supported dimension per sample.
pub const MAX_DIMS: usize = 8;
/// Largest supported samples per pixel.
pub const MAX_SPP: usize = 64;
/// Largest number of points in one tile (keeps every index in u32 and memory sane).
pub const MAX_POINTS: usize = 1 << 28;
/// Largest number of values (points x dims) in one tile: 1 GiB per buffer of
/// 32-bit values, of which a run holds several.
pub const MAX_VALUES: usize = 1 << 28;

/// The shape of a tile: W x H pixels x T frames, wrapping in x, y and t, with
/// `spp` samples of `dims` coordinates per pixel and frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// W: pixels per row, at least 1.
    pub width: usize,
    /// H: rows, at least 1.
    pub height: usize,
    /// T: frames, at least 1.
    pub frames: usize,
    /// Samples per pixel and frame, 1 to `MAX_SPP`.
    pub spp: usize,
    /// Coordinates per sample, 1 to `MAX_DIMS`.
    pub dims: usize,
}

impl Tile {
    /// An error unless `Tile::new` would make this tile: for one whose public
    /// fields were set by hand.
    pub fn check(&self) -> Result<()> {
        Tile::new(self.width, self.height, self.frames, self.spp, self.dims).map(|_| ())
    }

    /// A tile of W x H pixels x T frames, `spp` samples of `dims` coordinates
    /// each. Checks every parameter; the error says which one is wrong and why.
    pub fn new(width: usize, height: usize, frames: usize, spp: usize, dims: usize) -> Result<Self> {
        for (name, v) in [("width", width), ("height", height), ("frames", frames)] {
            if v == 0 {
                return Err(Error::invalid(format!("tile {name} must be at least 1, got 0")));
            }
        }
        if dims == 0 || dims > MAX_DIMS {
            return Err(Error::invalid(format!("dimensions per sample must be 1 to {MAX_DIMS}, got {dims}")));
        }
        if spp == 0 || spp > MAX_SPP {
            return Err(Error::invalid(format!("samples per pixel must be 1 to {MAX_SPP}, got {spp}")));
        }
        let points = width.checked_mul(height).and_then(|p| p.checked_mul(frames)).and_then(|p| p.checked_mul(spp));
        if points.is_none_or(|p| p > MAX_POINTS) {
            return Err(Error::invalid(format!(
                "tile {width}x{height}x{frames} with {spp} spp holds more than {MAX_POINTS} points"
            )));
        }
        if points.and_then(|p| p.checked_mul(dims)).is_none_or(|v| v > MAX_VALUES) {
            return Err(Error::invalid(format!(
                "tile {width}x{height}x{frames} with {spp} spp of d = {dims} holds more than {MAX_VALUES} values \
                 (points x d; 1 GiB a buffer)"
            )));
        }
        Ok(Self { width, height, frames, spp, dims })
    }

    /// Parses `WxHxT` (or `WxH`, meaning one frame).
    pub fn parse_size(text: &str) -> Result<(usize, usize, usize)> {
        let parts: Vec<&str> = text.split(['x', 'X']).collect();
        let bad = || Error::invalid(format!("size must look like 64x64x16 (W x H x T), got {text:?}"));
        if parts.len() < 2 || parts.len() > 3 {
            return Err(bad());
        }
        let mut v = [1usize; 3];
        for (i, p) in parts.iter().enumerate() {
            v[i] = p.trim().parse::<usize>().map_err(|_| bad())?;
        }
        Ok((v[0], v[1], v[2]))
    }

    /// Pixels over every frame: W x H x T (`usize::MAX` where that overflows,
    /// for a tile built by hand past `MAX_POINTS`; `check` refuses it).
    pub fn pixels(&self) -> usize {
        self.width.saturating_mul(self.height).saturating_mul(self.frames)
    }
    /// Samples in the tile: pixels x spp (saturating as `pixels`).
    pub fn points(&self) -> usize {
        self.pixels().saturating_mul(self.spp)
    }
    /// Coordinates in the tile: points x dims (saturating as `pixels`).
    pub fn values(&self) -> usize {
        self.points().saturating_mul(self.dims)
    }
    /// Pixel index of (x, y, t), all already wrapped into the tile.
    #[inline]
    pub fn pixel_index(&self, x: usize, y: usize, t: usize) -> usize {
        (t * self.height + y) * self.width + x
    }
    /// A one-line description, e.g. "64x64x16, 1 spp, d = 2".
    pub fn describe(&self) -> String {
        format!("{}x{}x{}, {} spp, d = {}", self.width, self.height, self.frames, self.spp, self.dims)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_validate() {
        assert_eq!(Tile::parse_size("64x32x16").unwrap(), (64, 32, 16));
        assert_eq!(Tile::parse_size("8x8").unwrap(), (8, 8, 1));
        assert!(Tile::parse_size("64x").is_err());
        assert!(Tile::parse_size("-1x2x3").is_err());
        assert!(Tile::new(0, 4, 4, 1, 2).is_err());
        assert!(Tile::new(4, 4, 4, 1, 0).is_err());
        assert!(Tile::new(4, 4, 4, 0, 2).is_err());
        assert!(Tile::new(4, 4, 4, 1, 9).is_err());
        assert!(Tile::new(usize::MAX / 2, 4, 4, 1, 2).is_err());
        // The largest tiles: 2^28 points of one value, 2^25 of eight; a value
        // more is refused before anything is allocated for it.
        assert!(Tile::new(1 << 14, 1 << 14, 1, 1, 1).is_ok());
        assert!(Tile::new(1 << 14, 1 << 14, 2, 1, 1).unwrap_err().to_string().contains("points"));
        assert!(Tile::new(4096, 4096, 2, 1, 8).is_ok());
        let e = Tile::new(4096, 4096, 16, 1, 8).unwrap_err().to_string();
        assert!(e.contains("more than 268435456 values"), "{e}");
        assert!(Tile::new(1 << 14, 1 << 14, 1, 1, 2).is_err());
        // Built by hand past the largest: the sizes saturate, and `check` refuses.
        let huge = Tile { width: usize::MAX / 2 + 1, height: 2, frames: 1, spp: 1, dims: 1 };
        assert_eq!((huge.pixels(), huge.points(), huge.values()), (usize::MAX, usize::MAX, usize::MAX));
        assert!(huge.check().is_err());
        let t = Tile::new(3, 2, 5, 4, 2).unwrap();
        assert_eq!(t.points(), 120);
        assert_eq!(t.pixel_index(2, 1, 4), (4 * 2 + 1) * 3 + 2);
    }
}
