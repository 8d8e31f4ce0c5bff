//! The `shapeflow` command's subcommands, one module each, and their options.

pub(crate) mod args;
pub(crate) mod keys;
pub(crate) mod run;
pub(crate) mod serve;
