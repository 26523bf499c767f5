//! The glossy room's mirror against the path tracer: the CPU inference shows in it the room
//! that the path tracer sees there, through the networks of the surfaces it reflects.

use std::path::Path;

use rrf_baker::glam::{Vec2, Vec3};
use rrf_baker::model::Model;
use rrf_baker::predict::{predict_image, Direct};
use rrf_baker::scene::Scene;
use rrf_baker::trace::{render, Camera, Footprint, Geometry, Radiance, RenderSettings, TraceSettings, World};

const SIZE: (u32, u32) = (96, 64);

/// Squared error of `values` against `reference`, over the reference's squares.
fn relative_squared_error(values: &[Vec3], reference: &[Vec3]) -> f32 {
    let error: f32 = values.iter().zip(reference).map(|(v, r)| (*v - *r).length_squared()).sum();
    error / reference.iter().map(|r| r.length_squared()).sum::<f32>()
}

/// The mirror's pixels, predicted, carry the reference's image: their mean within 10% of the
/// reference's, and their squared error under half that of the best flat fill (the mean), which
/// is what a network that smears the reflection comes to. Without the reflection the mirror
/// is black and the error is the reference's whole energy.
#[test]
fn the_mirror_shows_the_room_the_path_tracer_sees() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/glossy-room");
    let scene = Scene::load(&dir).unwrap();
    let model = Model::load(&dir.join("model.safetensors"), Some(&scene)).unwrap();
    let [mirror] = scene.mirrors()[..] else { panic!("the glossy room has one mirror: {:?}", scene.mirrors()) };
    let view = scene.view("mirror").unwrap();
    let geometry = Geometry::new(&scene);
    let world = World::new(&scene, &geometry, None);
    let (width, height) = SIZE;
    let camera = Camera::new(view, width as f32 / height as f32);

    let predicted = predict_image(&world, &camera, &model, SIZE, Direct::Learned);
    let settings = RenderSettings {
        width,
        height,
        spp: 512,
        trace: TraceSettings::default(),
        seed: 7,
        footprint: Footprint::Centre,
    };
    let reference = render(&world, &camera, &settings, &|_| {});

    let size = Vec2::new(width as f32, height as f32);
    let in_mirror: Vec<usize> = (0..width * height)
        .filter(|i| {
            let film = (Vec2::new((i % width) as f32, (i / width) as f32) + 0.5) / size;
            let dir = camera.direction(film);
            world
                .intersect(camera.eye, dir)
                .is_some_and(|hit| world.interaction(camera.eye, dir, hit).object == mirror.object)
        })
        .map(|i| i as usize)
        .collect();
    assert!(
        in_mirror.len() * 6 >= (width * height) as usize,
        "the mirror view sees the mirror: {} pixels",
        in_mirror.len()
    );
    let pick = |image: &[Radiance]| in_mirror.iter().map(|&i| image[i].gi()).collect::<Vec<_>>();
    let (predicted, reference) = (pick(&predicted.pixels), pick(&reference.pixels));

    let mean = |v: &[Vec3]| v.iter().sum::<Vec3>() / v.len() as f32;
    let (p, r) = (mean(&predicted), mean(&reference));
    let ratio = p.element_sum() / r.element_sum();
    let error = relative_squared_error(&predicted, &reference);
    let flat = relative_squared_error(&vec![r; reference.len()], &reference);
    eprintln!("{} mirror pixels: mean {p} against {r} (ratio {ratio:.3}); relative squared error {error:.4}, a flat fill's {flat:.4}", in_mirror.len());
    assert!((ratio - 1.0).abs() < 0.1, "the mirror's mean is {ratio:.3} of the reference's");
    assert!(error < 0.5 * flat, "the mirror's error {error:.4} is not under half a flat fill's {flat:.4}");
}
