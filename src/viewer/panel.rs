//! The walkthrough's settings panel (egui): the lights, the component shown, the exposure,
//! where direct light comes from, outlines of the trained boxes, and a graph of GPU time per
//! pass. egui lays it out and tessellates it; the renderer's UI pass draws the triangles
//! ([`rrf_renderer::passes::ui`]).

use egui::epaint::{ImageDelta, Primitive};
use egui::{Color32, Pos2, Rect, Stroke, TextureId};
use rrf_baker::glam::Vec3;
use rrf_baker::scene::Aabb;
use rrf_renderer::frame::{Shown, TIMED_PASSES};
use rrf_renderer::passes::ui::{UiDraw, UiFrame, UiTexels, UiVertex};
use rrf_renderer::vk;

use super::state::ViewerState;
use crate::frame_stats::Stats;
use crate::lights::MAX_INTENSITY;
use crate::parse::MAX_EXPOSURE;

/// Frames the GPU graph shows.
const GRAPH_FRAMES: usize = 120;
/// The panel's width in points.
const WIDTH: f32 = 270.0;
/// Colours of the timed passes in the graph, in [`TIMED_PASSES`] order.
const PASS_COLOURS: [Color32; TIMED_PASSES.len()] = [
    Color32::from_rgb(90, 160, 230),
    Color32::from_rgb(170, 120, 220),
    Color32::from_rgb(240, 170, 60),
    Color32::from_rgb(110, 200, 120),
    Color32::from_rgb(200, 200, 200),
];
/// The light's trained box and the camera's, as the outlines draw them.
const LIGHT_BOX_COLOUR: Color32 = Color32::from_rgb(255, 210, 60);
const CAMERA_BOX_COLOUR: Color32 = Color32::from_rgb(80, 200, 255);

/// What the panel needs to know of the frame.
pub struct FrameFacts {
    /// Column-major, to Vulkan clip space: for the box outlines.
    pub view_projection: [[f32; 4]; 4],
    /// Whether the device writes timestamps, for GPU time per pass.
    pub timed: bool,
    /// Whether the scene has mirrors, whose pass the graph then lists.
    pub mirrors: bool,
}

/// The panel's own settings and egui's state.
pub struct Panel {
    ctx: egui::Context,
    /// Whether the panel shows (the `U` key).
    pub shown: bool,
    /// Whether the trained boxes are outlined over the frame.
    pub boxes: bool,
    /// Where the panel's left edge was in the last frame, in points from the screen's left
    /// (the screen's width when it is hidden).
    left_edge: f32,
}

impl Panel {
    pub fn new(shown: bool) -> Self {
        let ctx = egui::Context::default();
        // One layout pass a frame: a second would apply a click's edit twice.
        ctx.options_mut(|o| o.max_passes = std::num::NonZeroUsize::MIN);
        Panel { ctx, shown, boxes: false, left_edge: f32::INFINITY }
    }

    /// Where the panel's left edge was in the last frame, in points from the screen's left;
    /// infinite when it was hidden.
    pub fn left_edge(&self) -> f32 {
        self.left_edge
    }

    /// egui's context, for the window's input translation (`egui-winit`).
    pub fn context(&self) -> &egui::Context {
        &self.ctx
    }

    /// Lays out one frame of the panel from `input`, applying what the user changed to
    /// `state`. Returns what to draw and egui's requests to the window (cursor shape).
    pub fn run(
        &mut self,
        input: egui::RawInput,
        state: &mut ViewerState,
        stats: &Stats,
        frame: &FrameFacts,
    ) -> (UiFrame, egui::PlatformOutput) {
        let mut left_edge = f32::INFINITY;
        let output = self.ctx.run_ui(input, |ui| {
            if self.boxes {
                outline_boxes(ui.ctx(), state, &frame.view_projection);
            }
            if self.shown {
                let panel = egui::Panel::right("settings").resizable(false).exact_size(WIDTH).show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| settings(ui, state, stats, frame, &mut self.boxes));
                });
                left_edge = panel.response.rect.left();
            }
        });
        self.left_edge = left_edge;
        let primitives = self.ctx.tessellate(output.shapes, output.pixels_per_point);
        let screen = self.ctx.content_rect().size();
        let mut frame = ui_frame(&primitives, output.pixels_per_point, [screen.x, screen.y]);
        frame.texels =
            output.textures_delta.set.iter().flat_map(|(id, deltas)| deltas.iter().map(|d| texels(*id, d))).collect();
        frame.freed = output.textures_delta.free.iter().map(|id| texture_number(*id)).collect();
        (frame, output.platform_output)
    }
}

