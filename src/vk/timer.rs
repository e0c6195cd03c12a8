//! GPU timing with timestamp queries.

use ash::vk;

use super::check;
use super::commands::Recording;
use super::context::Context;
use super::error::Result;

/// A pool of timestamp queries.
pub struct Timer {
    ctx: Context,
    pool: vk::QueryPool,
    count: u32,
}

impl Timer {
    /// A pool of `count` timestamps.
    pub fn new(ctx: &Context, count: u32) -> Result<Self> {
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(count);
        // SAFETY: a valid create info.
        let pool = check("vkCreateQueryPool", unsafe { ctx.device().create_query_pool(&info, None) })?;
        Ok(Self { ctx: ctx.clone(), pool, count })
    }

    /// Resets every query; record before the first `stamp`.
    pub fn reset(&self, cmd: Recording<'_>) {
        // SAFETY: `cmd` is being recorded.
        unsafe { self.ctx.device().cmd_reset_query_pool(cmd.raw(), self.pool, 0, self.count) };
    }

    /// Writes timestamp `index` once all earlier commands have finished.
    pub fn stamp(&self, cmd: Recording<'_>, index: u32) {
        // SAFETY: `cmd` is being recorded; `index` < count is the caller's plan.
        unsafe {
            self.ctx.device().cmd_write_timestamp(
                cmd.raw(),
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                self.pool,
                index,
            )
        };
    }

    /// Timestamps 0..n in nanoseconds (after the submission has completed).
    pub fn read_ns(&self, n: u32) -> Result<Vec<f64>> {
        let mut raw = vec![0u64; n as usize];
        // SAFETY: the submission that wrote them was waited for.
        check("vkGetQueryPoolResults", unsafe {
            self.ctx.device().get_query_pool_results(
                self.pool,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        })?;
        let period = self.ctx.info().timestamp_period_ns as f64;
        Ok(raw.iter().map(|&t| t as f64 * period).collect())
    }
}

impl Drop for Timer {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses the pool.
        unsafe { self.ctx.device().destroy_query_pool(self.pool, None) };
    }
}
