// `include` takes a string literal.
dae::dae! { include 42 }

fn main() {}
