// Pinocchio reference timings on the Panda, for the table of the book's Benchmarks
// (docs/book/src/benchmarks.md)
// (issue 16). Built and run by run.sh beside this file; see README.md there.
//
//   panda <panda_arm_7dof.urdf> [samples=64] [rounds=15]
//
// For `samples` random states (seeded: q uniform within the joint limits, v and a
// uniform in [-1, 1]), each algorithm is run over all the states in a tight loop, single
// thread, timed with std::chrono::steady_clock: a warm-up, then `rounds` rounds of
// `reps` passes over the states; the time per sample of each round is
// round time / (reps * samples), and the median (and minimum) over the rounds is printed.
// One element of each result is added to a checksum that is printed at the end, so the
// compiler cannot drop the work.
//
// crba is Pinocchio's default: it fills the upper triangle of data.M only. The
// "crba + symmetrize" row adds the copy of the strictly upper triangle to the lower one,
// which is what dvrk-model's Model::mass_matrix_into returns (the whole matrix).

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/regressor.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "states.hpp"

namespace pin = pinocchio;

struct Timing {
  double median_us;
  double min_us;
};

// Time `body(i)` for i = 0..n-1, `reps` passes per round, after `warmup` passes.
template <typename F>
static Timing time_per_sample(F &&body, int n, int reps, int rounds, int warmup) {
  for (int w = 0; w < warmup; ++w)
    for (int i = 0; i < n; ++i) body(i);
  std::vector<double> per_sample;
  per_sample.reserve(rounds);
  for (int r = 0; r < rounds; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < reps; ++k)
      for (int i = 0; i < n; ++i) body(i);
    const auto t1 = std::chrono::steady_clock::now();
    const double us = std::chrono::duration<double, std::micro>(t1 - t0).count();
    per_sample.push_back(us / (double(reps) * double(n)));
  }
  std::sort(per_sample.begin(), per_sample.end());
  return {per_sample[per_sample.size() / 2], per_sample.front()};
}

int main(int argc, char **argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s <panda_arm_7dof.urdf> [samples=64] [rounds=15]\n", argv[0]);
    return 2;
  }
  const std::string urdf = argv[1];
  const int n = argc > 2 ? std::atoi(argv[2]) : 64;
  const int rounds = argc > 3 ? std::atoi(argv[3]) : 15;
  if (n < 1 || rounds < 1) {
    std::fprintf(stderr, "samples and rounds must be positive\n");
    return 2;
  }

  pin::Model model;
  pin::urdf::buildModel(urdf, model);
  pin::Data data(model);
  const int nq = model.nq, nv = model.nv;

  // Seeded random states (states.hpp, shared with count.cpp).
  const States st = random_states(model, data, n);
  const auto &q = st.q, &v = st.v, &a = st.a, &tau = st.tau;

  // Enough passes for rounds of some 30 ms at ~1 µs per sample.
  const int reps = std::max(1, 32768 / n);
  const int warmup = std::max(1, reps / 4);
  double checksum = 0.0;

  struct Row {
    const char *name;
    Timing t;
  };
  std::vector<Row> rows;

  rows.push_back({"rnea", time_per_sample(
                              [&](int i) {
                                checksum += pin::rnea(model, data, q[i], v[i], a[i])[nv - 1];
                              },
                              n, reps, rounds, warmup)});
  rows.push_back({"computeJointTorqueRegressor",
                  time_per_sample(
                      [&](int i) {
                        const auto &y =
                            pin::computeJointTorqueRegressor(model, data, q[i], v[i], a[i]);
                        checksum += y(0, y.cols() - 1);
                      },
                      n, reps, rounds, warmup)});
  rows.push_back({"crba (upper triangle)", time_per_sample(
                                               [&](int i) {
                                                 checksum += pin::crba(model, data, q[i])(0, nv - 1);
                                               },
                                               n, reps, rounds, warmup)});
  rows.push_back({"crba + symmetrize",
                  time_per_sample(
                      [&](int i) {
                        pin::crba(model, data, q[i]);
                        data.M.triangularView<Eigen::StrictlyLower>() =
                            data.M.transpose().triangularView<Eigen::StrictlyLower>();
                        checksum += data.M(nv - 1, 0);
                      },
                      n, reps, rounds, warmup)});
  rows.push_back({"aba", time_per_sample(
                             [&](int i) {
                               checksum += pin::aba(model, data, q[i], v[i], tau[i])[nv - 1];
                             },
                             n, reps, rounds, warmup)});
  rows.push_back({"computeGeneralizedGravity",
                  time_per_sample(
                      [&](int i) {
                        checksum += pin::computeGeneralizedGravity(model, data, q[i])[nv - 1];
                      },
                      n, reps, rounds, warmup)});
  rows.push_back({"nonLinearEffects", time_per_sample(
                                          [&](int i) {
                                            checksum +=
                                                pin::nonLinearEffects(model, data, q[i], v[i])[nv - 1];
                                          },
                                          n, reps, rounds, warmup)});

  // Sanity: ABA inverts RNEA on the sampled states.
  double aba_err = 0.0;
  for (int i = 0; i < n; ++i)
    aba_err = std::max(aba_err, (pin::aba(model, data, q[i], v[i], tau[i]) - a[i]).lpNorm<Eigen::Infinity>());

  std::printf("Pinocchio %s, %s (nq=%d nv=%d), %d samples, %d rounds x %d passes, single thread\n",
              PINOCCHIO_VERSION, model.name.c_str(), nq, nv, n, rounds, reps);
  std::printf("| per sample | median | min |\n|---|---|---|\n");
  for (const auto &r : rows)
    std::printf("| %s | %.3f µs | %.3f µs |\n", r.name, r.t.median_us, r.t.min_us);
  std::printf("checksum %.12g, max |aba(rnea(a)) - a| %.3g\n", checksum, aba_err);
  return aba_err < 1e-6 ? 0 : 1;
}
