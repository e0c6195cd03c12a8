//! Texel-buffer views: a buffer read by a shader as an array of texels of one
//! format (`samplerBuffer`, `usamplerBuffer`) through the texture path. On some
//! implementations that path gathers scattered reads much faster than
//! storage-buffer loads: llvmpipe (Mesa 22.3) reads a storage buffer at
//! per-lane addresses one lane at a time, a texel buffer with one vector gather.

use ash::vk;

use super::buffer::Buffer;
use super::check;
use super::context::Context;
use super::error::{Error, Result};

/// A buffer viewed as texels of one format (a uniform texel buffer).
pub struct TexelView {
    ctx: Context,
    /// The view handle.
    pub raw: vk::BufferView,
    /// Texels the view holds: the whole buffer over the texel's size.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))]
    pub texels: u64,
}

impl TexelView {
    /// A view of the whole of `buffer` as texels of `format`, `texel_bytes`
    /// each. The formats a uniform texel buffer must support on every device
    /// (R32_SFLOAT, R32_UINT, R32G32B32A32_UINT, ...) need no query; a buffer of
    /// more texels than the device's maxTexelBufferElements is refused.
    pub fn new(ctx: &Context, buffer: &Buffer, format: vk::Format, texel_bytes: u64) -> Result<Self> {
        let texels = buffer.size / texel_bytes.max(1);
        let limit = ctx.info().max_texel_buffer_elements;
        if texels > limit {
            return Err(Error::invalid(format!(
                "a texel view of {texels} texels; the device's views hold at most {limit} (maxTexelBufferElements)"
            )));
        }
        let info = vk::BufferViewCreateInfo::default()
            .buffer(buffer.raw)
            .format(format)
            .offset(0)
            .range(texels * texel_bytes);
        // SAFETY: the buffer is alive and was made with UNIFORM_TEXEL_BUFFER usage
        // (Buffer::new); the range lies within it.
        let raw = check("vkCreateBufferView", unsafe { ctx.device().create_buffer_view(&info, None) })?;
        Ok(Self { ctx: ctx.clone(), raw, texels })
    }
}

impl Drop for TexelView {
    fn drop(&mut self) {
        // SAFETY: every submission that used the view has been waited for (each
        // submission is), and nothing else holds the handle.
        unsafe { self.ctx.device().destroy_buffer_view(self.raw, None) };
    }
}
