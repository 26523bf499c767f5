//! One module per `rrf` subcommand.

pub mod bake;
pub mod bench;
pub mod eval;
pub mod image_args;
pub mod info;
pub mod init;
pub mod reference;
pub mod render;
pub mod scene_args;
pub mod variant;
pub mod view;

/// The --model flag of the commands that render from a model.
pub const MODEL_HELP: &str = "Model file; default: model.safetensors beside scene.gltf or scene.glb, \
X.safetensors beside any other X.gltf or X.glb (where `rrf bake` writes it)";

/// What every command's SCENE argument accepts, and where the sidecar is looked for.
pub const SCENE_HELP: &str = "Scene: a folder holding scene.gltf or scene.glb, or a .gltf or .glb file. \
Its sidecar (light and camera boxes, views, bake settings) is the glTF's name with .toml: scene.toml, or \
MyScene.toml beside MyScene.glb";

/// The --direct flag of the commands that render from a model.
pub const DIRECT_HELP: &str = "Where direct light comes from: `auto` (the default: `analytic` where the scene's only \
light is its moving point or spot light and the variant can, `learned` otherwise), `learned` (the direct networks; any \
light) or `analytic` (computed from the BRDF for a point or spot light, with cube shadow maps; tiled and per-object \
variants only)";
