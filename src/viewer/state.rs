//! What the viewer shows and how input and scripts change it, apart from any window: the fly
//! camera, the lights inside their trained box (added, selected, moved, recoloured, dimmed and
//! removed), the component, the exposure, and the overlay text.

use anyhow::{bail, Result};
use rrf_baker::glam::Vec3;
use rrf_baker::scene::{Aabb, PlacedLight, Scene, View};
use rrf_renderer::frame::{Shown, TIMED_PASSES};
use rrf_renderer::passes::overlay::{Colour, TextGrid};

use super::controls::help_lines;
use super::script::Action;
use crate::direct_mode::DirectMode;
use crate::frame_stats::Stats;
use crate::lights::{fixed_lights, MAX_INTENSITY, MAX_LIGHTS};
use crate::parse::MAX_EXPOSURE;
use crate::scene_frame::FrameSettings;

/// Keys that act for as long as they are held.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Held {
    Forward,
    Back,
    Left,
    Right,
    Down,
    Up,
    Fast,
    LightLeft,
    LightRight,
    LightForward,
    LightBack,
    LightDown,
    LightUp,
}

/// A linear move of two points over a span of time.
#[derive(Clone, Copy, Debug)]
struct Tween {
    from: [Vec3; 2],
    to: [Vec3; 2],
    start: f64,
    seconds: f64,
}

impl Tween {
    fn at(&self, t: f64) -> ([Vec3; 2], bool) {
        let s = if self.seconds > 0.0 { ((t - self.start) / self.seconds).clamp(0.0, 1.0) } else { 1.0 } as f32;
        ([self.from[0].lerp(self.to[0], s), self.from[1].lerp(self.to[1], s)], s >= 1.0)
    }
}

pub struct ViewerState {
    pub scene_name: String,
    /// The view and lights the viewer starts from and `R` returns to.
    home: View,
    home_lights: Vec<PlacedLight>,
    pub eye: Vec3,
    yaw: f32,
    pitch: f32,
    pub fov_y: f32,
    /// Camera speed in metres per second.
    pub speed: f32,
    /// Copies of the moving light, at least one; the arrows move the selected one.
    pub lights: Vec<PlacedLight>,
    pub selected: usize,
    /// Why lights cannot be added, recoloured or dimmed in this scene, if they cannot.
    fixed_lights: Option<String>,
    /// What the last light edit from a key said (a refusal), for the overlay.
    pub light_note: Option<String>,
    light_box: Option<Aabb>,
    camera_box: Option<Aabb>,
    /// Whether the last light move was stopped by the edge of its box.
    pub light_at_edge: bool,
    pub shown: Shown,
    pub exposure: f32,
    /// Whether the exposure follows the frame's brightness (`super::exposure`).
    pub auto_exposure: bool,
    pub overlay: bool,
    pub help: bool,
    /// Where direct light comes from (the panel can change it).
    pub direct: DirectMode,
    /// The modes the panel offers, each with why it cannot be chosen, if it cannot.
    pub direct_choices: Vec<(DirectMode, Result<(), String>)>,
    camera_tween: Option<Tween>,
    light_tween: Option<Tween>,
}

fn yaw_pitch(forward: Vec3) -> (f32, f32) {
    let f = forward.normalize_or(Vec3::Z);
    (f.x.atan2(f.z), f.y.clamp(-1.0, 1.0).asin())
}

impl ViewerState {
    /// The viewer of `scene` from `view`, lit by `lights` (checked with
    /// `lights::check_lights`).
    pub fn new(scene: &Scene, view: View, lights: Vec<PlacedLight>) -> Self {
        let (yaw, pitch) = yaw_pitch(view.target - view.eye);
        let bounds = scene.bounds();
        let light_box = scene.moving_light.as_ref().map(|l| l.bounds);
        let mut state = ViewerState {
            scene_name: scene.name.clone(),
            eye: view.eye,
            yaw,
            pitch,
            fov_y: view.fov_y,
            speed: (bounds.max - bounds.min).length().max(1e-3) * 0.25,
            lights: lights.clone(),
            selected: 0,
            fixed_lights: fixed_lights(scene),
            light_note: None,
            light_box,
            camera_box: scene.camera_box,
            light_at_edge: false,
            shown: Shown::Gi,
            exposure: 0.0,
            auto_exposure: false,
            overlay: true,
            help: true,
            direct: DirectMode::Learned,
            direct_choices: Vec::new(),
            camera_tween: None,
            light_tween: None,
            home: view,
            home_lights: lights,
        };
        state.reset();
        state
    }

