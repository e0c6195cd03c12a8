//! The stopping rule on the device: `step_rule::Plateau` and `PlateauState` (and
//! `Until::Objective`'s target) as the `RuleState` that `glsl/fsot/plateau.comp`
//! evaluates after each iteration, and back; and `replay`, which runs that pass
//! alone over given objectives, so tests can hold it against the host's rule.

use super::layout::{binding, CostSlot, PlateauPush, RuleState};
use super::shaders;
use crate::core::step_rule::{Plateau, PlateauState, FINAL_FRACTION};
use crate::error::{Error, Result};
use crate::vk::buffer::upload_batch;
use crate::vk::commands::{barrier, copy};
use crate::vk::{Buffer, ComputeDesc, ComputePipeline, Context, Location};

impl RuleState {
    /// The rule `rule`, standing at `state`, ending the run at `target` if any.
    pub fn new(rule: &Plateau, state: &PlateauState, target: Option<f64>) -> Self {
        Self {
            previous: if state.previous.is_nan() { 0.0 } else { state.previous },
            sum: state.sum,
            decay_below: rule.decay_below,
            stop_below: rule.stop_below,
            target: target.unwrap_or(0.0),
            scale: state.scale,
            factor: rule.factor,
            floor_scale: FINAL_FRACTION,
            count: state.count,
            window: rule.window,
            has_previous: !state.previous.is_nan() as u32,
            has_target: target.is_some() as u32,
            stopped: 0,
            stop_iteration: 0,
            pad: 0,
        }
    }

    /// Where the rule stands, as the host keeps it (`previous` NaN before the
    /// first window's end).
    pub fn plateau_state(&self) -> PlateauState {
        let previous = if self.has_previous != 0 { self.previous } else { f64::NAN };
        PlateauState { scale: self.scale, previous, sum: self.sum, count: self.count }
    }

    /// The rule ended the run.
    pub fn stopped(&self) -> bool {
        self.stopped != 0
    }
}

/// The rule's pass (`plateau.comp`), which needs shaderFloat64; None without it.
pub fn pipeline(ctx: &Context) -> Result<Option<ComputePipeline>> {
    if !ctx.info().float64 {
        return Ok(None);
    }
    let desc = ComputeDesc {
        spirv: shaders::PLATEAU,
        bindings: binding::BINDINGS,
        push_bytes: std::mem::size_of::<PlateauPush>() as u32,
        spec: &[],
        sets: 1,
        images: &[],
        uniforms: &[],
        texels: &binding::TEXELS,
        full_subgroups: false,
    };
    Ok(Some(ComputePipeline::new(ctx, &desc)?))
}

/// Diagnostics: the rule's pass run alone from `start`, once per cost slot of
/// `slots` (iteration k reads slot k), in one submission; the rule's state after
/// each.
pub fn replay(ctx: &Context, start: RuleState, slots: &[CostSlot]) -> Result<Vec<RuleState>> {
    let Some(pass) = pipeline(ctx)? else {
        return Err(Error::VulkanUnavailable(format!("{} lacks shaderFloat64", ctx.info().name)));
    };
    let size = std::mem::size_of::<RuleState>() as u64;
    let costs = Buffer::new(
        ctx,
        (slots.len().max(1) * std::mem::size_of::<CostSlot>()) as u64,
        Location::Device,
        "replay-costs",
    )?;
    let schedule = Buffer::new(ctx, size, Location::Device, "replay-rule")?;
    let readback = Buffer::new(ctx, size * slots.len().max(1) as u64, Location::Readback, "replay-readback")?;
    // SAFETY: the buffers live until this function returns, after its one
    // submission is waited for: no dispatch of `pass` outlives them.
    unsafe { pass.bind(0, &[(binding::COSTS, &costs), (binding::SCHEDULE, &schedule)])? };
    let uploads = [(&costs, bytemuck::cast_slice(slots)), (&schedule, bytemuck::bytes_of(&start))];
    upload_batch(ctx, &uploads, |_| {})?;
    ctx.submit(|cmd| {
        for k in 0..slots.len() as u32 {
            let push = PlateauPush { slot: k, iteration: k };
            pass.dispatch(cmd, 0, [1, 1, 1], bytemuck::bytes_of(&push));
            barrier(cmd);
            copy(cmd, &schedule, &readback, size, k as u64 * size);
            barrier(cmd);
        }
    })?;
    let raw: Vec<u8> = readback.read(size as usize * slots.len())?;
    Ok(raw.chunks_exact(size as usize).map(bytemuck::pod_read_unaligned).collect())
}
