// An empty macro body is not a model.
dae::dae! {}

fn main() {}
