/* The C ABI from C, as a controller uses it: load a `dvrk-ident fit` result, evaluate
   gravity, inverse dynamics, the mass matrix and forward dynamics, and check the error
   paths (bad path, unknown robot, NULL pointers, NaN inputs, a workspace of another
   model): every error a negative code or a message, outputs untouched, no crash.

   Compiled with the system's `cc -O2` and run by tests/c_abi.rs:
     smoke RESULT CASES BAD_ROBOT_RESULT
   CASES holds a count K, then K cases of 4n numbers (q, dq, ddq, tau_fd). For each case
   the program prints the lines `g`, `tau`, `rigid`, `m` (row-major) and `ddq` (the forward
   dynamics under tau_fd), every number with %.17g, which the Rust test compares with
   dvrk-model's own results. CASES then holds the momentum observer's run: a count M and
   a step dt (s), the n gains (1/s), and M samples of 3n numbers (q, dq, tau); the program
   prints `obs` and the estimate after each update, with the error paths of
   dvrk_observer_update tried before update M/2 (the Rust side's observer, which sees
   none of them, must still agree bit for bit), then `obs-reset` after a reset and one
   update. Any failed check prints `FAIL ...` on stderr and exits 1. */
#include "dvrk_model.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures = 0;

#define CHECK(cond, ...)                                   \
    do {                                                   \
        if (!(cond)) {                                     \
            fprintf(stderr, "FAIL line %d: ", __LINE__);   \
            fprintf(stderr, __VA_ARGS__);                  \
            fprintf(stderr, "\n");                         \
            failures++;                                    \
        }                                                  \
    } while (0)

static void print_vector(const char *label, const double *x, size_t n) {
    printf("%s", label);
    for (size_t i = 0; i < n; i++) printf(" %.17g", x[i]);
    printf("\n");
}

/* Fills x with a sentinel no computation returns, to see that an error leaves it. */
static const double SENTINEL = -12345.678;
static void fill(double *x, size_t n) {
    for (size_t i = 0; i < n; i++) x[i] = SENTINEL;
}
static int untouched(const double *x, size_t n) {
    for (size_t i = 0; i < n; i++)
        if (x[i] != SENTINEL) return 0;
    return 1;
}

/* Checks that a call returned `code` and left out[0..len) untouched (len 0 where the
   output argument was NULL itself); the format and what follows name the call. */
static void check_code(int line, int rc, int code, const double *out, size_t len,
                       const char *format, ...) {
    if (rc == code && untouched(out, len)) return;
    va_list args;
    va_start(args, format);
    fprintf(stderr, "FAIL line %d: ", line);
    vfprintf(stderr, format, args);
    va_end(args);
    fprintf(stderr, " = %d, expected %d%s\n", rc, code,
            untouched(out, len) ? "" : " with the output untouched");
    failures++;
}
#define CHECK_CODE(call, code, out, len, ...) \
    check_code(__LINE__, call, code, out, len, __VA_ARGS__)

/* Every error path of the real-time calls: NULL model, workspace, input and output; a
   NaN and an infinity in each input; a workspace of another model. */
