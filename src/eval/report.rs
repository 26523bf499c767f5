//! `DIR/metrics.json` and `DIR/index.html`: every configuration's figure with its numbers.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context as _, Result};
use serde::Serialize;

use super::metrics::{Baselines, Metrics};
use super::seams::Seam;

#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct ComponentMetrics {
    pub gi: Metrics,
    pub direct: Metrics,
    pub indirect: Metrics,
}

impl ComponentMetrics {
    pub fn mean(all: &[ComponentMetrics]) -> ComponentMetrics {
        ComponentMetrics {
            gi: Metrics::mean(all.iter().map(|m| &m.gi)),
            direct: Metrics::mean(all.iter().map(|m| &m.direct)),
            indirect: Metrics::mean(all.iter().map(|m| &m.indirect)),
        }
    }

    fn by_name(&self) -> [(&'static str, &Metrics); 3] {
        [("gi", &self.gi), ("direct", &self.direct), ("indirect", &self.indirect)]
    }
}

#[derive(Debug, Serialize)]
pub struct Camera {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub fov_y: f32,
}

#[derive(Debug, Serialize)]
pub struct ConfigReport {
    pub name: String,
    pub camera: Camera,
    pub light: [f32; 3],
    /// The figure's file name in DIR.
    pub figure: String,
    /// Samples per pixel of its references (above the run's with `--floor-below`).
    pub spp: u32,
    pub reference_cached: bool,
    pub metrics: ComponentMetrics,
    /// The global image's metrics for trivial predictions of the same reference.
    pub baselines: Baselines,
    /// The global image's metrics of a second reference of the same spp with independent
    /// paths, against the first: below it, a prediction's error is the references' noise.
    pub floor: Metrics,
    /// The kd-tree cut whose prediction steps most beyond the reference's step across the same
    /// pixels (`eval::seams`), if any cut is in view.
    pub worst_seam: Option<Seam>,
    /// Cuts in view whose prediction steps more than the reference's, by over twice the
    /// reference's standard error.
    pub seams_over_reference: usize,
}

#[derive(Debug, Serialize)]
pub struct Report {
    pub scene: String,
    pub model: String,
    /// What made the predictions: the Vulkan device, or the CPU inference.
    pub predictions: String,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of the references (where `--floor-below` raised none).
    pub spp: u32,
    pub max_depth: u32,
    pub rr_depth: u32,
    pub seed: u64,
    /// Where in its pixel each reference path starts: "centre" or "area".
    pub footprint: &'static str,
    pub configs: Vec<ConfigReport>,
    pub mean: ComponentMetrics,
    pub mean_baselines: Baselines,
    pub mean_floor: Metrics,
}

pub fn write(dir: &Path, report: &Report) -> Result<()> {
    let json = dir.join("metrics.json");
    let text = serde_json::to_string_pretty(report).context("cannot serialise the metrics")?;
    std::fs::write(&json, text + "\n").with_context(|| format!("cannot write {}", json.display()))?;
    let html = dir.join("index.html");
    std::fs::write(&html, page(report)).with_context(|| format!("cannot write {}", html.display()))?;
    Ok(())
}

fn row(out: &mut String, label: &str, m: &ComponentMetrics) {
    let _ = write!(out, "<tr><th>{label}</th>");
    for (_, x) in m.by_name() {
        let _ = write!(
            out,
            "<td>{:.4}</td><td>{:.2}</td><td>{:.4}</td><td>{:.4}</td>",
            x.relmse, x.psnr, x.flip, x.hdr_flip
        );
    }
    out.push_str("</tr>\n");
}

fn page(r: &Report) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "<!doctype html>\n<meta charset=\"utf-8\">\n<title>rrf eval: {scene}</title>\n\
         <style>body{{font-family:sans-serif;background:#181818;color:#eee;margin:2em}}\
         table{{border-collapse:collapse}}td,th{{padding:2px 8px;text-align:right}}\
         img{{max-width:100%}}</style>\n\
         <h1>rrf eval: {scene}</h1>\n<p>Model <code>{model}</code>, predictions from {pred}. References: \
         the baker's path tracer, {spp} spp, max depth {depth}, at {w}×{h}. Configurations held out \
         from training (seed {seed}).</p>\n",
        scene = r.scene,
        model = r.model,
        pred = r.predictions,
        spp = r.spp,
        depth = r.max_depth,
        w = r.width,
        h = r.height,
        seed = r.seed,
    );
    s.push_str(
        "<table>\n<tr><th></th><th colspan=4>gi</th><th colspan=4>direct</th><th colspan=4>indirect</th></tr>\n\
         <tr><th>configuration</th>",
    );
    for _ in 0..3 {
        s.push_str("<th>relMSE</th><th>PSNR dB</th><th>FLIP</th><th>HDR-FLIP</th>");
    }
    s.push_str("</tr>\n");
    row(&mut s, "mean", &r.mean);
    for c in &r.configs {
        row(&mut s, &c.name, &c.metrics);
    }
    s.push_str("</table>\n");
    s.push_str(
        "<h2>Yardsticks for the global image</h2>\n<p>Floor: a second reference with independent paths \
         against the first (below it, error cannot be told from the references' noise). Black and mean \
         colour: trivial predictions, which a model must beat by far.</p>\n<table>\n\
         <tr><th>configuration</th><th>model FLIP</th><th>floor FLIP</th><th>black FLIP</th>\
         <th>mean colour FLIP</th><th>model HDR-FLIP</th><th>floor HDR-FLIP</th></tr>\n",
    );
    let yardsticks = |s: &mut String, name: &str, model: &Metrics, floor: &Metrics, baselines: &Baselines| {
        let _ = writeln!(
            s,
            "<tr><th>{name}</th><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td></tr>",
            model.flip, floor.flip, baselines.black.flip, baselines.mean_colour.flip, model.hdr_flip, floor.hdr_flip
        );
    };
    yardsticks(&mut s, "mean", &r.mean.gi, &r.mean_floor, &r.mean_baselines);
    for c in &r.configs {
        yardsticks(&mut s, &c.name, &c.metrics.gi, &c.floor, &c.baselines);
    }
    s.push_str("</table>\n");
    for c in &r.configs {
        let _ = write!(
            s,
            "<h2>{name}</h2>\n<p>eye {:?}, target {:?}, light {:?}; global relMSE {:.4}, FLIP {:.4}</p>\n\
             <img src=\"{fig}\" alt=\"{name}\">\n",
            c.camera.eye,
            c.camera.target,
            c.light,
            c.metrics.gi.relmse,
            c.metrics.gi.flip,
            name = c.name,
            fig = c.figure,
        );
    }
    s
}
