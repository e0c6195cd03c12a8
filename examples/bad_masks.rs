//! Writes well-formed EXR masks holding bad values, for scripts/bad-inputs.sh:
//! `cargo run --release --example bad_masks -- DIR` makes DIR/nan.exr (a NaN
//! sample) and DIR/outside.exr (a sample of 1.5).

use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::io::exr;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).ok_or("usage: bad_masks DIR")?);
    let tile = Tile::new(4, 4, 2, 1, 2)?;
    for (name, value) in [("nan.exr", f32::NAN), ("outside.exr", 1.5)] {
        let mut mask = Mask::white(tile, 1);
        mask.samples[3] = value;
        std::fs::write(dir.join(name), exr::encode_unchecked(&mask)?)?;
    }
    Ok(())
}
