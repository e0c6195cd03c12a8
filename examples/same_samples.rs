//! Compares two mask files: bit-identical samples or not, and their metadata
//! side by side (whether a change to the code changed any mask).
//!
//! cargo run --release --example same_samples -- A.exr B.exr
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [a, b] = &args[..] else {
        eprintln!("usage: same_samples A.exr B.exr");
        return ExitCode::from(2);
    };
    let (a, b) = match (fsot::io::exr::read(a.as_ref()), fsot::io::exr::read(b.as_ref())) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let differing = a.samples.iter().zip(&b.samples).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
    let same = a.tile == b.tile && differing == 0;
    // Distance on the torus: 0.999 and 0.001 are 0.002 apart.
    let largest = a
        .samples
        .iter()
        .zip(&b.samples)
        .map(|(x, y)| {
            let d = (x - y).abs();
            d.min(1.0 - d)
        })
        .fold(0.0f32, f32::max);
    println!(
        "{}: {} of {} samples differ, by at most {largest:e} (on the torus)",
        if same { "bit-identical" } else { "DIFFERENT" },
        differing + a.samples.len().abs_diff(b.samples.len()),
        a.samples.len()
    );
    for (k, v) in &a.meta {
        if b.meta(k) != Some(v.as_str()) {
            println!("  meta {k}: {v:?} / {:?}", b.meta(k));
        }
    }
    if same {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
