//! `rrf info [SCENE]`: without a scene, the Vulkan device, its driver and the limits that
//! matter to the renderer; with one, a summary of the scene.

use std::path::Path;

use anyhow::Result;
use rrf_baker::glam::Vec3;
use rrf_baker::scene::{AlphaMode, LightKind, Material, Scene, UvTransform};
use rrf_renderer::{Context, ContextOptions};
use serde_json::json;

pub fn run(scene: Option<&Path>, json: bool) -> Result<()> {
    match scene {
        Some(path) => scene_info(path, json),
        None => device_info(json),
    }
}

fn device_info(json: bool) -> Result<()> {
    let ctx = Context::new(&ContextOptions::from_env())?;
    if json {
        println!("{}", serde_json::to_string(&ctx.info)?);
    } else {
        println!("{}", ctx.info);
    }
    let report = ctx.finish();
    if !report.is_clean() {
        anyhow::bail!(
            "Vulkan teardown was not clean: {} validation messages, leaked {:?}",
            report.validation_messages,
            report.leaked
        );
    }
    Ok(())
}

/// What a material uses beyond its constant factors: textures (with a transform), alpha mask,
/// double sides, emission: what to check after an export.
fn material_features(m: &Material) -> Vec<String> {
    let names = ["base colour", "metallic-roughness", "normal", "emissive"];
    let mut features: Vec<String> = names
        .into_iter()
        .zip(m.textures())
        .filter_map(|(name, t)| {
            let transformed = if t?.transform == UvTransform::IDENTITY { "" } else { " (transformed)" };
            Some(format!("{name} texture{transformed}"))
        })
        .collect();
    if let AlphaMode::Mask { cutoff } = m.alpha_mode {
        features.push(format!("alpha mask (cutoff {cutoff})"));
    }
    if m.double_sided {
        features.push("double-sided".into());
    }
    if m.is_emissive() {
        features.push(format!("emits {:?}", m.emission.to_array()));
    }
    features
}

fn scene_info(path: &Path, json: bool) -> Result<()> {
    let scene = Scene::load(path)?;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    let area_lights = scene.area_lights().count();
    let material_names = |o: &rrf_baker::scene::Object| -> Vec<String> {
        o.parts.iter().map(|p| scene.materials[p.material as usize].name.clone()).collect()
    };
    let aabb = |b: &rrf_baker::scene::Aabb| json!({ "min": point(b.min), "max": point(b.max) });
    let moving_light = scene.moving_light.as_ref().map(|l| {
        json!({
            "node": l.node_name,
            "kind": match l.kind { LightKind::Point(_) => "point", LightKind::Area(_) => "area" },
            "default_position": point(l.default_position),
            "box": aabb(&l.bounds),
        })
    });
    if json {
        let summary = json!({
            "scene": scene.name,
            "gltf": scene.gltf_path,
            "sidecar": scene.sidecar_path,
            "model": scene.model_file(),
            "objects": scene.objects.len(),
            "triangles": scene.triangle_count(),
            "lights": scene.point_lights.len() + area_lights,
            "point_lights": scene.point_lights.len(),
            "area_lights": area_lights,
            "materials": scene.materials.len(),
            "textures": scene.textures.len(),
            "views": scene.views.iter().map(|v| &v.name).collect::<Vec<_>>(),
            "moving_light": moving_light,
            "camera_box": scene.camera_box.as_ref().map(aabb),
            "content_hash": format!("{:016x}", scene.content_hash),
            "object_list": scene.objects.iter().map(|o| json!({
                "id": o.id, "name": o.name, "triangles": o.triangles.len(), "materials": material_names(o),
                "mirror": scene.is_mirror(o.id),
            })).collect::<Vec<_>>(),
            "material_list": scene.materials.iter().map(|m| json!({
                "name": m.name, "features": material_features(m),
            })).collect::<Vec<_>>(),
            "warnings": scene.warnings,
        });
        println!("{summary}");
        return Ok(());
    }

    println!("scene      {} ({})", scene.name, scene.gltf_path.display());
    println!(
        "contents   {} objects, {} triangles, {} materials, {} textures",
        scene.objects.len(),
        scene.triangle_count(),
        scene.materials.len(),
        scene.textures.len()
    );
    let (sidecar, model) = (scene.sidecar_file(), scene.model_file());
    let state = |path: &Path, missing: &str| if path.is_file() { String::new() } else { format!(" ({missing})") };
    println!("sidecar    {}{}", sidecar.display(), state(&sidecar, "not there: `rrf init` writes a starter"));
    println!("model      {}{}", model.display(), state(&model, "not baked yet: `rrf bake`"));
    println!("\n  id  object                 triangles  materials");
    for o in &scene.objects {
        let mirror = if scene.is_mirror(o.id) { " (planar mirror: reflects, has no networks)" } else { "" };
        println!("{:>4}  {:<22} {:>9}  {}{mirror}", o.id, o.name, o.triangles.len(), material_names(o).join(", "));
    }
    println!("\n  material               what rrf reads besides its factors");
    for m in &scene.materials {
        let features = material_features(m);
        println!("  {:<22} {}", m.name, if features.is_empty() { "-".into() } else { features.join(", ") });
    }
    println!("\nlights");
    for l in &scene.point_lights {
        let cone = l.cone.map_or(String::new(), |c| {
            format!(
                ", spot towards {:?} ({:.1}°–{:.1}°)",
                c.direction.to_array(),
                c.cos_inner.acos().to_degrees(),
                c.cos_outer.acos().to_degrees()
            )
        });
        let kind = if l.cone.is_some() { "spot " } else { "point" };
        println!(
            "  {kind}  {:<16} at {:?}, intensity {:?} W/sr{cone}",
            l.name,
            l.position.to_array(),
            l.intensity.to_array()
        );
    }
    for o in scene.area_lights() {
        let materials = || o.parts.iter().map(|p| &scene.materials[p.material as usize]);
        let emission = materials().map(|m| m.emission).fold(Vec3::ZERO, Vec3::max);
        let textured = if materials().any(|m| m.emissive_texture.is_some()) { " × emissive texture" } else { "" };
        println!("  area   {:<16} radiance {:?}{textured}", o.name, emission.to_array());
    }
    println!("\nviews");
    for v in &scene.views {
        println!("  {:<10} eye {:?} target {:?} fov {:.1}°", v.name, v.eye.to_array(), v.target.to_array(), v.fov_y);
    }
    println!("\ndomains");
    match &scene.moving_light {
        Some(l) => println!(
            "  light   {} at {:?}, moves in {:?} .. {:?}",
            l.node_name,
            l.default_position.to_array(),
            l.bounds.min.to_array(),
            l.bounds.max.to_array()
        ),
        None => println!("  light   none (no [light] in a sidecar)"),
    }
    match &scene.camera_box {
        Some(b) => println!("  camera  {:?} .. {:?}", b.min.to_array(), b.max.to_array()),
        None => println!("  camera  none (no [camera] in a sidecar)"),
    }
    Ok(())
}

/// A point as JSON with the f32 noise rounded away (0.05, not 0.05000000074505806).
fn point(p: Vec3) -> [f64; 3] {
    p.to_array().map(|c| (f64::from(c) * 1e6).round() / 1e6)
}
