//! One module per `rrf` subcommand.

pub mod bake;
pub mod bench;
pub mod eval;
pub mod info;
pub mod reference;
pub mod render;
pub mod variant;
pub mod view;
pub mod view_args;
