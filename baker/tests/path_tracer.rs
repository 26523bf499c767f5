//! The path tracer against closed-form answers: a white furnace, the closed sphere, a point
//! light and a square area light over a Lambert plane; and the emitted/direct/indirect split.

use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use rrf_baker::glam::{Vec2, Vec3, Vec4};
use rrf_baker::model::Model;
use rrf_baker::predict::{predict_image, Direct};
use rrf_baker::scene::{
    Aabb, AlphaMode, BakePresets, ColorSpace, Cone, LightKind, Material, MaterialRange, MovingLight, Object,
    PlacedLight, PointLight, Scene, Texture, TextureRef, UvTransform, View,
};
use rrf_baker::trace::integrator::trace_ray;
use rrf_baker::trace::sampling::Rng;
use rrf_baker::trace::{render, Camera, Footprint, Geometry, Radiance, RenderSettings, TraceSettings, World};

fn material(base: f32, emission: f32) -> Material {
    Material {
        name: "m".into(),
        base_color: Vec3::splat(base),
        alpha: 1.0,
        base_color_texture: None,
        metallic: 0.0,
        roughness: 1.0,
        metallic_roughness_texture: None,
        normal_texture: None,
        emission: Vec3::splat(emission),
        emissive_texture: None,
        specular: 0.0, // pure Lambert
        double_sided: false,
        alpha_mode: AlphaMode::Opaque,
    }
}

struct Mesh {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

/// A UV sphere; `inward` turns it inside out (normals and winding face the centre).
fn sphere(center: Vec3, radius: f32, inward: bool) -> Mesh {
    let (segments, rings) = (48u32, 24u32);
    let mut m = Mesh { positions: vec![], normals: vec![], triangles: vec![] };
    for j in 0..=rings {
        for i in 0..=segments {
            let (theta, phi) = (PI * j as f32 / rings as f32, 2.0 * PI * i as f32 / segments as f32);
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            m.positions.push(center + radius * n);
            m.normals.push(if inward { -n } else { n });
        }
    }
    let row = segments + 1;
    for j in 0..rings {
        for i in 0..segments {
            let (a, b, c, d) = (j * row + i, j * row + i + 1, (j + 1) * row + i + 1, (j + 1) * row + i);
            for t in [[a, b, c], [a, c, d]] {
                let [p, q, r] = t.map(|k| m.positions[k as usize]);
                if (q - p).cross(r - p).length_squared() < 1e-12 {
                    continue;
                }
                let outward = (q - p).cross(r - p).dot(p - center) > 0.0;
                m.triangles.push(if outward != inward { t } else { [t[0], t[2], t[1]] });
            }
        }
    }
    m
}

/// An axis-aligned box; `inward` for an enclosure.
fn cuboid(min: Vec3, max: Vec3, inward: bool) -> Mesh {
    let mut m = Mesh { positions: vec![], normals: vec![], triangles: vec![] };
    let c = (min + max) / 2.0;
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = side;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |su: f32, sv: f32| {
                let mut p = c;
                p[axis] = if side > 0.0 { max[axis] } else { min[axis] };
                p[u] = if su > 0.0 { max[u] } else { min[u] };
                p[v] = if sv > 0.0 { max[v] } else { min[v] };
                p
            };
            let quad = [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
            let facing = if inward { -n } else { n };
            let base = m.positions.len() as u32;
            m.positions.extend(quad);
            m.normals.extend([facing; 4]);
            let geometric = (quad[1] - quad[0]).cross(quad[2] - quad[0]);
            let t = if geometric.dot(facing) > 0.0 { [[0, 1, 2], [0, 2, 3]] } else { [[0, 2, 1], [0, 3, 2]] };
            m.triangles.extend(t.map(|t| t.map(|i| base + i)));
        }
    }
    m
}

/// A horizontal square facing `facing` (±y), centred at `center`.
fn square(center: Vec3, half: f32, facing: f32) -> Mesh {
    let mut m = cuboid(center - Vec3::new(half, 0.0, half), center + Vec3::new(half, 0.0, half), false);
    // Keep only the face whose normal points along `facing`.
    let keep: Vec<[u32; 3]> =
        m.triangles.iter().copied().filter(|t| (m.normals[t[0] as usize].y - facing).abs() < 1e-6).collect();
    m.triangles = keep;
    m
}