/// The panel's sections.
fn settings(ui: &mut egui::Ui, state: &mut ViewerState, stats: &Stats, frame: &FrameFacts, boxes: &mut bool) {
    let (fps, frame_ms) = stats.recent_rate();
    ui.heading(format!("rrf: {}", state.scene_name));
    ui.label(format!("{fps:.1} fps, {frame_ms:.1} ms per frame"));
    egui::CollapsingHeader::new("Lights").default_open(true).show(ui, |ui| lights(ui, state));
    egui::CollapsingHeader::new("Image").default_open(true).show(ui, |ui| {
        ui.horizontal(|ui| {
            for shown in [Shown::Gi, Shown::Direct, Shown::Indirect] {
                ui.radio_value(&mut state.shown, shown, shown.name());
            }
        });
        ui.add_enabled(
            !state.auto_exposure,
            egui::Slider::new(&mut state.exposure, -MAX_EXPOSURE..=MAX_EXPOSURE).step_by(0.1).text("exposure, EV"),
        );
        ui.checkbox(&mut state.auto_exposure, "automatic exposure")
            .on_hover_text("Keeps the frame's median pixel at mid-grey, as a camera's meter does.");
    });
    egui::CollapsingHeader::new("GPU time per pass").default_open(true).show(ui, |ui| match frame.timed {
        true => gpu_graph(ui, stats, frame.mirrors),
        false => drop(ui.label("This device writes no timestamps.")),
    });
    egui::CollapsingHeader::new("Direct light").default_open(true).show(ui, |ui| {
        for (mode, allowed) in state.direct_choices.clone() {
            let choice =
                ui.add_enabled(allowed.is_ok(), egui::RadioButton::new(state.direct == mode, mode.description()));
            if choice.clicked() {
                state.direct = mode;
            }
            if let Err(why) = allowed {
                choice.on_disabled_hover_text(why);
            }
        }
    });
    egui::CollapsingHeader::new("Trained boxes").default_open(true).show(ui, |ui| {
        ui.checkbox(boxes, "outline them over the frame");
        ui.horizontal(|ui| {
            swatch(ui, LIGHT_BOX_COLOUR);
            ui.label("the light's");
            swatch(ui, CAMERA_BOX_COLOUR);
            ui.label("the camera's");
        });
        if state.camera_outside_box() {
            ui.colored_label(Color32::YELLOW, "The camera is outside its box: expect errors.");
        }
    });
    ui.separator();
    ui.label("U hides this panel; H lists the keys.");
}

