// `include` paths are relative to the crate root; this file does not exist.
dae::dae! { include "scenes/no_such_model.dae" }

fn main() {}
