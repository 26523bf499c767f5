//! Frames in flight: per-frame command buffers, fences, semaphores, timestamp queries and a
//! queue of work deferred until a frame has finished (destroying what it used, saving
//! screenshots it read back), so that the CPU records frame N+1 while the GPU runs frame N.

use ash::vk;

use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::error::{Result, VkContext};

/// Frames the CPU may record ahead of the GPU.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// Work to do once the frame that last used something has finished on the GPU: destroying
/// it, or reading what the frame wrote.
pub type Deferred = Box<dyn FnOnce(&Context)>;

/// The handles a frame records and submits with.
#[derive(Clone, Copy, Debug)]
pub struct FrameHandles {
    pub cmd: vk::CommandBuffer,
    /// Signalled when the swapchain image the frame draws to is ready.
    pub image_available: vk::Semaphore,
    /// The frame's timestamp queries, reset at the start of its command buffer.
    pub queries: vk::QueryPool,
}

/// One frame's own objects.
struct FrameSlot {
    cmd: vk::CommandBuffer,
    /// Signalled when the frame's commands have finished.
    fence: vk::Fence,
    image_available: vk::Semaphore,
    queries: vk::QueryPool,
    /// Whether the slot's last frame wrote timestamps that have not been read.
    stamped: bool,
    deferred: Vec<Deferred>,
}

/// A ring of [`FRAMES_IN_FLIGHT`] frame slots.
pub struct FrameLoop {
    pool: vk::CommandPool,
    slots: Vec<FrameSlot>,
    current: usize,
    timestamps: u32,
    /// Frames begun so far.
    pub frame: u64,
}

