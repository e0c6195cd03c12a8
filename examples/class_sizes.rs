//! How a kernel's class sizes spread, and what share of the slices and of the
//! members lies past each limit: what the workgroup transport's first pass hands
//! on at that limit (`VulkanHooks::local_max` in tests). From the level thresholds alone: a
//! slice's class holds the taps whose threshold exceeds its uniform level, so
//! P(size >= k) = threshold[k - 1] / 2^32. d = 2, 1 spp.
//!
//! cargo run --release --example class_sizes -- [WxHxT] [KERNEL] [LIMIT...]
//! (defaults: 128x128x30 perceptual-taa 256 512 1024 2048)
use std::process::ExitCode;

use fsot::core::kernel::{Kernel, KernelSpec};
use fsot::core::slice::level_thresholds;
use fsot::core::tile::Tile;
use fsot::optimize::settings::{slices_and_hits, Settings};

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}\nusage: class_sizes [WxHxT] [KERNEL] [LIMIT...]");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let size = args.first().map(String::as_str).unwrap_or("128x128x30");
    let kernel_name = args.get(1).map(String::as_str).unwrap_or("perceptual-taa");
    let limits = match args.get(2..) {
        Some(given) if !given.is_empty() => given
            .iter()
            .map(|a| a.parse().map_err(|_| format!("not a limit: {a}")))
            .collect::<Result<_, _>>()?,
        _ => vec![256usize, 512, 1024, 2048],
    };
    let d: Vec<usize> = size
        .split('x')
        .map(|v| v.parse().map_err(|_| format!("not WxHxT: {size}")))
        .collect::<Result<_, _>>()?;
    let [w, h, t] = d[..] else { return Err(format!("not WxHxT: {size}")) };
    let tile = Tile::new(w, h, t, 1, 2).map_err(|e| e.to_string())?;
    let spec = KernelSpec::from_name(kernel_name, 2.1, None, 0.1, 60.0).map_err(|e| e.to_string())?;
    let kernel = Kernel::new(spec, &tile);
    let (slices, _) = slices_and_hits(&tile, &kernel, &Settings::new(spec, 0)).map_err(|e| e.to_string())?;
    let thresholds = level_thresholds(&kernel);
    let p_at_least = |k: usize| thresholds[k - 1] as f64 / 4_294_967_296.0;
    let taps = thresholds.len();
    let mean: f64 = (1..=taps).map(p_at_least).sum();
    println!("{size} {kernel_name}, d = 2, 1 spp: {slices} slices an iteration, largest class {taps}, mean {mean:.1}");
    for limit in limits.into_iter().filter(|&l| l >= 1 && l < taps) {
        let slices_past = p_at_least(limit + 1);
        // Members of the classes past the limit: each holds the limit's members
        // and one more for every k past it that it reaches.
        let members_past = limit as f64 * slices_past + (limit + 1..=taps).map(p_at_least).sum::<f64>();
        println!(
            "past {limit}: {:.3}% of the slices ({:.0} an iteration), {:.2}% of the members",
            100.0 * slices_past,
            slices_past * slices as f64,
            100.0 * members_past / mean
        );
    }
    Ok(())
}
