//! Judges that differ from the optimizer. fsot's masks for the sigma 2.1 column
//! are made for an eye of sigma 2.1 watching TAA with alpha 0.1 at 60 fps; here
//! every method's masks of that column (the same seeds and renders as the main
//! tables) are judged, under TAA, by eyes and displays they were not made for:
//! sigma 1.5 and 2.8, TAA alpha 0.05 and 0.2 (the render and the reference both
//! resolved with it), 30 and 120 fps (the eye's temporal response at that rate),
//! the spatial Gaussian alone (no temporal response), FovVideoVDP's sustained
//! and transient channels kept apart instead of added into one filter, and the
//! plain RelMSE (no filter at all).
//!
//! A cell is the mean over the scenes of a method's pRelMSE (or RelMSE) as a
//! ratio to white noise's in the same scene and judge, per seed, then the mean
//! over seeds with its 95% interval.

use std::path::Path;

use serde::Serialize;

use crate::eval::render::{references, render, taa, MaskSampler};
use crate::eval::scenes::Scene;
use crate::eval::stats::Interval;
use crate::eval::suite::{method_mask, planned_masks, EvalSize, METHODS};
use fsot::core::mask::Mask;
use fsot::error::Result;
use fsot::quality::eye::Eye;
use fsot::quality::metric::{channels_apart, channels_seen, relative_errors};

/// The column the masks are made for.
pub const MADE_FOR_SIGMA: f64 = 2.1;

/// What a judge filters with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    /// The evaluation's eye: spatial Gaussian and temporal response.
    Perceptual,
    /// The spatial Gaussian alone.
    Spatial,
    /// No filter: RelMSE.
    Plain,
    /// FovVideoVDP's sustained and transient channels kept apart
    /// (`metric::channels_apart`).
    Channels,
}

/// One judge: its eye sigma, TAA alpha, frame rate and filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Judge {
    pub name: &'static str,
    pub sigma: f64,
    pub alpha: f64,
    pub fps: f64,
    pub filter: Filter,
}

const fn judge(name: &'static str, sigma: f64, alpha: f64, fps: f64, filter: Filter) -> Judge {
    Judge { name, sigma, alpha, fps, filter }
}

/// The optimizer's own judge first, then the others.
pub const JUDGES: [Judge; 10] = [
    judge("made for (2.1, 0.1, 60 fps)", 2.1, 0.1, 60.0, Filter::Perceptual),
    judge("sigma 1.5", 1.5, 0.1, 60.0, Filter::Perceptual),
    judge("sigma 2.8", 2.8, 0.1, 60.0, Filter::Perceptual),
    judge("alpha 0.05", 2.1, 0.05, 60.0, Filter::Perceptual),
    judge("alpha 0.2", 2.1, 0.2, 60.0, Filter::Perceptual),
    judge("30 fps", 2.1, 0.1, 30.0, Filter::Perceptual),
    judge("120 fps", 2.1, 0.1, 120.0, Filter::Perceptual),
    judge("spatial only", 2.1, 0.1, 60.0, Filter::Spatial),
    judge("channels apart", 2.1, 0.1, 60.0, Filter::Channels),
    judge("RelMSE", 2.1, 0.1, 60.0, Filter::Plain),
];

/// One method under one judge: the interval of its mean ratio to white noise.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobustRecord {
    pub method: String,
    pub judge: String,
    pub ratio: f64,
    pub ratio_ci95: f64,
    pub seeds: u32,
    pub scenes: usize,
}

impl Judge {
    fn eye(&self) -> Eye {
        match self.filter {
            Filter::Spatial => Eye::spatial_only(self.sigma),
            _ => Eye::new(self.sigma, self.fps),
        }
    }
}

