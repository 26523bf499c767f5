//! One module per `rrf` subcommand.

pub mod info;
pub mod reference;
pub mod view_args;