static void check_errors(const DvrkModel *model, DvrkWorkspace *ws, const DvrkModel *other,
                         const double *q, size_t n) {
    double *out = malloc(n * n * sizeof(double));
    double *bad = malloc(n * sizeof(double));
    DvrkWorkspace *other_ws = dvrk_workspace_new(other);

    fill(out, n * n);
    CHECK_CODE(dvrk_gravity(NULL, ws, q, out), DVRK_ERR_NULL, out, n, "gravity(NULL model)");
    CHECK_CODE(dvrk_gravity(model, NULL, q, out), DVRK_ERR_NULL, out, n, "gravity(NULL ws)");
    CHECK_CODE(dvrk_gravity(model, ws, NULL, out), DVRK_ERR_NULL, out, n, "gravity(NULL q)");
    CHECK_CODE(dvrk_gravity(model, ws, q, NULL), DVRK_ERR_NULL, out, 0, "gravity(NULL tau)");
    CHECK_CODE(dvrk_gravity(model, other_ws, q, out),
               DVRK_ERR_WORKSPACE, out, n, "gravity(other ws)");

    for (size_t k = 0; k < n; k++) {
        for (int inf = 0; inf < 2; inf++) {
            memcpy(bad, q, n * sizeof(double));
            bad[k] = inf ? INFINITY : NAN;
            fill(out, n * n);
            CHECK_CODE(dvrk_gravity(model, ws, bad, out),
                       DVRK_ERR_NOT_FINITE, out, n, "gravity(bad q[%zu])", k);
            CHECK_CODE(dvrk_mass_matrix(model, ws, bad, out),
                       DVRK_ERR_NOT_FINITE, out, n * n, "mass(bad q[%zu])", k);
            /* the bad vector in each of the three inputs in turn */
            for (int which = 0; which < 3; which++) {
                const double *in[3] = {q, q, q};
                in[which] = bad;
                CHECK_CODE(dvrk_inverse_dynamics(model, ws, in[0], in[1], in[2], out),
                           DVRK_ERR_NOT_FINITE, out, n, "id(bad input %d, [%zu])", which, k);
                CHECK_CODE(dvrk_rigid_body_dynamics(model, ws, in[0], in[1], in[2], out),
                           DVRK_ERR_NOT_FINITE, out, n, "rigid(bad input %d, [%zu])", which, k);
                CHECK_CODE(dvrk_forward_dynamics(model, ws, in[0], in[1], in[2], out),
                           DVRK_ERR_NOT_FINITE, out, n, "fd(bad input %d, [%zu])", which, k);
            }
        }
    }
    fill(out, n * n);
    CHECK_CODE(dvrk_inverse_dynamics(model, ws, q, NULL, q, out),
               DVRK_ERR_NULL, out, n, "id(NULL dq)");
    CHECK_CODE(dvrk_inverse_dynamics(model, ws, q, q, NULL, out),
               DVRK_ERR_NULL, out, n, "id(NULL ddq)");
    CHECK_CODE(dvrk_rigid_body_dynamics(model, ws, q, q, q, NULL),
               DVRK_ERR_NULL, out, 0, "rigid(NULL tau)");
    CHECK_CODE(dvrk_mass_matrix(NULL, ws, q, out), DVRK_ERR_NULL, out, n * n, "mass(NULL model)");
    CHECK_CODE(dvrk_mass_matrix(model, ws, q, NULL), DVRK_ERR_NULL, out, 0, "mass(NULL m)");
    CHECK_CODE(dvrk_forward_dynamics(model, NULL, q, q, q, out),
               DVRK_ERR_NULL, out, n, "fd(NULL ws)");
    CHECK_CODE(dvrk_forward_dynamics(model, ws, q, q, NULL, out),
               DVRK_ERR_NULL, out, n, "fd(NULL tau)");
    CHECK_CODE(dvrk_measured_to_model(model, NULL, out),
               DVRK_ERR_NULL, out, n, "measured_to_model(NULL)");
    CHECK_CODE(dvrk_model_to_measured_torque(NULL, q, out),
               DVRK_ERR_NULL, out, n, "model_to_measured_torque(NULL)");

    /* NULL objects are harmless everywhere else too. */
    CHECK(dvrk_model_dof(NULL) == 0, "dof(NULL)");
    CHECK(dvrk_model_n_measured(NULL) == 0, "n_measured(NULL)");
    CHECK(dvrk_workspace_new(NULL) == NULL, "workspace_new(NULL)");
    CHECK(dvrk_model_param_name(model, 1000000) == NULL, "param_name(out of range)");
    dvrk_workspace_free(NULL);
    dvrk_model_free(NULL);

    /* Every code has its own message; an unknown code has one too. */
    int codes[] = {DVRK_OK, DVRK_ERR_NULL, DVRK_ERR_NOT_FINITE, DVRK_ERR_WORKSPACE,
                   DVRK_ERR_NOT_POSITIVE_DEFINITE, DVRK_ERR_OVERFLOW, DVRK_ERR_INTERNAL,
                   DVRK_ERR_ARGUMENT};
    size_t nc = sizeof codes / sizeof codes[0];
    for (size_t i = 0; i < nc; i++) {
        CHECK(dvrk_error_string(codes[i]) != NULL && strlen(dvrk_error_string(codes[i])) > 0,
              "error_string(%d)", codes[i]);
        for (size_t j = 0; j < i; j++)
            CHECK(strcmp(dvrk_error_string(codes[i]), dvrk_error_string(codes[j])) != 0,
                  "codes %d and %d share a message", codes[i], codes[j]);
    }
    printf("error %d: %s\n", DVRK_ERR_NOT_FINITE, dvrk_error_string(DVRK_ERR_NOT_FINITE));
    CHECK(strcmp(dvrk_error_string(-999), "unknown error code") == 0, "error_string(-999)");

    dvrk_workspace_free(other_ws);
    free(bad);
    free(out);
}

/* The momentum observer over the samples of `cases` (see the top comment); `other` is
   another model, whose observer and workspace the calls on `model` refuse. */
