//! Where the walkthrough's start-up time goes: loading, Vulkan, the frame's set-up (mostly
//! pipelines) and the first frame, which a driver may also spend compiling.

use std::time::{Duration, Instant};

use serde_json::json;

/// Start-up phases, timed from the command's start.
pub struct StartUp {
    started: Instant,
    /// Each finished phase's name and length, in order.
    phases: Vec<(&'static str, Duration)>,
    last: Instant,
}

impl StartUp {
    /// Starts the clock.
    pub fn start() -> Self {
        let now = Instant::now();
        StartUp { started: now, phases: Vec::new(), last: now }
    }

    /// Ends phase `name`, which ran since the last phase ended.
    pub fn phase(&mut self, name: &'static str) {
        let now = Instant::now();
        self.phases.push((name, now - self.last));
        self.last = now;
    }

    /// Whether `phase` has ended.
    pub fn has(&self, name: &str) -> bool {
        self.phases.iter().any(|(n, _)| *n == name)
    }

    /// One line for the terminal: the total, then each phase.
    pub fn line(&self) -> String {
        let phases: Vec<String> = self.phases.iter().map(|(n, d)| format!("{n} {:.2} s", d.as_secs_f64())).collect();
        format!("start-up {:.2} s: {}", (self.last - self.started).as_secs_f64(), phases.join(", "))
    }

    /// The phases in seconds, and their total, for `--stats`.
    pub fn json(&self) -> serde_json::Value {
        let mut map: serde_json::Map<String, serde_json::Value> =
            self.phases.iter().map(|(n, d)| (key(n), json!(d.as_secs_f64()))).collect();
        map.insert("total".into(), json!((self.last - self.started).as_secs_f64()));
        serde_json::Value::Object(map)
    }
}

/// A phase's name as a JSON key: `frame set-up` → `frame_set_up`.
fn key(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_add_up_to_the_total() {
        let mut s = StartUp::start();
        std::thread::sleep(Duration::from_millis(5));
        s.phase("scene and model");
        s.phase("frame set-up");
        assert!(s.has("frame set-up") && !s.has("Vulkan"));
        let j = s.json();
        let parts = j["scene_and_model"].as_f64().unwrap() + j["frame_set_up"].as_f64().unwrap();
        assert!(j["scene_and_model"].as_f64().unwrap() >= 0.005);
        assert!((j["total"].as_f64().unwrap() - parts).abs() < 1e-9);
        assert!(s.line().starts_with("start-up 0.0"), "{}", s.line());
    }
}
