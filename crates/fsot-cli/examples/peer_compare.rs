//! Compares masks, ours and the published ones, on the independent perceived-error
//! test (with and without TAA, ratio to white noise of the same shape) and on the
//! `fsot score` objective under the taa kernel.
//!
//! cargo run --release --example peer_compare -- [MASK.exr | PEER.png ...]
//! QUANT8=1 quantises the .exr masks to 8 bits first, as the published ones are.
//! SPECTRA=DIR also writes each mask's XY and XT power spectra as PNG images
//! (DC in the centre, log scale from 1/100 to 10 times white noise).
//! A .png is read as a published 128x128x64 scalar mask: 8-bit grey (or grey in
//! RGB/RGBA, first channel read), the 64 frames
//! stacked vertically, value v standing for (v + 0.5) / 256 (see
//! ../shared/data/peer-masks/README.md; used for comparison only).
use fsot::core::kernel::KernelSpec;
use fsot::core::mask::Mask;
use fsot::core::objective::{score, SCORE_SLICES};
use fsot::quality::perceived::{ratio_to_white, TestSetup};

fn read_peer_png(path: &str) -> Result<Mask, String> {
    fsot::io::stacked_png::read(std::path::Path::new(path)).map_err(|e| e.to_string())
}

fn main() {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    let taa = KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap();
    println!("| mask | tile | perceived, TAA (x white) | perceived, no TAA (x white) | objective, taa kernel (x white) |");
    println!("| --- | --- | ---: | ---: | ---: |");
    for path in paths {
        let mask = if path.ends_with(".png") {
            read_peer_png(&path)
        } else {
            fsot::io::exr::read(path.as_ref()).map_err(|e| e.to_string())
        };
        let mask = match mask {
            // QUANT8=1: store our masks as the published ones are, 8 bits.
            Ok(mut m) if std::env::var("QUANT8").is_ok() && !path.ends_with(".png") => {
                m.samples.iter_mut().for_each(|v| *v = ((*v * 256.0).floor() + 0.5) / 256.0);
                m
            }
            Ok(m) => m,
            Err(e) => {
                eprintln!("error: {e}");
                std::process::exit(1);
            }
        };
        let with = ratio_to_white(&mask, &TestSetup::default(), 4);
        let without = ratio_to_white(&mask, &TestSetup { taa_alpha: None, ..TestSetup::default() }, 4);
        let s = score(&mask, taa, SCORE_SLICES);
        let name = std::path::Path::new(&path).file_name().unwrap().to_string_lossy().into_owned();
        if let Ok(dir) = std::env::var("SPECTRA") {
            use fsot_cli::eval::spectrum::{spectrum_png, spectrum_xt, spectrum_xy};
            let t = mask.tile;
            let stem = name.trim_end_matches(".png").trim_end_matches(".exr");
            let xy = spectrum_png(&spectrum_xy(&mask, 0).unwrap(), t.height, t.width).unwrap();
            let xt = spectrum_png(&spectrum_xt(&mask, 0).unwrap(), t.frames, t.width).unwrap();
            std::fs::write(format!("{dir}/{stem}-xy.png"), xy).unwrap();
            std::fs::write(format!("{dir}/{stem}-xt.png"), xt).unwrap();
        }
        println!("| {name} | {} | {with:.3} | {without:.3} | {:.3} |", mask.tile.describe(), s.ratio());
    }
}