static void run_observer(FILE *cases, const DvrkModel *model, DvrkWorkspace *ws,
                         const DvrkModel *other) {
    size_t n = dvrk_model_dof(model);
    int m_samples = 0;
    double dt = 0.0;
    if (fscanf(cases, "%d %lf", &m_samples, &dt) != 2) {
        CHECK(0, "no observer samples in the cases file");
        return;
    }
    double *gains = malloc(n * sizeof(double));
    double *x = malloc(3 * n * sizeof(double));
    double *out = malloc(n * sizeof(double));
    double *bad = malloc(n * sizeof(double));
    for (size_t i = 0; i < n; i++)
        if (fscanf(cases, "%lf", &gains[i]) != 1) CHECK(0, "gains");
    /* Gains that are not positive and finite, or none: no observer. */
    memcpy(bad, gains, n * sizeof(double));
    bad[n - 1] = 0.0;
    CHECK(dvrk_observer_new(model, bad) == NULL, "observer_new(gain 0)");
    bad[n - 1] = NAN;
    CHECK(dvrk_observer_new(model, bad) == NULL, "observer_new(gain NaN)");
    CHECK(dvrk_observer_new(model, NULL) == NULL, "observer_new(NULL gains)");
    CHECK(dvrk_observer_new(NULL, gains) == NULL, "observer_new(NULL model)");
    DvrkObserver *obs = dvrk_observer_new(model, gains);
    DvrkObserver *other_obs = dvrk_observer_new(other, gains);
    DvrkWorkspace *other_ws = dvrk_workspace_new(other);
    CHECK(obs != NULL && other_obs != NULL, "observer_new");
    const double *q = x, *dq = x + n, *tau = x + 2 * n;
    for (int k = 0; k < m_samples; k++) {
        for (size_t i = 0; i < 3 * n; i++)
            if (fscanf(cases, "%lf", &x[i]) != 1) CHECK(0, "observer sample %d", k);
        if (k == m_samples / 2) {
            fill(out, n);
            CHECK_CODE(dvrk_observer_update(model, ws, NULL, q, dq, tau, dt, out),
                       DVRK_ERR_NULL, out, n, "update(NULL observer)");
            CHECK_CODE(dvrk_observer_update(NULL, ws, obs, q, dq, tau, dt, out),
                       DVRK_ERR_NULL, out, n, "update(NULL model)");
            CHECK_CODE(dvrk_observer_update(model, ws, obs, q, NULL, tau, dt, out),
                       DVRK_ERR_NULL, out, n, "update(NULL dq)");
            CHECK_CODE(dvrk_observer_update(model, ws, obs, q, dq, tau, dt, NULL),
                       DVRK_ERR_NULL, out, 0, "update(NULL tau_ext)");
            CHECK_CODE(dvrk_observer_update(model, other_ws, obs, q, dq, tau, dt, out),
                       DVRK_ERR_WORKSPACE, out, n, "update(other ws)");
            CHECK_CODE(dvrk_observer_update(model, ws, other_obs, q, dq, tau, dt, out),
                       DVRK_ERR_ARGUMENT, out, n, "update(other observer)");
            CHECK_CODE(dvrk_observer_update(model, ws, obs, q, dq, tau, 0.0, out),
                       DVRK_ERR_ARGUMENT, out, n, "update(dt 0)");
            CHECK_CODE(dvrk_observer_update(model, ws, obs, q, dq, tau, -dt, out),
                       DVRK_ERR_ARGUMENT, out, n, "update(dt < 0)");
            CHECK_CODE(dvrk_observer_update(model, ws, obs, q, dq, tau, NAN, out),
                       DVRK_ERR_NOT_FINITE, out, n, "update(dt NaN)");
            CHECK_CODE(dvrk_observer_update(model, ws, obs, q, dq, tau, INFINITY, out),
                       DVRK_ERR_NOT_FINITE, out, n, "update(dt inf)");
            for (int which = 0; which < 3; which++) {
                memcpy(bad, x + which * n, n * sizeof(double));
                bad[which] = NAN;
                const double *in[3] = {q, dq, tau};
                in[which] = bad;
                CHECK_CODE(dvrk_observer_update(model, ws, obs, in[0], in[1], in[2], dt, out),
                           DVRK_ERR_NOT_FINITE, out, n, "update(NaN in input %d)", which);
            }
        }
        int rc = dvrk_observer_update(model, ws, obs, q, dq, tau, dt, out);
        CHECK(rc == DVRK_OK, "observer update %d: %s", k, dvrk_error_string(rc));
        print_vector("obs", out, n);
    }
    CHECK(dvrk_observer_reset(NULL) == DVRK_ERR_NULL, "reset(NULL)");
    CHECK(dvrk_observer_reset(obs) == DVRK_OK, "reset");
    int rc = dvrk_observer_update(model, ws, obs, q, dq, tau, dt, out);
    CHECK(rc == DVRK_OK, "update after reset: %s", dvrk_error_string(rc));
    print_vector("obs-reset", out, n);
    dvrk_observer_free(NULL);
    dvrk_observer_free(other_obs);
    dvrk_observer_free(obs);
    dvrk_workspace_free(other_ws);
    free(bad);
    free(out);
    free(x);
    free(gains);
}

/* Loading errors: each a NULL model with a message, which the test prints for the Rust
   side to check. */