    pub fn forward(&self) -> Vec3 {
        Vec3::new(self.pitch.cos() * self.yaw.sin(), self.pitch.sin(), self.pitch.cos() * self.yaw.cos())
    }

    pub fn view(&self) -> View {
        View { name: "viewer".into(), eye: self.eye, target: self.eye + self.forward(), up: Vec3::Y, fov_y: self.fov_y }
    }

    pub fn settings(&self) -> FrameSettings {
        FrameSettings {
            view: self.view(),
            lights: self.lights.clone(),
            exposure_scale: self.exposure.exp2(),
            shown: self.shown,
        }
    }

    fn set_camera(&mut self, eye: Vec3, target: Vec3) {
        self.eye = eye;
        (self.yaw, self.pitch) = yaw_pitch(target - eye);
    }

    /// The selected light.
    pub fn light(&self) -> &PlacedLight {
        &self.lights[self.selected]
    }

    /// Moves the selected light to `p`, or as near as its trained box allows.
    fn set_light(&mut self, p: Vec3) {
        self.place_light(self.selected, p);
    }

    /// Moves the selected light to `p`, or as near as its trained box allows, ending any
    /// scripted move of it (the panel's sliders).
    pub fn move_light(&mut self, p: Vec3) {
        self.light_tween = None;
        self.set_light(p);
    }

    /// The box the light was trained in, where the scene has a moving light.
    pub fn light_box(&self) -> Option<Aabb> {
        self.light_box
    }

    /// The box the camera was trained in, where the scene gives one.
    pub fn camera_box(&self) -> Option<Aabb> {
        self.camera_box
    }

    /// Whether the camera is outside the box it was trained in.
    pub fn camera_outside_box(&self) -> bool {
        self.camera_box.as_ref().is_some_and(|b| !b.contains(self.eye))
    }

    /// Why lights cannot be added, recoloured or dimmed in this scene, if they cannot.
    pub fn fixed_lights(&self) -> Option<&str> {
        self.fixed_lights.as_deref()
    }

    /// Moves light `index` to `p`, or as near as its trained box allows.
    fn place_light(&mut self, index: usize, p: Vec3) {
        let light = &mut self.lights[index];
        match &self.light_box {
            Some(b) => {
                let clamped = p.clamp(b.min, b.max);
                self.light_at_edge =
                    clamped.distance(p) > 1e-6 || clamped.cmpeq(b.min).any() || clamped.cmpeq(b.max).any();
                light.position = clamped;
            }
            None => light.position = p,
        }
    }

    /// Adds `light` and selects it.
    pub fn add_light(&mut self, light: PlacedLight) -> Result<()> {
        if let Some(why) = &self.fixed_lights {
            bail!("cannot add a light: {why}");
        }
        if self.lights.len() >= MAX_LIGHTS {
            bail!("cannot add a light: rrf renders at most {MAX_LIGHTS}");
        }
        self.lights.push(light);
        self.selected = self.lights.len() - 1;
        self.light_tween = None;
        let p = light.position;
        self.set_light(p);
        Ok(())
    }

    /// Adds a copy of the selected light where it is (the `L` key).
    pub fn duplicate_light(&mut self) -> Result<()> {
        self.add_light(*self.light())
    }

    /// Selects light `index` (from 0).
    pub fn select_light(&mut self, index: usize) -> Result<()> {
        if index >= self.lights.len() {
            bail!("there is no light {} (there are {})", index + 1, self.lights.len());
        }
        self.selected = index;
        self.light_tween = None;
        Ok(())
    }

    /// Removes the selected light, unless it is the last one.
    pub fn remove_light(&mut self) -> Result<()> {
        if self.lights.len() == 1 {
            bail!("cannot remove the last light");
        }
        self.lights.remove(self.selected);
        self.selected = self.selected.saturating_sub(1);
        self.light_tween = None;
        Ok(())
    }

    /// Sets the selected light's colour and intensity (`scale` = colour × intensity).
    pub fn set_light_scale(&mut self, scale: Vec3) -> Result<()> {
        if let Some(why) = &self.fixed_lights {
            bail!("cannot recolour or dim the light: {why}");
        }
        self.lights[self.selected].scale = scale.clamp(Vec3::ZERO, Vec3::splat(MAX_INTENSITY));
        Ok(())
    }