/// A scene of `meshes` whose UVs are the world x and z (so that a horizontal square maps a
/// texture from above, v along z) with the matching tangent (+x, bitangent +z).
fn scene(meshes: Vec<(Mesh, Material)>, point_lights: Vec<PointLight>) -> Scene {
    let mut objects = Vec::new();
    let mut materials = Vec::new();
    for (i, (mesh, mat)) in meshes.into_iter().enumerate() {
        let n = mesh.triangles.len() as u32;
        objects.push(Object {
            id: i as u32,
            name: format!("object{i}"),
            node: i,
            origin: Vec3::ZERO,
            uvs: mesh.positions.iter().map(|p| Vec2::new(p.x, p.z)).collect(),
            tangents: vec![Vec4::new(1.0, 0.0, 0.0, -1.0); mesh.positions.len()],
            positions: mesh.positions,
            normals: mesh.normals,
            triangles: mesh.triangles,
            parts: vec![MaterialRange { material: i as u32, triangles: 0..n }],
        });
        materials.push(mat);
    }
    Scene {
        name: "test".into(),
        gltf_path: PathBuf::from("test.gltf"),
        sidecar_path: None,
        objects,
        materials,
        textures: vec![],
        point_lights,
        views: vec![],
        moving_light: None,
        camera_box: None,
        bake: BakePresets::default(),
        eval: Default::default(),
        warnings: vec![],
        content_hash: 0,
        light_transport_hash: 0,
    }
}

/// Mean of `n` estimates of the radiance seen from `origin` towards `target`.
fn estimate(world: &World, origin: Vec3, target: Vec3, settings: &TraceSettings, n: u32, seed: u64) -> Radiance {
    let mut rng = Rng::new(seed, 0);
    let dir = (target - origin).normalize();
    let mut sum = Radiance::default();
    for _ in 0..n {
        sum += trace_ray(world, origin, dir, settings, &mut rng);
    }
    sum.scaled(1.0 / n as f32)
}

fn view(eye: Vec3, target: Vec3, fov_y: f32) -> View {
    View { name: "test".into(), eye, target, up: Vec3::Y, fov_y }
}

/// Inside an enclosure that emits radiance 1 and reflects nothing, white (albedo 1) objects
/// look exactly like the enclosure: radiance 1 everywhere, however light bounces between them.
#[test]
fn white_furnace() {
    let s = scene(
        vec![
            (cuboid(Vec3::splat(-2.0), Vec3::splat(2.0), true), material(0.0, 1.0)),
            (sphere(Vec3::new(-0.5, 0.0, 0.0), 0.45, false), material(1.0, 0.0)),
            (cuboid(Vec3::new(0.05, -0.6, -0.6), Vec3::new(0.8, 0.6, 0.6), false), material(1.0, 0.0)),
        ],
        vec![],
    );
    let geometry = Geometry::new(&s);
    let world = World::new(&s, &geometry, None);
    let camera = Camera::new(&view(Vec3::new(0.0, 0.8, 1.8), Vec3::ZERO, 60.0), 1.0);
    let settings = RenderSettings {
        width: 24,
        height: 24,
        spp: 128,
        trace: TraceSettings { max_depth: 64, rr_depth: None },
        seed: 1,
        footprint: Footprint::Area,
    };
    let image = render(&world, &camera, &settings, &|_| {});
    let values: Vec<Vec3> = image.component(|r| r.gi());
    let mean = values.iter().copied().sum::<Vec3>() / values.len() as f32;
    assert!((mean - Vec3::ONE).abs().max_element() < 0.005, "mean radiance {mean}");
    let far = values.iter().filter(|v| (**v - Vec3::ONE).abs().max_element() > 0.1).count();
    assert!(far * 100 <= values.len(), "{far} of {} pixels are more than 10% off", values.len());
    // Some pixels see the objects: their light is all reflected (direct and indirect).
    let reflected = image.pixels.iter().filter(|r| r.emitted == Vec3::ZERO).count();
    assert!(reflected > values.len() / 4, "the camera should see the objects");
}

