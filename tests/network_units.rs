//! The renderer's network units: for every object, the pairs of a leaf of its direct kd-tree
//! and a leaf of its indirect one whose blend supports meet, each weighing the product of its
//! leaves' weights. At every point an object's unit weights must sum to one, and the units
//! that carry a leaf must together weigh what the CPU inference weighs it (`predict_image`).

use std::path::Path;

use rrf::direct_mode::DirectMode;
use rrf::scene_frame::network_units;
use rrf_baker::glam::Vec3;
use rrf_baker::model::Model;
use rrf_baker::network::Component;
use rrf_baker::partition::BlendBox;
use rrf_baker::scene::Scene;
use rrf_baker::trace::sampling::Rng;
use rrf_renderer::passes::network::LeafBlend;

#[test]
fn units_weigh_each_objects_leaves_as_the_cpu_does() {
    for name in ["cornell-box", "many-objects"] {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
        let scene = Scene::load(&dir).unwrap();
        let model = Model::load(&dir.join("model.safetensors"), Some(&scene)).unwrap();
        let units = network_units(&scene, &model, DirectMode::Learned);
        assert!(units.len() > scene.objects.len(), "{name}: the shipped model splits some objects");
        let bounds = scene.bounds();
        let mut rng = Rng::new(7, 0);
        for _ in 0..2000 {
            let p = bounds.min + (bounds.max - bounds.min) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            for (id, object) in scene.objects.iter().enumerate() {
                let weighed: Vec<_> = units
                    .iter()
                    .filter(|u| u.object == id)
                    .map(|u| (weight(&u.direct.blend, p) * weight(&u.indirect.blend, p), u))
                    .filter(|&(w, _)| w > 0.0)
                    .collect();
                if !model.has(&object.name, Component::Direct) {
                    assert!(weighed.is_empty(), "{name} {}: no networks, no unit", object.name);
                    continue;
                }
                let total: f32 = weighed.iter().map(|(w, _)| w).sum();
                assert!((total - 1.0).abs() < 1e-5, "{name} {} at {p}: units weigh {total}", object.name);
                for component in [Component::Direct, Component::Indirect] {
                    for leaf in model.networks(&object.name, component) {
                        let carried: f32 = weighed
                            .iter()
                            .filter(|(_, u)| {
                                let n = if component == Component::Direct { u.direct } else { u.indirect };
                                // The leaf itself, not an equal network: two halves that both kept
                                // their parent's network hold the same numbers.
                                std::ptr::eq(n.params, leaf.params.as_slice())
                            })
                            .map(|(w, _)| w)
                            .sum();
                        let expected = leaf.blend.weight(p);
                        assert!(
                            (carried - expected).abs() < 1e-5,
                            "{name} {} at {p}: {carried} for {expected}",
                            object.name
                        );
                    }
                }
            }
        }
    }
}

/// A unit leaf's weight at `p`, by the baker's formula.
fn weight(b: &LeafBlend, p: Vec3) -> f32 {
    BlendBox { min: b.min, max: b.max, min_band: b.min_band, max_band: b.max_band }.weight(p)
}