    /// Multiplies the selected light's intensity by `factor` (the `+` and `-` keys).
    pub fn scale_intensity(&mut self, factor: f32) -> Result<()> {
        self.set_light_scale(self.light().scale * factor)
    }

    /// Gives the selected light the next of [`COLOURS`], at its intensity (the `C` key).
    pub fn next_colour(&mut self) -> Result<()> {
        let scale = self.light().scale;
        let intensity = scale.max_element();
        let now = COLOURS.iter().position(|c| (*c * intensity - scale).abs().max_element() < 1e-4 * intensity.max(1.0));
        let next = COLOURS[now.map_or(0, |i| (i + 1) % COLOURS.len())];
        self.set_light_scale(next * intensity)
    }

    /// Turns the camera by a mouse move of `dx`, `dy` pixels.
    pub fn look(&mut self, dx: f32, dy: f32) {
        const RADIANS_PER_PIXEL: f32 = 0.003;
        self.camera_tween = None;
        self.yaw -= dx * RADIANS_PER_PIXEL;
        self.pitch = (self.pitch - dy * RADIANS_PER_PIXEL).clamp(-1.55, 1.55);
    }

    /// The scroll wheel: each notch up makes the camera 25% faster.
    pub fn scroll(&mut self, notches: f32) {
        self.speed = (self.speed * 1.25f32.powf(notches)).clamp(1e-3, 1e4);
    }

    pub fn reset(&mut self) {
        let home = self.home.clone();
        self.set_camera(home.eye, home.target);
        self.lights = self.home_lights.clone();
        self.selected = 0;
        // The selected light last, so that the overlay's edge warning is its own.
        for i in (0..self.lights.len()).rev() {
            self.place_light(i, self.lights[i].position);
        }
        self.camera_tween = None;
        self.light_tween = None;
    }

    pub fn exposure_step(&mut self, stops: f32) {
        self.exposure = (self.exposure + stops).clamp(-MAX_EXPOSURE, MAX_EXPOSURE);
    }

    /// Advances held keys and running moves by `dt` seconds, at script time `t`.
    pub fn update(&mut self, held: &std::collections::HashSet<Held>, dt: f32, t: f64) {
        let on = |k: Held| if held.contains(&k) { 1.0f32 } else { 0.0 };
        let forward = self.forward();
        let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let walk = forward * (on(Held::Forward) - on(Held::Back))
            + right * (on(Held::Right) - on(Held::Left))
            + Vec3::Y * (on(Held::Up) - on(Held::Down));
        if walk != Vec3::ZERO {
            self.camera_tween = None;
            let fast = if held.contains(&Held::Fast) { 4.0 } else { 1.0 };
            self.eye += walk.normalize() * self.speed * fast * dt;
        }
        let light_walk = Vec3::new(
            on(Held::LightRight) - on(Held::LightLeft),
            on(Held::LightUp) - on(Held::LightDown),
            on(Held::LightForward) - on(Held::LightBack),
        );
        if light_walk != Vec3::ZERO {
            self.light_tween = None;
            // Half the light box's diagonal per second.
            let span = self.light_box.as_ref().map_or(1.0, |b| (b.max - b.min).length().max(1e-3));
            self.set_light(self.light().position + light_walk.normalize() * span * 0.5 * dt);
        }
        if let Some(tween) = self.camera_tween {
            let ([eye, target], done) = tween.at(t);
            self.set_camera(eye, target);
            if done {
                self.camera_tween = None;
            }
        }
        if let Some(tween) = self.light_tween {
            let ([p, _], done) = tween.at(t);
            self.set_light(p);
            if done {
                self.light_tween = None;
            }
        }
    }