/// A closed sphere with albedo a and emission e everywhere: radiance e / (1 − a), of which e
/// is emitted, e·a direct and the rest indirect. With depth D, e (1 − a^D) / (1 − a).
#[test]
fn closed_sphere() {
    let (a, e) = (0.5f32, 1.0f32);
    let s = scene(vec![(sphere(Vec3::ZERO, 1.0, true), material(a, e))], vec![]);
    let geometry = Geometry::new(&s);
    let world = World::new(&s, &geometry, None);
    let origin = Vec3::new(0.1, -0.2, 0.05);
    for (i, target) in [Vec3::X, Vec3::new(0.3, 1.0, -0.2), Vec3::new(-0.5, -0.5, 0.7)].iter().enumerate() {
        let exact = TraceSettings { max_depth: 30, rr_depth: None };
        let r = estimate(&world, origin, *target, &exact, 40_000, i as u64);
        assert!((r.emitted - Vec3::splat(e)).abs().max_element() < 1e-6, "emitted {}", r.emitted);
        assert!((r.direct - Vec3::splat(e * a)).abs().max_element() < 0.01, "direct {}", r.direct);
        let indirect = e * a * a * (1.0 - a.powi(28)) / (1.0 - a);
        assert!((r.indirect - Vec3::splat(indirect)).abs().max_element() < 0.01, "indirect {}", r.indirect);
        // Russian roulette changes the noise, not the expectation.
        let rr = TraceSettings { max_depth: 30, rr_depth: Some(3) };
        let r = estimate(&world, origin, *target, &rr, 40_000, 100 + i as u64);
        let total = e * (1.0 - a.powi(30)) / (1.0 - a);
        assert!((r.gi() - Vec3::splat(total)).abs().max_element() < 0.02, "gi with roulette {}", r.gi());
    }
}

/// A point light of intensity I at height h over a Lambert plane of albedo ρ:
/// L = ρ/π · I cos θ / d², exactly (next-event estimation of a point light has no noise).
#[test]
fn point_light_over_a_plane() {
    let (rho, h, intensity) = (0.5f32, 1.0f32, Vec3::new(2.0, 1.0, 0.5));
    let s = scene(
        vec![(square(Vec3::ZERO, 50.0, 1.0), material(rho, 0.0))],
        vec![PointLight { name: "lamp".into(), node: None, position: Vec3::new(0.0, h, 0.0), intensity, cone: None }],
    );
    let geometry = Geometry::new(&s);
    let world = World::new(&s, &geometry, None);
    let settings = TraceSettings { max_depth: 8, rr_depth: None };
    for x in [Vec3::ZERO, Vec3::new(0.5, 0.0, 0.0), Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 0.0, -0.5)] {
        let eye = x + Vec3::new(0.3, 0.4, 0.2);
        let r = estimate(&world, eye, x, &settings, 4, 0);
        let d = Vec3::new(0.0, h, 0.0) - x;
        let expected = rho / PI * intensity * (h / d.length()) / d.length_squared();
        assert!(
            (r.direct - expected).abs().max_element() <= 1e-4 * expected.max_element(),
            "{x}: {} vs {expected}",
            r.direct
        );
        assert_eq!(r.indirect, Vec3::ZERO, "a single plane has no indirect light");
    }
}

/// The same with a spot light pointing straight down, glTF's falloff between its cone angles:
/// full inside the inner cone, none outside the outer, ((cos θ − cos o)/(cos i − cos o))² between.
#[test]
fn spot_light_over_a_plane() {
    let (rho, h, intensity) = (0.5f32, 1.0f32, Vec3::new(2.0, 1.0, 0.5));
    let (inner, outer) = (20f32.to_radians(), 30f32.to_radians());
    let cone = Cone { direction: Vec3::NEG_Y, cos_inner: inner.cos(), cos_outer: outer.cos() };
    let lamp =
        PointLight { name: "spot".into(), node: None, position: Vec3::new(0.0, h, 0.0), intensity, cone: Some(cone) };
    let s = scene(vec![(square(Vec3::ZERO, 50.0, 1.0), material(rho, 0.0))], vec![lamp]);
    let geometry = Geometry::new(&s);
    let world = World::new(&s, &geometry, None);
    let settings = TraceSettings { max_depth: 8, rr_depth: None };
    for degrees in [0.0f32, 10.0, 19.0, 22.0, 25.0, 28.0, 31.0, 45.0] {
        let theta = degrees.to_radians();
        let x = Vec3::new(h * theta.tan(), 0.0, 0.0);
        let r = estimate(&world, x + Vec3::new(0.1, 0.4, 0.2), x, &settings, 4, 0);
        let d = Vec3::new(0.0, h, 0.0) - x;
        let falloff = ((theta.cos() - outer.cos()) / (inner.cos() - outer.cos())).clamp(0.0, 1.0).powi(2);
        let expected = rho / PI * intensity * falloff * (h / d.length()) / d.length_squared();
        assert!(
            (r.direct - expected).abs().max_element() <= 1e-4 * intensity.max_element(),
            "{degrees}°: {} vs {expected}",
            r.direct
        );
    }
}

