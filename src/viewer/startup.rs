//! Where the walkthrough's start-up time goes: loading, Vulkan, the frame's set-up (mostly
//! pipelines) and the first frame, which a driver may also spend compiling.

use std::time::{Duration, Instant};

use serde_json::json;

/// Start-up phases, timed from the command's start.
pub struct StartUp {
    /// Each finished phase's name and length, in order.
    phases: Vec<(&'static str, Duration)>,
    /// When the last phase ended (or the clock started).
    last: Instant,
}

impl StartUp {
    /// Starts the clock.
    pub fn start() -> Self {
        StartUp { phases: Vec::new(), last: Instant::now() }
    }

    /// Ends phase `name`, which ran since the last phase ended.
    pub fn phase(&mut self, name: &'static str) {
        let now = Instant::now();
        self.phases.push((name, now - self.last));
        self.last = now;
    }

    /// The phases' total.
    fn total(&self) -> Duration {
        self.phases.iter().map(|(_, d)| *d).sum()
    }

    /// One line for the terminal: the total, then each phase.
    pub fn line(&self) -> String {
        let phases: Vec<String> = self.phases.iter().map(|(n, d)| format!("{n} {:.2} s", d.as_secs_f64())).collect();
        format!("start-up {:.2} s: {}", self.total().as_secs_f64(), phases.join(", "))
    }

    /// The phases in seconds, and their total, for `--stats`.
    pub fn json(&self) -> serde_json::Value {
        let mut map: serde_json::Map<String, serde_json::Value> =
            self.phases.iter().map(|(n, d)| (key(n), json!(d.as_secs_f64()))).collect();
        map.insert("total".into(), json!(self.total().as_secs_f64()));
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
        let j = s.json();
        assert!(j.get("frame_set_up").is_some() && j.get("vulkan").is_none(), "{j}");
        let parts = j["scene_and_model"].as_f64().unwrap() + j["frame_set_up"].as_f64().unwrap();
        assert!(j["scene_and_model"].as_f64().unwrap() >= 0.005);
        assert!((j["total"].as_f64().unwrap() - parts).abs() < 1e-9);
        assert!(s.line().starts_with("start-up 0.0"), "{}", s.line());
    }
}
