//! Does ColorVideoVDP separate masks at the evaluation's image sizes? JOD of the
//! quick evaluation's renders (after TAA and without) for white noise, STBN and
//! fsot's perceptual-taa mask, on several display models, with the time each
//! prediction takes: what the choice of fsot eval's display rests on
//! (bench/results/jod-probe.txt).
//!
//! cargo run --release --example jod_probe -- [CACHE_DIR]
use std::path::PathBuf;
use std::time::Instant;

use fsot_cli::eval::jod::Judge;
use fsot_cli::eval::render::{references, render, taa, MaskSampler};
use fsot_cli::eval::scenes::SCENES;
use fsot_cli::eval::suite::{method_mask, EvalSize, TAA_ALPHA};

fn main() {
    let cache = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "eval-out/cache".into()));
    std::fs::create_dir_all(&cache).unwrap();
    let size = EvalSize::quick();
    let displays = ["standard_fhd", "standard_4k", "sdr_fhd_24", "standard_phone"];
    let judges: Vec<Judge> =
        displays.iter().map(|d| Judge::new(d, 60.0, fsot_cli::eval::jod::Grey::Luminance).unwrap()).collect();
    let methods = ["white", "stbn", "ours-perceptual-taa"];
    let masks: Vec<_> = methods.iter().map(|m| method_mask(m, 2.1, &size, &cache, 1).unwrap()).collect();
    let n = size.shot.image;
    println!(
        "# JOD, quick size ({n}x{n}, {} frames, judged after {}), 60 fps",
        size.shot.frames, size.warmup
    );
    println!("scene | taa | method | {} | seconds per prediction", displays.join(" | "));
    for scene in SCENES {
        let refs = references(scene, size.shot, size.reference_samples, Some(&cache)).unwrap();
        let refs_taa = taa(&refs, TAA_ALPHA);
        for (method, mask) in methods.iter().zip(&masks) {
            let frames = render(scene, size.shot, &MaskSampler::new(mask, scene.dims(), 100));
            for (with_taa, (f, r)) in
                [(false, (frames.clone(), &refs)), (true, (taa(&frames, TAA_ALPHA), &refs_taa))]
            {
                let start = Instant::now();
                let jods: Vec<String> =
                    judges.iter().map(|j| format!("{:.3}", j.jod(&f, r, size.warmup, n).unwrap())).collect();
                let per = start.elapsed().as_secs_f64() / judges.len() as f64;
                println!("{} | {with_taa} | {method} | {} | {per:.3}", scene.name(), jods.join(" | "));
            }
        }
    }
}
