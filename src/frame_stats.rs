//! Frame statistics, for `rrf view --stats` and its overlay and for `rrf bench`: CPU frame
//! times, GPU milliseconds per pass from timestamp queries, the process's memory.

use std::time::Instant;

use rrf_renderer::frame::TIMED_PASSES;
use serde_json::json;

/// Frames the overlay's figures average over.
const RECENT: usize = 30;

#[derive(Default)]
pub struct Stats {
    /// Milliseconds from one frame's start to the next's.
    pub frame_ms: Vec<f64>,
    /// GPU milliseconds of each timed interval, per frame.
    pub gpu_ms: [Vec<f64>; TIMED_PASSES.len()],
    last_start: Option<Instant>,
}

/// The middle value (the upper of the two middle ones for an even count); 0 for none.
pub fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The value below which `q` of `values` lie (nearest rank); 0 for none.
fn percentile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

fn recent(values: &[f64]) -> &[f64] {
    &values[values.len().saturating_sub(RECENT)..]
}

impl Stats {
    /// Marks the start of a frame.
    pub fn frame_started(&mut self) {
        let now = Instant::now();
        if let Some(last) = self.last_start.replace(now) {
            self.frame_ms.push((now - last).as_secs_f64() * 1e3);
        }
    }

    /// Adds a frame's timestamps (in ticks of `period_ns`).
    pub fn add_timestamps(&mut self, stamps: &[u64], period_ns: f64) {
        for (k, times) in self.gpu_ms.iter_mut().enumerate() {
            times.push(stamps[k + 1].wrapping_sub(stamps[k]) as f64 * period_ns * 1e-6);
        }
    }

    /// Frames per second and milliseconds per frame over the last frames.
    pub fn recent_rate(&self) -> (f64, f64) {
        let r = recent(&self.frame_ms);
        if r.is_empty() {
            return (0.0, 0.0);
        }
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        (1e3 / mean.max(1e-9), mean)
    }

    /// GPU milliseconds per timed pass over the last frames.
    pub fn recent_gpu_ms(&self) -> [f64; TIMED_PASSES.len()] {
        std::array::from_fn(|k| median(recent(&self.gpu_ms[k])))
    }

    /// The `--stats` summary: frames, median and 99th-percentile frame time, median GPU
    /// milliseconds per pass, and the process's peak resident memory.
    pub fn summary(&self, frames: u64) -> serde_json::Value {
        let gpu: serde_json::Map<String, serde_json::Value> =
            TIMED_PASSES.iter().zip(&self.gpu_ms).map(|(name, ms)| (format!("{name}_ms"), json!(median(ms)))).collect();
        json!({
            "frames": frames,
            "frame_ms_median": median(&self.frame_ms),
            "frame_ms_p99": percentile(&self.frame_ms, 0.99),
            "gpu_ms": gpu,
            "peak_rss_mib": memory_kib("VmHWM:").map(|k| k as f64 / 1024.0),
            "rss_mib": memory_kib("VmRSS:").map(|k| k as f64 / 1024.0),
        })
    }
}

/// A memory figure of this process from /proc/self/status, in KiB (Linux only).
fn memory_kib(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].trim().trim_end_matches("kB").trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_by_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(percentile(&v, 0.5), 50.0);
        assert_eq!(percentile(&v, 0.99), 99.0);
        assert_eq!(percentile(&[3.0], 0.99), 3.0);
        assert_eq!(percentile(&[], 0.5), 0.0);
    }

    #[test]
    fn summary_has_every_field() {
        let mut s = Stats { frame_ms: vec![10.0, 20.0, 30.0], ..Stats::default() };
        s.add_timestamps(&[0, 1_000_000, 1_500_000, 3_500_000, 4_000_000, 4_500_000], 1.0);
        let j = s.summary(3);
        assert_eq!(j["frame_ms_median"], 20.0);
        assert_eq!(j["gpu_ms"]["mirrors_ms"], 0.5);
        assert_eq!(j["gpu_ms"]["network_ms"], 2.0);
        assert!(j["peak_rss_mib"].as_f64().unwrap() > 0.0);
    }
}
