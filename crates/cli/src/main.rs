//! The `metaplate` command-line tool.
fn main() {}