/// Every method's masks of the sigma 2.1 column (and `fsot-planned`'s TAA plan
/// where the size plans) judged by `JUDGES` over `scenes`.
pub fn run_robustness(
    size: &EvalSize,
    scenes: &[Scene],
    cache: &Path,
    mut log: impl FnMut(&str),
) -> Result<Vec<RobustRecord>> {
    let n = size.shot.image;
    let eyes: Vec<Eye> = JUDGES.iter().map(Judge::eye).collect();
    let channels = Eye::channels(MADE_FOR_SIGMA, 60.0);
    // One first judged frame for every judge: the longest history.
    let start = eyes.iter().map(Eye::history).fold(size.warmup, usize::max);
    let mut methods: Vec<&str> = METHODS.to_vec();
    if size.planned {
        methods.push("fsot-planned");
    }
    let seeds = size.seeds as usize;
    // fsot-planned as planned for the run's first display.
    let first = size.displays.first().ok_or_else(|| fsot::error::Error::invalid("no display to judge on"))?;
    let viewing = fsot::core::kernel::Spatial::Display { ppd: fsot::core::display::preset_ppd(first)? };
    // Each method's masks, read once (none for fsot-planned: its masks are per scene).
    let masks: Vec<Vec<Mask>> = methods
        .iter()
        .map(|&method| match method {
            "fsot-planned" => Ok(Vec::new()),
            _ => (1..=seeds as u64)
                .map(|seed| method_mask(method, MADE_FOR_SIGMA, size, cache, seed))
                .collect(),
        })
        .collect::<Result<_>>()?;
    // values[method][judge][seed]: per scene, summed as ratios to white below.
    let mut sums = vec![vec![vec![0.0f64; seeds]; JUDGES.len()]; methods.len()];
    for &scene in scenes {
        let refs = references(scene, size.shot, size.reference_samples, Some(cache))?;
        let resolved: Vec<Vec<Vec<f64>>> = JUDGES.iter().map(|j| taa(&refs, j.alpha)).collect();
        let seen: Vec<Vec<Vec<f64>>> = JUDGES
            .iter()
            .zip(&eyes)
            .zip(&resolved)
            .map(|((j, eye), r)| match j.filter {
                Filter::Channels => channels_seen(r, &channels, start, n),
                _ => (start..r.len()).map(|f| eye.filter(r, f, n)).collect(),
            })
            .collect();
        // The main tables' masks for this scene (seed k reads mask k mod
        // `planned_masks`, made from seed 1 + that), made or read once.
        let planned: Vec<_> = match size.planned {
            true => (1..=u64::from(size.planned_masks.max(1)))
                .map(|s| planned_masks(scene, viewing, true, true, size, cache, s))
                .collect::<Result<_>>()?,
            false => Vec::new(),
        };
        // absolute[method][judge][seed]
        let mut absolute = vec![vec![vec![0.0f64; seeds]; JUDGES.len()]; methods.len()];
        for (m, method_masks) in masks.iter().enumerate() {
            #[allow(clippy::needless_range_loop)] // seed indexes two levels down
            for seed in 0..seeds {
                let renders = size.renders.max(1);
                for r in 0..renders {
                    let placement = 100 + 1000 * seed as u64 + r as u64;
                    let image = match method_masks.get(seed) {
                        Some(mask) => {
                            render(scene, size.shot, &MaskSampler::new(mask, scene.dims(), placement))
                        }
                        None => {
                            let reads = planned[seed % planned.len()].reads();
                            render(scene, size.shot, &MaskSampler::planned(&reads, placement))
                        }
                    };
                    // TAA once per alpha the judges use.
                    let mut resolved_image: Vec<(f64, Vec<Vec<f64>>)> = Vec::new();
                    for (k, j) in JUDGES.iter().enumerate() {
                        let at = match resolved_image.iter().position(|(a, _)| *a == j.alpha) {
                            Some(at) => at,
                            None => {
                                resolved_image.push((j.alpha, taa(&image, j.alpha)));
                                resolved_image.len() - 1
                            }
                        };
                        let frames = &resolved_image[at].1;
                        let value = match j.filter {
                            Filter::Channels => {
                                channels_apart(frames, &resolved[k], &seen[k], &channels, start, n)
                            }
                            Filter::Plain => {
                                relative_errors(frames, &resolved[k], &seen[k], &eyes[k], start, n).1
                            }
                            _ => relative_errors(frames, &resolved[k], &seen[k], &eyes[k], start, n).0,
                        };
                        absolute[m][k][seed] += value / renders as f64;
                    }
                }
            }
        }
        let white = methods.iter().position(|m| *m == "white").unwrap_or(0);
        for m in 0..methods.len() {
            for k in 0..JUDGES.len() {
                let white_mean = absolute[white][k].iter().sum::<f64>() / seeds as f64;
                for seed in 0..seeds {
                    sums[m][k][seed] += absolute[m][k][seed] / white_mean / scenes.len() as f64;
                }
            }
        }
        log(&format!("robustness: {} judged by {} judges", scene.name(), JUDGES.len()));
    }
    let mut out = Vec::new();
    for (m, method) in methods.iter().enumerate() {
        for (k, j) in JUDGES.iter().enumerate() {
            let i = Interval::of(&sums[m][k]);
            out.push(RobustRecord {
                method: method.to_string(),
                judge: j.name.to_string(),
                ratio: i.mean,
                ratio_ci95: i.ci95,
                seeds: size.seeds,
                scenes: scenes.len(),
            });
        }
    }
    Ok(out)
}

