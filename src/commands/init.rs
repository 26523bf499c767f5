//! `rrf init SCENE`: a starter sidecar for a glTF, chosen from what the scene holds, so that
//! `rrf bake` can run on a file fresh from an exporter.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use rrf_baker::atomic_file::write_atomically;
use rrf_baker::glam::Vec3;
use rrf_baker::scene::{Aabb, Scene};
use rrf_baker::trace::sampling::uniform_sphere;
use rrf_baker::trace::world::luminance;
use rrf_baker::trace::{Geometry, World};

#[derive(Args, Debug)]
pub struct InitArgs {
    #[arg(help = super::SCENE_HELP)]
    pub scene: PathBuf,
    /// Replace a sidecar that is already there.
    #[arg(long)]
    pub force: bool,
}

/// Half the size of the light's box, as a share of the scene's extent on each axis.
const LIGHT_BOX: f32 = 0.15;
/// Half the size of the camera's box, as a share of the scene's extent on each axis.
const CAMERA_BOX: f32 = 0.2;

/// The light that will move, and why it was chosen.
struct Choice {
    node: String,
    position: Vec3,
    /// Set when the sidecar adds the light (the scene has none).
    added_intensity: Option<Vec3>,
    why: String,
}

fn choose_light(scene: &Scene, bounds: &Aabb) -> Choice {
    let count = |n: usize, what: &str| match n {
        1 => format!("the scene's only {what}"),
        n => format!("the brightest of the scene's {n} {what}s"),
    };
    if let Some(light) =
        scene.point_lights.iter().max_by(|a, b| luminance(a.intensity).total_cmp(&luminance(b.intensity)))
    {
        return Choice {
            node: light.name.clone(),
            position: light.position,
            added_intensity: None,
            why: count(scene.point_lights.len(), "point light"),
        };
    }
    let power = |o: &rrf_baker::scene::Object| -> f32 {
        o.parts
            .iter()
            .map(|p| luminance(scene.materials[p.material as usize].emission) * o.area(p.triangles.clone()))
            .sum()
    };
    let emitters: Vec<_> = scene.area_lights().collect();
    if let Some(emitter) = emitters.iter().max_by(|a, b| power(a).total_cmp(&power(b))) {
        // Moving an area light moves its node: the box is around the node's position.
        return Choice {
            node: emitter.name.clone(),
            position: emitter.origin,
            added_intensity: None,
            why: count(emitters.len(), "emitter"),
        };
    }
    // No light at all: one the sidecar adds, high over the middle of the scene, bright enough
    // that a white floor under it reads well at exposure 0.
    let extent = bounds.max - bounds.min;
    let position = Vec3::new(
        (bounds.min.x + bounds.max.x) * 0.5,
        bounds.min.y + 0.8 * extent.y,
        (bounds.min.z + bounds.max.z) * 0.5,
    );
    let reach = (0.8 * extent.y).max(0.1 * extent.length()).max(0.1);
    Choice {
        node: "SidecarLight".into(),
        position,
        added_intensity: Some(Vec3::splat(3.0 * reach * reach)),
        why: "a point light the sidecar adds: the scene has no light".into(),
    }
}

/// Directions to probe free space with: a spherical Fibonacci set.
fn probe_directions() -> Vec<Vec3> {
    const N: usize = 64;
    (0..N)
        .map(|i| {
            let golden = 0.618_034_f32;
            uniform_sphere(rrf_baker::glam::Vec2::new((i as f32 + 0.5) / N as f32, (i as f32 * golden).fract()))
        })
        .collect()
}

/// How far `p` is from the nearest surface, if it is a place to look at the scene from: not
/// inside an object (no back face of a one-sided surface seen first), and with surfaces in at
/// least half the directions.
fn clearance(world: &World, p: Vec3) -> Option<f32> {
    let mut nearest = f32::INFINITY;
    let mut hits = 0;
    let directions = probe_directions();
    for &dir in &directions {
        let Some(hit) = world.intersect(p, dir) else { continue };
        let si = world.interaction(p, dir, hit);
        let material = &world.scene.materials[world.geometry.triangles[hit.triangle as usize].material as usize];
        if !si.front_face && !material.double_sided {
            return None;
        }
        hits += 1;
        nearest = nearest.min(hit.t);
    }
    (2 * hits >= directions.len()).then_some(nearest)
}

/// The most open place on a grid over the middle 80% of `bounds`, and its clearance.
fn open_place(world: &World, bounds: &Aabb) -> Option<(Vec3, f32)> {
    const STEPS: usize = 7;
    let mut best: Option<(Vec3, f32)> = None;
    for i in 0..STEPS * STEPS * STEPS {
        let t = Vec3::new((i % STEPS) as f32, (i / STEPS % STEPS) as f32, (i / (STEPS * STEPS)) as f32);
        let p = bounds.lerp(Vec3::splat(0.1) + t * (0.8 / (STEPS - 1) as f32));
        if let Some(c) = clearance(world, p) {
            if best.is_none_or(|(_, b)| c > b) {
                best = Some((p, c));
            }
        }
    }
    best
}