impl FrameLoop {
    /// A ring whose frames write up to `timestamps` timestamp queries each.
    pub fn new(ctx: &Context, timestamps: u32) -> Result<Self> {
        let device = &ctx.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create info; the pool is destroyed in `destroy` (or below on failure).
        let pool = unsafe { device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        let mut ring = FrameLoop { pool, slots: Vec::new(), current: 0, timestamps: timestamps.max(1), frame: 0 };
        for i in 0..FRAMES_IN_FLIGHT {
            match ring.make_slot(ctx, i) {
                Ok(slot) => ring.slots.push(slot),
                Err(e) => {
                    ring.destroy(ctx);
                    return Err(e);
                }
            }
        }
        Ok(ring)
    }

    fn make_slot(&self, ctx: &Context, index: usize) -> Result<FrameSlot> {
        ctx.step("vkCreateFence")?;
        let device = &ctx.device;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: a valid allocate info for this ring's pool, which frees the buffer with it.
        let cmd = unsafe { device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?[0];
        // Destroyed by the guard if a later step fails; null handles are skipped.
        let mut slot = ctx.guard(FrameSlot {
            cmd,
            fence: vk::Fence::null(),
            image_available: vk::Semaphore::null(),
            queries: vk::QueryPool::null(),
            stamped: false,
            deferred: Vec::new(),
        });
        // Signalled, so that the first wait on a fresh slot returns at once.
        let signalled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
        // SAFETY: a valid create info that outlives the call (true of the two below too).
        slot.fence = unsafe { device.create_fence(&signalled, None) }.vk("vkCreateFence")?;
        // SAFETY: as above.
        slot.image_available =
            unsafe { device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.vk("vkCreateSemaphore")?;
        let query_info =
            vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(self.timestamps);
        // SAFETY: as above.
        slot.queries = unsafe { device.create_query_pool(&query_info, None) }.vk("vkCreateQueryPool")?;
        ctx.set_name(cmd, &format!("frame {index} commands"));
        ctx.set_name(slot.fence, &format!("frame {index} done"));
        ctx.set_name(slot.image_available, &format!("frame {index} image available"));
        Ok(slot.keep())
    }

    /// Waits until the next slot's previous frame has finished, runs its deferred work, and
    /// begins its command buffer with its timestamp queries reset ([`FrameLoop::handles`]).
    /// Returns, if the slot's previous frame wrote timestamps, their values (in ticks).
    pub fn begin(&mut self, ctx: &Context) -> Result<Option<Vec<u64>>> {
        self.current = (self.frame % FRAMES_IN_FLIGHT as u64) as usize;
        self.frame += 1;
        let timestamps = self.timestamps;
        let slot = &mut self.slots[self.current];
        let device = &ctx.device;
        // SAFETY: the fence belongs to this slot.
        unsafe { device.wait_for_fences(&[slot.fence], true, u64::MAX) }.vk("vkWaitForFences")?;
        // Nothing of the slot's previous frame is pending any more.
        for work in slot.deferred.drain(..) {
            work(ctx);
        }
        let stamps = if slot.stamped {
            let mut values = vec![0u64; timestamps as usize];
            let flags = vk::QueryResultFlags::TYPE_64;
            // SAFETY: the slot's previous frame, now finished, wrote all `timestamps` queries.
            unsafe { device.get_query_pool_results(slot.queries, 0, &mut values, flags) }
                .vk("vkGetQueryPoolResults")?;
            slot.stamped = false;
            Some(values)
        } else {
            None
        };
        let flags = vk::CommandBufferResetFlags::empty();
        // SAFETY: the command buffer's last submission has finished (the fence above).
        unsafe { device.reset_command_buffer(slot.cmd, flags) }.vk("vkResetCommandBuffer")?;
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the command buffer was just reset.
        unsafe { device.begin_command_buffer(slot.cmd, &begin) }.vk("vkBeginCommandBuffer")?;
        // SAFETY: recording, outside a render pass; the pool holds `timestamps` queries.
        unsafe { device.cmd_reset_query_pool(slot.cmd, slot.queries, 0, timestamps) };
        Ok(stamps)
    }

    /// The slot of the frame [`FrameLoop::begin`] began last, from 0 to [`FRAMES_IN_FLIGHT`]:
    /// what the slot's previous frame used is free again.
    pub fn slot(&self) -> usize {
        self.current
    }

    /// The handles of the frame [`FrameLoop::begin`] began last.
    pub fn handles(&self) -> FrameHandles {
        let slot = &self.slots[self.current];
        FrameHandles { cmd: slot.cmd, image_available: slot.image_available, queries: slot.queries }
    }

    /// Ends the current frame's command buffer and submits it; it waits for `wait` (at the
    /// transfer stage, where the swapchain image is first written) and signals `signal`.
    /// `stamped`: whether the frame wrote all its timestamps.
    pub fn submit(
        &mut self,
        ctx: &Context,
        wait: Option<vk::Semaphore>,
        signal: Option<vk::Semaphore>,
        stamped: bool,
    ) -> Result<()> {
        let slot = &mut self.slots[self.current];
        let device = &ctx.device;
        let cmds = [slot.cmd];
        let waits: Vec<vk::Semaphore> = wait.into_iter().collect();
        let stages = vec![vk::PipelineStageFlags::TRANSFER; waits.len()];
        let signals: Vec<vk::Semaphore> = signal.into_iter().collect();
        let submit = vk::SubmitInfo::default()
            .command_buffers(&cmds)
            .wait_semaphores(&waits)
            .wait_dst_stage_mask(&stages)
            .signal_semaphores(&signals);
        // SAFETY: the command buffer is recording and is ended here; the fence is unsignalled
        // only between reset and submit, and both happen here.
        unsafe {
            device.end_command_buffer(slot.cmd).vk("vkEndCommandBuffer")?;
            device.reset_fences(&[slot.fence]).vk("vkResetFences")?;
            device.queue_submit(ctx.queue, &[submit], slot.fence).vk("vkQueueSubmit")?;
        }
        slot.stamped = stamped;
        Ok(())
    }

    /// Runs `work` once the current frame has finished on the GPU.
    pub fn defer(&mut self, work: Deferred) {
        self.slots[self.current].deferred.push(work);
    }

    /// Waits for every frame in flight and runs all deferred work.
    pub fn wait_all(&mut self, ctx: &Context) -> Result<()> {
        let fences: Vec<vk::Fence> = self.slots.iter().map(|s| s.fence).collect();
        if !fences.is_empty() {
            // SAFETY: the fences belong to this ring.
            unsafe { ctx.device.wait_for_fences(&fences, true, u64::MAX) }.vk("vkWaitForFences")?;
        }
        for slot in &mut self.slots {
            for work in slot.deferred.drain(..) {
                work(ctx);
            }
        }
        Ok(())
    }

    /// Waits for all frames, runs the deferred work and destroys the ring.
    pub fn destroy(mut self, ctx: &Context) {
        let _ = self.wait_all(ctx);
        for slot in self.slots.drain(..) {
            slot.destroy(ctx);
        }
        // SAFETY: no frame of the ring is pending any more; the pool frees its buffers.
        unsafe { ctx.device.destroy_command_pool(self.pool, None) };
    }
}

impl Destroy for FrameSlot {
    /// Destroys the slot's objects (its command buffer goes with the pool); null handles are
    /// skipped. No frame of the slot may be pending.
    fn destroy(self, ctx: &Context) {
        // SAFETY: as the caller guarantees, nothing uses the slot's objects.
        unsafe {
            ctx.device.destroy_fence(self.fence, None);
            ctx.device.destroy_semaphore(self.image_available, None);
            ctx.device.destroy_query_pool(self.queries, None);
        }
    }
}
