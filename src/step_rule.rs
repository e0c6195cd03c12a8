//! The update step: how the mean displacement of each sample (the negative
//! gradient of the objective, in units of distance) moves it. Element-wise, so
//! every backend applies the same formula.

/// How displacements become moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepRule {
    /// Momentum on the mean displacement: m = beta m + (1 - beta) g; x += step m.
    Momentum { step: f32, beta: f32 },
    /// Adam with bias correction; `lr` is a distance per iteration.
    Adam { lr: f32, beta1: f32, beta2: f32, eps: f32 },
}

impl StepRule {
    /// The default rule (chosen by measurement, see BENCHMARKS.md).
    pub const DEFAULT: StepRule = StepRule::Momentum { step: 2.0, beta: 0.8 };
    pub const DEFAULT_ADAM: StepRule = StepRule::Adam { lr: 1e-2, beta1: 0.9, beta2: 0.99, eps: 1e-8 };
}

/// Step size over the run: cosine decay from 1 to `FINAL_FRACTION` of the rule's
/// step, so early iterations move far and late ones average out the noise of the
/// stochastic slices.
pub const FINAL_FRACTION: f32 = 0.05;

pub fn schedule(iteration: u32, iterations: u32) -> f32 {
    if iterations <= 1 {
        return 1.0;
    }
    let x = iteration as f32 / (iterations - 1) as f32;
    FINAL_FRACTION + (1.0 - FINAL_FRACTION) * 0.5 * (1.0 + (std::f32::consts::PI * x).cos())
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
    use super::*;

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