/// The lights: which is selected, adding and removing, position, colour and intensity.
fn lights(ui: &mut egui::Ui, state: &mut ViewerState) {
    ui.horizontal_wrapped(|ui| {
        for i in 0..state.lights.len() {
            if ui.selectable_label(state.selected == i, format!("light {}", i + 1)).clicked() {
                state.key_edit(|s| s.select_light(i));
            }
        }
    });
    let editable = state.fixed_lights().is_none();
    ui.horizontal(|ui| {
        let can_add = editable && state.lights.len() < crate::lights::MAX_LIGHTS;
        if ui.add_enabled(can_add, egui::Button::new("add")).on_hover_text("a copy of the selected light").clicked() {
            state.key_edit(ViewerState::duplicate_light);
        }
        if ui.add_enabled(state.lights.len() > 1, egui::Button::new("remove")).clicked() {
            state.key_edit(ViewerState::remove_light);
        }
    });
    let mut position = state.light().position;
    let range = state.light_box().unwrap_or(Aabb { min: Vec3::splat(-1e3), max: Vec3::splat(1e3) });
    let mut moved = false;
    for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
        let slider = egui::Slider::new(&mut position[axis], range.min[axis]..=range.max[axis]).text(name);
        moved |= ui.add(slider).changed();
    }
    if moved {
        state.move_light(position);
    }
    if state.light_at_edge {
        ui.colored_label(Color32::YELLOW, "at the edge of its trained box");
    }
    let scale = state.light().scale;
    let mut intensity = scale.max_element();
    let mut colour = if intensity > 0.0 { (scale / intensity).to_array() } else { [1.0; 3] };
    ui.add_enabled_ui(editable, |ui| {
        let mut changed = false;
        ui.horizontal(|ui| {
            changed |= egui::color_picker::color_edit_button_rgb(ui, &mut colour).changed();
            ui.label("colour");
        });
        let slider = egui::Slider::new(&mut intensity, 0.0..=MAX_INTENSITY).logarithmic(true).text("intensity");
        changed |= ui.add(slider).changed();
        if changed {
            state.key_edit(|s| s.set_light_scale(Vec3::from(colour) * intensity));
        }
    });
    if let Some(why) = state.fixed_lights() {
        ui.label(format!("Lights cannot be added, recoloured or dimmed: {why}"));
    }
    if let Some(note) = &state.light_note {
        ui.colored_label(Color32::YELLOW, note);
    }
}

/// A small square of `colour`, for a legend.
fn swatch(ui: &mut egui::Ui, colour: Color32) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(10.0, 10.0), egui::Sense::hover());
    ui.painter().rect_filled(rect, 0.0, colour);
}

/// The GPU milliseconds of each timed pass over the last frames, stacked, newest on the right;
/// the mirrors' pass only in a scene with `mirrors`.
fn gpu_graph(ui: &mut egui::Ui, stats: &Stats, mirrors: bool) {
    let frames = stats.gpu_ms[0].len();
    if frames == 0 {
        ui.label("Timings arrive when the first frames have finished.");
        return;
    }
    let first = frames.saturating_sub(GRAPH_FRAMES);
    let totals: Vec<f64> = (first..frames).map(|f| stats.gpu_ms.iter().map(|ms| ms[f]).sum()).collect();
    // The scale: the largest frame, rounded up to 1, 2, 2.5 or 5 times a power of ten.
    let top = nice_ceiling(totals.iter().copied().fold(0.0, f64::max));
    let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width(), 60.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, Color32::from_gray(20));
    let bar = rect.width() / GRAPH_FRAMES as f32;
    for (i, f) in (first..frames).enumerate() {
        let x = rect.right() - (frames - first - i) as f32 * bar;
        let mut y = rect.bottom();
        for (k, ms) in stats.gpu_ms.iter().enumerate() {
            let h = (ms[f] / top) as f32 * rect.height();
            painter.rect_filled(Rect::from_min_max(Pos2::new(x, y - h), Pos2::new(x + bar, y)), 0.0, PASS_COLOURS[k]);
            y -= h;
        }
    }
    painter.text(
        rect.left_top() + egui::vec2(3.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("{top} ms"),
        egui::FontId::monospace(10.0),
        Color32::WHITE,
    );
    let recent = stats.recent_gpu_ms();
    for (k, name) in TIMED_PASSES.iter().enumerate().filter(|(_, name)| mirrors || **name != "mirrors") {
        ui.horizontal(|ui| {
            swatch(ui, PASS_COLOURS[k]);
            ui.label(format!("{name}: {:.2} ms", recent[k]));
        });
    }
}

/// The smallest of 1, 2, 2.5 and 5 times a power of ten that is at least `x`.
fn nice_ceiling(x: f64) -> f64 {
    let x = x.max(1e-3);
    let decade = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0].into_iter().map(|m| m * decade).find(|v| *v >= x * (1.0 - 1e-9)).unwrap_or(10.0 * decade)
}

