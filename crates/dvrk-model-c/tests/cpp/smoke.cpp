// The C++ wrapper (include/dvrk_model.hpp) as a controller uses it, compiled with the
// system's `c++ -O2` and run by tests/c_abi.rs with the same arguments and output
// lines as tests/c/smoke.c (`g`, `tau`, `rigid`, `m`, `ddq`, `from_measured`, `to_measured` per
// case, %.17g, and the momentum observer's `obs` and `obs-reset`), which the Rust test compares with dvrk-model's results. Also checks that
// a bad path and an unknown robot throw dvrk::Error with the reason, and that a NaN
// input returns DVRK_ERR_NOT_FINITE with the output untouched. Exits 1 on a failure.
#include "dvrk_model.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

static int failures = 0;

static void check(bool ok, const std::string &what) {
    if (!ok) {
        std::fprintf(stderr, "FAIL: %s\n", what.c_str());
        failures++;
    }
}

static void print_vector(const char *label, const std::vector<double> &x) {
    std::printf("%s", label);
    for (double v : x) std::printf(" %.17g", v);
    std::printf("\n");
}

// The message of the dvrk::Error that loading `path` throws ("" if none is thrown).
static std::string load_error(const std::string &path) {
    try {
        dvrk::Model model(path);
    } catch (const dvrk::Error &e) {
        return e.what();
    }
    return "";
}

// Whether an observer with these gains is refused with dvrk::Error.
static bool load_observer_error(const dvrk::Model &model, const double *gains) {
    try {
        dvrk::Observer observer(model, gains);
    } catch (const dvrk::Error &) {
        return true;
    }
    return false;
}

int main(int argc, char **argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: %s RESULT CASES BAD_ROBOT_RESULT\n", argv[0]);
        return 2;
    }
    dvrk::Model model(argv[1]);
    dvrk::Workspace ws(model);
    const std::size_t n = model.dof();
    std::printf("version %s\n", dvrk::version());
    std::printf("dof %zu measured %zu params %zu\n", n, model.n_measured(), model.n_params());
    std::printf("names %s %s %s\n", model.coordinate_name(0).c_str(),
                model.joint_name(n - 1).c_str(), model.param_name(model.n_params() - 1).c_str());

    std::ifstream cases(argv[2]);
    int k_cases = 0;
    cases >> k_cases;
    std::vector<double> q(n), dq(n), ddq(n), tau_fd(n), out(n), m(n * n);
    for (int c = 0; c < k_cases; c++) {
        for (auto *v : {&q, &dq, &ddq, &tau_fd})
            for (double &x : *v) cases >> x;
        check(ws.gravity(q.data(), out.data()) == DVRK_OK, "gravity");
        print_vector("g", out);
        check(ws.inverse_dynamics(q.data(), dq.data(), ddq.data(), out.data()) == DVRK_OK,
              "inverse dynamics");
        print_vector("tau", out);
        check(ws.rigid_body_dynamics(q.data(), dq.data(), ddq.data(), out.data()) == DVRK_OK,
              "rigid-body dynamics");
        print_vector("rigid", out);
        check(ws.mass_matrix(q.data(), m.data()) == DVRK_OK, "mass matrix");
        print_vector("m", m);
        check(ws.forward_dynamics(q.data(), dq.data(), tau_fd.data(), out.data()) == DVRK_OK,
              "forward dynamics");
        print_vector("ddq", out);
        check(model.measured_to_model(q.data(), out.data()) == DVRK_OK, "measured to model");
        print_vector("from_measured", out);
        check(model.model_to_measured_torque(tau_fd.data(), out.data()) == DVRK_OK,
              "model to measured");
        print_vector("to_measured", out);
    }
    check(static_cast<bool>(cases), "the cases file reads whole");

    // The momentum observer's run (see tests/c/smoke.c): `obs` lines, then `obs-reset`.
    int m_samples = 0;
    double dt = 0.0;
    cases >> m_samples >> dt;
    std::vector<double> gains(n), tau(n);
    for (double &g : gains) cases >> g;
    std::vector<double> zero(n, 0.0);
    check(load_observer_error(model, zero.data()), "Observer(gains 0) throws");
    dvrk::Observer observer(model, gains.data());
    for (int k = 0; k < m_samples; k++) {
        for (auto *v : {&q, &dq, &tau})
            for (double &x : *v) cases >> x;
        check(observer.update(ws, q.data(), dq.data(), tau.data(), dt, out.data()) == DVRK_OK,
              "observer update");
        print_vector("obs", out);
    }
    check(static_cast<bool>(cases), "the observer samples read whole");
    check(observer.reset() == DVRK_OK, "observer reset");
    check(observer.update(ws, q.data(), dq.data(), tau.data(), dt, out.data()) == DVRK_OK,
          "observer update after reset");
    print_vector("obs-reset", out);

    // A NaN: the code, and the output as it was.
    std::vector<double> bad = q;
    bad[0] = std::numeric_limits<double>::quiet_NaN();
    std::vector<double> kept(n, -12345.678);
    int rc = ws.gravity(bad.data(), kept.data());
    check(rc == DVRK_ERR_NOT_FINITE, std::string("gravity(NaN): ") + dvrk::error_string(rc));
    for (double x : kept) check(x == -12345.678, "gravity(NaN) wrote its output");

    // Loading errors as exceptions with the reason.
    std::printf("bad-path: %s\n", load_error("/nonexistent/result.json").c_str());
    std::printf("unknown-robot: %s\n", load_error(argv[3]).c_str());
    // A moved model keeps its workspaces valid.
    dvrk::Model moved(std::move(model));
    check(ws.gravity(q.data(), out.data()) == DVRK_OK, "gravity after the model moved");

    std::printf("failures %d\n", failures);
    return failures == 0 ? 0 : 1;
}
