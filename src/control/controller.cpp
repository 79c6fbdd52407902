// SPDX-License-Identifier: BSD-3-Clause
// The controller's description: ControllerBuilder collects and validates the nominal model, the
// requirements, the law, the actuation and the robust settings; Controller freezes them.
#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <atomic>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

#include "control/internal.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn {

using control_detail::format;

namespace {

std::uint64_t next_controller_id() {
  static std::atomic<std::uint64_t> counter{1};
  return counter++;
}

[[noreturn]] void refuse(const std::string& what, const char* who = "build") {
  throw std::invalid_argument(std::string("ukdyn::ControllerBuilder::") + who + ": " + what);
}

std::string coordinate_list(const System& sys) {
  std::string s;
  for (const auto& name : sys.coordinate_names()) s += (s.empty() ? "" : ", ") + name;
  return s;
}

// a symmetric positive definite n × n matrix, or a message saying why not (from `who`)
void check_weight(const MatrixXd& N, Index n, const char* who) {
  if (N.rows() != n || N.cols() != n) {
    refuse("the weight N must be n × n = " + format_number(n) + " × " + format_number(n) +
               ", got " + format_number(N.rows()) + " × " + format_number(N.cols()),
           who);
  }
  if (!N.allFinite()) refuse("the weight N holds NaN or Inf", who);
  const double scale = N.cwiseAbs().maxCoeff();
  if ((N - N.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale) {
    refuse("the weight N must be symmetric (max |N − Nᵀ| = " +
               format((N - N.transpose()).cwiseAbs().maxCoeff()) + ")",
           who);
  }
  Eigen::LLT<MatrixXd> llt(N);
  if (llt.info() != Eigen::Success) {
    refuse("the weight N must be positive definite (its Cholesky factorization failed)", who);
  }
}

}  // namespace

const char* to_string(ControlLaw law) {
  switch (law) {
    case ControlLaw::kGauss:
      return "gauss";
    case ControlLaw::kWeighted:
      return "weighted";
  }
  return "unknown";
}

double Controller::ultimate_error_bound(Index i, double kappa) const {
  if (!robust_) {
    throw std::invalid_argument(
        "ukdyn::Controller::ultimate_error_bound: the controller has no "
        "robust term");
  }
  // V → kappa ε / (2 γ),  |e| <= sqrt(V / c)
  return std::sqrt(kappa * robust_->boundary_layer /
                   (2.0 * gamma_.at(std::size_t(i)) * scale_.at(std::size_t(i))));
}

double Controller::lyapunov(Index i, double e, double e_dot) const {
  if (!robust_) {
    throw std::invalid_argument("ukdyn::Controller::lyapunov: the controller has no robust term");
  }
  const Constraint& c = requirements_.constraint(row_requirement(i));
  if (c.kind() != ConstraintKind::kHolonomic) return e * e;
  // V = (β² + 2α²) e² + 2α e e' + e'²
  const double a = c.stabilization().alpha, b = c.stabilization().beta;
  return (b * b + 2.0 * a * a) * e * e + 2.0 * a * e * e_dot + e_dot * e_dot;
}

ControllerBuilder::ControllerBuilder(System model) : model_(std::move(model)) {}

ControllerBuilder& ControllerBuilder::require(Constraint c) {
  requirements_.push_back(std::move(c));
  return *this;
}

ControllerBuilder& ControllerBuilder::require(Constraint c, const ErrorDynamics& d) {
  requirements_.push_back(requirement(std::move(c), d));
  return *this;
}

ControllerBuilder& ControllerBuilder::gauss() {
  law_ = ControlLaw::kGauss;
  return *this;
}

ControllerBuilder& ControllerBuilder::weighted(WeightFn N) {
  if (!N) throw std::invalid_argument("ukdyn::ControllerBuilder::weighted: empty callable");
  law_ = ControlLaw::kWeighted;
  weight_ = std::move(N);
  has_weight_constant_ = false;
  return *this;
}

ControllerBuilder& ControllerBuilder::weighted(const Eigen::Ref<const MatrixXd>& N) {
  // checked here, where it is given (a model file's error then points at N:), and in build()
  check_weight(N, model_.coordinate_count(), "weighted");
  law_ = ControlLaw::kWeighted;
  weight_constant_ = N;
  has_weight_constant_ = true;
  weight_ = nullptr;
  return *this;
}

ControllerBuilder& ControllerBuilder::actuated(const std::vector<std::string>& coordinates) {
  if (coordinates.empty()) {
    throw std::invalid_argument(
        "ukdyn::ControllerBuilder::actuated: the list of actuated "
        "coordinates is empty (omit it to actuate every coordinate)");
  }
  actuated_names_ = coordinates;
  has_actuation_matrix_ = false;
  return *this;
}

ControllerBuilder& ControllerBuilder::actuation(const Eigen::Ref<const MatrixXd>& S) {
  S_ = S;
  has_actuation_matrix_ = true;
  actuated_names_.clear();
  return *this;
}

ControllerBuilder& ControllerBuilder::robust(const RobustControl& settings) {
  robust_ = settings;
  return *this;
}

ControllerBuilder& ControllerBuilder::options(const ControlOptions& options) {
  options_ = options;
  return *this;
}

Controller ControllerBuilder::build() const {
  const Index n = model_.coordinate_count();
  // options
  if (options_.solver.algorithm != Algorithm::kDefault) {
    refuse(
        "the controller needs the default algorithm (SolverOptions::algorithm = kDefault): it "
        "reuses the decomposition of the physical constraints");
  }
  if (!(options_.feasibility_tolerance > 0.0)) {
    refuse("ControlOptions::feasibility_tolerance must be > 0, got " +
           format(options_.feasibility_tolerance));
  }
  // requirements: a System over the model's coordinates, evaluated by the constraint stage only
  // (its identity mass matrix is never evaluated)
  if (requirements_.empty()) {
    refuse("no requirement (add one with require(constraint, error dynamics))");
  }
  std::set<std::string> seen;
  SystemBuilder rb(model_.coordinate_names());
  rb.mass_matrix(MatrixXd::Identity(n, n));
  for (const Constraint& r : requirements_) {
    if (!seen.insert(r.name()).second) refuse("requirement '" + r.name() + "' is declared twice");
    if (r.is_unilateral()) {
      refuse("requirement '" + r.name() +
             "' is unilateral: a requirement is met as an equality; contacts belong to the "
             "model (its constraints), where the control holds them as the plant does "
             "(docs/contact.md, \"Contacts under control\")");
    }
    rb.add(r);
  }
  Controller c(model_, rb.build());
  c.n_ = n;
  c.options_ = options_;
  c.m_r_ = c.requirements_.constraint_rows();
  for (Index k = 0; k < c.requirements_.constraint_count(); ++k) {
    const Constraint& r = c.requirements_.constraint(k);
    for (Index i = 0; i < r.rows(); ++i) {
      c.row_names_.push_back(r.rows() == 1 ? r.name() : r.name() + "." + format_number(i));
      c.row_requirement_.push_back(k);
    }
  }
  // law and weight
  c.law_ = law_;
  if (law_ == ControlLaw::kWeighted) {
    if (has_weight_constant_) {
      check_weight(weight_constant_, n, "build");
      const MatrixXd N = weight_constant_;
      c.weight_ = [N](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                      Eigen::Ref<MatrixXd> out) { out = N; };
      c.weight_constant_ = true;
    } else {
      c.weight_ = weight_;
    }
  }
  // actuation: S = I (fully actuated), a selection of coordinates, or a matrix
  if (!actuated_names_.empty()) {
    std::set<Index> chosen;
    for (const std::string& name : actuated_names_) {
      Index j = -1;
      for (Index i = 0; i < n; ++i) {
        if (model_.coordinate_names()[std::size_t(i)] == name) j = i;
      }
      if (j < 0) {
        refuse("actuated coordinate '" + name + "' is not a coordinate of the model (" +
               coordinate_list(model_) + ")");
      }
      if (!chosen.insert(j).second) refuse("actuated coordinate '" + name + "' is listed twice");
      c.actuated_.push_back(j);
    }
    c.k_ = Index(c.actuated_.size());
    c.S_ = MatrixXd::Zero(n, c.k_);
    for (Index j = 0; j < c.k_; ++j) c.S_(c.actuated_[std::size_t(j)], j) = 1.0;
    c.fully_actuated_ = false;
  } else if (has_actuation_matrix_) {
    if (S_.rows() != n || S_.cols() < 1) {
      refuse("the actuation matrix S must have n = " + format_number(n) +
             " rows and at least one column, got " + format_number(S_.rows()) + " × " +
             format_number(S_.cols()));
    }
    if (!S_.allFinite()) refuse("the actuation matrix S holds NaN or Inf");
    Eigen::ColPivHouseholderQR<MatrixXd> qr(S_);
    qr.setThreshold(1e-12);
    if (qr.rank() < S_.cols()) {
      refuse("the actuation matrix S must have full column rank (" + format_number(S_.cols()) +
             "), its rank is " + format_number(qr.rank()) + ": remove dependent actuators");
    }
    c.S_ = S_;
    c.k_ = S_.cols();
    c.fully_actuated_ = false;
  } else {
    c.S_ = MatrixXd::Identity(n, n);
    c.k_ = n;
    c.fully_actuated_ = true;
  }
  // robust term: every requirement needs decaying error dynamics
  if (robust_) {
    const RobustControl& r = *robust_;
    if (!(r.bound >= 0.0) || !(r.relative_bound >= 0.0) || !std::isfinite(r.bound) ||
        !std::isfinite(r.relative_bound)) {
      refuse("the robust bounds must be >= 0, got bound = " + format(r.bound) +
             ", relative_bound = " + format(r.relative_bound));
    }
    if (!(r.gain_uncertainty >= 0.0 && r.gain_uncertainty < 1.0)) {
      refuse("the robust gain_uncertainty must lie in [0, 1), got " + format(r.gain_uncertainty));
    }
    if (!(r.boundary_layer > 0.0) || !std::isfinite(r.boundary_layer)) {
      refuse("the robust boundary_layer must be > 0, got " + format(r.boundary_layer));
    }
    for (Index i = 0; i < c.m_r_; ++i) {
      const Constraint& req = c.requirements_.constraint(c.row_requirement_[std::size_t(i)]);
      const double a = req.stabilization().alpha, b = req.stabilization().beta;
      if (req.kind() == ConstraintKind::kHolonomic) {
        if (!(a > 0.0 && b > 0.0)) {
          refuse(
              "the robust term needs error dynamics e'' + 2 alpha e' + beta² e = 0 with "
              "alpha > 0 and beta > 0 on every requirement; '" +
              req.name() + "' has alpha = " + format(a) + ", beta = " + format(b));
        }
        // γ = 2α (1 − α / sqrt(α² + β²)),  c = α² + β²
        c.gamma_.push_back(2.0 * a * (1.0 - a / std::sqrt(a * a + b * b)));
        c.scale_.push_back(a * a + b * b);
      } else if (req.kind() == ConstraintKind::kNonholonomic) {
        if (!(a > 0.0)) {
          refuse(
              "the robust term needs error dynamics e' + k e = 0 with k > 0 on every "
              "requirement; '" +
              req.name() + "' has k = " + format(a));
        }
        c.gamma_.push_back(2.0 * a);
        c.scale_.push_back(1.0);
      } else {
        refuse("the robust term needs error dynamics, which requirement '" + req.name() +
               "' (acceleration form) cannot have");
      }
    }
    c.robust_ = robust_;
  }
  c.id_ = next_controller_id();
  return c;
}

}  // namespace ukdyn