/// Outlines the light's and the camera's trained boxes over the frame, behind the panel.
fn outline_boxes(ctx: &egui::Context, state: &ViewerState, m: &[[f32; 4]; 4]) {
    let screen = ctx.content_rect();
    let painter = ctx.layer_painter(egui::LayerId::background());
    for (b, colour) in [(state.light_box(), LIGHT_BOX_COLOUR), (state.camera_box(), CAMERA_BOX_COLOUR)] {
        let Some(b) = b else { continue };
        for [p, q] in box_edges(&b) {
            if let Some([a, c]) = project_segment(m, p, q, screen) {
                painter.line_segment([a, c], Stroke::new(1.5, colour));
            }
        }
    }
}

/// The twelve edges of a box.
fn box_edges(b: &Aabb) -> Vec<[Vec3; 2]> {
    let corner = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    };
    let mut edges = Vec::with_capacity(12);
    for i in 0..8 {
        for axis in [1, 2, 4] {
            if i & axis == 0 {
                edges.push([corner(i), corner(i | axis)]);
            }
        }
    }
    edges
}

/// The segment from `p` to `q` on a screen of `screen` points, through the view-projection
/// `m` (column-major, Vulkan clip space: y down); the part in front of the camera, or `None`.
fn project_segment(m: &[[f32; 4]; 4], p: Vec3, q: Vec3, screen: Rect) -> Option<[Pos2; 2]> {
    let clip = |v: Vec3| -> [f32; 4] {
        let v = [v.x, v.y, v.z, 1.0];
        std::array::from_fn(|row| (0..4).map(|col| m[col][row] * v[col]).sum())
    };
    let (mut a, mut b) = (clip(p), clip(q));
    // Cut at a small positive w, so that nothing behind the camera is drawn.
    const NEAR_W: f32 = 1e-3;
    if a[3] < NEAR_W && b[3] < NEAR_W {
        return None;
    }
    if a[3] < NEAR_W || b[3] < NEAR_W {
        let t = (NEAR_W - a[3]) / (b[3] - a[3]);
        let cut: [f32; 4] = std::array::from_fn(|k| a[k] + t * (b[k] - a[k]));
        if a[3] < NEAR_W {
            a = cut;
        } else {
            b = cut;
        }
    }
    let to_screen = |c: [f32; 4]| {
        Pos2::new(
            screen.left() + (c[0] / c[3] * 0.5 + 0.5) * screen.width(),
            screen.top() + (c[1] / c[3] * 0.5 + 0.5) * screen.height(),
        )
    };
    Some([to_screen(a), to_screen(b)])
}

/// egui's texture ids as the UI pass numbers textures (user textures are not used).
fn texture_number(id: TextureId) -> u64 {
    match id {
        TextureId::Managed(n) => n,
        TextureId::User(n) => n | 1 << 63,
    }
}

/// One texture change for the UI pass.
fn texels(id: TextureId, delta: &ImageDelta) -> UiTexels {
    let egui::ImageData::Color(image) = &delta.image;
    UiTexels {
        texture: texture_number(id),
        offset: delta.pos.map(|[x, y]| [x as u32, y as u32]),
        size: [image.width() as u32, image.height() as u32],
        rgba: bytemuck::cast_slice(&image.pixels).to_vec(),
    }
}

