// Instruction counts per call of Pinocchio's algorithms on the Panda, the counterpart of
// ../count.rs (see README.md beside this file): `count URDF ALGORITHM ITERATIONS` calls
// crba, crba_sym (crba, then the upper triangle copied to the lower one), aba or rnea
// ITERATIONS times, cycling over the 64 seeded random states of states.hpp (panda.cpp's). Built with
// run.sh's compiler, flags and libraries (replace panda.cpp by count.cpp); run under
// `valgrind --tool=cachegrind --cache-sim=no` with two iteration counts, the difference of
// the instruction totals over the difference of the counts is the count per call.
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/parsers/urdf.hpp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>

#include "states.hpp"
namespace pin = pinocchio;
int main(int argc, char **argv) {
  const char *which = argv[2];
  const long iters = std::atol(argv[3]);
  pin::Model model;
  pin::urdf::buildModel(argv[1], model);
  pin::Data data(model);
  const int nv = model.nv, n = 64;
  const States st = random_states(model, data, n);
  const auto &q = st.q, &v = st.v, &a = st.a, &tau = st.tau;
  double checksum = 0.0;
  for (long k = 0; k < iters; ++k) {
    const int i = k % n;
    if (!std::strcmp(which, "crba")) {
      checksum += pin::crba(model, data, q[i])(0, nv - 1);
    } else if (!std::strcmp(which, "crba_sym")) {
      pin::crba(model, data, q[i]);
      data.M.triangularView<Eigen::StrictlyLower>() =
          data.M.transpose().triangularView<Eigen::StrictlyLower>();
      checksum += data.M(nv - 1, 0);
    } else if (!std::strcmp(which, "aba")) {
      checksum += pin::aba(model, data, q[i], v[i], tau[i])[nv - 1];
    } else if (!std::strcmp(which, "rnea")) {
      checksum += pin::rnea(model, data, q[i], v[i], a[i])[nv - 1];
    }
  }
  std::printf("%g\n", checksum);
  return 0;
}
