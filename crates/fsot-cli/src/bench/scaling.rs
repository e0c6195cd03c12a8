//! How cost grows: time per iteration and peak memory of the CPU path against
//! tile size, dimension and samples per pixel. Each configuration runs in its own
//! process (`fsot bench scaling-one`), so its peak resident memory is its own.

use std::time::Instant;

use fsot::core::kernel::KernelSpec;
use fsot::core::tile::Tile;
use fsot::error::{Error, Result};
use fsot::optimize::backend::BackendChoice;
use fsot::optimize::run::{CancelFlag, Run, RunOptions};
use fsot::optimize::settings::Settings;

/// One configuration's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct Scale {
    pub tile: Tile,
    pub slices: u32,
    pub seconds_per_iteration: f64,
    pub peak_bytes: u64,
}

/// Runs `iterations` iterations of the default kernel on the CPU path and times
/// them (setup excluded).
pub fn measure(tile: Tile, iterations: u32) -> Result<(u32, f64)> {
    let mut settings = Settings::new(KernelSpec::from_name("perceptual-taa", 2.1, None, 0.1, 60.0)?, 1);
    settings.iterations = iterations.max(1);
    let options = RunOptions::default().backend(BackendChoice::Cpu);
    let mut run = Run::start(tile, settings, None, options)?;
    let start = Instant::now();
    run.run(&CancelFlag::new(), &mut |_| {})?;
    Ok((run.backend().slices_per_iteration(), start.elapsed().as_secs_f64() / settings.iterations as f64))
}

/// Peak resident memory of this process (VmHWM), where /proc has it.
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The line `scaling-one` prints, and its reading.
pub fn format_line(slices: u32, seconds: f64, peak: u64) -> String {
    format!("scaling-one slices={slices} seconds_per_iteration={seconds:e} peak_bytes={peak}")
}

pub fn parse_line(tile: Tile, text: &str) -> Result<Scale> {
    let line = text
        .lines()
        .find(|l| l.starts_with("scaling-one "))
        .ok_or_else(|| Error::invalid(format!("scaling-one printed no figures: {text}")))?;
    let field = |name: &str| -> Result<f64> {
        line.split_whitespace()
            .find_map(|kv| kv.strip_prefix(name).and_then(|v| v.strip_prefix('=')))
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| Error::invalid(format!("scaling-one: no {name} in `{line}`")))
    };
    Ok(Scale {
        tile,
        slices: field("slices")? as u32,
        seconds_per_iteration: field("seconds_per_iteration")?,
        peak_bytes: field("peak_bytes")? as u64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_child_line_reads_back() {
        let tile = Tile::new(8, 8, 2, 1, 2).unwrap();
        let s = parse_line(tile, &format!("noise\n{}\n", format_line(40, 1.5e-3, 123456))).unwrap();
        assert_eq!((s.slices, s.seconds_per_iteration, s.peak_bytes), (40, 1.5e-3, 123456));
        assert!(parse_line(tile, "nothing").is_err());
        assert!(peak_resident_bytes().unwrap() > 1 << 20);
        let (slices, seconds) = measure(tile, 2).unwrap();
        assert!(slices > 0 && seconds > 0.0);
    }
}
