//! Rust mirrors of the push-constant blocks in `glsl/common.glsl` and
//! `glsl/radix_common.glsl`. Field order and types must match the GLSL structs;
//! `tests/gpu_layout` style checks live in the unit tests below.

/// Plain data that can be handed to Vulkan as bytes.
pub trait Pod: Copy {
    fn bytes(&self) -> &[u8] {
        // Safe for the #[repr(C)] structs below: u32/f32 fields only, no padding.
        unsafe { std::slice::from_raw_parts(self as *const Self as *const u8, std::mem::size_of::<Self>()) }
    }
}

/// `TransportPush` in common.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TransportPush {
    pub slice_key: u32,
    pub iteration: u32,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub spp: u32,
    pub dims: u32,
    pub taps: u32,
    pub slices: u32,
    pub cost_slot: u32,
    pub large_capacity: u32,
    pub pad: u32,
}
impl Pod for TransportPush {}

/// `UpdatePush` in common.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UpdatePush {
    pub values: u32,
    pub rule: u32,
    pub step_t: u32,
    pub scale: f32,
    pub inv_hits: f32,
    pub p0: f32,
    pub p1: f32,
    pub p2: f32,
    pub p3: f32,
    pub bias1: f32,
    pub bias2: f32,
    pub pad: u32,
}
impl Pod for UpdatePush {}

/// `RadixPush` in radix_common.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RadixPush {
    pub shift: u32,
    pub blocks: u32,
    pub chunks: u32,
    pub pad: u32,
}
impl Pod for RadixPush {}

/// `LargePush` in transport_large.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LargePush {
    pub transport: TransportPush,
}
impl Pod for LargePush {}

/// Byte offset of a kernel tap table entry: (dx, dy, dt, level threshold).
pub type TapEntry = [u32; 4];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_blocks_have_the_glsl_sizes() {
        // 12 scalars each; push constants must stay within the 128 bytes every
        // device guarantees.
        assert_eq!(std::mem::size_of::<TransportPush>(), 48);
        assert_eq!(std::mem::size_of::<UpdatePush>(), 48);
        assert_eq!(std::mem::size_of::<RadixPush>(), 16);
    }
}
