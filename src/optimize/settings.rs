//! What defines an optimization, whatever runs it: the settings, the state a run
//! can be saved in and resumed from, the slices per iteration, the starting
//! samples and the provenance written into a mask.

use crate::core::kernel::{Kernel, KernelSpec};
use crate::core::mask::Mask;
use crate::core::slice::DEFAULT_AXIS_SHARE;
use crate::core::step_rule::{Plateau, PlateauState, StepRule, FINAL_FRACTION};
use crate::core::tile::Tile;
use crate::error::{Error, Result};

/// Default number of times each sample is in a slice's class per iteration; sets
/// the default slices per iteration.
pub const DEFAULT_HITS: f64 = 16.0;
/// Iterations of a run by default (`Settings::new`), and the cap under a time
/// budget unless set higher.
pub const DEFAULT_ITERATIONS: u32 = 1000;

/// A cap on the iterations of a run that stops by a rule.
pub const DEFAULT_CAP: u32 = 10_000;

/// Iterations of the one-frame run an animated start makes (`Start::Animated`).
pub const SPATIAL_ITERATIONS: u32 = 200;

/// The share of a time budget the one-frame run of an animated start may take.
pub const SPATIAL_BUDGET_SHARE: f64 = 0.15;

/// The share of a time budget the quarter-tile run of a coarse start may take.
pub const COARSE_BUDGET_SHARE: f64 = 0.75;

/// The smallest quarter a coarse start makes, in pixels across and down: the
/// kernel's classes (a few pixels across) should fit inside one copy.
pub const COARSE_MIN_QUARTER: usize = 16;

/// What defines a run, whatever runs it. `Settings::new` and the setters:
///
/// ```
/// use fsot::{KernelSpec, Settings, Until};
/// let s = Settings::new(KernelSpec::named("taa")?, 7).iterations(200).until(Until::Iterations);
/// assert_eq!((s.iterations, s.seed), (200, 7));
/// # Ok::<(), fsot::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Settings {
    /// The kernel the error is filtered by.
    pub kernel: KernelSpec,
    /// The run's length (`Until::Iterations`) or its cap (the other rules).
    pub iterations: u32,
    /// Slices per iteration; `None`: enough for DEFAULT_HITS hits per sample.
    pub slices: Option<u32>,
    /// The seed every draw derives from.
    pub seed: u64,
    /// How displacements become moves.
    pub rule: StepRule,
    /// When the run ends.
    pub until: Until,
    /// Where the run starts when it is given no initial mask.
    pub start: Start,
    /// The share of slices along one coordinate, in [0, 1] (d >= 2; to within
    /// 2^-32): more spreads each coordinate read alone better, at the cost of
    /// the coordinates read together (`DEFAULT_AXIS_SHARE`). Under
    /// `Until::Objective` the target is judged on the run's own slices.
    pub axis_share: f64,
}

/// Where a run starts when it is given no initial mask.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Start {
    /// Independent uniform samples drawn from the seed.
    White,
    /// One frame optimized under the kernel's spatial filter alone
    /// (`SPATIAL_ITERATIONS`, and under a time budget at most
    /// `SPATIAL_BUDGET_SHARE` of it, its step following the clock or the
    /// iterations, whichever is further), then
    /// set in motion over the frames by a Kronecker sequence: each pixel's samples
    /// over time are a low-discrepancy sequence, each frame keeps the spatial
    /// structure. A tile of one frame starts white.
    Animated,
    /// Under a time budget only: a quarter of the tile (half its width and
    /// height, all its frames) made first by a run of the same settings in
    /// `COARSE_BUDGET_SHARE` of the budget (from its own `Auto` start), laid out
    /// 2x2 with each copy rotated in value (`animate::lay_out`), then the whole
    /// tile refined for the rest. A quarter takes a quarter of the time per
    /// iteration, so a budget too short for the whole tile to converge goes
    /// further; the copies keep the quarter's structure (rotated apart, not
    /// made anew), which the refinement barely changes. The tile's width and
    /// height must be even and at least 32 (an error otherwise).
    Coarse,
    /// `Animated` under a time budget (`Until::Seconds`), where the short run
    /// gains most from it, `White` otherwise: the default.
    Auto,
}

impl Start {
    /// Whether a run of these settings on `tile` starts animated.
    pub fn animates(self, until: Until, tile: &Tile) -> bool {
        let on = match self {
            Start::White | Start::Coarse => false,
            Start::Animated => true,
            Start::Auto => matches!(until, Until::Seconds(_)),
        };
        on && tile.frames > 1
    }
}

