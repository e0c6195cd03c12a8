//! The update step: how the mean displacement of each sample (the negative
//! gradient of the objective, in units of distance) moves it. Element-wise, so
//! every backend applies the same formula.

/// How displacements become moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepRule {
    /// Momentum on the mean displacement: m = beta m + (1 - beta) g; x += step m.
    Momentum {
        /// Distance moved per unit of momentum at full scale (the factor on m).
        step: f32,
        /// Weight of the previous momentum in each update.
        beta: f32,
    },
    /// Adam with bias correction; `lr` is a distance per iteration.
    Adam {
        /// Distance moved per iteration at full scale.
        lr: f32,
        /// Decay of the running mean of the displacement (first moment).
        beta1: f32,
        /// Decay of the running mean of its square (second moment).
        beta2: f32,
        /// Added to the second moment's square root, keeping the step finite.
        eps: f32,
    },
}

impl StepRule {
    /// The default rule (chosen by measurement, see BENCHMARKS.md).
    pub const DEFAULT: StepRule = StepRule::Momentum { step: 2.0, beta: 0.8 };
    /// Adam with lr 0.01, beta1 0.9, beta2 0.99 and eps 1e-8.
    pub const DEFAULT_ADAM: StepRule = StepRule::Adam { lr: 1e-2, beta1: 0.9, beta2: 0.99, eps: 1e-8 };

    /// The largest step (`Momentum::step`, `Adam::lr`): past it a move wraps
    /// round the unit interval many times over, and a 32-bit sample loses
    /// every digit (a step of 1e30 left every value 0).
    pub const MAX_STEP: f32 = 1000.0;

    /// An error unless every step is above 0 and at most `MAX_STEP` and every
    /// decay in [0, 1): a rule outside them moves samples to NaN or to nothing.
    pub fn check(&self) -> crate::error::Result<()> {
        let positive = |x: f32| x.is_finite() && x > 0.0;
        let step = |x: f32| positive(x) && x <= Self::MAX_STEP;
        let decay = |x: f32| (0.0..1.0).contains(&x);
        let ok = match *self {
            StepRule::Momentum { step: s, beta } => step(s) && decay(beta),
            StepRule::Adam { lr, beta1, beta2, eps } => step(lr) && decay(beta1) && decay(beta2) && positive(eps),
        };
        if ok {
            Ok(())
        } else {
            Err(crate::error::Error::invalid(format!(
                "step rule {self} out of range (steps above 0 and at most {}, decays in [0, 1))",
                Self::MAX_STEP
            )))
        }
    }
}

/// As files record it: `momentum (step 2, beta 0.8)`,
/// `adam (lr 0.01, beta1 0.9, beta2 0.99, eps 0.00000001)`.
impl std::fmt::Display for StepRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            StepRule::Momentum { step, beta } => write!(f, "momentum (step {step}, beta {beta})"),
            StepRule::Adam { lr, beta1, beta2, eps } => {
                write!(f, "adam (lr {lr}, beta1 {beta1}, beta2 {beta2}, eps {eps})")
            }
        }
    }
}

/// Step size over the run: cosine decay from 1 to `FINAL_FRACTION` of the rule's
/// step, so early iterations move far and late ones average out the noise of the
/// stochastic slices.
pub const FINAL_FRACTION: f32 = 0.05;

pub fn schedule(iteration: u32, iterations: u32) -> f32 {
    if iterations <= 1 {
        return 1.0;
    }
    schedule_between(1.0, progress(iteration, iterations))
}

/// How far through a run of `iterations` the schedule is at `iteration`: 0 at
/// the first, 1 at the last (0 throughout a run of one).
pub fn progress(iteration: u32, iterations: u32) -> f32 {
    if iterations <= 1 {
        return 0.0;
    }
    iteration as f32 / (iterations - 1) as f32
}

/// The step scale a run under a time budget starts at when it starts from a
/// mask (the animated start, or a mask given): that start is already well
/// spread, and full steps would first undo its order before refining it.
pub const FROM_MASK_START: f32 = 0.5;

/// The cosine schedule from `start` at `progress` 0 to `FINAL_FRACTION` at 1
/// (progress clamped to [0, 1]). A run under a time budget takes its progress
/// from the clock, or from its iterations (`progress`) where they are further.
pub fn schedule_between(start: f32, progress: f32) -> f32 {
    let x = progress.clamp(0.0, 1.0);
    FINAL_FRACTION + (start - FINAL_FRACTION) * 0.5 * (1.0 + (std::f32::consts::PI * x).cos())
}

/// An end-agnostic schedule, for runs that stop when iterations no longer pay:
/// the step scale starts at 1 and halves (down to `FINAL_FRACTION`) whenever a
/// window's mean objective estimate gains less than `decay_below` (relative) on
/// the previous window's; at the smallest scale, a window that gains less than
/// `stop_below` ends the run. Nothing in it depends on the run's length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plateau {
    /// Iterations per window (the Vulkan backend's batch, so that both backends
    /// decide at the same iterations).
    pub window: u32,
    /// Relative gain on the previous window below which the step is multiplied
    /// by `factor`.
    pub decay_below: f64,
    /// Relative gain on the previous window below which a run at the smallest
    /// step scale ends.
    pub stop_below: f64,
    /// What the step is multiplied by when a window does not pay.
    pub factor: f32,
}