/// A box of half-size `share` × the scene's extent (at least 1% of its diagonal, at most
/// `reach` on every axis) around `centre`, kept inside `bounds` where `inside`.
fn box_around(centre: Vec3, bounds: &Aabb, share: f32, reach: f32, inside: bool) -> Aabb {
    let extent = bounds.max - bounds.min;
    let half = (extent * share).max(Vec3::splat(0.01 * extent.length()).max(Vec3::splat(1e-3))).min(Vec3::splat(reach));
    let (mut min, mut max) = (centre - half, centre + half);
    if inside {
        min = min.max(bounds.min).min(centre);
        max = max.min(bounds.max).max(centre);
    }
    Aabb { min, max }
}

fn vec3(v: Vec3) -> String {
    format!("[{:.4}, {:.4}, {:.4}]", v.x, v.y, v.z)
}

pub fn run(args: &InitArgs) -> Result<()> {
    let located = Scene::load(&args.scene)?;
    let sidecar = located.sidecar_file();
    if sidecar.exists() && !args.force {
        bail!("{}: a sidecar is already there; edit it, or run `rrf init --force` to replace it", sidecar.display());
    }
    // The scene as the glTF alone has it, whatever a sidecar there says.
    let bytes =
        std::fs::read(&located.gltf_path).with_context(|| format!("cannot read {}", located.gltf_path.display()))?;
    let scene = Scene::from_gltf_bytes(&located.gltf_path, &bytes)?;
    let bounds = scene.bounds();
    let light = choose_light(&scene, &bounds);
    let light_box = box_around(light.position, &bounds, LIGHT_BOX, f32::INFINITY, light.added_intensity.is_none());

    // The camera box: around the glTF camera where it looks at the scene from inside it, else
    // around the most open place in the scene; small enough to keep clear of surfaces.
    let geometry = Geometry::new(&scene);
    let world = World::new(&scene, &geometry, None);
    let view = &scene.views[0];
    let at_camera = bounds.contains(view.eye).then(|| clearance(&world, view.eye).map(|c| (view.eye, c))).flatten();
    let (camera_centre, room, camera_why) = match at_camera {
        Some((eye, c)) => (eye, c, "around the glTF camera"),
        None => match open_place(&world, &bounds) {
            Some((p, c)) => (p, c, "around the most open place in the scene (no glTF camera inside it)"),
            None => bail!(
                "{}: found no place inside the scene to look at it from (an open scene with no glTF camera?); \
                 write the sidecar by hand (README: Scenes)",
                scene.gltf_path.display()
            ),
        },
    };
    let camera_box = box_around(camera_centre, &bounds, CAMERA_BOX, 0.5 * room, true);
    // The start view: the glTF camera where the box is around it, else the longest
    // unobstructed, roughly level look from the box's centre.
    let (start_eye, fov) = (camera_centre, view.fov_y);
    let direction = match at_camera {
        Some(_) => (view.target - view.eye).normalize(),
        None => {
            let depth = |d: Vec3| world.intersect(start_eye, d).map_or(0.0, |hit| hit.t);
            let level = probe_directions().into_iter().filter(|d| d.y.abs() < 0.3);
            level.max_by(|a, b| depth(*a).total_cmp(&depth(*b))).unwrap_or(Vec3::Z)
        }
    };
    let start_target = start_eye + direction;

    let mut text = format!(
        "# Written by `rrf init` for {}; edit freely (README: Scenes).\n\n",
        scene.gltf_path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default()
    );
    let _ = writeln!(text, "[light]                 # {}", light.why);
    let _ = writeln!(text, "node = {:?}", light.node);
    let _ = writeln!(text, "min = {}", vec3(light_box.min));
    let _ = writeln!(text, "max = {}", vec3(light_box.max));
    if let Some(intensity) = light.added_intensity {
        let _ = writeln!(text, "intensity = {}   # W/sr; the light sits at the box's centre", vec3(intensity));
    }
    let _ = writeln!(text, "\n[camera]                # {camera_why}");
    let _ = writeln!(text, "min = {}", vec3(camera_box.min));
    let _ = writeln!(text, "max = {}", vec3(camera_box.max));
    let _ = writeln!(text, "\n[views.start]");
    let _ = writeln!(text, "eye = {}", vec3(start_eye));
    let _ = writeln!(text, "target = {}", vec3(start_target));
    let _ = writeln!(text, "fov_y = {fov:.1}");
    let _ = writeln!(text, "\n# [bake.final]          # overrides of a bake preset; see `rrf bake --help`");
    let _ = writeln!(text, "# configurations = 256");

    write_atomically(&sidecar, |tmp| {
        std::fs::write(tmp, &text).with_context(|| format!("cannot write {}", tmp.display()))
    })?;
    // What was written must load: the import checks the boxes against the scene.
    Scene::load(&args.scene).with_context(|| format!("{} was written but does not load", sidecar.display()))?;
    eprintln!("wrote {}:", sidecar.display());
    eprintln!("  moving light  {:?}: {}", light.node, light.why);
    eprintln!("  light box     {} .. {}", vec3(light_box.min), vec3(light_box.max));
    eprintln!("  camera box    {} .. {}, {camera_why}", vec3(camera_box.min), vec3(camera_box.max));
    eprintln!("  view `start`  from {} towards {}", vec3(start_eye), vec3(start_target));
    eprintln!("next: rrf bake {} --quality preview", args.scene.display());
    Ok(())
}
