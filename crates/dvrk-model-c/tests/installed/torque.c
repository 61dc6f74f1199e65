/* The check of an installed dvrk-model C library against the command line:
     torque RESULT Q DQ DDQ
   (each vector comma-separated, model order) prints one JSON line {"tau": [...]}: the
   result's whole model, dvrk_inverse_dynamics at (Q, DQ, DDQ), every number %.17g,
   which run.sh compares with `dvrk-ident model ROBOT --torque --params RESULT`. */
#include <dvrk_model.h>

#include <stdio.h>
#include <stdlib.h>

/* Parses n comma-separated numbers; 0 on success. */
static int parse(const char *text, double *x, size_t n) {
    char *end = NULL;
    for (size_t i = 0; i < n; i++) {
        x[i] = strtod(text, &end);
        if (end == text) return 1;
        if (i + 1 < n) {
            if (*end != ',') return 1;
            text = end + 1;
        }
    }
    return *end != '\0';
}

static void print(const char *label, const double *x, size_t n, const char *after) {
    printf("\"%s\": [", label);
    for (size_t i = 0; i < n; i++) printf(i ? ", %.17g" : "%.17g", x[i]);
    printf("]%s", after);
}

int main(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: %s RESULT Q DQ DDQ\n", argv[0]);
        return 2;
    }
    char err[512];
    DvrkModel *model = dvrk_model_from_result(argv[1], err, sizeof err);
    if (!model) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    size_t n = dvrk_model_dof(model);
    double *v = malloc(4 * n * sizeof(double));
    double *q = v, *dq = v + n, *ddq = v + 2 * n, *tau = v + 3 * n;
    if (parse(argv[2], q, n) || parse(argv[3], dq, n) || parse(argv[4], ddq, n)) {
        fprintf(stderr, "Q, DQ and DDQ need %zu comma-separated numbers each\n", n);
        return 2;
    }
    DvrkWorkspace *ws = dvrk_workspace_new(model);
    int rc = dvrk_inverse_dynamics(model, ws, q, dq, ddq, tau);
    if (rc != DVRK_OK) {
        fprintf(stderr, "%s\n", dvrk_error_string(rc));
        return 1;
    }
    printf("{");
    print("tau", tau, n, "}\n");
    dvrk_workspace_free(ws);
    dvrk_model_free(model);
    free(v);
    return 0;
}
