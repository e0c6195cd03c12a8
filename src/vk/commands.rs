//! Command submission: one persistent command pool, command buffer and fence per
//! context (reset and reused, not made per call), the queue lock around
//! `vkQueueSubmit`, and the barrier and copy helpers recorded into it.

use ash::vk;

use super::buffer::Buffer;
use super::check;
use super::context::Context;
use super::error::{Error, Result};

/// The context's pool, its one primary command buffer and the fence it waits on.
pub(crate) struct Commands {
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
}

impl Commands {
    /// The command buffer (its handle names this context in validation messages).
    pub fn command_buffer(&self) -> vk::CommandBuffer {
        self.cmd
    }

    pub fn new(device: &ash::Device, queue_family: u32) -> Result<Self> {
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(queue_family);
        // SAFETY: a valid device and create info.
        let pool = check("vkCreateCommandPool", unsafe { device.create_command_pool(&info, None) })?;
        let made = (|| -> Result<(vk::CommandBuffer, vk::Fence)> {
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            // SAFETY: the pool was just made on this device.
            let cmd =
                check("vkAllocateCommandBuffers", unsafe { device.allocate_command_buffers(&alloc) })?[0];
            // SAFETY: a plain create call.
            let fence = check("vkCreateFence", unsafe {
                device.create_fence(&vk::FenceCreateInfo::default(), None)
            })?;
            Ok((cmd, fence))
        })();
        match made {
            Ok((cmd, fence)) => Ok(Self { pool, cmd, fence }),
            Err(e) => {
                // SAFETY: nothing from the pool was submitted.
                unsafe { device.destroy_command_pool(pool, None) };
                Err(e)
            }
        }
    }

    /// Destroys the pool and fence.
    ///
    /// # Safety
    /// Nothing recorded in the pool may be pending on the device.
    pub unsafe fn destroy(&self, device: &ash::Device) {
        // SAFETY: the caller guarantees the device is done with them.
        unsafe {
            device.destroy_fence(self.fence, None);
            device.destroy_command_pool(self.pool, None);
        }
    }
}

/// A command buffer in the recording state on a context's device: what every
/// function that records commands takes. `Context::submit` hands one to its
/// closure; a host recording into its own command buffer makes one with the
/// unsafe `Recording::new`, which states what such recording relies on.
#[derive(Clone, Copy)]
pub struct Recording<'a> {
    ctx: &'a Context,
    cmd: vk::CommandBuffer,
    /// Neither `Send` nor `Sync`: a command buffer records on one thread.
    _one_thread: std::marker::PhantomData<*const ()>,
}

impl<'a> Recording<'a> {
    /// Records into the host's `cmd` on `ctx`'s device.
    ///
    /// # Safety
    /// - `cmd` was allocated on `ctx`'s device, is in the recording state, and
    ///   stays in it while this value (or a copy) is used;
    /// - nothing else records into `cmd` meanwhile (Vulkan's external
    ///   synchronisation of command buffers);
    /// - the queue `cmd` is submitted to supports compute and transfer;
    /// - every buffer, image, pipeline and sort recorded through it stays alive,
    ///   and the host neither writes nor frees them, until the device has finished
    ///   the commands (fsot waits for nothing it did not submit itself);
    /// - the host orders fsot's commands against its own with barriers: fsot's
    ///   recorded passes begin and end with a full compute barrier of their own,
    ///   but cannot see what the host recorded around them.
    pub unsafe fn new(ctx: &'a Context, cmd: vk::CommandBuffer) -> Self {
        Self { ctx, cmd, _one_thread: std::marker::PhantomData }
    }

    /// The context whose device the commands are for.
    pub fn context(&self) -> &'a Context {
        self.ctx
    }

    /// The command buffer itself.
    pub fn raw(&self) -> vk::CommandBuffer {
        self.cmd
    }
}

