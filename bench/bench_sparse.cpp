// SPDX-License-Identifier: BSD-3-Clause
// The sparse engine against the dense one (#5, item 6), on planar chains of N uniform rods in
// absolute coordinates (x, y, theta per body; revolute joints written here as local-column
// constraints) hanging from (0, 0) with the last tip pinned back to the ground (a loop closure).
//
//   bench_sparse                     both parts below
//   bench_sparse --evaluations       one evaluation of the fundamental equation, dense and sparse,
//                                    N = 8 … 1024 (dense up to 256): median ns per evaluation and
//                                    per body over 5 timed repetitions (after a warm-up)
//   bench_sparse --p3 [--json=PATH]  the shared problem P3 (N = 8, 32, 128; bench/data):
//                                    RK4, h = 1e-3, T = 2 s, projection drift control, sparse
//                                    engine; one warm-up and five timed runs (median ms per
//                                    simulated second), then a run sampled at every step for the
//                                    closure violation, energy drift and the reported coordinate
//   --step=H                         the RK4 step of --p3 (default 1e-3, the shared protocol's)
//   --problems=PATH                  problems.json (default: bench/data/ in the repository)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "support/planar_revolute.hpp"

#include <ukdyn/core/system.hpp>
#include <ukdyn/dynamics/forward.hpp>
#include <ukdyn/dynamics/workspace.hpp>
#include <ukdyn/linalg/sparse.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace {

using ukdyn::Index;
using ukdyn::MatrixXd;
using ukdyn::VectorXd;

// --- the model: planar rods and revolute joints ---------------------------------------------

Eigen::Matrix2d rot(double th) {
  Eigen::Matrix2d R;
  R << std::cos(th), -std::sin(th), std::sin(th), std::cos(th);
  return R;
}

using ukdyn::testing::PlanarRevolute;  // tests/support/planar_revolute.hpp

// a rod of length d between the centres of mass of bodies i < j: phi = (|p_i − p_j|² − d²)/2,
// A = [Δᵀ 0 −Δᵀ 0] with Δ = p_i − p_j, b = −|v_i − v_j|²
class Rung final : public ukdyn::ConstraintModel {
 public:
  Rung(Index i, Index j, double d) : i_(i), j_(j), d_(d) {
    for (Index c = 0; c < 3; ++c) cols_.push_back(3 * i + c);
    for (Index c = 0; c < 3; ++c) cols_.push_back(3 * j + c);
  }
  const std::vector<Index>& columns() const override { return cols_; }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double,
                               ukdyn::ConstraintScratch*, Eigen::Ref<MatrixXd> A,
                               Eigen::Ref<VectorXd> b) const override {
    const Eigen::Vector2d D = q.segment<2>(3 * i_) - q.segment<2>(3 * j_);
    const Eigen::Vector2d V = qd.segment<2>(3 * i_) - qd.segment<2>(3 * j_);
    A.setZero();
    A.block(0, 0, 1, 2) = D.transpose();
    A.block(0, 3, 1, 2) = -D.transpose();
    b[0] = -V.squaredNorm();
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ukdyn::ConstraintScratch*, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    const Eigen::Vector2d D = q.segment<2>(3 * i_) - q.segment<2>(3 * j_);
    const Eigen::Vector2d V = qd.segment<2>(3 * i_) - qd.segment<2>(3 * j_);
    position[0] = 0.5 * (D.squaredNorm() - d_ * d_);
    velocity[0] = D.dot(V);
  }

 private:
  Index i_, j_;
  double d_;
  std::vector<Index> cols_;
};

struct Chain {
  ukdyn::System sys;
  VectorXd q0, qd0;
  double L = 0;
};

