//! The viewer's window: winit's event loop, keyboard and mouse input, and the surface.

use anyhow::{Context as _, Result};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use rrf_renderer::backend::swapchain::Surface;
use rrf_renderer::vk;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use super::gpu::ViewerGpu;
use super::state::Held;
use super::{Session, ViewerState};
use rrf_renderer::backend::present::Presenter;
use rrf_renderer::frame::Shown;

/// The key held for a continuous action, by physical position (WASD works on any layout).
fn held_key(key: KeyCode) -> Option<Held> {
    Some(match key {
        KeyCode::KeyW => Held::Forward,
        KeyCode::KeyS => Held::Back,
        KeyCode::KeyA => Held::Left,
        KeyCode::KeyD => Held::Right,
        KeyCode::KeyQ => Held::Down,
        KeyCode::KeyE => Held::Up,
        KeyCode::ShiftLeft | KeyCode::ShiftRight => Held::Fast,
        KeyCode::ArrowLeft => Held::LightLeft,
        KeyCode::ArrowRight => Held::LightRight,
        KeyCode::ArrowUp => Held::LightForward,
        KeyCode::ArrowDown => Held::LightBack,
        KeyCode::PageDown => Held::LightDown,
        KeyCode::PageUp => Held::LightUp,
        _ => return None,
    })
}

/// The event loop for a window, or why there can be none.
pub fn event_loop() -> Result<EventLoop<()>> {
    EventLoop::new().map_err(|e| anyhow::anyhow!("cannot open a window: {e}"))
}

/// The instance extensions a window on this event loop's display needs.
pub fn instance_extensions(event_loop: &EventLoop<()>) -> Result<Vec<&'static std::ffi::CStr>> {
    let display = event_loop.display_handle().context("no display handle")?.as_raw();
    Ok(rrf_renderer::backend::swapchain::required_instance_extensions(display)?)
}

struct App<'a> {
    gpu: &'a mut ViewerGpu,
    session: &'a mut Session,
    title: String,
    size: (u32, u32),
    present_mode: vk::PresentModeKHR,
    window: Option<Window>,
    presenter: Option<Presenter>,
    /// The panel's input from the window's events.
    egui: Option<egui_winit::State>,
    looking: bool,
    /// Whether the window is hidden (minimised or covered, where the platform says so).
    occluded: bool,
    cursor: Option<(f64, f64)>,
    error: Option<anyhow::Error>,
}

