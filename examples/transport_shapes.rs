//! The workgroup transport's GPU time per iteration on this device in a few
//! shapes: invocations per workgroup, slices per workgroup and the largest class
//! sorted in the first pass's shared memory (`VulkanHooks`; larger classes go to
//! the second pass). The shared memory a workgroup takes bounds how many
//! workgroups a GPU keeps resident, and with the display's eye most classes are
//! small (the kernel's mean class and largest class are printed), so a smaller
//! class limit can keep more of them in flight. Every shape runs the same
//! iterations in deterministic mode from the same white noise and must make the
//! same mask bit for bit, which is checked.
//!
//! ```text
//! cargo run --release --example transport_shapes -- [--size 128x128x30] [--iterations 50] [--sigma S]
//! ```
//!
//! Times come from the device's timestamp queries (`VulkanOptions::profile`).
//! The first shape is the one the run picks by itself.

use fsot::core::kernel::{Kernel, KernelSpec};
use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::optimize::backend::Backend;
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::{TransportKind, VulkanHooks, VulkanOptions, VulkanRun};
use fsot::vk::{Context, ContextOptions};

struct Args {
    size: (usize, usize, usize),
    iterations: u32,
    sigma: Option<f64>,
}

fn parse() -> Result<Args, String> {
    let mut args = Args { size: (128, 128, 30), iterations: 50, sigma: None };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or_else(|| format!("{flag} needs a value"))?;
        match flag.as_str() {
            "--size" => {
                let p: Vec<usize> = value
                    .split('x')
                    .map(|v| v.parse().map_err(|_| format!("--size {value}")))
                    .collect::<Result<_, _>>()?;
                let [w, h, t] = p[..] else { return Err(format!("--size takes WxHxT, got {value}")) };
                args.size = (w, h, t);
            }
            "--iterations" => {
                args.iterations =
                    value.parse().ok().filter(|n| *n > 0).ok_or(format!("--iterations {value}"))?
            }
            "--sigma" => {
                args.sigma =
                    Some(value.parse().ok().filter(|s: &f64| *s > 0.0).ok_or(format!("--sigma {value}"))?)
            }
            _ => return Err(format!("unknown flag {flag}")),
        }
    }
    Ok(args)
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = parse()?;
    let (w, h, t) = args.size;
    let tile = Tile::new(w, h, t, 1, 2)?;
    let spec = KernelSpec::from_name("perceptual-taa", args.sigma.unwrap_or(2.1), None, 0.1, 60.0)?;
    let spec = match args.sigma {
        Some(_) => spec,
        None => spec.on_display(fsot::core::display::parse(fsot::core::display::DEFAULT_DISPLAY)?)?,
    };
    let kernel = Kernel::new(spec, &tile);
    let ctx = Context::new(&ContextOptions { validation: false, device: None })?;
    println!(
        "{} on {}: kernel {}, {} taps (the largest class), mean class {:.1}; {} iterations per shape",
        tile.describe(),
        ctx.info().name,
        spec.describe(),
        kernel.taps.len(),
        kernel.mean_class_len(),
        args.iterations
    );
    let mut settings = Settings::new(spec, 1);
    settings.iterations = args.iterations;
    let start = Mask::white(tile, 1);
    let workgroup = |shape| VulkanHooks {
        transport: Some(TransportKind::Workgroup),
        workgroup_shape: Some(shape),
        ..VulkanHooks::default()
    };
    let shapes: Vec<(&str, VulkanHooks)> = vec![
        ("as chosen", VulkanHooks::default()),
        ("128 x 1, classes to 1024", VulkanHooks { local_max: Some(1024), ..workgroup((128, 1)) }),
        ("128 x 1, classes to 512", VulkanHooks { local_max: Some(512), ..workgroup((128, 1)) }),
        ("64 x 1, classes to 1024", VulkanHooks { local_max: Some(1024), ..workgroup((64, 1)) }),
        ("64 x 2, classes to 512", VulkanHooks { local_max: Some(512), ..workgroup((64, 2)) }),
        ("32 x 4, classes to 512", VulkanHooks { local_max: Some(512), ..workgroup((32, 4)) }),
        ("256 x 1, classes to 2048", workgroup((256, 1))),
    ];
    println!("| shape | transport ms | second pass and large classes ms | update ms | same mask |");
    println!("| --- | ---: | ---: | ---: | --- |");
    let mut reference: Option<Vec<f32>> = None;
    for (name, hooks) in shapes {
        let options = VulkanOptions::default().deterministic(true).profile(true).hooks(hooks);
        let mut run = match VulkanRun::new(&ctx, tile, settings, Some(&start), options) {
            Ok(run) => run,
            Err(e) => {
                println!("| {name} | not run: {e} | | | |");
                continue;
            }
        };
        while !run.finished() {
            run.step_up_to(args.iterations)?;
        }
        let samples = run.samples()?;
        let same = match &reference {
            None => {
                reference = Some(samples);
                "(the reference)".to_string()
            }
            Some(r) => {
                let differ = r.iter().zip(&samples).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
                if differ == 0 {
                    "yes".to_string()
                } else {
                    format!("NO: {differ} values differ")
                }
            }
        };
        let p = run.profile();
        let per = |ns: f64| ns / p.iterations.max(1) as f64 / 1e6;
        println!(
            "| {name} | {:.3} | {:.3} | {:.3} | {same} |",
            per(p.transport_ns),
            per(p.large_ns),
            per(p.update_ns)
        );
    }
    Ok(())
}