impl Plateau {
    /// The default rule (chosen by measurement, see BENCHMARKS.md).
    pub const DEFAULT: Plateau = Plateau { window: 32, decay_below: 0.01, stop_below: 0.002, factor: 0.5 };

    /// The longest window: 2^16 iterations.
    pub const MAX_WINDOW: u32 = 1 << 16;

    /// An error unless the window is 1 to `MAX_WINDOW` iterations, both gains
    /// are in [0, 1] and the factor is in (0, 1): for a rule set by hand.
    /// `Run::start` checks its rule.
    pub fn check(&self) -> crate::error::Result<()> {
        let gains = [self.decay_below, self.stop_below];
        let ok = (1..=Self::MAX_WINDOW).contains(&self.window)
            && gains.iter().all(|g| (0.0..=1.0).contains(g))
            && self.factor > 0.0
            && self.factor < 1.0;
        match ok {
            true => Ok(()),
            false => Err(crate::error::Error::invalid(format!(
                "a plateau rule needs a window of 1 to {} iterations, gains in [0, 1] and a factor in (0, 1), got {self:?}",
                Self::MAX_WINDOW
            ))),
        }
    }
}

/// Where a plateau schedule stands: enough to resume it exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlateauState {
    pub scale: f32,
    /// The last complete window's mean objective (NaN before the first).
    pub previous: f64,
    /// The current window's objectives so far.
    pub sum: f64,
    pub count: u32,
}

impl Default for PlateauState {
    fn default() -> Self {
        Self { scale: 1.0, previous: f64::NAN, sum: 0.0, count: 0 }
    }
}

impl PlateauState {
    /// Takes one iteration's objective estimate; true when the run should stop
    /// (at a window's end).
    pub fn observe(&mut self, rule: &Plateau, objective: f64) -> bool {
        self.sum += objective;
        self.count += 1;
        if self.count < rule.window.max(1) {
            return false;
        }
        let mean = self.sum / self.count as f64;
        let gain = (self.previous - mean) / self.previous; // NaN for the first window
        (self.previous, self.sum, self.count) = (mean, 0.0, 0);
        let at_floor = self.scale <= FINAL_FRACTION;
        if at_floor {
            return gain < rule.stop_below;
        }
        if gain < rule.decay_below {
            self.scale = (self.scale * rule.factor).max(FINAL_FRACTION);
        }
        false
    }
}

/// Per-coordinate optimizer state.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimizerState {
    pub rule: StepRule,
    pub first: Vec<f32>,
    pub second: Vec<f32>,
    /// Number of steps taken.
    pub steps: u32,
}

impl OptimizerState {
    pub fn new(rule: StepRule, values: usize) -> Self {
        let second = match rule {
            StepRule::Adam { .. } => vec![0.0; values],
            StepRule::Momentum { .. } => Vec::new(),
        };
        Self { rule, first: vec![0.0; values], second, steps: 0 }
    }
}

/// Wraps a coordinate into [0, 1) (also for values that round to 1.0 in f32).
#[inline]
pub fn wrap01(x: f32) -> f32 {
    let y = x - x.floor();
    if y >= 1.0 {
        0.0
    } else {
        y
    }
}