// N rods of total length 2 m, 1 kg/m (transverse inertia m L²/12), gravity (0, −9.81), pinned
// at (0, 0), at absolute angles phi; the last tip pinned to `closure` (the tip itself when NaN)
Chain chain(const std::vector<double>& phi, Eigen::Vector2d closure) {
  const Index N = Index(phi.size());
  const double L = 2.0 / double(N), m = L, I = m * L * L / 12.0, g = 9.81;
  ukdyn::SystemBuilder b(3 * N);
  VectorXd q(3 * N);
  Eigen::Vector2d p(0.0, 0.0);
  for (Index i = 0; i < N; ++i) {
    const Eigen::Vector2d u(std::cos(phi[std::size_t(i)]), std::sin(phi[std::size_t(i)]));
    q.segment<2>(3 * i) = p + 0.5 * L * u;
    q[3 * i + 2] = phi[std::size_t(i)];
    p += L * u;
    b.mass_block(3 * i, Eigen::Vector3d(m, m, I).asDiagonal().toDenseMatrix());
  }
  if (std::isnan(closure.x())) closure = p;
  b.forces([N, m, g](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) {
    Q.setZero();
    for (Index i = 0; i < N; ++i) Q[3 * i + 1] = -m * g;
  });
  b.potential_energy([N, m, g](const Eigen::Ref<const VectorXd>& x, double) {
    double V = 0.0;
    for (Index i = 0; i < N; ++i) V += m * g * x[3 * i + 1];
    return V;
  });
  const Eigen::Vector2d back(-0.5 * L, 0.0), tip(0.5 * L, 0.0);
  const auto pin = [](const std::string& name, Index i, Eigen::Vector2d si, Index j,
                      Eigen::Vector2d sj) {
    return ukdyn::Constraint(name, ukdyn::ConstraintKind::kHolonomic, 2,
                             std::make_shared<PlanarRevolute>(i, si, j, sj));
  };
  b.add(pin("pin0", 0, back, -1, Eigen::Vector2d(0.0, 0.0)));
  for (Index i = 1; i < N; ++i) b.add(pin("pin" + std::to_string(i), i, back, i - 1, tip));
  b.add(pin("closure", N - 1, tip, -1, closure));
  return {b.build(), q, VectorXd::Zero(3 * N), L};
}

// a ladder: two chains of N/2 rods (total length 2 m each) hanging from (0, 0) and (0.5, 0) at the
// same angles, body i of one tied to body i of the other by a rung between their centres of mass
// (N/2 − 1 independent loops), and each tip pinned back to the ground where it is
Chain ladder(const std::vector<double>& phi_half) {
  const Index H = Index(phi_half.size()), N = 2 * H;
  const double L = 2.0 / double(H), m = L, I = m * L * L / 12.0, g = 9.81, d = 0.5;
  ukdyn::SystemBuilder b(3 * N);
  VectorXd q(3 * N);
  Eigen::Vector2d p(0.0, 0.0);
  for (Index i = 0; i < H; ++i) {
    const Eigen::Vector2d u(std::cos(phi_half[std::size_t(i)]), std::sin(phi_half[std::size_t(i)]));
    for (Index side = 0; side < 2; ++side) {
      const Index k = i + side * H;
      q.segment<2>(3 * k) = p + 0.5 * L * u + Eigen::Vector2d(d * double(side), 0.0);
      q[3 * k + 2] = phi_half[std::size_t(i)];
    }
    p += L * u;
  }
  for (Index k = 0; k < N; ++k) {
    b.mass_block(3 * k, Eigen::Vector3d(m, m, I).asDiagonal().toDenseMatrix());
  }
  b.forces([N, m, g](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) {
    Q.setZero();
    for (Index i = 0; i < N; ++i) Q[3 * i + 1] = -m * g;
  });
  const Eigen::Vector2d back(-0.5 * L, 0.0), tip(0.5 * L, 0.0);
  const auto pin = [](const std::string& name, Index i, Eigen::Vector2d si, Index j,
                      Eigen::Vector2d sj) {
    return ukdyn::Constraint(name, ukdyn::ConstraintKind::kHolonomic, 2,
                             std::make_shared<PlanarRevolute>(i, si, j, sj));
  };
  for (Index side = 0; side < 2; ++side) {
    const Index o = side * H;
    const std::string s = side ? "b" : "a";
    b.add(pin(s + "pin0", o, back, -1, Eigen::Vector2d(d * double(side), 0.0)));
    for (Index i = 1; i < H; ++i)
      b.add(pin(s + "pin" + std::to_string(i), o + i, back, o + i - 1, tip));
    b.add(pin(s + "closure", o + H - 1, tip, -1, p + Eigen::Vector2d(d * double(side), 0.0)));
  }
  for (Index i = 1; i < H; ++i) {
    b.add(ukdyn::Constraint("rung" + std::to_string(i), ukdyn::ConstraintKind::kHolonomic, 1,
                            std::make_shared<Rung>(i, H + i, d)));
  }
  return {b.build(), q, VectorXd::Zero(3 * N), L};
}

