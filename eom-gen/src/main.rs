//! The `eom-gen` command-line tool.

fn main() {}