/// When a run ends.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Until {
    /// After exactly `iterations` iterations, with the cosine schedule over them.
    Iterations,
    /// When the plateau schedule says further iterations no longer pay.
    Plateau(Plateau),
    /// When a window's mean objective estimate is at most this (or the plateau
    /// schedule stops first).
    Objective(f64),
    /// When this many seconds of wall time have passed since the budget's
    /// origin (`RunOptions::budget_from`, else when `Run::start` began: setting
    /// up the backend included). The step scale follows the cosine
    /// schedule over the time left after set-up (from half the step when
    /// the run starts from a mask, as the animated start does), and no
    /// iteration starts that the pace so far says would end past the budget,
    /// so a run ends past it by at most about one iteration. The schedule's
    /// progress is the further of the clock's through the budget and the
    /// iterations' through `iterations`, so a run that its cap ends first
    /// still ends at the schedule's last step (within a step of a 32nd of
    /// the cap, where the GPU takes iterations in batches). The set-up
    /// counts but is not bounded: a budget shorter than the set-up (the
    /// start, the backend's pipelines and upload) ends past it by the set-up's
    /// time, with no iteration (`Run::set_up` says what it took). `iterations`
    /// caps it. How far it gets depends on the machine, so it is not
    /// reproducible bit for bit.
    Seconds(f64),
}

/// A time budget written as `1s`, `500ms`, `2m` or a number of seconds, in
/// seconds; the error ("must be ...") follows the name of what was read.
///
/// ```
/// use fsot::optimize::settings::parse_budget;
/// assert_eq!(parse_budget("500ms"), Ok(0.5));
/// assert_eq!(parse_budget("2m"), Ok(120.0));
/// assert!(parse_budget("-1s").is_err());
/// assert_eq!(parse_budget("86400"), Ok(86400.0));
/// assert!(parse_budget("86401").is_err() && parse_budget("1441m").is_err()); // past a day
/// assert!(parse_budget("1e-300s").is_err()); // less than a millisecond
/// ```
pub fn parse_budget(text: &str) -> std::result::Result<f64, String> {
    let t = text.trim();
    let (number, unit) = match () {
        _ if t.ends_with("ms") => (&t[..t.len() - 2], 1e-3),
        _ if t.ends_with('s') => (&t[..t.len() - 1], 1.0),
        _ if t.ends_with('m') => (&t[..t.len() - 1], 60.0),
        _ => (t, 1.0),
    };
    match number.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && BUDGET_SECONDS.contains(&(x * unit)) => Ok(x * unit),
        Ok(x) if x.is_finite() && x * unit > MAX_BUDGET_SECONDS => {
            Err(format!("must be at most {MAX_BUDGET_SECONDS} seconds (a day), got {text:?}"))
        }
        Ok(x) if x.is_finite() && x > 0.0 => {
            Err(format!("must be at least {MIN_BUDGET_SECONDS} s (a millisecond), got {text:?}"))
        }
        _ => Err(format!("must be a time above zero in ms, s or m, such as 1s, 500ms or 2m, got {text:?}")),
    }
}

/// The longest time budget a run takes: a day.
pub const MAX_BUDGET_SECONDS: f64 = 86_400.0;
/// The shortest: a millisecond (less makes no iteration).
pub const MIN_BUDGET_SECONDS: f64 = 1e-3;
/// The time budgets a run takes, in seconds.
pub const BUDGET_SECONDS: std::ops::RangeInclusive<f64> = MIN_BUDGET_SECONDS..=MAX_BUDGET_SECONDS;

impl Until {
    /// The end-agnostic schedule the rule runs, if any.
    pub fn plateau(&self) -> Option<Plateau> {
        match self {
            Until::Iterations | Until::Seconds(_) => None,
            Until::Plateau(p) => Some(*p),
            Until::Objective(_) => Some(Plateau::DEFAULT),
        }
    }
}

impl Settings {
    /// Settings for `kernel` and `seed`: DEFAULT_ITERATIONS iterations, the
    /// default slices and step rule, ending after exactly those iterations.
    pub fn new(kernel: KernelSpec, seed: u64) -> Self {
        Self {
            kernel,
            iterations: DEFAULT_ITERATIONS,
            slices: None,
            seed,
            rule: StepRule::DEFAULT,
            until: Until::Iterations,
            start: Start::Auto,
            axis_share: DEFAULT_AXIS_SHARE,
        }
    }