impl App<'_> {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let attributes = Window::default_attributes()
            .with_title(&self.title)
            .with_inner_size(PhysicalSize::new(self.size.0, self.size.1));
        let window = event_loop.create_window(attributes).context("cannot create the window")?;
        let display = window.display_handle().context("no display handle")?.as_raw();
        let handle = window.window_handle().context("no window handle")?.as_raw();
        let surface = Surface::new(&self.gpu.ctx, display, handle)?;
        self.presenter = Some(Presenter::new(surface, self.present_mode));
        self.egui = Some(egui_winit::State::new(
            self.session.panel.context().clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(self.gpu.max_texture_side()),
        ));
        self.window = Some(window);
        Ok(())
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let (Some(window), Some(presenter)) = (&self.window, &mut self.presenter) else { return Ok(()) };
        let size = window.inner_size();
        if !self.gpu.fit(presenter, (size.width, size.height))? {
            // Minimised: nothing to draw until the window is restored (a resize event).
            return Ok(());
        }
        let scale = window.scale_factor().round().max(1.0) as u32;
        let input = self.egui.as_mut().map(|e| e.take_egui_input(window));
        let requests = self.session.step(self.gpu, Some(presenter), scale, input)?;
        if let (Some(egui), Some(platform)) = (&mut self.egui, requests.platform) {
            egui.handle_platform_output(window, platform);
        }
        if let Some((w, h)) = requests.resize {
            // The swapchain follows when the window has its new size.
            let _ = window.request_inner_size(PhysicalSize::new(w, h));
        }
        if requests.quit {
            event_loop.exit();
        } else if !self.occluded || self.session.ends_by_itself() {
            window.request_redraw();
        }
        Ok(())
    }

    /// A key, unless the panel took it (`to_panel`: a text field has the focus); a key let go
    /// always counts, so that none stays held.
    fn key(&mut self, event_loop: &ActiveEventLoop, event: &KeyEvent, to_panel: bool) {
        let PhysicalKey::Code(code) = event.physical_key else { return };
        if let Some(held) = held_key(code) {
            match event.state {
                ElementState::Pressed if !to_panel => self.session.held.insert(held),
                ElementState::Pressed => false,
                ElementState::Released => self.session.held.remove(&held),
            };
            return;
        }
        if event.state != ElementState::Pressed || event.repeat || to_panel {
            return;
        }
        let state = &mut self.session.state;
        match code {
            KeyCode::Escape => event_loop.exit(),
            KeyCode::Digit1 | KeyCode::Numpad1 => state.shown = Shown::Gi,
            KeyCode::Digit2 | KeyCode::Numpad2 => state.shown = Shown::Direct,
            KeyCode::Digit3 | KeyCode::Numpad3 => state.shown = Shown::Indirect,
            KeyCode::BracketLeft => state.exposure_step(-0.5),
            KeyCode::BracketRight => state.exposure_step(0.5),
            KeyCode::KeyH => state.help = !state.help,
            KeyCode::KeyO => state.overlay = !state.overlay,
            KeyCode::KeyU => self.session.panel.shown = !self.session.panel.shown,
            KeyCode::KeyR => state.reset(),
            KeyCode::KeyL => state.key_edit(ViewerState::duplicate_light),
            KeyCode::Tab => state.key_edit(|s| s.select_light((s.selected + 1) % s.lights.len())),
            KeyCode::Delete | KeyCode::Backspace => state.key_edit(ViewerState::remove_light),
            KeyCode::KeyC => state.key_edit(ViewerState::next_colour),
            KeyCode::Minus | KeyCode::NumpadSubtract => state.key_edit(|s| s.scale_intensity(0.5f32.sqrt())),
            KeyCode::Equal | KeyCode::NumpadAdd => state.key_edit(|s| s.scale_intensity(2f32.sqrt())),
            KeyCode::KeyP => self.session.screenshot_key(),
            _ => {}
        }
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            if let Err(e) = self.open(event_loop) {
                self.fail(event_loop, e);
                return;
            }
        }
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        // What the panel takes (a click or the wheel over it, a key while one of its text
        // fields has the focus) goes no further. Keys reach it only then: egui would otherwise
        // take Tab for its own focus, and arrows for a slider clicked before, which the
        // walkthrough's keys would move as well.
        let typing = self.session.panel.context().text_edit_focused();
        let to_panel = match (&mut self.egui, &self.window, &event) {
            (_, _, WindowEvent::KeyboardInput { .. }) if !typing => false,
            (Some(egui), Some(window), _) => egui.on_window_event(window, &event).consumed,
            _ => false,
        };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) | WindowEvent::ScaleFactorChanged { .. } => {
                if let Some(w) = &self.window {
                    w.request_redraw();
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.fail(event_loop, e);
                }
            }
            WindowEvent::KeyboardInput { event, .. } => self.key(event_loop, &event, to_panel),
            WindowEvent::Focused(false) => self.session.held.clear(),
            // No frames while hidden; the loop sleeps until the window shows again.
            WindowEvent::Occluded(hidden) => {
                self.occluded = hidden;
                if let (false, Some(w)) = (hidden, &self.window) {
                    w.request_redraw();
                }
            }
            WindowEvent::MouseInput { button: MouseButton::Right, state, .. } => {
                self.looking = state == ElementState::Pressed && !to_panel;
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = (position.x, position.y);
                if let (true, Some(last)) = (self.looking, self.cursor) {
                    self.session.state.look((p.0 - last.0) as f32, (p.1 - last.1) as f32);
                }
                self.cursor = Some(p);
            }
            WindowEvent::MouseWheel { delta, .. } if !to_panel => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.session.state.scroll(notches);
            }
            _ => {}
        }
    }
}

/// Opens the window and runs the session until it ends or the window closes.
pub fn run(
    event_loop: EventLoop<()>,
    gpu: &mut ViewerGpu,
    session: &mut Session,
    title: String,
    size: (u32, u32),
    present_mode: vk::PresentModeKHR,
) -> Result<()> {
    // Frames are driven by redraw requests; with none (a minimised window) the loop sleeps.
    event_loop.set_control_flow(ControlFlow::Wait);
    let mut app = App {
        gpu,
        session,
        title,
        size,
        present_mode,
        window: None,
        presenter: None,
        egui: None,
        looking: false,
        occluded: false,
        cursor: None,
        error: None,
    };
    let ran = event_loop.run_app(&mut app).context("the window's event loop failed");
    // The surface goes before the window it was made for.
    let retired = match app.presenter.take() {
        Some(p) => app.gpu.retire(p),
        None => Ok(()),
    };
    let result = match app.error.take() {
        Some(e) => Err(e),
        None => ran.and(retired),
    };
    drop(app.window.take());
    result
}