// --- part 1: one evaluation ------------------------------------------------------------------

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// median ns per forward_dynamics over 5 repetitions of about 0.15 s each
// (moving: with velocities 0.3 sin(0.7 i), which only rows without redundancy admit; else at rest)
double ns_per_evaluation(const Chain& c, ukdyn::Engine engine, bool moving = true) {
  ukdyn::SolverOptions o;
  o.engine = engine;
  o.compute_residuals = false;  // as in a simulation
  ukdyn::Workspace ws(c.sys, o);
  VectorXd qd = c.qd0;
  for (Index i = 0; moving && i < qd.size(); ++i) qd[i] = 0.3 * std::sin(0.7 * double(i));
  using clock = std::chrono::steady_clock;
  // warm-up, and the repetition count
  long reps = 1;
  for (;;) {
    const auto t0 = clock::now();
    for (long r = 0; r < reps; ++r) ukdyn::forward_dynamics(c.sys, ws, c.q0, qd, 0.0);
    const double s = std::chrono::duration<double>(clock::now() - t0).count();
    if (s > 0.05) {
      reps = std::max(1L, long(double(reps) * 0.15 / s));
      break;
    }
    reps *= 4;
  }
  std::vector<double> runs;
  for (int k = 0; k < 5; ++k) {
    const auto t0 = clock::now();
    for (long r = 0; r < reps; ++r) ukdyn::forward_dynamics(c.sys, ws, c.q0, qd, 0.0);
    runs.push_back(1e9 * std::chrono::duration<double>(clock::now() - t0).count() / double(reps));
  }
  if (ws.status != ukdyn::Status::kOk) std::cerr << "evaluation failed\n";
  return median(runs);
}

// max relative difference of q'' and lambda, sparse against dense, at the benchmark's state
double difference(const Chain& c, bool moving = true) {
  VectorXd qd = c.qd0;
  for (Index i = 0; moving && i < qd.size(); ++i) qd[i] = 0.3 * std::sin(0.7 * double(i));
  ukdyn::Workspace wd(c.sys, ukdyn::SolverOptions{.engine = ukdyn::Engine::kDense});
  ukdyn::Workspace ws(c.sys, ukdyn::SolverOptions{.engine = ukdyn::Engine::kSparse});
  ukdyn::forward_dynamics(c.sys, wd, c.q0, qd, 0.0);
  ukdyn::forward_dynamics(c.sys, ws, c.q0, qd, 0.0);
  return std::max((ws.qdd - wd.qdd).norm() / wd.qdd.norm(),
                  (ws.lambda - wd.lambda).norm() / wd.lambda.norm());
}