    /// The kernel the error is filtered by.
    pub fn kernel(mut self, kernel: KernelSpec) -> Self {
        self.kernel = kernel;
        self
    }

    /// The run's length, or its cap where it stops by a rule.
    pub fn iterations(mut self, iterations: u32) -> Self {
        self.iterations = iterations;
        self
    }

    /// Slices per iteration (None: enough for DEFAULT_HITS hits per sample).
    pub fn slices(mut self, slices: Option<u32>) -> Self {
        self.slices = slices;
        self
    }

    /// The seed every draw derives from.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// How displacements become moves.
    pub fn rule(mut self, rule: StepRule) -> Self {
        self.rule = rule;
        self
    }

    /// When the run ends.
    pub fn until(mut self, until: Until) -> Self {
        self.until = until;
        self
    }

    /// Where the run starts when it is given no initial mask.
    pub fn start(mut self, start: Start) -> Self {
        self.start = start;
        self
    }

    /// The share of slices along one coordinate (d >= 2), in [0, 1]: for a
    /// vector mask whose channels are also read one at a time.
    ///
    /// ```
    /// use fsot::{KernelSpec, Settings};
    /// let s = Settings::new(KernelSpec::named("taa")?, 7).axis_share(0.85);
    /// assert_eq!(s.axis_share, 0.85);
    /// # Ok::<(), fsot::Error>(())
    /// ```
    pub fn axis_share(mut self, share: f64) -> Self {
        self.axis_share = share;
        self
    }
}

/// Where a run stands after some iterations: enough to continue it exactly
/// (`checkpoint.rs` stores it). `second` is empty unless the rule is Adam;
/// `plateau` is the end-agnostic schedule's state, for runs that stop by a rule.
#[derive(Clone, Debug, PartialEq)]
pub struct RunState {
    pub iteration: u32,
    pub samples: Vec<f32>,
    pub first: Vec<f32>,
    pub second: Vec<f32>,
    pub plateau: Option<PlateauState>,
}

impl RunState {
    /// Checks the state against a run's tile, rule and length.
    pub fn check(&self, tile: &Tile, settings: &Settings) -> Result<()> {
        let n = tile.values();
        let adam = matches!(settings.rule, StepRule::Adam { .. });
        if self.samples.len() != n || self.first.len() != n || self.second.len() != if adam { n } else { 0 } {
            return Err(Error::invalid("the saved state does not match this run's tile or step rule"));
        }
        if self.plateau.is_some() != settings.until.plateau().is_some() {
            return Err(Error::invalid("the saved state does not match this run's stopping rule"));
        }
        if let (Some(state), Some(rule)) = (self.plateau, settings.until.plateau()) {
            if state.count >= rule.window.max(1) {
                return Err(Error::invalid("the saved state's plateau window does not fit this run's rule"));
            }
            // The step's scale starts at most at 1 and falls no lower than the
            // schedule's floor; the objectives summed and averaged are
            // non-negative (no window yet: NaN).
            let scale = (FINAL_FRACTION..=1.0).contains(&state.scale);
            let previous = state.previous.is_nan() || (state.previous.is_finite() && state.previous >= 0.0);
            if !(scale && previous && state.sum.is_finite() && state.sum >= 0.0) {
                return Err(Error::invalid(format!(
                    "the saved state's plateau schedule is not one a run reaches (scale {}, window mean {}, sum {})",
                    state.scale, state.previous, state.sum
                )));
            }
        }
        if self.iteration > settings.iterations {
            return Err(Error::invalid(format!(
                "the saved state is at iteration {} of a run of {}",
                self.iteration, settings.iterations
            )));
        }
        Ok(())
    }
}

/// The starting samples: `init` (checked against the tile; a one-frame mask of
/// the tile's size is animated over its frames, `animate`) or white noise drawn
/// from the seed.
pub fn initial_samples(tile: &Tile, settings: &Settings, init: Option<&Mask>) -> Result<Vec<f32>> {
    let Some(m) = init else { return Ok(Mask::white(*tile, settings.seed).samples) };
    m.check().map_err(|e| Error::invalid(format!("the initial mask: {e}")))?;
    // A mask of the tile, or one frame of it (set in motion over its frames).
    let one_frame = Tile { frames: 1, ..*tile };
    if m.tile != *tile && m.tile != one_frame {
        return Err(Error::invalid(format!(
            "the initial mask is {} but the run asks for {}{}",
            m.tile.describe(),
            tile.describe(),
            if tile.frames > 1 { " (or one frame of it)" } else { "" }
        )));
    }
    if m.tile.frames == tile.frames {
        return Ok(m.samples.clone());
    }
    Ok(crate::core::animate::animate(m, tile.frames)?.samples)
}

