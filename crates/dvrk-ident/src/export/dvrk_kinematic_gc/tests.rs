//! The kinematic gravity-compensation file's unit tests: its refusals' hints.

use super::*;

/// The settings the refusals suggest stay hints until shown: the command line's
/// flags by default, another front end's spelling through `spelled` (Python's are
/// checked in tests/python/test_export.py where a result reaches them).
#[test]
fn refusals_spell_their_settings_when_shown() {
    let python = |h: Hint| match h {
        Hint::MethodSdp => "method=\"sdp\"".to_string(),
        Hint::DvrkGc => "FitResult.dvrk_gc()".to_string(),
        h => h.flag(),
    };
    let massless = Unsuited::Massless {
        link: "yaw".into(),
        first: 0.5,
    };
    let far = Unsuited::FarCom {
        link: "yaw".into(),
        com: [20.0, 0.0, 0.0],
        mass: 1.0,
    };
    assert!(massless.to_string().ends_with("fit with --method sdp)"));
    assert!(dvrk_logs::hint::spelled(&massless, python).ends_with("fit with method=\"sdp\")"));
    assert!(far
        .to_string()
        .ends_with("(fit with --method sdp for physically consistent links)"));
    let far = dvrk_logs::hint::spelled(&far, python);
    assert!(far.ends_with("(fit with method=\"sdp\" for physically consistent links)"));
    let mtm = Unsuited::Robot { name: "mtm".into() };
    assert!(dvrk_logs::hint::spelled(&mtm, python).ends_with("its own file: FitResult.dvrk_gc()"));
}
