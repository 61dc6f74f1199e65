//! The bundled example's files (`examples/`) as the values the tests compare with.

use dvrk_model::Model;

/// The parameters the bundled PSM log was simulated with (`examples/psm_params.json`),
/// in `model`'s order: the truth a fit of that log is checked against.
pub fn psm_params(model: &Model) -> Vec<f64> {
    let doc = crate::read_json(&crate::example("psm_params.json"));
    let map = doc["parameters"]
        .as_object()
        .expect("psm_params.json: an object of parameters");
    model
        .params_from_named(
            map.iter()
                .map(|(k, v)| (k.as_str(), v.as_f64().expect("a number"))),
            "psm_params.json",
        )
        .expect("psm_params.json names the model's parameters")
}
