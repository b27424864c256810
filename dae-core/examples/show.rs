//! Print what dae-core derives for a model file (a debugging aid; the `dae
//! derive` command is the user-facing version).
fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: show MODEL.dae");
        std::process::exit(2);
    };
    let src = match std::fs::read_to_string(&path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(2);
        }
    };
    match dae_core::Derived::from_str(&src) {
        Err(e) => println!("{}", dae_core::derive::render_error(&e, &path)),
        Ok(d) => {
            for c in d.constraint_infos() {
                println!("level {} source {}: 0 = {}", c.level, c.source, c.expr);
            }
            for f in &d.formulations {
                println!(
                    "{} d={:?} s={} c={}",
                    f.name, f.d_index, f.s_index, f.c_level
                );
                for i in 0..f.rows.len() {
                    println!("    {}", f.row_text(&d.model, i));
                }
            }
        }
    }
}
