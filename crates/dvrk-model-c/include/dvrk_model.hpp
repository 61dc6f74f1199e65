// dvrk_model.hpp: a thin header-only C++ wrapper of dvrk_model.h (C++11 or later).
//
// RAII owners of the model and its workspace, exceptions only where something is
// loaded or allocated (construction), and the real-time calls as noexcept member
// functions that return the C API's code (0 or a negative DVRK_ERR_*) over plain
// pointers, so an Eigen vector passes as `v.data()` and a row-major
// `Eigen::Matrix<double, Dynamic, Dynamic, RowMajor>` as `m.data()` (the mass matrix is
// symmetric, so a column-major one receives the same numbers).
//
//   dvrk::Model model("psm_sdp.json");      // throws dvrk::Error with the reason
//   dvrk::Workspace ws(model);              // one per thread; model must outlive it
//   std::vector<double> q(model.dof()), tau(model.dof());
//   if (ws.gravity(q.data(), tau.data()) != DVRK_OK) { /* dvrk::error_string(code) */ }
//
// Thread safety as the C API: a Model may be shared read-only between threads, a
// Workspace serves one thread at a time.
#ifndef DVRK_MODEL_HPP
#define DVRK_MODEL_HPP

#include <cstddef>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>

#include "dvrk_model.h"

namespace dvrk {

// A model could not be loaded (the message says why: bad path, unknown robot, missing
// parameters, ...).
class Error : public std::runtime_error {
  public:
    explicit Error(const std::string &message) : std::runtime_error(message) {}
};

// The static description of a return code.
inline const char *error_string(int code) noexcept { return dvrk_error_string(code); }

// The library's version, e.g. "0.1.0".
inline const char *version() noexcept { return dvrk_version(); }

// The model of a `dvrk-ident fit` result. Movable, not copyable; moving keeps the
// underlying DvrkModel, so workspaces made from it stay valid.
class Model {
  public:
    // Loads the result document at `result_path`; throws dvrk::Error on failure.
    explicit Model(const std::string &result_path) {
        char err[1024] = {0};
        model_.reset(dvrk_model_from_result(result_path.c_str(), err, sizeof err));
        if (!model_) throw Error(err);
    }

    // Model coordinates n: the length of q, dq, ddq, tau; the mass matrix is n×n.
    std::size_t dof() const noexcept { return dvrk_model_dof(get()); }
    // Measured joints (the dVRK's/ROS joint space).
    std::size_t n_measured() const noexcept { return dvrk_model_n_measured(get()); }
    // Parameters (with the fit's Stribeck terms).
    std::size_t n_params() const noexcept { return dvrk_model_n_params(get()); }
    // Names by index; empty for an index out of range.
    std::string param_name(std::size_t i) const { return text(dvrk_model_param_name(get(), i)); }
    std::string coordinate_name(std::size_t i) const {
        return text(dvrk_model_coordinate_name(get(), i));
    }
    std::string joint_name(std::size_t i) const { return text(dvrk_model_joint_name(get(), i)); }

    // Measured joint positions or velocities to model coordinates (n each). Real-time.
    int measured_to_model(const double *measured, double *model_out) const noexcept {
        return dvrk_measured_to_model(get(), measured, model_out);
    }
    // Model-coordinate torques to measured efforts (n each). Real-time.
    int model_to_measured_torque(const double *tau_model, double *measured_out) const noexcept {
        return dvrk_model_to_measured_torque(get(), tau_model, measured_out);
    }

    // The C handle, for the C API.
    const DvrkModel *get() const noexcept { return model_.get(); }

  private:
    static std::string text(const char *s) { return s ? std::string(s) : std::string(); }
    struct Free {
        void operator()(DvrkModel *m) const noexcept { dvrk_model_free(m); }
    };
    std::unique_ptr<DvrkModel, Free> model_;
};

// Scratch buffers for the real-time calls on one model, from one thread at a time.
// The model must outlive the workspace.
class Workspace {
  public:
    // Allocates (not real-time); throws std::bad_alloc if the library cannot.
    explicit Workspace(const Model &model)
        : model_(model.get()), ws_(dvrk_workspace_new(model.get())) {
        if (!ws_) throw std::bad_alloc();
    }

    // The real-time calls: no allocation, no lock, no exception; 0 or a negative
    // DVRK_ERR_* code with the output untouched. Vectors have dof() doubles, the mass
    // matrix dof()·dof() (row-major).
    int gravity(const double *q, double *tau) noexcept {
        return dvrk_gravity(model_, ws_.get(), q, tau);
    }
    int inverse_dynamics(const double *q, const double *dq, const double *ddq,
                         double *tau) noexcept {
        return dvrk_inverse_dynamics(model_, ws_.get(), q, dq, ddq, tau);
    }
    int rigid_body_dynamics(const double *q, const double *dq, const double *ddq,
                            double *tau) noexcept {
        return dvrk_rigid_body_dynamics(model_, ws_.get(), q, dq, ddq, tau);
    }
    int mass_matrix(const double *q, double *m) noexcept {
        return dvrk_mass_matrix(model_, ws_.get(), q, m);
    }
    int forward_dynamics(const double *q, const double *dq, const double *tau,
                         double *ddq) noexcept {
        return dvrk_forward_dynamics(model_, ws_.get(), q, dq, tau, ddq);
    }

    // The C handle, for the C API.
    DvrkWorkspace *get() noexcept { return ws_.get(); }

  private:
    struct Free {
        void operator()(DvrkWorkspace *w) const noexcept { dvrk_workspace_free(w); }
    };
    const DvrkModel *model_;
    std::unique_ptr<DvrkWorkspace, Free> ws_;
};

// The generalized-momentum observer of one model: each estimate of the external torque
// (tau - tau_model, N·m or N per model coordinate) follows it with a first-order lag of
// time constant 1/gain. One update per control cycle, from one thread at a time, with
// a Workspace of the same model. The model must outlive the observer.
class Observer {
  public:
    // dof() gains, 1/s, positive and finite; throws dvrk::Error otherwise (not real-time).
    Observer(const Model &model, const double *gains)
        : model_(model.get()), obs_(dvrk_observer_new(model.get(), gains)) {
        if (!obs_) throw Error("dvrk_observer_new: expected dof() gains, positive and finite (1/s)");
    }

    // One cycle: q, dq, tau (as measured) and the step dt (s) since the previous update;
    // the estimate into tau_ext (zeros on the first update). Real-time: 0 or a negative
    // DVRK_ERR_* code with tau_ext untouched.
    int update(Workspace &ws, const double *q, const double *dq, const double *tau, double dt,
               double *tau_ext) noexcept {
        return dvrk_observer_update(model_, ws.get(), obs_.get(), q, dq, tau, dt, tau_ext);
    }
    // Forgets the previous sample and the estimate. Real-time.
    int reset() noexcept { return dvrk_observer_reset(obs_.get()); }

  private:
    struct Free {
        void operator()(DvrkObserver *o) const noexcept { dvrk_observer_free(o); }
    };
    const DvrkModel *model_;
    std::unique_ptr<DvrkObserver, Free> obs_;
};

}  // namespace dvrk

#endif  // DVRK_MODEL_HPP
