//! Barriers from declared accesses.
//!
//! Every pass of a frame says which images and buffers it reads and writes, in which pipeline
//! stage and image layout ([`Use`]). [`ResourceStates`] remembers the last access of every
//! resource, across passes and across frames, and [`run_passes`] records, before each pass, the
//! one `vkCmdPipelineBarrier2` that orders it after what came before. This is the only place
//! where per-frame barriers are made; a pass never records one itself.

use std::collections::HashMap;

use ash::vk;

use crate::backend::context::Context;
use crate::backend::resources::{copy_to_buffer, Buffer, Image};

/// How a pass touches a resource: the stages and access kinds, and for images the layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Access {
    pub stage: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
    /// Ignored for buffers.
    pub layout: vk::ImageLayout,
}

const WRITES: vk::AccessFlags2 = vk::AccessFlags2::from_raw(
    vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw()
        | vk::AccessFlags2::SHADER_WRITE.as_raw()
        | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags2::TRANSFER_WRITE.as_raw()
        | vk::AccessFlags2::HOST_WRITE.as_raw()
        | vk::AccessFlags2::MEMORY_WRITE.as_raw(),
);

impl Access {
    pub const COMPUTE_READ: Access = Access::new(
        vk::PipelineStageFlags2::COMPUTE_SHADER,
        vk::AccessFlags2::SHADER_STORAGE_READ,
        vk::ImageLayout::GENERAL,
    );
    pub const COMPUTE_WRITE: Access = Access::new(
        vk::PipelineStageFlags2::COMPUTE_SHADER,
        vk::AccessFlags2::SHADER_STORAGE_WRITE,
        vk::ImageLayout::GENERAL,
    );
    pub const COMPUTE_READ_WRITE: Access = Access::new(
        vk::PipelineStageFlags2::COMPUTE_SHADER,
        vk::AccessFlags2::from_raw(
            vk::AccessFlags2::SHADER_STORAGE_READ.as_raw() | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw(),
        ),
        vk::ImageLayout::GENERAL,
    );
    /// Storage buffers read by a fragment shader.
    pub const FRAGMENT_READ: Access = Access::new(
        vk::PipelineStageFlags2::FRAGMENT_SHADER,
        vk::AccessFlags2::SHADER_STORAGE_READ,
        vk::ImageLayout::GENERAL,
    );
    /// A color attachment that is cleared and written, kept in `GENERAL` so that compute
    /// passes read it without a layout change.
    pub const COLOR_ATTACHMENT_WRITE: Access = Access::new(
        vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
        vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        vk::ImageLayout::GENERAL,
    );
    /// A color attachment that draws blend onto, in `GENERAL` like the one above.
    pub const COLOR_ATTACHMENT_BLEND: Access = Access::new(
        vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
        vk::AccessFlags2::from_raw(
            vk::AccessFlags2::COLOR_ATTACHMENT_READ.as_raw() | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw(),
        ),
        vk::ImageLayout::GENERAL,
    );
    /// An image sampled by a fragment shader.
    pub const FRAGMENT_SAMPLED: Access = Access::new(
        vk::PipelineStageFlags2::FRAGMENT_SHADER,
        vk::AccessFlags2::SHADER_SAMPLED_READ,
        vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    );
    pub const DEPTH_ATTACHMENT: Access = Access::new(
        vk::PipelineStageFlags2::from_raw(
            vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS.as_raw()
                | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw(),
        ),
        vk::AccessFlags2::from_raw(
            vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ.as_raw()
                | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw(),
        ),
        vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
    );
    /// Vertex attributes and indices read by a draw.
    pub const VERTEX_INDEX_READ: Access = Access::new(
        vk::PipelineStageFlags2::VERTEX_INPUT,
        vk::AccessFlags2::from_raw(
            vk::AccessFlags2::VERTEX_ATTRIBUTE_READ.as_raw() | vk::AccessFlags2::INDEX_READ.as_raw(),
        ),
        vk::ImageLayout::UNDEFINED,
    );
    pub const INDIRECT_READ: Access = Access::new(
        vk::PipelineStageFlags2::DRAW_INDIRECT,
        vk::AccessFlags2::INDIRECT_COMMAND_READ,
        vk::ImageLayout::UNDEFINED,
    );
    pub const TRANSFER_READ: Access = Access::new(
        vk::PipelineStageFlags2::ALL_TRANSFER,
        vk::AccessFlags2::TRANSFER_READ,
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
    );
    pub const TRANSFER_WRITE: Access = Access::new(
        vk::PipelineStageFlags2::ALL_TRANSFER,
        vk::AccessFlags2::TRANSFER_WRITE,
        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
    );
    /// The CPU reads a buffer after the submission's fence: the end of a read-back.
    pub const HOST_READ: Access =
        Access::new(vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ, vk::ImageLayout::UNDEFINED);
    /// A swapchain image handed to the presentation engine (ordered by the submit's semaphore).
    pub const PRESENT: Access =
        Access::new(vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE, vk::ImageLayout::PRESENT_SRC_KHR);

