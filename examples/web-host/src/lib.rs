//! A web build's start-up: the 64x64x32 RG mask an engine would otherwise embed,
//! made in the page by fsot's CPU path and handed to JavaScript as KTX2 bytes to
//! upload as a texture; or every mask of a scene file's plan, handed over as the
//! includes (`glsl/include/fsot.glsl`, `wgsl/fsot.wgsl`) read them. wasm32-unknown-unknown has one thread (fsot's parallel
//! loops run on it) and no clock, so the run takes a number of iterations rather
//! than a time budget: the mask does not depend on how fast the machine is.
//!
//! `run.mjs` loads the module in Node.js (a page does the same with
//! `WebAssembly.instantiateStreaming`); the module imports nothing, so a page can
//! also load it in a Web Worker and keep its main thread free while the mask is
//! made (a few seconds at 64x64x32, BENCHMARKS.md).

use std::cell::RefCell;

use fsot::{
    CancelFlag, CostModel, KernelSpec, Plan, RunOptions, SamplerPlan, Scene, Settings, Start, TexelFormat,
    Tile, Until,
};

thread_local! {
    /// The last call's output: a mask's KTX2 bytes, a plan's block and texels,
    /// or an error's text.
    static OUT: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
    /// What JavaScript wrote for `make_plan`: a scene file's text.
    static IN: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

fn put(bytes: Vec<u8>) {
    OUT.with(|out| *out.borrow_mut() = bytes);
}

/// Makes a `width` x `height` x `frames` mask of `dims` dimensions for TAA on a
/// 1080p display in `iterations` iterations from the animated start of `seed`,
/// keeps its KTX2 bytes (8-bit UNORM) for `out_ptr` and `out_len`, and returns
/// its objective as a fraction of white noise's; on an error, keeps the error's
/// text and returns -1.
#[no_mangle]
pub extern "C" fn make(width: u32, height: u32, frames: u32, dims: u32, iterations: u32, seed: u64) -> f64 {
    let made = (|| -> fsot::Result<(Vec<u8>, f64)> {
        let tile = Tile::new(width as usize, height as usize, frames as usize, 1, dims as usize)?;
        let kernel = KernelSpec::named("perceptual-taa")?.on_display_named("standard_fhd")?;
        // The animated start (one frame optimized, set in motion) is most of the
        // way there for a short run.
        let settings = Settings::new(kernel, seed).iterations(iterations).start(Start::Animated);
        let mask = fsot::optimize(tile, settings, None)?;
        Ok((mask.ktx2(Some(texel_format(dims as usize)))?, mask.score(kernel)?.ratio()))
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
/// and keeps the error's text (on a platform with a clock, returns the mask's
/// objective as a fraction of white noise's and keeps nothing new).
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

/// Room for `len` bytes of input (a scene file's text in UTF-8, for `make_plan`:
/// its length in bytes, as `TextEncoder` gives them, not in characters): where
/// JavaScript writes them, valid until the next call. The call may grow the
/// module's memory: view the memory after it.
#[no_mangle]
pub extern "C" fn input(len: usize) -> *mut u8 {
    IN.with(|input| {
        let mut input = input.borrow_mut();
        input.clear();
        input.resize(len, 0);
        input.as_mut_ptr()
    })
}

/// Makes every mask of the scene file written through `input` (its plan, as
/// `fsot plan` shows it) and keeps the plan as the includes read it: the plan
/// block, then the stacked texels, layer by layer (masks x T x spp layers of
/// W x H; 8-bit UNORM with 1 channel where every mask has 1 dimension, 2 where
/// the largest has 2, else 4). Returns the block's length in bytes; on an
/// error, keeps its text and returns -1.
#[no_mangle]
pub extern "C" fn make_plan() -> f64 {
    let made = (|| -> fsot::Result<(Vec<u8>, usize)> {
        let text = IN
            .with(|input| String::from_utf8(input.borrow().clone()))
            .map_err(|_| fsot::Error::invalid("the scene file is not UTF-8"))?;
        let scene = Scene::parse(&text, "scene").map_err(fsot::Error::invalid)?;
        let plan = Plan::new(&scene, &CostModel::unmeasured())?;
        let made = SamplerPlan::make(&plan, RunOptions::default(), &CancelFlag::new(), &mut |_| {})?
            .ok_or_else(|| fsot::Error::invalid("cancelled"))?;
        let mut bytes = made.plan_block()?;
        let block = bytes.len();
        bytes.extend(made.texels(texel_format(made.max_dims()))?);
        Ok((bytes, block))
    })();
    match made {
        Ok((bytes, block)) => {
            put(bytes);
            block as f64
        }
        Err(e) => {
            put(e.to_string().into_bytes());
            -1.0
        }
    }
}

/// The 8-bit UNORM format with channels for `dims`.
fn texel_format(dims: usize) -> TexelFormat {
    match dims {
        1 => TexelFormat::R8Unorm,
        2 => TexelFormat::R8G8Unorm,
        _ => TexelFormat::R8G8B8A8Unorm,
    }
}

/// Where the kept bytes start in the module's memory. Valid until the next call
/// of any export; a view of them from JavaScript is valid until the memory
/// grows, so copy them out before the next call.
#[no_mangle]
pub extern "C" fn out_ptr() -> *const u8 {
    OUT.with(|out| out.borrow().as_ptr())
}

/// How many bytes are kept.
#[no_mangle]
pub extern "C" fn out_len() -> usize {
    OUT.with(|out| out.borrow().len())
}
