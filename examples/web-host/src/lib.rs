//! A web build's start-up: the 64x64x32 RG mask an engine would otherwise embed,
//! made in the page by fsot's CPU path and handed to JavaScript as KTX2 bytes to
//! upload as a texture. wasm32-unknown-unknown has one thread (fsot's parallel
//! loops run on it) and no clock, so the run takes a number of iterations rather
//! than a time budget, and the mask is the same on every machine.
//!
//! `run.mjs` loads the module in Node.js (a page does the same with
//! `WebAssembly.instantiateStreaming`); the module imports nothing.

use fsot::{KernelSpec, Settings, Start, TexelFormat, Tile, Until};

/// The last mask's KTX2 bytes, or the last error's text.
static mut OUT: Vec<u8> = Vec::new();

fn put(bytes: Vec<u8>) {
    // SAFETY: one thread, and no reference to OUT outlives a call.
    unsafe { *std::ptr::addr_of_mut!(OUT) = bytes }
}

/// Makes a `width` x `height` x `frames` mask of `dims` dimensions for TAA on a
/// 1080p display in `iterations` iterations from the animated start of `seed`, keeps its KTX2 bytes
/// (8-bit UNORM) for `out_ptr`/`out_len`, and returns its objective as a
/// fraction of white noise's; on an error, keeps the error's text and returns -1.
#[no_mangle]
pub extern "C" fn make(width: u32, height: u32, frames: u32, dims: u32, iterations: u32, seed: u64) -> f64 {
    let made = (|| -> fsot::Result<(Vec<u8>, f64)> {
        let tile = Tile::new(width as usize, height as usize, frames as usize, 1, dims as usize)?;
        let kernel = KernelSpec::named("perceptual-taa")?.on_display_named("standard_fhd")?;
        // The animated start (one frame optimized, set in motion) is most of the
        // way there for a short run.
        let settings = Settings::new(kernel, seed).iterations(iterations).start(Start::Animated);
        let mask = fsot::optimize(tile, settings, None)?;
        let format = if dims == 1 { TexelFormat::R8Unorm } else { TexelFormat::R8G8Unorm };
        Ok((mask.ktx2(Some(format))?, mask.score(kernel)?.ratio()))
    })();
    match made {
        Ok((bytes, ratio)) => {
            put(bytes);
            ratio
        }
        Err(e) => {
            put(e.to_string().into_bytes());
            -1.0
        }
    }
}

/// Asks for a mask within a one-second budget, which needs a clock: returns -1
/// with the error's text kept (or the objective, on a platform with a clock).
#[no_mangle]
pub extern "C" fn make_within_a_second() -> f64 {
    let made = (|| -> fsot::Result<f64> {
        let tile = Tile::new(16, 16, 4, 1, 2)?;
        let kernel = KernelSpec::named("perceptual-taa")?;
        let settings = Settings::new(kernel, 1).iterations(100_000).until(Until::Seconds(1.0));
        fsot::optimize(tile, settings, None)?.score(kernel).map(|s| s.ratio())
    })();
    made.unwrap_or_else(|e| {
        put(e.to_string().into_bytes());
        -1.0
    })
}

/// Where the kept bytes start in the module's memory.
#[no_mangle]
pub extern "C" fn out_ptr() -> *const u8 {
    // SAFETY: as in `put`.
    unsafe { (*std::ptr::addr_of!(OUT)).as_ptr() }
}

/// How many bytes are kept.
#[no_mangle]
pub extern "C" fn out_len() -> usize {
    // SAFETY: as in `put`.
    unsafe { (*std::ptr::addr_of!(OUT)).len() }
}