    pub const fn new(stage: vk::PipelineStageFlags2, access: vk::AccessFlags2, layout: vk::ImageLayout) -> Self {
        Self { stage, access, layout }
    }

    fn writes(&self) -> bool {
        self.access.intersects(WRITES)
    }
}

/// A resource as the barrier code sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Resource {
    /// An image, its aspect, and its texel size in bytes (0 where unknown, as for swapchain
    /// images), for traffic estimates.
    Image {
        raw: vk::Image,
        aspect: vk::ImageAspectFlags,
        texel_bytes: u32,
    },
    Buffer(vk::Buffer),
}

impl Resource {
    pub fn image(image: &Image) -> Self {
        Resource::Image { raw: image.raw, aspect: image.aspect(), texel_bytes: image.texel_bytes() }
    }

    pub fn buffer(buffer: &Buffer) -> Self {
        Resource::Buffer(buffer.raw)
    }
}

/// One pass's access to one resource.
#[derive(Clone, Copy, Debug)]
pub struct Use {
    pub resource: Resource,
    pub access: Access,
}

impl Use {
    pub fn image(image: &Image, access: Access) -> Self {
        Use { resource: Resource::image(image), access }
    }

    pub fn buffer(buffer: &Buffer, access: Access) -> Self {
        Use { resource: Resource::buffer(buffer), access }
    }
}

/// What is known of a resource since its last write.
#[derive(Clone, Copy, Debug)]
struct State {
    layout: vk::ImageLayout,
    /// The last write (or layout transition): its stages and write accesses.
    write_stage: vk::PipelineStageFlags2,
    write_access: vk::AccessFlags2,
    /// Reads since then that are already ordered after it.
    read_stage: vk::PipelineStageFlags2,
    read_access: vk::AccessFlags2,
}

impl Default for State {
    fn default() -> Self {
        State {
            layout: vk::ImageLayout::UNDEFINED,
            write_stage: vk::PipelineStageFlags2::NONE,
            write_access: vk::AccessFlags2::NONE,
            read_stage: vk::PipelineStageFlags2::NONE,
            read_access: vk::AccessFlags2::NONE,
        }
    }
}

/// The last access of every resource that passes have used, kept across frames so that the
/// first pass of a frame waits for the last use in the frame before.
#[derive(Default)]
pub struct ResourceStates {
    states: HashMap<Resource, State>,
}

/// The barriers that order one pass after what came before.
#[derive(Default)]
struct Barriers {
    images: Vec<vk::ImageMemoryBarrier2<'static>>,
    buffers: Vec<vk::BufferMemoryBarrier2<'static>>,
}

impl ResourceStates {
    /// Records that `image` is in `layout` with no access pending (after a set-up submission
    /// that has finished).
    pub fn set_layout(&mut self, image: &Image, layout: vk::ImageLayout) {
        self.states.insert(Resource::image(image), State { layout, ..State::default() });
    }

    /// Records that `image` arrives from outside the queue's command stream, such as a
    /// swapchain image whose acquire semaphore the submission waits for at `stage`: its first
    /// use is ordered after that stage, and its contents are discarded.
    pub fn arrive(&mut self, image: Resource, stage: vk::PipelineStageFlags2) {
        self.states.insert(image, State { write_stage: stage, ..State::default() });
    }