    /// Applies a script action that changes the view (the caller handles the others) at
    /// script time `t`.
    pub fn apply(&mut self, action: &Action, t: f64) -> Result<()> {
        match *action {
            Action::Camera { eye, target, over } => {
                let from = [self.eye, self.eye + self.forward()];
                self.camera_tween = Some(Tween { from, to: [eye, target], start: t, seconds: over });
                self.update(&Default::default(), 0.0, t);
            }
            Action::Light { position, over } => {
                let from = [self.light().position; 2];
                self.light_tween = Some(Tween { from, to: [position; 2], start: t, seconds: over });
                self.update(&Default::default(), 0.0, t);
            }
            Action::AddLight(light) => self.add_light(light)?,
            Action::SelectLight(number) => self.select_light(number - 1)?,
            Action::RemoveLight => self.remove_light()?,
            Action::LightScale(scale) => self.set_light_scale(scale)?,
            Action::Component(shown) => self.shown = shown,
            Action::Direct(mode) => match self.direct_choices.iter().find(|(m, _)| *m == mode) {
                Some((_, Err(why))) => bail!("direct {}: {why}", mode.name()),
                _ => self.direct = mode,
            },
            Action::Exposure(ev) => {
                self.exposure = ev;
                self.auto_exposure = false;
            }
            Action::AutoExposure => self.auto_exposure = true,
            Action::Overlay(on) => self.overlay = on,
            Action::Resize(..) | Action::Screenshot(_) | Action::Panel(_) | Action::Boxes(_) | Action::Quit => {}
        }
        Ok(())
    }

    /// Runs a light edit from a key: a refusal goes to the overlay instead of failing.
    pub fn key_edit(&mut self, edit: impl FnOnce(&mut Self) -> Result<()>) {
        self.light_note = edit(self).err().map(|e| e.to_string());
    }

    /// The overlay's text for the current frame: one dark box of lines of equal width.
    /// `reflected`: how many mirrors the frame draws the reflection of, in a scene with mirrors.
    pub fn overlay_text(&self, stats: &Stats, device: &str, reflected: Option<usize>) -> TextGrid {
        let mut lines: Vec<(String, Colour)> = Vec::new();
        let (fps, frame_ms) = stats.recent_rate();
        lines.push((
            format!("rrf {}  {fps:5.1} fps  {frame_ms:6.1} ms/frame  {device}", self.scene_name),
            Colour::White,
        ));
        let gpu = stats.recent_gpu_ms();
        // The mirrors' interval only in a scene with mirrors.
        let timed = TIMED_PASSES.iter().zip(gpu).filter(|(name, _)| reflected.is_some() || **name != "mirrors");
        let passes: Vec<String> = timed.map(|(name, ms)| format!("{name} {ms:.2}")).collect();
        lines.push((format!("GPU ms: {}", passes.join("  ")), Colour::White));
        let (l, k) = (self.light().position, self.light().scale);
        let edge = if self.light_at_edge { "  at the edge of its trained box" } else { "" };
        let colour = if self.light_at_edge { Colour::Yellow } else { Colour::White };
        lines.push((
            format!(
                "light {}/{} at {:.2},{:.2},{:.2}  x {:.2},{:.2},{:.2}{edge}",
                self.selected + 1,
                self.lights.len(),
                l.x,
                l.y,
                l.z,
                k.x,
                k.y,
                k.z
            ),
            colour,
        ));
        if let Some(note) = &self.light_note {
            lines.push((note.clone(), Colour::Yellow));
        }
        let e = self.eye;
        let outside = self.camera_outside_box();
        let note = if outside { "  outside its trained box" } else { "" };
        lines.push((
            format!("camera {:.2},{:.2},{:.2}{note}", e.x, e.y, e.z),
            if outside { Colour::Yellow } else { Colour::White },
        ));
        let mirrors = reflected.map_or(String::new(), |n| format!("  reflections on ({n} in view)"));
        lines.push((
            format!(
                "showing {}  exposure {:+.1} EV  direct light {}{mirrors}",
                self.shown.name(),
                self.exposure,
                self.direct.name()
            ),
            Colour::Blue,
        ));
        if self.help {
            lines.push((String::new(), Colour::White));
            lines.extend(help_lines(HELP_WIDTH).into_iter().map(|h| (h, Colour::White)));
        } else {
            lines.push(("H: help".into(), Colour::White));
        }
        let width = lines.iter().map(|(t, _)| t.len()).max().unwrap_or(0);
        let mut grid = TextGrid::default();
        for (text, colour) in lines {
            grid.line(&format!("{text:<width$}"), colour);
        }
        grid
    }
}

/// Characters per line of the overlay's help.
const HELP_WIDTH: usize = 64;