/// egui's tessellated meshes as the UI pass's vertices, indices and draws, with clip
/// rectangles in pixels.
fn ui_frame(primitives: &[egui::ClippedPrimitive], pixels_per_point: f32, screen_points: [f32; 2]) -> UiFrame {
    let mut frame = UiFrame { screen_points, ..UiFrame::default() };
    for primitive in primitives {
        let Primitive::Mesh(mesh) = &primitive.primitive else { continue };
        if mesh.indices.is_empty() {
            continue;
        }
        let c = primitive.clip_rect;
        let (x0, y0) = ((c.min.x * pixels_per_point).round(), (c.min.y * pixels_per_point).round());
        let (x1, y1) = ((c.max.x * pixels_per_point).round(), (c.max.y * pixels_per_point).round());
        let clip = vk::Rect2D {
            offset: vk::Offset2D { x: x0 as i32, y: y0 as i32 },
            extent: vk::Extent2D { width: (x1 - x0).max(0.0) as u32, height: (y1 - y0).max(0.0) as u32 },
        };
        frame.draws.push(UiDraw {
            texture: texture_number(mesh.texture_id),
            clip,
            first_index: frame.indices.len() as u32,
            index_count: mesh.indices.len() as u32,
            vertex_offset: frame.vertices.len() as i32,
        });
        frame.indices.extend_from_slice(&mesh.indices);
        frame.vertices.extend(mesh.vertices.iter().map(|v| UiVertex {
            pos: [v.pos.x, v.pos.y],
            uv: [v.uv.x, v.uv.y],
            colour: v.color.to_array(),
        }));
    }
    frame
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn graph_scale_is_one_two_two_and_a_half_or_five_times_a_power_of_ten() {
        assert_eq!(nice_ceiling(0.7), 1.0);
        assert_eq!(nice_ceiling(1.0), 1.0);
        assert_eq!(nice_ceiling(1.2), 2.0);
        assert_eq!(nice_ceiling(2.2), 2.5);
        assert_eq!(nice_ceiling(37.0), 50.0);
        assert_eq!(nice_ceiling(60.0), 100.0);
    }

    #[test]
    fn a_segment_behind_the_camera_is_cut_at_its_plane() {
        // Clip space = world space with w = z: the camera looks down +z.
        let m = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]];
        let screen = Rect::from_min_size(Pos2::ZERO, egui::vec2(200.0, 100.0));
        let [a, b] = project_segment(&m, Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.5, 1.0), screen).unwrap();
        assert_eq!((a, b), (Pos2::new(100.0, 50.0), Pos2::new(200.0, 75.0)));
        assert!(project_segment(&m, Vec3::new(0.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -2.0), screen).is_none());
        let [a, b] = project_segment(&m, Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0), screen).unwrap();
        assert!(a.x == 100.0 && b == Pos2::new(100.0, 50.0));
        assert_eq!(box_edges(&Aabb { min: Vec3::ZERO, max: Vec3::ONE }).len(), 12);
    }

    #[test]
    fn egui_meshes_become_draws_with_their_own_vertex_offsets_and_pixel_clips() {
        let mut mesh = egui::Mesh::with_texture(TextureId::Managed(3));
        mesh.colored_vertex(Pos2::new(1.0, 2.0), Color32::RED);
        mesh.colored_vertex(Pos2::new(3.0, 2.0), Color32::RED);
        mesh.colored_vertex(Pos2::new(1.0, 4.0), Color32::RED);
        mesh.add_triangle(0, 1, 2);
        let clip = Rect::from_min_max(Pos2::new(0.5, 1.0), Pos2::new(10.0, 20.0));
        let primitive = egui::ClippedPrimitive { clip_rect: clip, primitive: Primitive::Mesh(mesh) };
        let frame = ui_frame(&[primitive.clone(), primitive], 2.0, [100.0, 50.0]);
        assert_eq!(frame.vertices.len(), 6);
        assert_eq!(frame.indices, vec![0, 1, 2, 0, 1, 2]);
        assert_eq!(frame.draws[1].first_index, 3);
        assert_eq!(frame.draws[1].vertex_offset, 3);
        assert_eq!(frame.draws[0].texture, 3);
        assert_eq!(frame.draws[0].clip.offset, vk::Offset2D { x: 1, y: 2 });
        assert_eq!(frame.draws[0].clip.extent, vk::Extent2D { width: 19, height: 38 });
        assert_eq!(frame.vertices[0].colour, [255, 0, 0, 255]);
    }
}