std::thread_local! {
    /// The contexts (their shared state's address) this thread is recording a
    /// submission for.
    static RECORDING: std::cell::RefCell<Vec<usize>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Marks this thread as recording for a context until dropped.
struct RecordingMark(usize);

impl RecordingMark {
    /// None where the thread's locals are already gone (a submission from a
    /// thread-local's destructor): such a submission goes unmarked.
    fn enter(key: usize) -> Result<Option<Self>> {
        let entered = RECORDING.try_with(|r| {
            let mut r = r.borrow_mut();
            if r.contains(&key) {
                return Err(Error::invalid(
                    "a submission on a context from inside the recording of another on it \
                     (an upload, download or sort inside `submit`'s closure): record into the \
                     closure's command buffer instead",
                ));
            }
            r.push(key);
            Ok(RecordingMark(key))
        });
        entered.map_or(Ok(None), |e| e.map(Some))
    }
}

impl Drop for RecordingMark {
    fn drop(&mut self) {
        let _ = RECORDING.try_with(|r| r.borrow_mut().retain(|k| *k != self.0)); // gone: nothing to unmark
    }
}

impl Context {
    /// Records commands with `record` into the context's command buffer, submits
    /// them and waits until the device has run them. Holds the context's command
    /// lock throughout and its queue lock around the submission. A submission
    /// on the same context from inside `record` (through an upload, a download
    /// or a sort) is an error, where it would wait for ever on the lock.
    pub fn submit(&self, record: impl FnOnce(Recording<'_>)) -> Result<()> {
        let s = &self.shared;
        let device = &s.device;
        let _mark = RecordingMark::enter(std::sync::Arc::as_ptr(s) as usize)?;
        let commands = s.commands.lock().map_err(|_| Error::invalid("the command lock is poisoned"))?;
        let cmd = commands.cmd;
        // SAFETY: the previous submission of this pool was waited for (below), so
        // nothing recorded in it is pending.
        check("vkResetCommandPool", unsafe {
            device.reset_command_pool(commands.pool, vk::CommandPoolResetFlags::empty())
        })?;
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the buffer is in the initial state after the pool reset.
        check("vkBeginCommandBuffer", unsafe { device.begin_command_buffer(cmd, &begin) })?;
        // SAFETY: `cmd` is this context's, in the recording state until the end
        // call below, recorded only here (the command lock is held), on the
        // context's compute queue; `submit` waits for the device before it
        // returns, so everything the closure borrows outlives the commands.
        record(unsafe { Recording::new(self, cmd) });
        // SAFETY: recording began above.
        check("vkEndCommandBuffer", unsafe { device.end_command_buffer(cmd) })?;
        let cmds = [cmd];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        let submitted = match super::fault::submission() {
            Some(injected) => Err(injected),
            None => {
                let _queue = s.queue_lock.lock().map_err(|_| Error::invalid("the queue lock is poisoned"))?;
                // SAFETY: the queue is externally synchronised by the queue lock held here;
                // the fence is unsignalled (reset after each wait).
                unsafe { device.queue_submit(s.queue, &submit, commands.fence) }
            }
        };
        check("vkQueueSubmit", submitted)?;
        // SAFETY: the fence belongs to this device.
        let waited = unsafe { device.wait_for_fences(&[commands.fence], true, u64::MAX) };
        if waited.is_err() {
            // What the commands use is freed once this returns: let the queue
            // finish them first (a lost device has nothing pending).
            if let Ok(_queue) = s.queue_lock.lock() {
                // SAFETY: the queue is externally synchronised by the queue lock held here.
                let _ = unsafe { device.queue_wait_idle(s.queue) };
            }
        }
        check("vkWaitForFences", waited)?;
        // SAFETY: the fence is signalled and not in use by a pending submission.
        check("vkResetFences", unsafe { device.reset_fences(&[commands.fence]) })
    }
}

/// A full memory barrier between recorded commands (compute and transfer writes
/// made visible to compute, transfer, host and indirect-argument reads, and
/// ordered before later compute and transfer writes: a fill after a dispatch
/// that wrote the buffer).
pub fn barrier(cmd: Recording<'_>) {
    let mb = vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::TRANSFER_WRITE
                | vk::AccessFlags::HOST_READ
                | vk::AccessFlags::INDIRECT_COMMAND_READ,
        );
    // SAFETY: `cmd` is being recorded (`Recording`).
    unsafe {
        cmd.context().device().cmd_pipeline_barrier(
            cmd.raw(),
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::COMPUTE_SHADER
                | vk::PipelineStageFlags::TRANSFER
                | vk::PipelineStageFlags::HOST
                | vk::PipelineStageFlags::DRAW_INDIRECT,
            vk::DependencyFlags::empty(),
            &[mb],
            &[],
            &[],
        )
    };
}

/// Copies the first `bytes` bytes of `src` to `dst` at `dst_offset`.
/// Panics for a range past either buffer.
pub fn copy(cmd: Recording<'_>, src: &Buffer, dst: &Buffer, bytes: u64, dst_offset: u64) {
    let fits = bytes > 0 && bytes <= src.size && dst_offset.checked_add(bytes).is_some_and(|end| end <= dst.size);
    assert!(fits, "a copy of {bytes} bytes from a buffer of {} to offset {dst_offset} of one of {}", src.size, dst.size);
    copy_raw(cmd, src.raw, dst.raw, bytes, dst_offset)
}

/// As `copy`, between buffer handles (a host's among them), which the caller
/// keeps alive with TRANSFER_SRC and TRANSFER_DST usage until the commands run.
pub(crate) fn copy_raw(cmd: Recording<'_>, src: vk::Buffer, dst: vk::Buffer, bytes: u64, dst_offset: u64) {
    let region = [vk::BufferCopy::default().size(bytes).dst_offset(dst_offset)];
    // SAFETY: `cmd` is being recorded; both buffers are alive and have TRANSFER
    // usage (the callers' promise).
    unsafe { cmd.context().device().cmd_copy_buffer(cmd.raw(), src, dst, &region) };
}

/// Sets every byte of `buffer` from `offset` for `bytes` bytes (vk::WHOLE_SIZE: to the end) to zero.
/// Panics for a range past the buffer or not in whole 4-byte words.
pub fn zero(cmd: Recording<'_>, buffer: &Buffer, offset: u64, bytes: u64) {
    let fits = offset % 4 == 0
        && offset < buffer.size
        && (bytes == vk::WHOLE_SIZE || bytes > 0 && bytes % 4 == 0 && offset + bytes <= buffer.size);
    assert!(fits, "zeroing {bytes} bytes at offset {offset} of a buffer of {}", buffer.size);
    // SAFETY: `cmd` is being recorded; the buffer has TRANSFER_DST usage.
    unsafe { cmd.context().device().cmd_fill_buffer(cmd.raw(), buffer.raw, offset, bytes, 0) };
}