/// The colours the `C` key steps through: white, warm, cool, red, green, blue.
pub const COLOURS: [Vec3; 6] = [
    Vec3::ONE,
    Vec3::new(1.0, 0.75, 0.5),
    Vec3::new(0.6, 0.8, 1.0),
    Vec3::new(1.0, 0.25, 0.2),
    Vec3::new(0.3, 1.0, 0.3),
    Vec3::new(0.3, 0.4, 1.0),
];

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped(name: &str) -> ViewerState {
        let scene = Scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)).unwrap();
        let view = scene.views[0].clone();
        ViewerState::new(&scene, view, vec![scene.default_light()])
    }

    fn state() -> ViewerState {
        shipped("cornell-box")
    }

    #[test]
    fn lights_are_added_selected_recoloured_and_removed() {
        let mut s = state();
        let first = *s.light();
        s.duplicate_light().unwrap();
        assert_eq!((s.lights.len(), s.selected), (2, 1));
        // The arrows move only the selected light.
        let held = [Held::LightLeft].into_iter().collect();
        s.update(&held, 0.1, 0.0);
        assert_eq!(s.lights[0], first);
        assert!(s.lights[1].position.x < first.position.x);
        s.next_colour().unwrap();
        assert_eq!(s.light().scale, COLOURS[1]);
        s.scale_intensity(0.5).unwrap();
        assert_eq!(s.light().scale, COLOURS[1] * 0.5);
        s.next_colour().unwrap();
        assert!((s.light().scale - COLOURS[2] * 0.5).abs().max_element() < 1e-6);
        s.select_light(0).unwrap();
        assert!(s.select_light(2).is_err());
        s.remove_light().unwrap();
        assert_eq!(s.lights.len(), 1);
        assert_eq!(s.light().scale, COLOURS[2] * 0.5, "the second light is left");
        assert!(s.remove_light().is_err(), "the last light stays");
        for _ in 1..MAX_LIGHTS {
            s.duplicate_light().unwrap();
        }
        assert!(s.duplicate_light().is_err());
        s.reset();
        assert_eq!(s.lights, vec![first]);
        let text = s.overlay_text(&Stats::default(), "test", None).text();
        assert!(text.contains("light 1/1 at"), "{text}");
    }

    #[test]
    fn a_scene_with_other_lights_keeps_its_one_light() {
        let mut s = shipped("gallery");
        s.key_edit(ViewerState::duplicate_light);
        assert_eq!(s.lights.len(), 1);
        let note = s.light_note.clone().unwrap();
        assert!(note.contains("Screen"), "{note}");
        assert!(s.scale_intensity(2.0).is_err() && s.next_colour().is_err());
        assert!(s.overlay_text(&Stats::default(), "test", None).text().contains(&note));
    }

    #[test]
    fn the_view_round_trips_through_yaw_and_pitch() {
        let s = state();
        let v = s.view();
        let home = &s.home;
        let expected = (home.target - home.eye).normalize();
        assert!((v.target - v.eye).normalize().distance(expected) < 1e-5);
    }

    #[test]
    fn the_overlay_says_when_reflections_are_on() {
        let s = state();
        assert!(!s.overlay_text(&Stats::default(), "test", None).text().contains("reflections"));
        assert!(s.overlay_text(&Stats::default(), "test", Some(1)).text().contains("reflections on (1 in view)"));
    }

    #[test]
    fn the_light_stays_in_its_box_and_says_so_at_the_edge() {
        let mut s = state();
        let b = s.light_box.unwrap();
        let held = [Held::LightUp].into_iter().collect();
        for _ in 0..600 {
            s.update(&held, 1.0 / 60.0, 0.0);
        }
        assert!(b.contains(s.light().position));
        assert!((s.light().position.y - b.max.y).abs() < 1e-6 && s.light_at_edge);
        assert!(s.overlay_text(&Stats::default(), "test", None).text().contains("edge of its trained box"));
        s.reset();
        assert!(!s.light_at_edge || b.contains(s.light().position));
    }

    #[test]
    fn scripted_moves_interpolate_and_finish() {
        let mut s = state();
        let start = s.eye;
        let goal = start + Vec3::new(0.1, 0.0, 0.0);
        s.apply(&Action::Camera { eye: goal, target: goal + Vec3::Z, over: 1.0 }, 0.0).unwrap();
        s.update(&Default::default(), 0.0, 0.5);
        assert!(s.eye.distance(start.lerp(goal, 0.5)) < 1e-5);
        s.update(&Default::default(), 0.0, 2.0);
        assert!(s.eye.distance(goal) < 1e-6 && s.forward().distance(Vec3::Z) < 1e-5);
    }
}
