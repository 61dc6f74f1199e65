// Gravity compensation and inverse dynamics from a dvrk-ident fit result.
#include <cstdio>
#include <vector>

#include "dvrk_model.hpp"

int main(int argc, char **argv) {
    if (argc != 2) return 2;
    // Loading reads files and allocates: before the control loop. Throws dvrk::Error.
    dvrk::Model model(argv[1]);
    dvrk::Workspace ws(model);  // one per thread
    const std::size_t n = model.dof();
    std::vector<double> q(n, 0.1), dq(n, 0.0), ddq(n, 0.0), tau(n);
    q[2] = 0.12;  // the PSM's insertion, in metres
    // In the loop: no allocation, no lock, no exception; 0 or a DVRK_ERR_* code.
    int rc = ws.gravity(q.data(), tau.data());
    if (rc != DVRK_OK) {
        std::fprintf(stderr, "%s\n", dvrk::error_string(rc));
        return 1;
    }
    std::printf("gravity");
    for (double t : tau) std::printf(" %.6f", t);
    rc = ws.inverse_dynamics(q.data(), dq.data(), ddq.data(), tau.data());
    if (rc != DVRK_OK) return 1;
    std::printf("\nstatic torque");
    for (double t : tau) std::printf(" %.6f", t);
    std::printf("\n");
    return 0;
}