/// Form factor from a point to the rectangle [0, x] × [0, z] at height h above it, signed
/// so that rectangles can be added and subtracted.
fn corner_form_factor(x: f32, z: f32, h: f32) -> f32 {
    let (a, b) = (x.abs() / h, z.abs() / h);
    let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
    let f = (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * PI);
    f * x.signum() * z.signum()
}

/// A square light of radiance Le facing down at height h over a Lambert plane of albedo ρ:
/// L = ρ · Le · F, with F the form factor of a parallel rectangle. This exercises light
/// sampling by area, BSDF sampling and their MIS weights together.
#[test]
fn square_area_light_over_a_plane() {
    let (rho, h, half, le) = (0.6f32, 0.8f32, 0.15f32, 10.0f32);
    let s = scene(
        vec![
            (square(Vec3::ZERO, 50.0, 1.0), material(rho, 0.0)),
            (square(Vec3::new(0.0, h, 0.0), half, -1.0), material(0.0, le)),
        ],
        vec![],
    );
    let geometry = Geometry::new(&s);
    let world = World::new(&s, &geometry, None);
    let settings = TraceSettings { max_depth: 2, rr_depth: None };
    for (i, x) in [Vec3::ZERO, Vec3::new(0.1, 0.0, 0.05), Vec3::new(0.6, 0.0, -0.3)].iter().enumerate() {
        let (x1, x2, z1, z2) = (-half - x.x, half - x.x, -half - x.z, half - x.z);
        let f = corner_form_factor(x2, z2, h) - corner_form_factor(x1, z2, h) - corner_form_factor(x2, z1, h)
            + corner_form_factor(x1, z1, h);
        let expected = rho * le * f;
        let eye = *x + Vec3::new(-0.2, 0.3, 0.25);
        let r = estimate(&world, eye, *x, &settings, 50_000, i as u64);
        let relative = (r.direct.x - expected).abs() / expected;
        assert!(relative < 0.005, "{x}: direct {} vs {expected} ({:.3}%)", r.direct.x, 100.0 * relative);
    }
}

/// `scene` with light `kind`, now at `at`, as its moving light.
fn with_moving_light(mut scene: Scene, kind: LightKind, at: Vec3) -> Scene {
    let bounds = Aabb { min: Vec3::splat(-10.0), max: Vec3::splat(10.0) };
    scene.moving_light = Some(MovingLight { node_name: "light".into(), kind, default_position: at, bounds });
    scene
}

/// Two copies of a moving point light, each recoloured, over a Lambert plane: the sum of
/// the closed form of each, ρ/π · Σ s_k I cos θ_k / d_k², exactly.
#[test]
fn copies_of_a_point_light_add_up() {
    let (rho, intensity) = (0.5f32, Vec3::new(2.0, 1.0, 0.5));
    let trained = Vec3::new(0.0, 1.0, 0.0);
    let s = scene(vec![(square(Vec3::ZERO, 50.0, 1.0), material(rho, 0.0))], vec![lamp(trained, intensity)]);
    let s = with_moving_light(s, LightKind::Point(0), trained);
    let lights = [
        PlacedLight { position: Vec3::new(-0.5, 1.2, 0.3), scale: Vec3::new(1.0, 0.2, 0.1) },
        PlacedLight { position: Vec3::new(0.8, 0.6, -0.4), scale: Vec3::new(0.5, 0.5, 3.0) },
    ];
    let geometry = Geometry::new(&s);
    let world = World::with_lights(&s, &geometry, &lights);
    let settings = TraceSettings { max_depth: 8, rr_depth: None };
    for x in [Vec3::ZERO, Vec3::new(0.5, 0.0, 0.0), Vec3::new(-1.0, 0.0, 2.0)] {
        let r = estimate(&world, x + Vec3::new(0.3, 0.4, 0.2), x, &settings, 4, 0);
        let lit = |l: &PlacedLight| {
            let d = l.position - x;
            rho / PI * intensity * l.scale * (l.position.y / d.length()) / d.length_squared()
        };
        let expected: Vec3 = lights.iter().map(lit).sum();
        assert!(
            (r.direct - expected).abs().max_element() <= 1e-4 * expected.max_element(),
            "{x}: {} vs {expected}",
            r.direct
        );
    }
}

