//! The 2019 package's `params.json` layout (`fit --wpi-json`, `export --wpi-json`, Python
//! `FitResult.wpi_params()`): the published 2019 parameters come in it, so a fit of ours
//! compares with them field by field and can stand in for them.

/// The parameters in the 2019 package's `params.json` layout: one entry per frame
/// (`"1"` … `"N"`, fixed and virtual frames included, zeros where a frame has no such
/// element), each `{I, r, m, Fc, Fv, Fo, Im, K}` with `I` the inertia about the centre of
/// mass `[xx, xy, xz, yy, yz, zz]` (kg·m²), `r` the centre of mass (m), `m` the mass (kg),
/// `Im` the motor inertia and `K` the spring stiffness.
pub fn wpi_params_json(model: &dvrk_model::Model, params: &[f64]) -> serde_json::Value {
    let mut out = serde_json::Map::new();
    // Frames after the last one with parameters (the PSM's tool-tip frames 17-18, added
    // for wrenches) are not in the 2019 layout, which numbers the dynamic frames only;
    // an empty frame between two with parameters (the PSM's frame 3) is.
    let dynamic = model
        .frames
        .iter()
        .rposition(|f| f.inertia.is_some() || !f.elements.is_empty())
        .map_or(0, |last| last + 1);
    for (i, f) in model.frames.iter().take(dynamic).enumerate() {
        let (mut inertia, mut com, mut mass) = ([0.0; 6], [0.0; 3], 0.0);
        if let Some(p0) = f.inertia {
            let s = dvrk_model::inertia::standard_from_barycentric(&params[p0..p0 + 10]);
            inertia = s.inertia_com;
            com = s.com;
            mass = s.mass;
        }
        let mut entry = serde_json::json!({
            "I": inertia, "r": com, "m": mass, "Fc": 0.0, "Fv": 0.0, "Fo": 0.0, "Im": 0.0, "K": 0.0
        });
        for (field, v) in f.elements.iter().flat_map(|e| e.wpi_fields(params)) {
            entry[field] = v.into();
        }
        out.insert((i + 1).to_string(), entry);
    }
    serde_json::Value::Object(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wpi_layout_has_every_frame_and_standard_values() {
        let model = dvrk_model::Model::builtin("psm").unwrap();
        let mut pi = vec![0.0; model.n_params()];
        let p0 = model.frame(1).inertia.unwrap();
        let bary = dvrk_model::inertia::barycentric_from_standard(
            2.0,
            [0.1, -0.2, 0.05],
            [0.01, 0.001, 0.0, 0.02, 0.0, 0.03],
        );
        pi[p0..p0 + 10].copy_from_slice(&bary);
        let fc = model.param_index("Fc10").unwrap();
        pi[fc] = 0.25;
        let ia = model.param_index("Ia11").unwrap();
        pi[ia] = 0.003;
        let doc = wpi_params_json(&model, &pi);
        let obj = doc.as_object().unwrap();
        assert_eq!(obj.len(), 16);
        assert!((doc["1"]["m"].as_f64().unwrap() - 2.0).abs() < 1e-15);
        assert!((doc["1"]["r"][1].as_f64().unwrap() + 0.2).abs() < 1e-15);
        assert!((doc["1"]["I"][3].as_f64().unwrap() - 0.02).abs() < 1e-15);
        assert_eq!(doc["10"]["Fc"].as_f64().unwrap(), 0.25);
        assert_eq!(doc["11"]["Im"].as_f64().unwrap(), 0.003);
        assert_eq!(doc["3"]["m"].as_f64().unwrap(), 0.0);
    }
}