/// The robustness table: a row per method, a column per judge; the lowest of a
/// column bold where its interval clears the runner-up's.
pub fn to_markdown(records: &[RobustRecord]) -> String {
    let mut methods: Vec<&str> = Vec::new();
    for r in records {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    let scenes = records.first().map(|r| r.scenes).unwrap_or(0);
    let mut out = format!(
        "\n### Judges that differ from the optimizer (with TAA; masks made for sigma 2.1, alpha 0.1, 60 fps; \
         mean over {scenes} scenes of the ratio to white noise, +- the 95% interval over seeds)\n\n| method | {} |\n| --- |{}\n",
        JUDGES.iter().map(|j| j.name).collect::<Vec<_>>().join(" | "),
        " ---: |".repeat(JUDGES.len())
    );
    let get = |m: &str, j: &str| records.iter().find(|r| r.method == m && r.judge == j);
    let winners: Vec<Option<&str>> = JUDGES
        .iter()
        .map(|j| {
            let mut ranked: Vec<(&str, Interval)> = methods
                .iter()
                .filter(|m| **m != "white")
                .filter_map(|m| get(m, j.name).map(|r| (*m, Interval { mean: r.ratio, ci95: r.ratio_ci95 })))
                .collect();
            ranked.sort_by(|a, b| a.1.mean.total_cmp(&b.1.mean));
            match ranked.as_slice() {
                [best, next, ..] if !best.1.overlaps(&next.1) => Some(best.0),
                _ => None,
            }
        })
        .collect();
    for m in &methods {
        let cells: Vec<String> = JUDGES
            .iter()
            .zip(&winners)
            .map(|(j, w)| match get(m, j.name) {
                Some(r) if *w == Some(*m) => format!("**{:.3} +- {:.3}**", r.ratio, r.ratio_ci95),
                Some(r) => format!("{:.3} +- {:.3}", r.ratio, r.ratio_ci95),
                None => "-".into(),
            })
            .collect();
        out += &format!("| {m} | {} |\n", cells.join(" | "));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::suite::TAA_ALPHA;

    #[test]
    fn the_first_judge_is_the_one_the_masks_are_made_for_and_each_other_changes_one_thing() {
        assert_eq!((JUDGES[0].sigma, JUDGES[0].alpha, JUDGES[0].fps), (MADE_FOR_SIGMA, TAA_ALPHA, 60.0));
        assert_eq!(JUDGES[0].filter, Filter::Perceptual);
        for j in &JUDGES[1..] {
            let changed = [
                j.sigma != JUDGES[0].sigma,
                j.alpha != JUDGES[0].alpha,
                j.fps != JUDGES[0].fps,
                j.filter != JUDGES[0].filter,
            ];
            assert_eq!(changed.iter().filter(|c| **c).count(), 1, "{}", j.name);
        }
    }
}