void ladders() {
  std::cout << "\nThe same for ladders (two closed chains of N/2 bodies side by side, body i of "
               "one tied to body i of the other by a rung: N/2 + 1 loops, parallelograms whose "
               "self-stress makes one row redundant), at rest\n\n";
  std::cout << "| N | n | m | rank | dense ns | sparse ns | dense / sparse | sparse ns per body | "
               "nnz(L_G) | sparse vs dense (q'', lambda) |\n"
               "|---|---|---|---|---|---|---|---|---|---|\n";
  for (Index N : {8, 32, 128, 512, 1024}) {
    std::vector<double> phi;
    const Index H = N / 2;
    for (Index i = 0; i < H; ++i) {
      phi.push_back(-0.8 + 1.6 * double(i) / double(std::max<Index>(H - 1, 1)) +
                    0.2 * std::sin(1.7 * double(i)));
    }
    const Chain c = ladder(phi);
    const double sparse = ns_per_evaluation(c, ukdyn::Engine::kSparse, false);
    const double dense = N <= 128 ? ns_per_evaluation(c, ukdyn::Engine::kDense, false) : NAN;
    const ukdyn::SparseDecomposition d(c.sys);
    ukdyn::Workspace ws(c.sys, ukdyn::SolverOptions{.engine = ukdyn::Engine::kSparse});
    ukdyn::forward_dynamics(c.sys, ws, c.q0, c.qd0, 0.0);
    std::cout << "| " << N << " | " << c.sys.coordinate_count() << " | " << c.sys.constraint_rows()
              << " | " << ws.rank << " | " << std::fixed << std::setprecision(0);
    if (std::isnan(dense)) {
      std::cout << "— | " << sparse << " | — | ";
    } else {
      std::cout << dense << " | " << sparse << " | " << std::setprecision(2) << dense / sparse
                << " | ";
    }
    std::cout << std::setprecision(1) << sparse / double(N) << " | " << d.factor_nonzeros()
              << " | ";
    if (std::isnan(dense)) {
      std::cout << "— |" << std::endl;
    } else {
      std::cout << std::scientific << std::setprecision(1) << difference(c, false)
                << std::defaultfloat << " |" << std::endl;
    }
  }
}

void evaluations() {
  std::cout
      << "One evaluation of the fundamental equation (forward_dynamics, no Gauss/virtual-work "
         "residuals), closed chains of N planar bodies: n = 3N, m = 2N + 2; median of 5\n\n";
  std::cout << "| N | n | m | dense ns | sparse ns | dense / sparse | sparse ns per body | "
               "nnz(A) | nnz(L_G) | sparse vs dense (q'', lambda) |\n"
               "|---|---|---|---|---|---|---|---|---|---|\n";
  for (Index N : {2, 3, 4, 6, 8, 16, 32, 64, 128, 256, 512, 1024}) {
    std::vector<double> phi;
    for (Index i = 0; i < N; ++i) {
      phi.push_back(-0.8 + 1.6 * double(i) / double(std::max<Index>(N - 1, 1)) +
                    0.2 * std::sin(1.7 * double(i)));
    }
    const Chain c = chain(phi, Eigen::Vector2d(NAN, NAN));
    const double sparse = ns_per_evaluation(c, ukdyn::Engine::kSparse);
    const double dense = N <= 256 ? ns_per_evaluation(c, ukdyn::Engine::kDense) : NAN;
    const ukdyn::SparseDecomposition d(c.sys);
    std::cout << "| " << N << " | " << 3 * N << " | " << 2 * N + 2 << " | ";
    if (std::isnan(dense)) {
      std::cout << "— | ";
    } else {
      std::cout << std::fixed << std::setprecision(0) << dense << " | ";
    }
    std::cout << std::fixed << std::setprecision(0) << sparse << " | ";
    if (std::isnan(dense)) {
      std::cout << "— | ";
    } else {
      std::cout << std::setprecision(2) << dense / sparse << " | ";
    }
    std::cout << std::setprecision(1) << sparse / double(N) << " | " << d.nonzeros() << " | "
              << d.factor_nonzeros() << " | ";
    if (std::isnan(dense)) {
      std::cout << "— |" << std::endl;
    } else {
      std::cout << std::scientific << std::setprecision(1) << difference(c) << std::defaultfloat
                << " |" << std::endl;
    }
  }
}

// --- part 2: P3 ------------------------------------------------------------------------------

