//! A renderer's start-up: a small 2-D mask made on the CPU through fsot's
//! public API, and, with Vulkan, the device fsot would run on.
use fsot::{KernelSpec, Settings, Tile};

fn main() -> fsot::Result<()> {
    let tile = Tile::new(16, 16, 4, 1, 2)?;
    let mut settings = Settings::new(KernelSpec::named("perceptual-taa")?, 1);
    settings.iterations = 20;
    let mask = fsot::optimize(tile, settings, None)?;
    println!("made a {}x{}x{} mask, {} samples", tile.width, tile.height, tile.frames, mask.samples.len());
    #[cfg(feature = "vulkan")]
    match fsot::vk::Context::new(&fsot::vk::ContextOptions::default()) {
        Ok(ctx) => println!("Vulkan device: {}", ctx.info().name),
        Err(e) => println!("no Vulkan device: {e}"),
    }
    Ok(())
}