static void check_load_errors(const char *bad_robot_result) {
    char err[256];
    err[0] = 'x';
    CHECK(dvrk_model_from_result(NULL, err, sizeof err) == NULL, "from_result(NULL)");
    printf("null-path: %s\n", err);
    CHECK(dvrk_model_from_result("/nonexistent/result.json", err, sizeof err) == NULL,
          "from_result(bad path)");
    printf("bad-path: %s\n", err);
    CHECK(dvrk_model_from_result(bad_robot_result, err, sizeof err) == NULL,
          "from_result(unknown robot)");
    printf("unknown-robot: %s\n", err);
    /* A short buffer: truncated and NUL-terminated; a NULL one: no message, no crash. */
    char small[8];
    memset(small, 'x', sizeof small);
    CHECK(dvrk_model_from_result("/nonexistent/result.json", small, sizeof small) == NULL,
          "from_result(bad path, small err)");
    CHECK(strlen(small) == sizeof small - 1, "truncated message of %zu bytes", strlen(small));
    CHECK(dvrk_model_from_result("/nonexistent/result.json", NULL, 0) == NULL,
          "from_result(bad path, NULL err)");
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: %s RESULT CASES BAD_ROBOT_RESULT\n", argv[0]);
        return 2;
    }
    char err[512];
    DvrkModel *model = dvrk_model_from_result(argv[1], err, sizeof err);
    if (!model) {
        fprintf(stderr, "FAIL: cannot load %s: %s\n", argv[1], err);
        return 1;
    }
    DvrkModel *other = dvrk_model_from_result(argv[1], err, sizeof err);
    CHECK(other != NULL, "second load: %s", err);
    size_t n = dvrk_model_dof(model);
    printf("version %s\n", dvrk_version());
    printf("dof %zu measured %zu params %zu\n", n, dvrk_model_n_measured(model),
           dvrk_model_n_params(model));
    printf("names %s %s %s\n", dvrk_model_coordinate_name(model, 0),
           dvrk_model_joint_name(model, n - 1),
           dvrk_model_param_name(model, dvrk_model_n_params(model) - 1));
    DvrkWorkspace *ws = dvrk_workspace_new(model);
    CHECK(ws != NULL, "workspace_new");

    FILE *cases = fopen(argv[2], "r");
    if (!cases) {
        fprintf(stderr, "FAIL: cannot open %s\n", argv[2]);
        return 1;
    }
    int k_cases = 0;
    if (fscanf(cases, "%d", &k_cases) != 1) return 1;
    double *x = malloc(4 * n * sizeof(double));
    double *out = malloc(n * n * sizeof(double));
    for (int c = 0; c < k_cases; c++) {
        for (size_t i = 0; i < 4 * n; i++)
            if (fscanf(cases, "%lf", &x[i]) != 1) return 1;
        const double *q = x, *dq = x + n, *ddq = x + 2 * n, *tau_fd = x + 3 * n;
        int rc;
        rc = dvrk_gravity(model, ws, q, out);
        CHECK(rc == DVRK_OK, "gravity: %s", dvrk_error_string(rc));
        print_vector("g", out, n);
        rc = dvrk_inverse_dynamics(model, ws, q, dq, ddq, out);
        CHECK(rc == DVRK_OK, "inverse dynamics: %s", dvrk_error_string(rc));
        print_vector("tau", out, n);
        rc = dvrk_rigid_body_dynamics(model, ws, q, dq, ddq, out);
        CHECK(rc == DVRK_OK, "rigid-body dynamics: %s", dvrk_error_string(rc));
        print_vector("rigid", out, n);
        rc = dvrk_mass_matrix(model, ws, q, out);
        CHECK(rc == DVRK_OK, "mass matrix: %s", dvrk_error_string(rc));
        print_vector("m", out, n * n);
        rc = dvrk_forward_dynamics(model, ws, q, dq, tau_fd, out);
        CHECK(rc == DVRK_OK, "forward dynamics: %s", dvrk_error_string(rc));
        print_vector("ddq", out, n);
        rc = dvrk_measured_to_model(model, q, out);
        CHECK(rc == DVRK_OK, "measured to model: %s", dvrk_error_string(rc));
        print_vector("from_measured", out, n);
        rc = dvrk_model_to_measured_torque(model, tau_fd, out);
        CHECK(rc == DVRK_OK, "model to measured: %s", dvrk_error_string(rc));
        print_vector("to_measured", out, n);
    }
    run_observer(cases, model, ws, other);
    fclose(cases);

    check_errors(model, ws, other, x, n);
    check_load_errors(argv[3]);

    free(out);
    free(x);
    dvrk_workspace_free(ws);
    dvrk_model_free(other);
    dvrk_model_free(model);
    printf("failures %d\n", failures);
    return failures == 0 ? 0 : 1;
}