    /// Forgets what happened to `resource`: a resource just made, whose handle may be that of
    /// one destroyed before, starts with no access and no layout.
    pub fn forget(&mut self, resource: Resource) {
        self.states.remove(&resource);
    }

    /// Forgets every resource that `others` knows: those of a part of the frame that is
    /// destroyed, whose handles new resources may reuse.
    pub fn forget_all(&mut self, others: &ResourceStates) {
        self.states.retain(|resource, _| !others.states.contains_key(resource));
    }

    /// Updates the states for `uses` and returns the barriers they need.
    fn barriers(&mut self, uses: &[Use]) -> Barriers {
        let mut merged: Vec<Use> = Vec::with_capacity(uses.len());
        for u in uses {
            match merged.iter_mut().find(|m| m.resource == u.resource) {
                Some(m) => {
                    debug_assert!(m.access.layout == u.access.layout, "one pass uses {:?} in two layouts", u.resource);
                    m.access.stage |= u.access.stage;
                    m.access.access |= u.access.access;
                }
                None => merged.push(*u),
            }
        }
        let mut out = Barriers::default();
        for u in merged {
            let state = self.states.entry(u.resource).or_default();
            let is_image = matches!(u.resource, Resource::Image { .. });
            let transition = is_image && state.layout != u.access.layout;
            let needed = if transition || u.access.writes() {
                // Wait for the last write and every read since; make the write available.
                Some((state.write_stage | state.read_stage, state.write_access))
            } else if state.write_stage != vk::PipelineStageFlags2::NONE
                && !(state.read_stage.contains(u.access.stage) && state.read_access.contains(u.access.access))
            {
                Some((state.write_stage, state.write_access))
            } else {
                None
            };
            if let Some((src_stage, src_access)) = needed {
                // A first write to a resource nobody used before needs no barrier.
                if transition || src_stage != vk::PipelineStageFlags2::NONE {
                    push_barrier(&mut out, u, state.layout, src_stage, src_access);
                }
            }
            if transition || u.access.writes() {
                *state = State {
                    layout: if is_image { u.access.layout } else { vk::ImageLayout::UNDEFINED },
                    write_stage: u.access.stage,
                    write_access: u.access.access & WRITES,
                    read_stage: if u.access.writes() { vk::PipelineStageFlags2::NONE } else { u.access.stage },
                    read_access: if u.access.writes() { vk::AccessFlags2::NONE } else { u.access.access },
                };
            } else {
                state.read_stage |= u.access.stage;
                state.read_access |= u.access.access;
            }
        }
        out
    }
}

fn push_barrier(
    out: &mut Barriers,
    u: Use,
    old_layout: vk::ImageLayout,
    src_stage: vk::PipelineStageFlags2,
    src_access: vk::AccessFlags2,
) {
    match u.resource {
        Resource::Image { raw, aspect, .. } => out.images.push(
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(src_stage)
                .src_access_mask(src_access)
                .dst_stage_mask(u.access.stage)
                .dst_access_mask(u.access.access)
                .old_layout(old_layout)
                .new_layout(u.access.layout)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(raw)
                .subresource_range(vk::ImageSubresourceRange {
                    aspect_mask: aspect,
                    base_mip_level: 0,
                    level_count: 1,
                    base_array_layer: 0,
                    layer_count: 1,
                }),
        ),
        Resource::Buffer(raw) => out.buffers.push(
            vk::BufferMemoryBarrier2::default()
                .src_stage_mask(src_stage)
                .src_access_mask(src_access)
                .dst_stage_mask(u.access.stage)
                .dst_access_mask(u.access.access)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .buffer(raw)
                .size(vk::WHOLE_SIZE),
        ),
    }
}

/// One pass of a frame: its name (a debug label), what it uses, and how to record it.
pub struct Pass<'a> {
    pub name: &'static str,
    pub uses: Vec<Use>,
    pub record: Box<dyn FnOnce(vk::CommandBuffer) + 'a>,
    /// A timestamp query to write when the pass is done.
    pub timestamp: Option<(vk::QueryPool, u32)>,
}

