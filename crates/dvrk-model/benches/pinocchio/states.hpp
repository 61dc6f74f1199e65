// The seeded random states both programs here use (panda.cpp times them, count.cpp counts
// instructions over them), so that the two measure the same samples: q uniform within the
// joint limits, v and a uniform in [-1, 1], and tau = rnea(q, v, a), the torques of the
// state's own motion (so that aba returns a).
#pragma once
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>
#include <random>
#include <vector>

struct States {
  std::vector<Eigen::VectorXd> q, v, a, tau;
};

inline States random_states(const pinocchio::Model &model, pinocchio::Data &data, int n) {
  const int nq = model.nq, nv = model.nv;
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<double> unit(0.0, 1.0), sym(-1.0, 1.0);
  States s{std::vector<Eigen::VectorXd>(n, Eigen::VectorXd(nq)),
           std::vector<Eigen::VectorXd>(n, Eigen::VectorXd(nv)),
           std::vector<Eigen::VectorXd>(n, Eigen::VectorXd(nv)),
           std::vector<Eigen::VectorXd>(n)};
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < nq; ++j) {
      const double lo = model.lowerPositionLimit[j], hi = model.upperPositionLimit[j];
      s.q[i][j] = lo + (hi - lo) * unit(rng);
    }
    for (int j = 0; j < nv; ++j) s.v[i][j] = sym(rng);
    for (int j = 0; j < nv; ++j) s.a[i][j] = sym(rng);
    s.tau[i] = pinocchio::rnea(model, data, s.q[i], s.v[i], s.a[i]);
  }
  return s;
}
