//! One module per `rrf` subcommand.

pub mod info;
