//! `--direct auto`, the default of every command that renders: analytic direct light (the
//! paper's mode, sharp shadows) where the scene's only light is its moving point or spot light
//! and the variant can compute it, learned direct light everywhere else.

use std::path::Path;

use rrf::direct_mode::DirectMode;
use rrf_baker::scene::Scene;
use rrf_renderer::passes::network::Variant;

fn scene(name: &str) -> Scene {
    Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)).unwrap()
}

#[test]
fn auto_picks_analytic_for_a_lone_point_light_and_learned_elsewhere() {
    let cases = [
        ("cornell-box", "an area light", DirectMode::Learned),
        ("glossy-room", "an area light", DirectMode::Learned),
        ("gallery", "a spot light beside an emissive screen", DirectMode::Learned),
        ("many-objects", "a point light alone", DirectMode::Analytic),
    ];
    for (name, lights, expected) in cases {
        let scene = scene(name);
        for variant in [Some(Variant::Tiled), Some(Variant::PerObject), None] {
            assert_eq!(DirectMode::Auto.resolve(&scene, variant), expected, "{name} ({lights}), {variant:?}");
        }
        assert_eq!(DirectMode::Auto.resolve(&scene, Some(Variant::Storage)), DirectMode::Learned, "{name}: storage");
        for chosen in [DirectMode::Learned, DirectMode::Analytic] {
            assert_eq!(chosen.resolve(&scene, Some(Variant::Tiled)), chosen, "{name}: an explicit mode stays");
        }
    }
}
