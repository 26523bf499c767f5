//! The renderer's network units: for every object, the boxes where a leaf of its direct
//! kd-tree meets a leaf of its indirect one. Every point must lie in exactly one unit of each
//! object, and that unit must carry the two leaves whose regions hold the point, the ones the
//! CPU inference picks (`predict_image`).

use std::path::Path;

use rrf::gpu_frame::{network_units, Direct};
use rrf_baker::glam::Vec3;
use rrf_baker::model::Model;
use rrf_baker::network::Component;
use rrf_baker::scene::Scene;
use rrf_baker::trace::sampling::Rng;

#[test]
fn units_partition_each_object_into_pairs_of_leaves() {
    for name in ["cornell-box", "many-objects"] {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
        let scene = Scene::load(&dir).unwrap();
        let model = Model::load(&dir.join("model.safetensors"), Some(&scene)).unwrap();
        let units = network_units(&scene, &model, Direct::Learned);
        assert!(units.len() > scene.objects.len(), "{name}: the shipped model splits some objects");
        let bounds = scene.bounds();
        let mut rng = Rng::new(7, 0);
        for _ in 0..2000 {
            let p = bounds.min + (bounds.max - bounds.min) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            for (id, object) in scene.objects.iter().enumerate() {
                let holding: Vec<_> = units
                    .iter()
                    .filter(|u| u.object == id && (0..3).all(|a| u.min[a] <= p[a] && p[a] < u.max[a]))
                    .collect();
                let leaf =
                    |component| model.networks(&object.name, component).into_iter().find(|n| n.region.contains(p));
                match (leaf(Component::Direct), leaf(Component::Indirect)) {
                    (Some(direct), Some(indirect)) => {
                        assert_eq!(holding.len(), 1, "{name} {} at {p}", object.name);
                        assert!(holding[0].direct.params == direct.params.as_slice(), "{name} {}", object.name);
                        assert!(holding[0].indirect.params == indirect.params.as_slice(), "{name} {}", object.name);
                    }
                    _ => assert!(holding.is_empty(), "{name} {}: no networks, no unit", object.name),
                }
            }
        }
    }
}