/// Two copies of a moving square area light, at different heights and recoloured, over a
/// Lambert plane: ρ · Le · Σ s_k F_k, with light sampling picking among both copies' triangles
/// and MIS weighing BSDF-sampled hits on either. A camera ray that meets a copy sees its
/// scaled emission.
#[test]
fn copies_of_a_square_light_add_up() {
    let (rho, half, le) = (0.6f32, 0.15f32, 10.0f32);
    let trained = Vec3::new(0.0, 0.8, 0.0);
    let s = scene(
        vec![(square(Vec3::ZERO, 50.0, 1.0), material(rho, 0.0)), (square(trained, half, -1.0), material(0.0, le))],
        vec![],
    );
    let s = with_moving_light(s, LightKind::Area(1), trained);
    let lights = [
        PlacedLight { position: Vec3::new(0.1, 0.8, 0.0), scale: Vec3::new(1.0, 0.25, 0.5) },
        PlacedLight { position: Vec3::new(-0.3, 0.5, 0.2), scale: Vec3::new(0.5, 2.0, 1.0) },
    ];
    let geometry = Geometry::new(&s);
    let world = World::with_lights(&s, &geometry, &lights);
    let settings = TraceSettings { max_depth: 2, rr_depth: None };
    for (i, x) in [Vec3::ZERO, Vec3::new(0.6, 0.0, -0.3)].iter().enumerate() {
        let lit = |l: &PlacedLight| {
            let (cx, cz, h) = (l.position.x - x.x, l.position.z - x.z, l.position.y);
            let (x1, x2, z1, z2) = (cx - half, cx + half, cz - half, cz + half);
            let f = corner_form_factor(x2, z2, h) - corner_form_factor(x1, z2, h) - corner_form_factor(x2, z1, h)
                + corner_form_factor(x1, z1, h);
            rho * le * f * l.scale
        };
        let expected: Vec3 = lights.iter().map(lit).sum();
        let r = estimate(&world, *x + Vec3::new(-0.2, 0.3, 0.25), *x, &settings, 50_000, i as u64);
        let relative = ((r.direct - expected).abs() / expected).max_element();
        assert!(relative < 0.01, "{x}: direct {} vs {expected} ({:.3}%)", r.direct, 100.0 * relative);
    }
    for l in &lights {
        let below = l.position - Vec3::new(0.02, 0.3, -0.01);
        let r = estimate(&world, below, l.position, &settings, 1, 0);
        assert!((r.emitted - le * l.scale).abs().max_element() < 1e-4, "{}: {}", l.position, r.emitted);
    }
}

fn texture(width: u32, height: u32, texels: Vec<[u8; 4]>, color_space: ColorSpace) -> Texture {
    Texture { name: "t".into(), width, height, texels, color_space }
}

fn lamp(position: Vec3, intensity: Vec3) -> PointLight {
    PointLight { name: "lamp".into(), node: None, position, intensity, cone: None }
}

/// A point light at height 1 over a Lambert plane, and halfway up a black square whose alpha
/// texture (two texels, transparent then opaque, mapped over x in [-1, 1] by a texture
/// transform) cuts it out where x < 0: the plane is lit exactly as without the square where
/// the shadow ray passes through the cut-out, and black where it meets the solid half.
#[test]
fn alpha_mask_cuts_out_shadows() {
    let (rho, intensity) = (0.5f32, Vec3::splat(2.0));
    let mut occluder = material(0.0, 0.0);
    occluder.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    // u = x / 2 + 0.5: texel 0 (alpha 0) centred at u = 0.25, texel 1 (alpha 1) at 0.75; with
    // bilinear filtering and wrapping, alpha ≥ 0.5 exactly for u in [0.5, 1], x in [0, 1].
    let transform = UvTransform::new([0.5, 0.0], 0.0, [0.5, 1.0]);
    occluder.base_color_texture = Some(TextureRef { texture: 0, transform });
    let mut s = scene(
        vec![
            (square(Vec3::ZERO, 50.0, 1.0), material(rho, 0.0)),
            (square(Vec3::new(0.0, 0.5, 0.0), 1.0, -1.0), occluder),
        ],
        vec![lamp(Vec3::Y, intensity)],
    );
    s.textures.push(texture(2, 1, vec![[0, 0, 0, 0], [0, 0, 0, 255]], ColorSpace::Srgb));
    let geometry = Geometry::new(&s);
    let world = World::new(&s, &geometry, None);
    let settings = TraceSettings { max_depth: 4, rr_depth: None };
    // The shadow ray from plane point x crosses the square at x / 2.
    for x in [-1.5f32, -1.0, -0.3, 0.3, 1.0, 1.5] {
        let p = Vec3::new(x, 0.0, 0.1);
        let r = estimate(&world, p + Vec3::new(0.1, 0.3, 0.1), p, &settings, 4, 0);
        let d = Vec3::Y - p;
        let lit = rho / PI * intensity * (1.0 / d.length()) / d.length_squared();
        let expected = if x < 0.0 { lit } else { Vec3::ZERO };
        assert!((r.direct - expected).abs().max_element() <= 1e-4 * lit.x, "x = {x}: {} vs {expected}", r.direct);
    }
    // The eye under the square sees the plane through the cut-out half, the square elsewhere.
    let through = world.intersect(Vec3::new(-0.5, 1.0, 0.0), Vec3::NEG_Y).unwrap();
    assert!((through.t - 1.0).abs() < 1e-5, "through the cut-out: t = {}", through.t);
    let solid = world.intersect(Vec3::new(0.5, 1.0, 0.0), Vec3::NEG_Y).unwrap();
    assert!((solid.t - 0.5).abs() < 1e-5, "on the solid half: t = {}", solid.t);
}

