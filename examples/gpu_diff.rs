//! Diagnostic: GPU against CPU displacements slice by slice (one slice per
//! iteration), printing the worst differences with their context.
use fsot::core::kernel::{Kernel, KernelSpec};
use fsot::core::mask::Mask;
use fsot::core::rng::seed_key;
use fsot::core::slice::SliceSampler;
use fsot::core::tile::Tile;
use fsot::core::transport::{project, transport_slice, Scratch};
use fsot::optimize::backend::Backend;
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::{VulkanOptions, VulkanRun};
use fsot::vk::{Context, ContextOptions};

fn main() {
    let ctx = Context::new(&ContextOptions::default()).unwrap();
    let tile = Tile::new(16, 16, 8, 1, 2).unwrap();
    let mut s = Settings::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 21);
    s.iterations = 400;
    s.slices = Some(1);
    let mask = Mask::white(tile, 21);
    let kernel = Kernel::new(s.kernel, &tile);
    let sampler = SliceSampler::new(seed_key(s.seed), tile, &kernel, s.axis_share);
    let options = VulkanOptions::default().deterministic(true);
    let mut gpu = VulkanRun::new(&ctx, tile, s, Some(&mask), options).unwrap();
    let mut worst = (0.0f64, String::new());
    let mut hist = [0usize; 8];
    for it in 0..300 {
        let slice = sampler.draw(it, 0);
        let g = gpu.displacements(it).unwrap();
        let mut members = Vec::new();
        transport_slice(&mask.samples, &tile, &kernel, &slice, &mut Scratch::default(), |p, d| {
            members.push((p, d))
        });
        let n = members.len();
        for &(p, d) in &members {
            let i = p as usize * 2;
            let along = g[i] * slice.theta[0] + g[i + 1] * slice.theta[1];
            let e = (along - d).abs();
            let b = if e > 0.0 { ((-e.log10()).floor() as usize).min(7) } else { 7 };
            hist[b] += 1;
            if e > worst.0 {
                worst = (
                    e,
                    format!(
                        "it {it} n {n} theta ({:.6}, {:.6}) point {p} proj {:.6} cpu {d:.8} gpu {along:.8}",
                        slice.theta[0],
                        slice.theta[1],
                        project(&mask.samples[i..i + 2], &slice)
                    ),
                );
            }
        }
    }
    println!("device {}: worst |gpu - cpu| per slice = {:.3e}: {}", ctx.info().name, worst.0, worst.1);
    println!("error histogram by decade (>=1e-0 .. <1e-7): {hist:?}");
}
