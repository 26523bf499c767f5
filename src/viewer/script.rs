//! Scripts of timed viewer events, for tests, demos and benchmarks.
//!
//! One event per line: `TIME COMMAND ARGUMENTS`, with TIME in seconds of script time. Script
//! time advances by exactly 1/60 s per frame, whatever the frame rate, so that a script gives
//! the same frames on every machine. `#` starts a comment. Commands:
//!
//! | command | effect |
//! |---|---|
//! | `camera X,Y,Z X,Y,Z [over S]` | eye and target; with `over`, moves there linearly in S seconds |
//! | `light X,Y,Z [over S]` | the selected light's position (kept inside its trained box) |
//! | `add-light X,Y,Z[:color=R,G,B][:intensity=K]` | adds a light (as `--light` says) and selects it |
//! | `select-light N` | selects light N, from 1 |
//! | `remove-light` | removes the selected light (not the last) |
//! | `light-color R,G,B [intensity K]` | the selected light's colour (0 to 1) and intensity |
//! | `component gi\|direct\|indirect` | which light is shown |
//! | `direct learned\|analytic` | where direct light comes from (the frame is made again) |
//! | `exposure EV\|auto` | exposure in stops, or automatic |
//! | `resize WxH` | the frame (and window) size in pixels |
//! | `screenshot FILE.png` | saves the frame as shown, overlay included (unless `--no-overlay`) |
//! | `overlay on\|off` | shows or hides the overlay |
//! | `panel on\|off` | shows or hides the settings panel |
//! | `boxes on\|off` | outlines the light's and the camera's trained boxes, or not |
//! | `quit` | ends the run (otherwise it ends one frame after the last event) |

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use rrf_baker::glam::Vec3;
use rrf_baker::scene::PlacedLight;
use rrf_renderer::frame::Shown;

use crate::direct_mode::DirectMode;
use crate::lights::parse_light;
use crate::parse::{parse_exposure, parse_size, parse_vec3};

/// Script time per frame.
pub const FRAME_SECONDS: f64 = 1.0 / 60.0;

#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    Camera {
        eye: Vec3,
        target: Vec3,
        over: f64,
    },
    Light {
        position: Vec3,
        over: f64,
    },
    AddLight(PlacedLight),
    /// From 1.
    SelectLight(usize),
    RemoveLight,
    /// Colour × intensity.
    LightScale(Vec3),
    Component(Shown),
    /// Where direct light comes from (the frame is made again).
    Direct(DirectMode),
    Exposure(f32),
    AutoExposure,
    Resize(u32, u32),
    Screenshot(PathBuf),
    Overlay(bool),
    Panel(bool),
    /// Outlines of the trained boxes.
    Boxes(bool),
    Quit,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    pub time: f64,
    pub action: Action,
}

/// A parsed script, events in time order (stable for equal times).
#[derive(Clone, Debug, Default)]
pub struct Script {
    pub events: Vec<Event>,
}

impl Script {
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read script {}", path.display()))?;
        Self::parse(&text).with_context(|| format!("script {}", path.display()))
    }

    pub fn parse(text: &str) -> Result<Self> {
        let mut events = Vec::new();
        for (number, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let event = parse_line(line).with_context(|| format!("line {}: {line:?}", number + 1))?;
            events.push(event);
        }
        events.sort_by(|a, b| a.time.total_cmp(&b.time));
        Ok(Script { events })
    }

    /// The frames the script runs: until its last event, plus one frame to show it.
    pub fn frames(&self) -> u64 {
        let end = self.events.last().map_or(0.0, |e| e.time);
        (end / FRAME_SECONDS).ceil() as u64 + 1
    }

    /// The events due in the frame at script time `t` (those in `[t, t + FRAME_SECONDS)`).
    pub fn due(&self, frame: u64) -> impl Iterator<Item = &Event> {
        let (start, end) = (frame as f64 * FRAME_SECONDS, (frame + 1) as f64 * FRAME_SECONDS);
        // A small tolerance so that "1.0" falls in frame 60, not 59, despite rounding.
        let eps = 1e-9;
        self.events.iter().filter(move |e| e.time >= start - eps && e.time < end - eps)
    }
}

/// The script's commands.
const COMMANDS: [&str; 15] = [
    "camera",
    "light",
    "add-light",
    "select-light",
    "remove-light",
    "light-color",
    "component",
    "direct",
    "exposure",
    "resize",
    "screenshot",
    "overlay",
    "panel",
    "boxes",
    "quit",
];

fn on_off(word: &str) -> Result<bool> {
    match word {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => bail!("expected on or off, not {word:?}"),
    }
}

