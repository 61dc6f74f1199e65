//! Prints the base parameters of a robot: `cargo run -p dvrk-model --example print_base -- psm`.
fn main() {
    let name = std::env::args().nth(1).unwrap_or_else(|| "psm".into());
    let t = std::time::Instant::now();
    let model = dvrk_model::Model::load(&name).expect("model");
    let base = model.base_parameters().expect("base parameters");
    println!(
        "{} base parameters of {} ({:?})",
        base.rank(),
        model.n_params(),
        t.elapsed()
    );
    for (i, e) in base.expressions.iter().enumerate() {
        println!("{:3} {e}", i + 1);
    }
}
