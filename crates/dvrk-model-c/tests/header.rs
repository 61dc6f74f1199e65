//! The committed header is what cbindgen makes of src/ (lib.rs and its modules): CI
//! fails when an entry point, a constant or a doc comment changed without the header.
//! With `DVRK_UPDATE_HEADER=1` the test writes the header instead (then commit it).

use std::path::Path;

#[test]
fn header_is_up_to_date() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let bindings = cbindgen::generate(dir).expect("cbindgen parses src/lib.rs");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let generated = String::from_utf8(generated).expect("UTF-8 header");
    let path = dir.join("include/dvrk_model.h");
    if std::env::var_os("DVRK_UPDATE_HEADER").is_some() {
        std::fs::write(&path, &generated).expect("write the header");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "{} is not what cbindgen generates from src/lib.rs: run \
         `DVRK_UPDATE_HEADER=1 cargo test --release -p dvrk-model-c --test header` and commit it",
        path.display()
    );
    // The declarations the issue fixes, by name, so a rename is noticed here too.
    for name in [
        "typedef struct DvrkModel DvrkModel;",
        "typedef struct DvrkWorkspace DvrkWorkspace;",
        "DvrkModel *dvrk_model_from_result(const char *result_path, char *err, size_t err_len);",
        "void dvrk_model_free(DvrkModel *model);",
        "size_t dvrk_model_dof(const DvrkModel *model);",
        "DvrkWorkspace *dvrk_workspace_new(const DvrkModel *model);",
        "void dvrk_workspace_free(DvrkWorkspace *ws);",
        "int dvrk_gravity(",
        "int dvrk_inverse_dynamics(",
        "int dvrk_mass_matrix(",
        "int dvrk_forward_dynamics(",
        "const char *dvrk_error_string(int code);",
        "const char *dvrk_version(void);",
        "typedef struct DvrkObserver DvrkObserver;",
        "DvrkObserver *dvrk_observer_new(const DvrkModel *model, const double *gains);",
        "int dvrk_observer_update(",
        "int dvrk_observer_reset(DvrkObserver *observer);",
        "void dvrk_observer_free(DvrkObserver *observer);",
        "#define DVRK_ERR_ARGUMENT -7",
    ] {
        assert!(generated.contains(name), "the header lacks `{name}`");
    }
}