/// The most slices an iteration or a score draws: 2^24, thirty times the default
/// of a 128x128x64 scalar tile (each slice holds its direction and its classes'
/// sums while it is transported).
pub const MAX_SLICES: u32 = 1 << 24;

/// The most class memberships a sample may expect per iteration. Its
/// displacements (each at most sqrt(d) <= 2.83 along a coordinate) are summed in
/// fixed point of 2^-40, whose range is +-2^23: a million leaves room for the
/// busiest sample of a tile (the default is `DEFAULT_HITS`).
pub const MAX_HITS: f64 = 1e6;

/// Slices per iteration (the setting, or enough for DEFAULT_HITS class
/// memberships per sample) and the resulting expected hits per sample; an
/// error for slice settings no run can draw (no slices, an axis share outside
/// [0, 1], more than `MAX_HITS` hits per sample).
pub fn slices_and_hits(tile: &Tile, kernel: &Kernel, settings: &Settings) -> Result<(u32, f64)> {
    check_axis_share(settings.axis_share)?;
    let mean_points = kernel.mean_class_len() * tile.spp as f64;
    let slices = match settings.slices {
        Some(s) if !(1..=MAX_SLICES).contains(&s) => {
            return Err(Error::invalid(format!("slices per iteration must be 1 to {MAX_SLICES}, got {s}")))
        }
        Some(s) => s,
        None => ((DEFAULT_HITS * tile.points() as f64 / mean_points).ceil() as u32).clamp(16, MAX_SLICES),
    };
    let hits = slices as f64 * mean_points / tile.points() as f64;
    if hits > MAX_HITS {
        return Err(Error::invalid(format!(
            "{slices} slices per iteration put each sample in about {hits:.0} classes an iteration; at most \
             {MAX_HITS:.0} (the range of the displacement sums): give fewer slices"
        )));
    }
    Ok((slices, hits))
}

/// An error unless `share` is an axis share a run can draw by: in [0, 1].
pub fn check_axis_share(share: f64) -> Result<()> {
    if (0.0..=1.0).contains(&share) {
        Ok(())
    } else {
        Err(Error::invalid(format!("the axis share must be between 0 and 1, got {share:?}")))
    }
}

/// The axis share a run on `tile` records, where it matters: None for the
/// default, and for d = 1 (every slice lies along the one axis).
pub fn recorded_axis_share(tile: &Tile, s: &Settings) -> Option<String> {
    (s.axis_share != DEFAULT_AXIS_SHARE && tile.dims >= 2).then(|| s.axis_share.to_string())
}