/// A point light above a Lambert plane whose normal map tilts the shading normal towards the
/// tangent and the bitangent: L = ρ/π · I · (n·l) / d² with the texel's decoded normal.
#[test]
fn normal_map_tilts_the_shading_normal() {
    let (rho, intensity) = (0.5f32, Vec3::splat(3.0));
    let encode = |v: f32| ((v * 0.5 + 0.5) * 255.0).round() as u8;
    let texel = [encode(0.4), encode(-0.3), encode(0.75f32.sqrt()), 255];
    let decoded = Vec3::from_array([0, 1, 2].map(|i| texel[i] as f32 / 255.0 * 2.0 - 1.0));
    let mut plane = material(rho, 0.0);
    plane.normal_texture = Some((TextureRef { texture: 0, transform: UvTransform::IDENTITY }, 1.0));
    let mut s = scene(vec![(square(Vec3::ZERO, 50.0, 1.0), plane)], vec![lamp(Vec3::new(0.0, 1.0, 0.0), intensity)]);
    s.textures.push(texture(1, 1, vec![texel], ColorSpace::Linear));
    let geometry = Geometry::new(&s);
    let world = World::new(&s, &geometry, None);
    let settings = TraceSettings { max_depth: 4, rr_depth: None };
    // Tangent +x, bitangent +z, normal +y: tangent-space (x, y, z) is world (x, z, y).
    let n = Vec3::new(decoded.x, decoded.z, decoded.y).normalize();
    for x in [-0.8f32, 0.0, 0.5, 1.2] {
        let p = Vec3::new(x, 0.0, 0.2);
        let r = estimate(&world, p + Vec3::new(0.1, 0.5, 0.3), p, &settings, 4, 0);
        let d = Vec3::Y - p;
        let expected = rho / PI * intensity * n.dot(d.normalize()).max(0.0) / d.length_squared();
        assert!((r.direct - expected).abs().max_element() <= 1e-4 * intensity.x, "x = {x}: {} vs {expected}", r.direct);
    }
}