fn parse_line(line: &str) -> Result<Event> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let [time, command, args @ ..] = words.as_slice() else { bail!("expected TIME COMMAND [ARGUMENTS]") };
    let time: f64 = time.parse().with_context(|| format!("time {time:?} is not a number of seconds"))?;
    if !(time.is_finite() && time >= 0.0) {
        bail!("time {time} must be a finite number of seconds, 0 or more");
    }
    // `... over S` on the commands that move things.
    let over = |args: &[&str]| -> Result<f64> {
        match args {
            [] => Ok(0.0),
            ["over", s] => match s.parse::<f64>() {
                Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
                _ => bail!("over {s:?}: expected a duration in seconds, 0 or more"),
            },
            _ => bail!("unexpected {:?}; expected nothing or `over SECONDS`", args.join(" ")),
        }
    };
    let action = match (*command, args) {
        ("camera", [eye, target, rest @ ..]) => {
            let eye = parse_vec3(eye, "camera eye")?;
            let target = parse_vec3(target, "camera target")?;
            if eye.distance(target) < 1e-6 {
                bail!("camera: eye and target are the same point");
            }
            Action::Camera { eye, target, over: over(rest)? }
        }
        ("light", [position, rest @ ..]) => {
            Action::Light { position: parse_vec3(position, "light")?, over: over(rest)? }
        }
        ("add-light", [spec]) => {
            let light = parse_light(spec, Vec3::NAN)?;
            if light.position.is_nan() {
                bail!("add-light: give the position as x,y,z");
            }
            Action::AddLight(light)
        }
        ("select-light", [n]) => match n.parse::<usize>() {
            Ok(n) if n >= 1 => Action::SelectLight(n),
            _ => bail!("select-light {n:?}: expected a light number from 1"),
        },
        ("remove-light", []) => Action::RemoveLight,
        ("light-color", [color, rest @ ..]) => {
            let mut spec = format!("0,0,0:color={color}");
            match rest {
                [] => {}
                ["intensity", k] => spec += &format!(":intensity={k}"),
                _ => bail!("light-color: unexpected {:?}; expected nothing or `intensity K`", rest.join(" ")),
            }
            Action::LightScale(parse_light(&spec, Vec3::ZERO)?.scale)
        }
        ("component", [name]) => Action::Component(match *name {
            "gi" => Shown::Gi,
            "direct" => Shown::Direct,
            "indirect" => Shown::Indirect,
            _ => bail!("component {name:?}: expected gi, direct or indirect"),
        }),
        ("direct", ["learned"]) => Action::Direct(DirectMode::Learned),
        ("direct", ["analytic"]) => Action::Direct(DirectMode::Analytic),
        ("exposure", ["auto"]) => Action::AutoExposure,
        ("exposure", [ev]) => Action::Exposure(parse_exposure(ev).map_err(|e| anyhow!("exposure {e}"))?),
        ("resize", [size]) => {
            let (w, h) = parse_size(size)?;
            Action::Resize(w, h)
        }
        ("screenshot", [file]) => {
            if !file.to_ascii_lowercase().ends_with(".png") {
                bail!("screenshot {file:?}: the file must end in .png");
            }
            Action::Screenshot(PathBuf::from(file))
        }
        ("overlay", [on]) => Action::Overlay(on_off(on)?),
        ("panel", [on]) => Action::Panel(on_off(on)?),
        ("boxes", [on]) => Action::Boxes(on_off(on)?),
        ("quit", []) => Action::Quit,
        (c, _) if COMMANDS.contains(&c) => bail!("wrong arguments for {c}; see `rrf view --help`"),
        (c, _) => bail!("unknown command {c:?}; expected {}", COMMANDS.join(", ")),
    };
    Ok(Event { time, action })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_command_in_time_order() {
        let script = Script::parse(
            "# demo\n\
             2.0 screenshot out.png\n\
             0 camera 0,1,2 0,1,0 over 1.5   # move\n\
             0.5 light 0.1,0.2,0.3\n\
             1 component direct\n\
             1 exposure -1.5\n\
             1.5 resize 320x200\n\
             1.5 overlay off\n\
             2.5 quit\n",
        )
        .unwrap();
        let actions: Vec<&Action> = script.events.iter().map(|e| &e.action).collect();
        assert_eq!(
            actions[0],
            &Action::Camera { eye: Vec3::new(0.0, 1.0, 2.0), target: Vec3::new(0.0, 1.0, 0.0), over: 1.5 }
        );
        assert_eq!(actions[2], &Action::Component(Shown::Direct));
        assert_eq!(actions[4], &Action::Resize(320, 200));
        assert_eq!(actions[7], &Action::Quit);
        assert_eq!(script.frames(), 151);
        assert_eq!(script.due(60).count(), 2, "both events at t = 1 fall in frame 60");
        assert_eq!(script.due(59).count(), 0);
    }

    #[test]
    fn errors_name_the_line_and_the_problem() {
        for (text, needle) in [
            ("0 fly 1,2,3", "unknown command"),
            ("x camera 0,0,0 1,1,1", "not a number"),
            ("-1 quit", "0 or more"),
            ("0 camera 1,1,1 1,1,1", "same point"),
            ("0 light 1,2", "x,y,z"),
            ("0 light 1,2,3 over -1", "over"),
            ("0 component all", "gi, direct or indirect"),
            ("0 resize 0x10", "WxH"),
            ("0 screenshot a.jpg", ".png"),
            ("0 quit now", "wrong arguments"),
            ("0 overlay maybe", "on or off"),
            ("0 boxes 1", "on or off"),
        ] {
            let e = format!("{:#}", Script::parse(&format!("# c\n{text}")).unwrap_err());
            assert!(e.contains("line 2") && e.contains(needle), "{text:?} gave {e:?}");
        }
    }
}