/// A mask with the provenance of a run.
pub fn run_mask(tile: &Tile, s: &Settings, iterations: u32, slices: u32, samples: Vec<f32>) -> Mask {
    let mut meta = vec![
        ("method".to_string(), "fsot".to_string()),
        ("kernel".to_string(), s.kernel.describe()),
        ("seed".to_string(), s.seed.to_string()),
        ("iterations".to_string(), iterations.to_string()),
        ("slices".to_string(), slices.to_string()),
        ("step".to_string(), s.rule.to_string()),
        ("version".to_string(), env!("CARGO_PKG_VERSION").to_string()),
    ];
    if s.start.animates(s.until, tile) {
        meta.push(("start".to_string(), "animated".to_string()));
    } else if s.start == Start::Coarse {
        meta.push(("start".to_string(), "coarse".to_string()));
    }
    if let Some(share) = recorded_axis_share(tile, s) {
        meta.push(("axis_share".to_string(), share));
    }
    if let Until::Seconds(budget) = s.until {
        meta.push(("budget_seconds".to_string(), budget.to_string()));
    }
    meta.sort();
    Mask { tile: *tile, samples, meta }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::kernel::{Kernel, KernelSpec};

    #[test]
    fn slices_that_would_overrun_the_displacement_sums_are_refused() {
        // One pixel: every slice's class is the whole tile, so each sample is in
        // every slice; its sum could reach slices x 2.83, past 2^23 at 2^24.
        let tile = Tile::new(1, 1, 1, 64, 1).unwrap();
        let kernel = Kernel::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), &tile);
        let mut settings = Settings::new(kernel.spec, 0);
        settings.slices = Some(MAX_SLICES);
        let err = slices_and_hits(&tile, &kernel, &settings).unwrap_err();
        assert!(err.to_string().contains("give fewer slices"), "{err}");
        settings.slices = Some(1_000_000);
        let (_, hits) = slices_and_hits(&tile, &kernel, &settings).unwrap();
        assert_eq!(hits, 1e6);
        // The worst sum a million hits can make stays inside the fixed point's range.
        let worst = hits * 8f64.sqrt() * crate::optimize::cpu::FIXED_SCALE;
        assert!(worst < i64::MAX as f64 / 2.0, "{worst:e}");
    }

    #[test]
    fn the_default_slice_count_is_at_most_max_slices_however_large_the_tile_and_small_the_classes() {
        // 2^28 points under a point-like eye: 16 hits per point would be 2^32 slices.
        let tile = Tile::new(16384, 16384, 1, 1, 1).unwrap();
        let spec = KernelSpec::from_name("spatial", 0.01, None, 0.1, 60.0).unwrap();
        let kernel = Kernel::new(spec, &tile);
        let settings = Settings::new(spec, 0);
        let (slices, _) = slices_and_hits(&tile, &kernel, &settings).unwrap();
        assert_eq!(slices, MAX_SLICES);
        let small = Tile::new(1, 1, 1, 1, 1).unwrap();
        let (slices, _) = slices_and_hits(&small, &Kernel::new(spec, &small), &settings).unwrap();
        assert_eq!(slices, 16, "at least 16");
    }

    #[test]
    fn an_initial_mask_of_another_shape_is_named_as_it_was_given() {
        let settings = Settings::new(KernelSpec::named("taa").unwrap(), 0);
        let one = Mask::white(Tile::new(8, 8, 1, 1, 2).unwrap(), 1);
        for (w, t, d) in [(16, 4, 2), (8, 8, 1)] {
            let e = initial_samples(&Tile::new(w, 8, t, 1, d).unwrap(), &settings, Some(&one)).unwrap_err();
            let e = e.to_string();
            assert!(e.contains("the initial mask is 8x8x1, 1 spp, d = 2") && e.contains("or one frame of it"), "{e}");
        }
        let moving = initial_samples(&Tile::new(8, 8, 4, 1, 2).unwrap(), &settings, Some(&one)).unwrap();
        assert_eq!(moving.len(), 8 * 8 * 4 * 2);
        assert_eq!(initial_samples(&one.tile, &settings, Some(&one)).unwrap(), one.samples);
    }

    #[test]
    fn a_saved_plateau_window_past_the_rules_is_refused() {
        use crate::core::step_rule::{Plateau, PlateauState};
        let tile = Tile::new(2, 2, 1, 1, 1).unwrap();
        let mut settings = Settings::new(KernelSpec::named("taa").unwrap(), 0);
        settings.until = Until::Plateau(Plateau::DEFAULT);
        let saved = |count, scale| RunState {
            iteration: 0,
            samples: vec![0.5; 4],
            first: vec![0.0; 4],
            second: vec![],
            plateau: Some(PlateauState { count, scale, ..PlateauState::default() }),
        };
        assert!(saved(Plateau::DEFAULT.window - 1, 0.5).check(&tile, &settings).is_ok());
        assert!(saved(Plateau::DEFAULT.window, 0.5).check(&tile, &settings).is_err(), "a full window");
        assert!(saved(0, f32::NAN).check(&tile, &settings).is_err(), "a NaN step scale");
        for scale in [1.0, FINAL_FRACTION] {
            assert!(saved(0, scale).check(&tile, &settings).is_ok(), "{scale}");
        }
        for scale in [f32::MAX, 1.5, FINAL_FRACTION / 2.0, 0.0, -0.5] {
            let e = saved(0, scale).check(&tile, &settings).unwrap_err().to_string();
            assert!(e.contains("not one a run reaches"), "{scale}: {e}");
        }
        let with = |previous: f64, sum: f64| {
            let mut state = saved(3, 0.5);
            state.plateau = Some(PlateauState { previous, sum, ..state.plateau.unwrap() });
            state.check(&tile, &settings)
        };
        assert!(with(f64::NAN, 0.0).is_ok() && with(0.25, 0.5).is_ok());
        for (previous, sum) in [(f64::INFINITY, 0.0), (-1.0, 0.0), (0.25, f64::NAN), (0.25, -1.0), (0.25, f64::INFINITY)] {
            let e = with(previous, sum).unwrap_err().to_string();
            assert!(e.contains("not one a run reaches"), "{previous} {sum}: {e}");
        }
    }
}
