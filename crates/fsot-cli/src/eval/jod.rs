//! The independent judge: ColorVideoVDP (Mantiuk et al., SIGGRAPH 2024, the
//! successor of the FovVideoVDP model the paper used), through the
//! `colorvideovdp` crate (a pure-Rust port of cvvdp 0.5.7, validated by its
//! authors against the PyTorch reference). It shares nothing with fsot's
//! kernels: its own contrast sensitivity, masking and temporal channels, on a
//! named display model.
//!
//! Tone mapping, radiance to display: each frame divided by the reference's
//! brightest pixel over the judged frames (the same scale for every method of a
//! scene), clamped to [0, 1] as a fraction of the display's peak luminance, and
//! encoded with the sRGB transfer function; the display model's EOTF, black
//! level and ambient light turn it into luminance. Frames before `start` (the
//! warm-up) are not shown to the judge.

use colorvideovdp::{Color, Cvvdp, DisplayModel, Execution, Image, Options};

use fsot::error::{Error, Result};

/// The display the evaluation judges on: ColorVideoVDP's own default, a 30-inch
/// 3840 x 2160 monitor of 200 cd/m^2 seen from 0.75 m (about 75 pixels per
/// degree); `examples/jod_probe.rs` shows how the masks separate on it and
/// on other displays.
pub const DISPLAY: &str = "standard_4k";

/// The version of the colorvideovdp crate (Cargo.lock pins it).
pub const CRATE_VERSION: &str = "0.1.1";

/// How grey frames reach the judge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Grey {
    /// One channel: ColorVideoVDP then feeds the same luminance to its
    /// achromatic and both colour-opponent channels (the reference
    /// implementation's path for single-channel input): the colour
    /// channels' sensitivity then weighs achromatic noise.
    Luminance,
    /// Three equal sRGB channels, as a display shows a grey image: the colour
    /// channels see (almost) no contrast, the achromatic ones all of it.
    #[default]
    Rgb,
}

impl Grey {
    pub fn name(&self) -> &'static str {
        match self {
            Grey::Luminance => "luminance",
            Grey::Rgb => "rgb",
        }
    }
}

/// ColorVideoVDP on a display model at a frame rate.
pub struct Judge {
    metric: Cvvdp,
    fps: f32,
    grey: Grey,
    pub display: String,
}

fn vdp_error(e: colorvideovdp::Error) -> Error {
    Error::invalid(format!("ColorVideoVDP: {e}"))
}

/// The frames from `start` as the judges see them: divided by the reference's
/// brightest judged pixel, clamped to [0, 1] and sRGB-encoded; the render's
/// then the reference's.
pub fn shown(render: &[Vec<f64>], reference: &[Vec<f64>], start: usize) -> [Vec<Vec<f32>>; 2] {
    let peak = reference[start..].iter().flatten().fold(1e-12f64, |a, &b| a.max(b));
    let encode = |seq: &[Vec<f64>]| {
        seq[start..].iter().map(|f| f.iter().map(|&v| srgb_encode(v / peak)).collect()).collect()
    };
    [encode(render), encode(reference)]
}

/// The sRGB encoding of a linear value in [0, 1].
fn srgb_encode(v: f64) -> f32 {
    let v = v.clamp(0.0, 1.0);
    let e = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    e as f32
}

impl Judge {
    pub fn new(display: &str, fps: f64, grey: Grey) -> Result<Self> {
        let model = DisplayModel::from_name(display).map_err(vdp_error)?;
        // Rows split over the rayon pool (results identical to one thread).
        let metric =
            Cvvdp::new(model, Options::default().with_execution(Execution::Parallel)).map_err(vdp_error)?;
        Ok(Self { metric, fps: fps as f32, grey, display: display.to_string() })
    }

    /// The JOD (10: no visible difference) of `render` against `reference`
    /// (n x n frames), over the frames from `start`.
    pub fn jod(&self, render: &[Vec<f64>], reference: &[Vec<f64>], start: usize, n: usize) -> Result<f64> {
        Ok(self.verdict(render, reference, start, n)?.jod)
    }

    /// The frame rate the judge watches at.
    pub fn fps(&self) -> f64 {
        self.fps as f64
    }