struct P3 {
  std::string id;
  double T = 2, V_eq = 0, reference = 0;
  std::vector<double> phi0;
};

std::vector<P3> load_p3(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("bench_sparse: cannot read " + path + " (use --problems=PATH)");
  const nlohmann::json j = nlohmann::json::parse(in);
  // reference coordinates at T from the shared README
  const std::vector<std::pair<std::string, double>> refs = {
      {"P3_N8", -1.4271540}, {"P3_N32", -1.3904325}, {"P3_N128", -1.3939935}};
  std::vector<P3> out;
  for (const auto& [id, ref] : refs) {
    for (const auto& p : j.at("problems")) {
      if (p.at("id") != id) continue;
      P3 r;
      r.id = id;
      r.T = p.at("T");
      r.V_eq = p.at("V_eq");
      r.reference = ref;
      for (const auto& l : p.at("links")) r.phi0.push_back(l.at("phi0"));
      out.push_back(r);
    }
  }
  return out;
}

double g_step = 1e-3;  // --step=H (the shared protocol: 1e-3)

ukdyn::SimulationOptions p3_options(double T, double every) {
  ukdyn::SimulationOptions o;
  o.integrator = ukdyn::Integrator::kRK4;
  o.step = g_step;
  o.t_end = T;
  o.output_every = every;
  o.drift = ukdyn::DriftControl::kProjection;
  o.solver.engine = ukdyn::Engine::kSparse;
  return o;
}

std::string num(double v) {
  std::ostringstream os;
  os << std::setprecision(17) << v;
  return os.str();
}

