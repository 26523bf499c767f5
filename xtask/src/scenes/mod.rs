//! `cargo xtask scenes`: writes the scenes under `scenes/` from code, so that they can be
//! reproduced and changed. Each scene is a plain glTF (`scene.gltf`, `scene.bin`, PNGs) and a
//! sidecar `scene.toml`.

mod cornell_box;
mod gallery;
mod glossy_room;
mod gltf_writer;
mod many_objects;
mod shapes;

use std::path::Path;

/// Builds a scene: the glTF and the sidecar's text.
type SceneBuilder = fn() -> (gltf_writer::GltfBuilder, String);

pub fn generate(root: &Path) -> Result<(), String> {
    let scenes: [(&str, SceneBuilder); 4] = [
        ("cornell-box", cornell_box::build),
        ("gallery", gallery::build),
        ("glossy-room", glossy_room::build),
        ("many-objects", many_objects::build),
    ];
    for (name, build) in scenes {
        let dir = root.join("scenes").join(name);
        let (builder, sidecar) = build();
        let triangles = builder.triangles;
        builder.write(&dir)?;
        std::fs::write(dir.join("scene.toml"), sidecar).map_err(|e| format!("{}: {e}", dir.display()))?;
        eprintln!("xtask: wrote {} ({triangles} triangles)", dir.display());
    }
    Ok(())
}