    /// The JOD of `render` against `reference` and what it pools: per channel and band.
    pub fn verdict(
        &self,
        render: &[Vec<f64>],
        reference: &[Vec<f64>],
        start: usize,
        n: usize,
    ) -> Result<Verdict> {
        if render.len() != reference.len() || start >= render.len() {
            return Err(Error::invalid(format!(
                "a judge of {} frames against {}, from frame {start}",
                render.len(),
                reference.len()
            )));
        }
        let [test, reference] = shown(render, reference, start);
        let frames = |seq: &[Vec<f32>]| -> Result<Vec<Image>> {
            seq.iter()
                .map(|f| {
                    let encoded = f.iter().copied();
                    match self.grey {
                        Grey::Luminance => Image::new(n, n, 1, encoded.collect()),
                        Grey::Rgb => Image::new(n, n, 3, encoded.flat_map(|e| [e, e, e]).collect()),
                    }
                    .map_err(vdp_error)
                })
                .collect()
        };
        let prediction = self
            .metric
            .predict_video(&frames(&test)?, &frames(&reference)?, self.fps, Color::Srgb)
            .map_err(vdp_error)?;
        let (channels, frames) = (prediction.channels, prediction.frames);
        let bands = prediction.band_frequencies.len();
        let q = &prediction.quality_per_channel;
        let pooled = (0..channels)
            .map(|c| {
                (0..bands)
                    .map(|b| {
                        let weight =
                            CHANNEL_WEIGHTS[c] * if b + 1 == bands { BASEBAND_WEIGHTS[c] } else { 1.0 };
                        let mean_square = (0..frames)
                            .map(|f| (q[(c * frames + f) * bands + b] as f64 * weight).powi(2))
                            .sum::<f64>()
                            / frames as f64;
                        mean_square.sqrt()
                    })
                    .collect()
            })
            .collect();
        Ok(Verdict {
            jod: prediction.jod as f64,
            bands: pooled,
            band_frequencies: prediction.band_frequencies.iter().map(|&f| f as f64).collect(),
        })
    }
}

/// ColorVideoVDP's weights per channel (sustained achromatic, red-green,
/// yellow-violet, transient achromatic) and of each channel's baseband, as
/// cvvdp 0.5.7's calibration (cvvdp_parameters.json) gives them.
const CHANNEL_WEIGHTS: [f64; 4] = [1.0, 1.0, 1.0, 0.808_113_455_772_399_9];
const BASEBAND_WEIGHTS: [f64; 4] =
    [0.003_633_448_621_258_139_6, 1.662_772_417_068_481_4, 4.118_745_326_995_85, 25.259_698_867_797_85];

/// A verdict: the JOD and the differences it pools.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    pub jod: f64,
    /// Per channel (sustained achromatic, red-green, yellow-violet, transient
    /// achromatic; grey frames leave the two colour channels near zero) and
    /// band (finest first, the baseband last): the root mean square over frames
    /// of the pooled difference times the weights the JOD pools it with. The
    /// JOD falls with the L4 norm of a frame's values over bands and channels.
    pub bands: Vec<Vec<f64>>,
    /// Band frequencies, cycles per degree (the baseband last).
    pub band_frequencies: Vec<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_sequences_score_ten_and_more_noise_scores_lower() {
        let judge = Judge::new(DISPLAY, 60.0, Grey::Luminance).unwrap();
        let n = 32;
        let mut stream = fsot::core::rng::Stream::new(3);
        let reference: Vec<Vec<f64>> = (0..12).map(|_| vec![0.5; n * n]).collect();
        let noisy = |amplitude: f64, stream: &mut fsot::core::rng::Stream| -> Vec<Vec<f64>> {
            reference
                .iter()
                .map(|f| f.iter().map(|v| v + amplitude * (stream.next_f64() - 0.5)).collect())
                .collect()
        };
        let same = judge.jod(&reference, &reference, 4, n).unwrap();
        assert!((same - 10.0).abs() < 1e-3, "{same}");
        let weak = judge.jod(&noisy(0.05, &mut stream), &reference, 4, n).unwrap();
        let strong = judge.jod(&noisy(0.4, &mut stream), &reference, 4, n).unwrap();
        assert!(strong < weak && weak < 10.0, "weak {weak}, strong {strong}");
    }
}