/// Moves one coordinate. `g` is its mean displacement, `scale` the schedule
/// factor, `t` the 1-based step number; `first`/`second` its state.
#[inline]
pub fn step_value(
    rule: StepRule,
    x: f32,
    g: f32,
    scale: f32,
    t: u32,
    first: &mut f32,
    second: Option<&mut f32>,
) -> f32 {
    match rule {
        StepRule::Momentum { step, beta } => {
            *first = beta * *first + (1.0 - beta) * g;
            wrap01(x + step * scale * *first)
        }
        StepRule::Adam { lr, beta1, beta2, eps } => {
            let v = second.expect("Adam keeps a second moment"); // ok: OptimizerState::new allocates it for Adam
            *first = beta1 * *first + (1.0 - beta1) * g;
            *v = beta2 * *v + (1.0 - beta2) * g * g;
            let mh = *first / (1.0 - beta1.powi(t as i32));
            let vh = *v / (1.0 - beta2.powi(t as i32));
            wrap01(x + lr * scale * mh / (vh.sqrt() + eps))
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_step_past_the_largest_is_refused() {
        for rule in [StepRule::Momentum { step: 1e30, beta: 0.0 }, StepRule::Adam { lr: 1e4, beta1: 0.9, beta2: 0.99, eps: 1e-8 }] {
            assert!(rule.check().unwrap_err().to_string().contains("at most 1000"), "{rule:?}");
        }
        assert!(StepRule::Momentum { step: StepRule::MAX_STEP, beta: 0.0 }.check().is_ok());
    }

    use super::*;

    #[test]
    fn a_rule_reads_in_a_file_as_words_and_numbers() {
        assert_eq!(StepRule::DEFAULT.to_string(), "momentum (step 2, beta 0.8)");
        assert_eq!(StepRule::DEFAULT_ADAM.to_string(), "adam (lr 0.01, beta1 0.9, beta2 0.99, eps 0.00000001)");
    }

    #[test]
    fn adam_and_momentum_steps_follow_their_closed_forms_under_a_constant_gradient() {
        // Adam's bias correction makes every step under a constant gradient g
        // lr scale g / (|g| + eps); momentum's k-th moves step scale (1 - beta^k) g.
        let (g, scale, t_max) = (-0.02f32, 0.7f32, 5u32);
        let adam = StepRule::Adam { lr: 0.01, beta1: 0.9, beta2: 0.99, eps: 1e-8 };
        let (mut x, mut m, mut v) = (0.5f32, 0.0f32, 0.0f32);
        for t in 1..=t_max {
            let expected = 0.01f64 * 0.7 * (-0.02) / (0.02 + 1e-8);
            let next = step_value(adam, x, g, scale, t, &mut m, Some(&mut v));
            assert!(((next - x) as f64 - expected).abs() < 1e-7, "t = {t}: moved {} not {expected}", next - x);
            x = next;
        }
        let momentum = StepRule::Momentum { step: 2.0, beta: 0.8 };
        let (mut x, mut m) = (0.5f32, 0.0f32);
        for k in 1..=t_max {
            let expected = 2.0f64 * 0.7 * (1.0 - 0.8f64.powi(k as i32)) * -0.02;
            let next = step_value(momentum, x, g, scale, k, &mut m, None);
            assert!(((next - x) as f64 - expected).abs() < 1e-7, "k = {k}: moved {} not {expected}", next - x);
            x = next;
        }
    }

    #[test]
    fn wrapping_stays_in_the_half_open_unit_interval() {
        assert_eq!(wrap01(1.0), 0.0);
        assert_eq!(wrap01(-0.25), 0.75);
        assert!(wrap01(-1e-9) < 1.0);
        assert_eq!(wrap01(2.5), 0.5);
    }

    #[test]
    fn schedule_decays_from_one_to_the_final_fraction() {
        assert_eq!(schedule(0, 100), 1.0);
        assert!((schedule(99, 100) - FINAL_FRACTION).abs() < 1e-6);
        assert!(schedule(30, 100) > schedule(60, 100));
    }

    #[test]
    fn a_schedule_from_a_lower_start_decays_by_the_same_cosine_to_the_same_floor() {
        // Closed form in f64: FINAL + (start - FINAL) (1 + cos(pi x)) / 2.
        for start in [1.0f32, FROM_MASK_START, 0.2] {
            for i in 0..=20 {
                let x = i as f64 / 20.0;
                let f = FINAL_FRACTION as f64;
                let want = f + (start as f64 - f) * 0.5 * (1.0 + (std::f64::consts::PI * x).cos());
                assert!((schedule_between(start, x as f32) as f64 - want).abs() < 1e-6, "{start} at {x}");
            }
            assert_eq!(schedule_between(start, -1.0), start);
            assert!((schedule_between(start, 2.0) - FINAL_FRACTION).abs() < 1e-7);
        }
    }

    #[test]
    fn a_plateau_halves_the_step_until_the_floor_then_stops() {
        let rule = Plateau { window: 4, decay_below: 0.01, stop_below: 0.002, factor: 0.5 };
        let mut s = PlateauState::default();
        // Falling 10% a window: the step stays; the first window only sets the mark.
        for w in 0..3 {
            for _ in 0..4 {
                assert!(!s.observe(&rule, 0.9f64.powi(w)));
            }
            assert_eq!(s.scale, 1.0);
        }
        // A drop to 0.5 still pays; then flat: halves every window down to the
        // floor, then stops at the next flat window.
        let stops: Vec<bool> = (0..4).map(|_| s.observe(&rule, 0.5)).collect();
        assert!(!stops.contains(&true));
        assert_eq!(s.scale, 1.0);
        let mut halvings = 0;
        loop {
            let before = s.scale;
            let stop = (0..4).map(|_| s.observe(&rule, 0.5)).last().unwrap();
            if stop {
                break;
            }
            assert!(s.scale < before || s.scale == FINAL_FRACTION);
            halvings += 1;
            assert!(halvings < 10, "never stopped");
        }
        assert_eq!(s.scale, FINAL_FRACTION);
        assert_eq!(halvings, 5, "1 -> 0.5 -> 0.25 -> 0.125 -> 0.0625 -> 0.05");
    }

    #[test]
    fn momentum_converges_to_a_fixed_displacement() {
        let rule = StepRule::Momentum { step: 1.0, beta: 0.5 };
        let (mut x, mut m) = (0.2f32, 0.0f32);
        // A constant pull of 0.1 towards 0.3 each step, recomputed from x.
        for t in 1..100 {
            let g = 0.5 * (0.3 - x);
            x = step_value(rule, x, g, 1.0, t, &mut m, None);
        }
        assert!((x - 0.3).abs() < 1e-4, "{x}");
    }
}
