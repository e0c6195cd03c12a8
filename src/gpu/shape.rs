//! How the transport pass is launched on a device, within lavapipe's loop cap.

use crate::vk::DeviceInfo;

/// Classes up to this many samples are sorted in shared memory (the
/// specialization constant `FSOT_LOCAL_MAX` of transport.comp).
pub const LOCAL_MAX: u32 = 2048;
/// Classes up to this many samples are sorted by one invocation in the per-lane
/// transport (`FSOT_LANE_MAX` of transport_lane.comp; its private arrays take 16
/// bytes per sample per invocation, which lavapipe takes and an NVIDIA driver
/// refuses: the per-lane transport is for CPU implementations only).
pub const LANE_MAX: u32 = 2048;
/// Loop iterations one transport invocation may spend over its slices: under half
/// of lavapipe's cap of 65535 per invocation.
pub const LOOP_BUDGET: u32 = 30_000;

/// The two transport passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportKind {
    /// One workgroup per slice, bitonic sort in shared memory (GPUs).
    Workgroup,
    /// One invocation per slice, bucket sort in private memory (CPU implementations).
    PerLane,
}

/// How the transport pass is launched on a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TransportShape {
    /// Invocations per workgroup.
    pub workgroup: u32,
    /// Slices per workgroup, one after another.
    pub slices_per_group: u32,
    /// The workgroup is one subgroup: subgroup barriers suffice.
    pub one_subgroup: bool,
    /// One invocation per slice (`transport_lane.comp`): for CPU implementations,
    /// which run invocations as SIMD lanes and pay dearly for barriers and
    /// shared-memory traffic between lanes.
    pub per_lane: bool,
}

impl TransportShape {
    /// GPUs: 128 invocations, one slice each. CPU implementations (lavapipe):
    /// one subgroup per workgroup (its barriers are nearly free there, while a
    /// workgroup barrier costs a coroutine switch per subgroup) and 16 slices per
    /// workgroup (launches are dear), fewer when the kernel's largest class would
    /// take an invocation past LOOP_BUDGET loop iterations (lavapipe silently
    /// drops iterations past 65535 per invocation). On CPU implementations, the
    /// per-lane transport when the kernel allows. `forced` (invocations, slices
    /// per workgroup): the workgroup transport with that shape.
    pub fn for_device(info: &DeviceInfo, max_class: u32, forced: Option<(u32, u32)>) -> Self {
        let mut shape = if info.is_cpu() {
            let wg = info.subgroup_size.clamp(1, 128);
            // Per lane when one invocation can also write out the largest class
            // for the large-class path within the loop budget.
            let per_lane = max_class <= LOOP_BUDGET / 2;
            Self { workgroup: wg, slices_per_group: 16, one_subgroup: true, per_lane }
        } else {
            Self {
                workgroup: 128.min(info.max_workgroup_invocations),
                slices_per_group: 1,
                one_subgroup: false,
                per_lane: false,
            }
        };
        let worst = Self::slice_iterations(max_class.min(LOCAL_MAX), shape.workgroup);
        shape.slices_per_group = shape.slices_per_group.min((LOOP_BUDGET / worst).max(1));
        if let Some((wg, spg)) = forced.filter(|&(wg, spg)| wg > 0 && spg > 0) {
            shape.workgroup = wg.min(info.max_workgroup_invocations);
            shape.slices_per_group = spg;
            shape.per_lane = false;
            shape.one_subgroup = shape.workgroup <= info.subgroup_size;
        }
        shape
    }

    /// Upper bound on the loop iterations one invocation spends on a class of
    /// `n` samples (n <= LOCAL_MAX) in a workgroup of `wg`: gather, bitonic
    /// stages, targets, reduction.
    pub fn slice_iterations(n: u32, wg: u32) -> u32 {
        let p = n.max(2).next_power_of_two();
        let log = p.trailing_zeros();
        let per_stage = p.div_ceil(wg);
        let stages = log * (log + 1) / 2;
        stages * (per_stage + 1) + 3 * per_stage + 2 * log + 64
    }

    /// Workgroups of the transport pass for `slices` slices.
    pub fn groups(&self, slices: u32) -> u32 {
        if self.per_lane {
            slices.div_ceil(self.workgroup)
        } else {
            slices.div_ceil(self.slices_per_group)
        }
    }
}

/// `groups` workgroups as a dispatch, spread over y past 65535.
pub fn two_d(groups: u32) -> [u32; 3] {
    let x = groups.clamp(1, 65535);
    [x, groups.div_ceil(x).max(1), 1]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_invocation_stays_under_the_loop_budget() {
        // The largest local class on one subgroup of 8 (lavapipe), and many
        // slices per workgroup only when classes are small.
        assert!(TransportShape::slice_iterations(LOCAL_MAX, 8) < LOOP_BUDGET);
        for max_class in [2u32, 100, 500, 1360, 2048, 100_000] {
            let worst = TransportShape::slice_iterations(max_class.min(LOCAL_MAX), 8);
            let spg = 16u32.min((LOOP_BUDGET / worst).max(1));
            assert!(spg * worst <= LOOP_BUDGET, "{max_class}: {spg} x {worst}");
        }
        // Per lane, one invocation sorts a whole class: clear, count, prefix and
        // place (one loop over n each), then either insertion moves (n + at most
        // 4n, FSOT_INSERTION_BUDGET) or the heap-sort fallback (3n/2 sift-downs
        // of at most log2 n steps each), then targets and scatter (n). At
        // LANE_MAX the fallback is the worst case, about 47k: under lavapipe's
        // 65535 for all loops of an invocation.
        let n = LANE_MAX;
        let log = n.ilog2();
        let insertion = n + 4 * n;
        let heap = 3 * n / 2 + (3 * n / 2) * log;
        let per_lane = 5 * n + insertion.max(heap);
        assert!(per_lane < 50_000, "{per_lane}");
        // A bitonic network of 2048 on 8 invocations: 66 stages of 256 pairs.
        assert!(TransportShape::slice_iterations(2048, 8) >= 66 * 256);
    }
}
