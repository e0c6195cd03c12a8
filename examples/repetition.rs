//! How much of a mask's error pattern repeats across the tile: for the mask's
//! first coordinate u, the error each pixel keeps after TAA (an exponential
//! moving average of weight 0.1 over frames, run twice round the tile's frames
//! so that its start is forgotten), and in each frame alone, of two integrands,
//! the smooth u - 1/2 and the step [u < 0.3] - 0.3; then the correlation (Pearson, over every pixel and
//! every frame of the second round) between that error at pixel (x, y) and at
//! (x + LAG, y), and at (x, y + LAG), both wrapping. Each lag is the mean of the
//! two. Independent errors give about 0; a tile repeated every LAG pixels gives 1.
//!
//! cargo run --release --example repetition -- MASK.exr [LAG ...]
//! (lags default to a quarter and a half of the tile's width)
use std::process::ExitCode;

/// An integrand of u, by name.
type Integrand = (&'static str, fn(f64) -> f64);

/// TAA's blend weight, and 1: each frame alone.
const ALPHAS: [(f64, &str); 2] = [(0.1, "TAA"), (1.0, "one frame")];

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!("usage: repetition MASK.exr [LAG ...]");
        return ExitCode::from(2);
    };
    let mask = match fsot::io::exr::read(path.as_ref()) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let t = mask.tile;
    let lags: Vec<usize> = match args[1..].iter().map(|a| a.parse()).collect::<Result<Vec<usize>, _>>() {
        Ok(l) if !l.is_empty() => l,
        Ok(_) => vec![t.width / 4, t.width / 2],
        Err(e) => {
            eprintln!("error: a lag must be a whole number of pixels: {e}");
            return ExitCode::from(2);
        }
    };
    let integrands: [Integrand; 2] =
        [("u - 1/2", |u| u - 0.5), ("[u < 0.3] - 0.3", |u| (u < 0.3) as u8 as f64 - 0.3)];
    println!("{path}: {}", t.describe());
    for ((alpha, reading), (name, f)) in ALPHAS.iter().flat_map(|a| integrands.iter().map(move |i| (*a, *i)))
    {
        // TAA's history per pixel, run twice round the frames; the second round's
        // frames are kept.
        let pixels = t.width * t.height;
        let mut history = vec![0.0f64; pixels];
        let mut kept = Vec::with_capacity(t.frames);
        for round in 0..2 {
            for frame in 0..t.frames {
                for (p, h) in history.iter_mut().enumerate() {
                    let u = mask.sample(p % t.width, p / t.width, frame, 0)[0] as f64;
                    *h = (1.0 - alpha) * *h + alpha * f(u);
                }
                if round == 1 {
                    kept.push(history.clone());
                }
            }
        }
        let line: Vec<String> = lags
            .iter()
            .map(|&lag| {
                let across = correlation(&kept, |x, y| ((x + lag) % t.width, y), t.width, t.height);
                let down = correlation(&kept, |x, y| (x, (y + lag) % t.height), t.width, t.height);
                format!("lag {lag}: {:.3}", (across + down) / 2.0)
            })
            .collect();
        println!("  {reading}, {name}: {}", line.join(", "));
    }
    ExitCode::SUCCESS
}

/// Pearson's correlation between every frame's error at (x, y) and at
/// `to(x, y)`.
fn correlation(frames: &[Vec<f64>], to: impl Fn(usize, usize) -> (usize, usize), w: usize, h: usize) -> f64 {
    let (mut sa, mut sb, mut saa, mut sbb, mut sab, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for e in frames {
        for y in 0..h {
            for x in 0..w {
                let (x2, y2) = to(x, y);
                let (a, b) = (e[y * w + x], e[y2 * w + x2]);
                sa += a;
                sb += b;
                saa += a * a;
                sbb += b * b;
                sab += a * b;
                n += 1.0;
            }
        }
    }
    let cov = sab / n - (sa / n) * (sb / n);
    let var = (saa / n - (sa / n).powi(2)) * (sbb / n - (sb / n).powi(2));
    cov / var.sqrt()
}