/// The emitter's 2×2 texels in linear values, rows of increasing v: red, blue; green, white
/// (its sRGB bytes are 0 and 255, which decode to exactly 0 and 1).
const LINEAR_TEXELS: [[[f32; 3]; 2]; 2] = [[[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], [[0.0, 1.0, 0.0], [1.0, 1.0, 1.0]]];

/// Bilinear filtering of a 2×2 texture that repeats, as glTF's default sampler has it: texel
/// centres at 1/4 and 3/4, and past them a blend with the texel on the other side.
fn bilinear(texels: &[[[f32; 3]; 2]; 2], uv: Vec2) -> Vec3 {
    let p = uv * 2.0 - 0.5;
    let (x0, y0) = (p.x.floor(), p.y.floor());
    let (fx, fy) = (p.x - x0, p.y - y0);
    let at = |x: f32, y: f32| Vec3::from(texels[(y as i64).rem_euclid(2) as usize][(x as i64).rem_euclid(2) as usize]);
    let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1.0, y0) * fx;
    let bottom = at(x0, y0 + 1.0) * (1.0 - fx) + at(x0 + 1.0, y0 + 1.0) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// A square light with an emissive texture over a Lambert plane: L = ρ/π ∫ Le(y) cos θx
/// cos θy / r² dA, by quadrature over the square. Light sampling picks triangles by textured
/// power and the BSDF-sampled hits see the texture, so both strategies and MIS must agree.
#[test]
fn textured_emitter_over_a_plane() {
    let (rho, h, half, le) = (0.6f32, 0.8f32, 0.3f32, 10.0f32);
    let mut light = material(0.0, le);
    // Red-blue-green-white texels, stretched over the square.
    let transform = UvTransform::new([0.5, 0.5], 0.0, [0.5 / half, 0.5 / half]);
    light.emissive_texture = Some(TextureRef { texture: 0, transform });
    let mut s = scene(
        vec![(square(Vec3::ZERO, 50.0, 1.0), material(rho, 0.0)), (square(Vec3::new(0.0, h, 0.0), half, -1.0), light)],
        vec![],
    );
    s.textures.push(texture(
        2,
        2,
        vec![[255, 0, 0, 255], [0, 0, 255, 255], [0, 255, 0, 255], [255, 255, 255, 255]],
        ColorSpace::Srgb,
    ));
    let geometry = Geometry::new(&s);
    let world = World::new(&s, &geometry, None);
    let settings = TraceSettings { max_depth: 2, rr_depth: None };
    let n = 400;
    for (i, x) in [Vec3::ZERO, Vec3::new(0.2, 0.0, -0.1), Vec3::new(0.7, 0.0, 0.4)].iter().enumerate() {
        let mut irradiance = Vec3::ZERO;
        let cell = 2.0 * half / n as f32;
        for j in 0..n {
            for k in 0..n {
                let y = Vec3::new(-half + (j as f32 + 0.5) * cell, h, -half + (k as f32 + 0.5) * cell);
                // The square's UVs are its (x, z); the transform maps [-half, half]² to [0, 1]².
                let uv = Vec2::new(0.5 + 0.5 * y.x / half, 0.5 + 0.5 * y.z / half);
                let emitted = le * bilinear(&LINEAR_TEXELS, uv);
                let d = y - *x;
                let cos = h / d.length();
                irradiance += emitted * cos * cos / d.length_squared() * cell * cell;
            }
        }
        let expected = rho / PI * irradiance;
        let r = estimate(&world, *x + Vec3::new(-0.2, 0.3, 0.25), *x, &settings, 50_000, i as u64);
        let relative = ((r.direct - expected) / expected).abs().max_element();
        assert!(relative < 0.01, "{x}: direct {} vs {expected} ({:.2}%)", r.direct, 100.0 * relative);
    }
}

fn cornell() -> Scene {
    Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell-box")).unwrap()
}

/// The split: the components are disjoint parts of the same paths. Direct light does not
/// depend on how deep the rest of the path goes, and a depth of 2 leaves no indirect light.
#[test]
fn components_split_the_same_paths() {
    let scene = cornell();
    let geometry = Geometry::new(&scene);
    let world = World::new(&scene, &geometry, None);
    let camera = Camera::new(&scene.views[0], 1.0);
    let base = RenderSettings {
        width: 32,
        height: 32,
        spp: 8,
        trace: TraceSettings::default(),
        seed: 5,
        footprint: Footprint::Area,
    };
    let deep = render(&world, &camera, &base, &|_| {});
    let shallow = render(
        &world,
        &camera,
        &RenderSettings { trace: TraceSettings { max_depth: 2, rr_depth: None }, ..base },
        &|_| {},
    );
    for (d, s) in deep.pixels.iter().zip(&shallow.pixels) {
        assert_eq!(d.emitted, s.emitted);
        assert_eq!(d.direct, s.direct);
        assert_eq!(s.indirect, Vec3::ZERO);
        assert_eq!(d.gi(), d.emitted + d.direct + d.indirect);
    }
    let total = |pick: fn(&Radiance) -> Vec3| deep.pixels.iter().map(pick).sum::<Vec3>();
    assert!(total(|r| r.indirect).min_element() > 0.0, "the Cornell box has indirect light");
    // Colour bleeding: indirect light off the red and green walls is not grey.
    let indirect = total(|r| r.indirect);
    assert!((indirect.x - indirect.y).abs() > 0.01 * indirect.x, "indirect {indirect}");
}

#[test]
fn same_seed_same_image_different_seed_different_image() {
    let scene = cornell();
    let geometry = Geometry::new(&scene);
    let world = World::new(&scene, &geometry, None);
    let camera = Camera::new(&scene.views[0], 1.0);
    let s = RenderSettings {
        width: 24,
        height: 16,
        spp: 4,
        trace: TraceSettings::default(),
        seed: 9,
        footprint: Footprint::Area,
    };
    let a = render(&world, &camera, &s, &|_| {});
    let b = render(&world, &camera, &s, &|_| {});
    let c = render(&world, &camera, &RenderSettings { seed: 10, ..s }, &|_| {});
    assert!(a.pixels == b.pixels);
    assert!(a.pixels != c.pixels);
}

/// A centre-footprint image traces each pixel's centre ray, the one the renderer's G-buffer
/// (and its CPU twin, `predict_image`) shades: their emitted light agrees pixel for pixel, the
/// light's rim included, where an area-footprint image blends the rim's pixels with the
/// ceiling.
#[test]
fn centre_footprint_traces_the_renderers_rays() {
    let scene = cornell();
    let geometry = Geometry::new(&scene);
    let world = World::new(&scene, &geometry, None);
    let camera = Camera::new(&scene.views[0], 1.0);
    let model = Model::load(&scene.model_file(), Some(&scene)).unwrap();
    let size = 48;
    let predicted = predict_image(&world, &camera, &model, (size, size), Direct::Learned).component(|r| r.emitted);
    let emitted = |footprint| {
        let trace = TraceSettings { max_depth: 1, rr_depth: None };
        let s = RenderSettings { width: size, height: size, spp: 4, trace, seed: 3, footprint };
        render(&world, &camera, &s, &|_| {}).component(|r| r.emitted)
    };
    let centre = emitted(Footprint::Centre);
    assert!(centre.iter().any(|e| e.max_element() > 0.0), "the view sees the light");
    assert!(centre == predicted, "the same rays see the same emission");
    let rim = emitted(Footprint::Area).iter().zip(&centre).filter(|(a, c)| a != c).count();
    assert!(rim > 0, "an area footprint blends the light's rim");
}

/// A centre-footprint image finds each pixel's first vertex once and shares it among the
/// pixel's paths; each path is still, to the bit, the one `trace_ray` traces along the pixel's
/// centre ray with the path's own random stream.
#[test]
fn centre_footprint_paths_are_trace_rays_paths() {
    let scene = cornell();
    let geometry = Geometry::new(&scene);
    let world = World::new(&scene, &geometry, None);
    let camera = Camera::new(&scene.views[0], 1.0);
    let (width, height, spp, seed) = (12, 10, 3, 21);
    let s = RenderSettings { width, height, spp, trace: TraceSettings::default(), seed, footprint: Footprint::Centre };
    let image = render(&world, &camera, &s, &|_| {});
    for y in 0..height {
        for x in 0..width {
            let pixel = u64::from(y * width + x);
            let film = (Vec2::new(x as f32, y as f32) + 0.5) / Vec2::new(width as f32, height as f32);
            let mut sum = Radiance::default();
            for sample in 0..spp {
                let mut rng = Rng::new(seed, pixel * u64::from(spp) + u64::from(sample));
                sum += trace_ray(&world, camera.eye, camera.direction(film), &s.trace, &mut rng);
            }
            assert_eq!(image.pixels[pixel as usize], sum.scaled(1.0 / spp as f32), "pixel ({x}, {y})");
        }
    }
}

/// Moving the area light moves its light: the floor under the new position gets brighter.
#[test]
fn moving_the_light_moves_the_light() {
    let scene = cornell();
    let geometry = Geometry::new(&scene);
    let light = scene.moving_light.clone().unwrap();
    let settings = TraceSettings { max_depth: 2, rr_depth: None };
    let floor_left = Vec3::new(0.45, 0.0, 0.15);
    let eye = Vec3::new(0.278, 0.3, -0.5);
    let near = World::new(&scene, &geometry, Some(Vec3::new(0.40, 0.45, 0.15)));
    let far = World::new(&scene, &geometry, Some(Vec3::new(0.16, 0.45, 0.43)));
    assert!(light.bounds.contains(Vec3::new(0.40, 0.45, 0.15)));
    let a = estimate(&near, eye, floor_left, &settings, 4000, 1).direct;
    let b = estimate(&far, eye, floor_left, &settings, 4000, 1).direct;
    assert!(a.x > 2.0 * b.x, "near {a} vs far {b}");
}
