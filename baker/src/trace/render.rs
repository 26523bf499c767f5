//! Path-traced images: tiles on all cores through rayon, the same image for the same seed.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::camera::Camera;
use super::integrator::{radiance_leaving, trace_ray, FirstVertex, Radiance, TraceSettings};
use super::sampling::Rng;
use super::world::World;

const TILE: u32 = 16;

#[derive(Clone, Copy, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub trace: TraceSettings,
    pub seed: u64,
    pub footprint: Footprint,
}

/// Where in its pixel each path starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Footprint {
    /// Anywhere in the pixel's square, uniformly: a box-filtered, antialiased image.
    #[default]
    Area,
    /// Through the pixel's centre: the one ray whose hit the rasterised G-buffer stores, so
    /// that the image converges to what the renderer's networks should output pixel for pixel,
    /// and a comparison with it scores the shading, not the raster's aliasing of edges and
    /// textures.
    Centre,
}

/// An image of per-pixel radiance by component, rows top to bottom.
pub struct RadianceImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Radiance>,
}

impl RadianceImage {
    /// One component (or the sum) as RGB rows.
    pub fn component(&self, pick: impl Fn(&Radiance) -> Vec3) -> Vec<Vec3> {
        self.pixels.iter().map(pick).collect()
    }
}

/// Renders `camera`'s view of `world`. `progress` is called with the number of pixels of each
/// finished tile, from worker threads.
pub fn render(world: &World, camera: &Camera, s: &RenderSettings, progress: &(dyn Fn(u64) + Sync)) -> RadianceImage {
    let tiles_x = s.width.div_ceil(TILE);
    let tiles_y = s.height.div_ceil(TILE);
    let tiles: Vec<(u32, Vec<Radiance>)> = (0..tiles_x * tiles_y)
        .into_par_iter()
        .map(|tile| {
            let (x0, y0) = ((tile % tiles_x) * TILE, (tile / tiles_x) * TILE);
            let (x1, y1) = ((x0 + TILE).min(s.width), (y0 + TILE).min(s.height));
            let mut pixels = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
            for y in y0..y1 {
                for x in x0..x1 {
                    pixels.push(render_pixel(world, camera, s, x, y));
                }
            }
            progress(pixels.len() as u64);
            (tile, pixels)
        })
        .collect();

    let mut image = vec![Radiance::default(); (s.width * s.height) as usize];
    for (tile, pixels) in tiles {
        let (x0, y0) = ((tile % tiles_x) * TILE, (tile / tiles_x) * TILE);
        let w = (x0 + TILE).min(s.width) - x0;
        for (i, p) in pixels.into_iter().enumerate() {
            let (x, y) = (x0 + i as u32 % w, y0 + i as u32 / w);
            image[(y * s.width + x) as usize] = p;
        }
    }
    RadianceImage { width: s.width, height: s.height, pixels: image }
}

fn render_pixel(world: &World, camera: &Camera, s: &RenderSettings, x: u32, y: u32) -> Radiance {
    let pixel = u64::from(y) * u64::from(s.width) + u64::from(x);
    // One stream per path, so that a path's length never shifts another path's numbers.
    let stream = |sample: u32| Rng::new(s.seed, pixel * u64::from(s.spp) + u64::from(sample));
    let size = Vec2::new(s.width as f32, s.height as f32);
    let direction = |offset: Vec2| camera.direction((Vec2::new(x as f32, y as f32) + offset) / size);
    let mut sum = Radiance::default();
    match s.footprint {
        Footprint::Area => {
            for sample in 0..s.spp {
                let mut rng = stream(sample);
                let dir = direction(rng.next_vec2());
                sum += trace_ray(world, camera.eye, dir, &s.trace, &mut rng);
            }
        }
        Footprint::Centre => {
            // Every path starts along the same ray: its first vertex is found once, as
            // `trace_ray` would find it for each path.
            let dir = direction(Vec2::splat(0.5));
            if let Some(hit) = world.intersect(camera.eye, dir) {
                let si = world.interaction(camera.eye, dir, hit);
                let first = FirstVertex::new(world, &si, -dir, &s.trace);
                for sample in 0..s.spp {
                    sum += radiance_leaving(world, &first, None, &s.trace, &mut stream(sample));
                }
            }
        }
    }
    sum.scaled(1.0 / s.spp.max(1) as f32)
}
