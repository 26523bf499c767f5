//! Images predicted by a model on the CPU: primary hits by ray casting, then each object's
//! networks with the CPU reference inference, and in planar mirrors what their reflected rays
//! see. The exact counterpart of the GPU renderer.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::model::Model;
use crate::network::{evaluate_blended, raw_inputs, reflectance, Component, Network};
use crate::scene::PlacedLight;
use crate::trace::bsdf::schlick;
use crate::trace::integrator::{offset_origin, point_lights_at};
use crate::trace::sampling::Frame;
use crate::trace::{Camera, Radiance, RadianceImage, World};

/// The networks of every object, by object id (none for objects without networks; one per
/// leaf of a kd-tree for split objects).
struct ObjectNetworks<'a> {
    direct: Vec<Vec<&'a Network>>,
    indirect: Vec<Vec<&'a Network>>,
}

impl<'a> ObjectNetworks<'a> {
    fn new(world: &World, model: &'a Model) -> Self {
        let lookup =
            |component| world.scene.objects.iter().map(|o| model.networks(&o.name, component)).collect::<Vec<_>>();
        ObjectNetworks { direct: lookup(Component::Direct), indirect: lookup(Component::Indirect) }
    }
}

/// Where predicted direct light comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Direct {
    /// The direct networks.
    #[default]
    Learned,
    /// The path tracer's next-event estimate of the world's point lights at the hit, which
    /// is exact (the renderer's analytic mode, with ray-cast shadows for shadow maps).
    Analytic,
}

/// One ray through each pixel centre: emission where it hits an emitter, the object's
/// networks elsewhere (once per light of `world`, at its position, scaled by its `scale`, and
/// summed), nothing where it hits nothing. A planar mirror shows what its reflected ray sees
/// so, weighted by its Fresnel term; a mirror seen in a mirror shows only its emission (one
/// reflection, as the renderer draws it). `direct` says where direct light comes from.
pub fn predict_image(
    world: &World,
    camera: &Camera,
    model: &Model,
    (width, height): (u32, u32),
    direct: Direct,
) -> RadianceImage {
    let predictor = Predictor { world, networks: ObjectNetworks::new(world, model), direct };
    let size = Vec2::new(width as f32, height as f32);
    let pixels = (0..width * height)
        .into_par_iter()
        .map(|i| {
            let film = (Vec2::new((i % width) as f32, (i / width) as f32) + 0.5) / size;
            predictor.seen(camera.eye, camera.direction(film), true)
        })
        .collect();
    RadianceImage { width, height, pixels }
}

struct Predictor<'a> {
    world: &'a World<'a>,
    networks: ObjectNetworks<'a>,
    direct: Direct,
}

impl Predictor<'_> {
    /// The predicted radiance that reaches `origin` along the ray `dir` (unit); through a
    /// mirror only if `reflect`.
    fn seen(&self, origin: Vec3, dir: Vec3, reflect: bool) -> Radiance {
        let world = self.world;
        let Some(hit) = world.intersect(origin, dir) else { return Radiance::default() };
        let si = world.interaction(origin, dir, hit);
        let object = si.object as usize;
        if let Some(mirror) = world.geometry.mirrors[object] {
            let mut radiance = Radiance { emitted: si.emission, ..Radiance::default() };
            if let (true, Some(normal)) = (reflect, mirror.normal_towards(origin)) {
                let cos = -dir.dot(normal);
                let reflected = dir + 2.0 * cos * normal;
                let behind = self.seen(offset_origin(&si, reflected), reflected, false);
                let f = schlick(si.bsdf.base_color, cos);
                // Light that leaves an emitter and meets the mirror first is the mirror's
                // direct light; what other surfaces reflect to it is indirect, as the path
                // tracer splits them.
                radiance.direct = f * behind.emitted;
                radiance.indirect = f * (behind.direct + behind.indirect);
            }
            return radiance;
        }
        let r = reflectance(si.bsdf.base_color, si.bsdf.metallic, si.bsdf.specular);
        let eval = |networks: &[&Network]| {
            let lit = |l: &PlacedLight| {
                let raw = raw_inputs(si.position, -dir, l.position, si.shading_normal, si.roughness);
                evaluate_blended(networks, &raw) * l.scale
            };
            world.lights.iter().map(lit).sum::<Vec3>() * r
        };
        let direct = match self.direct {
            Direct::Learned => eval(&self.networks.direct[object]),
            Direct::Analytic => {
                let frame = Frame::new(si.shading_normal);
                point_lights_at(world, &si, &frame, &si.bsdf.seen_from(frame.to_local(-dir)))
            }
        };
        Radiance { emitted: si.emission, direct, indirect: eval(&self.networks.indirect[object]) }
    }
}
