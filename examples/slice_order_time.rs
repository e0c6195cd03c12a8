//! How long one iteration's slice order takes on the device (the per-lane
//! transport's ordering passes, for CPU implementations of Vulkan): the mean
//! of 300 `VulkanRun::slice_order` calls, each one submission of the passes
//! for one iteration and the download of its order (so a submission's fixed
//! cost is in every figure), after 5 untimed calls.
//!
//! cargo run --release --example slice_order_time -- [WxHxT] [KERNEL]
//! (defaults: 32x32x16 taa; d = 2, 1 spp, seed 7)
use std::process::ExitCode;

use fsot::core::kernel::KernelSpec;
use fsot::core::tile::Tile;
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::{VulkanOptions, VulkanRun};

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}\nusage: slice_order_time [WxHxT] [KERNEL]");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let size = args.first().map(String::as_str).unwrap_or("32x32x16");
    let kernel = args.get(1).map(String::as_str).unwrap_or("taa");
    let dims: Vec<usize> = size
        .split('x')
        .map(|v| v.parse().map_err(|_| format!("bad size {size}")))
        .collect::<Result<_, _>>()?;
    let [w, h, t] = dims[..] else { return Err(format!("bad size {size}")) };
    let tile = Tile::new(w, h, t, 1, 2).map_err(|e| e.to_string())?;
    let spec = KernelSpec::from_name(kernel, 2.1, None, 0.1, 60.0).map_err(|e| e.to_string())?;
    let ctx = fsot::vk::Context::new(&Default::default()).map_err(|e| e.to_string())?;
    let run = VulkanRun::new(&ctx, tile, Settings::new(spec, 7), None, VulkanOptions::default())
        .map_err(|e| e.to_string())?;
    let order = |i| -> Result<fsot::optimize::vulkan::LaneOrder, String> {
        run.slice_order(i)
            .map_err(|e| e.to_string())?
            .ok_or_else(|| "this device takes the workgroup transport, which orders no slices".to_string())
    };
    for i in 0..5 {
        order(i)?;
    }
    let start = std::time::Instant::now();
    let mut chunks = 0;
    for i in 0..300 {
        chunks += order(i)?.chunks;
    }
    let ms = start.elapsed().as_secs_f64() * 1e3 / 300.0;
    println!(
        "{size} {kernel} on {}: {ms:.3} ms an iteration's slice order (mean of 300), {:.1} chunks",
        ctx.info().name,
        chunks as f64 / 300.0
    );
    Ok(())
}
