//! The on-screen overlay: lines of text drawn by the GPU over the display image
//! (`overlay.comp`), in an 8×8 bitmap font that the caller supplies.

use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;

use crate::backend::compute::{Bind, ComputePass};
use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::resources::{Buffer, Image};
use crate::backend::sync::{Access, Pass, Use};
use crate::error::Result;

/// Characters per line and lines of the overlay.
pub const COLUMNS: u32 = 96;
pub const ROWS: u32 = 24;

/// Colours of the overlay's palette (`overlay.comp`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colour {
    White = 0,
    Yellow = 1,
    Red = 2,
    Blue = 3,
}

/// What the overlay shows: a grid of cells, each a character and a colour; empty cells are
/// transparent.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextGrid {
    cells: Vec<u32>,
    next_row: u32,
}

impl Default for TextGrid {
    fn default() -> Self {
        TextGrid { cells: vec![0; (COLUMNS * ROWS) as usize], next_row: 0 }
    }
}

impl TextGrid {
    /// Appends a line (cut at [`COLUMNS`]; non-ASCII characters show as `?`). Lines past
    /// [`ROWS`] are dropped.
    pub fn line(&mut self, text: &str, colour: Colour) {
        if self.next_row >= ROWS {
            return;
        }
        let start = (self.next_row * COLUMNS) as usize;
        // A space before and after makes the darkened box frame the text.
        let padded = format!(" {text} ");
        for (cell, ch) in self.cells[start..start + COLUMNS as usize].iter_mut().zip(padded.chars()) {
            let ch = if ch.is_ascii() && !ch.is_ascii_control() { ch as u32 } else { u32::from(b'?') };
            *cell = ch | (colour as u32) << 8;
        }
        self.next_row += 1;
    }

    /// The lines written so far, as text (for tests and logs).
    pub fn text(&self) -> String {
        self.cells
            .chunks(COLUMNS as usize)
            .take(self.next_row as usize)
            .map(|row| {
                row.iter()
                    .map(|&c| char::from((c & 0x7f) as u8))
                    .collect::<String>()
                    .trim_matches(['\0', ' '])
                    .to_string()
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    origin: [i32; 2],
    columns: u32,
    rows: u32,
    scale: u32,
}

pub struct OverlayPass {
    pass: ComputePass,
    glyphs: Buffer,
    /// The grid on the device, rewritten by each frame's command buffer.
    text: Buffer,
}

impl OverlayPass {
    /// `spirv` is `overlay.comp`; `font` holds the 128 ASCII glyphs, one byte per row with
    /// bit 0 the leftmost pixel; `display` is the RGBA8 storage image the text goes on.
    pub fn new(ctx: &Context, spirv: &[u32], font: &[[u8; 8]; 128], display: &Image) -> Result<Self> {
        let words: Vec<u32> = font
            .iter()
            .flat_map(|g| [u32::from_le_bytes([g[0], g[1], g[2], g[3]]), u32::from_le_bytes([g[4], g[5], g[6], g[7]])])
            .collect();
        let glyphs = ctx.guard(ctx.create_buffer_with_data(
            "overlay glyphs",
            bytemuck::cast_slice(&words),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?);
        let text = ctx.guard(ctx.create_buffer(
            "overlay text",
            u64::from(COLUMNS * ROWS * 4),
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?);
        let bindings = [Bind::StorageImage(display), Bind::StorageBuffer(&glyphs), Bind::StorageBuffer(&text)];
        let pass = ComputePass::new(ctx, "overlay", spirv, &bindings, std::mem::size_of::<Push>() as u32, (8, 8))?;
        Ok(OverlayPass { pass, glyphs: glyphs.keep(), text: text.keep() })
    }

    /// Points the pass at another display image (after a resize); no frame that uses it may
    /// be pending.
    pub fn rebind(&self, ctx: &Context, display: &Image) {
        self.pass.rebind(
            ctx,
            &[Bind::StorageImage(display), Bind::StorageBuffer(&self.glyphs), Bind::StorageBuffer(&self.text)],
        );
    }

    /// The passes that upload `grid` and draw it over `display` at `scale` screen pixels per
    /// font pixel, from the top-left corner.
    pub fn passes<'a>(&'a self, ctx: &'a Context, display: &Image, grid: &TextGrid, scale: u32) -> [Pass<'a>; 2] {
        let cells = grid.cells.clone();
        let upload =
            Pass::new("overlay text upload", vec![Use::buffer(&self.text, Access::TRANSFER_WRITE)], move |cmd| {
                // SAFETY: recording outside a render pass; COLUMNS × ROWS × 4 bytes, under
                // vkCmdUpdateBuffer's 64 KiB, and the buffer is that size.
                unsafe { ctx.device.cmd_update_buffer(cmd, self.text.raw, 0, bytemuck::cast_slice(&cells)) };
            });
        let scale = scale.max(1);
        let margin = 4 * scale as i32;
        let push = Push { origin: [margin, margin], columns: COLUMNS, rows: ROWS, scale };
        let uses = vec![
            Use::image(display, Access::COMPUTE_READ_WRITE),
            Use::buffer(&self.glyphs, Access::COMPUTE_READ),
            Use::buffer(&self.text, Access::COMPUTE_READ),
        ];
        let (width, height) = (COLUMNS * 8 * scale, ROWS * 8 * scale);
        let draw = Pass::new("overlay", uses, move |cmd| {
            self.pass.record(ctx, cmd, bytemuck::bytes_of(&push), width, height);
        });
        [upload, draw]
    }

    pub fn destroy(self, ctx: &Context) {
        self.pass.destroy(ctx);
        ctx.destroy_buffer(self.glyphs);
        ctx.destroy_buffer(self.text);
    }
}

impl Destroy for OverlayPass {
    fn destroy(self, ctx: &Context) {
        OverlayPass::destroy(self, ctx);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_padded_cut_and_coloured() {
        let mut grid = TextGrid::default();
        grid.line("fps 60", Colour::White);
        grid.line(&"x".repeat(200), Colour::Red);
        grid.line("ü", Colour::White);
        assert_eq!(grid.cells[0], u32::from(b' '));
        assert_eq!(grid.cells[1], u32::from(b'f'));
        assert_eq!(grid.cells[COLUMNS as usize + 1] >> 8, Colour::Red as u32);
        assert_eq!(grid.text(), format!("fps 60\n{}\n?", "x".repeat(COLUMNS as usize - 1)));
        for _ in 0..ROWS {
            grid.line("more", Colour::White);
        }
        assert_eq!(grid.text().lines().count(), ROWS as usize);
    }
}
