//! The user-interface pass against blending worked out by hand: two frames over a display
//! image, with a texture made whole and then changed in one texel, draws clipped to a
//! rectangle, points twice as large as pixels, and premultiplied alpha over the image.

mod common;

use common::{finish_clean, gpu};
use rrf::shaders;
use rrf_renderer::backend::sync::{run_passes, ResourceStates};
use rrf_renderer::passes::ui::{UiDraw, UiFrame, UiPass, UiTexels, UiVertex};
use rrf_renderer::{vk, Destroy};

const W: u32 = 40;
const H: u32 = 30;
/// The texture both frames sample.
const TEXTURE: u64 = 7;

/// Two triangles covering `[x0, x1) × [y0, y1)` points, of one `colour`, sampling `uv`.
fn quad(vertices: &mut Vec<UiVertex>, indices: &mut Vec<u32>, [x0, y0, x1, y1]: [f32; 4], uv: f32, colour: [u8; 4]) {
    let base = vertices.len() as u32;
    for (x, y) in [(x0, y0), (x1, y0), (x1, y1), (x0, y1)] {
        vertices.push(UiVertex { pos: [x, y], uv: [uv, uv], colour });
    }
    indices.extend([0, 1, 2, 0, 2, 3].map(|i| i + base));
}

fn rect(x: i32, y: i32, width: u32, height: u32) -> vk::Rect2D {
    vk::Rect2D { offset: vk::Offset2D { x, y }, extent: vk::Extent2D { width, height } }
}

#[test]
fn ui_draws_blend_over_the_display_as_premultiplied_alpha() {
    let ctx = gpu();
    let extent = vk::Extent2D { width: W, height: H };
    let usage =
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::COLOR_ATTACHMENT;
    let display = ctx.create_image("display", extent, vk::Format::R8G8B8A8_UNORM, usage).unwrap();
    let mut pass = UiPass::new(&ctx, shaders::UI_VERT, shaders::UI_FRAG).unwrap();
    let mut states = ResourceStates::default();
    // The screen is 20 × 15 points: two pixels per point.
    let screen_points = [W as f32 / 2.0, H as f32 / 2.0];

    // Frame 1: a 2 × 2 white texture, and an opaque quad over the whole screen (whose
    // contents were undefined).
    let (mut vertices, mut indices) = (Vec::new(), Vec::new());
    quad(&mut vertices, &mut indices, [0.0, 0.0, 20.0, 15.0], 0.25, [10, 20, 30, 255]);
    let first = UiFrame {
        screen_points,
        texels: vec![UiTexels { texture: TEXTURE, offset: None, size: [2, 2], rgba: vec![255; 16] }],
        draws: vec![UiDraw {
            texture: TEXTURE,
            clip: rect(0, 0, W, H),
            first_index: 0,
            index_count: 6,
            vertex_offset: 0,
        }],
        vertices,
        indices,
        freed: vec![],
    };
    // Frame 2: texel (1, 1) turns red; a half-transparent red quad over x 5..15, y 3..12
    // points, clipped to the left half of the screen; an opaque white quad tinted by the red
    // texel over the bottom three points.
    let (mut vertices, mut indices) = (Vec::new(), Vec::new());
    quad(&mut vertices, &mut indices, [5.0, 3.0, 15.0, 12.0], 0.25, [100, 0, 0, 128]);
    quad(&mut vertices, &mut indices, [0.0, 12.0, 20.0, 15.0], 0.75, [255, 255, 255, 255]);
    let second = UiFrame {
        screen_points,
        texels: vec![UiTexels { texture: TEXTURE, offset: Some([1, 1]), size: [1, 1], rgba: vec![255, 0, 0, 255] }],
        draws: vec![
            UiDraw { texture: TEXTURE, clip: rect(0, 0, W / 2, H), first_index: 0, index_count: 6, vertex_offset: 0 },
            // Indices of the second quad count from its own first vertex.
            UiDraw { texture: TEXTURE, clip: rect(-5, 0, W + 10, H), first_index: 6, index_count: 6, vertex_offset: 0 },
        ],
        vertices,
        indices,
        freed: vec![],
    };
    for (slot, frame) in [first, second].iter().enumerate() {
        for image in pass.prepare(&ctx, slot, frame, &mut || Ok(())).unwrap() {
            states.forget(image);
        }
        let passes = pass.passes(&ctx, &display, slot, frame).unwrap();
        ctx.submit_once(|cmd| run_passes(&ctx, cmd, &mut states, passes)).unwrap();
        pass.submitted().destroy(&ctx);
    }
    let out = ctx.read_image(&display, vk::ImageLayout::GENERAL).unwrap();

    let base = [10.0, 20.0, 30.0].map(|c| c / 255.0);
    let alpha = 128.0 / 255.0;
    let blended = [100.0 / 255.0 + base[0] * (1.0 - alpha), base[1] * (1.0 - alpha), base[2] * (1.0 - alpha)];
    for y in 0..H {
        for x in 0..W {
            let want = if y >= 24 {
                [1.0, 0.0, 0.0]
            } else if (10..20).contains(&x) && (6..24).contains(&y) {
                blended
            } else {
                base
            };
            let i = 4 * (y * W + x) as usize;
            for c in 0..3 {
                let got = out[i + c];
                // 8-bit storage of the blend, plus float slack.
                assert!(
                    (got - want[c]).abs() <= 1.0 / 255.0 + 1e-4,
                    "pixel ({x}, {y}) channel {c}: {got}, want {}",
                    want[c]
                );
            }
        }
    }

    pass.destroy(&ctx);
    ctx.destroy_image(display);
    finish_clean(ctx);
}
