//! The independent perceived-error test on mask files: renders the animated
//! integrands with each mask, with and without TAA, and prints the error as a ratio
//! to white noise of the same shape.
//!
//! cargo run --release --example perceived -- MASK.exr [MASK.exr ...]
use fsot::quality::perceived::{ratio_to_white, TestSetup};

fn main() {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    if paths.is_empty() {
        eprintln!("usage: perceived MASK.exr [MASK.exr ...]");
        std::process::exit(2);
    }
    println!("mask,tile,taa_ratio,no_taa_ratio");
    for path in paths {
        let mask = match fsot::io::exr::read(path.as_ref()) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("error: {e}");
                std::process::exit(1);
            }
        };
        let taa = ratio_to_white(&mask, &TestSetup::default(), 4);
        let plain = ratio_to_white(&mask, &TestSetup { taa_alpha: None, ..TestSetup::default() }, 4);
        println!("{path},{},{taa:.4},{plain:.4}", mask.tile.describe());
    }
}
