//! Path tracer throughput on the Cornell box: 256×256, 256 spp, max depth 8, Russian roulette
//! from depth 5 (the settings of the Mitsuba 3 comparison in shared/FACTS.md), on all cores
//! and on one. `--scene` names another of `scenes/` (its first view, its light where the glTF
//! puts it).
//!
//! `--centre` starts every path of a pixel at its centre, as `rrf eval`'s references do.
//!
//! `cargo bench -p rrf-baker --bench path_tracer [-- --spp N] [--scene NAME] [--centre]`
//!
//! The checksum (FNV-1a of every pixel's components) tells whether a change to the
//! tracer that should only make it faster left its output as it was, to the bit.

use std::path::Path;
use std::time::Instant;

use rrf_baker::hash::Fnv64;
use rrf_baker::scene::Scene;
use rrf_baker::trace::{render, Camera, Footprint, Geometry, RadianceImage, RenderSettings, TraceSettings, World};

fn main() {
    let option = |name: &str| std::env::args().skip_while(|a| a != name).nth(1);
    let spp = option("--spp").and_then(|s| s.parse().ok()).unwrap_or(256u32);
    let name = option("--scene").unwrap_or_else(|| "cornell-box".into());
    let footprint = match std::env::args().any(|a| a == "--centre") {
        true => Footprint::Centre,
        false => Footprint::Area,
    };
    let scene = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(&name))
        .unwrap_or_else(|e| panic!("scenes/{name} does not load: {e}"));
    let start = Instant::now();
    let geometry = Geometry::new(&scene);
    let bvh_ms = start.elapsed().as_secs_f64() * 1e3;
    let world = World::new(&scene, &geometry, None);
    let camera = Camera::new(&scene.views[0], 1.0);
    let settings = RenderSettings {
        width: 256,
        height: 256,
        spp,
        trace: TraceSettings { max_depth: 8, rr_depth: Some(5) },
        seed: 0,
        footprint,
    };
    let paths = 256.0 * 256.0 * f64::from(spp);
    println!(
        "{name} 256x256, {spp} spp, {footprint:?} footprint, max depth 8, roulette from 5; BVH build {bvh_ms:.2} ms"
    );
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    for threads in [cores, 1] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
        let start = Instant::now();
        let image = pool.install(|| render(&world, &camera, &settings, &|_| {}));
        let seconds = start.elapsed().as_secs_f64();
        let mean = image.pixels.iter().map(|r| r.gi()).sum::<rrf_baker::glam::Vec3>() / image.pixels.len() as f32;
        println!(
            "{threads} thread(s): {seconds:.2} s, {:.2} M paths/s (image mean {:.4} {:.4} {:.4}, checksum {:016x})",
            paths / seconds / 1e6,
            mean.x,
            mean.y,
            mean.z,
            checksum(&image)
        );
    }
}

fn checksum(image: &RadianceImage) -> u64 {
    let mut hash = Fnv64::default();
    for value in image.pixels.iter().flat_map(|r| [r.emitted, r.direct, r.indirect]).flat_map(|v| v.to_array()) {
        hash.write(&value.to_le_bytes());
    }
    hash.0
}