void p3(const std::string& problems, const std::string& json_path) {
  std::vector<std::string> records;
  std::cout
      << "\nP3 (closed chain), RK4 h = 1e-3, T = 2 s, projection drift control, sparse engine\n\n"
      << "| problem | n | m | ms per simulated second (median of 5) | runs (ms/s) | max "
         "closure violation (m) | final violation (m) | phi link 1 at T (rad) | error vs "
         "reference | max rel. energy drift | projections |\n"
      << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const P3& p : load_p3(problems)) {
    const Chain c = chain(p.phi0, Eigen::Vector2d(1.2, 0.0));
    const Index N = Index(p.phi0.size());
    // one warm-up, five timed runs (samples at 0 and T only)
    std::vector<double> wall;
    for (int run = 0; run < 6; ++run) {
      const auto t0 = std::chrono::steady_clock::now();
      const ukdyn::Trajectory tr = ukdyn::simulate(c.sys, c.q0, c.qd0, p3_options(p.T, 0.0));
      const auto t1 = std::chrono::steady_clock::now();
      if (tr.stats.status != ukdyn::Status::kOk)
        std::cerr << p.id << ": " << tr.stats.message << "\n";
      if (run > 0) wall.push_back(std::chrono::duration<double>(t1 - t0).count());
    }
    // a run sampled at every step: closure from the poses, energy, coordinate
    const ukdyn::Trajectory tr = ukdyn::simulate(c.sys, c.q0, c.qd0, p3_options(p.T, g_step));
    const Index n = tr.n, S = tr.samples();
    double max_gap = 0, final_gap = 0, drift = 0;
    const double E0 = tr.energy.front() - p.V_eq;
    for (Index s = 0; s < S; ++s) {
      const Eigen::Map<const VectorXd> q(tr.q.data() + s * n, n);
      const Eigen::Vector2d tip =
          q.segment<2>(3 * (N - 1)) + rot(q[3 * (N - 1) + 2]) * Eigen::Vector2d(0.5 * c.L, 0.0);
      const double gap = (tip - Eigen::Vector2d(1.2, 0.0)).norm();
      max_gap = std::max(max_gap, gap);
      if (s == S - 1) final_gap = gap;
      drift = std::max(drift, std::abs(tr.energy[std::size_t(s)] - p.V_eq - E0) / std::abs(E0));
    }
    // "phi of link 1": the first link (L0, pinned at the origin)
    const double coord = tr.q[std::size_t((S - 1) * n + 2)];
    const double ms = 1e3 * median(wall) / p.T;
    std::cout << "| " << p.id << " | " << n << " | " << c.sys.constraint_rows() << " | "
              << std::fixed << std::setprecision(1) << ms << " | ";
    for (std::size_t i = 0; i < wall.size(); ++i) {
      std::cout << (i ? ", " : "") << std::setprecision(0) << 1e3 * wall[i] / p.T;
    }
    std::cout << " | " << std::scientific << std::setprecision(1) << max_gap << " | " << final_gap
              << " | " << std::fixed << std::setprecision(7) << coord << " | " << std::scientific
              << std::setprecision(1) << coord - p.reference << " | " << drift << " | "
              << tr.stats.projections << " |" << std::defaultfloat << std::endl;
    std::ostringstream r;
    r << "{\"engine\": \"ukdyn\", \"config\": \"absolute coordinates (x, y, theta per rod), "
         "sparse engine (block Cholesky of M, rank-revealing sparse LDL' of A M^-1 A'), "
         "projection drift control\", \"problem\": \""
      << p.id << "\", \"integrator\": \"rk4\", \"h\": 0.001, \"T\": " << num(p.T)
      << ", \"nq\": " << n << ", \"n_closure_eqs\": " << c.sys.constraint_rows()
      << ", \"wall_runs\": [";
    for (std::size_t i = 0; i < wall.size(); ++i) r << (i ? ", " : "") << num(wall[i]);
    r << "], \"wall_per_sim_s\": " << num(median(wall) / p.T)
      << ", \"max_violation\": " << num(max_gap) << ", \"final_violation\": " << num(final_gap)
      << ", \"E0\": " << num(E0) << ", \"E_final\": " << num(tr.energy.back() - p.V_eq)
      << ", \"rel_drift_final\": " << num((tr.energy.back() - p.V_eq - E0) / std::abs(E0))
      << ", \"rel_drift_max\": " << num(drift) << ", \"coord_name\": \"phi_link1\", \"coord_t1\": "
      << num(tr.q[std::size_t((S / 2) * n + 2)]) << ", \"coord_final\": " << num(coord)
      << ", \"steps\": " << tr.stats.steps << ", \"deterministic\": true, \"extra\": "
      << "{\"coord_reference\": " << num(p.reference)
      << ", \"coord_error\": " << num(coord - p.reference)
      << "}, \"settings\": {\"drift\": \"projection\", "
      << "\"projection_tolerance\": 1e-12}, \"error\": "
      << (tr.stats.status == ukdyn::Status::kOk ? "null" : "\"" + tr.stats.message + "\"") << "}";
    records.push_back(r.str());
  }
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    out << "[\n";
    for (std::size_t i = 0; i < records.size(); ++i) {
      out << "  " << records[i] << (i + 1 < records.size() ? ",\n" : "\n");
    }
    out << "]\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  bool want_eval = false, want_p3 = false;
  std::string json_path;
  std::string problems =
      (std::filesystem::path(__FILE__).parent_path() / "data/problems.json").string();
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--evaluations") {
      want_eval = true;
    } else if (a == "--p3") {
      want_p3 = true;
    } else if (a.rfind("--json=", 0) == 0) {
      json_path = a.substr(7);
    } else if (a.rfind("--step=", 0) == 0) {
      g_step = std::stod(a.substr(7));
    } else if (a.rfind("--problems=", 0) == 0) {
      problems = a.substr(11);
    } else {
      std::cerr << "usage: bench_sparse [--evaluations] [--p3] [--json=PATH] [--step=H] "
                   "[--problems=PATH]\n";
      return 2;
    }
  }
  if (!want_eval && !want_p3) want_eval = want_p3 = true;
  try {
    if (want_eval) {
      evaluations();
      ladders();
    }
    if (want_p3) p3(problems, json_path);
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}
