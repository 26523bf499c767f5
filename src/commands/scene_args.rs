//! The arguments of every command that renders a scene with a model (`render`, `view`,
//! `bench`, `eval`): the scene, the model and where direct light comes from.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rrf_baker::model::Model;
use rrf_baker::scene::Scene;

use super::bake::model_to_render;
use super::{DIRECT_HELP, MODEL_HELP, SCENE_HELP};
use crate::direct_mode::DirectMode;

#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    #[arg(help = SCENE_HELP)]
    pub scene: PathBuf,
    #[arg(long, help = MODEL_HELP)]
    pub model: Option<PathBuf>,
    #[arg(long, value_enum, default_value_t = DirectMode::Auto, help = DIRECT_HELP)]
    pub direct: DirectMode,
}

impl SceneArgs {
    /// The scene, and the model to render it with (`--model`, or the one beside the scene),
    /// with a warning for each object the model cannot light well.
    pub fn load(&self) -> Result<(Scene, Model)> {
        let scene = Scene::load(&self.scene)?;
        let model = model_to_render(&scene, self.model.as_deref())?;
        Ok((scene, model))
    }
}