impl<'a> Pass<'a> {
    pub fn new(name: &'static str, uses: Vec<Use>, record: impl FnOnce(vk::CommandBuffer) + 'a) -> Self {
        Pass { name, uses, record: Box::new(record), timestamp: None }
    }
}

/// Records `passes` in order, each after the barrier its uses need.
pub fn run_passes(ctx: &Context, cmd: vk::CommandBuffer, states: &mut ResourceStates, passes: Vec<Pass>) {
    for pass in passes {
        let barriers = states.barriers(&pass.uses);
        if !barriers.images.is_empty() || !barriers.buffers.is_empty() {
            let info = vk::DependencyInfo::default()
                .image_memory_barriers(&barriers.images)
                .buffer_memory_barriers(&barriers.buffers);
            // SAFETY: `cmd` is recording outside a render pass instance; every handle in the
            // barriers belongs to this device and is alive while the command buffer is pending.
            unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &info) };
        }
        ctx.begin_label(cmd, pass.name);
        (pass.record)(cmd);
        ctx.end_label(cmd);
        if let Some((pool, query)) = pass.timestamp {
            // SAFETY: the pool was reset for this frame; `query` is in range.
            unsafe { ctx.device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, pool, query) };
        }
    }
}

/// The passes that copy `image` into `buffer` and make the copy visible to the host, for a
/// frame list.
pub fn read_back_passes<'a>(ctx: &'a Context, image: &'a Image, buffer: &'a Buffer) -> [Pass<'a>; 2] {
    let copy = Pass::new(
        "read-back copy",
        vec![Use::image(image, Access::TRANSFER_READ), Use::buffer(buffer, Access::TRANSFER_WRITE)],
        move |cmd| copy_to_buffer(ctx, cmd, image, buffer),
    );
    let host = Pass::new("read-back to host", vec![Use::buffer(buffer, Access::HOST_READ)], |_| {});
    [copy, host]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(n: u64) -> Resource {
        Resource::Image { raw: vk::Handle::from_raw(n), aspect: vk::ImageAspectFlags::COLOR, texel_bytes: 16 }
    }

    #[test]
    fn first_write_transitions_then_reads_wait_once() {
        let mut states = ResourceStates::default();
        let img = image(1);
        let write = states.barriers(&[Use { resource: img, access: Access::COMPUTE_WRITE }]);
        assert_eq!(write.images.len(), 1, "UNDEFINED -> GENERAL");
        let read = states.barriers(&[Use { resource: img, access: Access::COMPUTE_READ }]);
        assert_eq!(read.images.len(), 1, "read after write waits");
        assert_eq!(read.images[0].src_access_mask, vk::AccessFlags2::SHADER_STORAGE_WRITE);
        let again = states.barriers(&[Use { resource: img, access: Access::COMPUTE_READ }]);
        assert!(again.images.is_empty(), "a second read of the same kind is already ordered");
        let rewrite = states.barriers(&[Use { resource: img, access: Access::COMPUTE_WRITE }]);
        assert_eq!(rewrite.images.len(), 1, "write after read waits for the read");
        assert_eq!(rewrite.images[0].src_stage_mask, vk::PipelineStageFlags2::COMPUTE_SHADER);
    }

    #[test]
    fn layout_change_and_host_read() {
        let mut states = ResourceStates::default();
        let img = image(2);
        let buf = Resource::Buffer(vk::Handle::from_raw(3));
        states.barriers(&[Use { resource: img, access: Access::COMPUTE_WRITE }]);
        let copy = states.barriers(&[
            Use { resource: img, access: Access::TRANSFER_READ },
            Use { resource: buf, access: Access::TRANSFER_WRITE },
        ]);
        assert_eq!(copy.images[0].old_layout, vk::ImageLayout::GENERAL);
        assert_eq!(copy.images[0].new_layout, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
        assert!(copy.buffers.is_empty(), "nothing used the buffer before");
        let host = states.barriers(&[Use { resource: buf, access: Access::HOST_READ }]);
        assert_eq!(host.buffers.len(), 1);
        assert_eq!(host.buffers[0].dst_stage_mask, vk::PipelineStageFlags2::HOST);
    }
}
